"""Issue 21 item 3 measured with the reference's band: level 3 and levels 1-2 with
``torsional.wrap_statics`` run on the same parameters at each value no source gives
(chainmodel.analysis.trade_study.UNCERTAIN: contact stiffness, seat clearance and joint damping
x0.5 and x2), so the comparison of 3 is made where level 3 itself is, not at one point.

Two measurements per variant:

* the driven sprocket's torsional mode: ring-down after a sudden start to 5 rpm
  (docs/scripts/ringdown.py's ``ring``), C1 and xu2010;
* the running span tensions on xu2010 at 43.2 N m, 30 and 60 rpm: means over 0.3-0.6 s of the
  tight and slack spans (the earlier reduced-order work's slack-span criterion).

    python docs/scripts/item3_band.py            # both tables (about 20 s, kernels warm)
    python docs/scripts/item3_band.py ring       # the ring-down table only
    python docs/scripts/item3_band.py running    # the running table only
    python docs/scripts/item3_band.py c1         # C1 at 60 and 100 rpm with the band
                                                 # (its torsional resonance; about 15 s)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.analysis.trade_study import UNCERTAIN, band_overrides
from chainmodel.scene import load_scene

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ringdown import analytical, ring  # noqa: E402

VARIANTS = (("nominal", 1.0),) + UNCERTAIN
SPEEDS = (30.0, 60.0)


def overrides(name, what, factor):
    if what == "nominal":
        return {}
    return band_overrides(load_scene(name), what, factor)


def ring_table():
    print("ring-down of the driven sprocket [Hz] (levels 1-2 with torsional.wrap_statics); "
          "error against level 3 at the same parameters")
    print(f"{'scene':7s} {'variant':24s} {'level 3':>8s} {'level 1':>16s} {'level 2':>16s}")
    for name in ("C1", "xu2010"):
        est = analytical(name)
        band = (0.6 * est, 1.4 * est)
        for what, factor in VARIANTS:
            p = overrides(name, what, factor)
            f3, _ = ring(name, 3, band=band, parameters=p)
            cells = []
            for level in (1, 2):
                f, _ = ring(name, level, band=band, parameters=p, torsional_wrap_statics=True)
                cells.append(f"{f:8.2f} ({100 * (f / f3 - 1):+5.1f}%)")
            label = what if what == "nominal" else f"{what} x{factor:g}"
            print(f"{name:7s} {label:24s} {f3:8.2f} {cells[0]:>16s} {cells[1]:>16s}", flush=True)


def spans(name, level, rpm, p, duration, **kw):
    """(tight, slack) mean span tensions [N] over the second half of ``duration``."""
    r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, duration=duration,
                            output_interval=2e-4, parameters=p, **kw)
    m = r.time >= 0.5 * duration
    return float(np.mean(r["tight_span.tension"][m])), float(np.mean(r["slack_span.tension"][m]))


def span_table(name, rows, duration, load):
    """Levels 1-2 with the option against level 3 on the same parameters, per (rpm, variants)."""
    print(f"{name} at {load}, mean span tensions over {duration / 2:g}-{duration:g} s; levels "
          "1-2 with torsional.wrap_statics, error against level 3 at the same parameters "
          "(tight / slack)")
    print(f"{'rpm':>4s} {'variant':24s} {'level 3 [N]':>16s} {'level 1':>16s} {'level 2':>16s}")
    for rpm, variants in rows:
        for what, factor in variants:
            p = overrides(name, what, factor)
            t3, s3 = spans(name, 3, rpm, p, duration)
            cells = []
            for level in (1, 2):
                t, s = spans(name, level, rpm, p, duration, torsional_wrap_statics=True)
                cells.append(f"{100 * (t / t3 - 1):+5.1f} / {100 * (s / s3 - 1):+5.1f}%")
            label = what if what == "nominal" else f"{what} x{factor:g}"
            print(f"{rpm:4.0f} {label:24s} {t3:7.1f} / {s3:6.1f} {cells[0]:>16s} "
                  f"{cells[1]:>16s}", flush=True)


def main(argv):
    what = argv[1] if len(argv) > 1 else "both"
    t0 = time.time()
    if what in ("both", "ring"):
        ring_table()
    if what in ("both", "running"):
        span_table("xu2010", [(rpm, VARIANTS) for rpm in SPEEDS], 0.6, "43.2 N m")
    if what == "c1":
        span_table("C1", [(60.0, VARIANTS), (100.0, VARIANTS)], 1.2, "its preset load")
    print(f"wall {time.time() - t0:.0f} s")


if __name__ == "__main__":
    main(sys.argv)
