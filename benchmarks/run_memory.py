"""Peak memory of a run per sample, per level: the basis of chainmodel.run_memory.WORKING_ARRAYS.

    python benchmarks/run_memory.py [--samples N]

For each level: a warm-up run (compilation outside the measurement), then ``simulate`` of
seed 003's drive with N samples and its ``summary()`` under tracemalloc (numpy reports its
buffers to it). Prints the peak in bytes and in float64 arrays per sample beyond the outputs.
"""

from __future__ import annotations

import argparse
import gc
import tracemalloc

import chainmodel
from chainmodel.models import ALL_OUTPUTS
from chainmodel.run_memory import WORKING_ARRAYS


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=50_000)
    ap.add_argument("--levels", default="0,1,2,3")
    args = ap.parse_args()
    n_out = len(ALL_OUTPUTS)
    print(f"{'level':>5} {'samples':>8} {'peak [MB]':>10} {'arrays/sample':>14} "
          f"{'outputs':>8} {'working':>8} {'WORKING_ARRAYS':>15}")
    for level in (int(x) for x in args.levels.split(",")):
        # level 3 is slow per simulated second: sample it finely over a shorter run
        interval = 1e-5 if level < 3 else 2e-6
        duration = (args.samples - 1) * interval
        chainmodel.simulate("xu2010", fidelity=level, duration=0.02, output_interval=interval)
        gc.collect()
        tracemalloc.start()
        r = chainmodel.simulate("xu2010", fidelity=level, duration=duration,
                                output_interval=interval, ramp_time=min(0.05, duration / 4))
        r.summary()
        peak = tracemalloc.get_traced_memory()[1]
        tracemalloc.stop()
        samples = len(r.time)
        per = peak / (8 * samples)
        print(f"{level:>5} {samples:>8} {peak / 1e6:>10.1f} {per:>14.1f} {n_out:>8} "
              f"{per - n_out:>8.1f} {WORKING_ARRAYS[level]:>15}")
        del r
        gc.collect()


if __name__ == "__main__":
    main()
