"""``fidelity = "auto"``: the cheapest level and stepper that the measured trade table says meet
an accuracy target on the outputs asked for (issue 11; docs/tradeoff.md).

The table is chainmodel/data/tradeoff.csv, written by ``chainmodel bench tradeoff``
(:mod:`chainmodel.analysis.trade_study`): per measured scene and configuration (level x stepper
x tolerance or step), the wall time per simulated second and the relative error of eight
figures against a converged level-3 reference. :func:`choose`

1. maps the requested outputs to the figures that measure them (:data:`OUTPUT_FIGURES`); an
   output that only level 3 computes (:data:`LEVEL3_ONLY`: levels 0-2 give quasi-static
   estimates) forces level 3, the midspan deflection forces level >= 2;
2. finds the nearest measured scene whose level-3 reference is valid (a scene marked
   "reference invalid" is never a source): the Euclidean distance between the natural
   logarithms of the groups of :func:`scene_features` (meshing frequency over the lowest
   quasi-static mode and over the first span mode, 1 + load over static tension, both tooth
   counts, the chain's pitch); the answer is *extrapolated* when that distance exceeds 1 (the
   scene is more than a factor e = 2.7 away in one group, or a factor 2 in two) or the
   scene's meshing frequency is more than a factor 2 beyond the table's range of
   mesh_over_mode;
3. takes the cheapest configuration whose error on every requested figure is at most
   ``accuracy`` on every measured scene within distance 1 (the nearest one at least; measured
   on each of them: a level that refused one has no worst case there) and which the scene
   accepts (level 0 refuses speeds above half its lowest quasi-static mode, level 2
   a slack span); if none meets the target, the most accurate one, and says so. The table's
   errors count the reference's uncertainty band (worst case over level 3 with the values no
   source gives at x0.5 and x2 and the joint damping at its joint-friction factor,
   chainmodel.analysis.trade_study.band_errors). For a span tension (:data:`SPAN_FIGURES`)
   on a drive that is not a measured scene, the configurations of levels 0-2 whose meshing
   lies at or above the line from which their level warns that its spans miss string modes
   (:data:`SPAN_LINES`, below) are passed over where a level 0-2 below its own line meets the
   target: their table error does not carry over to this drive (on the audits' drives of
   docs/tradeoff.md, the 17 where this changes the choice read the tight span 4-88 %
   off level 3's band with the cheaper level, 2-44 % with the level 2 taken in its place;
   level 3 is not taken for that alone);
4. **promises** that error (the largest over those neighbouring scenes) only when the answer
   is not extrapolated, the target is met and at least half of the error is the level's own
   (its error against the nominal reference, :data:`MODEL_ERROR_SHARE`) rather than level 3's
   uncertainty band, which does not carry over between drives (not asked of a measured scene
   itself, whose band was measured: :data:`SAME_SCENE`), and, for a ripple figure
   (:data:`RIPPLE_FIGURES`), it was measured on at least :data:`RIPPLE_NEIGHBOURS`
   neighbouring scenes, and, for a span tension of levels 0-2, the drive's meshing lies
   below the line from which that level warns that its spans miss string modes, with the
   span's first string mode taken at the static tension (``mesh_over_span``, an upper bound
   of the slack span's; :data:`SPAN_FIGURES`, :data:`SPAN_LINES`); the promise is meant to hold
   within 2x on a drive outside the table (tests/test_tradeoff.py measures it). Otherwise
   ``promised`` is False and the message says it cannot promise, and why.

Physics does not import this module (the library's ``simulate``, the CLI and the FMU adapter
do).
"""

from __future__ import annotations

import csv
import logging
import math
from dataclasses import dataclass, field
from functools import lru_cache
from importlib import resources
from typing import Any

from .models import ALL_OUTPUTS, model_class
from .models.limits import span_string_frequency
from .parameters import FIDELITY_NAMES
from .validity import LEVEL2_SPAN_MODE_RATIO, SPAN_MODE_SHARE

