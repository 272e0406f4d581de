"""Regression tests of an exported FMU in the FMI Cross-Check layout (issue 13).

A *reference set* is a folder of scenario folders, each in the layout of the FMI Cross-Check
rules (github.com/modelica/fmi-cross-check):

    <scenario>/in.csv      "time" and the FMU's inputs on the communication grid
    <scenario>/ref.csv     "time" and the reference outputs on the same grid
    <scenario>/ref.opt     StartTime, StopTime, StepSize, RelTol (one "key,value" a line)
    <scenario>/start.csv   parameters set before initialization ("name,value"; ChainDrive's
                           addition: the Cross-Check rules run every FMU at its defaults)
    <scenario>/README.md   the purpose of the scenario and the outputs meaningful for it

The committed set (``references/`` at the top of the repository, shipped inside the FMU as
``documentation/fmu_references/``) is produced by the *library* (:func:`make_references`:
``Scene`` model + ``Stepper.advance`` with the inputs of ``in.csv`` held over each step, as a
fixed-step FMI master holds them), a path independent of the FMU adapter, pythonfmu and the
host. :func:`check` runs an FMU through a host (:func:`chainmodel.fmu_hosts.run_fmu`) and
compares every output with fmpy's own tube, :func:`fmpy.util.validate_signal` (the Modelica
Association csv-compare band):

* vertical half-width ``RelTol`` x (range of the reference output): the stated accuracy of the
  level (:data:`ACCURACY`, docs/fmu.md "Regression testing your FMU");
* horizontal width: one communication step on either side of each reference sample: a master
  may read the outputs of t_k before or after setting the inputs of t_k (direct feedthrough),
  and hosts place communication points by integer nanoseconds or floating-point sums.

No physics here; this module is an analysis tool and is never imported by the models.
"""

from __future__ import annotations

import math
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Mapping, Sequence

import numpy as np

__all__ = ["ACCURACY", "SCENARIOS", "Profile", "ScenarioSpec", "ReferenceError", "Reference",
           "OutputCheck", "make_references", "read_reference", "read_references", "check",
           "record", "write_reference", "INPUT_NAMES", "OUTPUT_NAMES"]

from ..units import RPM  # noqa: E402  (one definition: chainmodel.units)
INPUT_NAMES = ("input_shaft.angle", "input_shaft.speed", "load.torque")

#: tube half-height (fraction of each output's range over the scenario) per fidelity level,
#: from the accuracy the model states (docs/numerics.md, docs/multibody.md, docs/fmu.md):
#: 0: stateless exact four-bar solved to machine precision: only round-off (1e-9 of the range);
#: 1, 2: RK4 at solver.tolerance = 5e-4 errs by 4-10 x the tolerance of the speed ripple
#:       amplitude and a small fraction of that on the tension (docs/numerics.md, "Measured
#:       convergence"); the ripple amplitude is at most half the range: 10 x 5e-4 of the range;
#: 3: velocity Verlet at the automatic step errs by 1.4e-2 of the speed ripple amplitude and
#:    1.4e-4 of the tension's peak (same table): 1.4e-2 / 2 of the range.
ACCURACY = {0: 1e-6, 1: 10 * 5e-4, 2: 10 * 5e-4, 3: 1.4e-2 / 2}

#: communication step and length of the committed references
STEP_SIZE = 5e-4
DURATION = 0.2


def _output_names() -> list[str]:
    from ..models.base import ALL_OUTPUTS
    return [o.name for o in ALL_OUTPUTS]


OUTPUT_NAMES = tuple(_output_names())


class ReferenceError(ValueError):
    """A reference folder that does not follow the layout; the message names the file."""


# --- input profiles ----------------------------------------------------------------------------

