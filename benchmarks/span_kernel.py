"""Cost of one level 1-2 kernel evaluation (chainmodel.kernels.spans.evaluate) on states of a
real run: C1 and xu2010, levels 1 and 2, 0.3 s of each scene from rest sampled every tenth
output point (300 states with their inputs), each evaluated 20 times in a compiled loop; best of
--repeat. The whole-call figures are benchmarks/reduced.py --targets'; this isolates the
right-hand side from the stepping loop (docs/performance.md, issue 20 third pass).

    python benchmarks/span_kernel.py [--repeat 5] [--scenes C1 xu2010]
"""

from __future__ import annotations

import argparse
import os
import time

import numba
import numpy as np

import chainmodel
from chainmodel.kernels import spans as S


@numba.njit
def _loop(X, th, w, a, ld, G, P, reps):
    dx = np.empty(X.shape[1])
    aux = np.empty(S.A_SIZE)
    acc = 0.0
    for _ in range(reps):
        for i in range(X.shape[0]):
            S.evaluate(X[i], th[i], w[i], a[i], ld[i], G, P, dx, aux)
            acc += dx[0] + aux[0]
    return acc


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--scenes", nargs="*", default=["C1", "xu2010"])
    args = ap.parse_args()
    print(f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}\n")
    print("| scene | level | states | ns per evaluate |")
    print("|---|---|---|---|")
    for name in args.scenes:
        for level in (1, 2):
            sc = chainmodel.Scene.from_preset(name, fidelity=level, duration=0.3)
            model = sc.model()
            stepper = sc.stepper(model)
            times = sc.times()
            inputs = sc.input_arrays(times)
            X = []
            for t in times[1::10]:
                stepper.advance(float(t), sc.inputs)
                X.append(np.array(stepper.x, float))
            X = np.array(X)
            idx = np.arange(len(X)) * 10 + 1
            th, w, a, ld = (np.ascontiguousarray(v[idx]) for v in inputs)
            _loop(X[:2], th[:2], w[:2], a[:2], ld[:2], model.G, model.P, 1)     # compile
            best = np.inf
            for _ in range(args.repeat):
                t0 = time.perf_counter()
                _loop(X, th, w, a, ld, model.G, model.P, 20)
                best = min(best, (time.perf_counter() - t0) / (20 * len(X)))
            print(f"| {name} | {level} | {len(X)} | {best * 1e9:.0f} |", flush=True)


if __name__ == "__main__":
    main()
