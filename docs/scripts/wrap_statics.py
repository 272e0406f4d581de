"""Statics of the chain wrapped on a sprocket, with level 3's seat and link model: why levels
0-2's slack span sits above level 3's (docs/reduced_models.md, "Closing the slack-span gap").

    python docs/scripts/wrap_statics.py      # about 40 s

A prototype, not part of the models: one sprocket's whole wrap (n seated rollers) with both
ends pulled tangentially by the span tensions Ta and Tb, every roller in level 3's seat (arc of
radial clearance dR = R_t - R_r, flanks beyond gamma = 60 deg - 45 deg / z; contact stiffness
k_c), links tension-only with joint play (kernels.multibody_forces.accelerations), solved as a minimum
of the potential energy. ``give`` returns how far each span end is pulled out of the wrap. The
length balance n_span (Tu + Tl) / (2 k) + the four ends' give = L - M p then gives the static
span tension and the loaded split at rest (xu2010: 25/17 teeth, 15/9 wrapped rollers, 24.77
span links as a tooth-period mean, L - M p = 593.9 um). Compare level 3 at rest: 528 N static,
1082 / 79 N loaded (mean over the driver's phase; docs/reduced_models.md).
"""
import math

import numpy as np
from scipy.optimize import brentq, minimize

from chainmodel.parameters import validate

_P = validate({})      # the schema's defaults: seed 003's xu2010 chain, as level 3 uses them
K_LINK = _P["chain.link_stiffness"]                          # [N/m]
K_C = _P["contact.stiffness"]                                # [N/m]
D_R = _P["contact.seat_radius"] - _P["chain.roller_radius"]  # radial seat clearance [m]
PITCH = _P["drive.pitch"]
GAP = _P["chain.joint_clearance"]                            # [m]
EXCESS = 0.0005939077869307698   # L - M p, tooth-period mean [m] (xu2010, 46 links)
SPAN_LINKS = 24.77


def give(z: int, n: int, Ta: float, Tb: float) -> tuple[float, float]:
    """(e_a, e_b) [m]: how far the wrap's first and last rollers are pulled out along the spans
    by the tensions Ta and Tb."""
    a = math.pi / z
    R = PITCH / (2 * math.sin(a))
    g = math.radians(60) - math.pi / (4 * z)
    cg, sg = math.cos(g), math.sin(g)
    th = 2 * a * np.arange(n)
    C = np.c_[R * np.cos(th), R * np.sin(th)]
    ct, st = np.cos(th), np.sin(th)
    ua = np.array([math.sin(th[0]), -math.cos(th[0])])
    ub = np.array([-math.sin(th[-1]), math.cos(th[-1])])

    def energy(y):
        X = C + 1e-6 * y.reshape(-1, 2)
        d = X - C
        sl = d[:, 0] * ct + d[:, 1] * st
        tl = -d[:, 0] * st + d[:, 1] * ct
        dd = np.hypot(sl, tl)
        pen = np.where(-sl >= dd * cg, dd - D_R, np.abs(tl) * sg - sl * cg - D_R)
        e = np.sum(0.5 * K_C * np.maximum(pen, 0) ** 2)
        s = np.hypot(*np.diff(X, axis=0).T) - PITCH
        e += np.sum(0.5 * K_LINK * np.maximum(s, 0) ** 2) + np.sum(0.5 * K_LINK * np.minimum(s + GAP, 0) ** 2)
        return 1e6 * (e - Ta * (X[0] @ ua) - Tb * (X[-1] @ ub))

    y0 = np.zeros(2 * n)
    y0[0::2], y0[1::2] = -50 * ct, -50 * st
    r = minimize(energy, y0, method="BFGS", options=dict(gtol=1e-7, maxiter=50000))
    X = C + 1e-6 * r.x.reshape(-1, 2)
    return float((X[0] - C[0]) @ ua), float((X[-1] - C[-1]) @ ub)


def stretch(Tu: float, Tl: float) -> float:
    """Spans' stretch plus the four ends' give [m] at span tensions Tu, Tl (driver wrap 25 / 15,
    driven 17 / 9)."""
    a1, b1 = give(25, 15, Tu, Tl)
    a2, b2 = give(17, 9, Tl, Tu)
    return SPAN_LINKS / 2 * (Tu + Tl) / K_LINK + a1 + b1 + a2 + b2


if __name__ == "__main__":
    T0 = brentq(lambda T: stretch(T, T) - EXCESS, 300, 700, xtol=0.5)
    print(f"static span tension        {T0:.1f} N   (level 3: 528 N; levels 0-2: 608 N)")
    Tl = brentq(lambda T: stretch(T + 1000, T) - EXCESS, 0.5, 300, xtol=0.5)
    print(f"loaded at rest, dT 1000 N  {Tl + 1000:.1f} / {Tl:.1f} N   (level 3: 1082 / 79 N; "
          "levels 0-2: 1111 / 105 N)")
    print("end give e_a [um] of a span at tension Ta while the other carries Tb:")
    for z, n in ((25, 15), (17, 9)):
        for Ta in (75, 528, 1077):
            print(f"  z = {z}, Ta = {Ta:4d} N: " + "  ".join(
                f"Tb = {Tb}: {1e6 * give(z, n, Ta, Tb)[0]:5.1f}" for Tb in (75, 528, 1077)))
