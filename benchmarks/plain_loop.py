"""Cost of the fixed-step loop on the model interface (``integrate.python_loop_model``: the
twin the tests compare), which since issue 20 item 1 runs rk4_loop's own functions as plain
Python (chainmodel.kernels.plain_loop). Prints one row per scene:
best wall time of ``simulate()`` over --repeat runs, the stepper's counts and the final driven
angle (to compare two trees bitwise: run it with each on PYTHONPATH).

    CHAINMODEL_NUMBA=0 python benchmarks/plain_loop.py [--repeat 2]
"""

from __future__ import annotations

import argparse
import os
import time

import chainmodel
from chainmodel import integrate, simulation

CASES = (("xu2010", 1, 0.05), ("C1", 2, 0.05), ("xu2010", 3, 0.005))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=2)
    args = ap.parse_args(argv)
    print(f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}; best of {args.repeat}\n")
    print("| scene | level | duration [s] | wall [s] | steps | events | rhs evaluations | "
          "final driven.angle [rad] |")
    print("|---|---|---|---|---|---|---|---|")
    for name, level, duration in CASES:
        sc = chainmodel.Scene.from_preset(name, fidelity=level, duration=duration,
                                          output_interval=1e-3)
        best, r = float("inf"), None
        for _ in range(args.repeat):
            t = time.perf_counter()
            r = simulation.run_scene(sc, model=integrate.python_loop_model(sc.model()))
            best = min(best, time.perf_counter() - t)
        print(f"| {name} | {level} | {duration:g} | {best:.3f} | {r.stats['steps']} | "
              f"{r.stats['events']} | {r.stats['rhs_evaluations']} | "
              f"{float(r['driven.angle'][-1])!r} |", flush=True)


if __name__ == "__main__":
    main()
