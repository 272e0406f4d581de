#!/usr/bin/env python
"""Does a process holding ChainDrive.fmu and the example system's two plain pythonfmu FMUs
(examples/system: Motor, Load) exit cleanly? And if not, whose crash is it?

    python benchmarks/system_exit.py dist/ChainDrive.fmu --runs 50         # table of exit codes
    python benchmarks/system_exit.py dist/ChainDrive.fmu --bisect --runs 40
                  # the same count for every combination of the three FMUs
    python benchmarks/system_exit.py dist/ChainDrive.fmu --valgrind       # one run under valgrind:
                  # which FMU's binary reads or frees freed memory at exit
    ... --launch-examples     # the example FMUs with ChainDrive's launcher in front of their
                              # binaries (examples/system/build.py --launch), as docs/fmu.md
                              # tells users to build theirs
    ... --chaindrive-first    # load order ChainDrive, Motor, Load
    ... --os-exit             # each process ends with os._exit(0) after flushing stdout

Each run is a fresh Python executing tests/test_system_exit.py's SYSTEM_LIFE script (fmpy: every
FMU extracted, instantiated, initialized in the order Motor, ChainDrive, Load, 10 coupled steps
of 0.1 ms at fidelity 0, terminated, freed, folder deleted; normal exit). The example FMUs are built first (examples/system/build.py).
"""

from __future__ import annotations

import argparse
import collections
import itertools
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

from host_exit import invalid_reports   # benchmarks/ is the script's folder

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))
sys.path.insert(0, str(ROOT / "examples" / "system"))


def count(script: str, runs: int) -> collections.Counter:
    counts = collections.Counter()
    for _ in range(runs):
        proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True)
        ok = proc.returncode == 0 and proc.stdout.strip().endswith("done")
        last = (proc.stderr.strip().splitlines() or [""])[-1][:60]
        corrupted = "corrupted" in proc.stderr or "free()" in proc.stderr
        counts["clean" if ok and not corrupted else f"exit {proc.returncode}"
               + (f" ({last})" if last else "")] += 1
    return counts


def valgrind(script: str) -> None:
    with tempfile.TemporaryDirectory() as tmp:
        log = Path(tmp) / "vg.txt"
        env = dict(os.environ, PYTHONMALLOC="malloc", CHAINMODEL_NUMBA="0")
        proc = subprocess.run(["valgrind", "--num-callers=30", f"--log-file={log}",
                               sys.executable, "-c", script], env=env, capture_output=True,
                              text=True)
        lines = log.read_text().splitlines()
    reports = invalid_reports(lines)
    # the dynamic loader's own strncmp reads (is_dst) are valgrind false positives: counted only
    loader = [r for r in reports if any("dl-load.c" in ln for ln in r[1:4])]
    print(f"valgrind: {len(reports)} invalid accesses ({len(loader)} in the dynamic loader's "
          f"string functions, not shown), process exit {proc.returncode}")
    for r in reports:
        if r in loader:
            continue
        libs = sorted(set(re.findall(r"\((?:in|within) [^)]*/([^/)]+\.so)\)", "\n".join(r))))
        print(f"- {r[0]}  [{', '.join(libs)}]")
        print("    " + "\n    ".join(r[1:12]))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", type=Path, help="ChainDrive.fmu")
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--bisect", action="store_true", help="every combination of the FMUs")
    ap.add_argument("--valgrind", action="store_true")
    ap.add_argument("--launch-examples", action="store_true")
    ap.add_argument("--os-exit", action="store_true",
                    help="end each process with os._exit(0) (no exit handlers run)")
    ap.add_argument("--chaindrive-first", action="store_true",
                    help="load order ChainDrive, Motor, Load (default Motor, ChainDrive, Load)")
    args = ap.parse_args(argv)
    from test_system_exit import system_script
    import build as examples
    tmp = tempfile.TemporaryDirectory()
    motor, load = examples.build(Path(tmp.name), args.launch_examples)
    # the system's order (motor, chain drive, load), the order a master adds them in
    fmus = {"Motor": motor, "ChainDrive": args.fmu.resolve(), "Load": load}
    if args.chaindrive_first:
        fmus = {"ChainDrive": fmus.pop("ChainDrive"), **fmus}
    tail = "import os, sys\nsys.stdout.flush()\nos._exit(0)\n" if args.os_exit else ""
    if args.valgrind:
        valgrind(system_script(fmus) + tail)
        return 0
    combos = [tuple(fmus)]
    if args.bisect:
        combos = [c for k in (1, 2, 3) for c in itertools.combinations(fmus, k)]
    print(f"| FMUs in the process | runs | result |\n|---|---|---|")
    for combo in combos:
        counts = count(system_script({k: fmus[k] for k in combo}) + tail, args.runs)
        print(f"| {' + '.join(combo)} | {args.runs} | "
              + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items())) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
