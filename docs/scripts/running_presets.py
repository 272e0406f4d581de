"""Levels 1-2's running spans against level 3 beyond the trade study's scenes
(docs/reduced_models.md, "Running spans on seed 004's presets").

Two tables, means over the second half of each run (0.6 s on xu2010, 1.2 s on the 25.4 mm
presets), at each scene's own load:

* ``table``: xu2010 at 15-600 rpm and seed 004's presets C1, C2, C3, B1 and D1 at 30-400 rpm,
  levels 1 and 2 against level 3 (tight / slack), with the meshing frequency f_m, the slack
  span's first string mode f_1 at level 3's running tension (seed 004 eq 61, the moving
  string's, ``chainmodel.analysis.summary.span_modes``) and the nearest match of k f_m with
  n f_1 (k = 1, 2; n = 1-3; either span) as its detuning;
* ``c1``: C1 over 70-130 rpm in 5 rpm steps, each level's mean tight span and driven-speed
  RMS ripple: where each level puts the resonance that C1 at 100 rpm sits on the flank of
  (and level 1 without its lagged sag, ``torsional.sag_lag = false``, as "1 no lag").
  ``c1 FIGURE.png`` also draws it.

    python docs/scripts/running_presets.py table      # about 6 min with cold level-3 runs
    python docs/scripts/running_presets.py c1 docs/figures/c1_resonance_ladder.png

A run a level refuses prints its reason in the cell. It reads only the public API.
"""

from __future__ import annotations

import math
import sys
import time
import warnings

import numpy as np

import chainmodel
from chainmodel.analysis.summary import span_modes
from chainmodel.scene import load_scene

CASES = ([("xu2010", rpm) for rpm in (15, 30, 45, 60, 75, 90, 120, 200, 300, 600)]
         + [("C1", rpm) for rpm in (30, 45, 60, 80, 100, 120, 150, 200, 400)]
         + [("C2", rpm) for rpm in (60, 100, 200, 400)]
         + [("C3", rpm) for rpm in (60, 150)]
         + [("B1", rpm) for rpm in (100, 300)]
         + [("D1", rpm) for rpm in (100, 300)])
C1_SPEEDS = tuple(range(70, 135, 5))


def duration(name: str) -> float:
    return 0.6 if name == "xu2010" else 1.2


def running(name: str, rpm: float, level: int, parameters=None):
    """(mean tight, mean slack, driven-speed RMS ripple) over the run's second half, or the
    reason the level refused it."""
    dur = duration(name)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, duration=dur,
                                    output_interval=2e-4, parameters=parameters)
    except Exception as e:              # a refusal is a result of this table
        return f"refused: {str(e)[:60]}"
    m = r.time >= 0.5 * dur
    return (float(r["tight_span.tension"][m].mean()), float(r["slack_span.tension"][m].mean()),
            float(r["driven.speed"][m].std()))


def table():
    print("| scene | rpm | f_m [Hz] | slack f_1 at level 3 [Hz] | nearest match (detuning) | "
          "level 3 tight / slack [N] | level 1 | level 2 |\n|---|---|---|---|---|---|---|---|")
    for name, rpm in CASES:
        sc = load_scene(name)
        row = {level: running(name, rpm, level) for level in (3, 1, 2)}
        if isinstance(row[3], str):
            print(f"| {name} | {rpm} | | | | {row[3]} | | |", flush=True)
            continue
        t3, s3, _ = row[3]
        w = rpm * 2 * math.pi / 60
        modes = span_modes(sc.drive, sc.parameters, w, t3, s3)
        detuning = modes["span_resonance_detuning"]
        match = (f"{modes['span_resonance']} ({100 * detuning:+.1f} %)"
                 if not math.isnan(detuning) else "none of modes 1-3")
        cells = [row[k] if isinstance(row[k], str) else
                 f"{100 * (row[k][0] / t3 - 1):+.1f} / {100 * (row[k][1] / s3 - 1):+.1f} %"
                 for k in (1, 2)]
        print(f"| {name} | {rpm} | {w * sc.drive.n_driver / (2 * math.pi):.1f} | "
              f"{modes['slack_span_mode_hz']:.1f} | {match} | {t3:.1f} / {s3:.1f} | {cells[0]} | "
              f"{cells[1]} |", flush=True)


def c1(figure: str | None = None):
    print("C1 at its load, 1.2 s runs: mean tight span [N] and driven-speed RMS ripple [rad/s]")
    runs = {1: (1, None), "1 no lag": (1, {"torsional.sag_lag": False}), 2: (2, None),
            3: (3, None)}
    print(f"{'rpm':>5s} {'f_m [Hz]':>9s} " + " ".join(f"{f'level {k}':>20s}" for k in runs))
    data = {k: [] for k in runs}
    for rpm in C1_SPEEDS:
        cells = []
        for key, (level, parameters) in runs.items():
            t, _, ripple = running("C1", rpm, level, parameters)
            data[key].append((t, ripple))
            cells.append(f"{t:9.1f} / {ripple:6.3f}")
        print(f"{rpm:5d} {rpm * 12 / 60:9.1f} " + " ".join(f"{c:>20s}" for c in cells), flush=True)
    for level in runs:
        i = int(np.argmax([x[0] for x in data[level]]))
        print(f"level {level}: its tight span peaks at {C1_SPEEDS[i]} rpm "
              f"({data[level][i][0]:.1f} N, meshing {C1_SPEEDS[i] * 12 / 60:.1f} Hz)")
    if figure:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        fig, (a, b) = plt.subplots(2, 1, figsize=(7, 6), sharex=True)
        for level, style in ((3, "k-o"), (2, "C0-s"), (1, "C3-^"), ("1 no lag", "C3:v")):
            a.plot(C1_SPEEDS, [x[0] for x in data[level]], style, label=f"level {level}")
            b.plot(C1_SPEEDS, [x[1] for x in data[level]], style, label=f"level {level}")
        a.set_ylabel("mean tight span [N]")
        b.set_ylabel("driven-speed RMS ripple [rad/s]")
        b.set_xlabel("input speed [rpm] (meshing frequency = rpm / 5 Hz)")
        a.legend()
        a.set_title("C1 (12/18 teeth, 25.4 mm) at its load: the torsional resonance per level")
        for ax in (a, b):
            ax.grid(alpha=0.3)
        fig.tight_layout()
        fig.savefig(figure, dpi=110)
        print(f"wrote {figure}")


if __name__ == "__main__":
    start = time.perf_counter()
    args = sys.argv[1:] or ["table"]
    if args[0] == "table":
        table()
    elif args[0] == "c1":
        c1(args[1] if len(args) > 1 else None)
    else:
        sys.exit(f"unknown table {args[0]!r}; choose table or c1 [FIGURE.png]")
    print(f"wall {time.perf_counter() - start:.0f} s")
