"""Sweep scaling from 1 to 2 Dask workers and the per-case overhead (docs/performance.md,
"Sweeps").

    python benchmarks/sweep_scaling.py [STUDY.toml] [--repeats R] [--set NAME=VALUE ...]

Runs the study (default: examples/studies/speed_pretension.toml) serially, on a LocalCluster
of 1 worker and of 2 workers, interleaved, R times each, into fresh directories, and prints a
table of medians: wall seconds of the cases (cluster start and worker warm-up excluded, shown
apart), the sum of the cases' own seconds, the parallel efficiency T(1 worker) / (2 T(2
workers)), and the overhead per case, (workers x wall - sum of case seconds) / cases: what
scheduling, result transfer, events and the journal add to each case.
"""

from __future__ import annotations

import argparse
import os
import statistics
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("study", nargs="?", default=str(ROOT / "examples/studies/speed_pretension.toml"))
    ap.add_argument("--repeats", type=int, default=2)
    ap.add_argument("--set", action="append", default=[], dest="settings")
    ap.add_argument("--chunk-size", type=int, default=None,
                    help="cases per chunk on the workers (default: the sweep's, 8 chunks per worker)")
    args = ap.parse_args()
    from chainmodel.analysis.sweep import sweep
    from chainmodel.cli import _parse_settings
    fixed = _parse_settings(args.settings)
    chunking = {} if args.chunk_size is None else {"chunk_size": args.chunk_size}
    modes = {"serial": dict(serial=True), "1 worker": dict(workers=1, **chunking),
             "2 workers": dict(workers=2, **chunking)}
    runs: dict[str, list] = {m: [] for m in modes}
    print(f"load before: {os.getloadavg()}")
    with tempfile.TemporaryDirectory() as tmp:
        for r in range(args.repeats):
            for name, kw in modes.items():
                t0 = time.perf_counter()
                res = sweep(args.study, Path(tmp) / f"{name}-{r}", plots=False, **kw, **fixed)
                total = time.perf_counter() - t0
                run = res.run
                runs[name].append((run.wall_s, run.case_seconds, run.startup_s, total,
                                   run.computed, run.workers, run.chunks))
                print(f"  {name:9s} repeat {r}: wall {run.wall_s:.2f} s, cases {run.case_seconds:.2f} s, "
                      f"start {run.startup_s:.2f} s, whole call {total:.2f} s, {run.chunks} chunks", flush=True)
    print(f"load after: {os.getloadavg()}")
    med = {m: [statistics.median(x[k] for x in v) for k in range(5)] + [v[0][5], v[0][6]]
           for m, v in runs.items()}
    n = med["serial"][4]
    print(f"\n{n:.0f} cases, medians of {args.repeats}\n")
    print("| mode | wall of the cases [s] | sum of case seconds [s] | cluster start + warm-up [s] "
          "| overhead per case [ms] | overhead / case compute |")
    print("|---|---|---|---|---|---|")
    for m, (wall, cases, start, total, computed, workers, chunks) in med.items():
        over = (workers * wall - cases) / computed
        print(f"| {m} ({chunks} chunks) | {wall:.2f} | {cases:.2f} | {start:.2f} | {1e3 * over:.1f} "
              f"| {100 * over / (cases / computed):.1f} % |")
    eff = med["1 worker"][0] / (2 * med["2 workers"][0])
    print(f"\nparallel efficiency 1 -> 2 workers: T1 / (2 T2) = {med['1 worker'][0]:.2f} / "
          f"(2 x {med['2 workers'][0]:.2f}) = {100 * eff:.0f} %")
    eff_s = med["serial"][0] / (2 * med["2 workers"][0])
    print(f"against the serial run: {100 * eff_s:.0f} %")


if __name__ == "__main__":
    main()