__all__ = ["AutoChoice", "choose", "scene_features", "table", "OUTPUT_FIGURES", "LEVEL3_ONLY",
           "FIGURES", "DEFAULT_ACCURACY", "validate_request", "parse_rows"]

log = logging.getLogger("chainmodel.fidelity_auto")

#: the figures of the table (chainmodel.analysis.trade_study.METRICS)
FIGURES = ("mean_tight_tension", "peak_tight_tension", "mean_slack_tension",
           "peak_slack_tension", "driven_speed_ripple", "input_torque_ripple", "mesh_amplitude",
           "transmission_error")
#: output name -> the figures of the table that measure it
OUTPUT_FIGURES = {
    "tight_span.tension": ("mean_tight_tension", "peak_tight_tension"),
    "slack_span.tension": ("mean_slack_tension", "peak_slack_tension"),
    "driven.speed": ("driven_speed_ripple", "mesh_amplitude"),
    "driven.acceleration": ("driven_speed_ripple", "mesh_amplitude"),
    "velocity_ratio": ("driven_speed_ripple", "mesh_amplitude"),
    "input_shaft.torque": ("input_torque_ripple",),
    "transmission_error": ("transmission_error",),
    "driven.angle": ("transmission_error",),
    # exact at every level (the input's own motion, the geometry of the polygon)
    "driver.angle": (), "driver.speed": (), "tight_span.length": (),
}
#: outputs only level 3 computes; levels 0-2 report quasi-static estimates (output_descriptions)
LEVEL3_ONLY = ("chain.max_link_tension", "contact.max_force", "chain.min_link_tension")
#: outputs zero below level 2 (no transverse span motion)
LEVEL2_UP = ("tight_span.midspan_deflection",)
DEFAULT_ACCURACY = 0.05
#: nearest-scene distance (natural-log units) beyond which the choice is called extrapolated
EXTRAPOLATION_DISTANCE = 1.0
#: the share of a configuration's worst-case error (over the neighbours' bands) that its error
#: against the nominal reference must reach for a promise. The band is a property of each
#: drive's unknown values and does not carry over from one drive to another; the level's own
#: error does. With a nominal error E_n >= 0.5 E of the promised E (so the neighbours' band
#: adds B <= E_n), E_n + 3 B <= 2 E: the promise holds within 2x for a drive whose band is up to
#: 3x its neighbours'. Below that share the "error" is mostly level 3's own uncertainty, which
#: the drive may have much more of (an unseen 10B 11/33 drive: 15-45x its neighbour's band,
#: docs/tradeoff.md "Auditing the promise").
MODEL_ERROR_SHARE = 0.5
#: a drive this close to a measured scene (natural-log units; the table keeps six digits) is
#: that scene: its own band was measured, so the model-error share is not asked of it
SAME_SCENE = 1e-3
#: figures governed by where the meshing sits against each drive's own modes: their error
#: is promised only from at least :data:`RIPPLE_NEIGHBOURS` neighbouring measured scenes
#: (one scene does not show how it varies: on the 16B mixer level 1's driven-speed ripple is
#: 14 % off at 200 rpm and 58 % at 500 rpm, and promised from 200 rpm it was 2-5x off at 100
#: and 150 rpm, on the 12B conveyor and an unseen 10B drive; docs/tradeoff.md, "Auditing
#: the promise")
RIPPLE_FIGURES = ("driven_speed_ripple", "input_torque_ripple", "mesh_amplitude",
                  "transmission_error")
#: span tensions: promised from levels 0-2 only below the line where that level warns that its
#: spans miss string modes (:data:`SPAN_LINES`, chainmodel.validity's span_modes_missing and
#: span_modes_beyond). Above it the level's error is the spans' bowing, which follows each
#: drive's string modes, load share and pretension and does not carry over from a measured
#: scene: an audit of 60 `new-scene` drives at 200-600 rpm loaded to their static tension had
#: level 1 promise 11.5 % on the tight span and miss by 2-17x on 37 of 61 promised cases
#: (docs/tradeoff.md, "Auditing the promise")
SPAN_FIGURES = OUTPUT_FIGURES["tight_span.tension"] + OUTPUT_FIGURES["slack_span.tension"]
SPAN_LINES = {0: SPAN_MODE_SHARE, 1: SPAN_MODE_SHARE, 2: LEVEL2_SPAN_MODE_RATIO}
RIPPLE_NEIGHBOURS = 2


