"""Levels 0-2's static tension and span ends: the spans' weight (the elastic catenary,
:mod:`.span_sag`; issue 21 item 4, docs/reduced_models.md "One static tension, gravity
included") and, with ``torsional.wrap_statics``, level 3's statics (items 3-4, "One wrap and one
static tension from level 3's statics").

Levels 1-2 hold each span between its sprockets with the law T_raw = (l - n p_free - f) /
(n / k + c) (spans.py ``_tension``): n links of stiffness k in series with an end compliance c,
and a free length f the ends give away. With ``torsional.wrap_statics`` the span tension is
T = (T_raw + sqrt(T_raw^2 + 4 a^2)) / 2: the raw law well above a floor a, a where the raw law
reaches zero, a^2 / |T_raw| below it. All three are fitted to the static equilibrium of level
3's own chain (:mod:`chainmodel.models.multibody_statics`: the same rollers, links, seats with
their clearance and flanks, gravity), condensed onto the driven sprocket's rotation (driver held
at angle 0):

* the driven sprocket's torsional stiffness K_m at which levels 1-2's two-inertia system
  (:func:`modal_stiffness`) rings at level 3's linear driven-sprocket mode
  (:func:`~chainmodel.models.multibody_statics.linear_driven_modes`: level 3 linearised at
  rest, its seated rollers condensed onto their sprockets, its span rollers' inertia kept),
  its mean over ``ANGLES`` driver positions in a tooth period (level 3's static tension and
  with it its mode move over a tooth: C1 364-551 N and 24.5-25.3 Hz; levels 1-2's
  tooth-period-mean link counts see the mean; :func:`_tooth_modes`; where it lies more than
  ``MODE_SPREAD`` from that mean at a position, levels 1-2 warn, :func:`mode_spread`), and
  level 1's R_o^2 sum_spans s_s / (n_s / k + c) = K_m gives c (n_s the tooth-period-mean link
  counts level 1 uses, s_s the floor's slope dT / dT_raw at rest). Levels 1-2 then refit the
  stiffness, floor and f with it, to their own linear mode at rest
  (:mod:`chainmodel.models.torsional_mode`, the same tooth-period mean: level 2's string
  modes push the two-inertia system's mode up, by 3 % on C1); K_m is where that fit starts.
  Not the statics' secant K_3 = 2 dM / |phi2(+dM) - phi2(-dM)| over a load step
  dM = ``LOAD_STEP`` T_0 R_o either way (the static condensation, kept as
  ``WrapFit.stiffness``): above the spans' string modes
  their rollers do not follow their static shapes, and that moves the mode by +5 % (C1,
  xu2010) to a factor of 4 in stiffness (a sagging chain, whose static secant is its sag's);
  docs/reduced_models.md, "Item 3, the torsional mode: one wrap";
* the held tension T_h: the mean of level 3's static tension (the two spans' middle links at
  rest, no load) over ``ANGLES`` driver positions in a tooth period. Level 3's equilibria move
  over a tooth (xu2010 520-558 N, mean 540 N, 526 N at angle 0; C1 373-532 N, mean 450 N,
  500 N at angle 0) and levels 1-2's spans move about what their law holds by their own
  polygon, so the law holds the mean, not the angle-0 value (docs/reduced_models.md, "The held
  tension is level 3's tooth-period mean"); T_0 at angle 0 where a position has no
  equilibrium, or where the mean leaves no plausible ends (then a warning, :func:`fallbacks`);
* the floor a from level 3's slack span under the load M_a = (1 - ``SLACK_SHARE``) 2 T_h R_o,
  at which the raw law's slack span would carry SLACK_SHARE T_h, its mean over the same
  driver positions: level 1's law at rest under M_a gives it (the wrap passes the tight span's
  tension round to the slack span's end, so level 3's span tensions' sum rises under load;
  docs/reduced_models.md); level 2's own fit takes its strings' sag S_N / T^2 into that law
  (:func:`_floored`), so the floor does not hold the weight a second time ("Level 2's floor
  and its strings' sag"); a = 0 where the floor cannot match (a sagging chain, whose slack span
  hardly loses tension) or no loaded equilibrium is found;
* T_h and levels 0-2's static law T_h = floor((X - 2 f) / (D + 2 c)) (static_tension.
  static_numerator's X, D without seats) give f.

So levels 0-2 hold level 3's static tension by construction, its tooth-period mean, sag,
clearance and the flanks' tension decay around the wrap included; they report level 3's
static tension at angle 0, the scene's (:func:`static_span_tension`). Level 1's
driven-sprocket mode is level 3's over a tooth period and its loaded split at rest follows
level 3's. Computed once per (drive, parameters): 3 + 4 x 5 static solves and four
linearisations.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

import numpy as np

from .. import parameters as PRM
from ..geometry import Drive
from ..kinematics.wrapping import tooth_period_geometry
from . import span_sag as SG
from .chain_inertia import sprocket_mass_matrix, two_inertia_stiffness
from . import static_tension as ST

__all__ = ["WrapFit", "wrap_fit", "tooth_positions", "span_ends", "static_span_tension",
           "held_span_tension", "weighted_static_tension", "weighted", "span_sag_terms",
           "straight_span_sags",
           "modal_stiffness", "softplus",
           "LOAD_STEP", "SLACK_SHARE", "SHORTFALL", "slack_shortfall", "sag_tension",
           "unavailable", "honoured", "fallbacks",
           "note_fallback", "parameters_key", "STATIC_IGNORED", "END_RATIO",
           "span_elastic_compliance", "raw_tension", "mode_spread", "MODE_SPREAD"]

#: the secant's load step dM / (T_0 R_o)
LOAD_STEP = 0.2
#: the loaded split is fitted where a linear law's slack span would carry this share of T_0
SLACK_SHARE = 0.25
#: levels 0-1 warn where their law's slack span under the fit's load, with no floor able to
#: lift it, is more than this share below level 3's (a chain hanging on its sag)
SHORTFALL = 0.2
#: driver positions over a tooth period at which the loaded split is solved (their mean)
ANGLES = 4
#: the weight's share of the static tension from which (MU_LOW) and to which (MU_HIGH) level
#: 3's statics replace the parabola's sag term (:func:`weighted_static_tension`)
MU_LOW, MU_HIGH = 0.25, 0.75
#: level 3's sag term is taken only within this factor of the parabola's (measured S_3 / S on
#: the unseen 08A, 08B, 10A, 12A drives: 0.86-1.03); beyond it level 3's static tension is not
#: the weight's doing
SAG_RATIO = 2.0
#: largest fitted end compliance per span, in units of the span's own elastic compliance
#: (its links and loaded seats): beyond it the chain at rest is held by its sag or lifts off
#: its seats, and ends linear from rest would not carry a load (:func:`_plausible`; measured:
#: 0.008-1.8 on C1, C2, xu2010, the 08B fan slack or taut, the 9/6 and 120/12-tooth drives,
#: 8.7 on the 6/9-tooth drive; 1.5e4 on a loose chain hanging at rest; docs/reduced_models.md)
END_RATIO = 10.0

_CACHE: dict = {}
#: why the fit failed, per (drive, parameters) key (:func:`unavailable`)
_FAILED: dict = {}
#: where the fit fell back to a weaker stiffness, per (level or None, drive, parameters) key
#: (:func:`fallbacks`)
_FELL_BACK: dict = {}
#: what a level's own fit does not read (its options and string modes it does)
_OWN_SKIP = ("solver.", "output")


@dataclass(frozen=True)
class WrapFit:
    """Level 3's statics condensed for levels 0-2 (module docstring).

    compliance, free_length: per span end pair (c [m/N], f [m]) for spans.py's law on K_m
    (levels 1-2 refit them to their own mode: :func:`span_ends` with ``stiffness``);
    static_tension: T_0 [N]; stiffness: the statics' secant K_3 [N m/rad] (driven sprocket,
    driver held); upper, lower: the two span tensions at rest [N]; solves_wall: seconds spent;
    softness: the floor a [N]; loaded_slack: level 3's slack span it is fitted to [N];
    modal_stiffness: K_m [N m/rad], the stiffness c is fitted to; mode: level 3's linear
    driven-sprocket mode [Hz] (nan where none was found: K_m is then K_3); held_tension: T_h
    [N], level 3's static tension's mean over ``ANGLES`` driver positions in a tooth period,
    which the law (c, f, a) holds at rest (T_0 where a position has no equilibrium or the
    mean gives no plausible ends); split_difference: the tension difference [N] under which
    level 3's slack span ``loaded_slack`` was taken; modes: level 3's linear driven-sprocket
    mode [Hz] at each driver position ``mode`` is the mean of (angle 0 first; empty where
    K_m is the secant); tensions: level 3's static tension [N] at each driver position solved
    (angle 0 first)."""
    compliance: float
    free_length: float
    static_tension: float
    stiffness: float
    upper: float
    lower: float
    solves_wall: float
    softness: float = 0.0
    loaded_slack: float = float("nan")
    modal_stiffness: float = float("nan")
    mode: float = float("nan")
    held_tension: float = float("nan")
    split_difference: float = float("nan")
    modes: tuple[float, ...] = ()
    tensions: tuple[float, ...] = ()


#: parameters no fit reads: the statics and the linear modes are taken at zero velocity and
#: undamped, so no damper acts; the fidelity and the breaking load (validity's) neither
STATIC_IGNORED = frozenset(("fidelity", "chain.link_damping", "chain.joint_damping",
                            "contact.damping", "driven.damping", "input_shaft.damping",
                            "chain.breaking_load", "multibody.paper_damping"))


def parameters_key(drive: Drive, params: Mapping[str, Any],
                   skip: tuple[str, ...] = ("solver.", "output", "torsional.", "modal.")):
    """A cache key of the drive and the parameters whose names do not start with ``skip``
    (by default those level 3's statics do not read) and are not ``STATIC_IGNORED``: levels
    0-2 of one drive, and a sweep over its dampers, share one fit."""
    return (drive, tuple(sorted((k, v) for k, v in params.items()
                                if not k.startswith(skip) and k not in STATIC_IGNORED)))



def wrap_fit(drive: Drive, params: Mapping[str, Any]) -> WrapFit:
    """(c, f, T_0, K_3, ...) of this drive and parameters (module docstring); cached."""
    key = parameters_key(drive, params)
    hit = _CACHE.get(key)
    if isinstance(hit, ValueError):     # refused before: level 3's statics are not redone
        raise hit
    if hit is not None:
        return hit
    try:
        fit = _wrap_fit(drive, params, key)
    except ValueError as exc:
        fit = exc
    if len(_CACHE) > 256:
        _CACHE.clear()
    _CACHE[key] = fit
    if isinstance(fit, ValueError):
        raise fit
    return fit


def _wrap_fit(drive: Drive, params: Mapping[str, Any], key: tuple) -> WrapFit:
    # level 3 and its statics are imported when first needed: levels 0-2 import this module
    # and most of their runs never ask for them
    from .multibody import MultibodyModel
    from .multibody_statics import solve_statics, static_state
    p3 = {k: v for k, v in params.items() if k in PRM.BY_NAME}
    model = MultibodyModel(drive, p3)
    rest = static_state(model)
    t0 = rest.mean_tension
    ro = drive.driven.pitch_radius
    w = abs(p3["gravity"]) * p3["chain.link_mass"]
    if not max(t0, w) > 0.0:
        raise ValueError("the chain carries no tension at rest (no pretension, no weight), so "
                         "its wrap has no stiffness at rest to fit")
    for share in (LOAD_STEP, 0.25 * LOAD_STEP, 0.05 * LOAD_STEP):
        # a smaller step where a roller at a tooth tip (where its contact ends) stalls Newton
        dm = share * max(t0, w) * ro
        try:
            plus = _loaded(model, rest, dm)
            minus = _loaded(model, rest, -dm)
            break
        except ValueError:
            if share == 0.05 * LOAD_STEP:
                raise
    k3 = 2.0 * dm / abs(minus.driven_angle - plus.driven_angle)
    wall = rest.wall + plus.wall + minus.wall
    # the driver at ANGLES positions over a tooth period, as level 1's tooth-period-mean link
    # counts see the chain: the held tension's, the loaded split's and the mode's means
    rests = [rest]
    try:
        for angle in tooth_positions(drive)[1:]:
            rests.append(static_state(model, angle))
            wall += rests[-1].wall
    except ValueError:  # positions with no equilibrium: the loaded split has no mean there
        pass
    # what levels 0-2's spans hold at rest: level 3's tooth-period mean (module docstring)
    if len(rests) == ANGLES:
        t_held, held_note = float(np.mean([r.mean_tension for r in rests])), None
    else:
        t_held = t0
        held_note = (f"levels 0-2's spans hold level 3's static tension at driver angle 0 "
                     f"({t0:.4g} N), not its tooth-period mean: level 3's statics found no "
                     f"equilibrium at one of the {ANGLES} driver positions in a tooth period "
                     f"that the mean takes")
    # the loaded split: level 3's slack span at a load that would take a linear law's slack
    # span to SLACK_SHARE of the held tension
    m_b = (1.0 - SLACK_SHARE) * 2.0 * t_held * ro
    slack3 = None
    if len(rests) == ANGLES:
        try:
            slacks = []
            for start in rests:
                state = start.state
                for share in (0.25, 0.5, 0.75, 1.0):
                    sol = solve_statics(model, start.driver_angle, share * m_b, start=state)
                    state = sol.state
                    wall += sol.wall
                slacks.append(min(sol.tension_upper, sol.tension_lower))
            slack3 = float(np.mean(slacks))
        except ValueError:   # no loaded equilibrium found: no floor
            slack3 = None
    omegas, swapped = [], False
    try:
        omegas, swapped = _tooth_modes(model, rests)
        omega, short = float(np.mean(omegas)), ANGLES - len(omegas)
        km = modal_stiffness(drive, p3, omega)
    except ValueError as exc:   # no mode to take (singular roller stiffness): the secant
        omegas, omega, km = [], float("nan"), k3
        _FELL_BACK[(None,) + key] = (
            f"level 3's linear driven-sprocket mode was not found ({exc}), so levels 1-2 take "
            f"the wrap stiffness from its statics' secant K_3 = {k3:.4g} N m/rad, which is "
            f"stiffer than the mode's (their torsional mode about +5 % on C1 and xu2010, up to "
            f"2x on a sagging chain); run level 3 where the torsional mode matters")
    else:
        if short:
            _FELL_BACK[(None,) + key] = (
                f"level 3's linear driven-sprocket mode was found at {ANGLES - short} of "
                f"{ANGLES} driver positions in a tooth period (no static equilibrium or no "
                f"mode at the others), so levels 1-2's wrap stiffness is fitted to their mean "
                f"{omega / (2.0 * math.pi):.4g} Hz, not the tooth period's (level 3's mode "
                f"moves by 3 % over a tooth on C1); run level 3 where the torsional mode "
                f"matters")
        else:
            _FELL_BACK.pop((None,) + key, None)
    if swapped:
        _FELL_BACK[("swap",) + key] = (
            f"level 3's two torsional modes on the input shaft swap roles over a driver tooth "
            f"(the chain's, the sprockets' pitch circles moving against each other, is found at "
            f"some of the fit's {ANGLES} driver positions only), so levels 1-2 follow the mode "
            f"with the larger share of the driven sprocket at all of them: their torsional "
            f"mode may be off level 3's by up to about 10 % (xu2010 at twice its seat "
            f"clearance on a 20 kN.m/rad shaft: -8.8 %; a 9/9 drive of 20 links: -4.2 %); run "
            f"level 3 where the torsional mode matters")
    else:
        _FELL_BACK.pop(("swap",) + key, None)
    dt = m_b / ro
    # the slack span under the fit's load hangs on its sag in level 3: the floor is fitted
    # over the spans' parabola sag, so it stands only for what the sag does not hold
    sags = SG.span_terms(drive, p3)
    try:
        c, f, b = _ends(drive, p3, t_held, slack3, km, dt, sags)
    except ValueError as exc:
        if t_held == t0:
            raise
        # the tooth-period mean leaves the spans too soft at rest for level 3's mode (a floor
        # fitted under a low mean): the ends hold the angle-0 tension, as before the mean
        c, f, b = _ends(drive, p3, t0, slack3, km, dt, sags)
        held_note = (f"levels 0-2's spans hold level 3's static tension at driver angle 0 "
                     f"({t0:.4g} N), not its tooth-period mean ({t_held:.4g} N): on the mean "
                     f"{exc} (their running span means then sit off level 3's by the "
                     f"difference)")
        t_held = t0
    if held_note is None:
        _FELL_BACK.pop(("held",) + key, None)
    else:
        _FELL_BACK[("held",) + key] = held_note
    return WrapFit(c, f, t0, k3, rest.tension_upper, rest.tension_lower, wall, b,
                   float("nan") if slack3 is None else slack3, km, omega / (2.0 * math.pi),
                   t_held, dt, tuple(w / (2.0 * math.pi) for w in omegas),
                   tuple(float(r.mean_tension) for r in rests))


def tooth_positions(drive: Drive) -> np.ndarray:
    """The ``ANGLES`` driver angles [rad] over a tooth period at which the fit takes level 3's
    loaded split and mode, and levels 1-2 their own mode (means over them), angle 0 first."""
    return 2.0 * math.pi / drive.n_driver * np.arange(ANGLES) / ANGLES


def _tooth_modes(model, rests, wrap_first: bool = True) -> tuple[list[float], bool]:
    """([omega, ...] [rad/s], swapped): level 3's linear driven-sprocket mode
    (:func:`~chainmodel.models.multibody_statics.linear_driven_modes`) at the driver
    positions of ``rests`` where it has one (their mean is the fit's; ``ANGLES`` minus their
    count the positions missed), picked with ``wrap_first`` as linearised_modes says, or by
    the larger share at every position where the wrap's mode is taken at some only (then
    ``swapped`` is True); ValueError
    where the first position (angle 0) has no mode. Level 3's static tension, and with it its
    wrap's stiffness, moves with the driver's position (C1: 364-551 N, mode 24.5-25.3 Hz);
    levels 1-2 see the chain's tooth-period mean. At the other positions, the mode nearest
    angle 0's among those with a comparable response or share in the driven sprocket
    (``near``)."""
    from .multibody_statics import linear_driven_modes
    took: list[bool] = []
    omega = linear_driven_modes(model, rests[0], wrap_first=wrap_first, choice=took)[0]
    omegas = [omega]
    for rest in rests[1:]:
        try:
            omegas.append(linear_driven_modes(model, rest, near=omega, wrap_first=wrap_first,
                                              choice=took)[0])
        except ValueError:
            pass
    if any(took) and not all(took):
        # the wrap's mode at some positions only: the two static modes swap their roles over
        # the tooth (a 9/9 drive of 20 links on xu2010's shaft: the wrap's mode 361-382 Hz at
        # three positions, the other's continuation at the fourth 191 Hz, whose mean rang 12 %
        # low), so one mode is followed over the whole tooth: the larger share's
        return _tooth_modes(model, rests, wrap_first=False)[0], True
    return omegas, False


def _ends(drive: Drive, params: Mapping[str, Any], t0: float, slack3: float | None,
          stiffness: float, dt: float, sags: tuple[float, float] = (0.0, 0.0)
          ) -> tuple[float, float, float]:
    """(c, f, a) of the span law at rest: c with which level 1's law stiffens the driven
    sprocket by ``stiffness`` [N m/rad], a with which its slack span under the tension
    difference ``dt`` (the load M_a / R_o) is level 3's ``slack3`` there (None: no floor), f
    with which it holds ``t0`` at rest (module
    docstring; the floor's slope and c fixed in turn, four passes). ``sags`` [N^2 m]: the sag
    terms (S_upper, S_lower) the level's own span law adds (level 2's strings): the slack span
    under M_a is then the law's with them, so the floor does not hold the weight a second time."""
    ro = drive.driven.pitch_radius
    k = params["chain.link_stiffness"]
    n_up, n_low = _mean_links(drive)
    excess, links = ST.rest_geometry(drive)
    x = excess + links * params["chain.pretension"] / k
    target = stiffness / (ro * ro)
    b = 0.0
    c = _compliance(target, n_up, n_low, k, 1.0, 1.0)
    spans = (n_up, n_low, k, sags)
    for _ in range(4):
        t0_lin = raw_tension(t0, b)
        s = _slope(t0_lin, b)
        c = _compliance(target, n_up, n_low, k, s, s)
        if slack3 is None or slack3 <= _split_slack(t0, 0.0, c, spans, dt):
            break
        b = _softness(t0, slack3, c, spans, dt)
    t0_lin = raw_tension(t0, b)
    # the floor is the cause where the spans without it would take non-negative ends
    by_floor = c < 0.0 < b and _compliance(target, n_up, n_low, k, 1.0, 1.0) >= 0.0
    _plausible(c, span_elastic_compliance(drive, params), stiffness,
               _slope(t0_lin, b) if by_floor else 1.0)
    return c, 0.5 * (x - t0_lin * (links / k + 2.0 * c)), b


