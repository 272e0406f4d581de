"""The measured speed-accuracy trade over many scenes (issue 11): ``chainmodel bench tradeoff``.

For each scene of :data:`SCENES` every configuration of :data:`CONFIGS` (fidelity level x
stepper x tolerance or step) runs over the same short run and is compared with a converged
level-3 reference (Verlet at a quarter of level 3's own step, docs/multibody.md "Convergence":
its figures move by < 0.03 % from h to h/8). For every run the study records

* the wall time per simulated second, median of ``repeats`` warm runs (the kernels compiled
  and the model built once before), and the peak Python/numpy memory of one run (tracemalloc);
* the relative error against the reference of the figures of :data:`METRICS`, all over the
  steady window of :func:`chainmodel.analysis.summary.steady_window`, counted with the
  reference's uncertainty band (issue 21 item 7): the reference is rerun with each value no
  source gives (:data:`UNCERTAIN`) at x0.5 and x2, and with the joint damping at the value
  whose losses match the joint friction it stands in for where that lies outside x0.5-x2
  (:func:`joint_friction_factor`); the band is the min-max of each figure over those runs,
  and the error is the worst case over the band (:func:`band_errors`);
* whether the reference is valid (``Result.valid``, ``Result.warnings``): a scene whose
  reference is invalid is kept in the table as "reference invalid", without errors.

A level a scene refuses (level 0 above half its lowest quasi-static mode, level 2 with a slack
span) is recorded with status ``not valid here``, a run that fails with ``failed: ...``.
The rows are tidy (one per scene x configuration) and go to a CSV that
:mod:`chainmodel.fidelity_auto` reads at run time (chainmodel/data/tradeoff.csv).
"""

from __future__ import annotations

import csv
import hashlib
import json
import math
import statistics
import subprocess
import sys
import time
import tracemalloc
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..fidelity_auto import parse_rows as _parse_rows, scene_features
from ..loss_balance import balance_duration, run_shares
from ..models.base import SimulationDiverged
from ..parameters import FIDELITY_NAMES
from ..scene import Scene, load_scene
from ..simulation import run_scene
from .summary import steady_window

__all__ = ["SceneSpec", "Config", "SCENES", "CONFIGS", "METRICS", "scene_features", "metrics",
           "relative_errors", "run_study", "write_csv", "read_csv", "markdown", "plot",
           "cold_costs"]

#: figure key -> (label, summary key of Result.summary() where there is one)
METRICS = {
    "mean_tight_tension": ("mean tight-span tension", "mean_tight_tension_n"),
    "peak_tight_tension": ("peak tight-span tension", "peak_tight_tension_n"),
    "mean_slack_tension": ("mean slack-span tension", "mean_slack_tension_n"),
    "peak_slack_tension": ("peak slack-span tension", "peak_slack_tension_n"),
    "driven_speed_ripple": ("driven-speed ripple RMS", "driven_speed_ripple_rms_rad_s"),
    "input_torque_ripple": ("input-shaft torque ripple RMS", None),
    "mesh_amplitude": ("driven-speed amplitude at the meshing frequency", None),
    "transmission_error": ("transmission error RMS", None),
}
#: the tension figures' errors are relative to max(|reference|, this x the reference's mean tight
#: tension), so a slack span near zero tension does not turn a few newtons into 1000 %
TENSION_FLOOR = 0.02


@dataclass(frozen=True)
class SceneSpec:
    """A named scene of the study: a preset and scene overrides (load_scene keywords)."""
    name: str
    preset: str
    overrides: dict = field(default_factory=dict)

    def scene(self, **more) -> Scene:
        return load_scene(self.preset, **{**self.overrides, **more})


def _tight(n1, n2, links, pitch=0.015875):
    """Overrides for an n1/n2 drive at xu2010's pitch whose chain of ``links`` wraps tightly
    (centre distance from the links, seed 004 section 2), as tests/test_extremes.py builds them."""
    return dict(drive_driver_teeth=n1, drive_driven_teeth=n2, drive_links=links,
                drive_centre_distance=0.0)


_EXAMPLES = Path(__file__).resolve().parents[2] / "examples" / "scenes"

#: the study's scenes; durations keep >= 4 tooth periods in the steady half of the run
SCENES = (
    SceneSpec("xu2010 30 rpm", "xu2010", dict(input_speed_rpm=30, duration=0.8)),
    SceneSpec("xu2010 120 rpm", "xu2010", dict(input_speed_rpm=120, duration=0.4)),
    SceneSpec("xu2010 600 rpm", "xu2010", dict(input_speed_rpm=600, duration=0.2)),
    SceneSpec("xu2010 2000 rpm", "xu2010", dict(input_speed_rpm=2000, duration=0.15,
                                                 output_interval=5e-5)),
    SceneSpec("C1 100 rpm", "C1", dict(input_speed_rpm=100, duration=1.2)),
    SceneSpec("C1 400 rpm", "C1", dict(input_speed_rpm=400, duration=1.2)),
    SceneSpec("coarse 6/9 300 rpm", "xu2010", dict(_tight(6, 9, 16), static_tension=400,
                                                   load_torque=5.0, input_speed_rpm=300,
                                                   duration=0.3)),
    SceneSpec("long centre N=60 120 rpm", "xu2010", dict(_tight(25, 17, 144), static_tension=500,
                                                        load_torque=20.0, input_speed_rpm=120,
                                                        duration=0.4)),
    # two more chain sizes (issue 21 item 7), the example drives of examples/scenes/ with their
    # chain's own values (chainmodel.chains): 08B 19/38 teeth 120 links (the newcomer's drive
    # of issue 21 at 600-1300 rpm), 16B 15/30 teeth 70 links
    SceneSpec("08B fan 600 rpm", str(_EXAMPLES / "08b_fan_1500rpm.toml"),
              dict(input_speed_rpm=600, duration=0.4)),
    SceneSpec("08B fan 1200 rpm", str(_EXAMPLES / "08b_fan_1500rpm.toml"),
              dict(input_speed_rpm=1200, duration=0.3)),
    SceneSpec("16B mixer 200 rpm", str(_EXAMPLES / "16b_mixer.toml"),
              dict(input_speed_rpm=200, duration=0.6)),
    SceneSpec("16B mixer 500 rpm", str(_EXAMPLES / "16b_mixer.toml"),
              dict(input_speed_rpm=500, duration=0.4)),
)