def scene_features(scene, model=None) -> dict[str, float]:
    """Dimensionless groups that place a scene among the measured ones:

    * ``mesh_over_mode``: meshing frequency z1 n / 60 over the lowest quasi-static mode of the
      drive (the driven sprocket's torsional or the spans' first axial frequency, the one
      level 0 is limited by: it refuses above 0.5);
    * ``mesh_over_span``: meshing frequency over the first transverse frequency of a span of
      length (N + f) p at the static tension T0, (1 / 2L) sqrt(T0 / rho) (resonance near 1, 2);
    * ``load_over_static``: the load's span tension, load torque / r_o, over T0 (above about 1
      the slack span unloads towards zero);
    * ``z1``, ``z2``: the tooth counts (polygonal action ~ 1 / z);
    * ``pitch_mm``: the chain's pitch (the chain size: its stiffnesses, mass and clearances).

    ``model``: the scene's level-0 model when the caller has built it (choose() does)."""
    if model is None:
        model = scene.with_overrides(fidelity=0).model()
    d = model.drive
    pitch_mm = 1e3 * d.pitch
    f_mesh = d.n_driver * abs(scene.operating.speed) / (2 * math.pi)
    f_t, f_ax = model._frequencies
    t0 = max(float(model.static_tension()), 1e-9)
    rho = scene.parameters["chain.link_mass"] / d.pitch
    f_span = span_string_frequency((d.span_pitches + d.pitch_fraction) * d.pitch, t0, 0.0, rho)
    load = abs(scene.operating.load_torque) / d.driven.pitch_radius
    return {"mesh_over_mode": f_mesh / min(f_t, f_ax), "mesh_over_span": f_mesh / f_span,
            "load_over_static": load / t0, "z1": float(d.n_driver), "z2": float(d.n_driven),
            "pitch_mm": pitch_mm}


def _log_groups(f: dict) -> tuple[float, ...]:
    # log(x + small) so that 0 rpm (mesh ratios 0) stays finite: it sits far below every
    # measured scene and is called extrapolated, as it should be
    return (math.log(f["mesh_over_mode"] + 1e-3), math.log(f["mesh_over_span"] + 1e-3),
            math.log(1.0 + f["load_over_static"]), math.log(f["z1"]), math.log(f["z2"]),
            math.log(f["pitch_mm"]))


@lru_cache(maxsize=None)
def table() -> tuple[dict, ...]:
    """Rows of chainmodel/data/tradeoff.csv (numbers as floats; '' as None)."""
    return tuple(parse_rows(resources.files(__package__).joinpath("data", "tradeoff.csv")
                            .read_text()))


def parse_rows(text: str) -> list[dict]:
    """Rows of a trade-study CSV (``#`` comment lines skipped; numbers as floats, '' as None)."""
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]
    rows = []
    for r in csv.DictReader(lines):
        out = {}
        for k, v in r.items():
            if k in ("scene", "config", "level_name", "method", "status", "note", "span_source",
                     "reference_note"):
                out[k] = v
            elif k == "level":
                out[k] = int(v)
            else:
                out[k] = float(v) if v not in ("", None) else None
        rows.append(out)
    return rows


