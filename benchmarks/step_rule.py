"""Convergence study behind the fixed-step rule (docs/numerics.md): output error against
solver.tolerance, and the agreement across communication steps at the default tolerance.

    python benchmarks/step_rule.py [--duration 0.3]

Runs are driven as the FMU drives them (Stepper.advance_held, inputs held first-order) with a
constant input speed from t = 0 (the drive starts from its static equilibrium; the input shaft
jumps to speed, which rings every mode) and the scene's load. Outputs are compared every 10 ms
from 0.1 s on: max |tight-span tension error| / its peak and max |driven-speed error| / its
ripple amplitude (half its peak-to-peak).

Table 1: error against a reference (tolerance 1e-9 at levels 1-2, a quarter of the automatic
step at level 3, communication step 10 ms) for tolerances 1e-2 .. 1e-5, with the internal steps
per simulated second and the h * omega of the rule. Table 2: the default tolerance at
communication steps of 1e-5, 1e-4, 1e-3 and 1e-2 s against the 1e-5 s run (what
tests/test_step_independence.py asserts).
"""

from __future__ import annotations

import argparse
import os
import time

import numpy as np

import chainmodel
from chainmodel.integrate import OUTPUT_NAMES, accuracy_step

T_TIGHT = OUTPUT_NAMES.index("tight_span.tension")
W_DRIVEN = OUTPUT_NAMES.index("driven.speed")

CASES = [("xu2010", 1, 13.0, {}), ("xu2010", 2, 13.0, {}), ("C1", 1, 41.9, {}),
         ("xu2010", 3, 13.0, {"chain_joint_damping": 0.02})]


def held_run(scene, h, speed, duration):
    st = scene.stepper()
    load = scene.operating.load_torque
    every = max(1, round(1e-2 / h))
    rows = []
    wall = time.perf_counter()
    for k in range(round(duration / h)):
        row = st.advance_held((k + 1) * h, speed * k * h, speed, 0.0, load)
        if (k + 1) % every == 0:
            rows.append(((k + 1) * h, row[T_TIGHT], row[W_DRIVEN]))
    return np.array(rows), st.stats["steps"] / duration, time.perf_counter() - wall


def errors(run, ref):
    win = ref[:, 0] >= 0.1 - 1e-9
    peak = np.max(np.abs(ref[win, 1]))
    ripple = 0.5 * (np.max(ref[win, 2]) - np.min(ref[win, 2]))
    return (np.max(np.abs(run[win, 1] - ref[win, 1])) / peak,
            np.max(np.abs(run[win, 2] - ref[win, 2])) / ripple)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.3)
    args = ap.parse_args(argv)
    print(f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    print("\n| scene | level | tolerance | h omega (rk4) | steps / s | tension err / peak | "
          "speed err / ripple |")
    print("|---|---|---|---|---|---|---|")
    for name, level, speed, over in CASES:
        scene = chainmodel.Scene.from_preset(name, fidelity=level, **over)
        if level == 3:
            h = scene.stepper().h
            ref, _, _ = held_run(scene.with_overrides(solver_step=h / 4), 1e-2, speed,
                                 args.duration)
            for label, step in (("auto", 0.0), ("h/2", h / 2)):
                run, rate, _ = held_run(scene.with_overrides(solver_step=step), 1e-2, speed,
                                        args.duration)
                e_t, e_w = errors(run, ref)
                print(f"| {name} | 3 | - (step {label}) | - | {rate:.0f} | {e_t:.1e} | "
                      f"{e_w:.1e} |", flush=True)
            continue
        ref, _, _ = held_run(scene.with_overrides(solver_tolerance=1e-9), 1e-2, speed,
                             args.duration)
        for tol in (1e-2, 3e-3, 1e-3, 5e-4, 1e-4, 1e-5):
            run, rate, _ = held_run(scene.with_overrides(solver_tolerance=tol), 1e-2, speed,
                                    args.duration)
            e_t, e_w = errors(run, ref)
            print(f"| {name} | {level} | {tol:g} | {accuracy_step('rk4', tol):.3f} | {rate:.0f} "
                  f"| {e_t:.1e} | {e_w:.1e} |", flush=True)
    print("\n| scene | level | communication step [s] | tension err / peak | speed err / ripple "
          "| wall [s] |")
    print("|---|---|---|---|---|---|")
    for name, level, speed, over in CASES:
        scene = chainmodel.Scene.from_preset(name, fidelity=level, **over)
        runs = {h: held_run(scene, h, speed, args.duration) for h in (1e-5, 1e-4, 1e-3, 1e-2)}
        ref = runs[1e-5][0]
        for h, (run, _, wall) in runs.items():
            e_t, e_w = errors(run, ref)
            print(f"| {name} | {level} | {h:g} | {e_t:.1e} | {e_w:.1e} | {wall:.2f} |",
                  flush=True)


if __name__ == "__main__":
    main()