@dataclass(frozen=True)
class Profile:
    """Input-shaft speed piecewise linear through ``speed`` knots (t [s], rpm), angle its exact
    integral from 0, acceleration its slope; load torque piecewise constant (``torque``: (t, N.m)
    from t on)."""

    speed: tuple[tuple[float, float], ...]
    torque: tuple[tuple[float, float], ...]

    def arrays(self, t) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """(angle, speed, acceleration, torque) at the times ``t`` (exact)."""
        t = np.atleast_1d(np.asarray(t, float))
        kt = np.array([k[0] for k in self.speed])
        kw = np.array([k[1] for k in self.speed]) * RPM
        w = np.interp(t, kt, kw)
        slopes = np.append(np.diff(kw) / np.diff(kt), 0.0)
        seg = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, len(kt) - 1)
        acc = np.where(t < kt[-1], slopes[seg], 0.0)
        # angle at each knot: trapezoids of the linear speed
        knot_angle = np.concatenate([[0.0], np.cumsum(0.5 * (kw[1:] + kw[:-1]) * np.diff(kt))])
        dt = t - kt[seg]
        angle = knot_angle[seg] + kw[seg] * dt + 0.5 * acc * dt * dt
        tt = np.array([k[0] for k in self.torque])
        tq = np.array([k[1] for k in self.torque])
        torque = tq[np.clip(np.searchsorted(tt, t, side="right") - 1, 0, len(tt) - 1)]
        return angle, w, acc, torque


@dataclass(frozen=True)
class ScenarioSpec:
    name: str
    purpose: str
    profile: Profile
    levels: tuple[int, ...] = (0, 1, 2, 3)


#: the scenarios of the committed references, each at every level in ``levels`` (xu2010, seed
#: 003 section 7: 25/17 teeth, 120 rpm, 43.2 N.m - the FMU's defaults)
SCENARIOS = (
    ScenarioSpec("startup", "start-up: input speed ramps from rest to 120 rpm over 50 ms under "
                 "the 43.2 N.m load, then holds",
                 Profile(((0.0, 0.0), (0.05, 120.0)), ((0.0, 43.2),))),
    ScenarioSpec("speed_step", "input-speed step: 100 rpm reached over 50 ms, then a step to "
                 "120 rpm over 2 ms at t = 0.1 s (a motor's speed command), load 43.2 N.m",
                 Profile(((0.0, 0.0), (0.05, 100.0), (0.1, 100.0), (0.102, 120.0)),
                         ((0.0, 43.2),))),
    ScenarioSpec("load_step", "load step: 120 rpm reached over 50 ms at 21.6 N.m, then the "
                 "load steps to 43.2 N.m at t = 0.1 s",
                 Profile(((0.0, 0.0), (0.05, 120.0)), ((0.0, 21.6), (0.1, 43.2)))),
    ScenarioSpec("reversal", "reversal: 60 rpm reached over 40 ms, then the input reverses "
                 "linearly to -60 rpm between 0.08 s and 0.14 s, load 10 N.m throughout",
                 Profile(((0.0, 0.0), (0.04, 60.0), (0.08, 60.0), (0.14, -60.0)),
                         ((0.0, 10.0),))),
)


# --- the reference files -----------------------------------------------------------------------

@dataclass
class Reference:
    """One scenario folder, read and checked."""

    path: Path
    opts: dict[str, float]
    inputs: dict[str, np.ndarray]           # name -> values on ``time``
    time: np.ndarray
    outputs: dict[str, np.ndarray]          # name -> reference values on ``time``
    start_values: dict[str, object] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.path.name


def _write_csv(path: Path, time: np.ndarray, columns: Mapping[str, np.ndarray]) -> None:
    names = ["time", *columns]
    data = np.column_stack([time, *columns.values()])
    lines = [",".join(f'"{n}"' for n in names)]
    lines += [",".join(repr(float(v)) for v in row) for row in data]
    path.write_text("\n".join(lines) + "\n")


def _fmt_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    return repr(v) if isinstance(v, float) else str(v)


