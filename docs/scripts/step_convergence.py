"""The automatic step against a converged run, levels 1-2 (docs/numerics.md, "Steps spanning
output points" and "Level 2 at the bound").

Two tables, 1 s runs, differences over the second half:

* ``spanning``: level 1 at the default 0.1 ms outputs, its steps spanning output points (the
  default) against one step per point (``solver_step`` = the output interval): evaluations
  per point and the RMS difference of the driven speed and
  the span tensions as a share of their standard deviation;
* ``bound``: outputs every 1 ms (an FMU's communication step), levels 1 and 2 at the
  automatic step and at fixed steps, against ``solver_step = 5e-5``: the tight span's RMS
  difference;
* ``sensitivity``: C1 at 400 rpm at that fine step, the driven inertia changed by 0.01-1 %:
  how far a tiny change of the problem moves the run (level 2's response there is not a
  well-conditioned time series).

    python docs/scripts/step_convergence.py            # all three (about 40 s)
    python docs/scripts/step_convergence.py bound      # one
"""

from __future__ import annotations

import sys
import time

import numpy as np

import chainmodel
from chainmodel import simulation

SPANNING = (("C1", 400.0), ("C1", 100.0), ("C1", 60.0), ("xu2010", 120.0))
BOUND = (("C1", 400.0), ("C1", 100.0), ("xu2010", 120.0))
OUTPUTS = ("driven.speed", "tight_span.tension", "slack_span.tension")


def _scene(name, level, rpm, interval):
    return chainmodel.Scene.from_preset(name, fidelity=level, duration=1.0,
                                        input_speed_rpm=rpm, output_interval=interval)


def _rms(a, b, key):
    m = a.time >= 0.5
    d = a[key][m] - b[key][m]
    return float(np.sqrt(np.mean(d * d))), float(np.std(b[key][m]))


def spanning():
    print("level 1, outputs every 0.1 ms: steps spanning points against one step per point")
    print(f"{'scene':>12s} {'evaluations / point':>22s}  RMS difference / standard deviation")
    for name, rpm in SPANNING:
        sc = _scene(name, 1, rpm, 1e-4)
        r = simulation.run_scene(sc)
        one = simulation.run_scene(sc.with_overrides(solver_step=1e-4))
        n = len(r.time) - 1
        cells = []
        for key in OUTPUTS:
            d, sd = _rms(r, one, key)
            cells.append(f"{key.split('.')[0]} {100 * d / sd:.2g} %")
        print(f"{name:>6s} {rpm:4.0f} {r.stats['rhs_evaluations'] / n:8.2f} against "
              f"{one.stats['rhs_evaluations'] / n:5.2f}   " + ", ".join(cells), flush=True)


def bound():
    print("\noutputs every 1 ms: tight-span RMS difference against solver_step = 5e-5 [N]")
    steps = (1e-3, 5e-4, 2.5e-4, 1e-4)
    print(f"{'scene':>12s} {'level':>5s} {'std [N]':>8s} {'automatic':>10s} "
          + " ".join(f"{h * 1e3:>7g} ms" for h in steps))
    for name, rpm in BOUND:
        for level in (1, 2):
            sc = _scene(name, level, rpm, 1e-3)
            ref = simulation.run_scene(sc.with_overrides(solver_step=5e-5))
            auto = simulation.run_scene(sc)
            d, sd = _rms(auto, ref, "tight_span.tension")
            cells = []
            for h in steps:
                try:
                    cells.append(f"{_rms(simulation.run_scene(sc.with_overrides(solver_step=h)), ref, 'tight_span.tension')[0]:10.3g}")
                except (ValueError, chainmodel.models.base.SimulationDiverged):
                    cells.append(f"{'unstable':>10s}")
            print(f"{name:>6s} {rpm:4.0f} {level:5d} {sd:8.3g} {d:10.3g} " + " ".join(cells),
                  flush=True)


def sensitivity():
    print("\nC1 at 400 rpm, outputs every 1 ms, solver_step = 5e-5: the driven inertia changed by "
          "a small fraction against the nominal run (tight span)")
    for level in (1, 2):
        base = _scene("C1", level, 400.0, 1e-3).with_overrides(solver_step=5e-5)
        inertia = base.parameters["driven.inertia"]
        ref = simulation.run_scene(base)
        m = ref.time >= 0.5
        cells = []
        for f in (1e-4, 1e-3, 1e-2):
            r = simulation.run_scene(base.with_overrides(driven_inertia=inertia * (1 + f)))
            d, sd = _rms(r, ref, "tight_span.tension")
            mean = float(np.mean(r["tight_span.tension"][m]) / np.mean(ref["tight_span.tension"][m]))
            cells.append(f"x(1 + {f:g}): RMS {d:6.3g} N, mean {100 * (mean - 1):+.2f} %")
        print(f"  level {level} (std {sd:.3g} N): " + "; ".join(cells), flush=True)


TABLES = {"spanning": spanning, "bound": bound, "sensitivity": sensitivity}

if __name__ == "__main__":
    start = time.perf_counter()
    for what in sys.argv[1:] or list(TABLES):
        if what not in TABLES:
            sys.exit(f"unknown table {what!r}; choose from {', '.join(TABLES)}")
        TABLES[what]()
    print(f"wall {time.perf_counter() - start:.0f} s")
