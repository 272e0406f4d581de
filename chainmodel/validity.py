"""Where a result is valid: pure checks from (drive, parameters, outputs) to a list of problems
(issue 21 item 5; docs/stability.md "Where a result is valid", docs/multibody.md "Validity
monitors"). Like fmpy's ``validation.py``, nothing here raises: every check returns
:class:`Problem` s, each naming its cause, the numbers and what to change. ``Problem.invalid``
marks a result that means nothing (``Result.valid`` is then False, ``chainmodel run`` exits 3);
the others are warnings (``Result.warnings``, the CLI's WARNING rows, fmi2Warning in the FMU).

Checks and their thresholds (each from a standard, the model's own law or geometry):

* **chain length** (every level): the chain of M links is compared with the wrapping length
  L(phi) of the rigid layout over one tooth period (seed 004 section 2, eq 13;
  ``kinematics.wrapping.wrap_length_range``). Its play is the pin-bushing clearance of every
  joint, M ``chain.joint_clearance`` (ISO 606: bush bore minus pin diameter). Too long:
  M p - L_max > play (slack at every instant by more than its joints can take up: the slack
  span hangs, which levels 0-2's straight spans do not model); too short:
  L_min - M p > play (it must stretch elastically at every instant). ``Drive`` itself refuses a
  chain shorter than L_min by 0.2 % or more, which for ISO clearances (0.3 % of a 10B pitch) comes
  first.
* **breaking load** (every level): the largest contact force, link tension or link compression
  against parameter ``chain.breaking_load`` when the mapping has it, else the ISO 606 minimum
  tensile strength of the ``presets.ISO606`` chain of this pitch (and roller diameter; of two
  matches the lower). No check for a pitch ISO 606 does not list.
* **penetration** (level 3): the roller-seat contact is a penalty law,
  F_n = max(0, k_c delta + c_c d(delta)/dt) with delta the overlap beyond the seat clearance
  (``kernels.multibody_forces.accelerations``), so the model's overlap is delta = F_n / k_c
  (``contact.max_force`` / ``contact.stiffness``; the damper's share is left in). k_c is seed
  003's *equivalent* contact stiffness (its section 5: the pin-bush, bush-roller and
  roller-tooth contacts in series), so delta is mostly the joint's deformation, which moves
  the lumped roller-and-pin mass point, not the roller's own penetration into the tooth:
  invalid beyond the roller radius, where the model's roller centre lies inside the tooth and
  its contact geometry means nothing. It is not compared with the seat clearance (as until the
  twentieth session of issue 21): the model's overlap passes the largest ISO 606 seat
  clearance at 6-9 % of the chain's breaking load, an ordinary working load (a 16A 15/45
  drive at its rated 4 kW was warned), while the roller's own Hertz approach in its seat
  (``chainmodel.chains.hertz_line_contact_approach``, Johnson 1985) is 12-24 um at the
  breaking load, a tenth of that clearance, for every chain listed: no roller penetrates its
  seat beyond the clearance before the breaking-load monitor speaks (docs/multibody.md,
  "Where level 3 is valid").
* **teeth skipped** (levels 1-3): at every whole driver tooth period (driver angle
  phi1_0 + k 2 pi / z1) the transmission error phi2 - (z1 / z2) phi1 returns to its start while
  the chain stays seated (the tooth-periodic polygon part cancels). A change of more than half
  a driven tooth, pi / z2, plus what the chain's slack lets the driven sprocket lag
  (:func:`skip_threshold`: a chain too long offsets it once as the load takes the slack up),
  means a roller has passed a tooth tip: invalid. Over k periods that is a mean speed ratio
  off z1 / z2 by more than 1 / (2k) relative (for a taut chain).
* **damper losses** (level 3): the power its chain loses (only in its dampers) against the
  pin-bushing friction the joint dampers stand in for (:mod:`chainmodel.loss_balance`): a
  warning when the loss exceeds twice that friction by more than 2 % of the transmitted work
  (the input work; the load's where an overrunning load drives the chain).
* **span modes missing** (levels 0-1): these levels' spans carry no transverse modes. A
  warning where the meshing frequency f_m (z1 times the mean |driver speed| / 2 pi) reaches
  :data:`SPAN_MODE_SHARE` = 0.4 of the slack span's first string frequency f_1 (seed 004 eq
  61, the moving string's, ``models.limits.drive_string_frequency``, at the run's mean slack
  tension; 0 Hz where that is no more than the centrifugal tension), naming the frequencies
  and what to run instead. Both means skip the first SPAN_START_PERIODS driver tooth periods
  and are judged at every whole driver tooth period from SPAN_JUDGE_PERIODS on, in the
  sample-by-sample path (the FMU) and the whole-run one (the library) alike; a verdict that
  fired stays. The line is empirical (docs/reduced_models.md,
  "Running spans on seed 004's presets"): every drive and speed where level 1 read more than
  3 % low on the tight span or 6 % low on the slack span lies at f_m / f_1 >= 0.50 at level
  1's own tension (the lowest C1 at 45 rpm; 0.49 at level 3's), and below 0.4 lie xu2010 at
  15 rpm (0.28) and C1 at 30 rpm (0.33), where level 1 passes, and the 6/9-tooth drive at 300
  rpm (0.30), whose slack span level 1 reads 6.9 % high (its few teeth, not the spans'
  bowing). At 0.4 the meshing's second harmonic is at 0.8 f_1, where a string answers its
  ends' motion at that harmonic 1 / (1 - 0.8^2) = 2.8x quasi-statically (the fundamental, at
  0.4 f_1, only 1.19x); the parametric resonances through the tension ripple (f_m near
  2 f_1 / n) lie above it too. Above the line level 1 also passes on some drives (xu2010 at
  30, 45 and 75 rpm; the 08B fan at 600 rpm, f_m / f_1 = 13: 1.4 / 1.9 % low), so the warning
  says "may".
* **slack span hanging** (levels 0-2): where the load holds the slack span's running mean
  tension (the same samples and instants as the span-modes check) below
  :data:`SLACK_LOADED_SHARE` = 0.8 of the static tension and the span's weight w L (w the
  chain's weight per metre, L the spans' tooth-period-mean length) is at least
  :data:`SLACK_HANGING_SHARE` = 0.14 of that mean, the slack span hangs on its weight and
  levels 0-2 read it low (an audit's 16B 21/21 and 08B 19/38 drives with no pretension at 5
  rpm, docs/reduced_models.md "A slack span hanging on its weight": levels 0-2 within 1 % of
  level 3 with no load at any inclination, 2.2 % at 88 deg; under load 7-9 % low laid
  horizontal at w L / T_s 0.14-0.15, up to 40 % inclined 80-88 deg, and within 5.2 % at
  0.11-0.21 on the 16B at 30 N m; the tight span within 2 %). Empirical, so "may"; it fires
  on some runs that pass (3 % low at 0.15).
* **span modes beyond level 2's** (level 2): the same measure as the check above, at level
  2's own mean slack tension, with the line at :data:`LEVEL2_SPAN_MODE_RATIO` = 1.5 f_1, where
  the meshing's second harmonic reaches the third string mode and the meshing itself 0.75 of
  the second (answered 2.3 x quasi-statically), modes its default single Galerkin mode per
  span does not hold. Empirical too (docs/scripts/level2_beyond_modes.py,
  docs/scripts/level2_span_survey.py; docs/reduced_models.md, "Level 2 beyond its modes"):
  the twenty-fifth session's 20 runs had none between 1.03 (passing) and 2.14 (failing) and
  drew the line at 2 f_1; the twenty-eighth session's survey of 90 drives with pretension
  filled the gap: every run where level 2 read more than 3 % low on the tight span or 6 % low
  on the slack span lies at f_m / f_1 >= 1.60 (up to 18 % low below 2), and below 1.5 only two
  runs on the first mode itself fail (a 12B 8/16 at 600 rpm, 0.94, +10 %; a 12B 17/34 at 200
  rpm, 0.97, -3.3 %); xu2010 at 90 rpm, 1.65, reads its slack span 6.7 % low. Above the line
  it also passes on some (the 08B fan at 600 rpm, 13.2), so the warning says "may". More
  modes are no cure to promise: on xu2010 at 600 rpm three bring the slack span from -27 to
  -6 %, nine take it to +66 %. The line is kept whatever ``modal.modes``, the only count
  measured across the drives. Since the twenty-ninth session f_1 is taken at the lower of
  level 2's own mean slack tension and the one its spans hold where they do not vibrate
  (level 0's quasi-static split of the mean load, plus the centrifugal tension): where level
  2's spans vibrate, their stretch lifts its own slack tension and with it its own string
  mode, so that judged on its own mean the meshing fell back below the line where level 3's
  spans bow beyond it (an audit's 08A 9/10 drive without pretension at 450 rpm: 1.23 f_1 at
  level 2's own 94 N, 1.65 at level 3's 53 N, level 2's spans +16 / +78 %, silent; the 12B
  8/16 above, +10 %, is warned at 1.56 f_1 at 517 N against its own 809 N). On the survey's
  90 drives with pretension no run within 3 % / 6 % gained the warning.
* **span vibration** (level 2): its spans' mean tension sum, over the same samples and
  judged at the same instants as the span-modes check, against a rigid chain's, sample by
  sample (twice the static tension, or the driven sprocket's tension difference |load +
  driven damping x speed + driven inertia x the input's acceleration x z1 / z2| / R_o over a
  slack span at the weight's floor where more, plus both spans' centrifugal tension rho v^2;
  seed 004 eqs 15-16). A warning at :data:`VIBRATION_RATIO` = 3 x and either by more than
  :data:`VIBRATION_FLOOR` = 1 % of the breaking load or with the meshing within
  :data:`LOCK_BAND` = 20 % of the slack span's first string mode at its running mean
  tension (seed 004 eq 61): there level 2's string mode, stiffened by its own stretch, has
  followed the meshing up and its stretch carries most of the tension. The floor alone let
  light chains through (a 12B 8/16 drive without pretension at 200 rpm: 3.15 x level 3's sum,
  258 N over the rigid chain's, under the 12B's 289 N floor, at 0.96 f_1); the band alone
  would not tell a chain carrying next to nothing (no weight, no pretension: any tension is
  many times its rigid sum) from a locked one. Without a breaking load (a pitch no ISO 606
  chain has and no chain.breaking_load) only the band counts. On an 08A 9/10 drive of 25
  links level 2 read 1.7-5.5 x level 3's sum at 600-1200 rpm (level 3 itself 2.2-2.6 x the
  rigid chain's); on the trade study's scenes level 2 reads 1.1-1.5 x and level 3 1.2-1.8 x
  (docs/reduced_models.md, "Level 2's spans locked on the meshing").
* **driven-speed reversal** (levels 1-3): the driven sprocket turning against the input's
  direction (by more than REVERSAL_SPEED) under forward drive: once the driver has turned one
  tooth in the input's present direction (the release of level 3's initial layout is over by
  then) and while the input runs at FORWARD_SHARE of its largest speed in that direction or
  more (through a commanded reversal or stop the driven sprocket's lag or lead turns it
  "backwards" at speeds near zero). A warning: a torsional vibration larger than the
  mean speed is physics a model may hold (a sudden start rings it), but it is resonance or slack
  chain, and the means mix both directions.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import Any, Mapping, Sequence

import numpy as np

from .geometry import Drive
from .loss_balance import OUTPUTS as LOSS_OUTPUTS
from .loss_balance import LossBalance
from .models.limits import drive_string_frequency

__all__ = ["Problem", "chain_play", "geometry_problems", "breaking_load",
           "output_problems", "problems", "result_problems", "start_problems", "Monitor",
           "REVERSAL_SPEED"]

#: a driven speed against the input's direction by more than this [rad/s] is a reversal
REVERSAL_SPEED = 1e-3
#: forward drive: the input turning one way at this share of its largest speed in that
#: direction or more (a commanded reversal or stop passes through speeds at which any
#: torsional lag or lead of the driven sprocket turns it "backwards": not a vibration larger
#: than the running speed)
FORWARD_SHARE = 0.1

OUTPUTS = ("driver.angle", "driven.speed", "transmission_error", "contact.max_force",
           "chain.max_link_tension", "chain.min_link_tension")
#: what the span checks read besides OUTPUTS (levels 0-1's span modes the first two, level
#: 2's span vibration all three)
SPAN_OUTPUTS = ("slack_span.tension", "driver.speed", "tight_span.tension")
#: levels 0-1 warn where the meshing frequency reaches this share of the slack span's first
#: string frequency (its second harmonic at 0.8 of it; module docstring, "span modes missing")
SPAN_MODE_SHARE = 0.4
#: levels 0-2 warn where the slack span's weight w L reaches this share of its running mean
#: tension while the load holds it below SLACK_LOADED_SHARE of the static tension (module
#: docstring, "slack span hanging")
SLACK_HANGING_SHARE = 0.14
SLACK_LOADED_SHARE = 0.8
#: level 2 warns where the meshing frequency reaches this multiple of the slack span's first
#: string frequency: its second harmonic on the third string mode, which its default single
#: Galerkin mode per span does not hold (module docstring, "span modes beyond level 2's")
LEVEL2_SPAN_MODE_RATIO = 1.5
#: its means skip the first SPAN_START_PERIODS driver tooth periods (the start and the ramp's
#: transient) and are judged at each whole driver tooth period once the driver has turned
#: SPAN_JUDGE_PERIODS, in both the sample-by-sample path (the FMU) and the whole-run one (the
#: library), so that both read the same samples at the same instants: the FMU does not warn on
#: a start-up mean, nor the library on a partial last tooth period, where the other would not
SPAN_START_PERIODS = 2
SPAN_JUDGE_PERIODS = 4
#: level 2 warns where its span tensions' mean sum over whole driver tooth periods is this many
#: times the rigid chain's sum (:meth:`Monitor.rigid_sum`): its string modes' stretch,
#: locked on the meshing, then carries most of the tension (module docstring, "span
#: vibration"; on the trade study's scenes level 2 reads 1.1-1.6 x, level 3 up to 2.6 x)
VIBRATION_RATIO = 3.0
#: ... and exceeds it by at least this share of the chain's breaking load (where known: the
#: 08A audit drive's locked runs by 2.4-15 %) ...
VIBRATION_FLOOR = 0.01
#: ... or the meshing lies within this share of the slack span's first string mode at the
#: spans' running tension: the lock's own signature, which tells a light chain's string
#: stiffened onto the meshing (12B, 12A, 10B 8/16 drives without pretension at 200 rpm:
#: 2.95-3.15 x level 3's span sum, 0.96-0.98 f_1) from one carrying next to nothing; 20 %, not
#: 10 %, for two 9/10 drives at 0.83-0.88 f_1 whose spans level 2 read 7-21 % off (every
#: drive of the survey with a sum of 3 x a rigid chain's is one without pretension, and each
#: of those failed 3 % / 6 % per span: docs/reduced_models.md, "Per span, every level below 3")
LOCK_BAND = 0.2


@dataclass(frozen=True)
class Problem:
    """One finding: ``code`` (chain_too_long, chain_too_short, breaking_load,
    penetration_roller, teeth_skipped, driven_reversal, damper_losses, span_modes_missing,
    span_modes_beyond, span_vibration, hanging_spans, ...), the sentence, and whether it makes the result
    meaningless."""

    code: str
    message: str
    invalid: bool = False

    def __str__(self) -> str:
        return self.message

    @property
    def text(self) -> str:
        """The sentence as warnings show it: an invalid result's starts "the result is not
        valid: "."""
        return ("the result is not valid: " if self.invalid else "") + self.message

    @property
    def cause(self) -> str:
        """The problem in a few words (the CLI's one-line error)."""
        return CAUSES.get(self.code, self.code)


