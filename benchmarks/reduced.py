"""Cost and accuracy of the reduced-order levels 1 (torsional) and 2 (modal, one mode per span).

For the xu2010 and C1 scenes (fidelity 1 and 2), RK4 runs the scene from rest (speed ramp, then
steady running) at a 10 ms and a 1 ms communication step, side by side. Columns per interval:

* "x real time": simulated seconds per wall second of the whole ``simulate()`` call (model
  set-up, initial state, stepping, outputs at every communication point; best of --repeat
  runs, after a warm-up run of the same scene, so numba compilation and per-drive caches are
  not counted - a first call in a fresh process pays those once);
* "stepper": the same counting only the time inside the stepper (``Result.stats["wall_time"]``);
* errors against the reference, over the second half of the run: the largest driven-angle
  difference and the RMS tight-span tension difference. Reference: RK4 at 1/8 of
  min(automatic step, 1 ms), outputs every 1 ms (the 10 ms runs are compared at their own
  points, every tenth); its own error is estimated against 1/16 and printed first.

Rows: RK4 at the automatic step and at a quarter of min(automatic step, interval), both compiled
when numba is present; with --per-point also the automatic step through the per-communication-
point path (one Python round trip per point, as the FMU steps); with --all (1 ms only) the
plain-Python RK4 and Verlet and the adaptive steppers.

A last table splits the automatic-step runs' wall time into stepping and the rest.

``--targets``: only the table of issue 8's targets - the whole ``simulate()`` call over 1 s at
the scenes' default output interval (1e-4 s), levels 1 and 2, best of --repeat (level 1 >= 100x
real time, level 2 >= 50x: issue 20 item 7; issue 8 asked 20x), with the stepping / rest split
and the evaluations per point.

    python benchmarks/reduced.py [--duration 0.5] [--repeat 3] [--per-point] [--all]
    python benchmarks/reduced.py --targets [--repeat 5] [--set NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import inspect
import os
import time

import numpy as np

import chainmodel
from chainmodel import integrate, simulation
from chainmodel import _numba

INTERVALS = (1e-2, 1e-3)
BATCHED = "batched" in inspect.signature(simulation.run_scene).parameters


def run(scene, method, step=0.0, rtol=1e-6, compiled=True, batched=True, repeat=1):
    """(result, best wall time of the whole call, best stepper time)."""
    sc = scene.with_overrides(solver_method=method, solver_step=step, solver_rtol=rtol)
    kw = {"batched": batched} if BATCHED else {}
    # compiled=False: rk4_loop's loop as plain Python on Model.rhs (integrate.python_loop_model)
    model = None if compiled else integrate.python_loop_model(sc.model())
    warm = sc.with_overrides(duration=2 * sc.output_interval)
    simulation.run_scene(warm, model=None if compiled else integrate.python_loop_model(warm.model()),
                         **kw)  # warm-up
    best, best_stepper, r = np.inf, np.inf, None
    for _ in range(repeat):
        t = time.perf_counter()
        r = simulation.run_scene(sc, model=model, **kw)
        best = min(best, time.perf_counter() - t)
        best_stepper = min(best_stepper, r.stats["wall_time"])
    return r, best, best_stepper


def errors(r, ref, duration):
    """(max |d phi2|, rms dT) over the second half, at r's communication points."""
    idx = np.searchsorted(ref.time, r.time - 1e-12)
    assert np.allclose(ref.time[idx], r.time, rtol=0, atol=1e-9)
    mask = r.time >= 0.5 * duration
    d_phi = float(np.max(np.abs(r["driven.angle"][mask] - ref["driven.angle"][idx][mask])))
    d_t = float(np.sqrt(np.mean((r["tight_span.tension"][mask]
                                 - ref["tight_span.tension"][idx][mask]) ** 2)))
    return d_phi, d_t


