"""Running span tensions where the slack span hangs on its sag (docs/reduced_models.md, "One
static tension, gravity included"): levels 1, 2 and 3, means over the second half of 1 s.

Drives: two `chainmodel new-scene` drives with no pretension (10A 19/38 at 900 rpm and 25 N m;
08B 13/39 at 300 rpm and 8 N m; tight wrap, 40 pitches), and the trade study's long-centre drive
(25/17, 144 links, 500 N, 120 rpm, 20 N m). Level 1's straight spans hang in their quasi-static
sag (spans.py ``_tension``), level 2's string modes sag by themselves, level 3's rollers hang
on their links.

    python docs/scripts/sagging_slack_span.py            # about 10 s with warm kernels
    python docs/scripts/sagging_slack_span.py --ladder   # levels 1-2 on the seat ladder
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


def means(scene, level, **kw):
    r = chainmodel.simulate(scene, fidelity=level, duration=1.0, output_interval=2e-4, **kw)
    m = r.time >= 0.5
    return r.static_tension, r["tight_span.tension"][m].mean(), r["slack_span.tension"][m].mean()


LADDER = {"torsional_wrap_statics": False} if "--ladder" in sys.argv[1:] else {}


def row(name, scene, **kw):
    cells = [means(scene, level, **kw, **(LADDER if level < 3 else {})) for level in (1, 2, 3)]
    t3, s3 = cells[2][1:]
    text = "  ".join(f"L{level} {t:7.1f} / {s:6.1f} N ({100 * (s / s3 - 1):+5.1f} %)"
                     for level, (_, t, s) in zip((1, 2, 3), cells))
    print(f"{name:28s} T0 {cells[0][0]:6.1f} N  {text}", flush=True)


def main():
    print("tight / slack span means, slack against level 3"
          + ("; levels 1-2 on the seat ladder" if LADDER else ""))
    with tempfile.TemporaryDirectory() as tmp:
        for name, kw in NEW:
            path = Path(tmp) / "scene.toml"
            path.write_text(scene_text(static_tension=0.0, **kw))
            row(name, path)
    row("long centre N=60 120 rpm", "xu2010", **LONG)


if __name__ == "__main__":
    main()