def _mean_links(drive: Drive) -> tuple[float, float]:
    """(upper, lower) span's tooth-period-mean link count."""
    g = tooth_period_geometry(drive, 100)
    return float(np.mean(g.upper_links)), float(np.mean(g.lower_links))


def slack_shortfall(drive: Drive, params: Mapping[str, Any], level: int | None) -> str | None:
    """Why levels 0-1's slack span under load falls short of level 3's, or None; derived from
    the (cached) :func:`wrap_fit` of a drive whose fit was honoured. It falls short where the
    fit found no floor (softness 0: :func:`_softness` found none that reaches level 3's at the
    fit's end compliance) and the law's slack span under the fit's load is more than
    ``SHORTFALL`` below level 3's there: a chain hanging on its sag, whose quasi-static sag
    (soft) and torsional mode above the spans' string modes (stiff) one span law does not hold
    (docs/reduced_models.md, "Level 1 on a chain hanging on its sag"). Level 2's strings sag by
    themselves and level 3 is the reference. chainmodel.validity turns it into a warning (code
    ``slack_span_sag``)."""
    if level not in (0, 1):
        return None
    fit = wrap_fit(drive, params)
    if math.isnan(fit.loaded_slack) or fit.softness > 0.0:
        return None
    # the sag levels 0-1 carry themselves (torsional.sag_lag): the law's slack span with it
    spans = _mean_links(drive) + (params["chain.link_stiffness"],
                                  straight_span_sags(drive, params))
    held = _split_slack(fit.held_tension, 0.0, fit.compliance, spans, fit.split_difference)
    # the kernels' floor under either span: the weight along it (span_sag.hanging_tension)
    held = max(held, SG.hanging_tension(drive, params))
    if held >= (1.0 - SHORTFALL) * fit.loaded_slack:
        return None
    m_b = fit.split_difference * drive.driven.pitch_radius
    return (
        f"levels 0-1's slack span under load falls short of level 3's on this drive, which "
        f"hangs on its sag (its spans hold {fit.held_tension:.4g} N at rest): under {m_b:.3g} "
        f"N m level 3's slack span carries {fit.loaded_slack:.3g} N, theirs {held:.3g} N, and "
        f"no floor under their span law, at the end compliance that gives level 3's torsional "
        f"mode, lifts it there (a static sag and a mode above the spans' string modes do not "
        f"fit one span law; running, a 10A 19/38 drive with no pretension at 900 rpm: level 1 "
        f"-59 %, level 2 -7 %). Take span tensions from level 2 or 3, or run level 1 on the "
        f"seat ladder (torsional.wrap_statics = false: its spans keep their quasi-static sag, "
        f"and its torsional mode is that of the ladder's seats)")