CAUSES = {"chain_too_long": "chain too long for the centre distance",
          "chain_too_short": "chain too short for the centre distance",
          "breaking_load": "force above the chain's breaking load",
          "penetration_roller": "roller penetration beyond the roller radius",
          "teeth_skipped": "teeth skipped",
          "driven_reversal": "driven sprocket reversing under forward drive",
          "damper_losses": "level 3's dampers dissipate more than joint friction would",
          "span_modes_missing": "the meshing reaches span modes that levels 0-1 do not have",
          "span_modes_beyond": "the meshing reaches string modes above level 2's",
          "slack_span_hanging": "a slack span hanging on its weight under the load",
          "wrap_statics_unavailable": "torsional.wrap_statics not honoured",
          "wrap_statics_fallback": "torsional.wrap_statics on a weaker fit",
          "slack_span_sag": "slack span below level 3's on a chain hanging on its sag",
          "torsional_mode_moves": "level 3's torsional mode moving over a tooth beyond one "
                                  "mode's reach",
          "implausible_value": "a chain value far from its ISO 606 chain's",
          "hanging_spans": "spans hanging along their length at level 1 or 2",
          "span_vibration": "level 2's spans vibrating beyond its string model",
          "start_unloaded": "level 3 started unloaded: no static equilibrium under the load",
          "start_not_at_rest": "level 2 started with its strings off their own sag: no rest "
                               "found"}