def write_reference(folder: Path, *, time, inputs: Mapping[str, np.ndarray],
                    outputs: Mapping[str, np.ndarray], step_size: float, rel_tol: float,
                    start_values: Mapping[str, object], readme: str) -> Path:
    """Write one scenario folder in the layout of the module docstring."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    time = np.asarray(time, float)
    _write_csv(folder / "in.csv", time, inputs)
    _write_csv(folder / "ref.csv", time, outputs)
    (folder / "ref.opt").write_text(
        f"StartTime,{float(time[0])!r}\nStopTime,{float(time[-1])!r}\n"
        f"StepSize,{float(step_size)!r}\nRelTol,{float(rel_tol)!r}\n")
    (folder / "start.csv").write_text(
        "".join(f"{k},{_fmt_value(v)}\n" for k, v in start_values.items()))
    (folder / "README.md").write_text(readme)
    return folder


def _readme(title: str, purpose: str, level: int, meaningful: Sequence[str],
            estimates: Sequence[str], source: str, rel_tol: float, step: float) -> str:
    from ..parameters import FIDELITY_NAMES
    return (f"# {title}\n\n{purpose}.\n\nFidelity {level} ({FIDELITY_NAMES[level]}); {source}. "
            f"Communication step {step:g} s, inputs in `in.csv` held over each step by the host, "
            "parameters not in `start.csv` at the FMU's defaults.\n\n"
            f"Meaningful outputs at this level: {', '.join(meaningful)}.\n\n"
            + (f"Quasi-static estimates at this level (compared, but they only follow the "
               f"inputs): {', '.join(estimates)}.\n\n" if estimates else "")
            + f"Tube: RelTol = {rel_tol:g} of each output's range, one communication step wide "
              "in time (docs/fmu.md, \"Regression testing your FMU\").\n")


def non_default_parameters(params: Mapping) -> dict:
    """The parameters of ``params`` whose values differ from the schema's defaults: what a
    reference sets as start values (the FMU starts from the defaults)."""
    from .. import parameters as P
    defaults = P.validate({})
    return {k: v for k, v in params.items() if defaults.get(k) != v}


def held_acceleration(times, speed) -> np.ndarray:
    """The acceleration a co-simulation FMU of ChainDrive uses over the step from times[k]:
    backward difference of the speed samples (0 at the first point; docs/fmu.md)."""
    acc = np.zeros(len(times))
    acc[1:] = np.diff(speed) / np.diff(times)
    return acc


def library_run(model, params, times, angle, speed, torque) -> dict[str, np.ndarray]:
    """Every output on ``times`` from the library's co-simulation session
    (:class:`chainmodel.cosim.CosimSession`, what the FMU adapter maps FMI onto) driven as a
    fixed-step FMI master drives a co-simulation FMU: the inputs sampled at t_k held over
    [t_k, t_k+1] (the angle advancing at the held speed, the acceleration the backward
    difference of :func:`held_acceleration`), the outputs at t_k+1 read before the inputs of
    t_k+1 are set."""
    from ..cosim import CosimSession
    session = CosimSession()
    session.set_inputs(float(angle[0]), float(speed[0]), float(torque[0]))
    session.build(params, float(times[0]), model=model)
    data = {n: np.empty(len(times)) for n in OUTPUT_NAMES}
    out = session.stepper.outputs()
    for i, t in enumerate(times):
        if i:
            k = i - 1
            session.set_inputs(float(angle[k]), float(speed[k]), float(torque[k]))
            row = session.step(float(times[k]), float(t) - float(times[k]), t_end=float(t))
            out = dict(zip(OUTPUT_NAMES, row.tolist()))
        for n in OUTPUT_NAMES:
            data[n][i] = out[n]
    return data


def make_references(root: str | Path, levels: Sequence[int] = (0, 1, 2, 3),
                    scenarios: Sequence[ScenarioSpec] = SCENARIOS) -> list[Path]:
    """Write the committed reference set under ``root`` from the LIBRARY: the xu2010 scene at
    each level, the profile sampled on the grid and run by :func:`library_run`."""
    from ..models.base import QUASI_STATIC
    from ..scene import Scene

    root = Path(root)
    written = []
    for spec in scenarios:
        for level in spec.levels:
            sc = Scene.from_preset("xu2010", fidelity=level, duration=DURATION,
                                   output_interval=STEP_SIZE)
            times = sc.times()
            model = sc.model()
            angle, speed, acc, torque = spec.profile.arrays(times)
            data = library_run(model, sc.parameters, times, angle, speed, torque)
            descriptions = model.output_descriptions()
            estimates = [n for n in OUTPUT_NAMES if descriptions.get(n, "").startswith(QUASI_STATIC)]
            meaningful = [n for n in OUTPUT_NAMES if n not in estimates]
            start = non_default_parameters(sc.parameters)
            name = f"L{level}_{spec.name}"
            written.append(write_reference(
                root / name, time=times,
                inputs=dict(zip(INPUT_NAMES, (angle, speed, torque))),
                outputs={n: np.asarray(data[n], float) for n in OUTPUT_NAMES},
                step_size=STEP_SIZE, rel_tol=ACCURACY[level], start_values=start,
                readme=_readme(name, spec.purpose[0].upper() + spec.purpose[1:], level,
                               meaningful, estimates,
                               "produced by the chainmodel library (Scene xu2010, "
                               "Stepper.advance with the inputs of in.csv held over each step; "
                               "chainmodel.analysis.fmu_test.make_references)",
                               ACCURACY[level], STEP_SIZE)))
    return written


def read_reference(folder: str | Path, outputs: Sequence[str] | None = None,
                   inputs: Sequence[str] = INPUT_NAMES) -> Reference:
    """Read one scenario folder; ReferenceError (naming the file) when it is malformed.
    ``outputs``/``inputs``: the FMU's output/input names every column must belong to."""
    from fmpy.util import read_csv, read_ref_opt_file

    from ..parameters import parse_text
    folder = Path(folder)
    outputs = list(OUTPUT_NAMES if outputs is None else outputs)
    if not folder.is_dir():
        raise ReferenceError(f"reference folder {str(folder)!r} does not exist")
    for required in ("ref.opt", "ref.csv"):
        if not (folder / required).is_file():
            raise ReferenceError(f"{folder / required}: missing (a reference folder needs "
                                 "ref.opt and ref.csv, optionally in.csv and start.csv)")
    try:
        opts = read_ref_opt_file(str(folder / "ref.opt"))
    except Exception as exc:
        raise ReferenceError(f"{folder / 'ref.opt'}: {exc}") from None

    def table(name, allowed, what):
        path = folder / name
        try:
            data = read_csv(str(path))
        except Exception as exc:
            raise ReferenceError(f"{path}: not a Cross-Check CSV ({exc})") from None
        names = list(data.dtype.names)
        if names[0] != "time":
            raise ReferenceError(f"{path}: the first column must be time, got {names[0]!r}")
        bad = [n for n in names[1:] if n not in allowed]
        if bad:
            raise ReferenceError(f"{path}: column(s) {', '.join(bad)} are not {what} of the FMU "
                                 f"(valid: {', '.join(allowed)})")
        t = np.asarray(data["time"], float)
        if len(t) < 2 or np.any(np.diff(t) <= 0):
            raise ReferenceError(f"{path}: time must increase over at least two rows")
        return t, {n: np.asarray(data[n], float) for n in names[1:]}

    time, ref = table("ref.csv", outputs, "outputs")
    if not ref:
        raise ReferenceError(f"{folder / 'ref.csv'}: no output column")
    ins: dict[str, np.ndarray] = {}
    if (folder / "in.csv").is_file():
        tin, ins = table("in.csv", list(inputs), "inputs")
        if len(tin) != len(time) or np.max(np.abs(tin - time)) > 1e-9 * max(1.0, time[-1]):
            raise ReferenceError(f"{folder / 'in.csv'}: its times are not those of ref.csv")
    n = round((opts["StopTime"] - opts["StartTime"]) / opts["StepSize"])
    if opts["StartTime"] != 0.0 or len(time) != n + 1 or abs(time[-1] - opts["StopTime"]) > \
            1e-9 * max(1.0, opts["StopTime"]):
        raise ReferenceError(f"{folder / 'ref.opt'}: StartTime must be 0 and ref.csv must have "
                             f"one row every StepSize up to StopTime ({n + 1} rows), it has "
                             f"{len(time)} rows up to {time[-1]!r} s")
    start: dict[str, object] = {}
    if (folder / "start.csv").is_file():
        for k, line in enumerate((folder / "start.csv").read_text().splitlines(), 1):
            if not line.strip():
                continue
            parts = line.split(",")
            if len(parts) != 2:
                raise ReferenceError(f"{folder / 'start.csv'}: line {k} is not 'name,value'")
            start[parts[0].strip()] = parse_text(parts[1])
    return Reference(folder, opts, ins, time, ref, start)