@dataclass(frozen=True)
class Config:
    """One way to run a scene: a level, a stepper and its tolerance or step (as a fraction of
    level 3's own Verlet step)."""
    level: int
    method: str                    # rk4, rk45, verlet, or "-" for the stateless level 0
    tolerance: float | None = None  # solver.tolerance of the fixed-step rule
    step_fraction: float | None = None

    @property
    def label(self) -> str:
        if self.level == 0:
            return "0 kinematic"
        s = f"{self.level} {self.method}"
        if self.tolerance is not None:
            s += f" tol {self.tolerance:g}"
        if self.step_fraction is not None:
            s += f" h x {self.step_fraction:g}"
        return s

    def overrides(self, scene: Scene) -> dict:
        if self.level == 0:
            return dict(fidelity=0)
        out = dict(fidelity=self.level, solver_method=self.method)
        if self.tolerance is not None:
            out["solver_tolerance"] = self.tolerance
        if self.step_fraction is not None:
            out["solver_step"] = level3_step(scene) * self.step_fraction
        return out


def level3_step(scene: Scene) -> float:
    """The Verlet step level 3 chooses itself for ``scene`` (solver.step = 0)."""
    sc = scene.with_overrides(fidelity=3, solver_method="verlet", solver_step=0.0)
    return float(sc.stepper().h)


CONFIGS = (
    Config(0, "-"),
    *(Config(lv, "rk4", tol) for lv in (1, 2) for tol in (5e-3, 5e-4, 5e-5)),
    # rk45 left out since issue 21: the issue-11 study measured the same errors as rk4 on every
    # scene at 100-200x the cost (docs/tradeoff.md), and its rows were 3/4 of the wall time
    Config(3, "verlet", step_fraction=1.0),
    Config(3, "verlet", step_fraction=0.5),
)
REFERENCE = Config(3, "verlet", step_fraction=0.25)


#: the values no source gives, each run at x0.5 and x2 for the reference's uncertainty band
#: (issue 21 item 7): the roller-seat contact stiffness (seed 003's eq 16 level carried to the
#: chain by a Hertz ratio, chainmodel.chains), the seat clearance contact.seat_radius -
#: chain.roller_radius (ISO 606's minimum seating radius, a real sprocket's is larger) and the
#: pin-bushing joint damping (the schema's assumed value)
UNCERTAIN = (("contact.stiffness", 0.5), ("contact.stiffness", 2.0),
             ("seat_clearance", 0.5), ("seat_clearance", 2.0),
             ("chain.joint_damping", 0.5), ("chain.joint_damping", 2.0))


#: the joint damping is a viscous stand-in for pin-bushing friction sized on xu2010 at 120 rpm
#: (docs/multibody.md); its band also reaches the factor at which level 3's dampers dissipate
#: the joint friction of the scene (:func:`joint_friction_factor`) when that lies more than
#: this ratio outside the factors of UNCERTAIN (eighteenth session of issue 21: on the 16B
#: mixer x4 removes a slack-span vibration the x0.5-x2 band keeps, docs/reduced_models.md)
JOINT_FRICTION = "chain.joint_damping"
JOINT_FRICTION_MARGIN = 1.25


def joint_friction_factor(base: Scene, cache_dir: Path | None = None,
                          log=lambda s: None) -> float | None:
    """Joint friction over level 3's chain losses at the nominal values: the factor on
    ``chain.joint_damping`` that would make its dampers dissipate, to first order, the
    pin-bushing friction mu r_pin z1 (1/z1 + 1/z2) w1 (T_tight + T_slack) they stand in for
    (:class:`chainmodel.loss_balance.LossBalance`, mu = 0.1, r_pin of the scene's ISO 606
    chain). Level 3 at its own step over at least three driver revolutions (the balance starts
    after one and needs one more). None where the balance has no window, no ISO 606 chain or
    no loss; cached under ``cache_dir``."""
    sc = base.with_overrides(fidelity=3)
    sc = sc.with_overrides(duration=balance_duration(sc, sc.duration))
    path = None
    if cache_dir is not None:
        path = Path(cache_dir) / f"friction_{_cache_key(sc)}.json"
        if path.exists():
            return json.loads(path.read_text())["factor"]
    log(f"{sc.name}: joint friction against level 3's losses ({sc.duration:.3g} s) ...")
    shares = run_shares(run_scene(sc))
    factor = shares[1] / shares[0] if shares is not None and shares[0] > 0 else None
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({"factor": factor}))
    return factor