#: levels 1-2 warn where level 3's driven-sprocket mode at some driver position of the fit lies
#: more than this fraction from the tooth-period mean they carry (module docstring)
MODE_SPREAD = 0.10


def mode_spread(drive: Drive, params: Mapping[str, Any], level: int | None) -> str | None:
    """Why levels 1-2's torsional mode may be off level 3's at a driver position, or None.

    Levels 1-2 hold one wrap stiffness, fitted so that their mode is the mean of level 3's
    over ``ANGLES`` driver positions in a tooth period (:func:`wrap_fit`). Where level 3's
    mode at some position lies more than ``MODE_SPREAD`` from that mean, its chain is a
    different spring from one part of a tooth to the next and one mode does not stand for it
    (its static tension swings with the chain's path length over
    the tooth: an audit's 7/7 10B drive, 9-1206 N with 20 links, 444-457 N with 21, spans of a
    whole number of pitches): the trade study's 6/9-tooth drive, 72-236 Hz over a tooth,
    rings at 137 Hz at levels 1-2 against level 3's 233 Hz after a sudden start to 5 rpm;
    seed 004's A1, 3.7-21.9 Hz, at 13.9 against 21.0 Hz from 1 rpm (docs/reduced_models.md,
    "Level 3's mode over a tooth"). chainmodel.validity turns it into a warning (code
    ``torsional_mode_moves``)."""
    if level not in (1, 2):
        return None
    fit = wrap_fit(drive, params)
    if len(fit.modes) < 2 or not fit.mode > 0.0:
        return None
    lo, hi = min(fit.modes), max(fit.modes)
    off = max(fit.mode / lo - 1.0, 1.0 - fit.mode / hi)
    if off <= MODE_SPREAD:
        return None
    how = (f"{100.0 * off:.0f} % off level 3's" if off < 1.0 else
           f"off level 3's by a factor of {1.0 + off:.2g}")
    return (f"level 3's driven-sprocket mode at rest moves over a driver tooth from {lo:.4g} to "
            f"{hi:.4g} Hz (linearised at {len(fit.modes)} driver positions), and level {level} "
            f"carries their mean, {fit.mode:.4g} Hz, as one mode: at a position its torsional "
            f"mode is {how}, and its torsional response (a "
            f"resonance's speed, the ring after a step) may be off by as much or more (the "
            f"trade study's 6/9-tooth drive, 72-236 Hz over a tooth: 137 Hz against level 3's "
            f"233 Hz). Level 3's static tension moves from {min(fit.tensions):.4g} to "
            f"{max(fit.tensions):.4g} N over the same tooth: the chain's path length changes "
            f"with the driver's position. Run level 3 where the torsional mode matters; a centre "
            f"distance that keeps the path length over a tooth (on equal sprockets, spans of a "
            f"whole number of pitches), more teeth on the small sprocket or a tensioner evens "
            f"the wrap out")