def read_references(root: str | Path, outputs: Sequence[str] | None = None) -> list[Reference]:
    """Every scenario folder under ``root`` (a folder holding ref.opt is itself one)."""
    root = Path(root)
    if not root.is_dir():
        raise ReferenceError(f"references folder {str(root)!r} does not exist")
    if (root / "ref.opt").is_file() or (root / "ref.csv").is_file():
        return [read_reference(root, outputs)]
    folders = sorted(p for p in root.iterdir() if p.is_dir())
    if not folders:
        raise ReferenceError(f"references folder {str(root)!r} holds no scenario folder")
    return [read_reference(p, outputs) for p in folders]


# --- comparison --------------------------------------------------------------------------------

@dataclass(frozen=True)
class OutputCheck:
    scenario: str
    output: str
    passed: bool
    worst: float          # worst |deviation| / tube half-height (> 1: outside the tube)
    at: float             # time of the worst deviation [s]
    outside: int          # samples outside the tube
    time: np.ndarray
    value: np.ndarray
    y_min: np.ndarray
    y_max: np.ndarray
    t_band: np.ndarray
    error: str | None = None


def tube(ref: Reference, name: str, t: np.ndarray, y: np.ndarray) -> OutputCheck:
    """fmpy's tube (validate_signal) around the reference output ``name``: band sampled on
    the reference grid, ``dx`` = 3 samples (one step either side), ``dy`` = RelTol."""
    from fmpy.util import validate_signal
    t_ref = ref.time.copy()
    y_ref = ref.outputs[name]
    t_band, y_min, y_max, i_out = validate_signal(t=t, y=y, t_ref=t_ref, y_ref=y_ref,
                                                  num=len(t_ref), dx=3, dy=ref.opts["RelTol"])
    lo, hi = np.interp(t, t_band, y_min), np.interp(t, t_band, y_max)
    # half-height as validate_signal computes it (the band minus the filtered reference)
    rng = float(np.max(y_ref) - np.min(y_ref))
    w = (rng * ref.opts["RelTol"]) if rng > 0 else (
        0.5 if y_ref[0] == 0 else abs(float(y_ref[0])) * ref.opts["RelTol"])
    excess = np.maximum(lo - y, y - hi)              # > 0 outside the band
    with np.errstate(invalid="ignore"):
        rel = 1.0 + excess / w if w > 0 else np.where(excess > 0, np.inf, 0.0)
    rel = np.where(np.isfinite(y), rel, np.inf)
    inner = (t > t_band[0]) & (t < t_band[-1])
    rel_in = np.where(inner, rel, -np.inf)
    k = int(np.argmax(rel_in))
    outside = int(np.count_nonzero(i_out | (inner & ~np.isfinite(y))))
    return OutputCheck(ref.name, name, outside == 0, float(max(rel_in[k], 0.0)), float(t[k]),
                       outside, t, y, y_min, y_max, t_band)