# --- geometry (every level) ---------------------------------------------------------------------

def chain_play(drive: Drive, params: Mapping[str, Any]) -> float:
    """Length the chain gives or takes without load [m]: M ``chain.joint_clearance``."""
    return (drive.links or 0) * float(params.get("chain.joint_clearance", 0.0))


def skip_threshold(drive: Drive, params: Mapping[str, Any]) -> float:
    """The driven sprocket's drift from the tooth ratio [rad] beyond which a tooth was skipped:
    half a driven tooth, pi / z2, plus what the chain's slack lets it lag without skipping, its
    length beyond the shortest wrapping length over a tooth period (seed 004 eq 13) with its
    joints' play (:func:`chain_play`), taken up along the driven pitch circle. A chain too long
    for its centre distance offsets the driven sprocket by up to that slack when the load takes
    it up; a skipped tooth moves it by a whole tooth more each time."""
    half = math.pi / drive.n_driven
    if drive.links is None:
        return half
    lmin = _wrap_range(drive)[0]
    slack = max(0.0, drive.links * drive.pitch + chain_play(drive, params) - lmin)
    return half + slack / drive.driven.pitch_radius


def geometry_problems(drive: Drive, params: Mapping[str, Any],
                      level: int | None = None) -> list[Problem]:
    """The chain too long or too short for its centre distance by more than its play (module
    docstring), an option the model could not honour, or honoured on a weaker fit
    (``torsional.wrap_statics``; with ``level``, that level's own fit too), and chain values
    far from every ISO 606 chain of the pitch (:func:`implausible_values`)."""
    odd = implausible_values(drive, params)
    if drive.links is None:
        return odd
    length = _length_problems(drive, params)
    if level == 3 and length and length[0].code == "chain_too_long":
        length = [_level3_start(drive, params, length[0])]
    if level == 1 and length and length[0].code == "chain_too_long":
        length = [Problem("chain_too_long", f"{length[0].message}. {TOO_LONG_AT_LEVEL1}")]
    # the option is levels 0-2's: level 3 holds its own statics and says nothing of it
    wrap = [] if level == 3 else _wrap_statics_problems(drive, params, level)
    wrap += _hanging_problems(drive, params, level)
    if length and wrap and wrap[0].code == "wrap_statics_unavailable":
        # the length is the cause: one warning, which says what it also costs (the wrap fit)
        return odd + [Problem(length[0].code,
                              f"{length[0].message}. Therefore {wrap[0].message}")]
    return odd + length + wrap


#: what a chain too long does to level 1 (the twenty-fourth session's audit; level 2 refuses
#: such a chain, its strings need both spans taut at rest)
TOO_LONG_AT_LEVEL1 = (
    "Level 1's spans are elastic catenaries of a taut span; on a chain hanging this deep their "
    "running tensions are not the hanging chain's and may swing far from its sag tension (a "
    "12B 19/19 drive 2.1 pitches too long, no load, 2 rpm: level 1 0-55 N where the sag holds "
    "14 N, which levels 0 and 3 keep within 0.3 N): take span tensions from level 0 or 3")


#: a chain value this many times above or below the nearest ISO 606 chain's of the drive's
#: pitch is questioned (a unit slip: grams for kilograms, N/mm for N/m); the presets' seed
#: values lie within 4.5x of theirs
IMPLAUSIBLE_RATIO = 30.0


def implausible_values(drive: Drive, params: Mapping[str, Any]) -> list[Problem]:
    """Each chain value (chainmodel.chains.CHAIN_PARAMETERS) more than IMPLAUSIBLE_RATIO times
    above or below the closest of the ISO 606 chains of ``drive.pitch`` (none for a pitch no
    chain here has): a warning naming the value, the chain's and the ratio."""
    from .chains import chains_of_pitch, parameter_values
    refs = [(name, parameter_values(name)) for name in chains_of_pitch(drive.pitch)]
    out = []
    for key in (refs[0][1] if refs else {}):
        given = params.get(key)
        if key == "drive.pitch" or isinstance(given, bool) or not isinstance(given, (int, float)):
            continue
        near = [(abs(math.log(given / v[key])), name, v[key]) for name, v in refs
                if given > 0 and isinstance(v.get(key), float) and v[key] > 0]
        if not near:
            continue
        gap, name, ref = min(near)
        if gap > math.log(IMPLAUSIBLE_RATIO):
            unit = _unit(key)
            out.append(Problem("implausible_value", (
                f"{key} = {given:g} {unit} is {given / ref:.3g} x the value of the nearest "
                f"ISO 606 chain of this pitch ({name}: {ref:.4g} {unit}, chainmodel.chains): "
                "a unit slip?")))
    return out


def _unit(name: str) -> str:
    from .parameters import BY_NAME
    return BY_NAME[name].unit if name in BY_NAME else ""


def _wrap_statics_problems(drive: Drive, params: Mapping[str, Any],
                           level: int | None) -> list[Problem]:
    from .models.wrap_statics import (fallbacks, mode_spread, slack_shortfall, span_ends,
                                      unavailable)
    if not params.get("torsional.wrap_statics"):
        return []
    if level in (0, 1, 2):
        span_ends(drive, params)    # the fit or its refusal recorded, as the level's build does
    why = unavailable(drive, params)
    if why is None:
        found = [Problem("wrap_statics_fallback", f"torsional.wrap_statics: {note}")
                 for note in fallbacks(drive, params, level)]
        short = slack_shortfall(drive, params, level)
        if short is not None:
            found.append(Problem("slack_span_sag", f"torsional.wrap_statics: {short}"))
        spread = mode_spread(drive, params, level)
        if spread is not None:
            found.append(Problem("torsional_mode_moves", f"torsional.wrap_statics: {spread}"))
        return found
    return [Problem("wrap_statics_unavailable", (
        f"torsional.wrap_statics = true was not honoured: level 3's statics give this drive "
        f"no wrap to fit ({why}), so levels 0-2 hold their span ends with the seat ladder "
        f"(torsional.seat_compliance) and the catenary instead; where the chain hangs on its "
        f"sag their slack span under load reads low (nothing holds it up but a sag the "
        f"parabola may not cover), and on spans hanging along their length levels 1-2's read "
        f"high instead; run level 3 where the torsional mode or the slack span matters "
        f"(docs/reduced_models.md, \"Where the fit is refused\")"))]


#: the breaking-load warning calls a peak this many times what the load holds at rest a
#: transient and, on a flexible input shaft, names the shaft (Monitor._transient)
TRANSIENT_RATIO = 1.25

#: levels 1-2 warn where the weight along the spans (span_sag.hanging_tension) is at least
#: this share of the static tension and their span ends are not fitted to level 3's wrap
HANGING_SHARE = 0.25


def _hanging_problems(drive: Drive, params: Mapping[str, Any],
                      level: int | None) -> list[Problem]:
    """Levels 1-2 on spans hanging along their length (a near-vertical drive): their span law
    is elastic from the seat ladder's ends, so the polygon's length changes stretch its links,
    where level 3's chain takes them up in the lower sprocket's hanging wrap at about the
    weight's tension (docs/reduced_models.md, "Spans hanging along their length"). Only where
    the wrap fit is not honoured: on its ends (a drive inclined up to 85 degrees) levels 1-2
    follow level 3."""
    from .models.span_sag import hanging_tension
    from .models.wrap_statics import honoured, span_ends, weighted_static_tension
    if level not in (1, 2) or drive.links is None:
        return []
    hang = hanging_tension(drive, params)
    if not hang > 0.0:
        return []
    span_ends(drive, params)        # the fit or its refusal recorded, as the level's build does
    if honoured(drive, params):
        return []
    static = weighted_static_tension(drive, params)
    if hang < HANGING_SHARE * static:
        return []
    return [Problem("hanging_spans", (
        f"the spans hang along their length (the weight along them alone holds {hang:.3g} N "
        f"of the {static:.3g} N static tension): level {level}'s span law stretches the "
        f"chain's links where level 3's chain takes the polygon's length changes up in the "
        f"lower sprocket's hanging wrap, so its running span tensions may be far off, either "
        f"way (a vertical 16B 21/21 drive with no pretension at 5-100 rpm: levels 1 and 2 at "
        f"4-10 x level 3's span tensions with no load; under 100 N m the slack span +23 to "
        f"+29 % at level 1 and -34 % at level 2, the tight span within 1 %). Take span "
        f"tensions from level 3, or add pretension (docs/reduced_models.md, \"Spans hanging "
        f"along their length\")"))]