def span_elastic_compliance(drive: Drive, params: Mapping[str, Any]) -> float:
    """A span's elastic compliance [m/N]: its tooth-period mean link count / k plus the seat
    ladder's loaded seats at both ends (clearance taken up), whatever
    ``torsional.seat_compliance`` says (a real wrap has seats): the yardstick of
    :func:`_plausible`."""
    n = 0.5 * sum(_mean_links(drive))
    seats = ST.seat_series_compliance(dict(params, **{"torsional.seat_compliance": True}),
                                      drive)[0]
    return n / params["chain.link_stiffness"] + seats


def _plausible(c: float, elastic: float, stiffness: float, slope: float = 1.0) -> None:
    """ValueError unless the fitted end compliance c [m/N] is one of a wrap: not negative (a
    series of seats, wrapped links and clearance) and at most ``END_RATIO`` times the span's
    ``elastic`` compliance (its mean links and loaded seats). Outside, the gap between the
    level's spans and level 3's mode at rest is not the wrap's: a chain stiffer at rest than
    its links (very soft links), a long sagging span whose floor (``slope`` dT / dT_raw at rest
    below 1, given where the spans without the floor would take ends of non-negative
    compliance) softens the spans at rest more than the mode allows - the slack span's static
    sag and a torsional mode above the spans' string modes, which one span law does not hold
    (C3, ``fine``: docs/reduced_models.md) - or a chain that hangs at rest, where ends linear
    from rest would stretch the loaded span by metres."""
    if c < 0.0:
        why = (f", with the floor fitted to level 3's slack span under load taking the spans' "
               f"slope at rest to {slope:.3g} (a long sagging span: its static sag and its "
               f"mode above the string modes do not fit one span law)" if slope < 0.999 else "")
        raise ValueError(
            f"level 3's driven-sprocket mode at rest (wrap stiffness {stiffness:.4g} N m/rad) "
            f"is stiffer than this level's spans alone{why}: it would take a negative end "
            f"compliance ({c:.3g} m/N), so the gap is not the wrap's")
    if c > END_RATIO * elastic:
        raise ValueError(
            f"level 3's driven-sprocket mode at rest (wrap stiffness {stiffness:.4g} N m/rad) "
            f"would take span ends {c / elastic:.3g} times as compliant as the span's links "
            f"and seats (more than {END_RATIO:g}): the chain at rest hangs on its sag or lifts "
            f"off its seats, and ends linear from rest would not carry a load")