def _run(fmu: Path, ref: Reference, host: str):
    from ..fmu_hosts import run_fmu
    return run_fmu(fmu, host, stop_time=ref.opts["StopTime"], step_size=ref.opts["StepSize"],
                   inputs=ref.inputs, start_values=ref.start_values, outputs=list(ref.outputs))


def fmu_variables(fmu: Path) -> tuple[list[str], list[str]]:
    """(output names, input names) of the FMU's modelDescription.xml."""
    from fmpy import read_model_description
    md = read_model_description(str(fmu))
    return ([v.name for v in md.modelVariables if v.causality == "output"],
            [v.name for v in md.modelVariables if v.causality == "input"])


def check(fmu: str | Path, references: Sequence[Reference], host: str = "fmpy"
          ) -> list[OutputCheck]:
    """Run ``fmu`` with ``host`` through every reference; one OutputCheck per scenario and
    output, in reference order. A run the FMU refuses or abandons (initialization refused, a
    step discarded) fails every output of that scenario, with the reason as ``error``."""
    from ..fmu_hosts import HostUnavailable
    fmu = Path(fmu)
    results = []
    for ref in references:
        try:
            run = _run(fmu, ref, host)
        except HostUnavailable:
            raise
        except Exception as exc:      # the FMU failed this scenario: a regression, not a usage error
            why = " ".join(str(exc).split()) or type(exc).__name__
            empty = np.array([])
            results += [OutputCheck(ref.name, n, False, math.inf, math.nan, len(ref.time),
                                    empty, empty, empty, empty, empty, error=why)
                        for n in ref.outputs]
            continue
        for name in ref.outputs:
            results.append(tube(ref, name, run.time, run.outputs[name]))
    return results