def _length_problems(drive: Drive, params: Mapping[str, Any]) -> list[Problem]:
    lmin, lmean, lmax = _wrap_range(drive)
    M, p = drive.links, drive.pitch
    play = chain_play(drive, params)
    if M * p - lmax > play:
        extra = M * p - lmax
        return [Problem("chain_too_long", (
            f"the chain is too long: drive.links = {M} is {1e3 * extra:.4g} mm ({extra / p:.3g} "
            f"pitches) longer than its wrapping length at centre distance "
            f"{1e3 * drive.centre_distance:.6g} mm ({lmax / p:.3f} pitches at most over a tooth "
            f"period, seed 004 eq 13), more than its joints' play ({M} x chain.joint_clearance = "
            f"{1e3 * play:.3g} mm): the slack span hangs in a sag instead of the taut span the "
            f"models start from; {_what_fits(drive, params, lmin, lmax, longest=True)}"))]
    if lmin - M * p > play:
        short = lmin - M * p
        return [Problem("chain_too_short", (
            f"the chain is too short: drive.links = {M} is {1e3 * short:.4g} mm shorter than "
            f"its wrapping length at centre distance {1e3 * drive.centre_distance:.6g} mm "
            f"({lmin / p:.3f} pitches at least over a tooth period, seed 004 eq 13), more than "
            f"its joints' play ({M} x chain.joint_clearance = {1e3 * play:.3g} mm): every link "
            f"is stretched at rest; {_what_fits(drive, params, lmin, lmax, longest=False)}"))]
    return []


def _level3_start(drive: Drive, params: Mapping[str, Any], problem: Problem) -> Problem:
    """Level 3 starts a chain too long from its static equilibrium, hanging in its sag
    (MultibodyModel.initial_state); where its statics find none (their Newton solve of a deep
    sag can stall), from straight spans, whose links then start in compression: the chain
    too long warning says so, so that the forces of the start-up are not read as the load's
    (the breaking-load warning that follows would say "use a lower load")."""
    from .models.multibody import MultibodyModel
    from .parameters import BY_NAME
    # the run's own static solution (cached per drive and parameters: no second solve)
    if MultibodyModel(drive, {k: v for k, v in params.items() if k in BY_NAME}
                      ).static_solution() is not None:
        return problem
    return Problem(problem.code, (
        f"{problem.message}. Level 3's statics find no equilibrium for this chain (their Newton "
        f"solve does not converge), so level 3 starts it from straight spans with its "
        f"slack links in compression: the forces of the first milliseconds (link or contact "
        f"forces above the breaking load, a reversing driven sprocket) are that start's, not "
        f"the load's"))


@lru_cache(maxsize=64)
def _wrap_range(drive: Drive) -> tuple[float, float, float]:
    from .kinematics.wrapping import wrap_length_range
    return wrap_length_range(drive)


def _what_fits(drive: Drive, params: Mapping[str, Any], lmin: float, lmax: float,
               longest: bool) -> str:
    """What to change: the link count nearest to the chain's that fits this centre distance
    within its play (L_min / (p + c) <= M <= L_max / (p - c), and no shorter than Drive takes),
    and the centre distance at which the chain's own links wrap tightly."""
    p, c = drive.pitch, float(params.get("chain.joint_clearance", 0.0))
    lo = max(math.ceil(lmin / (p + c) - 1e-9), math.ceil(lmin * (1.0 - 2e-3) / p - 1e-9), 4)
    hi = math.floor(lmax / (p - c) + 1e-9) if c < p else lo
    links = (f"use drive.links = {hi if longest else lo}" if lo <= hi else
             "no whole number of links fits this centre distance within the play")
    try:
        tight = Drive.from_links(drive.n_driver, drive.n_driven, p, drive.links)
    except ValueError:  # pragma: no cover - only for chains that cannot wrap at all
        return links
    return (f"{links}{', or' if lo <= hi else '; use'} drive.centre_distance = "
            f"{tight.centre_distance:.6g} m (0: the distance at which {drive.links} links wrap "
            f"tightly)")


# --- thresholds -----------------------------------------------------------------------------------

def breaking_load(drive: Drive, params: Mapping[str, Any]) -> tuple[float, str] | None:
    """(breaking load [N], where it comes from), or None if neither parameter
    ``chain.breaking_load`` nor an ISO 606 chain of this pitch gives one."""
    given = params.get("chain.breaking_load")
    if given is not None and float(given) > 0:
        return float(given), f"chain.breaking_load = {float(given) / 1e3:.4g} kN"
    from .presets import iso606_matches
    sizes, same_roller = iso606_matches(drive.pitch,
                                        2.0 * float(params.get("chain.roller_radius", 0.0)))
    if not sizes:
        return None
    chain = min(sizes, key=lambda c: c.tensile_strength)
    names = "/".join(c.name for c in sizes)
    which = (f"ISO 606 {chain.name}" if len(sizes) == 1 else
             f"ISO 606 {chain.name} (the lower of {names}, which match this pitch"
             + (" and roller)" if same_roller else ")"))
    return chain.tensile_strength, (f"{which}: minimum tensile strength "
                                    f"{chain.tensile_strength / 1e3:.4g} kN")


# --- the outputs' statistics, from whole arrays or sample by sample -------------------------------

@dataclass
class _Stats:
    """What the output checks need, accumulated over the samples seen."""
    max_contact: float = 0.0
    t_contact: float = math.nan
    max_link: float = 0.0
    t_link: float = math.nan
    min_link: float = 0.0
    t_min_link: float = math.nan
    reversal: float = 0.0          # most negative driven speed along the input's direction
    t_reversal: float = math.nan
    reversed_samples: int = 0
    driven_samples: int = 0
    drift: float = 0.0             # transmission error at a whole tooth period minus at start
    t_drift: float = math.nan
    periods: int = 0               # whole driver tooth periods reached
    last_k: int = 0
    last_drift: float = 0.0
    slack_sum: float = 0.0         # slack-span tension and driver speed summed over the
    speed_sum: float = 0.0         # samples once the driver has turned a tooth (levels 0-1)
    span_samples: int = 0
    tight_sum: float = 0.0         # tight-span tension, the rigid chain's span sum and the load
    rigid_sum: float = 0.0         # torque over the same samples (level 2's span-vibration and
    load_sum: float = 0.0          # span-modes checks)
    span_periods: float = 0.0      # driver tooth periods turned (from the first sample)
    max_load: float = 0.0          # largest |load torque| seen [N m]