def span_ends(drive: Drive, params: Mapping[str, Any], *, stretch: float = 0.0,
              stiffness: float | None = None,
              sags: tuple[float, float] = (0.0, 0.0)) -> tuple[float, float, float]:
    """(compliance c [m/N], free length f [m], floor a [N]) of levels 0-2's span law: from
    :func:`wrap_fit` with ``torsional.wrap_statics`` (and a drive with a link count); else - or
    where level 3 has no static equilibrium - the seat ladder's compliance
    (:func:`~chainmodel.models.static_tension.seat_series_compliance`), no floor, and under
    gravity the free length at which the law at rest gives :func:`weighted_static_tension`.

    ``stretch`` [N^2 m] is the sag term the level's own span law adds at rest (level 2's
    string modes: :func:`~chainmodel.models.span_sag.sag_term` with its mode count; 0 at levels
    0-1): the ends give that stretch away again, 2 f grows by stretch / T_0^2, so the level
    holds the static tension at rest once and not the sag twice.

    ``stiffness`` [N m/rad], with ``torsional.wrap_statics``: fit c (and the floor and f with
    it) to this driven-sprocket stiffness instead of :func:`wrap_fit`'s K_m (levels 1-2 fit it
    on their own linearised mode: :mod:`chainmodel.models.torsional_mode`), with ``sags`` the
    per-span sag terms the level's law holds itself (:func:`_ends`)."""
    if drive is not None and drive.links is not None and params.get("torsional.wrap_statics"):
        try:
            fit = wrap_fit(drive, params)
        except ValueError as exc:    # reported by unavailable() (chainmodel.validity)
            _FAILED[parameters_key(drive, params)] = str(exc)
        else:
            _FAILED.pop(parameters_key(drive, params), None)
            c, f, a = fit.compliance, fit.free_length, fit.softness
            if stiffness is not None:      # a ValueError here is the caller's (its trial)
                slack3 = None if math.isnan(fit.loaded_slack) else fit.loaded_slack
                c, f, a = _ends(drive, params, fit.held_tension, slack3, stiffness,
                                fit.split_difference, sags)
            return c, f + _given_back(stretch, fit.held_tension), a
    c, f = ST.seat_series_compliance(params, drive)
    if drive is None or drive.links is None or params["gravity"] == 0.0:
        return c, f, 0.0
    t0 = weighted_static_tension(drive, params)
    if t0 <= 0.0:           # slack at rest (no parabola holds it): the ladder's ends
        return c, f, 0.0
    # the free length at which the ladder's law T_raw = (X - 2 f) / D gives t0 at rest
    x, d = ST.static_numerator(drive, params)
    return c, f + 0.5 * (x - t0 * d) + _given_back(stretch, t0), 0.0


def _given_back(stretch: float, t0: float) -> float:
    return 0.5 * stretch / (t0 * t0) if stretch > 0.0 and t0 > 0.0 else 0.0