def record(fmu: str | Path, references: Sequence[Reference], out: str | Path,
           host: str = "fmpy") -> list[Path]:
    """A new reference set from the FMU itself: each reference's inputs, start values and
    options, the outputs the FMU computes now (after an intended change)."""
    fmu, out = Path(fmu), Path(out)
    written = []
    for ref in references:
        run = _run(fmu, ref, host)
        folder = out / ref.name
        old = (ref.path / "README.md").read_text() if (ref.path / "README.md").is_file() else \
            f"# {ref.name}\n"
        readme = (old.rstrip() + f"\n\nRecorded from {fmu.name} with {host} {run.version} "
                  "(chainmodel fmu-test --record).\n")
        written.append(write_reference(folder, time=run.time, inputs=ref.inputs,
                                       outputs=run.outputs, step_size=ref.opts["StepSize"],
                                       rel_tol=ref.opts["RelTol"],
                                       start_values=ref.start_values, readme=readme))
    return written


def scene_reference(scene, out: str | Path, fmu: str | Path, host: str = "fmpy") -> Path:
    """Record a user's scene (TOML path, preset or Scene) through the FMU as one reference
    folder: the scene's inputs on its grid, every parameter that differs from the FMU's
    defaults as a start value, RelTol the accuracy of the scene's level."""
    from ..fmu_hosts import run_fmu
    from ..scene import load_scene
    sc = load_scene(scene)
    times = sc.times()
    angle, speed, acc, torque = sc.input_arrays(times)
    start = non_default_parameters(sc.parameters)
    step = float(times[1] - times[0])
    run = run_fmu(fmu, host, stop_time=float(times[-1]), step_size=step,
                  inputs=dict(zip(INPUT_NAMES, (angle, speed, torque))), start_values=start,
                  outputs=list(OUTPUT_NAMES))    # the library's (not motor.*: masters' only)
    level = sc.fidelity
    folder = Path(out) / (sc.name.replace(" ", "_") or "scene")
    readme = (f"# {folder.name}\n\nScene {sc.name!r} at fidelity {level}, recorded from "
              f"{Path(fmu).name} with {host} {run.version} (chainmodel fmu-test --record "
              f"--scene). Tube: RelTol = {ACCURACY[level]:g} of each output's range, one "
              "communication step wide in time.\n")
    return write_reference(folder, time=run.time, inputs=dict(zip(INPUT_NAMES,
                                                                  (angle, speed, torque))),
                           outputs=run.outputs, step_size=step, rel_tol=ACCURACY[level],
                           start_values=start, readme=readme)


