"""Cost and accuracy of the reduced-order levels 1 (torsional) and 2 (modal, one mode per span).

For the xu2010 and C1 scenes, each suitable stepper runs the scene from rest (speed ramp, then
steady running) with a 1 ms communication step; the table gives wall seconds per simulated
second, the real-time factor, and the error against a reference run of the same level: RK4 with
a step 8 times smaller than the automatic one (both compiled when numba is present). Errors are
the largest driven-angle difference and the RMS tight-span tension difference over the second
half of the run. "x real time" counts the whole simulate() call (model set-up, outputs at every
communication point); "stepper only" the time inside the stepper's advance.

    python benchmarks/reduced.py [--duration 0.5] [--interval 1e-3]
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

import chainmodel
from chainmodel import integrate
from chainmodel.models import spans


def run(scene, method, step=0.0, rtol=1e-6, compiled=True):
    sc = scene.with_overrides(solver_method=method, solver_step=step, solver_rtol=rtol)
    old = integrate.FixedStepper.compiled
    integrate.FixedStepper.compiled = compiled
    try:
        chainmodel.simulate(sc.with_overrides(duration=2 * sc.output_interval))  # warm-up/JIT
        t = time.perf_counter()
        r = chainmodel.simulate(sc)
        wall = time.perf_counter() - t
    finally:
        integrate.FixedStepper.compiled = old
    return r, wall


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.5)
    ap.add_argument("--interval", type=float, default=1e-3)
    args = ap.parse_args(argv)
    print(f"numba: {spans.NUMBA}; duration {args.duration} s, communication step {args.interval} s")
    print(f"{'scene':8s} {'level':9s} {'stepper':22s} {'wall/sim s':>11s} {'x real time':>11s} "
          f"{'stepper only':>12s} {'max |d phi2| rad':>16s} {'rms dT N':>9s} {'events':>7s}")
    for name in ("xu2010", "C1"):
        for level in (1, 2):
            scene = chainmodel.Scene.from_preset(name, fidelity=level, duration=args.duration,
                                                 output_interval=args.interval)
            model = scene.model()
            h_auto = 0.9 * integrate.stability_limit("rk4") * model.stable_step(None)
            ref, _ = run(scene, "rk4", step=min(h_auto, args.interval) / 8)
            mask = ref.time >= 0.5 * args.duration
            cases = [("rk4 (compiled)", "rk4", 0.0, True),
                     ("rk4 h/4 (compiled)", "rk4", min(h_auto, args.interval) / 4, True),
                     ("rk4 (python)", "rk4", 0.0, False)]
            if model.second_order:
                cases.append(("verlet (python)", "verlet", 0.0, False))
            cases += [("rk45 rtol 1e-6", "rk45", 0.0, True), ("dop853 rtol 1e-8", "dop853", 0.0, True)]
            for label, method, step, compiled in cases:
                if compiled and method == "rk4" and not spans.NUMBA:
                    continue
                try:
                    r, wall = run(scene, method, step, rtol=1e-8 if method == "dop853" else 1e-6,
                                  compiled=compiled)
                except Exception as exc:  # report, keep going
                    print(f"{name:8s} {model.name:9s} {label:22s} failed: {exc}")
                    continue
                per = wall / args.duration
                stepper = r.stats["wall_time"] / args.duration
                d_phi = float(np.max(np.abs(r["driven.angle"][mask] - ref["driven.angle"][mask])))
                d_t = float(np.sqrt(np.mean((r["tight_span.tension"][mask]
                                             - ref["tight_span.tension"][mask]) ** 2)))
                print(f"{name:8s} {model.name:9s} {label:22s} {per:11.4f} {1 / per:11.1f} "
                      f"{1 / stepper:12.1f} {d_phi:16.3e} {d_t:9.3g} {r.stats['events']:7d}")


if __name__ == "__main__":
    main()
