"""Static tension of a chain with no pretension near a tight wrap: the elastic catenary a
level 0-2 model would give (measured, not built) against level 3's settled static tension
(issue 21 item 4; docs/reduced_models.md, "Static tension with gravity").

The 08B fan drive of examples/scenes/08b_fan_1500rpm.toml without its static tension, the
centre distance moved from the tight-wrap one. Catenary: the static tension T solves
X + sum_spans (w cos psi)^2 l^3 / (24 T^2) = T D, with (X, D) of
chainmodel.models.static_tension._static_numerator (excess length over the spans' free
length with the seats' terms, and the spans' compliance), w = m g / p, psi each span's
direction, l its mean length (parabolic sag, Irvine's elastic cable).

    python docs/scripts/static_sag.py        # a few seconds
"""

from __future__ import annotations

import math

from scipy.optimize import brentq

from chainmodel.models.static_tension import _static_numerator
from chainmodel.scene import load_scene

PATH = "examples/scenes/08b_fan_1500rpm.toml"


def main():
    d0 = load_scene(PATH, fidelity=1, static_tension=None).drive
    print(f"{'centre distance - tight [mm]':>28s} {'catenary [N]':>12s} {'levels 0-2 now':>14s} "
          f"{'level 3 [N]':>11s}")
    for dc in (0.0, -0.5e-3, -2e-3, -5e-3):
        a = d0.centre_distance + dc
        m = load_scene(PATH, fidelity=1, static_tension=None, drive_centre_distance=a).model()
        p, d, r = m.params, m.drive, m.reference
        x, dd = _static_numerator(d, p)
        w = p["chain.link_mass"] / d.pitch * p["gravity"]
        sag = sum((w * math.cos(r["dir_" + s])) ** 2 * r["l_" + s] ** 3 / 24 for s in ("up", "low"))
        t = brentq(lambda tt: tt * dd - x - sag / tt ** 2, 1e-6, 1e7)
        t3 = load_scene(PATH, fidelity=3, static_tension=None,
                        drive_centre_distance=a).model().static_tension()
        print(f"{1e3 * dc:28.1f} {t:12.1f} {m.static_tension():14.1f} {t3:11.1f}", flush=True)


if __name__ == "__main__":
    main()
