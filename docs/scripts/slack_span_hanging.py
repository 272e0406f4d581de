"""A slack span hanging on its weight (docs/reduced_models.md, "A slack span hanging on its
weight"; chainmodel.validity's ``slack_span_hanging`` warning): levels 0-2 against level 3 on
the slack span of `new-scene` drives with no pretension at 5 rpm, over the inclination of the
line of centres and the load. Means over 1.5-3 s of a 3 s run.

Columns: level 3's mean tight / slack span, w L / T_s (the slack span's weight over level 3's
mean slack tension), T_s / T_0 (over the static tension), and each level's slack-span error
with its validity codes.

    python docs/scripts/slack_span_hanging.py                    # 16B 21/21 at 0 / 30 / 100 N m
    python docs/scripts/slack_span_hanging.py 08B 19 38 0,20     # another drive and loads
"""

from __future__ import annotations

import math
import sys
import tempfile
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.models.chain_inertia import mean_span_length
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene


def main(argv=None):
    args = sys.argv[1:] if argv is None else argv
    chain, z1, z2 = (args[0], int(args[1]), int(args[2])) if len(args) >= 3 else ("16B", 21, 21)
    loads = [float(x) for x in args[3].split(",")] if len(args) > 3 else [0.0, 30.0, 100.0]
    path = Path(tempfile.mkdtemp()) / "drive.toml"
    path.write_text(scene_text(z1, z2, 5.0, 0.0, chain=chain, static_tension=0.0))
    sc = load_scene(str(path))
    weight = (sc.parameters["chain.link_mass"] / sc.parameters["drive.pitch"] * 9.81
              * mean_span_length(sc.drive))
    print(f"{chain} {z1}/{z2}, no pretension, 5 rpm; slack span's weight w L = {weight:.3g} N")
    print("| load [N m] | inclination | level 3 [N] | w L / T_s | T_s / T_0 | level 0 | level 1 "
          "| level 2 |")
    print("|---|---|---|---|---|---|---|---|")
    for load in loads:
        for deg in (0, 30, 45, 60, 70, 80, 88):
            row = {}
            for level in (0, 1, 2, 3):
                r = chainmodel.simulate(str(path), fidelity=level, duration=3.0,
                                        load_torque=load, drive_inclination=math.radians(deg))
                m = r.time >= 1.5
                row[level] = (float(np.mean(r["tight_span.tension"][m])),
                              float(np.mean(r["slack_span.tension"][m])),
                              sorted({q.code for q in r.problems}), r.static_tension)
            t3, s3, _, static = row[3]
            cells = [f"{100 * (row[lv][1] / s3 - 1):+.1f} % {', '.join(row[lv][2]) or '-'}"
                     for lv in (0, 1, 2)]
            print(f"| {load:g} | {deg} deg | {t3:.1f} / {s3:.1f} | {weight / s3:.2f} | "
                  f"{s3 / static:.2f} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
