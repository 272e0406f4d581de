#!/usr/bin/env python
"""How often does a process that uses the FMU the way hosts ordinarily do fail to exit cleanly?

    python benchmarks/host_exit.py dist/ChainDrive.fmu --runs 50          # table of exit codes
    python benchmarks/host_exit.py dist/ChainDrive.fmu --valgrind          # one run under valgrind:
                                                                           # errors inside the wrapper

Each run is a fresh Python executing tests/test_fmu_embedding.py's HOST_LIFE script
(fmpy.simulate_fmu twice, then FMU2Slave instances with state get/set/free, one fatal error,
freeInstance(), one instance left alive, normal exit). docs/fmu.md ("Hosts") has the figures.
"""

from __future__ import annotations

import argparse
import collections
import os
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))



def invalid_reports(lines: list[str]) -> list[list[str]]:
    """valgrind's error reports in its log ``lines``: each "Invalid ..." line with its stack
    ("at"/"by" lines) up to a blank line, the "==pid==" prefixes stripped."""
    reports, current = [], None
    for line in lines:
        body = re.sub(r"^==\d+== ?", "", line)
        if body.startswith("Invalid"):
            current = [body]
            reports.append(current)
        elif current is not None and body.strip():
            current.append(body)
        else:
            current = None
    return reports

def script(fmu: Path) -> str:
    from test_fmu_embedding import HOST_LIFE
    return f"FMU = {str(fmu)!r}\n" + HOST_LIFE


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", type=Path)
    ap.add_argument("--runs", type=int, default=50)
    ap.add_argument("--valgrind", action="store_true")
    args = ap.parse_args(argv)
    code = script(args.fmu.resolve())
    if args.valgrind:
        with tempfile.TemporaryDirectory() as tmp:
            log = Path(tmp) / "vg.txt"
            env = dict(os.environ, PYTHONMALLOC="malloc", CHAINMODEL_NUMBA="0")
            proc = subprocess.run(["valgrind", f"--log-file={log}", sys.executable, "-c", code],
                                  env=env, capture_output=True, text=True)
            lines = log.read_text().splitlines()
        reports = invalid_reports(lines)
        wrapper = [r for r in reports   # the launcher, or pythonfmu's binary behind it
                   if any(name in ln for ln in r[:4]
                          for name in ("ChainDrive.so", "ChainDrive.pythonfmu.so", "finalizePython"))]
        print(f"valgrind ({len(reports)} reports, process exit {proc.returncode}): "
              f"{len(wrapper)} invalid access(es) inside pythonfmu's wrapper")
        for r in wrapper[:3]:
            print("\n".join(r[:12]))
        return 0
    counts = collections.Counter()
    for k in range(args.runs):
        proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
        counts[proc.returncode] += 1
        if proc.returncode:
            print(f"run {k + 1}: exit {proc.returncode}: {proc.stderr.strip().splitlines()[-1:]}")
    print(f"{args.runs} runs of {args.fmu}: " + ", ".join(f"exit {c}: {n}"
                                                         for c, n in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