def band_variants(base: Scene, uncertain=UNCERTAIN, cache_dir: Path | None = None,
                  log=lambda s: None) -> list[tuple[str, float]]:
    """The (value, factor) runs of the scene's band: ``uncertain``, and the joint damping at
    :func:`joint_friction_factor` where that lies more than JOINT_FRICTION_MARGIN outside the
    joint damping's factors in ``uncertain`` (none when ``uncertain`` has no joint damping)."""
    out = list(uncertain)
    factors = [f for n, f in uncertain if n == JOINT_FRICTION]
    if factors:
        f = joint_friction_factor(base, cache_dir, log)
        if f is not None and not (min(factors) / JOINT_FRICTION_MARGIN <= f
                                  <= max(factors) * JOINT_FRICTION_MARGIN):
            out.append((JOINT_FRICTION, float(f"{f:.3g}")))
    return out


def band_overrides(scene: Scene, name: str, factor: float) -> dict:
    """Parameter overrides that scale the uncertain value ``name`` of ``scene`` by ``factor``.
    The contact damping follows the contact stiffness as sqrt(factor), keeping its fraction of
    critical damping (0.1 x 2 sqrt(k m), chainmodel.chains)."""
    p = scene.parameters
    if name == "seat_clearance":
        gap = p["contact.seat_radius"] - p["chain.roller_radius"]
        return {"contact.seat_radius": p["chain.roller_radius"] + factor * gap}
    if name == "contact.stiffness":
        return {"contact.stiffness": factor * p["contact.stiffness"],
                "contact.damping": math.sqrt(factor) * p["contact.damping"]}
    if name not in p:
        raise ValueError(f"uncertain value {name!r} is not a parameter of scene {scene.name!r}")
    return {name: factor * p[name]}


def band_scene(base: Scene, name: str, factor: float) -> tuple[Scene, str]:
    """``base`` at level 3 with the uncertain value scaled, keeping the scene's static tension
    target; where the variant cannot reach it (a stiffer contact on a chain that wraps tightly
    already gives more), the same assembly instead: the nominal's level-3 chain.pretension.
    Returns the scene and a note ('' or what was kept)."""
    over = band_overrides(base, name, factor)
    try:
        return base.with_overrides(over, fidelity=3), ""
    except ValueError as exc:
        if "static_tension" not in str(exc):
            raise
        pre = base.with_overrides(fidelity=3).parameters["chain.pretension"]
        return (base.with_overrides({**over, "chain.pretension": pre}, fidelity=3),
                f"static tension target unreachable ({str(exc).split(';')[0]}): the nominal's "
                f"chain.pretension {pre:.4g} N kept")


def band_label(name: str, factor: float) -> str:
    return f"{name} x{factor:g}"


# --- figures -------------------------------------------------------------------------------

def metrics(result) -> dict[str, float]:
    """The figures of :data:`METRICS` of one run over its steady window."""
    s = result.summary()
    t = result.time
    mask = steady_window(t, result.scene.operating.ramp_time, float(t[-1]))
    out = {k: float(s[key]) for k, (_, key) in METRICS.items() if key is not None}
    tight, slack, _ = span_tensions(result, mask)
    out.update(mean_tight_tension=float(np.mean(tight)), peak_tight_tension=float(np.max(tight)),
               mean_slack_tension=float(np.mean(slack)), peak_slack_tension=float(np.max(slack)))
    out["input_torque_ripple"] = float(np.std(result["input_shaft.torque"][mask]))
    out["transmission_error"] = float(np.std(result["transmission_error"][mask]))
    out["mesh_amplitude"] = mesh_amplitude(t[mask], result["driven.speed"][mask],
                                           float(s["meshing_frequency_hz"]))
    return out


#: outputs of the two physical spans, if the library gives them (issue 21 item 2)
PHYSICAL_SPANS = ("upper_span.tension", "lower_span.tension")


def span_tensions(result, mask) -> tuple[np.ndarray, np.ndarray, str]:
    """The tight and slack span's tension over ``mask``, each one physical span (issue 21 item
    2: a window's mean is the mean of one physical span).

    If the result has the two physical spans' outputs (:data:`PHYSICAL_SPANS`), the tight span
    is the one of larger mean over the window (the span the driver pulls under steady forward
    power flow) and the slack one the other; otherwise the ``tight_span`` / ``slack_span``
    outputs are read as they are: each is one physical span, since the library names the
    spans by their role, the driver's pull (kernels/span_roles.py; docs/tradeoff.md "Per-span
    means"). The third value says which source was used."""
    names = set(result.names)
    if all(n in names for n in PHYSICAL_SPANS):
        a, b = (np.asarray(result[n])[mask] for n in PHYSICAL_SPANS)
        return (a, b, "physical") if np.mean(a) >= np.mean(b) else (b, a, "physical")
    return (np.asarray(result["tight_span.tension"])[mask],
            np.asarray(result["slack_span.tension"])[mask], "roles")


def mesh_amplitude(t: np.ndarray, x: np.ndarray, f: float) -> float:
    """Amplitude of ``x`` at frequency ``f``: one-bin Fourier projection over the last whole
    number of periods in the window (no leakage from the mean); nan below one period."""
    if not (f > 0) or len(t) < 3:
        return math.nan
    periods = math.floor((t[-1] - t[0]) * f)
    if periods < 1:
        return math.nan
    keep = t >= t[-1] - periods / f - 0.5 * (t[1] - t[0])
    tt, xx = t[keep], x[keep] - np.mean(x[keep])
    return float(2.0 * abs(np.mean(xx * np.exp(-2j * math.pi * f * tt))))


