"""Cost per communication step of the ChainDrive FMU through fmpy, next to a bare pythonfmu FMU.

    python benchmarks/fmu_cost.py                  # build both FMUs in a temp dir, measure, print
    python benchmarks/fmu_cost.py --write-doc      # ... and rewrite "## FMU" in docs/performance.md

Both FMUs are driven by the same master loop through fmpy's low-level API, interleaved block by
block in the same run: per step set the three inputs, fmi2DoStep, get the fifteen outputs. The
bare FMU (benchmarks/bare_fmu/BareFmu.py, same inputs and outputs, does nothing) is the floor
every pythonfmu FMU pays. For every fidelity level the table gives the ChainDrive FMU, the
floor, their ratio, and the library's own cost per output point (``simulate()`` of the same
scene and grid, whole call, divided by its points), plus the adapter's own Python measured
in-process without FMI. Targets (issue 8): levels 0-2 within 2x the floor; level 3 within the
floor + 1.3x the library's cost per output. Built FMUs go to a temporary directory (nothing is
committed).
"""

from __future__ import annotations

import argparse
import datetime
import math
import os
import platform
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

BARE_SOURCE = ROOT / "benchmarks" / "bare_fmu" / "BareFmu.py"
INPUTS = ("input_shaft.angle", "input_shaft.speed", "load.torque")
DOC = ROOT / "docs" / "performance.md"
COMMAND = "python benchmarks/fmu_cost.py --write-doc"


def build_bare_fmu(dest_dir: str | Path) -> Path:
    """Build the do-nothing FMU into ``dest_dir`` (e.g. a temporary directory)."""
    from pythonfmu import FmuBuilder
    return Path(FmuBuilder.build_FMU(BARE_SOURCE, dest=Path(dest_dir)))


def build_chaindrive_fmu(dest_dir: str | Path) -> Path:
    import build_fmu
    return build_fmu.build(Path(dest_dir) / "ChainDrive.fmu", quiet=True)


class _Master:
    """One FMU instance driven by the benchmark loop."""

    def __init__(self, fmu_path: Path, parameters: dict | None = None):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave
        md = read_model_description(str(fmu_path))
        self.var = {v.name: v for v in md.modelVariables}
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=extract(str(fmu_path)),
                             modelIdentifier=md.coSimulation.modelIdentifier, instanceName="bench")
        self.fmu.instantiate()
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for name, value in (parameters or {}).items():
            v = self.var[name]
            {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
             "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[v.type](
                [v.valueReference], [value])
        self.in_vr = [self.var[n].valueReference for n in INPUTS]
        self.out_vr = [v.valueReference for v in md.modelVariables if v.causality == "output"]
        self.t = 0.0

    def start(self, u0):
        self.fmu.setReal(self.in_vr, list(u0))
        self.fmu.exitInitializationMode()

    def run(self, inputs: np.ndarray, h: float) -> float:
        """Seconds per communication step over the rows of ``inputs``."""
        fmu, in_vr, out_vr, t = self.fmu, self.in_vr, self.out_vr, self.t
        set_real, do_step, get_real = fmu.setReal, fmu.doStep, fmu.getReal
        rows = inputs.tolist()
        wall = time.perf_counter()
        for row in rows:
            set_real(in_vr, row)
            do_step(t, h)
            t += h
            get_real(out_vr)
        wall = time.perf_counter() - wall
        self.t = t
        return wall / len(rows)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()