@dataclass
class AutoChoice:
    """What :func:`choose` picked and why."""
    level: int
    overrides: dict               # scene overrides: fidelity, solver_method, solver_tolerance...
    config: str                   # the table's name of the configuration
    expected_error: float         # largest table error over the requested figures
    figures: tuple                # the requested figures
    source_scene: str             # nearest measured scene
    distance: float
    extrapolated: bool
    met: bool                     # the table says the target is met
    accuracy: float
    notes: list = field(default_factory=list)
    #: the model :func:`choose` built to check that the chosen level accepts the scene (its
    #: scene differs from the chosen one only in solver settings, which no model reads):
    #: simulate() runs it instead of building it again
    model: Any = field(default=None, repr=False, compare=False)
    #: the expected error is promised (to hold within 2x) only for a drive near measured ones
    #: with the target met; otherwise False and ``why_not`` says why
    promised: bool = False
    why_not: str = ""
    neighbours: tuple = ()        # the measured scenes the expected error is the largest over
    #: the scene that runs: the given one with :attr:`overrides` applied, built once while
    #: checking the level (simulate() runs it as it is)
    scene: Any = field(default=None, repr=False, compare=False)
    #: the levels whose model was built, in the order checked (cheapest acceptable first)
    levels_checked: tuple = ()
    #: the same configuration's largest error against the nominal reference alone (no band)
    #: over the same neighbours: the part of expected_error that is the level's own
    nominal_error: float = math.nan

    @property
    def message(self) -> str:
        if self.figures:
            s = (f"fidelity auto: {self.config} ({FIDELITY_NAMES[self.level]}), expected error "
                 f"{100 * self.expected_error:.3g} % on {', '.join(self.figures)} against "
                 f"level 3 over its uncertainty band "
                 f"(target {100 * self.accuracy:g} %{'' if self.met else ', NOT met by any measured configuration'}); "
                 f"source: chainmodel/data/tradeoff.csv, scene '{self.source_scene}' at "
                 f"distance {self.distance:.2f}")
        else:   # outputs only level 3 computes: the table measures no error for them
            s = (f"fidelity auto: {self.config} ({FIDELITY_NAMES[self.level]}); the table "
                 f"measures no error for the outputs asked, so none is expected (the "
                 f"configuration from scene '{self.source_scene}' at distance "
                 f"{self.distance:.2f}, chainmodel/data/tradeoff.csv)")
        if self.extrapolated:
            s += " (extrapolated: this scene is outside the measured ones)"
        if self.promised:
            s += (f"; promised: error <= {100 * self.expected_error:.3g} % (meant to hold "
                  f"within 2x; worst case over {', '.join(self.neighbours)})")
        else:
            s += f"; cannot promise an error: {self.why_not}"
        if self.notes:
            s += "; " + "; ".join(self.notes)
        return s


def validate_request(outputs, accuracy) -> tuple[tuple[str, ...], float]:
    """Check and normalise ``outputs`` (names of outputs or figures; None: all figures) and
    ``accuracy`` (a relative error in (0, 1]); ValueError naming the parameter otherwise."""
    known = set(OUTPUT_FIGURES) | set(LEVEL3_ONLY) | set(LEVEL2_UP) | set(FIGURES)
    if outputs is None:
        outputs = FIGURES
    elif isinstance(outputs, str):
        outputs = tuple(o.strip() for o in outputs.split(",") if o.strip())
    else:
        outputs = tuple(outputs)
    if not outputs:
        raise ValueError("outputs must name at least one output, got an empty list; valid: "
                         + ", ".join(sorted(known)))
    bad = [o for o in outputs if not isinstance(o, str) or o not in known]
    if bad:
        raise ValueError(f"outputs {bad} not known to fidelity='auto'; valid: "
                         + ", ".join(sorted(known)))
    if accuracy is None:
        accuracy = DEFAULT_ACCURACY
    try:
        acc = float(accuracy)
    except (TypeError, ValueError):
        acc = math.nan
    if isinstance(accuracy, bool) or not (0.0 < acc <= 1.0):
        raise ValueError(f"accuracy must be a relative error in (0, 1] (0.05 = 5 %), "
                         f"got {accuracy!r}")
    return outputs, acc


