#!/usr/bin/env python
"""A fresh process that instantiates the FMU and runs 0.05 s of level 1, with the compiled kernels
(numba, loaded from the per-machine cache) against the pure-numpy twins (CHAINMODEL_NUMBA=0).

    python benchmarks/fresh_process.py [dist/ChainDrive.fmu] [--repeats 5]

Issue 8's target: the numba process takes at most 1.5x the CHAINMODEL_NUMBA=0 one (no compile
left). Each run is a new Python executing fmpy.simulate_fmu on xu2010 (level 1, 0.05 s at
0.1 ms, the scene's inputs as a table); the two kinds are interleaved and the whole process is
timed from the parent (imports included). One run with numba first fills the cache if it is
empty; it is reported apart, not in the medians. Prints a table; docs/performance.md has the
results.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

SCRIPT = r"""
import sys
import numpy as np
import fmpy
from chainmodel.scene import Scene
scene = Scene.from_preset("xu2010", fidelity=1, duration=0.05)
h = 1e-4
t = np.arange(0, 0.05 + h / 2, h)
u = [scene.inputs(v) for v in t]
signals = np.array([(v, w.angle, w.speed, w.torque) for v, w in zip(t, u)],
                   dtype=[("time", float), ("input_shaft.angle", float),
                          ("input_shaft.speed", float), ("load.torque", float)])
r = fmpy.simulate_fmu(sys.argv[1], stop_time=0.05, step_size=h, output_interval=h,
                      input=signals, start_values={"fidelity": 1})
assert r["tight_span.tension"][-1] > 0
"""


def run_once(fmu: Path, numba: bool) -> float:
    env = dict(os.environ, CHAINMODEL_NUMBA="1" if numba else "0")
    wall = time.perf_counter()
    subprocess.run([sys.executable, "-c", SCRIPT, str(fmu)], env=env, check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    return time.perf_counter() - wall


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", type=Path, nargs="?", default=ROOT / "dist" / "ChainDrive.fmu")
    ap.add_argument("--repeats", type=int, default=5)
    args = ap.parse_args(argv)
    if not args.fmu.exists():
        ap.error(f"FMU {args.fmu} does not exist; build it with python build_fmu.py")
    first = run_once(args.fmu, True)
    runs = {True: [], False: []}
    for _ in range(args.repeats):
        for numba in (True, False):
            runs[numba].append(run_once(args.fmu, numba))
    med = {k: statistics.median(v) for k, v in runs.items()}
    load = os.getloadavg()
    print(f"first numba process (fills the cache if empty): {first:.2f} s")
    print("| kernels | median [s] | runs [s] |")
    print("|---|---:|---|")
    for numba, name in ((True, "numba (cached)"), (False, "CHAINMODEL_NUMBA=0")):
        print(f"| {name} | {med[numba]:.2f} | {', '.join(f'{v:.2f}' for v in runs[numba])} |")
    ratio = med[True] / med[False]
    print(f"ratio numba / numpy: {ratio:.2f} (target <= 1.5: {'met' if ratio <= 1.5 else 'NOT met'})"
          f"; load average {load[0]:.2f} {load[1]:.2f} {load[2]:.2f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