def _adapter(tmp: str):
    """The adapter (fmu_src/ChainDrive.py) in-process, with a copy of the package as its vendored
    chainmodel (a copy, not a link: numba caches compiled kernels beside their source file, and
    a link would leave entries for the adapter's private module name in the worktree)."""
    import importlib.util
    import shutil
    vendor = Path(tmp) / "_vendor"
    vendor.mkdir()
    shutil.copytree(ROOT / "chainmodel", vendor / "chainmodel",
                    ignore=shutil.ignore_patterns("__pycache__"))
    spec = importlib.util.spec_from_file_location("_bench_adapter",
                                                  ROOT / "fmu_src" / "ChainDrive.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod.ChainDrive(instance_name="bench", resources=tmp)


def adapter_cost(level: int, parameters: dict, table: np.ndarray, h: float) -> float:
    """Seconds per step of the adapter called in-process without FMI (set inputs, do_step, get
    outputs): what the FMU costs besides the pythonfmu floor."""
    with tempfile.TemporaryDirectory(prefix="fmu_adapter_") as tmp:
        slave = _adapter(tmp)
        vr = {v.name: k for k, v in slave.vars.items()}
        in_vr = [vr[n] for n in INPUTS]
        out_vr = [k for k, v in slave.vars.items() if v.causality.name == "output"]
        slave.setup_experiment(0.0)
        for name, value in parameters.items():
            {float: slave.set_real, int: slave.set_integer, bool: slave.set_boolean,
             str: slave.set_string}[type(value)]([vr[name]], [value])
        slave.set_real(in_vr, list(table[0]))
        slave.exit_initialization_mode()
        rows = table[1:].tolist()
        t, best = 0.0, math.inf
        for block in range(0, len(rows), 500):
            wall = time.perf_counter()
            for row in rows[block:block + 500]:
                slave.set_real(in_vr, row)
                slave.do_step(t, h)
                t += h
                slave.get_real(out_vr)
            best = min(best, (time.perf_counter() - wall) / len(rows[block:block + 500]))
        return best


def library_cost(scene, points: int, h: float, repeats: int = 3) -> float:
    """Seconds per output point of the library's whole simulate() call (run_scene) on the same
    scene and grid (best of ``repeats``, after a warm-up)."""
    from chainmodel.simulation import run_scene
    sc = scene.with_overrides(duration=points * h, output_interval=h)
    run_scene(sc.with_overrides(duration=10 * h))
    best = math.inf
    for _ in range(repeats):
        wall = time.perf_counter()
        run_scene(sc)
        best = min(best, time.perf_counter() - wall)
    return best / points


def fmu_step_cost(steps: int = 200, repeats: int = 15, h: float = 1e-4, levels=(0, 1, 2, 3),
                  chaindrive: str | Path | None = None, bare: str | Path | None = None) -> dict:
    """Per level: cost per communication step [s] of the ChainDrive FMU and of the bare FMU
    through fmpy, interleaved (medians over ``repeats`` blocks of ``steps``), the library's
    cost per output and the adapter's own. Builds the FMUs not given. Scene: xu2010 (seed 003:
    ramp to 120 rpm in 0.05 s, 43.2 N.m), the blocks from t = 0."""
    from chainmodel.scene import Scene
    n = steps * repeats + 1
    results = {}
    with tempfile.TemporaryDirectory(prefix="fmu_cost_") as tmp:
        chaindrive = Path(chaindrive) if chaindrive else build_chaindrive_fmu(tmp)
        bare = Path(bare) if bare else build_bare_fmu(tmp)
        for level in levels:
            scene = Scene.from_preset("xu2010", fidelity=level)
            u = [scene.inputs(k * h) for k in range(n)]
            table = np.array([[v.angle, v.speed, v.torque] for v in u])
            cd = _Master(chaindrive, scene.parameters)
            bf = _Master(bare)
            cd.start(table[0])
            bf.start(table[0])
            wall = time.perf_counter()
            cd.run(table[1:2], h)       # the first step compiles the FMU's own kernels
            first = time.perf_counter() - wall
            cost_cd, cost_bare = [], []
            for r in range(repeats):
                block = table[1 + r * steps: 1 + (r + 1) * steps]
                cost_bare.append(bf.run(block, h))
                cost_cd.append(cd.run(block, h))
            cd.close()
            bf.close()
            med = statistics.median
            results[level] = {"chaindrive_s": med(cost_cd), "bare_s": med(cost_bare),
                              "ratio": med(c / b for c, b in zip(cost_cd, cost_bare)),
                              "library_s": library_cost(scene, n - 1, h),
                              "adapter_s": adapter_cost(level, scene.parameters, table, h),
                              "first_step_s": first,
                              "all": {"chaindrive": cost_cd, "bare": cost_bare}}
    return {"levels": results, "steps": steps, "repeats": repeats, "h": h}


def machine() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        model = next(line.split(":", 1)[1].strip() for line in out.splitlines()
                     if line.startswith("Model name"))
    except Exception:
        model = platform.processor() or "unknown CPU"
    import os
    return f"{model}, {os.cpu_count()} cores, Python {platform.python_version()}"


def section(res: dict) -> str:
    def us(s):
        return f"{s * 1e6:,.1f} µs"

    rows = []
    for level, r in res["levels"].items():
        if level < 3:
            target = f"{2 * r['bare_s'] * 1e6:,.0f} µs (2x floor)"
            met = r["chaindrive_s"] <= 2 * r["bare_s"]
        else:
            bound = r["bare_s"] + 1.3 * r["library_s"]
            target = f"{bound * 1e6:,.0f} µs (floor + 1.3 x library)"
            met = r["chaindrive_s"] <= bound
        rows.append(f"| {level} | {us(r['chaindrive_s'])} | {us(r['bare_s'])} | "
                    f"{r['ratio']:.2f} | {us(r['library_s'])} | {us(r['adapter_s'])} | "
                    f"{target}: {'met' if met else 'NOT met'} |")
    import fmpy
    import pythonfmu
    load = " ".join(f"{v:.2f}" for v in os.getloadavg())
    return f"""## FMU

Cost per communication step of `ChainDrive.fmu` through fmpy's low-level API, next to a bare
pythonfmu FMU with the same 3 inputs and 15 outputs that does nothing
(`benchmarks/bare_fmu/BareFmu.py`), measured interleaved block by block in the same run. Master
loop per step: set the 3 inputs, `fmi2DoStep`, get the 15 outputs. Scene: xu2010 (seed 003
drive, ramp to 120 rpm, 43.2 N.m), h = {res['h']:g} s, median of {res['repeats']} blocks of
{res['steps']} steps from t = 0. "library": the whole `simulate()` call on the same grid divided
by its output points; "adapter": `fmu_src/ChainDrive.py` called in-process without FMI (best
block of 500 steps).

| level | ChainDrive FMU | bare FMU (floor) | ratio (median per block) | library per output | adapter alone | target |
|---|---:|---:|---:|---:|---:|---|
{chr(10).join(rows)}

One `fmi2DoStep` is one compiled call at every level (the step, its stable-step guard and the
15 outputs into a buffer; `Stepper.advance_held`); the adapter copies the values. The rest of
the FMU's cost is pythonfmu's own per-call path (the floor: ctypes, the C++ wrapper, the GIL,
Python-side get/set), paid three times a step by this master.

Command: `{COMMAND}`; machine: {machine()}; fmpy {fmpy.__version__}, pythonfmu
{pythonfmu.__version__}; load average {load} (when other jobs share the 2 cores the interleaving
keeps the ratios fair; the absolute figures are indicative); date
{datetime.date.today().isoformat()}.
"""


def write_section(text: str, doc: Path = DOC) -> None:
    """Replace (or add) the '## FMU' section of the shared docs/performance.md."""
    if doc.is_file():
        lines = doc.read_text().splitlines(keepends=True)
        start = next((i for i, line in enumerate(lines) if line.strip() == "## FMU"), None)
        if start is None:
            body = "".join(lines).rstrip("\n") + "\n\n" + text
        else:
            end = next((i for i in range(start + 1, len(lines))
                        if lines[i].startswith("## ")), len(lines))
            body = "".join(lines[:start]) + text + ("\n" if end < len(lines) else "") + \
                "".join(lines[end:])
    else:
        body = "# Performance\n\n" + text
    doc.write_text(body)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--steps", type=int, default=200, help="steps per block")
    ap.add_argument("--repeats", type=int, default=15, help="blocks, interleaved")
    ap.add_argument("--levels", type=int, nargs="*", default=[0, 1, 2, 3])
    ap.add_argument("--write-doc", action="store_true", help="rewrite '## FMU' in docs/performance.md")
    args = ap.parse_args(argv)
    res = fmu_step_cost(args.steps, args.repeats, levels=tuple(args.levels))
    text = section(res)
    print(text)
    if args.write_doc:
        write_section(text)
        print(f"updated {DOC}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