def _level_model(scene, row, drive, level0):
    """(scene, model) of ``scene`` with ``row``'s settings (:func:`_row_settings`) if its
    level accepts the scene's operating point, else None. The model is built on ``drive``
    (the geometry does not depend on the level or the solver); ``level0``: the (scene, model)
    at level 0 already built for the features, reused when the row is level 0's."""
    try:
        settings = _row_settings(row)
        if settings == {"fidelity": 0}:
            sc, model = level0
        else:
            sc = scene.with_overrides(**settings)
            model = model_class(sc.fidelity)(drive, sc.parameters)
        sc.check_operating_point(model)
    except ValueError:
        return None
    return sc, model


def choose(scene, outputs=None, accuracy=None, rows=None) -> AutoChoice:
    """The cheapest configuration the table says meets ``accuracy`` on ``outputs`` for
    ``scene`` (see the module docstring)."""
    outputs, accuracy = validate_request(outputs, accuracy)
    rows = table() if rows is None else rows
    min_level, notes = 0, []
    if any(o in LEVEL3_ONLY for o in outputs):
        min_level = 3
        notes.append("level 3 forced: " + ", ".join(o for o in outputs if o in LEVEL3_ONLY)
                     + " are quasi-static estimates below it")
    elif any(o in LEVEL2_UP for o in outputs):
        min_level = 2
        notes.append("level >= 2 forced: the midspan deflection is zero below it")
    figs = tuple(dict.fromkeys(f for o in outputs
                               for f in (OUTPUT_FIGURES.get(o, ()) if o not in FIGURES else (o,))))
    sc0 = scene if scene.fidelity == 0 else scene.with_overrides(fidelity=0)
    model0 = sc0.model()
    features = scene_features(scene, model0)
    here = _log_groups(features)
    by_scene: dict[str, list] = {}
    for r in rows:
        by_scene.setdefault(r["scene"], []).append(r)
    # a scene whose reference is invalid (every row "reference invalid") is no source,
    # and neither is one whose reference runs outside level 3's validity (warnings)
    by_scene = {k: v for k, v in by_scene.items() if any(r["status"] == "ok" for r in v)
                and not (v[0].get("reference_problems") or 0)}
    if not by_scene:
        raise ValueError("fidelity='auto': the trade table has no scene with a valid reference")
    dist = {}
    for name, rs in by_scene.items():
        there = _log_groups(rs[0])
        dist[name] = math.sqrt(sum((a - b) ** 2 for a, b in zip(here, there)))
    source = min(dist, key=dist.get)
    f_here = features["mesh_over_mode"]
    span = [rs[0]["mesh_over_mode"] for rs in by_scene.values()]
    in_range = 0.5 * min(span) <= f_here <= 2.0 * max(span)
    extrapolated = dist[source] > EXTRAPOLATION_DISTANCE or not in_range
    neighbours = sorted((n for n in dist if dist[n] <= EXTRAPOLATION_DISTANCE),
                        key=dist.get) or [source]

    def own_error(r, kind="err"):
        errs = [r.get(f"{kind}_{f}") for f in figs]
        errs = [e for e in errs if e is not None and math.isfinite(e)]
        return max(errs) if errs else 0.0

    # a configuration's error here: the worst over the neighbouring scenes that ran it (over
    # their bands, and against their nominal references alone)
    by_config, by_config_nominal = {}, {}
    for n in neighbours:
        for r in by_scene[n]:
            if r["status"] == "ok":
                by_config.setdefault(r["config"], []).append(own_error(r))
                by_config_nominal.setdefault(r["config"], []).append(own_error(r, "errnom"))

    def error(r):
        return max(by_config.get(r["config"], [own_error(r)]))

    def covered(r):
        # measured on every neighbour: a level that refused one of them (level 0 above its
        # speed limit) has no error there, and a worst case over fewer scenes is no worst case
        return len(by_config.get(r["config"], ())) == len(neighbours)

    cands = [r for r in by_scene[source] if r["status"] == "ok" and r["level"] >= min_level
             and (not figs or all(r[f"err_{f}"] is not None for f in figs))]

    def spans_missed(r):
        # span tensions asked of a level whose spans miss string modes here (SPAN_LINES): no
        # measured scene's error carries over to them
        return (dist[source] > SAME_SCENE and r["level"] in SPAN_LINES
                and any(f in SPAN_FIGURES for f in figs)
                and features["mesh_over_span"] >= SPAN_LINES[r["level"]])

    def meets(r):
        return error(r) <= accuracy and covered(r)

    # where span tensions are asked and a level 0-2 that holds the spans' string modes here
    # meets the accuracy, it goes before the cheaper ones that miss them: their table error does
    # not carry over to this drive (level 3 is not preferred for that alone)
    holds = any(meets(r) and r["level"] <= 2 and not spans_missed(r) for r in cands)

    # the cheapest row meeting the accuracy, else the most accurate (then cheapest), among the
    # rows whose level accepts the scene: levels are checked (a model built) in that order,
    # only until one accepts
    def rank(r):
        if meets(r):
            return (0, 1 if holds and spans_missed(r) else 0, r["wall_per_sim_s"], 0.0)
        return (1, 0 if covered(r) else 1, error(r), r["wall_per_sim_s"])

    # a level's first row tried either is accepted (the loop ends) or its level refuses the
    # scene, so one (scene, model) per level is built, with that row's settings
    built: dict = {}
    best = None
    for r in sorted(cands, key=rank):
        if r["level"] not in built:
            built[r["level"]] = _level_model(scene, r, model0.drive, (sc0, model0))
        if built[r["level"]] is not None:
            best = r
            break
    if best is None:
        raise ValueError(f"fidelity='auto' found no configuration of level >= {min_level} "
                         f"measured on '{source}' that this scene accepts")
    met = error(best) <= accuracy and covered(best)
    nominal = max(by_config_nominal.get(best["config"], [own_error(best, "errnom")]))
    sc, model = built[best["level"]]
    overrides = _overrides(sc, best, model)
    if overrides.get("solver_step", 0.0) != sc.parameters["solver.step"]:
        sc = sc.with_overrides(solver_step=overrides["solver_step"])
    why_not = ""
    if not figs:
        why_not = ("the table measures no error for " + ", ".join(outputs)
                   + " (only level 3 computes them)")
    elif not in_range:
        why_not = (f"its meshing frequency is {f_here:.3g} x its lowest quasi-static mode, more "
                   f"than a factor 2 outside the measured {min(span):.3g}-{max(span):.3g}")
    elif dist[source] > EXTRAPOLATION_DISTANCE:
        why_not = (f"the nearest measured scene '{source}' is {dist[source]:.2f} away (limit "
                   f"{EXTRAPOLATION_DISTANCE:g}) in {_far_groups(here, by_scene[source][0])}")
    elif not met:
        why_not = f"no measured configuration meets {100 * accuracy:g} % there"
        if error(best) <= accuracy:
            why_not += (f" on all {len(neighbours)} neighbouring measured scenes (this one was "
                        f"measured on {len(by_config.get(best['config'], ()))} of them; its "
                        "level refuses the others)")
    elif spans_missed(best):
        why_not = (f"its meshing is {features['mesh_over_span']:.3g} x its spans' first string "
                   f"mode at the static tension, at or above the {SPAN_LINES[best['level']]:g} x "
                   f"from which level {best['level']} warns that its spans miss string modes (the "
                   "slack span's mode, lower under load, crosses it first): there its span "
                   "tensions' error is the spans' bowing, which follows each drive's string "
                   "modes, load and pretension and does not carry over from a measured scene "
                   "(an audit of 60 new drives: level 1 promised 11.5 % and missed by 2-17x on "
                   "37 of 61 promises)")
    elif (dist[source] > SAME_SCENE and any(f in RIPPLE_FIGURES for f in figs)
          and len(by_config.get(best["config"], ())) < RIPPLE_NEIGHBOURS):
        why_not = (f"the table measured it on {len(by_config.get(best['config'], ()))} "
                   f"neighbouring scene ('{source}') where it needs {RIPPLE_NEIGHBOURS}: the "
                   "error of a ripple figure ("
                   + ", ".join(f for f in figs if f in RIPPLE_FIGURES)
                   + ") follows where the meshing sits against each drive's own modes, and one "
                   "scene does not show how it varies")
    elif dist[source] > SAME_SCENE and not nominal >= MODEL_ERROR_SHARE * error(best):
        why_not = (f"at the measured neighbours its {100 * error(best):.3g} % is mostly level 3's "
                   f"own uncertainty band (its error against the nominal reference is "
                   f"{100 * nominal:.3g} %); that band comes from values no source gives "
                   "(contact stiffness, seat clearance, joint damping) and differs from drive "
                   "to drive, so it does not carry over to this one")
    choice = AutoChoice(best["level"], overrides, best["config"],
                        error(best), figs, source, dist[source], extrapolated, met, accuracy,
                        notes, model, promised=not why_not, why_not=why_not,
                        neighbours=tuple(n for n in neighbours
                                         if any(r["config"] == best["config"]
                                                and r["status"] == "ok" for r in by_scene[n])),
                        scene=sc, levels_checked=tuple(built), nominal_error=nominal)
    log.info(choice.message)
    return choice


