#!/usr/bin/env python
"""The FMU in fmusim (Modelica Reference-FMUs' C simulator) with nothing configured: each level
under ``env -i`` against fmpy.simulate_fmu on the same input file, then exit codes.

    python benchmarks/fmusim_host.py dist/ChainDrive.fmu --fmusim /path/to/fmusim --runs 20

fmusim is not installable from PyPI or Debian: it was built from Reference-FMUs commit 7b3fc08^
(the last with fmusim/) with gcc against Debian's libxml2, minizip, zlib and sundials 6.4 (one
token changed for CVODE 6: SUN_COMM_NULL -> NULL; CVODE serves only model exchange). Inputs:
input_shaft.angle = 12 t, input_shaft.speed = 12 rad/s, load.torque = 20 N m at every 0.1 ms
point to 4 ms; fmusim prints 16 significant digits, so outputs are compared to 1e-12 (relative
to the output's largest magnitude).
"""

from __future__ import annotations

import argparse
import collections
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", type=Path)
    ap.add_argument("--fmusim", type=Path, required=True)
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--levels", default="0,1,2,3")
    args = ap.parse_args(argv)
    import fmpy
    tmp = Path(tempfile.mkdtemp())
    rows = [(k * 100_000 / 1e9) for k in range(41)]
    (tmp / "in.csv").write_text("time,input_shaft.angle,input_shaft.speed,load.torque\n" + "".join(
        f"{t!r},{12.0 * t!r},12.0,20.0\n" for t in rows))
    table = np.array([(t, 12.0 * t, 12.0, 20.0) for t in rows],
                     dtype=[("time", float), ("input_shaft.angle", float),
                            ("input_shaft.speed", float), ("load.torque", float)])

    def fmusim(level, out):
        return subprocess.run(["env", "-i", str(args.fmusim.resolve()), "--interface-type", "cs",
                               "--start-value", "fidelity", str(level), "--input-file",
                               str(tmp / "in.csv"), "--output-interval", "1e-4", "--stop-time",
                               "0.004", "--output-file", str(out), str(args.fmu.resolve())],
                              capture_output=True, text=True, timeout=600)

    print("| level | fmusim exit | samples | worst |fmusim - fmpy| / max|fmpy| |")
    print("|---|---|---|---|")
    for level in (int(v) for v in args.levels.split(",")):
        out = tmp / f"out{level}.csv"
        proc = fmusim(level, out)
        if proc.returncode != 0:
            print(f"| {level} | {proc.returncode} | - | {proc.stderr.strip()[-200:]} |")
            continue
        got = np.genfromtxt(out, delimiter=",", names=True, deletechars="")
        ref = fmpy.simulate_fmu(str(args.fmu), start_values={"fidelity": level}, input=table,
                                stop_time=0.004, output_interval=1e-4)
        names = [n for n in ref.dtype.names if n != "time"]
        n = min(len(got), len(ref))
        worst = max(float(np.max(np.abs(got[name.strip('"')][:n] - ref[name][:n]))
                          / max(np.max(np.abs(ref[name][:n])), 1e-300)) for name in names)
        print(f"| {level} | 0 | {len(got)} (fmpy {len(ref)}) | {worst:.1e} |", flush=True)
    counts = collections.Counter()
    for _ in range(args.runs):
        proc = fmusim(0, tmp / "exit.csv")
        counts[proc.returncode] += 1
    print(f"{args.runs} runs of fmusim at level 0 (4 ms) under env -i: "
          + ", ".join(f"exit {c}: {k}" for c, k in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
