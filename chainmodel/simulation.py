"""``simulate``: the friendly top-level function over scenes and steppers, and its Result."""

from __future__ import annotations

import csv
import sys
import time as _time
from functools import cached_property
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from .models import ALL_OUTPUTS, SimulationDiverged  # noqa: F401  (re-exported)
from .parameters import FIDELITY_NAMES
from .run_memory import check_run_memory
from .scene import Scene, load_scene

__all__ = ["simulate", "Result", "run_scene", "resolve", "run_resolved"]

UNITS = {o.name: o.unit for o in ALL_OUTPUTS}


class Result:
    """Time series of every output of a run: ``result.time``, ``result["driven.speed"]``."""

    def __init__(self, scene: Scene, time: np.ndarray, data: dict[str, np.ndarray],
                 descriptions: dict[str, str], wall_time: float, stats: dict,
                 static_tension, snapshots: list | None = None,
                 start_fallback: str | None = None):
        self.scene = scene
        self.time = time
        self._data = data
        self.descriptions = descriptions
        self.units = dict(UNITS)
        self.wall_time = wall_time
        self.stats = stats
        # a number, or a callable computed on first use (level 3 settles the chain for it)
        self._static_tension = static_tension
        self.snapshots = snapshots or []
        #: fidelity="auto": the chainmodel.fidelity_auto.AutoChoice that picked the level
        self.auto_choice = None
        #: why the run did not start where its level starts (Model.start_fallback)
        self.start_fallback = start_fallback

    @property
    def static_tension(self) -> float:
        """Static span tension at rest with no load of this level [N] (Model.static_tension)."""
        if callable(self._static_tension):
            self._static_tension = float(self._static_tension())
        return self._static_tension

    @property
    def fidelity(self) -> int:
        return self.scene.fidelity

    @property
    def fidelity_name(self) -> str:
        return FIDELITY_NAMES[self.fidelity]

    @property
    def names(self) -> list[str]:
        return list(self._data)

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self._data[name]
        except KeyError:
            raise KeyError(f"no output {name!r}; outputs are: {', '.join(self._data)}") from None

    def __contains__(self, name: str) -> bool:
        return name in self._data

    def summary(self) -> dict[str, Any]:
        from .analysis.summary import summarise
        return summarise(self)

    @cached_property
    def problems(self) -> list:
        """Where this result leaves the model's validity (chainmodel.validity: the chain's
        length against its centre distance, the breaking load, level 3's penetration, teeth
        skipped, driven-speed reversal), as validity.Problem s; their sentences are also in
        :attr:`warnings`."""
        from .validity import result_problems
        return result_problems(self)

    @property
    def valid(self) -> bool:
        """False when a problem makes the result meaningless (teeth skipped, a roller inside a
        tooth: ``Problem.invalid``); ``chainmodel run`` then exits with status 3."""
        return not any(p.invalid for p in self.problems)

    @property
    def warnings(self) -> list[str]:
        """What the summary warns about (a short steady window, an output interval that cannot
        resolve the meshing frequency, the validity problems); the CLI prints them."""
        notes = [self.auto_choice.message] if self.auto_choice is not None else []
        return list(self.summary()["warnings"]) + notes

    def to_csv(self, path: str | Path) -> Path:
        path = Path(path)
        with path.open("w", newline="") as fh:
            w = csv.writer(fh)
            w.writerow(["time"] + self.names)
            w.writerow(["s"] + [self.units.get(n, "") for n in self.names])
            for i, t in enumerate(self.time):
                w.writerow([repr(float(t))] + [repr(float(self._data[n][i])) for n in self.names])
        return path

    def __repr__(self) -> str:
        return (f"Result(scene={self.scene.name!r}, fidelity={self.fidelity_name!r}, "
                f"{len(self.time)} samples to t={self.time[-1]:g} s)")