class Monitor:
    """The output checks of one run, fed sample by sample (the FMU: :meth:`update` after each
    communication step returns the sentences of problems found for the first time) or all at
    once (:func:`output_problems`). ``names``: the order of the outputs in a row."""

    def __init__(self, drive: Drive, params: Mapping[str, Any], level: int,
                 names: Sequence[str] | None = None, started_unloaded: bool = False):
        self.drive, self.params, self.level = drive, dict(params), int(level)
        #: the run began unloaded (Model.start_fallback at level 3): a force peak is the
        #: load's step (level 2's fallback, its strings off their own sag, is no such start)
        self.started_unloaded = bool(started_unloaded) and self.level == 3
        self.period = 2.0 * math.pi / drive.n_driver
        self.stats = _Stats()
        self._start = None          # (driver angle, transmission error) at the first sample
        self._last = None           # (driver angle, transmission error, time) of the last one
        # the input's direction (+1, -1, 0 below REVERSAL_SPEED; 2 before the first sample),
        # the driver angle where it took it and the largest |input speed| since: "forward
        # drive" is one tooth turned in one direction at FORWARD_SHARE of that speed or more
        self._dir = (2, 0.0, 0.0)
        self._reported: set[str] = set()
        self._index = ({n: names.index(n) for n in OUTPUTS} if names is not None
                       and all(n in names for n in OUTPUTS) else None)
        self._ix = tuple(self._index[n] for n in OUTPUTS) if self._index else ()
        self._k = 0                 # whole tooth periods of the driver at the last sample
        # (reversal, drift, force, losses, (span modes, span vibration, slack hanging))
        self._alarm = (False, False, 0.0, False, (False, False, False))
        # below these no output check can fire: update() then skips problems() (FMU steps)
        bl = breaking_load(drive, self.params)
        self._force_alarm = math.inf if bl is None else bl[0]
        if self.level == 3:
            self._force_alarm = min(self._force_alarm, self.params["contact.stiffness"]
                                    * self.params["chain.roller_radius"])
        self._skip_limit = skip_threshold(drive, self.params)
        self._losses = LossBalance(drive, self.params) if self.level == 3 else None
        self._loss_ix = (tuple(names.index(n) for n in LOSS_OUTPUTS)
                         if self._losses is not None and names is not None
                         and all(n in names for n in LOSS_OUTPUTS) else None)
        # levels 0-1's span-modes check reads the slack span, level 2's the tight one too
        self._span_need = SPAN_OUTPUTS if self.level == 2 else SPAN_OUTPUTS[:2]
        self._span_ix = (tuple(names.index(n) for n in self._span_need)
                         if self.level <= 2 and names is not None
                         and all(n in names for n in self._span_need) else None)
        self._span_found = None     # (f_m, f_1, slack, own) of the last judgement that fired
        self._hanging = None        # (slack span's weight, its mean tension, static) that fired
        self._hang_constants = None
        self._vibration = None      # level 2: (span tension sum, rigid chain's sum) that fired
        # the span-vibration check's floor (VIBRATION_FLOOR): without a breaking load (a pitch
        # no ISO 606 chain has, no chain.breaking_load) only the lock's signature (LOCK_BAND)
        self._vibration_floor = None if bl is None else VIBRATION_FLOOR * bl[0]
        self._rigid = None          # _rigid_constants, when first needed
        self._still = None          # _still_slack's level-0 model, when first needed
        self._input_last = None     # (time, input speed) of the last sample: its acceleration

    # -- sample by sample --------------------------------------------------------------------
    def update(self, t: float, row, input_speed: float, load_torque: float = 0.0) -> list[str]:
        """Take one sample (``row`` indexed as ``names``; ``load_torque`` the load input) and
        return the sentences of the problems that appear with it (each problem once per run)."""
        if self._index is None:
            return []
        a, b, c, d, e, f = self._ix
        k = self._k
        if abs(load_torque) > self.stats.max_load:
            self.stats.max_load = abs(float(load_torque))
        self._sample(float(t), float(row[a]), float(row[b]), float(row[c]), float(row[d]),
                     float(row[e]), float(row[f]), float(input_speed))
        span = self._alarm[4]
        if self.level == 2:     # the input's acceleration, a backward difference
            acceleration, last = 0.0, self._input_last
            if last is not None and t > last[0]:
                acceleration = (float(input_speed) - last[1]) / (float(t) - last[0])
            self._input_last = (float(t), float(input_speed))
        if self._span_ix is not None:
            turned = abs(float(row[a]) - self._start[0]) / self.period
            if turned >= SPAN_START_PERIODS:
                s = self.stats
                s.slack_sum += float(row[self._span_ix[0]])
                s.speed_sum += abs(float(row[self._span_ix[1]]))
                if self.level == 2:
                    s.tight_sum += float(row[self._span_ix[2]])
                    s.rigid_sum += float(self.rigid_sum(float(row[self._span_ix[1]]),
                                                        float(row[b]), float(load_torque),
                                                        acceleration))
                    s.load_sum += float(load_torque)
                s.span_samples += 1
                s.span_periods = max(s.span_periods, turned)
                if self._k != k:        # judged at each whole driver tooth period
                    self._span_judge(s.speed_sum, s.slack_sum, s.span_samples,
                                     s.span_periods, s.tight_sum, s.rigid_sum, s.load_sum)
                    # each of the three on its own: a second span problem after a first is new
                    span = (self._span_found is not None, self._vibration is not None,
                            self._hanging is not None)
        losses = False
        if self._loss_ix is not None:
            self._losses.add_one(float(t), *(float(row[i]) for i in self._loss_ix),
                                 float(load_torque))
            losses = self._losses.message() is not None
        s = self.stats
        force = max(s.max_contact, s.max_link, -s.min_link)
        alarm = (s.reversed_samples > 0, abs(s.drift) > self._skip_limit,
                 force if force > self._force_alarm else 0.0, losses, span)
        if alarm == self._alarm:        # nothing that could raise a new problem has changed
            return []
        self._alarm = alarm
        new = []
        for p in self.problems():
            if p.code not in self._reported:
                self._reported.add(p.code)
                new.append(p.text)
        return new

    def _directions(self, w_in, phi1):
        """:meth:`_sample`'s forward drive over whole arrays: per sample the input's direction
        (0 where it is not forward drive: below REVERSAL_SPEED or FORWARD_SHARE of its
        direction's largest speed so far) and the driver angle where that direction began
        (carried across calls)."""
        sign = np.where(w_in >= REVERSAL_SPEED, 1, np.where(w_in <= -REVERSAL_SPEED, -1, 0))
        n = len(sign)
        changed = np.empty(n, bool)
        changed[0] = sign[0] != self._dir[0]
        changed[1:] = sign[1:] != sign[:-1]
        starts = np.flatnonzero(changed)
        last = np.maximum.accumulate(np.where(changed, np.arange(n), -1))
        since = np.where(last >= 0, phi1[np.maximum(last, 0)], self._dir[1])
        # the largest |input speed| within each run of one direction (a run continued from the
        # last call starts from its peak)
        peak = np.abs(w_in)
        bounds = [0, *starts[starts > 0], n]
        for a, b in zip(bounds[:-1], bounds[1:]):
            carried = self._dir[2] if a == 0 and not changed[0] else 0.0
            peak[a:b] = np.maximum.accumulate(np.maximum(peak[a:b], carried))
        self._dir = (int(sign[-1]), float(since[-1]), float(peak[-1]))
        forward = np.where(np.abs(w_in) >= FORWARD_SHARE * peak, sign, 0)
        return forward, since

    def _sample(self, t, phi1, w2, te, fc, tmax, tmin, w_in):
        s = self.stats
        if fc > s.max_contact:
            s.max_contact, s.t_contact = fc, t
        if tmax > s.max_link:
            s.max_link, s.t_link = tmax, t
        if tmin < s.min_link:
            s.min_link, s.t_min_link = tmin, t
        if self._start is None:
            self._start = (phi1, te)
        phi0, te0 = self._start
        sign = 1 if w_in >= REVERSAL_SPEED else (-1 if w_in <= -REVERSAL_SPEED else 0)
        if sign != self._dir[0]:
            self._dir = (sign, phi1, abs(w_in))
        elif abs(w_in) > self._dir[2]:
            self._dir = (sign, self._dir[1], abs(w_in))
        if (sign and abs(phi1 - self._dir[1]) >= self.period
                and abs(w_in) >= FORWARD_SHARE * self._dir[2]):
            s.driven_samples += 1
            along = w2 if w_in > 0 else -w2
            if along < -REVERSAL_SPEED:
                s.reversed_samples += 1
                if math.isnan(s.t_reversal):
                    s.t_reversal = t
                s.reversal = min(s.reversal, along)
        k = math.floor((phi1 - phi0) / self.period)
        if k != self._k and self._last is not None:
            self._crossings(self._last[0], self._last[1], phi1, te, t)
        self._k = k
        self._last = (phi1, te, t)

    def _crossings(self, a0, e0, a1, e1, t):
        """Transmission error at each whole tooth period the driver passed from a0 to a1."""
        phi0, te0 = self._start
        P = self.period
        k0 = math.floor((a0 - phi0) / P)
        k1 = math.floor((a1 - phi0) / P)
        if k0 == k1:
            return
        lo, hi = (k0 + 1, k1) if k1 > k0 else (k1 + 1, k0)
        s = self.stats
        for k in range(lo, hi + 1):
            if k == 0:
                # back at the start angle after rocking back: no tooth period has passed, and
                # the transmission error there is the spans' elastic take-up of the load
                continue
            target = phi0 + k * P
            f = (target - a0) / (a1 - a0)
            drift = e0 + f * (e1 - e0) - te0
            if abs(drift) > abs(s.drift):
                s.drift, s.t_drift = drift, t
            if abs(k) >= s.periods:
                s.periods, s.last_k, s.last_drift = abs(k), k, drift

    # -- whole arrays --------------------------------------------------------------------------
    def update_arrays(self, time, outputs: Mapping[str, np.ndarray], input_speed,
                      load_torque=0.0) -> None:
        """Take a whole run (arrays by output name; ``input_speed``, ``load_torque``: the
        inputs at each sample, or one number) at once; the same statistics as feeding
        :meth:`_sample` every sample, vectorised."""
        t = np.asarray(time, float)
        if self._losses is not None and all(n in outputs for n in LOSS_OUTPUTS) and len(t):
            self._losses.add(t, *(outputs[n] for n in LOSS_OUTPUTS), load_torque)
        phi1 = np.asarray(outputs["driver.angle"], float)
        w2 = np.asarray(outputs["driven.speed"], float)
        te = np.asarray(outputs["transmission_error"], float)
        w_in = np.broadcast_to(np.asarray(input_speed, float), t.shape)
        s = self.stats
        if not len(t):
            return
        s.max_load = max(s.max_load, float(np.max(np.abs(load_torque))))
        fc = np.asarray(outputs["contact.max_force"], float)
        tmax = np.asarray(outputs["chain.max_link_tension"], float)
        tmin = np.asarray(outputs["chain.min_link_tension"], float)
        i, j, m = int(np.argmax(fc)), int(np.argmax(tmax)), int(np.argmin(tmin))
        if fc[i] > s.max_contact:
            s.max_contact, s.t_contact = float(fc[i]), float(t[i])
        if tmax[j] > s.max_link:
            s.max_link, s.t_link = float(tmax[j]), float(t[j])
        if tmin[m] < s.min_link:
            s.min_link, s.t_min_link = float(tmin[m]), float(t[m])
        if self._start is None:
            self._start = (float(phi1[0]), float(te[0]))
        phi0, te0 = self._start
        sign, since = self._directions(np.asarray(w_in, float), phi1)
        driven = (sign != 0) & (np.abs(phi1 - since) >= self.period)
        along = np.where(w_in > 0, w2, -w2)
        rev = driven & (along < -REVERSAL_SPEED)
        s.driven_samples += int(driven.sum())
        s.reversed_samples += int(rev.sum())
        if rev.any():
            if math.isnan(s.t_reversal):
                s.t_reversal = float(t[np.argmax(rev)])
            s.reversal = min(s.reversal, float(np.min(along[rev])))
        k = np.floor((phi1 - phi0) / self.period)
        if self.level <= 2 and all(n in outputs for n in self._span_need):
            speed = np.asarray(outputs["driver.speed"], float)
            vibration = self.level == 2         # the tight span and the rigid chain's sum too
            load = np.broadcast_to(np.asarray(load_torque, float), t.shape)
            self._span_arrays(phi1, k, np.asarray(outputs["slack_span.tension"], float),
                              np.abs(speed), load,
                              np.asarray(outputs["tight_span.tension"], float) if vibration
                              else None,
                              self.rigid_sum(speed, w2, load, self._input_accelerations(
                                  t, np.asarray(w_in, float)))
                              if vibration else None)
        if self._last is not None:
            self._crossings(self._last[0], self._last[1], float(phi1[0]), float(te[0]),
                            float(t[0]))
        for i in np.flatnonzero(np.diff(k) != 0):
            self._crossings(float(phi1[i]), float(te[i]), float(phi1[i + 1]), float(te[i + 1]),
                            float(t[i + 1]))
        self._last = (float(phi1[-1]), float(te[-1]), float(t[-1]))
        self._k = int(k[-1])

    def _input_accelerations(self, t, w_in):
        """The input's acceleration at each sample, as :meth:`update` takes it: the backward
        difference from the sample before (carried across calls; 0 at the run's first)."""
        last = self._input_last
        t_before = np.concatenate(([last[0] if last else t[0]], t[:-1]))
        w_before = np.concatenate(([last[1] if last else w_in[0]], w_in[:-1]))
        dt = t - t_before
        self._input_last = (float(t[-1]), float(w_in[-1]))
        return np.where(dt > 0.0, (w_in - w_before) / np.where(dt > 0.0, dt, 1.0), 0.0)

    def _span_arrays(self, phi1, k, slack, speed, load, tight, rigid):
        """The span checks' sums of a whole run, judged at every whole driver tooth period as
        :meth:`update` judges them sample by sample (the same samples, the same verdicts)."""
        s = self.stats
        periods = np.abs(phi1 - self._start[0]) / self.period
        counted = periods >= SPAN_START_PERIODS
        slack_sum = s.slack_sum + np.cumsum(np.where(counted, slack, 0.0))
        speed_sum = s.speed_sum + np.cumsum(np.where(counted, speed, 0.0))
        if self.level == 2:     # the span-vibration check's sums
            tight_sum = s.tight_sum + np.cumsum(np.where(counted, tight, 0.0))
            rigid_sum = s.rigid_sum + np.cumsum(np.where(counted, rigid, 0.0))
            load_sum = s.load_sum + np.cumsum(np.where(counted, load, 0.0))
        else:
            tight_sum = rigid_sum = load_sum = np.zeros(len(counted))
        samples = s.span_samples + np.cumsum(counted)
        turned = np.maximum(s.span_periods, np.maximum.accumulate(np.where(counted, periods,
                                                                           0.0)))
        previous = np.concatenate(([self._k], k[:-1]))
        for i in np.flatnonzero(counted & (k != previous) & (turned >= SPAN_JUDGE_PERIODS)):
            self._span_judge(float(speed_sum[i]), float(slack_sum[i]), int(samples[i]),
                             float(turned[i]), float(tight_sum[i]), float(rigid_sum[i]),
                             float(load_sum[i]))
        s.slack_sum, s.speed_sum = float(slack_sum[-1]), float(speed_sum[-1])
        s.tight_sum, s.rigid_sum = float(tight_sum[-1]), float(rigid_sum[-1])
        s.load_sum = float(load_sum[-1])
        s.span_samples, s.span_periods = int(samples[-1]), float(turned[-1])

    # -- the findings ----------------------------------------------------------------------------
    def _span_judge(self, speed_sum, slack_sum, samples, periods, tight_sum=0.0,
                    rigid_sum=0.0, load_sum=0.0):
        """Judge the span checks on these sums. Levels 0-1: keeps (meshing frequency, slack
        span's first string frequency [Hz], mean slack tension [N], None) when the meshing
        reaches SPAN_MODE_SHARE of that frequency. Level 2: the same at
        LEVEL2_SPAN_MODE_RATIO, with the string frequency at the lower of its mean slack
        tension and the one its spans hold where they do not vibrate (:meth:`_still_slack`;
        then the last element is level 2's own mean): vibrating spans stretch and stiffen
        level 2's own strings, so that the meshing would seem to fall back below the line
        where level 3's spans bow beyond it (module docstring, "span modes beyond level 2's");
        and keeps (the spans' mean tension sum, the rigid chain's [N], both means over the
        samples) when the first is VIBRATION_RATIO times the second and above it by
        VIBRATION_FLOOR of the breaking load, or with the meshing within LOCK_BAND of the
        string frequency at its own mean (the lock's signature: the string's own stretch has
        tuned it onto the meshing). A verdict that fired stays (a warning is not taken back,
        as in the FMU's log)."""
        if not samples or periods < SPAN_JUDGE_PERIODS:
            return
        if self.level > 2:
            return
        speed, slack = speed_sum / samples, slack_sum / samples
        f_m, f_1 = self._frequencies(speed, slack)
        line, judged = SPAN_MODE_SHARE, (f_1, slack, None)
        if self.level == 2:
            total = (tight_sum + slack_sum) / samples
            rigid = rigid_sum / samples
            locked = f_1 > 0.0 and abs(f_m / f_1 - 1.0) <= LOCK_BAND
            if total > VIBRATION_RATIO * rigid and (
                    self._vibration_floor is not None and total - rigid > self._vibration_floor
                    or locked):
                self._vibration = (total, rigid)
            line = LEVEL2_SPAN_MODE_RATIO
            if self._span_found is None and f_m < line * f_1:
                still = self._still_slack(speed, load_sum / samples)
                if still < slack:
                    judged = (self._frequencies(speed, still)[1], still, slack)
        if self._hanging is None:
            self._hanging = self._slack_hanging(slack)
        if f_m > 0.0 and f_m >= line * judged[0]:
            self._span_found = (f_m,) + judged

    def _still_slack(self, speed, load) -> float:
        """The slack span's tension [N] where the spans do not vibrate, at mean |driver speed|
        ``speed`` [rad/s] and mean load torque ``load`` [N m]: level 0's quasi-static split
        (:meth:`~chainmodel.models.kinematic.KinematicModel.quasi_static_spans`) of |load +
        driven.damping x driven speed|, plus the centrifugal tension."""
        if self._still is None:
            from .models.kinematic import KinematicModel
            self._still = KinematicModel(self.drive, self.params)
        _, _, damping, _, centrifugal2, _ = self._rigid_constants()
        held = abs(load + damping * self.drive.tooth_ratio * speed)
        return (float(self._still.quasi_static_spans(held)[1])
                + 0.5 * centrifugal2 * speed * speed)

    def _frequencies(self, speed, slack) -> tuple[float, float]:
        """(meshing frequency, the slack span's first string frequency) [Hz] at mean |driver
        speed| ``speed`` and mean slack tension ``slack``; f_1 is 0 where the slack span carries
        no more than its centrifugal tension (every meshing frequency is then above its modes)."""
        f_m = speed * self.drive.n_driver / (2.0 * math.pi)
        return f_m, drive_string_frequency(self.drive, self.params, slack, speed)

    def rigid_sum(self, driver_speed, driven_speed, load, input_acceleration=0.0):
        """What a rigid chain's two spans carry together at a sample [N] (numbers or arrays):
        twice the static tension, or, where more, the tension difference the driven sprocket
        asks, |load + driven.damping x driven speed + driven.inertia x z1 / z2 x input
        acceleration| / R_o, over a slack span at the weight's floor; plus both spans'
        centrifugal tension (seed 004 eqs 15-16; span_sag.hanging_tension). Taken sample by
        sample, so an alternating load counts as it alternates. The inertia torque is the rigid
        chain's: the input's acceleration through the tooth ratio (a start's ramp asks it of
        the spans: on a 16B 17/34 drive of steel-disc sprockets ramped to 600 rpm in 0.05 s,
        47 N m, 340 N of tension difference); the polygon's speed ripple, whose mean over a
        tooth period is nil, is left out."""
        static2, hang2, damping, inv_r, centrifugal2, inertia = (self._rigid
                                                                 or self._rigid_constants())
        held = (abs(load + damping * driven_speed + inertia * input_acceleration) * inv_r
                + hang2)
        # builtins for one sample (the FMU's every step: numpy's ufuncs on floats cost ~1 us)
        held = np.maximum(static2, held) if isinstance(held, np.ndarray) else max(static2, held)
        return held + centrifugal2 * driver_speed * driver_speed

    def _rigid_constants(self) -> tuple:
        """(2 x static tension, 2 x hanging tension, driven.damping, 1 / R_o, both spans'
        centrifugal tension per (rad/s)^2 of driver speed, driven.inertia x z1 / z2), when
        first needed (:meth:`rigid_sum`, :meth:`_still_slack`)."""
        if self._rigid is None:
            from .models.kinematic import centrifugal_tension
            from .models.span_sag import hanging_tension
            from .models.wrap_statics import static_span_tension
            d, p = self.drive, self.params
            self._rigid = (2.0 * static_span_tension(d, p), 2.0 * hanging_tension(d, p),
                           p["driven.damping"], 1.0 / d.driven.pitch_radius,
                           2.0 * float(centrifugal_tension(d, p, 1.0)),
                           p["driven.inertia"] * d.tooth_ratio)
        return self._rigid

    def _slack_hanging(self, slack):
        """(weight of the slack span [N], its mean tension ``slack``, the static tension) where
        the load has taken the slack span below SLACK_LOADED_SHARE of the static tension and
        its weight w L is at least SLACK_HANGING_SHARE of its mean tension, else None."""
        if self._hang_constants is None:
            from .models.chain_inertia import mean_span_length
            from .models.wrap_statics import static_span_tension
            d, p = self.drive, self.params
            self._hang_constants = (p["chain.link_mass"] / d.pitch * abs(p["gravity"])
                                    * mean_span_length(d), static_span_tension(d, p))
        weight, static = self._hang_constants
        if not (weight > 0.0 and slack < SLACK_LOADED_SHARE * static):
            return None
        if weight < SLACK_HANGING_SHARE * max(slack, 0.0):
            return None
        return weight, slack, static

    def _span_line(self, f_m, f_1, slack, share, own=None) -> tuple[str, float]:
        """The span-modes warnings' shared parts: where the meshing f_m lies against the slack
        span's first string mode f_1 at tension ``slack`` (the line at ``share`` x f_1; ``own``
        the level's own mean where ``slack`` is the spans' still tension), and the input speed
        [rpm] below the line, rounded down so that the speed printed is below it."""
        at = (f"at its mean {slack:.4g} N" if own is None else
              f"at the {slack:.4g} N its spans hold where they do not vibrate; level 2's own "
              f"mean, {own:.4g} N, is its vibration's stretch, which stiffens its own strings")
        where = (f"{f_m / f_1:.3g} x the slack span's first string mode ({f_1:.4g} Hz {at}; "
                 f"warned from {share:g} x)" if f_1 > 0.0
                 else "above every string mode of the slack span, whose "
                 + (f"mean {slack:.4g} N" if own is None else
                    f"tension where the spans do not vibrate, {slack:.4g} N,")
                 + " is no more than its centrifugal tension")
        return where, math.floor(600.0 * share * f_1 / self.drive.n_driver) / 10.0

    def _beyond_level2(self, f_m, f_1, slack, own) -> Problem:
        """Level 2's span-modes warning: the meshing reaches string modes it does not hold."""
        n = int(self.params["modal.modes"])
        where, below = self._span_line(f_m, f_1, slack, LEVEL2_SPAN_MODE_RATIO, own)
        return Problem("span_modes_beyond", (
            f"level 2 holds {n} string mode{'s' if n > 1 else ''} per span "
            f"(modal.modes), and the meshing ({f_m:.4g} Hz) is {where}: where the spans bow "
            f"in higher modes, level 3's span tensions run higher and this level's may read "
            f"low (with one mode: up to 13 % on the tight span and 28 % on the slack span on "
            f"the drives first measured, up to 58 % on the spans' sum over a survey of 90 "
            f"drives of 8-17 teeth at 200-1200 rpm; on a chain without pretension either way, "
            f"0.14-2.4 x level 3's sum; "
            f"more modes moved xu2010 at 600 rpm either way, its slack span -27 % with one, "
            f"-6 % with three, +66 % with nine; docs/reduced_models.md, \"Level 2 beyond its "
            f"modes\" and \"Level 2's spans locked on the meshing\"); check against "
            f"fidelity 3"
            + (f", or run below {below:g} rpm" if below >= 1.0 else "")
            + (", or give the chain more static tension (its string modes rise with it)"
               if own is not None else "")))

    def _transient(self, peak: float) -> str:
        """The breaking-load warning's last clause where ``peak`` [N] is more than
        ``TRANSIENT_RATIO`` times what the largest load holds in the tight span at rest,
        max(|M| / R_2, chain.pretension + |M| / 2 R_2) (the slack span taken up, or both spans
        elastic about the pretension): a transient, and what drove it. An audit's 16A 11/55 at
        9000 N.m (40.5 kN held): started unloaded, 81-82 kN in the first 10 ms on any input
        shaft; started loaded (5000 N static tension), 57 kN on the default 12 kN.m/rad shaft,
        the driver swinging on it, and 41.5 kN with a rigid one. '' otherwise."""
        p, load = self.params, self.stats.max_load
        r2 = self.drive.driven.pitch_radius
        held = max(load / r2, max(p["chain.pretension"], 0.0) + load / (2.0 * r2))
        if not held > 0.0 or peak < TRANSIENT_RATIO * held:
            return ""
        text = (f"; the peak is {peak / held:.2g} x the {held / 1e3:.4g} kN the load holds in "
                f"the tight span at rest, a transient")
        if self.started_unloaded:
            return (text + ": level 3 started unloaded (start_unloaded) and the load stepped "
                    "onto its chain; a static tension that gives it a loaded equilibrium starts "
                    "it loaded")
        if p["input_shaft.rigid"] or p.get("input_shaft.causality", "angle") != "angle":
            return text + " such as the start or a load step"
        k = p["input_shaft.stiffness"]
        wind = load * self.drive.n_driver / self.drive.n_driven / k
        return (text + f" in which the driver swings on its input shaft (input_shaft.stiffness "
                f"= {k:g} N.m/rad winds {wind:.3g} rad under the load): give the real shaft's "
                f"stiffness or set input_shaft.rigid = true")

    def problems(self) -> list[Problem]:
        """Problems found in the samples so far (geometry not included: :func:`problems`)."""
        s, d, p = self.stats, self.drive, self.params
        out: list[Problem] = []
        bl = breaking_load(d, p)
        if bl is not None:
            limit, source = bl
            worst = max((s.max_contact, "contact force", s.t_contact),
                        (s.max_link, "link tension", s.t_link),
                        (-s.min_link, "link compression", s.t_min_link), key=lambda c: c[0])
            if worst[0] > limit:
                out.append(Problem("breaking_load", (
                    f"the {worst[1]} reaches {worst[0] / 1e3:.4g} kN at t = {worst[2]:.4g} s, "
                    f"above the chain's breaking load ({source}): such a chain would break, "
                    f"and the model holds to small strain only; use a lower load or speed, more "
                    f"static tension on a slack chain, more teeth on the small sprocket or a "
                    f"larger chain" + self._transient(worst[0]))))
        if self.level == 3:
            kc = p["contact.stiffness"]
            pen = s.max_contact / kc
            rr = p["chain.roller_radius"]
            law = (f"penalty contact F = k_c delta + c_c delta', contact.stiffness k_c = "
                   f"{kc / 1e6:.4g} kN/mm")
            if pen > rr:
                out.append(Problem("penetration_roller", (
                    f"a roller penetrates its seat by {1e3 * pen:.3g} mm at t = "
                    f"{s.t_contact:.4g} s (contact.max_force {s.max_contact / 1e3:.4g} kN / "
                    f"{law}), more than the roller radius {1e3 * rr:.3g} mm: the roller "
                    f"centre is inside the tooth and the contact geometry means nothing; use a "
                    f"lower speed or load, more teeth, a stiffer contact or a lower level"),
                    invalid=True))
        if self._losses is not None:
            why = self._losses.message()
            if why is not None:
                out.append(Problem("damper_losses", why))
        if self._hanging is not None:
            weight, slack, static = self._hanging
            out.append(Problem("slack_span_hanging", (
                f"the slack span hangs on its weight under the load: its {weight:.3g} N of "
                f"chain is {weight / max(slack, 1e-9):.2g} x its mean tension {slack:.4g} N "
                f"(warned from {SLACK_HANGING_SHARE:g} x, with the load holding it below "
                f"{SLACK_LOADED_SHARE:g} of the {static:.4g} N static tension); there levels 0-2 "
                f"may read the slack span low (on drives with no pretension under load: 7-9 % "
                f"laid horizontal on an 08B and a 16B drive, up to 40 % inclined 80-88 deg; the "
                f"tight span within 2 %; docs/reduced_models.md, \"A slack span hanging on "
                f"its weight\"); take the slack span from level 3, or add pretension")))
        found = self._span_found
        if found is not None and self.level == 2:
            out.append(self._beyond_level2(*found))
        elif found is not None:
            f_m, f_1, slack, _ = found
            where, below = self._span_line(f_m, f_1, slack, SPAN_MODE_SHARE)
            out.append(Problem("span_modes_missing", (
                f"level {self.level} has no span modes, and the meshing ({f_m:.4g} Hz) is "
                f"{where}: where the spans bow, "
                f"level 3's span tensions run higher and this level's may be off, mostly low "
                f"(level 1 on the drives measured: up to 55 % low on the tight span and 82 % "
                f"on the slack span; high on spans hanging along an inclined line, +27 % on the "
                f"slack span at 80 deg; docs/reduced_models.md, \"Running spans on seed 004's "
                f"presets\"); "
                + ("check against fidelity 2 or 3" if f_m < LEVEL2_SPAN_MODE_RATIO * f_1 else
                   f"check against fidelity 3 (level 2 warns too from "
                   f"{LEVEL2_SPAN_MODE_RATIO:g} x, beyond its one string mode per span)")
                + (f", or run below {below:g} rpm" if below >= 1.0 else
                   " (its slack span carries almost no tension)"))))
        if self._vibration is not None:
            total, rigid = self._vibration
            out.append(Problem("span_vibration", (
                f"level 2's spans vibrate beyond its string model's range: over whole driver "
                f"tooth periods their tensions sum to {total:.4g} N, {total / rigid:.3g} x the "
                f"{rigid:.4g} N a rigid chain's spans carry here (twice the static tension or "
                f"the driven sprocket's tension difference, plus the centrifugal tension; "
                f"warned from {VIBRATION_RATIO:g} x with the excess over "
                f"{100 * VIBRATION_FLOOR:g} % of the breaking load or the slack span's first "
                f"string mode within {100 * LOCK_BAND:g} % of the meshing): the stretch of its "
                f"string modes, locked on the meshing, carries the rest. On an 08A 9/10 drive of 25 links at 600-1200 rpm "
                f"level 2's span tensions summed to 1.7-5.5 x level 3's, whose own sum was "
                f"2.2-2.6 x the rigid chain's; on small sprockets without pretension level 3's "
                f"spans lock too and level 2 read 0.4-9 x its sum; take span tensions from "
                f"level 3 (docs/reduced_models.md, \"Level 2's spans locked on the "
                f"meshing\")")))
        if self.level >= 1:
            half = math.pi / d.n_driven
            slack = self._skip_limit - half
            if abs(s.drift) > self._skip_limit:
                ratio = (d.tooth_ratio + s.last_drift / (s.last_k * self.period)
                         if s.last_k else math.nan)
                teeth = s.drift / (2 * math.pi / d.n_driven)
                out.append(Problem("teeth_skipped", (
                    f"teeth skipped: by t = {s.t_drift:.4g} s the driven sprocket is "
                    f"{teeth:+.3g} driven teeth off the chain (more than half a tooth, pi / z2 = "
                    f"{half:.4g} rad"
                    + (f", plus the {slack:.3g} rad the chain's slack lets it lag" if slack > 0
                       else "")
                    + f", at a whole driver tooth period); the mean speed ratio over "
                    f"{s.periods} whole driver tooth periods is {ratio:.6g} against the exact "
                    f"tooth ratio {d.n_driver}/{d.n_driven} = {d.tooth_ratio:.6g}: the chain "
                    f"jumps teeth and the result is not a working drive; use more teeth on the "
                    f"small sprocket, a taut chain (more static tension or fewer links), a "
                    f"lower speed or load, or a larger chain"), invalid=True))
            if s.reversed_samples:
                frac = s.reversed_samples / max(s.driven_samples, 1)
                out.append(Problem("driven_reversal", (
                    f"the driven sprocket turns backwards under forward drive: "
                    f"{abs(s.reversal):.4g} rad/s against the input's direction (first at t = "
                    f"{s.t_reversal:.4g} s, {100 * frac:.3g} % of the samples once the driver "
                    f"has turned a tooth): a torsional vibration larger than the mean speed "
                    f"(resonance) or a slack chain, and the means mix both directions; use "
                    f"another speed (away from the resonance), more static tension or damping, "
                    f"or fewer links")))
        return out