def relative_errors(figs: dict, ref: dict) -> dict[str, float]:
    """|figure - reference| / scale per figure; the scale is |reference|, for tensions at least
    TENSION_FLOOR x the reference's mean tight tension."""
    floor = TENSION_FLOOR * abs(ref["mean_tight_tension"])
    out = {}
    for k in METRICS:
        scale = abs(ref[k])
        if "tension" in k:
            scale = max(scale, floor)
        out[k] = abs(figs[k] - ref[k]) / scale if scale > 0 and math.isfinite(figs[k]) \
            else math.nan
    return out


def band_errors(figs: dict, ref: dict, lo: dict, hi: dict) -> dict[str, dict[str, float]]:
    """Errors of ``figs`` counted with the reference's band [lo, hi] (nominal reference inside):

    * ``err``: the worst case over the band, max(|v - lo|, |v - hi|) / scale - a level *meets*
      a target only if this is within it (its error holds whichever value in the band is true);
    * ``errnom``: against the nominal reference alone, |v - ref| / scale (the old figure);
    * ``band``: the band's half-width (hi - lo) / 2 / scale, the reference's own uncertainty;
    * ``dist``: the distance from v to the band, max(0, lo - v, v - hi) / scale (0 inside it);

    scale as :func:`relative_errors` (|reference|, tensions at least TENSION_FLOOR x its mean
    tight tension)."""
    floor = TENSION_FLOOR * abs(ref["mean_tight_tension"])
    out = {"err": {}, "errnom": {}, "band": {}, "dist": {}}
    for k in METRICS:
        scale = abs(ref[k])
        if "tension" in k:
            scale = max(scale, floor)
        v = figs[k]
        if not (scale > 0 and math.isfinite(v) and math.isfinite(lo[k]) and math.isfinite(hi[k])):
            for d in out.values():
                d[k] = math.nan
            continue
        out["err"][k] = max(abs(v - lo[k]), abs(v - hi[k])) / scale
        out["dist"][k] = max(0.0, lo[k] - v, v - hi[k]) / scale
        out["errnom"][k] = abs(v - ref[k]) / scale
        out["band"][k] = 0.5 * (hi[k] - lo[k]) / scale
    return out


# --- running -------------------------------------------------------------------------------

def _cache_key(scene: Scene) -> str:
    blob = json.dumps({"parameters": {k: repr(v) for k, v in sorted(scene.parameters.items())},
                       "duration": scene.duration, "interval": scene.output_interval,
                       "operating": repr(scene.operating), "drive": repr(scene.drive)},
                      sort_keys=True)
    return hashlib.sha1(blob.encode()).hexdigest()[:16]


def _reference_run(base: Scene, label: str, cache_dir: Path | None, log) -> dict:
    """Level 3 at REFERENCE's step on ``base``: figures, wall time per simulated second,
    validity (Result.valid) and warnings; cached on disk under ``cache_dir`` by a hash of the
    whole scene (a change of any level-3 parameter reruns it)."""
    sc = base.with_overrides(**REFERENCE.overrides(base))
    path = None
    if cache_dir is not None:
        path = Path(cache_dir) / f"ref2_{_cache_key(sc)}.json"
        if path.exists():
            return json.loads(path.read_text())
    log(f"{label} ...")
    wall = time.perf_counter()
    r = run_scene(sc)
    data = {"figures": metrics(r), "cost": (time.perf_counter() - wall) / float(r.time[-1]),
            "valid": bool(r.valid), "warnings": list(r.warnings),
            "problems": [p.text for p in r.problems],
            "span_source": span_tensions(r, slice(None))[2]}
    if path is not None:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps(data))
    return data


def reference_band(spec: SceneSpec, cache_dir: Path | None = None, log=lambda s: None,
                   uncertain=UNCERTAIN) -> dict:
    """The scene's reference (level 3, Verlet at h/4) and its uncertainty band: the same run
    with each value of ``uncertain`` scaled (:func:`band_overrides`). Returns ``figures``,
    ``cost``, ``valid``, ``warnings`` of the nominal run; ``lo`` / ``hi`` per figure, the
    min-max over the nominal run and every valid band run; ``runs``: each band run's label,
    figures and validity (an invalid band run is left out of the band and named in
    ``dropped``)."""
    base = spec.scene()
    nominal = _reference_run(base, f"{spec.name}: reference {REFERENCE.label}", cache_dir, log)
    runs = []
    for name, factor in band_variants(base, uncertain, cache_dir, log):
        label = band_label(name, factor)
        try:
            sc, note = band_scene(base, name, factor)
            if (name, factor) not in uncertain:
                note = "; ".join(filter(None, [note, "the joint friction's factor"]))
            d = _reference_run(sc, f"{spec.name}: band {label}", cache_dir, log)
        except (ValueError, SimulationDiverged) as exc:   # refused or diverged: out, named
            d, note = {"figures": None, "valid": False, "warnings": [str(exc)]}, ""
        runs.append({"label": label, "note": note, **d})
    kept = [nominal["figures"]] + [r["figures"] for r in runs if r["valid"]]
    lo = {k: min(f[k] for f in kept) for k in METRICS}
    hi = {k: max(f[k] for f in kept) for k in METRICS}
    return {**nominal, "lo": lo, "hi": hi, "runs": runs,
            "dropped": [r["label"] for r in runs if not r["valid"]]}


