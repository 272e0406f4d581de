"""Spans hanging along their length: a vertical 16B 21/21 drive of 60 links where they wrap
tightly, no pretension, sprockets as solid steel discs (chainmodel new-scene's), the line of
centres inclined 90 deg (and 86 / 80 deg with --inclinations). Levels 0-3: the static tension
(each level's ``static_tension()``) and the running span means over the second half of the run,
with no load and under 20 N m (docs/reduced_models.md, "Spans hanging along their length").

The weight along a span's chord is its floor: half the weight of the span's rise
(span_sag.hanging_tension), printed first.

    python docs/scripts/hanging_spans.py                     # about 40 s with warm kernels
    python docs/scripts/hanging_spans.py --inclinations 90 86 80
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.models.span_sag import hanging_tension
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene

SPEEDS = (5.0, 30.0, 100.0)
LOADS = (0.0, 20.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--inclinations", type=float, nargs="+", default=[90.0])
    args = ap.parse_args(argv)
    path = Path(tempfile.mkdtemp()) / "vertical.toml"
    path.write_text(scene_text(21, 21, 5.0, 0.0, chain="16B", links=60, static_tension=0.0))
    for degrees in args.inclinations:
        tilt = math.radians(degrees)
        sc = load_scene(str(path), fidelity=0, drive_inclination=tilt)
        statics = [load_scene(str(path), fidelity=level, drive_inclination=tilt).model()
                   .static_tension() for level in range(4)]
        print(f"\n{degrees:g} deg: weight along a span's floor "
              f"{hanging_tension(sc.drive, sc.parameters):.2f} N; static tension levels 0-3 "
              + " / ".join(f"{t:.2f}" for t in statics) + " N")
        print(f"{'load':>6s} {'rpm':>5s}  " + "  ".join(f"{'level ' + str(v):>15s}"
                                                     for v in range(4))
              + "   (mean tight / slack span [N])")
        for load in LOADS:
            for rpm in SPEEDS:
                duration = max(1.2, 6.0 * 60.0 / rpm / 21.0)
                cells = []
                for level in range(4):
                    r = chainmodel.simulate(str(path), fidelity=level, input_speed_rpm=rpm,
                                            load_torque=load, drive_inclination=tilt,
                                            duration=duration, ramp_time=0.1,
                                            output_interval=1e-3)
                    m = r.time >= 0.5 * duration
                    cells.append(f"{np.mean(r['tight_span.tension'][m]):7.1f}/"
                                 f"{np.mean(r['slack_span.tension'][m]):<7.1f}")
                print(f"{load:6g} {rpm:5g}  " + "  ".join(cells))


if __name__ == "__main__":
    main()
