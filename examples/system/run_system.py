#!/usr/bin/env python
"""Motor -> ChainDrive -> Load in torque causality, run in libcosim (OspSystemStructure.xml here)
and in a Jacobi master written with fmpy (docs/fmu.md, "In a system model").

The Motor FMU (examples/system/Motor.py, ``causality = torque``) is a PI speed controller: it
reads the rotor speed ChainDrive integrates (``motor.speed``) and gives the torque
(``motor.torque``); ChainDrive (``input_shaft.causality = torque``) integrates the rotor on the
stiff input-shaft spring inside its own stepper; the Load FMU's torque follows the driven speed.
Every FMU sees the others' outputs of the last communication point (Jacobi; libcosim's fixed-step
algorithm does the same). The load is the example Load's law 21.6 N m + 1.72 N m s/rad x driven
speed with the speed-dependent part in ChainDrive's ``driven.damping`` (the start values of
OspSystemStructure.xml, mirrored in :func:`start_values`); ``--start load:damping=1.7189
load:torque0=21.6 chain:driven.damping=0`` feeds it back through the Load FMU instead.

    python examples/system/run_system.py                        # levels 1 and 3, both masters
    python examples/system/run_system.py --levels 1 --masters jacobi --stop 0.2
    python examples/system/run_system.py --fmus DIR             # FMUs already built in DIR

It prints, per master and level, the mean tight-span tension and mean motor speed over the run
at each communication step, and their relative differences from the smallest step's run.
"""

from __future__ import annotations

import argparse
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]

#: (from FMU, output) -> (to FMU, input): the wiring of OspSystemStructure.xml
CONNECTIONS = (("motor", "torque", "chain", "motor.torque"),
               ("chain", "motor.speed", "motor", "shaft.speed"),
               ("chain", "driven.speed", "load", "speed"),
               ("load", "torque", "chain", "load.torque"))
#: angle causality, for comparison (Jacobi master only): the Motor FMU integrates the rotor and
#: sends its angle and speed; ChainDrive returns the torque its input shaft takes
CONNECTIONS_ANGLE = (("motor", "rotor.angle", "chain", "input_shaft.angle"),
                     ("motor", "rotor.speed", "chain", "input_shaft.speed"),
                     ("chain", "input_shaft.torque", "motor", "shaft.torque"),
                     ("chain", "driven.speed", "load", "speed"),
                     ("load", "torque", "chain", "load.torque"))
SOURCES = {"motor": "Motor.fmu", "chain": "ChainDrive.fmu", "load": "Load.fmu"}
#: the example Load's speed-dependent part [N m s/rad] (43.2 N m at 120 rpm = 21.6 + this x
#: 12.566 rad/s), given to ChainDrive's driven.damping: integrated with the drive, not fed back
#: through a held torque (OspSystemStructure.xml, docs/fmu.md "In a system model")
SPLIT_DAMPING = 21.6 / 12.566370614359172
#: what the comparison reads: (FMU, output) -> label
RECORDED = {("chain", "tight_span.tension"): "tension", ("chain", "motor.speed"): "speed"}


def start_values(level: int, extra: dict | None = None) -> dict[str, dict]:
    """Start values per FMU: the causalities, ChainDrive's fidelity, then ``extra``
    ({fmu: {variable: value}})."""
    values = {"motor": {"causality": "torque"},
              "chain": {"input_shaft.causality": "torque", "fidelity": level,
                        "driven.damping": SPLIT_DAMPING},
              "load": {"damping": 0.0, "torque0": 21.6}}
    for fmu, more in (extra or {}).items():
        values[fmu].update(more)
    return values


def parse_start(items) -> dict[str, dict]:
    """``fmu:variable=value`` items (e.g. ``load:damping=0``) as {fmu: {variable: value}}."""
    out: dict[str, dict] = {}
    for item in items or ():
        try:
            head, value = item.split("=", 1)
            fmu, name = head.split(":", 1)
        except ValueError:
            raise SystemExit(f"run_system: --start {item!r}: expected fmu:variable=value")
        if fmu not in SOURCES:
            raise SystemExit(f"run_system: --start {item!r}: fmu must be one of "
                             f"{', '.join(SOURCES)}")
        v = value.strip()
        try:
            parsed = int(v) if v.lstrip("-").isdigit() else float(v)
        except ValueError:
            parsed = v
        out.setdefault(fmu, {})[name] = parsed
    return out


def build_fmus(folder: Path) -> Path:
    """ChainDrive.fmu (build_fmu.py) and Motor.fmu, Load.fmu (build.py) into ``folder``, with
    OspSystemStructure.xml beside them."""
    folder.mkdir(parents=True, exist_ok=True)
    if not (folder / "ChainDrive.fmu").is_file():
        subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out",
                        str(folder / "ChainDrive.fmu"), "-q"], check=True)
    if not (folder / "Motor.fmu").is_file() or not (folder / "Load.fmu").is_file():
        subprocess.run([sys.executable, str(HERE / "build.py"), "--out", str(folder), "--launch"],
                       check=True, stdout=subprocess.DEVNULL)
    shutil.copy(HERE / "OspSystemStructure.xml", folder / "OspSystemStructure.xml")
    return folder


