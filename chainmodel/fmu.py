"""Run the built ChainDrive FMU through fmpy, and describe it (no physics here).

``simulate_fmu(fmu_path, scene)`` is what ``chainmodel run --via-fmu`` calls: the same scene,
communication grid and Result as :func:`chainmodel.simulation.run_scene`, but every sample comes
from the FMU. fmpy is imported only when these functions run, so the package (and the copy of it
vendored inside the FMU) does not need fmpy.

    python -m chainmodel.fmu dist/ChainDrive.fmu --doc     # markdown table of its variables
"""

from __future__ import annotations

import math
import shutil
import time as _time
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .fmu_log import FMULog

__all__ = ["simulate_fmu", "FMUSession", "FMUError", "reference_scene", "variables_table",
           "update_doc_table", "differing_files"]

#: where build_fmu.py puts its copy of this package inside the FMU
_VENDORED = "resources/_vendor/chainmodel/"


class FMUError(RuntimeError):
    """The FMU refused a call; the message carries what the FMU logged."""


def reference_scene():
    """The scene of docs/fmu_reference.csv: xu2010 (seed 003 section 7) at fidelity 0, 0.2 s
    (ramp to 120 rpm over 0.05 s, 43.2 N.m load), sampled every 1 ms."""
    from .scene import Scene
    return Scene.from_preset("xu2010", fidelity=0, duration=0.2, output_interval=1e-3)


_EXTRACTED: dict[tuple, str] = {}


def differing_files(fmu_path: str | Path) -> list[str]:
    """The files of this package (``chainmodel/...``) whose content differs between the FMU's
    embedded copy and the package installed here, or that only one of them has (compiled
    caches left out, as build_fmu.py leaves them out): empty when the FMU was built from this
    very chainmodel. A different list means the FMU's results are another version's."""
    import hashlib
    import zipfile
    here = Path(__file__).resolve().parent
    skip = ("__pycache__", ".pyc", ".pyo")

    def digest(data: bytes) -> str:
        return hashlib.sha256(data).hexdigest()

    ours = {p.relative_to(here).as_posix(): digest(p.read_bytes()) for p in here.rglob("*")
            if p.is_file() and not any(k in p.as_posix() for k in skip)}
    with zipfile.ZipFile(fmu_path) as z:
        theirs = {n[len(_VENDORED):]: digest(z.read(n)) for n in z.namelist()
                  if n.startswith(_VENDORED) and not n.endswith("/")
                  and not any(k in n for k in skip)}
    return sorted("chainmodel/" + k for k in set(ours) | set(theirs)
                  if ours.get(k) != theirs.get(k))


def _extracted(fmu_path: Path) -> str:
    """Unzip each FMU file once per process (the FMU imports its Python code from there)."""
    import atexit

    from fmpy import extract
    st = fmu_path.stat()
    key = (str(fmu_path.resolve()), st.st_mtime_ns, st.st_size)
    if key not in _EXTRACTED or not Path(_EXTRACTED[key]).is_dir():
        if not _EXTRACTED:
            atexit.register(lambda: [shutil.rmtree(d, ignore_errors=True)
                                     for d in _EXTRACTED.values()])
        _EXTRACTED[key] = extract(str(fmu_path))
    return _EXTRACTED[key]


def _value_refs(md):
    by_name = {v.name: v for v in md.modelVariables}
    # the library's outputs (run_scene's columns); motor.angle and motor.speed are for masters
    from .models import ALL_OUTPUTS
    known = {o.name for o in ALL_OUTPUTS}
    outputs = [v.name for v in md.modelVariables if v.causality == "output" and v.name in known]
    return by_name, outputs


def simulate_fmu(fmu_path: str | Path, scene: Any = "xu2010", *, log: Callable[[str], None] | None = None,
                 progress: bool = False):
    """Simulate ``scene`` with the FMU at ``fmu_path`` and return a
    :class:`chainmodel.simulation.Result` like :func:`chainmodel.simulation.run_scene` does.

    ``scene``: a :class:`~chainmodel.scene.Scene`, a preset name or a TOML path. Every parameter
    of the scene is set on the FMU (by name; the FMU must know them all), the scene's operating
    profile gives the three inputs at each communication point of ``scene.times()``, and at each
    point the outputs are read *after* the inputs of that point are set (the FMU recomputes
    its outputs for them: direct feedthrough). Differences from ``run_scene`` therefore come only
    from the FMU's conventions: inputs held first-order within a step and the input-shaft
    acceleration estimated by backward difference of the speed (0 at t = 0) instead of the
    profile's exact acceleration (see docs/fmu.md).

    ``log``: called with each message the FMU logs (e.g. ``print``). ``progress``: one
    updating line on stderr, as ``run_scene`` shows it. Errors raise ValueError
    (initialization refused: the message names the parameter), or
    :class:`~chainmodel.models.base.SimulationDiverged` (a step was discarded), or
    :class:`FMUError`.

    ``result.stats`` has ``communication_steps``, ``wall_time``, ``startup_time`` (the part of
    it before the first step: instantiation or reset, parameters, initialization) and ``fmu``;
    ``result.descriptions`` are the chosen level's output descriptions. Many runs of one FMU
    (a sweep) reuse one instance with :class:`FMUSession`.
    """
    with FMUSession(fmu_path, log=log) as session:
        return session.run(scene, progress=progress)