def weighted_static_tension(drive: Drive, params: Mapping[str, Any], *,
                            exact: bool = True) -> float:
    """:func:`weighted` 's tension [N]."""
    return weighted(drive, params, exact=exact)[0]


def span_sag_terms(drive: Drive, params: Mapping[str, Any]) -> tuple[float, float]:
    """(S_upper, S_lower) [N^2 m]: each span's sag term (span_sag), scaled as
    :func:`weighted` scales their sum, for level 1's straight spans (spans.py ``_tension``); (0,
    0) without weight or for a sag too deep for the parabola."""
    if drive.links is None or params["gravity"] == 0.0:
        return 0.0, 0.0
    s_eff = weighted(drive, params)[1]
    terms = SG.span_terms(drive, params)
    s = sum(terms)
    if not s_eff > 0.0 or not s > 0.0:
        return 0.0, 0.0
    return tuple(s_eff / s * term for term in terms)


def straight_span_sags(drive: Drive, params: Mapping[str, Any]) -> tuple[float, float]:
    """(S_upper, S_lower) [N^2 m]: the sag terms levels 0-1's straight spans carry themselves
    (level 0 quasi-statically, level 1 through its lagged sag: ``torsional.sag_lag``). On
    level 3's wrap (``torsional.wrap_statics`` honoured) the parabola's w_n^2 L^3 / 24 per span
    (:func:`~chainmodel.models.span_sag.span_terms`), over which :func:`wrap_fit` fits the
    floor; on the seat ladder (also where the fit is refused) the terms of its elastic
    catenary (:func:`span_sag_terms`). (0, 0) without gravity or a link count, and with
    ``torsional.sag_lag`` off on the wrap (there the floor then holds the slack span alone);
    off on the ladder level 1 keeps the quasi-static sag, level 0 none (before the twentieth
    session of issue 21)."""
    if drive.links is None or params["gravity"] == 0.0:
        return 0.0, 0.0
    if params.get("torsional.wrap_statics"):
        if not params.get("torsional.sag_lag", True):
            return 0.0, 0.0
        span_ends(drive, params)            # the fit, or its refusal recorded
        if honoured(drive, params):
            return tuple(float(v) for v in SG.span_terms(drive, params))
    return span_sag_terms(drive, params)


def weighted(drive: Drive, params: Mapping[str, Any], *,
             exact: bool = True) -> tuple[float, float]:
    """Levels 0-2's static span tension at rest, no load, the spans' weight included [N]: the
    elastic catenary on the seat ladder (:mod:`chainmodel.models.span_sag`), T^3 - T_raw T^2 -
    S / D = 0. Where the weight carries a large share of it the sag term S is taken from level
    3's statics instead of the parabola (:func:`_calibrated_sag_term`): with mu = 1 - T_raw / T
    the weight's share at the parabola's S, S_eff = S + (S_3 - S) s((mu - MU_LOW) / (MU_HIGH -
    MU_LOW)), s the smoothstep, so the tension is continuous in the pretension, a chain with no
    pretension that the ladder leaves slack (mu >= 1) carries level 3's sag tension exactly,
    and a pretensioned drive (mu < MU_LOW) never asks for level 3's statics. ``exact=False``
    skips that (the parabola's S throughout: within 7 % where they differ, docs/reduced_models.md).

    The spans' weight along them sets a floor under it (:func:`_hanging`): a steeply rising
    span hangs from its upper end, whatever the ladder's compatibility asks.

    Returns (T [N], S_eff [N^2 m]); S_eff 0 where there is no weight or the sag is too deep for
    the parabola (then T is level 3's statics or the ladder's)."""
    if drive.links is None:
        return params["chain.pretension"], 0.0
    t, s_eff, deep = _sagging(drive, params, exact)
    # a chain sagging deeper than the parabola (far too long: geometry_problems says so) hangs
    # in its sag, whose tension level 3's statics give where they converge
    if not deep and t < SAG_RATIO * SG.hanging_tension(drive, params):
        t = max(t, _hanging(drive, params, exact))
    return t, s_eff


def _hanging(drive: Drive, params: Mapping[str, Any], exact: bool) -> float:
    """The static tension [N] a chain with no pretension carries on spans hanging along their
    length (a near-vertical drive): level 3's statics at no pretension where they find an
    equilibrium, held between the weight's own floor F
    (:func:`~chainmodel.models.span_sag.hanging_tension`, which leaves out the lower
    sprocket's hanging wrap) and ``SAG_RATIO`` F, else F. A floor under :func:`weighted`'s
    tension, not a term of its cubic: a span taut along its whole length (pretension above
    it) takes the ladder's tension; one that is not hangs and its lower end loops, its mean
    held by the weight (no equilibrium of the ladder's stretch). :func:`weighted` asks for it
    only where its tension is below SAG_RATIO F, so the clamp keeps the result continuous
    where that starts (in the inclination, the pretension)."""
    floor = SG.hanging_tension(drive, params)
    if not exact:
        return floor
    t3 = sag_tension(drive, dict(params, **{"chain.pretension": 0.0}))
    return floor if t3 is None else min(max(t3, floor), SAG_RATIO * floor)


def _sagging(drive: Drive, params: Mapping[str, Any],
             exact: bool) -> tuple[float, float, bool]:
    """:func:`weighted` without the hanging floor: the cubic on the parabola's or level 3's
    sag term; and whether the spans sag deeper than the parabola holds."""
    x, d = ST.static_numerator(drive, params)
    raw = x / d
    s = SG.sag_term(drive, params)
    t = SG.tension(raw, s / d)
    if s > 0.0 and SG.deep(drive, params, t):
        # no shallow parabola: level 3's statics where they find an equilibrium (a chain this
        # long takes no pretension: pretension_error), else the ladder's 0 N
        t3 = sag_tension(drive, params) if exact else None
        return (max(raw, 0.0) if t3 is None else t3), 0.0, True
    if s <= 0.0 or not exact:
        return t, s, False
    mu = 1.0 - raw / t
    if mu <= MU_LOW:
        return t, s, False
    s3 = _calibrated_sag_term(drive, params)
    if s3 is None:
        return t, s, False
    u = min(1.0, (mu - MU_LOW) / (MU_HIGH - MU_LOW))
    s_eff = s + (s3 - s) * u * u * (3.0 - 2.0 * u)
    return SG.tension(raw, s_eff / d), s_eff, False