def reference_figures(spec: SceneSpec, cache_dir: Path | None = None,
                      log=lambda s: None) -> tuple[dict, float]:
    """The nominal reference's figures and its wall time per simulated second."""
    d = _reference_run(spec.scene(), f"{spec.name}: reference {REFERENCE.label}", cache_dir, log)
    return d["figures"], d["cost"]


def measure(scene: Scene, repeats: int = 3) -> dict:
    """Figures, peak memory and median warm wall time per simulated second of ``scene``."""
    run_scene(scene.with_overrides(duration=min(scene.duration, 20 * scene.output_interval)))
    tracemalloc.start()
    r = run_scene(scene)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    figs = metrics(r)
    walls = []
    for _ in range(repeats):
        w = time.perf_counter()
        r = run_scene(scene)
        walls.append((time.perf_counter() - w) / float(r.time[-1]))
    return {"figures": figs, "peak_memory_mb": peak / 2 ** 20,
            "wall_per_sim_s": statistics.median(walls), "wall_spread": max(walls) - min(walls)}


def run_study(scenes=SCENES, configs=CONFIGS, repeats: int = 3, cache_dir: Path | None = None,
              log=lambda s: None, uncertain=UNCERTAIN) -> list[dict]:
    """One tidy row per scene x configuration (see the module docstring); ``uncertain``: the
    values varied for the reference's band (() for none: the band is the nominal run)."""
    rows = []
    for spec in scenes:
        base = spec.scene()
        feats = scene_features(base)
        band = reference_band(spec, cache_dir, log, uncertain)
        ref, ref_cost = band["figures"], band["cost"]
        # what makes the result invalid first ("the result is not valid: ..."), then warnings
        ref_note = "; ".join(sorted(band.get("problems") or band["warnings"],
                                    key=lambda w: not w.startswith("the result is not valid")))
        for cfg in configs:
            row = {"scene": spec.name, "level": cfg.level, "level_name": FIDELITY_NAMES[cfg.level],
                   "method": cfg.method, "tolerance": cfg.tolerance,
                   "step_fraction": cfg.step_fraction, "config": cfg.label, **feats,
                   "reference_wall_per_sim_s": ref_cost, "reference_valid": int(band["valid"]),
                   "reference_warnings": len(band["warnings"]),
                   "reference_problems": len(band.get("problems", [])),
                   "band_runs": 1 + len(band["runs"]) - len(band["dropped"]),
                   "span_source": band.get("span_source", ""),
                   "reference_note": ref_note[:400] if band.get("problems") else ""}
            if not band["valid"]:
                # a reference that means nothing (Result.valid False): the scene is kept in the
                # table, marked, with no errors; fidelity="auto" never uses it as a source
                row.update(status="reference invalid", note=ref_note[:400])
                rows.append(row)
                continue
            try:
                sc = base.with_overrides(**cfg.overrides(base))
                sc.check_operating_point(sc.model())
            except ValueError as exc:
                row.update(status="not valid here", note=str(exc).split(":")[0][:120])
                rows.append(row)
                log(f"{spec.name}: {cfg.label}: not valid here")
                continue
            try:
                m = measure(sc, repeats)
            except Exception as exc:  # noqa: BLE001 - recorded in the table, the study goes on
                row.update(status="failed", note=f"{type(exc).__name__}: {exc}"[:160])
                rows.append(row)
                log(f"{spec.name}: {cfg.label}: failed ({type(exc).__name__})")
                continue
            be = band_errors(m["figures"], ref, band["lo"], band["hi"])
            err = be["err"]
            row.update(status="ok", note="",
                       wall_per_sim_s=m["wall_per_sim_s"],
                       wall_spread=m["wall_spread"], peak_memory_mb=m["peak_memory_mb"],
                       **{f"{kind}_{k}": v for kind in be for k, v in be[kind].items()},
                       **{f"value_{k}": m["figures"][k] for k in METRICS},
                       **{f"ref_{k}": ref[k] for k in METRICS},
                       **{f"reflo_{k}": band["lo"][k] for k in METRICS},
                       **{f"refhi_{k}": band["hi"][k] for k in METRICS})
            row["err_max"] = max(v for v in err.values() if math.isfinite(v))
            rows.append(row)
            row["errnom_max"] = max((v for v in be["errnom"].values() if math.isfinite(v)),
                                    default=math.nan)
            log(f"{spec.name}: {cfg.label}: {m['wall_per_sim_s']:.3g} s/s, "
                f"max error over the band {100 * row['err_max']:.2f} %")
    return rows


def cold_costs(levels=(0, 1, 2, 3), preset: str = "xu2010", duration: float = 0.1) -> dict:
    """Wall time of the first run in a fresh process (import + model + kernels from the
    on-disk numba cache + run), per level, of ``preset`` for ``duration`` s."""
    out = {}
    for lv in levels:
        code = ("import time; w = time.perf_counter(); import chainmodel; "
                f"chainmodel.simulate({preset!r}, fidelity={lv}, duration={duration}); "
                "print(time.perf_counter() - w)")
        res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        out[lv] = float(res.stdout.strip().splitlines()[-1]) if res.returncode == 0 else math.nan
    return out


# --- output --------------------------------------------------------------------------------

