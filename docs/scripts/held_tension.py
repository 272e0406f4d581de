"""What levels 0-2's spans hold at rest, measured against level 3 (docs/reduced_models.md,
"The held tension is level 3's tooth-period mean").

Three tables, each a tooth-period mean (the driver turning at 1 rpm is quasi-static; means over
two tooth periods after 0.3 s):

* ``rest``: level 3's static tension at the fit's four driver positions (its statics) and the
  spans' tension at rest over a tooth at levels 1 and 3, binned by the driver's tooth phase;
* ``load``: the tight and slack spans under a load whose tension difference is a share of twice
  the static tension, levels 1-3;
* ``running``: the running spans at the scene's load, levels 1-2 against level 3.

    python docs/scripts/held_tension.py            # all three, xu2010 and C1 (about 40 s)
    python docs/scripts/held_tension.py running    # one table
    python docs/scripts/held_tension.py running --zeta 0.0064   # level 2 at that modal damping

It reads only the public API, so it runs on an older checkout too (the "before" figures).
"""

from __future__ import annotations

import sys
import time

import numpy as np

import chainmodel
from chainmodel.models.multibody_statics import static_state
from chainmodel.models.wrap_statics import tooth_positions, wrap_fit
from chainmodel.scene import load_scene

SCENES = ("xu2010", "C1")
SHARES = (0.25, 0.5, 0.75, 0.9, 1.0)
SPEEDS = {"xu2010": ((5, 15, 30, 45, 60, 90, 120), 0.6), "C1": ((5, 30, 60, 100), 1.2)}


def quasi_static(name, level, load, bins=8):
    """(tight, slack, binned mean span tension) over two tooth periods at 1 rpm."""
    d = load_scene(name).drive
    period = 60.0 / d.n_driver
    r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=1.0, duration=0.3 + 2 * period,
                            output_interval=2e-4, load_torque=load)
    m = r.time >= 0.3
    tight, slack = r["tight_span.tension"][m], r["slack_span.tension"][m]
    phase = (r["driver.angle"][m] * d.n_driver / (2 * np.pi)) % 1.0
    k = np.floor(phase * bins).astype(int)
    mean = 0.5 * (tight + slack)
    return float(tight.mean()), float(slack.mean()), [float(mean[k == i].mean()) for i in range(bins)]


def rest_table():
    print("at rest, no load: level 3's statics at the fit's driver positions, and the spans' "
          "mean tension by the driver's tooth phase (eighths) turning at 1 rpm [N]")
    for name in SCENES:
        sc = load_scene(name)
        model3 = sc.with_overrides(fidelity=3).model()
        statics = [static_state(model3, a).mean_tension for a in tooth_positions(sc.drive)]
        fit = wrap_fit(sc.drive, sc.model().params)
        held = getattr(fit, "held_tension", float("nan"))
        print(f"{name}: static tension (driver at 0) {fit.static_tension:.1f} N; level 3 at "
              f"{len(statics)} positions {', '.join(f'{t:.1f}' for t in statics)}, mean "
              f"{np.mean(statics):.1f} N; levels 0-2 hold {held:.1f} N")
        for level in (1, 3):
            _, _, bins = quasi_static(name, level, 0.0)
            print(f"  level {level}: " + " ".join(f"{b:6.1f}" for b in bins)
                  + f"   mean {np.mean(bins):6.1f}", flush=True)


def load_table():
    print("\nquasi-static under load (1 rpm), tight / slack [N]; load share = tension "
          "difference / (2 x static tension)")
    for name in SCENES:
        sc = load_scene(name)
        t0 = sc.model().static_tension()
        ro = sc.drive.driven.pitch_radius
        print(f"{name} (static tension {t0:.1f} N)")
        print(f"{'share':>6s} {'level 3':>16s} {'level 1':>22s} {'level 2':>22s}")
        for share in SHARES:
            load = share * 2.0 * t0 * ro
            t3, s3, _ = quasi_static(name, 3, load)
            cells = []
            for level in (1, 2):
                t, s, _ = quasi_static(name, level, load)
                cells.append(f"{s:6.1f} ({100 * (t / t3 - 1):+4.1f}/{100 * (s / s3 - 1):+5.1f}%)")
            print(f"{share:6.2f} {t3:7.1f} / {s3:6.1f} {cells[0]:>22s} {cells[1]:>22s}", flush=True)


def running_table():
    print("\nrunning at the scene's load, means over the second half; error against level 3, "
          "tight / slack")
    for name in SCENES:
        speeds, duration = SPEEDS[name]
        print(f"{name} ({duration:g} s runs)")
        print(f"{'rpm':>5s} {'level 3 [N]':>16s} {'level 1':>16s} {'level 2':>16s}")
        for rpm in speeds:
            row = {}
            for level in (1, 2, 3):
                extra = ({"modal_damping_ratio": ZETA} if level == 2 and ZETA is not None
                         else {})
                r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm,
                                        duration=duration, output_interval=2e-4, **extra)
                m = r.time >= 0.5 * duration
                row[level] = (r["tight_span.tension"][m].mean(), r["slack_span.tension"][m].mean())
            t3, s3 = row[3]
            cells = [f"{100 * (row[k][0] / t3 - 1):+5.1f} / {100 * (row[k][1] / s3 - 1):+5.1f}%"
                     for k in (1, 2)]
            print(f"{rpm:5g} {t3:7.1f} / {s3:6.1f} {cells[0]:>16s} {cells[1]:>16s}", flush=True)


TABLES = {"rest": rest_table, "load": load_table, "running": running_table}
#: level 2's modal.damping_ratio in the running table (None: its default)
ZETA = None

if __name__ == "__main__":
    start = time.perf_counter()
    args = sys.argv[1:]
    if "--zeta" in args:
        i = args.index("--zeta")
        ZETA = float(args[i + 1])
        del args[i:i + 2]
        print(f"level 2 with modal.damping_ratio = {ZETA:g}")
    for what in args or list(TABLES):
        if what not in TABLES:
            sys.exit(f"unknown table {what!r}; choose from {', '.join(TABLES)}")
        TABLES[what]()
    print(f"wall {time.perf_counter() - start:.0f} s")