def targets(scenes, repeat, settings=None):
    """Whole 1 s simulate() calls at the default output interval (issue 8's targets), wall and
    CPU time (the machine is shared: CPU time is what a dedicated core gives; above the wall
    time where another thread spins, e.g. a BLAS pool after a set-up call). ``settings``:
    overrides for every scene (``--set``), e.g. the seat ladder beside the default."""
    print(f"numba: {_numba.enabled()}; best of {repeat}; load average "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}\n")
    print("| scene | level | x real time, wall | x real time, CPU | target | stepping [ms] | "
          "rest [ms] | internal steps | evaluations per point |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name in scenes:
        for level, goal in ((1, 100), (2, 50)):
            sc = chainmodel.Scene.from_preset(name, fidelity=level, duration=1.0)
            sc = sc.with_overrides(**(settings or {}))
            simulation.run_scene(sc.with_overrides(duration=0.01))          # warm-up
            wall = cpu = stepping = np.inf
            for _ in range(repeat):
                w, c = time.perf_counter(), time.process_time()
                r = simulation.run_scene(sc)
                wall = min(wall, time.perf_counter() - w)
                cpu = min(cpu, time.process_time() - c)
                stepping = min(stepping, r.stats["wall_time"])
            points = len(r.time) - 1
            print(f"| {name} | {level} | {1 / wall:.0f} | {1 / cpu:.0f} | {goal} | "
                  f"{stepping * 1e3:.1f} | {(wall - stepping) * 1e3:.1f} | {r.stats['steps']} | "
                  f"{r.stats['rhs_evaluations'] / points:.2f} |", flush=True)


def fmt(x):
    return f"{x:.2g}" if abs(x) < 10 else f"{x:.0f}" if abs(x) >= 100 else f"{x:.1f}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=0.5)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--per-point", action="store_true",
                    help="also time the per-communication-point path")
    ap.add_argument("--all", action="store_true",
                    help="also plain-Python RK4/Verlet and adaptive steppers (1 ms only)")
    ap.add_argument("--scenes", nargs="*", default=["xu2010", "C1"])
    ap.add_argument("--targets", action="store_true",
                    help="only the whole 1 s call at the default output interval")
    ap.add_argument("--set", action="append", default=[], metavar="NAME=VALUE",
                    help="with --targets: a scene setting for every run, as chainmodel run's "
                         "--set (e.g. torsional.wrap_statics=false)")
    args = ap.parse_args(argv)
    if args.targets:
        from chainmodel.cli_support import parse_settings
        return targets(args.scenes, args.repeat, parse_settings(args.set))
    dur = args.duration
    print(f"numba: {_numba.enabled()}; duration {dur} s; best of {args.repeat}; batched path: "
          f"{BATCHED}; load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}")
    head = ("| scene | level | stepper | " + " | ".join(
        f"{iv * 1e3:g} ms: x real time | stepper | max dphi2 [rad] | rms dT [N]"
        for iv in INTERVALS) + " |")
    rows = [head, "|" + "---|" * (3 + 4 * len(INTERVALS))]
    ref_rows = []
    split_rows = []
    for name in args.scenes:
        for level in (1, 2):
            base = chainmodel.Scene.from_preset(name, fidelity=level, duration=dur,
                                                output_interval=min(INTERVALS))
            model = base.model()
            h_auto = base.stepper(model).h       # the automatic step's bound at the start
            h_ref = min(h_auto, min(INTERVALS)) / 8
            ref, _, _ = run(base, "rk4", step=h_ref)
            ref2, _, _ = run(base, "rk4", step=h_ref / 2)
            ref_rows.append(f"| {name} | {level} | {h_auto:.3g} | {h_ref:.3g} | "
                            + " | ".join(fmt(v) for v in errors(ref, ref2, dur)) + " |")
            cases, split = {}, {}
            for iv in INTERVALS:
                scene = base.with_overrides(output_interval=iv)
                todo = [("rk4 auto (compiled)", "rk4", 0.0, True, True),
                        ("rk4 h/4 (compiled)", "rk4", min(h_auto, iv) / 4, True, True)]
                if args.per_point and BATCHED:
                    todo.append(("rk4 auto (compiled, per point)", "rk4", 0.0, True, False))
                if args.all and iv == min(INTERVALS):
                    todo += [("rk4 (python)", "rk4", 0.0, False, True)]
                    if model.second_order:
                        todo.append(("verlet (python)", "verlet", 0.0, False, True))
                    todo += [("rk45 rtol 1e-6", "rk45", 0.0, True, True),
                             ("dop853 rtol 1e-8", "dop853", 0.0, True, True)]
                for label, method, step, compiled, batched in todo:
                    if compiled and method == "rk4" and not _numba.enabled():
                        label = label.replace("compiled", "numpy")
                    try:
                        r, wall, stepper = run(scene, method, step,
                                               rtol=1e-8 if method == "dop853" else 1e-6,
                                               compiled=compiled, batched=batched,
                                               repeat=args.repeat)
                    except Exception as exc:  # report, keep going
                        cases.setdefault(label, {})[iv] = f"failed: {exc}"
                        continue
                    d_phi, d_t = errors(r, ref, dur)
                    if label.startswith("rk4 auto"):
                        split.setdefault(label, {})[iv] = (
                            f"{wall * 1e3:.1f} | {stepper * 1e3:.1f} | {(wall - stepper) * 1e3:.1f}")
                    cases.setdefault(label, {})[iv] = (
                        f"{dur / wall:.1f} | {dur / stepper:.1f} | {d_phi:.2g} | {fmt(d_t)}")
                    print(f"  {name} {level} {iv:g} {label}: whole {dur / wall:.1f}x, stepper "
                          f"{dur / stepper:.1f}x, {d_phi:.2g} rad, {d_t:.3g} N, "
                          f"{r.stats['events']} events, {r.stats['rhs_evaluations']} rhs",
                          flush=True)
            for label, by_iv in cases.items():
                cells = [by_iv.get(iv, "- | - | - | -") for iv in INTERVALS]
                rows.append(f"| {name} | {level} | {label} | " + " | ".join(cells) + " |")
            for label, by_iv in split.items():
                cells = [by_iv.get(iv, "- | - | -") for iv in INTERVALS]
                split_rows.append(f"| {name} | {level} | {label} | " + " | ".join(cells) + " |")
    print()
    print("Reference (RK4 at h_ref) against RK4 at h_ref/2, same measures:\n")
    print("| scene | level | automatic step [s] | h_ref [s] | max dphi2 [rad] | rms dT [N] |")
    print("|---|---|---|---|---|---|")
    print("\n".join(ref_rows))
    print()
    print("\n".join(rows))
    print()
    print(f"Where the whole call's time goes ({dur} s simulated; ms; rest = set-up, initial "
          "state, input sampling and outputs):\n")
    print("| scene | level | stepper | " + " | ".join(
        f"{iv * 1e3:g} ms: whole | stepping | rest" for iv in INTERVALS) + " |")
    print("|" + "---|" * (3 + 3 * len(INTERVALS)))
    print("\n".join(split_rows))


if __name__ == "__main__":
    main()