class _Progress:
    """One updating line on stderr for long runs."""

    def __init__(self, enabled: bool, total: float, label: str):
        self.enabled, self.total, self.label = enabled, total, label
        self.last = 0.0
        self.start = _time.perf_counter()

    def update(self, t: float, force: bool = False):
        if not self.enabled:
            return
        now = _time.perf_counter()
        if force or now - self.last > 0.5:
            self.last = now
            frac = t / self.total if self.total else 1.0
            elapsed = now - self.start
            # no estimate before 5 %: one-off start-up costs (compilation) would dominate it
            eta = f", ~{elapsed * (1 - frac) / frac:.0f} s left" if frac >= 0.05 else ""
            sys.stderr.write(f"\r{self.label}: t = {t:.4g} / {self.total:.4g} s "
                             f"({100 * frac:5.1f} %), {elapsed:.1f} s elapsed{eta} ")
            sys.stderr.flush()

    def close(self):
        if self.enabled:
            self.update(self.total, force=True)
            sys.stderr.write("\n")


#: communication points per batched call (bounds memory; the progress line updates between)
BATCH_POINTS = 4096


def _run_batched(scene, model, stepper, times, data, bar) -> bool:
    """Every communication point through the stepper's compiled many-point path (one call per
    BATCH_POINTS points, the inputs sampled beforehand, the outputs computed inside): the
    numbers of the per-point loop without its Python round trip per point, except where level
    1's steps span several points (docs/numerics.md, "Steps spanning output points"). False
    (nothing done) when the stepper and model have no such path."""
    inputs = scene.input_arrays(times)
    out = np.empty((min(BATCH_POINTS, len(times) - 1) + 1, len(ALL_OUTPUTS)))
    names = [o.name for o in ALL_OUTPUTS]
    first = stepper.outputs()
    start = 0
    while start < len(times) - 1:
        stop = min(start + BATCH_POINTS, len(times) - 1)
        sl = slice(start, stop + 1)
        rows = out[:stop - start + 1]
        if not stepper.advance_points(times[sl], *(a[sl] for a in inputs), rows):
            return False            # only possible at the first chunk: nothing written yet
        for k, name in enumerate(names):
            data[name][start + 1:stop + 1] = rows[1:, k]
        bar.update(float(times[stop]))
        start = stop
    for name in names:
        data[name][0] = first[name]
    return True


def run_scene(scene: Scene, progress: bool = False, snapshot_every: int = 0,
              batched: bool = True, model=None) -> Result:
    """Run ``scene`` with its stepper over its duration, sampling every output at each
    communication point; ``snapshot_every=k`` keeps the model's snapshot every k samples.

    ``batched``: where the stepper and model offer it (levels 1-3 with their compiled loops),
    run many communication points in one compiled call, outputs included - the same numbers as
    the per-point loop (``batched=False``, one ``Stepper.advance`` per point as the FMU steps),
    without its Python overhead per point. At level 1, where the step bound spans two or more
    output intervals, the batched call takes one step over several points and fills them from
    its dense output: faster, and within the tolerance of the per-point loop, not equal to it
    (docs/numerics.md, "Steps spanning output points").

    ``model``: the scene's model when the caller has built it already (simulate() with
    fidelity="auto": the choice built it to check the level); else it is built here.

    A run whose time series would not fit in memory is refused before anything is allocated
    (:class:`chainmodel.run_memory.RunTooLarge`, a ValueError with the estimate and what fits)."""
    check_run_memory(scene.duration, scene.output_interval, scene.fidelity)
    model = scene.model() if model is None else model
    scene.check_operating_point(model)
    times = scene.times()
    if model.n_states == 0 and model.vectorised and not snapshot_every:
        # stateless level: every sample at once (vectorised over time)
        wall = _time.perf_counter()
        data = model.evaluate(*scene.input_arrays(times))
        wall = _time.perf_counter() - wall
        return Result(scene, times, data, model.output_descriptions(), wall,
                      {"steps": 0, "rhs_evaluations": 0, "events": 0, "wall_time": wall},
                      model.static_tension)
    stepper = scene.stepper(model)
    data = {o.name: np.empty(len(times)) for o in ALL_OUTPUTS}
    snaps = []
    bar = _Progress(progress, float(times[-1]), f"{scene.name} ({FIDELITY_NAMES[scene.fidelity]})")
    wall = _time.perf_counter()
    if batched and not snapshot_every and _run_batched(scene, model, stepper, times, data, bar):
        wall = _time.perf_counter() - wall
        bar.close()
        return Result(scene, times, data, model.output_descriptions(), wall,
                      dict(stepper.stats), model.static_tension, snaps, model.start_fallback)
    out = stepper.outputs()
    for i, t in enumerate(times):
        if i:
            out = stepper.advance(float(t), scene.inputs)
        for name in data:
            data[name][i] = out[name]
        if snapshot_every and i % snapshot_every == 0:
            snaps.append((float(t), model.snapshot(float(t), stepper.x, stepper.inputs)))
        bar.update(float(t))
    wall = _time.perf_counter() - wall
    bar.close()
    return Result(scene, times, data, model.output_descriptions(), wall, dict(stepper.stats),
                  model.static_tension, snaps, model.start_fallback)


