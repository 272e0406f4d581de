#!/usr/bin/env python
"""Error and cost against the communication step of the example system (Motor -> ChainDrive ->
Load, torque causality; examples/system/run_system.py) in libcosim and the fmpy Jacobi master.

    python benchmarks/system_steps.py                      # levels 1 and 3, both masters
    python benchmarks/system_steps.py --levels 1 --masters jacobi --stop 0.5

For each load (LOADS: the example Load FMU, torque0 + damping * driven speed; the same law with
its damping in ChainDrive's driven.damping; a constant 43.2 N m) and each master and level: the mean tight-span tension and mean
motor speed over 1 s at each step, their relative differences from the 1e-4 s run, and the wall
time of the run. Prints a markdown table (docs/performance.md, "System model steps").
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples" / "system"))

import run_system as R  # noqa: E402

#: the loads compared: the example Load FMU as it is; the same law with its speed-dependent
#: part inside ChainDrive (driven.damping, integrated with the drive) and the Load FMU giving the
#: constant part; a constant load
LOADS = {"example": ("example Load FMU (21.6 N m + 1.72 N m s/rad x driven speed)",
                     {"load": {"damping": R.SPLIT_DAMPING, "torque0": 21.6},
                      "chain": {"driven.damping": 0.0}}),
         "split": ("the same load, 1.72 N m s/rad in ChainDrive's driven.damping, Load FMU "
                   "21.6 N m (run_system.py's default)", {}),
         "constant": ("constant 43.2 N m", {"load": {"damping": 0.0, "torque0": 43.2},
                                            "chain": {"driven.damping": 0.0}})}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--levels", type=int, nargs="+", default=[1, 3])
    ap.add_argument("--steps", type=float, nargs="+", default=[1e-4, 2e-4, 5e-4, 1e-3, 2e-3])
    ap.add_argument("--stop", type=float, default=1.0)
    ap.add_argument("--masters", nargs="+", choices=sorted(R.MASTERS),
                    default=["libcosim", "jacobi"])
    ap.add_argument("--fmus", type=Path, default=None,
                    help="folder with the three FMUs (built there if missing)")
    ap.add_argument("--loads", nargs="+", choices=list(LOADS), default=list(LOADS))
    args = ap.parse_args(argv)
    folder = R.build_fmus(args.fmus or ROOT / "examples" / "system" / "dist")
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"machine: {platform.machine()} {platform.processor() or ''}, {os.cpu_count()} "
          f"CPUs, load average {load:.2f} at start; stop time {args.stop:g} s")
    for key in args.loads:
        name, extra = LOADS[key]
        print(f"\nload: {name}\n")
        print(R.HEADER)
        R.study(folder, args.masters, args.levels, args.steps, args.stop, extra=extra)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    print(f"\nload average {load:.2f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
