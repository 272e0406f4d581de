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

__all__ = ["simulate_fmu", "FMUError", "reference_scene", "variables_table", "update_doc_table"]


class FMUError(RuntimeError):
    """The FMU refused a call; the message carries what the FMU logged."""


def reference_scene():
    """The scene of docs/fmu_reference.csv: xu2010 (seed 003 section 7) at fidelity 0, 0.2 s
    (ramp to 120 rpm over 0.05 s, 43.2 N.m load), sampled every 1 ms."""
    from .scene import Scene
    return Scene.from_preset("xu2010", fidelity=0, duration=0.2, output_interval=1e-3)


class _Log:
    """fmpy logger callbacks that keep the FMU's messages (and optionally pass them on)."""

    LABELS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")

    def __init__(self, echo: Callable[[str], None] | None = None):
        from ctypes import byref

        from fmpy.fmi1 import calloc, free
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
        self.messages: list[tuple[int, str]] = []
        self.echo = echo
        cb = fmi2CallbackFunctions()
        cb.logger = fmi2CallbackLoggerTYPE(self._log)
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:  # formats the printf-style message the FMU passes
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(byref(cb))
        except Exception:  # pragma: no cover - fmpy without the proxy library
            pass
        self.callbacks = cb

    def _log(self, env, instance, status, category, message):
        text = message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
        self.messages.append((int(status), text))
        if self.echo:
            self.echo(f"[{self.LABELS[status] if 0 <= status < 6 else status}] {text}")

    def problems(self, since: int = 0) -> str:
        msgs = [m for s, m in self.messages[since:] if s >= 1]
        return "; ".join(msgs) if msgs else "the FMU logged no reason"


_EXTRACTED: dict[tuple, str] = {}


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
    outputs = [v.name for v in md.modelVariables if v.causality == "output"]
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

    ``result.stats`` has ``communication_steps``, ``wall_time`` and ``fmu`` (the path);
    ``result.descriptions`` are the chosen level's output descriptions.
    """
    from fmpy import read_model_description
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import FMU2Slave

    from .models import SimulationDiverged
    from .parameters import FIDELITY_NAMES
    from .scene import load_scene
    from .simulation import Result, _Progress

    sc = load_scene(scene)
    fmu_path = Path(fmu_path)
    if not fmu_path.is_file():
        raise ValueError(f"FMU {str(fmu_path)!r} does not exist; build it with "
                         "`python build_fmu.py`")
    md = read_model_description(str(fmu_path))
    by_name, outputs = _value_refs(md)
    missing = [n for n in sc.parameters if n not in by_name]
    if missing:
        raise ValueError(f"the FMU {fmu_path.name} has no parameter(s) {', '.join(missing)}; "
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
    times = sc.times()
    data = np.empty((len(times), len(outputs)))
    logger = _Log(log)
    bar = _Progress(progress, float(times[-1]),
                    f"{sc.name} ({FIDELITY_NAMES[sc.fidelity]}, via FMU)")

    unzipdir = _extracted(fmu_path)
    fmu = None
    wall = _time.perf_counter()
    try:
        fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir,
                        modelIdentifier=md.coSimulation.modelIdentifier,
                        instanceName="chainmodel")
        fmu.instantiate(callbacks=logger.callbacks, loggingOn=True)
        fmu.setupExperiment(startTime=float(times[0]), stopTime=float(times[-1]))
        fmu.enterInitializationMode()
        setters = {"Real": fmu.setReal, "Integer": fmu.setInteger,
                   "Boolean": fmu.setBoolean, "String": fmu.setString}
        for typ, (vrs, values) in groups.items():
            setters[typ](vrs, values)

        def inputs(t):
            u = sc.inputs(float(t))
            fmu.setReal(in_vr, [u.angle, u.speed, u.torque])

        inputs(times[0])
        mark = len(logger.messages)
        try:
            fmu.exitInitializationMode()
        except FMICallException:
            raise ValueError(logger.problems(mark)) from None
        data[0] = fmu.getReal(out_vr)
        for i in range(1, len(times)):
            mark = len(logger.messages)
            try:
                fmu.doStep(currentCommunicationPoint=float(times[i - 1]),
                           communicationStepSize=float(times[i] - times[i - 1]))
            except FMICallException as exc:
                raise SimulationDiverged(f"FMU step to t = {times[i]:.6g} s failed ({exc}): "
                                         f"{logger.problems(mark)}") from None
            inputs(times[i])
            data[i] = fmu.getReal(out_vr)
            bar.update(float(times[i]))
        bar.close()
        fmu.terminate()
    except FMICallException as exc:
        raise FMUError(f"{exc}: {logger.problems()}") from None
    finally:
        if fmu is not None and fmu.component is not None:
            # Free the instance but keep the shared library loaded: unloading pythonfmu's
            # wrapper inside a running Python (fmpy's freeInstance does dlclose) corrupts the
            # heap at interpreter exit now and then (PythonFMU issue #228; FMPy #147 suggests
            # this workaround). The library is unloaded with the process.
            fmu.fmi2FreeInstance(fmu.component)
            fmu.component = None
    wall = _time.perf_counter() - wall

    try:   # metadata only: the chosen level's descriptions and static tension
        model = sc.model()
        descriptions, static = model.output_descriptions(), model.static_tension
    except Exception:
        descriptions = {n: by_name[n].description or "" for n in outputs}
        static = math.nan
    series = {name: data[:, k].copy() for k, name in enumerate(outputs)}
    stats = {"communication_steps": len(times) - 1, "wall_time": wall, "fmu": str(fmu_path)}
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