COLUMNS = ("scene", "config", "level", "level_name", "method", "tolerance", "step_fraction",
           "status", "wall_per_sim_s", "wall_spread", "peak_memory_mb",
           *(f"err_{k}" for k in METRICS), "err_max",
           "mesh_over_mode", "mesh_over_span", "load_over_static", "z1", "z2", "pitch_mm",
           "reference_wall_per_sim_s", "reference_valid", "reference_warnings",
           "reference_problems", "band_runs",
           "span_source", *(f"ref_{k}" for k in METRICS),
           *(f"reflo_{k}" for k in METRICS), *(f"refhi_{k}" for k in METRICS),
           *(f"band_{k}" for k in METRICS), *(f"dist_{k}" for k in METRICS),
           *(f"errnom_{k}" for k in METRICS), "errnom_max", "reference_note",
           *(f"value_{k}" for k in METRICS), "note")


def write_csv(rows: list[dict], path: str | Path, header: str = "") -> Path:
    path = Path(path)
    with path.open("w", newline="") as fh:
        for line in header.splitlines():
            fh.write(f"# {line}\n")
        w = csv.DictWriter(fh, COLUMNS, extrasaction="ignore")
        w.writeheader()
        for r in rows:
            w.writerow({k: ("" if r.get(k) is None else
                            (f"{r[k]:.6g}" if isinstance(r.get(k), float) else r[k]))
                        for k in COLUMNS if k in r})
    return path


def read_csv(text: str) -> list[dict]:
    """Rows of a study CSV (``# `` comment lines skipped), numbers as floats."""
    return _parse_rows(text)