def simulate(scene: "str | Path | Scene" = "xu2010", *, parameters: Mapping[str, Any] | None = None,
             progress: bool = False, snapshot_every: int = 0, outputs=None, accuracy=None,
             choice=None, **overrides) -> Result:
    """Simulate a scene (preset name, TOML path or Scene) and return every output over time.

    Keyword overrides: ``fidelity`` (0-3 or kinematic/torsional/modal/multibody), ``duration``,
    ``output_interval``, ``input_speed_rpm``, ``ramp_time``, ``load_torque``,
    ``static_tension``, and any parameter, dots written as underscores
    (``chain_link_damping=50``) or given in ``parameters={"chain.link_damping": 50}``.

    ``fidelity="auto"`` picks the cheapest level and stepper settings that the measured trade
    table (chainmodel/data/tradeoff.csv, docs/tradeoff.md) says meet ``accuracy`` (relative,
    default 0.05) on ``outputs`` (output names such as "driven.speed", default: every measured
    figure); ``result.auto_choice`` and ``result.warnings`` say what it chose, the expected
    error and its source (chainmodel.fidelity_auto).

    ``choice``: an AutoChoice that :func:`resolve` made already (the CLI prints it before the
    run): its scene runs on the model it built, and nothing is chosen or overridden again.
    """
    if choice is None:
        sc, choice = resolve(scene, parameters=parameters, outputs=outputs, accuracy=accuracy,
                             **overrides)
    elif parameters or overrides or outputs is not None or accuracy is not None:
        raise ValueError("simulate(choice=...) runs the choice's scene as it is; give the "
                         "overrides, outputs and accuracy to resolve() instead")
    else:
        sc = choice.scene
    return run_resolved(sc, choice, progress=progress, snapshot_every=snapshot_every)


def resolve(scene: "str | Path | Scene", *, parameters: Mapping[str, Any] | None = None,
            outputs=None, accuracy=None, **overrides):
    """The first steps of one run, each handing the next what it needs: load the scene, apply
    the overrides (one :meth:`Scene.with_overrides`), and with ``fidelity="auto"`` choose the
    level (:func:`chainmodel.fidelity_auto.choose`, which builds the chosen scene and its
    model once). Returns (scene, choice): the scene that runs and the AutoChoice or None.
    Arguments as :func:`simulate`; the CLI calls this and :func:`run_resolved` too."""
    auto = isinstance(overrides.get("fidelity"), str) and \
        overrides["fidelity"].strip().lower() == "auto"
    if auto:
        overrides.pop("fidelity")
    elif outputs is not None or accuracy is not None:
        raise ValueError("outputs and accuracy are only used with fidelity='auto', got "
                         f"fidelity={overrides.get('fidelity', 'the scene default')!r}")
    sc = load_scene(scene)
    if parameters or overrides:
        sc = sc.with_overrides(parameters=parameters, **overrides)
    if not auto:
        return sc, None
    from .fidelity_auto import choose
    choice = choose(sc, outputs, accuracy)
    return choice.scene, choice


def run_resolved(sc: Scene, choice=None, *, progress: bool = False,
                 snapshot_every: int = 0) -> Result:
    """The rest of one run after :func:`resolve`: run ``sc`` (on the model the choice built,
    if any: it is not built again) and wrap the result; a divergence that the drive's
    geometry explains says so."""
    try:
        result = run_scene(sc, progress=progress, snapshot_every=snapshot_every,
                           model=None if choice is None else choice.model)
    except SimulationDiverged as exc:
        # a chain far too long or short for its centre distance makes level 3 diverge at once;
        # say so rather than leave the step blamed (chainmodel.validity)
        from .validity import geometry_problems
        found = geometry_problems(sc.drive, sc.parameters)
        if not found:
            raise
        raise SimulationDiverged(f"{exc}. The likely cause is not the step: "
                                 f"{found[0].message}") from exc
    result.auto_choice = choice
    return result
