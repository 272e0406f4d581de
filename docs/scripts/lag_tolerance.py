"""C1 at 400 rpm at level 1 over 1.2 s, with and without the lagged sag, at three tolerances:
best-of-3 wall time, steps, located events, evaluations and the slack span's mean over
0.5-1.2 s (docs/reduced_models.md, "A step that outran the sag").

    python docs/scripts/lag_tolerance.py
"""

import time

import numpy as np

import chainmodel


def main():
    print("lag   tolerance  wall [ms]  steps  events  evaluations  slack mean [N]")
    for lag in (True, False):
        for tol in (5e-3, 2e-3, 5e-4):
            kw = dict(fidelity=1, duration=1.2, input_speed_rpm=400.0, solver_tolerance=tol,
                      torsional_sag_lag=lag)
            chainmodel.simulate("C1", **kw)          # compiled kernels warm
            best = np.inf
            for _ in range(3):
                t0 = time.perf_counter()
                r = chainmodel.simulate("C1", **kw)
                best = min(best, time.perf_counter() - t0)
            st = r.stats
            slack = np.mean(r["slack_span.tension"][r.time >= 0.5])
            print(f"{str(lag):5s} {tol:9.0e}  {best * 1e3:9.1f}  {st['steps']:5d}  "
                  f"{st['events']:6d}  {st['rhs_evaluations']:11d}  {slack:14.1f}")


if __name__ == "__main__":
    main()
