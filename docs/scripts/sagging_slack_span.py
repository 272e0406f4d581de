"""Running span tensions where the slack span hangs on its sag (docs/reduced_models.md, "One
static tension, gravity included" and "Level 1's lagged sag"): levels 0-3, means over the
second half of 2 s (level 1's sag settles within about 0.2 s of a change), and levels 0-1 without the spans' sag (torsional.sag_lag = false: the law
before the twentieth session of issue 21).

Drives: two `chainmodel new-scene` drives with no pretension (10A 19/38 at 900 rpm and 25 N m;
08B 13/39 at 300 rpm and 8 N m; tight wrap, 40 pitches), the trade study's long-centre drive
(25/17, 144 links, 500 N, 120 rpm, 20 N m), and three drives of an independent audit (the
twentieth session's): 08A 12/36 and 16B 19/45 with no pretension at the tight wrap, 12A 14/28
at 250 N. Level 1's straight spans hang in their lagged sag (kernels/spans.py ``_lagged``),
level 0's in its quasi-static sag, level 2's string modes sag by themselves, level 3's rollers
hang on their links.

    python docs/scripts/sagging_slack_span.py            # about 40 s with warm kernels
    python docs/scripts/sagging_slack_span.py --ladder   # levels 0-2 on the seat ladder
                                                         # (torsional.wrap_statics = false)
"""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

import chainmodel
from chainmodel.new_scene import scene_text

NEW = [("10A 19/38 900 rpm 25 N m", dict(driver_teeth=19, driven_teeth=38, speed_rpm=900.0,
                                          load_torque=25.0, chain="10A")),
       ("08B 13/39 300 rpm 8 N m", dict(driver_teeth=13, driven_teeth=39, speed_rpm=300.0,
                                        load_torque=8.0, chain="08B"))]
LONG = dict(drive_driver_teeth=25, drive_driven_teeth=17, drive_links=144,
            drive_centre_distance=0.0, static_tension=500.0, load_torque=20.0,
            input_speed_rpm=120.0)
#: the audit's drives: (name, new-scene arguments, static tension [N]; 0: no pretension)
AUDIT = [("08A 12/36 600 rpm 15 N m", dict(driver_teeth=12, driven_teeth=36, speed_rpm=600.0,
                                            load_torque=15.0, chain="08A", links=106), 0.0),
         ("16B 19/45 100 rpm 300 N m", dict(driver_teeth=19, driven_teeth=45, speed_rpm=100.0,
                                             load_torque=300.0, chain="16B", links=114), 0.0),
         ("12A 14/28 250 N 300 rpm 60 N m", dict(driver_teeth=14, driven_teeth=28,
                                                  speed_rpm=300.0, load_torque=60.0,
                                                  chain="12A", links=102), 250.0)]


def means(scene, level, **kw):
    r = chainmodel.simulate(scene, fidelity=level, duration=2.0, output_interval=2e-4, **kw)
    m = r.time >= 1.0
    return r.static_tension, r["tight_span.tension"][m].mean(), r["slack_span.tension"][m].mean()


LADDER = {"torsional_wrap_statics": False} if "--ladder" in sys.argv[1:] else {}


def row(name, scene, **kw):
    ref = means(scene, 3, **kw)
    t3, s3 = ref[1:]
    cells = []
    for level, lag in ((0, False), (1, False), (0, True), (1, True), (2, True)):
        try:
            _, t, s = means(scene, level, **kw, **LADDER, torsional_sag_lag=lag)
        except ValueError as exc:       # a level that refuses the scene
            cells.append(f"L{level}{'' if lag else ' no sag'} refused ({str(exc)[:40]})")
            continue
        cells.append(f"L{level}{'' if lag else ' no sag'} {t:7.1f} / {s:6.1f} N "
                     f"({100 * (t / t3 - 1):+5.1f} / {100 * (s / s3 - 1):+5.1f} %)")
    print(f"{name:32s} T0 {ref[0]:6.1f} N  L3 {t3:7.1f} / {s3:6.1f} N", flush=True)
    for c in cells:
        print(f"{'':34s}{c}", flush=True)


def main():
    print("tight / slack span means, against level 3"
          + ("; levels 0-2 on the seat ladder" if LADDER else ""))
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        for name, kw in NEW:
            path.write_text(scene_text(static_tension=0.0, **kw))
            row(name, path)
        row("long centre N=60 120 rpm", "xu2010", **LONG)
        for name, kw, tension in AUDIT:
            path.write_text(scene_text(static_tension=tension, **kw))
            row(name, path)


if __name__ == "__main__":
    main()