_GROUP_NAMES = ("meshing frequency / lowest quasi-static mode",
                "meshing frequency / first span mode", "1 + load / static tension",
                "driver teeth", "driven teeth", "chain pitch")


def _far_groups(here, row) -> str:
    """The groups in which a drive is farthest from a measured scene, largest first."""
    d = [(abs(a - b), name, math.exp(abs(a - b))) for a, b, name
         in zip(here, _log_groups(row), _GROUP_NAMES)]
    d.sort(reverse=True)
    return ", ".join(f"{name} (x{ratio:.2g})" for gap, name, ratio in d[:2] if gap > 0.05) \
        or "several groups"


def _row_settings(row) -> dict:
    """The scene overrides of a table row, with the automatic step (solver_step 0) where the
    row sets the step as a fraction of it."""
    lv = row["level"]
    out = {"fidelity": lv}
    if lv == 0:
        return out
    out["solver_method"] = row["method"]
    if row.get("tolerance") is not None:
        out["solver_tolerance"] = row["tolerance"]
    if row.get("step_fraction") is not None:
        out["solver_step"] = 0.0
    return out


def _overrides(scene, row, model) -> dict:
    """:func:`_row_settings` with the step fraction applied: ``scene`` and ``model`` are the
    row's (built with the automatic step)."""
    out = _row_settings(row)
    frac = row.get("step_fraction")
    if frac is not None and frac != 1.0:      # 1.0: level 3's own step
        out["solver_step"] = float(scene.stepper(model).h) * frac
    return out