def _unit(name: str) -> str:
    """Unit of an FMU output or input (the FMU's own), '-' where it has none."""
    from ..models import ALL_OUTPUTS
    units = {o.name: o.unit for o in ALL_OUTPUTS}
    units.update({"input_shaft.angle": "rad", "input_shaft.speed": "rad/s", "load.torque": "N.m"})
    return units.get(name) or "-"


def plot_worst(results: Sequence[OutputCheck], path: str | Path, count: int = 6) -> Path:
    """Figure of the ``count`` outputs with the largest deviation relative to their tube."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    worst = sorted((r for r in results if r.error is None), key=lambda r: -r.worst)[:count]
    if not worst:
        raise ValueError("no output ran, nothing to plot")
    fig, axes = plt.subplots(len(worst), 1, figsize=(8, 2.2 * len(worst)), squeeze=False)
    for ax, r in zip(axes[:, 0], worst):
        ax.fill_between(r.t_band, r.y_min, r.y_max, color="0.85", label="tube")
        ax.plot(r.time, r.value, lw=0.8, label="FMU")
        ax.axvline(r.at, color="r", lw=0.5)
        ax.set_title(f"{r.scenario}: {r.output} - {'pass' if r.passed else 'FAIL'}, worst "
                     f"{r.worst:.3g} of the tube at {r.at:.4g} s", fontsize=8)
        ax.tick_params(labelsize=7)
        ax.set_ylabel(f"{r.output} [{_unit(r.output)}]", fontsize=7)
    axes[0, 0].legend(fontsize=7)
    axes[-1, 0].set_xlabel("time [s]")
    fig.tight_layout()
    fig.savefig(path, dpi=100)
    plt.close(fig)
    return Path(path)


# --- command line ------------------------------------------------------------------------------

def register(subparsers) -> None:
    p = subparsers.add_parser(
        "fmu-test", help="regression-test an FMU against reference sets (FMI Cross-Check layout)",
        description="Run FMU through a host against reference sets in the FMI Cross-Check layout "
                    "and compare every output with fmpy's tube (fmpy.util.validate_signal). "
                    "One line per scenario and output; exit 0 when all pass, 1 when any fails, "
                    "2 for bad usage or input. docs/fmu.md, 'Regression testing your FMU'.")
    p.add_argument("fmu", metavar="FMU", help="the FMU file, e.g. dist/ChainDrive.fmu")
    p.add_argument("--references", metavar="DIR",
                   help="reference set (a folder of scenario folders, or one scenario folder); "
                        "default: the set shipped in the FMU's documentation/fmu_references")
    p.add_argument("--host", choices=("fmpy", "libcosim"), default="fmpy",
                   help="importer that runs the FMU (default fmpy)")
    p.add_argument("--record", metavar="DIR",
                   help="instead of comparing, write a new reference set from the FMU itself "
                        "into DIR (the inputs of --references, or of --scene)")
    p.add_argument("--scene", metavar="TOML",
                   help="with --record: record this scene (TOML file or preset name) instead")
    p.add_argument("--plot", metavar="FILE",
                   help="figure of the worst deviations (needs matplotlib)")
    p.set_defaults(handler=cmd_fmu_test)


def _shipped_references(fmu: Path, tmp: Path) -> Path:
    import zipfile
    try:
        with zipfile.ZipFile(fmu) as z:
            members = [m for m in z.namelist() if m.startswith("documentation/fmu_references/")]
            if not members:
                raise ValueError(f"{fmu} ships no documentation/fmu_references; give "
                                 "--references DIR")
            z.extractall(tmp, members)
    except zipfile.BadZipFile:
        raise ValueError(f"FMU {str(fmu)!r} is not a zip file (an FMU is)") from None
    return tmp / "documentation" / "fmu_references"


def cmd_fmu_test(args) -> int:
    import sys
    import tempfile
    from ..fmu_hosts import HostUnavailable
    fmu = Path(args.fmu)
    if not fmu.is_file():
        raise ValueError(f"FMU {args.fmu!r} does not exist; build it with `python build_fmu.py`")
    if args.scene and not args.record:
        raise ValueError("--scene is for --record DIR (record a scene as a new reference)")
    if args.plot:
        from ..plots import check_plot_path
        check_plot_path(args.plot)          # before the runs: .png, .pdf or .svg
    try:
        outputs, inputs = fmu_variables(fmu)
    except Exception as exc:
        raise ValueError(f"{fmu}: cannot read its modelDescription.xml ({exc})") from None
    with tempfile.TemporaryDirectory(prefix="chaindrive_fmu_test_") as tmp:
        try:
            if args.record and args.scene:
                folder = scene_reference(args.scene, args.record, fmu, args.host)
                print(f"recorded {folder}")
                return 0
            root = Path(args.references) if args.references else \
                _shipped_references(fmu, Path(tmp))
            refs = read_references(root, outputs)
            for r in refs:
                bad = [n for n in r.inputs if n not in inputs]
                if bad:
                    raise ReferenceError(f"{r.path / 'in.csv'}: {', '.join(bad)} not inputs of "
                                         f"{fmu.name}")
            if args.record:
                for folder in record(fmu, refs, args.record, args.host):
                    print(f"recorded {folder}")
                return 0
            results = check(fmu, refs, args.host)
        except HostUnavailable as exc:
            raise ValueError(str(exc)) from None
    width = max(len(r.scenario) for r in results)
    owidth = max(len(r.output) for r in results)
    for r in results:
        verdict = "pass" if r.passed else "FAIL"
        if r.error is not None:
            print(f"{verdict} {r.scenario:<{width}} {r.output:<{owidth}} run failed: {r.error}")
        else:
            print(f"{verdict} {r.scenario:<{width}} {r.output:<{owidth}} worst {r.worst:.3g} of "
                  f"the tube at t = {r.at:.6g} s" + (f" ({r.outside} samples outside)"
                                                    if r.outside else ""))
    failed = [r for r in results if not r.passed]
    moved = sorted({r.output for r in failed})
    print(f"fmu-test: {len(results) - len(failed)} of {len(results)} outputs pass in "
          f"{len(refs)} scenarios ({args.host})"
          + (f"; outputs that moved: {', '.join(moved)}" if moved else ""))
    if args.plot:
        try:
            import matplotlib  # noqa: F401
        except ImportError:
            print("fmu-test: no figure, matplotlib is not installed (pip install "
                  "'chainmodel[plot]')", file=sys.stderr)
        else:
            print(f"wrote {plot_worst(results, args.plot)}")
    return 1 if failed else 0


def main_generate(argv=None) -> int:
    """``python -m chainmodel.analysis.fmu_test [DIR]``: regenerate the committed references."""
    import sys
    argv = sys.argv[1:] if argv is None else argv
    root = Path(argv[0]) if argv else Path("references")
    if root.is_dir():
        for p in root.iterdir():
            if p.is_dir() and (p / "ref.opt").is_file():
                shutil.rmtree(p)
    for p in make_references(root):
        print(p)
    return 0


if __name__ == "__main__":
    raise SystemExit(main_generate())