# --- the Jacobi master (fmpy) ----------------------------------------------------------------

class _Instance:
    def __init__(self, name: str, path: Path, unzip: Path):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        self.md = read_model_description(str(path))
        self.vars = {v.name: v for v in self.md.modelVariables}
        folder = extract(str(path), str(unzip / name))
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=folder,
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName=name)
        self.fmu.instantiate()

    def vr(self, name: str) -> int:
        return self.vars[name].valueReference

    def set_start(self, values: dict) -> None:
        for name, value in values.items():
            v = self.vars[name]
            setter, kind = {"Real": (self.fmu.setReal, float),
                            "Integer": (self.fmu.setInteger, int),
                            "Boolean": (self.fmu.setBoolean, bool),
                            "String": (self.fmu.setString, str)}[v.type]
            setter([v.valueReference], [kind(value)])


def run_jacobi(folder: Path, level: int, step: float, stop: float, extra=None,
               causality: str = "torque") -> dict[str, np.ndarray]:
    """The three FMUs stepped side by side: at each communication point every output is read,
    then every input set, then every FMU stepped over ``step`` (fmpy's FMU2Slave)."""
    n = int(round(stop / step))
    rec = {label: np.empty(n + 1) for label in RECORDED.values()}
    with tempfile.TemporaryDirectory() as tmp:
        fmus = {name: _Instance(name, folder / src, Path(tmp)) for name, src in SOURCES.items()}
        starts = start_values(level, extra)
        connections, recorded = CONNECTIONS, dict(RECORDED)
        if causality == "angle":
            starts["motor"]["causality"] = starts["chain"]["input_shaft.causality"] = "angle"
            connections = CONNECTIONS_ANGLE
            recorded = {("chain", "tight_span.tension"): "tension",
                        ("motor", "rotor.speed"): "speed"}
        try:
            links = [(fmus[a], fmus[a].vr(out), fmus[b], fmus[b].vr(inp))
                     for a, out, b, inp in connections]
            reads = [(label, fmus[f], fmus[f].vr(v)) for (f, v), label in recorded.items()]

            def exchange():
                values = [src.fmu.getReal([vr])[0] for src, vr, _, _ in links]
                for (_, _, dst, vr), value in zip(links, values):
                    dst.fmu.setReal([vr], [value])

            for name, inst in fmus.items():
                inst.fmu.setupExperiment(startTime=0.0)
                inst.fmu.enterInitializationMode()
                inst.set_start(starts[name])
            exchange()             # initial values through the connections, as libcosim does
            for inst in fmus.values():
                inst.fmu.exitInitializationMode()
            for k in range(n + 1):
                exchange()
                for label, inst, vr in reads:
                    rec[label][k] = inst.fmu.getReal([vr])[0]
                if k == n:
                    break
                for name, inst in fmus.items():
                    try:         # fmpy raises on a status other than fmi2OK
                        inst.fmu.doStep(currentCommunicationPoint=k * step,
                                        communicationStepSize=step)
                    except Exception as exc:
                        error = RuntimeError(f"fmi2DoStep of {name} at t = {k * step:.6g} s: "
                                             f"{exc}")
                        error.record = {label: v[:k + 1] for label, v in rec.items()}
                        raise error from exc
        finally:
            for inst in fmus.values():
                inst.fmu.terminate()
                inst.fmu.freeInstance()
    return rec


# --- libcosim (libcosimpy) -------------------------------------------------------------------

