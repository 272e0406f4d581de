"""Static tension of a chain with no pretension near and away from its tight wrap, at every
level (issue 21 item 4; docs/reduced_models.md, "One wrap and one static tension from level 3's
statics").

The 08B fan drive of examples/scenes/08b_fan_1500rpm.toml without its static tension, the
centre distance moved from the tight-wrap one. Columns: the elastic catenary (parabolic sag,
Irvine's cable, on levels 0-2's seat ladder: X + sum_spans (w cos psi)^2 l^3 / (24 T^2) = T D);
the seat ladder alone (levels 0-2 before issue 21: 0 N on a slack chain); level 1 by default
(a chain that hangs on its sag takes level 3's statics without being asked,
wrap_statics.hangs_on_its_sag); levels 0, 1, 2 with torsional.wrap_statics (span
ends condensed from level 3's statics); level 3's static equilibrium (multibody_statics: Newton
steps, wall time of the solve); level 3's dynamic model over 0.1 s at rest started from that
equilibrium (the mean of its two span outputs).

    python docs/scripts/static_sag.py        # a few seconds
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from chainmodel.integrate import Verlet
from chainmodel.models import Inputs
from chainmodel.models.multibody_statics import static_state
from chainmodel.models.static_tension import static_numerator
from chainmodel.models.static_tension import static_span_tension as ladder
from chainmodel.scene import load_scene

PATH = "examples/scenes/08b_fan_1500rpm.toml"


def at_rest(model, x):
    u = Inputs(0.0, 0.0, 0.0)
    st = Verlet(model, 0.0, x.copy(), u)
    rows = [st.advance(i * 1e-3, u) for i in range(1, 101)]
    return float(np.mean([0.5 * (r["tight_span.tension"] + r["slack_span.tension"])
                          for r in rows]))


def main():
    d0 = load_scene(PATH, fidelity=1, static_tension=None).drive
    print(f"{'dc [mm]':>8s} {'catenary':>9s} {'ladder':>7s} {'L1 default':>10s} {'L0 wrap':>8s} {'L1 wrap':>8s} "
          f"{'L2 wrap':>8s} {'L3 statics':>10s} {'steps':>5s} {'solve':>7s} {'L3 at rest':>10s}")
    for dc in (0.0, -0.5e-3, -2e-3, -5e-3, -10e-3, -20e-3):
        a = d0.centre_distance + dc
        m = load_scene(PATH, fidelity=1, static_tension=None, drive_centre_distance=a).model()
        p, d, r = m.params, m.drive, m.reference
        x, dd = static_numerator(d, p)
        w = p["chain.link_mass"] / d.pitch * p["gravity"]
        sag = sum((w * math.cos(r["dir_" + s])) ** 2 * r["l_" + s] ** 3 / 24 for s in ("up", "low"))
        t = brentq(lambda tt: tt * dd - x - sag / tt ** 2, 1e-6, 1e7)
        wrap = []
        for lv in (0, 1, 2):
            try:
                wrap.append(load_scene(PATH, fidelity=lv, static_tension=None,
                                       drive_centre_distance=a,
                                       torsional_wrap_statics=True).model().static_tension())
            except ValueError:   # level 2 refuses a chain longer than its wrap (modal.py)
                wrap.append(math.nan)
        m3 = load_scene(PATH, fidelity=3, static_tension=None, drive_centre_distance=a).model()
        sol = static_state(m3)
        print(f"{1e3 * dc:8.1f} {t:9.1f} {ladder(d, p):7.1f} {m.static_tension():10.2f} {wrap[0]:8.2f} {wrap[1]:8.2f} "
              f"{wrap[2]:8.2f} {sol.mean_tension:10.2f} {sol.iterations:5d} "
              f"{1e3 * sol.wall:5.0f}ms {at_rest(m3, sol.state):10.2f}", flush=True)


if __name__ == "__main__":
    main()