def markdown(rows: list[dict], targets=(0.01, 0.05, 0.20)) -> str:
    """The per-scene table (cost and every error) and the map of the cheapest configuration
    meeting each target on all figures."""
    short = {"mean_tight_tension": "tight mean", "peak_tight_tension": "tight peak",
             "mean_slack_tension": "slack mean", "peak_slack_tension": "slack peak",
             "driven_speed_ripple": "speed ripple", "input_torque_ripple": "torque ripple",
             "mesh_amplitude": "mesh ampl.", "transmission_error": "TE"}
    out = ["Errors in % relative to the nominal reference (level 3, Verlet at h/4), each the "
           "**worst case over the reference's band** (level 3 with "
           + ", ".join(sorted({n for n, _ in UNCERTAIN})) + " at x0.5 and x2, and "
           f"{JOINT_FRICTION} at its joint-friction factor where outside those): "
           "max(|v - lo|, |v - hi|). The row 'band half-width' is the reference's own "
           "uncertainty (hi - lo) / 2 on the same scale: no configuration can be shown better "
           "than it.\n"]
    for scene in dict.fromkeys(r["scene"] for r in rows):
        first = next(r for r in rows if r["scene"] == scene)
        out.append(f"### {scene}\n")
        if first["status"] == "reference invalid":
            out.append("**Reference invalid** (Result.valid False at level 3): dropped from the "
                       "trade and never a source of `fidelity=\"auto\"`. " + first["note"] + "\n")
            continue
        if first.get("reference_note"):
            out.append("*Marked: the reference runs outside level 3's validity* (never a source "
                       "of `fidelity=\"auto\"`): " + first["reference_note"] + "\n")
        out.append("| configuration | ms per simulated s | peak MB | "
                   + " | ".join(f"{short[k]} %" for k in METRICS) + " |")
        out.append("|" + "---|" * (3 + len(METRICS)))
        ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        if ok:
            out.append(f"| band half-width ({ok[0].get('band_runs') or '?'} runs) | | | "
                       + " | ".join(f"{100 * ok[0][f'band_{k}']:.2g}" for k in METRICS) + " |")
        for r in (r for r in rows if r["scene"] == scene):
            if r["status"] != "ok":
                out.append(f"| {r['config']} | {r['status']} |" + " |" * (1 + len(METRICS)))
                continue
            out.append(f"| {r['config']} | {1e3 * r['wall_per_sim_s']:.3g} | "
                       f"{r['peak_memory_mb']:.3g} | " + " | ".join(
                           f"{100 * r[f'err_{k}']:.2g}" for k in METRICS) + " |")
        out.append("")
    out.append("### Cheapest configuration meeting a target on every figure (band counted)\n")
    out.append("| scene | " + " | ".join(f"{100 * t:g} %" for t in targets) + " |")
    out.append("|" + "---|" * (1 + len(targets)))
    for scene in dict.fromkeys(r["scene"] for r in rows):
        cells = []
        for t in targets:
            ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"
                  and r["err_max"] <= t]
            best = min(ok, key=lambda r: r["wall_per_sim_s"]) if ok else None
            cells.append(f"{best['config']} ({1e3 * best['wall_per_sim_s']:.3g} ms/s)"
                         if best else "none")
        out.append(f"| {scene} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def headline(rows: list[dict]) -> str:
    """Per scene and figure the best of levels 0-2 at their default stepper (level 0, rk4 tol
    5e-4): its error over the band in %, (level), ± the band's half-width in %."""
    short = ("tight mean", "tight peak", "slack mean", "slack peak", "speed ripple",
             "torque ripple", "mesh ampl.", "TE")
    out = ["| scene | band half-width %, largest | "
           + " | ".join(short) + " |", "|" + "---|" * (2 + len(METRICS))]
    default = {"0 kinematic", "1 rk4 tol 0.0005", "2 rk4 tol 0.0005"}
    for scene in dict.fromkeys(r["scene"] for r in rows):
        rs = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        if not rs:
            out.append(f"| {scene} | reference invalid: dropped |" + " |" * len(METRICS))
            continue
        widths = [rs[0][f"band_{k}"] for k in METRICS if math.isfinite(rs[0][f"band_{k}"])]
        cells = []
        for k in METRICS:
            low = [r for r in rs if r["config"] in default and math.isfinite(r[f"err_{k}"])]
            if not low:
                cells.append("- (none valid)")
                continue
            b = min(low, key=lambda r: r[f"err_{k}"])
            cells.append(f"{100 * b[f'err_{k}']:.2g} ({b['level']}) ±{100 * b[f'band_{k}']:.2g}")
        mark = " (ref. warns)" if rs[0].get("reference_note") else ""
        out.append(f"| {scene}{mark} | {100 * max(widths):.2g} | " + " | ".join(cells) + " |")
    return "\n".join(out) + "\n"


def update_doc_block(path: str | Path, name: str, text: str) -> bool:
    """Replace the text between ``<!-- study:NAME -->`` and ``<!-- /study:NAME -->`` in the
    doc at ``path`` (the study owns what is between the markers); False if there are none."""
    path = Path(path)
    if not path.is_file():
        return False
    doc = path.read_text()
    start, end = f"<!-- study:{name} -->", f"<!-- /study:{name} -->"
    i, j = doc.find(start), doc.find(end)
    if i < 0 or j < i:
        return False
    path.write_text(doc[:i + len(start)] + "\n" + text.rstrip("\n") + "\n" + doc[j:])
    return True


def plot(rows: list[dict], pareto_path: str | Path, map_path: str | Path,
         targets=(0.01, 0.05, 0.20)) -> None:
    """Error (largest over the figures) against cost, one curve per level and one panel per
    scene; and the map of the lowest level meeting each target per scene."""
    import matplotlib
    import matplotlib.ticker
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    scenes = list(dict.fromkeys(r["scene"] for r in rows))
    ncol = 4
    nrow = math.ceil(len(scenes) / ncol)
    fig, axes = plt.subplots(nrow, ncol, figsize=(4 * ncol, 3.3 * nrow), squeeze=False)
    colours = {0: "tab:blue", 1: "tab:orange", 2: "tab:green", 3: "tab:red"}
    for ax, scene in zip(axes.flat, scenes):
        ok = [r for r in rows if r["scene"] == scene and r["status"] == "ok"]
        if not ok:
            ax.set_title(f"{scene}: reference invalid, dropped", fontsize=9)
            ax.axis("off")
            continue
        width = max((ok[0][f"band_{k}"] for k in METRICS if math.isfinite(ok[0][f"band_{k}"])),
                    default=0.0)
        if width > 0:     # the reference's own uncertainty: nothing can be shown better
            ax.axhspan(1e-3, width, color="0.9", zorder=0)
        for lv in range(4):
            pts = sorted((r["wall_per_sim_s"], max(r["err_max"], 1e-3),
                          max(r.get("errnom_max") or 1e-3, 1e-3)) for r in rows
                         if r["scene"] == scene and r["level"] == lv and r["status"] == "ok")
            if pts:
                x, worst, nom = zip(*pts)
                ax.loglog(x, worst, "o-", color=colours[lv], label=FIDELITY_NAMES[lv])
                ax.loglog(x, nom, "o", mfc="none", color=colours[lv], ms=4)
        ax.set_ylim(1e-3, None)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
        for t in targets:
            ax.axhline(t, color="0.7", lw=0.8, ls="--")
        ax.set_title(scene + (" (ref. warns)" if ok[0].get("reference_note") else ""),
                     fontsize=9)
        ax.set_xlabel("wall s per simulated s")
        ax.set_ylabel("largest error: over the band (o-), nominal (o)", fontsize=8)
    for ax in list(axes.flat)[len(scenes):]:
        ax.axis("off")
    axes.flat[0].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(pareto_path, dpi=110)
    plt.close(fig)

    panels = (("every figure", "err_max"), ("mean tight-span tension (sizing)",
                                             "err_mean_tight_tension"))
    fig, axes = plt.subplots(1, len(panels), figsize=(9.5, 0.45 * len(scenes) + 1.4),
                             sharey=True)
    for ax, (what, key) in zip(axes, panels):
        grid = np.full((len(scenes), len(targets)), -1.0)
        for i, scene in enumerate(scenes):
            for j, t in enumerate(targets):
                ok = [r["level"] for r in rows if r["scene"] == scene and r["status"] == "ok"
                      and r[key] is not None and r[key] <= t]
                grid[i, j] = min(ok) if ok else 4
                if not any(r["scene"] == scene and r["status"] == "ok" for r in rows):
                    grid[i, j] = 5          # reference invalid
        ax.imshow(grid, cmap=plt.get_cmap("viridis", 6), vmin=-0.5, vmax=5.5, aspect="auto")
        for i in range(len(scenes)):
            for j in range(len(targets)):
                v = int(grid[i, j])
                ax.text(j, i, FIDELITY_NAMES[v] if v < 4 else ("none" if v == 4
                                                              else "ref. invalid"),
                        ha="center", va="center", color="w" if v < 3 else "k", fontsize=8)
        ax.set_xticks(range(len(targets)), [f"{100 * t:g} %" for t in targets])
        ax.set_title(f"lowest level meeting the target,\n{what}, band counted", fontsize=9)
    warned = {r["scene"] for r in rows if r.get("reference_note")}
    axes[0].set_yticks(range(len(scenes)), [s + (" (ref. warns)" if s in warned else "")
                                            for s in scenes], fontsize=8)
    fig.tight_layout()
    fig.savefig(map_path, dpi=110)
    plt.close(fig)


# --- CLI: chainmodel bench tradeoff ---------------------------------------------------------

def add_arguments(p) -> None:
    """Options of ``chainmodel bench tradeoff`` (added to the ``bench`` parser)."""
    g = p.add_argument_group("bench tradeoff (the study)")
    g.add_argument("--scenes", default=None,
                   help="comma-separated study scenes (default all: "
                        + ", ".join(s.name for s in SCENES) + ")")
    g.add_argument("--repeats", type=int, default=3, help="warm timed runs per configuration")
    # defaults: this package's data file (what fidelity="auto" reads) and the checkout's docs
    root = Path(__file__).resolve().parents[2]
    g.add_argument("--csv", default=str(root / "chainmodel" / "data" / "tradeoff.csv"),
                   help="CSV written (default: the package's own, read by fidelity='auto')")
    g.add_argument("--markdown", default=str(root / "docs" / "tradeoff_results.md"),
                   help="tables written")
    g.add_argument("--doc", default=str(root / "docs" / "tradeoff.md"),
                   help="doc whose <!-- study:headline --> and <!-- study:run --> blocks are "
                        "rewritten ('' for none)")
    g.add_argument("--figures", default=str(root / "docs" / "figures"),
                   help="directory of the two plots ('' for none)")
    g.add_argument("--cache-dir", default=str(Path.home() / ".cache" / "chainmodel" / "tradeoff"),
                   help="where level-3 references are cached ('' for no cache)")
    g.add_argument("--cold", action="store_true",
                   help="also time the first run of each level in a fresh process")
    g.add_argument("--fmu", action="store_true", help="also the FMU's cost per communication "
                   "step at 1e-4 and 1e-3 s (builds the FMU; benchmarks/fmu_cost.py)")


def run_cli(args) -> int:
    import datetime
    import os
    import platform
    names = {s.name: s for s in SCENES}
    if args.scenes:
        wanted = [n.strip() for n in args.scenes.split(",")]
        bad = [n for n in wanted if n not in names]
        if bad:
            raise ValueError(f"--scenes: unknown scene(s) {bad}; valid: {', '.join(names)}")
        scenes = [names[n] for n in wanted]
    else:
        scenes = list(SCENES)
    if args.repeats < 1:
        raise ValueError(f"--repeats must be >= 1, got {args.repeats}")

    def log(msg):
        sys.stderr.write(msg + "\n")
        sys.stderr.flush()

    start = time.perf_counter()
    load = os.getloadavg()
    rows = run_study(scenes, CONFIGS, args.repeats, Path(args.cache_dir) if args.cache_dir
                     else None, log)
    took = time.perf_counter() - start
    header = (f"chainmodel bench tradeoff (issue 11), {datetime.date.today()}, "
              f"{platform.machine()} {os.cpu_count()} cores, load average at start "
              f"{load[0]:.2f}, {took:.0f} s; errors relative to level 3 verlet at h/4, worst "
              f"case over its band ({', '.join(band_label(n, f) for n, f in UNCERTAIN)}, and "
              f"{JOINT_FRICTION} at the joint friction's factor where outside those)")
    write_csv(rows, args.csv, header)
    md = [f"<!-- written by `chainmodel bench tradeoff`: {header} -->\n", markdown(rows)]
    if args.cold:
        cold = cold_costs()
        md.append("\nCold start (first run in a fresh process, import + kernels from the numba "
                  "cache + 0.1 s of xu2010): " + ", ".join(
                      f"level {lv} {v:.2f} s" for lv, v in cold.items()) + "\n")
    if args.fmu:
        md.append(fmu_section())
    Path(args.markdown).write_text("\n".join(md))
    if args.figures:
        fig = Path(args.figures)
        fig.mkdir(parents=True, exist_ok=True)
        plot(rows, fig / "tradeoff_pareto.png", fig / "tradeoff_map.png")
    if args.doc:
        update_doc_block(args.doc, "headline", headline(rows))
        update_doc_block(args.doc, "run", f"Last run: {header}.")
    print(markdown(rows), end="")
    log(f"wrote {args.csv} and {args.markdown} in {took:.0f} s")
    return 0


def fmu_section() -> str:
    """The FMU's cost per communication step on xu2010 at 1e-4 and 1e-3 s, measured by
    benchmarks/fmu_cost.py of the repository checkout (loaded from its file, not from sys.path:
    a benchmark script, not part of the package)."""
    import importlib.util
    script = Path(__file__).resolve().parents[2] / "benchmarks" / "fmu_cost.py"
    spec = importlib.util.spec_from_file_location("fmu_cost", script)
    if spec is None or not script.is_file():
        raise ValueError(f"--fmu needs the benchmark script {script} (a repository checkout)")
    fmu_cost = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(fmu_cost)
    lines = ["\n### FMU path (xu2010, 120 rpm; benchmarks/fmu_cost.py)\n",
             "| level | step 1e-4 s: us per step | step 1e-3 s: us per step |", "|---|---|---|"]
    res = {h: fmu_cost.fmu_step_cost(steps=100, repeats=5, h=h) for h in (1e-4, 1e-3)}
    for lv in (0, 1, 2, 3):
        lines.append(f"| {lv} | " + " | ".join(
            f"{1e6 * res[h]['levels'][lv]['chaindrive_s']:.0f}" for h in (1e-4, 1e-3)) + " |")
    return "\n".join(lines) + "\n"