def run_libcosim(folder: Path, level: int, step: float, stop: float, extra=None
                 ) -> dict[str, np.ndarray]:
    """The OSP system structure in libcosim, its base step set to ``step`` and ChainDrive's
    fidelity to ``level`` (a copy of the file)."""
    from libcosimpy.CosimEnums import CosimVariableType
    from libcosimpy.CosimExecution import CosimExecution
    from libcosimpy.CosimLogging import CosimLogLevel, log_output_level
    from libcosimpy.CosimObserver import CosimObserver

    sys.path.insert(0, str(ROOT))
    from chainmodel.fmu_hosts import _real_samples

    n = int(round(stop / step))
    text = (HERE / "OspSystemStructure.xml").read_text()
    text = text.replace("<BaseStepSize>1e-3</BaseStepSize>", f"<BaseStepSize>{step!r}</BaseStepSize>")
    text = text.replace('<Integer value="1"/>', f'<Integer value="{int(level)}"/>')
    config = folder / f"OspSystemStructure_{level}_{step:g}.xml"
    config.write_text(text)
    log_output_level(CosimLogLevel.ERROR)
    execution = CosimExecution.from_osp_config_file(str(config))
    slaves = {s.name.decode() if isinstance(s.name, bytes) else s.name: s.index
              for s in execution.slave_infos()}
    observer = CosimObserver.create_time_series(buffer_size=n + 2)
    execution.add_observer(observer)

    def reference(index, name):
        return next(x for x in execution.slave_variables(index)
                    if (x.name.decode() if isinstance(x.name, bytes) else x.name) == name)

    for fmu, values in (extra or {}).items():
        for name, value in values.items():
            var = reference(slaves[fmu], name)
            setter, kind = {CosimVariableType.REAL: (execution.real_initial_value, float),
                            CosimVariableType.INTEGER: (execution.integer_initial_value, int),
                            CosimVariableType.BOOLEAN: (execution.boolean_initial_value, bool),
                            CosimVariableType.STRING: (execution.string_initial_value, str)}[
                CosimVariableType(var.type)]
            if not setter(slaves[fmu], var.reference, kind(value)):
                raise RuntimeError(f"libcosim refused the start value {fmu}:{name} = {value!r}")
    refs = {}
    for (f, v), label in RECORDED.items():
        index = slaves[f]
        vr = reference(index, v).reference
        observer.start_time_series(index, vr, CosimVariableType.REAL)
        refs[label] = (index, vr)
    for k in range(n):
        if not execution.step():
            raise RuntimeError(f"libcosim step from t = {k * step:.6g} s failed")
    rec = {label: _real_samples(observer, index, vr, n + 1)
           for label, (index, vr) in refs.items()}
    execution.stop()
    config.unlink()
    return rec


MASTERS = {"jacobi": run_jacobi, "libcosim": run_libcosim,
           "jacobi-angle": lambda *a: run_jacobi(*a, causality="angle")}


def means(rec: dict[str, np.ndarray]) -> dict[str, float]:
    """Mean tight-span tension and mean motor speed over the run (every sample but t = 0)."""
    return {label: float(np.mean(values[1:])) for label, values in rec.items()}


def study(folder: Path, masters, levels, steps, stop, out=print, extra=None) -> list[dict]:
    """Every master x level x step; rows with the means, their relative differences from the
    smallest step's and the wall time."""
    rows = []
    for master in masters:
        for level in levels:
            ref = None
            for step in sorted(steps):
                wall = time.perf_counter()
                try:
                    m = means(MASTERS[master](folder, level, step, stop, extra))
                    error = None
                except RuntimeError as exc:
                    m, error = {"tension": float("nan"), "speed": float("nan")}, str(exc)
                wall = time.perf_counter() - wall
                if ref is None:
                    ref = m
                row = dict(master=master, level=level, step=step, wall=wall, **m,
                           d_tension=abs(m["tension"] / ref["tension"] - 1),
                           d_speed=abs(m["speed"] / ref["speed"] - 1), error=error)
                rows.append(row)
                out(format_row(row))
    return rows


HEADER = ("| master | level | step [s] | mean tension [N] | mean motor speed [rad/s] | "
          "tension diff | speed diff | wall [s] |\n|---|---|---|---|---|---|---|---|")


def format_row(r: dict) -> str:
    if r["error"]:
        return (f"| {r['master']} | {r['level']} | {r['step']:g} | failed: {r['error']} "
                f"| | | | {r['wall']:.1f} |")
    return (f"| {r['master']} | {r['level']} | {r['step']:g} | {r['tension']:.2f} | "
            f"{r['speed']:.4f} | {100 * r['d_tension']:.3f} % | {100 * r['d_speed']:.3f} % | "
            f"{r['wall']:.1f} |")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 3])
    ap.add_argument("--steps", type=float, nargs="+", default=[1e-4, 1e-3, 2e-3])
    ap.add_argument("--stop", type=float, default=1.0)
    ap.add_argument("--masters", nargs="+", choices=sorted(MASTERS), default=["libcosim", "jacobi"])
    ap.add_argument("--fmus", type=Path, default=None,
                    help="folder with ChainDrive.fmu, Motor.fmu, Load.fmu (built there if missing)")
    ap.add_argument("--start", nargs="*", metavar="FMU:VARIABLE=VALUE",
                    help="start values, e.g. load:damping=0 load:torque0=43.2")
    args = ap.parse_args(argv)
    extra = parse_start(args.start)
    folder = build_fmus(args.fmus or HERE / "dist")
    print(HEADER)
    rows = study(folder, args.masters, args.levels, args.steps, args.stop, extra=extra)
    bad = [r for r in rows if r["error"] or max(r["d_tension"], r["d_speed"]) > 0.01]
    print(f"{len(rows) - len(bad)} of {len(rows)} runs within 1 % of the smallest step's")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())