def output_problems(drive: Drive, params: Mapping[str, Any], level: int, time,
                    outputs: Mapping[str, np.ndarray], input_speed,
                    load_torque=0.0, started_unloaded: bool = False) -> list[Problem]:
    """The output checks (breaking load; at level 3 the roller's overlap and the damper losses;
    at levels 0-1 the span modes; at levels 1-3 teeth skipped and driven-speed reversal) over a
    whole run. ``input_speed``,
    ``load_torque``: the inputs at each sample (or one number); ``started_unloaded``: the run
    began unloaded (Model.start_fallback)."""
    if any(n not in outputs for n in OUTPUTS):
        return []
    mon = Monitor(drive, params, level, started_unloaded=started_unloaded)
    mon.update_arrays(time, outputs, input_speed, load_torque)
    return mon.problems()


def problems(drive: Drive, params: Mapping[str, Any], level: int, time=None,
             outputs: Mapping[str, np.ndarray] | None = None, input_speed=None,
             load_torque=0.0, started_unloaded: bool = False) -> list[Problem]:
    """Geometry checks, then the output checks if ``outputs`` are given."""
    found = geometry_problems(drive, params, level)
    if outputs is not None:
        found += output_problems(drive, params, level, time, outputs, input_speed, load_torque,
                                 started_unloaded)
    return found


def result_problems(result) -> list[Problem]:
    """:func:`problems` of a ``simulation.Result`` (its scene's drive, parameters, level and
    input speed)."""
    sc = result.scene
    _, speed, _, load = sc.input_arrays(result.time)
    outputs = {n: result[n] for n in OUTPUTS + LOSS_OUTPUTS + SPAN_OUTPUTS if n in result}
    found = problems(sc.drive, sc.parameters, result.fidelity, result.time, outputs, speed, load,
                     bool(result.start_fallback))
    return found + start_problems(result.start_fallback, result.fidelity)


def start_problems(fallback: str | None, level: int | None = 3) -> list[Problem]:
    """The run's start where the model could not start where it should (``Model.start_fallback``:
    level 3 without a loaded static equilibrium, code ``start_unloaded``; level 2 without a
    rest with its strings at their own sag, ``start_not_at_rest``)."""
    if not fallback:
        return []
    return [Problem("start_unloaded" if level == 3 else "start_not_at_rest", fallback)]