def _calibrated_sag_term(drive: Drive, params: Mapping[str, Any]) -> float | None:
    """The sag term S_3 [N^2 m] at which the elastic catenary on the seat ladder gives level
    3's static tension of this chain with no pretension (:func:`sag_tension`), or None where
    level 3 has no equilibrium, carries no more than the ladder's raw law, or needs a sag term
    more than ``SAG_RATIO`` times off the parabola's."""
    p0 = dict(params, **{"chain.pretension": 0.0})
    t3 = sag_tension(drive, p0)
    if t3 is None:
        return None
    x, d = ST.static_numerator(drive, p0)
    raw0 = x / d
    if not t3 > max(raw0, 0.0):
        return None
    s3 = d * t3 * t3 * (t3 - raw0)
    s = SG.sag_term(drive, p0)
    if not 1.0 / SAG_RATIO <= s3 / s <= SAG_RATIO:
        # level 3 parts from the ladder at rest for reasons other than the weight (a coarse
        # polygon, seat flanks: docs/reduced_models.md "Not yet one quantity")
        return None
    return s3


def fallbacks(drive: Drive, params: Mapping[str, Any], level: int | None = None) -> list[str]:
    """Where ``torsional.wrap_statics`` was honoured at levels 0-2 on a weaker fit than its
    own (sentences, empty if none): the spans hold level 3's static tension at angle 0, not its
    tooth-period mean (levels 0-2); level 3 had no linear mode (:func:`wrap_fit` took the
    static secant K_3), or the model of ``level`` could not be fitted to it (:mod:`chainmodel.
    models.torsional_mode`: the ends stay on K_m; levels 1-2). chainmodel.validity turns each
    into a warning."""
    if level == 3:          # level 3 its own statics
        return []
    key = parameters_key(drive, params)
    found = [_FELL_BACK[("held",) + key]] if ("held",) + key in _FELL_BACK else []
    if level == 0:          # level 0 takes the held tension and the floor from the fit, no mode
        return found
    if (None,) + key in _FELL_BACK:
        found.insert(0, _FELL_BACK[(None,) + key])
    if ("swap",) + key in _FELL_BACK:
        found.append(_FELL_BACK[("swap",) + key])
    own = (level,) + parameters_key(drive, params, skip=_OWN_SKIP)
    if level is not None and own in _FELL_BACK:
        found.append(_FELL_BACK[own])
    return found


def note_fallback(level: int, drive: Drive, params: Mapping[str, Any],
                  why: str | None) -> None:
    """Record (``why``) or clear (None) the fallback of ``level`` 's own fit for
    :func:`fallbacks`."""
    key = (level,) + parameters_key(drive, params, skip=_OWN_SKIP)
    if why is None:
        _FELL_BACK.pop(key, None)
    else:
        _FELL_BACK[key] = why


def unavailable(drive: Drive, params: Mapping[str, Any]) -> str | None:
    """Why ``torsional.wrap_statics`` could not be honoured for this drive when a level 0-2
    model asked (level 3's statics found no equilibrium, or the fit refused it: :func:`_plausible`
    and a chain with no tension at rest), or None; the model then held its span ends with the
    seat ladder. chainmodel.validity turns it into a warning."""
    if drive is None or drive.links is None or not params.get("torsional.wrap_statics"):
        return None
    return _FAILED.get(parameters_key(drive, params))


def honoured(drive: Drive, params: Mapping[str, Any]) -> bool:
    """Whether the span ends come from the wrap fit: ``torsional.wrap_statics`` on, a drive
    with a link count, and the fit (already attempted, as building the model's span ends does)
    not refused (:func:`unavailable`)."""
    return (bool(params.get("torsional.wrap_statics")) and drive is not None
            and drive.links is not None and unavailable(drive, params) is None)


def sag_tension(drive: Drive, params: Mapping[str, Any]) -> float | None:
    """Level 3's static span tension [N] of this drive at rest, no load (its static
    equilibrium, gravity included: :func:`~chainmodel.models.multibody_statics.static_state`),
    or None where the statics find no equilibrium; cached per drive and parameters."""
    key = ("sag",) + parameters_key(drive, params)
    if key not in _CACHE:
        from .multibody import MultibodyModel          # when first needed (see wrap_fit)
        from .multibody_statics import static_state
        try:
            t0 = static_state(MultibodyModel(drive, {k: v for k, v in params.items()
                                                      if k in PRM.BY_NAME})).mean_tension
        except ValueError:
            t0 = None
        if len(_CACHE) > 256:
            _CACHE.clear()
        _CACHE[key] = t0
    return _CACHE[key]


def static_span_tension(drive: Drive, params: Mapping[str, Any], *, exact: bool = True,
                        fitted: bool = True) -> float:
    """Levels 0-2's static span tension [N], the drive's as the scene defines it (at rest, no
    load, driver at angle 0): with ``torsional.wrap_statics`` level 3's there (the fit's T_0;
    the spans themselves hold level 3's tooth-period mean, :func:`held_span_tension`); else
    :func:`weighted_static_tension` (``exact`` passed on).

    ``fitted=False`` with ``torsional.wrap_statics``: level 3's static tension itself
    (:func:`sag_tension`, one static solve) without the fit's load steps and linearisations (a
    scene's pretension search: its trials need only the tension). Where the fit would then
    fail, the model holds the seat ladder's tension instead and :func:`unavailable` says so."""
    if drive.links is None:
        return ST.static_span_tension(drive, params)
    if params.get("torsional.wrap_statics") and not fitted:
        t3 = sag_tension(drive, params)
        if t3 is not None:
            return t3
    fit = _honoured_fit(drive, params)
    if fit is not None:
        return fit.static_tension
    return weighted_static_tension(drive, params, exact=exact)


def held_span_tension(drive: Drive, params: Mapping[str, Any]) -> float:
    """The tension levels 0-2's span law holds at rest, no load [N] (its tooth-period-mean
    geometry): with ``torsional.wrap_statics`` level 3's tooth-period mean, which the fitted
    ends hold by construction (``WrapFit.held_tension``); else the static span tension
    (:func:`static_span_tension`), which the seat ladder holds."""
    fit = _honoured_fit(drive, params) if drive.links is not None else None
    return fit.held_tension if fit is not None else static_span_tension(drive, params)