def output_names() -> tuple[str, ...]:
    return tuple(o.name for o in ALL_OUTPUTS)


#: units of the FMU adapter's Real auto.* parameters (build_fmu.py writes them)
FMU_UNITS = {"auto.accuracy": "1", "auto.input_speed": "rad/s", "auto.load_torque": "N.m"}
#: the FMU adapter's auto.* parameters (names)
FMU_PARAMETERS = ("auto.enabled", "auto.outputs", *FMU_UNITS)

#: scene override keyword -> parameter name (for callers holding a parameter dict: the FMU)
_PARAM_OF = {"fidelity": "fidelity", "solver_method": "solver.method",
             "solver_tolerance": "solver.tolerance", "solver_step": "solver.step"}


def choose_parameters(params: dict, speed: float, load_torque: float, outputs=None,
                      accuracy=None) -> tuple[dict, AutoChoice]:
    """:func:`choose` for a validated parameter dict and an expected steady operating point
    (input speed [rad/s], load torque [N.m]); returns the parameters with fidelity and the
    solver settings replaced, and the choice. The FMU adapter calls this (it holds no physics
    and no selection logic of its own)."""
    from .scene import OperatingPoint, Scene
    sc = Scene("fmu", dict(params), OperatingPoint(abs(float(speed)), 0.05, float(load_torque)))
    choice = choose(sc, outputs, accuracy)
    new = dict(params)
    for key, value in choice.overrides.items():
        new[_PARAM_OF[key]] = value
    return new, choice