class FMUSession:
    """One FMU, extracted once, and one instance of it reused for many runs.

    The first :meth:`run` instantiates; each later one calls ``fmi2Reset`` (pythonfmu builds a
    fresh adapter object, so a run after a reset gives the numbers of a run on a new instance)
    and re-instantiates only where the reset is refused, e.g. after a failed run. This is how
    FMPy's parameter-variation example runs a chunk of cases on one instance; a sweep worker
    keeps one session per chunk. :meth:`close` frees the instance as fmpy does (the FMU pins
    pythonfmu's library, so the unload is harmless; docs/fmu.md, "Hosts"). ``unzipdir``: where the FMU is already extracted
    (default: extracted once per process into a temporary directory)."""

    def __init__(self, fmu_path: str | Path, *, log: Callable[[str], None] | None = None,
                 unzipdir: str | Path | None = None):
        from fmpy import read_model_description
        self.path = Path(fmu_path)
        if not self.path.is_file():
            raise ValueError(f"FMU {str(self.path)!r} does not exist; build it with "
                             "`python build_fmu.py`")
        self.md = read_model_description(str(self.path))
        self.by_name, self.outputs = _value_refs(self.md)
        self.logger = FMULog(log)
        self.unzipdir = str(unzipdir) if unzipdir is not None else _extracted(self.path)
        self.fmu = None
        self._used = False
        self.instantiations = 0     # how often an instance was created (resets reuse one)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def _instance(self):
        """A fresh or reset instance, ready for setupExperiment."""
        from fmpy.fmi1 import FMICallException
        from fmpy.fmi2 import FMU2Slave
        if self.fmu is not None and self._used:
            try:
                self.fmu.reset()
                self._used = False
                return self.fmu
            except FMICallException:
                self._free()
        if self.fmu is None:
            self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                                 modelIdentifier=self.md.coSimulation.modelIdentifier,
                                 instanceName="chainmodel")
            self.fmu.instantiate(callbacks=self.logger.callbacks, loggingOn=True)
            self.instantiations += 1
        return self.fmu

    def _free(self):
        fmu, self.fmu = self.fmu, None
        if fmu is not None and fmu.component is not None:
            fmu.freeInstance()   # as fmpy's own simulate_fmu does (docs/fmu.md, "Hosts")

    def close(self) -> None:
        self._free()

    def run(self, scene: Any, progress: bool = False):
        """Simulate ``scene`` on this session's instance (see :func:`simulate_fmu`)."""
        from fmpy.fmi1 import FMICallException

        from .fmu_hosts import FmpyBinding, master_loop
        from .models import SimulationDiverged
        from .parameters import FIDELITY_NAMES
        from .run_memory import check_run_memory
        from .scene import load_scene
        from .simulation import Result, _Progress

        sc = load_scene(scene)
        if sc.parameters["input_shaft.causality"] != "angle":
            raise ValueError("simulate_fmu drives the FMU's input shaft (angle causality); "
                             "parameter input_shaft.causality = torque needs a master that sets "
                             "motor.torque (examples/system/run_system.py); the library runs it "
                             "with chainmodel.simulate")
        by_name, outputs, logger = self.by_name, self.outputs, self.logger
        missing = [n for n in sc.parameters if n not in by_name]
        if missing:
            raise ValueError(f"the FMU {self.path.name} has no parameter(s) {', '.join(missing)}; "
                             "rebuild it from this version of chainmodel")
        groups: dict[str, tuple[list, list]] = {}
        for name, value in sc.parameters.items():
            v = by_name[name]
            vrs, values = groups.setdefault(v.type, ([], []))
            vrs.append(v.valueReference)
            values.append(value)
        in_vr = [by_name[n].valueReference for n in
                 ("input_shaft.angle", "input_shaft.speed", "load.torque")]
        out_vr = [by_name[n].valueReference for n in outputs]
        check_run_memory(sc.duration, sc.output_interval, sc.fidelity, len(outputs))
        times = sc.times()
        data = np.empty((len(times), len(outputs)))
        bar = _Progress(progress, float(times[-1]),
                        f"{sc.name} ({FIDELITY_NAMES[sc.fidelity]}, via FMU)")

        wall = _time.perf_counter()
        try:
            fmu = self._instance()
            self._used = True       # from here on, the next run resets (or re-instantiates)
            fmu.setupExperiment(startTime=float(times[0]), stopTime=float(times[-1]))
            fmu.enterInitializationMode()
            setters = {"Real": fmu.setReal, "Integer": fmu.setInteger,
                       "Boolean": fmu.setBoolean, "String": fmu.setString}
            for typ, (vrs, values) in groups.items():
                setters[typ](vrs, values)

            angle, speed, _, torque = sc.input_arrays(times)
            u = np.ascontiguousarray(np.column_stack((angle, speed, torque)))
            fmu.setReal(in_vr, u[0].tolist())
            mark = len(logger.messages)
            try:
                fmu.exitInitializationMode()
            except FMICallException:
                raise ValueError(logger.problems(mark)) from None
            data[0] = fmu.getReal(out_vr)
            startup = _time.perf_counter() - wall
            i = master_loop(FmpyBinding(fmu, in_vr, out_vr), times, u, data,
                            feedthrough=True, progress=bar)
            if i < len(times):
                raise SimulationDiverged(f"FMU step to t = {times[i]:.6g} s failed: "
                                         f"{logger.problems()}")
            bar.close()
            fmu.terminate()
        except FMICallException as exc:
            raise FMUError(f"{exc}: {logger.problems()}") from None
        wall = _time.perf_counter() - wall

        try:   # metadata only: the chosen level's descriptions and static tension
            model = sc.model()
            descriptions, static = model.output_descriptions(), model.static_tension()
        except Exception:
            descriptions = {n: by_name[n].description or "" for n in outputs}
            static = math.nan
        series = {name: data[:, k].copy() for k, name in enumerate(outputs)}
        stats = {"communication_steps": len(times) - 1, "wall_time": wall, "fmu": str(self.path),
                 "startup_time": startup}
        return Result(sc, times, series, descriptions, wall, stats, static)