def _honoured_fit(drive: Drive, params: Mapping[str, Any]) -> WrapFit | None:
    """The wrap fit where ``torsional.wrap_statics`` is honoured (:func:`honoured`; fitting
    it, or recording its refusal, through :func:`span_ends` as a model build does), else
    None."""
    if not params.get("torsional.wrap_statics"):
        return None
    span_ends(drive, params)
    return wrap_fit(drive, params) if honoured(drive, params) else None


def softplus(raw: float, b: float) -> float:
    """The span law's floor under the slack span, (raw + sqrt(raw^2 + 4 b^2)) / 2 (raw itself
    for b = 0, clamped at 0; spans.py ``_tension``)."""
    if b <= 0.0:
        return max(raw, 0.0)
    r = math.sqrt(raw * raw + 4.0 * b * b)
    return 0.5 * (raw + r) if raw > 0 else 2.0 * b * b / (r - raw)


def raw_tension(t0, b):
    """The raw (linear-law) tension whose floored value (:func:`softplus`) is t0: t0 - b^2 /
    t0; t0 itself without a floor (b = 0)."""
    if b <= 0.0:
        return t0
    return t0 - b * b / t0


def _slope(raw, b):
    return 1.0 if b <= 0.0 else 0.5 * (1.0 + raw / math.sqrt(raw * raw + 4.0 * b * b))


def modal_stiffness(drive: Drive, params: Mapping[str, Any], omega: float) -> float:
    """K_m [N m/rad]: the driven sprocket's stiffness R_o^2 k at which levels 1-2's two-inertia
    system (:mod:`.chain_inertia`: their sprocket mass matrix M and stiffness matrix K(k) on
    spans of stiffness k at the pitch radii, the input shaft's spring on the driver unless it
    is rigid) has a mode at ``omega``. det(K(k) - omega^2 M) is linear in k (the spans' part of K
    has rank one), so its root comes from two evaluations; rigid, k = omega^2 M22 / R_o^2.
    Raises ValueError where no positive k puts the driven sprocket's mode there."""
    m = sprocket_mass_matrix(drive, params)
    ro = drive.driven.pitch_radius
    w2 = omega * omega
    k = w2 * m[1, 1] / (ro * ro)
    if not params["input_shaft.rigid"]:
        # the rigid root sets the scale of the second evaluation (no cancellation)
        d0, d1 = (float(np.linalg.det(two_inertia_stiffness(drive, params, kk) - w2 * m))
                  for kk in (0.0, k))
        k = k * d0 / (d0 - d1)
    if not k > 0.0:
        raise ValueError(f"no span stiffness puts levels 1-2's driven mode at "
                         f"level 3's {omega / (2 * math.pi):.4g} Hz")
    return float(k * ro * ro)


def _compliance(target, n_up, n_low, k, su, sl):
    """c with su / (n_up / k + c) + sl / (n_low / k + c) = target (span stiffness per R_o^2)."""
    # scipy.optimize imported with this module made an FMU's every fmi2Instantiate grow the
    # process (1.3 MB over 500; tests/test_fmu_embedding.py): imported where first needed
    from scipy.optimize import brentq

    def stiff(c):
        return su / (n_up / k + c) + sl / (n_low / k + c)

    lo = -0.999 * min(n_up, n_low) / k
    hi = max(n_up, n_low) / k
    while stiff(hi) > target:
        hi *= 4.0
    return float(brentq(lambda cc: stiff(cc) - target, lo, hi, xtol=1e-18, rtol=1e-13))


def _floored(raw: float, b: float, ks: float) -> float:
    """The span law's tension with a sag term: T = softplus(raw + ks / T^2, b) (``ks`` = k_eff
    S [N^3]: the sag's stretch S / T^2 the law adds; softplus itself for ks = 0)."""
    t = softplus(raw, b)
    if ks <= 0.0:
        return t
    from scipy.optimize import brentq
    # g(T) = T - softplus(raw + ks / T^2, b) rises in T; <= 0 at softplus(raw, b), >= 0 at
    # max(raw, 0) + b + ks^(1/3) (zero there for raw = b = 0: hence the margin)
    lo = max(t, 1e-9 * ks ** (1.0 / 3.0))
    hi = max(raw, 0.0) + b + 1.5 * ks ** (1.0 / 3.0)
    return float(brentq(lambda tt: tt - softplus(raw + ks / (tt * tt), b), lo, hi,
                        xtol=1e-12 * hi, rtol=1e-13))


def _split_slack(t0, b, c, spans, dt):
    """The slack span's tension of the level's law at rest under a load whose tension
    difference is dt: both spans' raw tensions move by their stiffness times one rotation u
    from where each holds t0, _floored(R_u + k_u u) - _floored(R_l - k_l u) = dt (``spans``:
    n_up, n_low, k, their sag terms)."""
    from scipy.optimize import brentq
    n_up, n_low, k, (s_up, s_low) = spans
    ku, kl = 1.0 / (n_up / k + c), 1.0 / (n_low / k + c)
    t0_lin = raw_tension(t0, b)
    # at u = 0 each span's raw tension plus its sag's k S / t0^2 is t0_lin: both hold t0
    r_u, r_l = t0_lin - ku * s_up / (t0 * t0), t0_lin - kl * s_low / (t0 * t0)

    def diff(u):
        return (_floored(r_u + ku * u, b, ku * s_up) - _floored(r_l - kl * u, b, kl * s_low)
                - dt)

    hi = dt / min(ku, kl)
    while diff(hi) < 0:
        hi *= 2.0
    u = brentq(diff, 0.0, hi, xtol=1e-15)
    return _floored(r_l - kl * u, b, kl * s_low)


def _softness(t0, slack3, c, spans, dt):
    """b with which the level's law's slack span under dt is level 3's slack3 (T_0 kept)."""
    from scipy.optimize import brentq

    def err(b):
        return _split_slack(t0, b, c, spans, dt) - slack3

    hi = max(slack3, 1e-3)
    while err(hi) < 0 and hi < 1e3 * t0:
        hi *= 2.0
    if err(hi) < 0:
        return 0.0
    if err(1e-9 * t0) > 0:      # the sag alone holds the slack span above level 3's
        return 0.0
    return float(brentq(err, 1e-9 * t0, hi, xtol=1e-9 * t0))


def _loaded(model, rest, load):
    """The equilibrium under ``load``, Newton started from the unloaded one ``rest`` (a sagging
    span's load step is small next to its distance from the straight layout)."""
    from .multibody_statics import solve_statics, static_state
    try:
        return solve_statics(model, 0.0, load, start=rest.state)
    except ValueError:
        return static_state(model, 0.0, load)