# --- documentation -------------------------------------------------------------------------

def variables_table(fmu_path: str | Path) -> str:
    """Markdown tables (inputs, outputs, parameters) of the FMU's variables, from its
    modelDescription.xml."""
    from fmpy import read_model_description
    md = read_model_description(str(fmu_path))

    def cell(text):
        return (text or "").replace("|", "\\|")

    lines = []
    for title, causality in (("Inputs", "input"), ("Outputs", "output"),
                             ("Parameters", "parameter")):
        rows = [v for v in md.modelVariables if v.causality == causality]
        lines += [f"#### {title} ({len(rows)})", "",
                  "| name | type | unit | start | variability | description |",
                  "|---|---|---|---|---|---|"]
        for v in rows:
            unit = v.unit or ""
            if v.displayUnit:
                unit += f" (shown in {v.displayUnit})"
            start = "" if v.start is None else str(v.start)
            lines.append(f"| `{v.name}` | {v.type} | {cell(unit)} | {cell(start)} | "
                         f"{v.variability} | {cell(v.description)} |")
        lines.append("")
    de = md.defaultExperiment
    lines.append(f"Default experiment: start {de.startTime} s, stop {de.stopTime} s, "
                 f"step {de.stepSize} s, tolerance {de.tolerance}.")
    return "\n".join(lines) + "\n"


BEGIN, END = "<!-- BEGIN GENERATED VARIABLES -->", "<!-- END GENERATED VARIABLES -->"


def update_doc_table(fmu_path: str | Path, doc: str | Path) -> None:
    """Replace the text between the generated-variables markers of ``doc``."""
    doc = Path(doc)
    text = doc.read_text()
    if BEGIN not in text or END not in text:
        raise ValueError(f"{doc} has no {BEGIN} ... {END} markers")
    head, rest = text.split(BEGIN, 1)
    _, tail = rest.split(END, 1)
    doc.write_text(f"{head}{BEGIN}\n{variables_table(fmu_path)}{END}{tail}")


def _main(argv=None) -> int:
    import argparse
    ap = argparse.ArgumentParser(prog="python -m chainmodel.fmu",
                                 description="Describe or run the ChainDrive FMU.")
    ap.add_argument("fmu", nargs="?", default="dist/ChainDrive.fmu")
    ap.add_argument("--doc", action="store_true", help="print the variables as Markdown tables")
    ap.add_argument("--run", metavar="SCENE", help="simulate a scene through the FMU and print "
                    "its summary")
    args = ap.parse_args(argv)
    if args.doc:
        print(variables_table(args.fmu), end="")
    if args.run:
        result = simulate_fmu(args.fmu, args.run)
        for key, value in result.summary().items():
            print(f"{key}: {value}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(_main())
