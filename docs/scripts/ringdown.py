"""Ring-down of the driven sprocket's torsional mode per fidelity level (issue 21 item 3).

A sudden start to 5 rpm (no ramp, no load torque) rings the driven sprocket on the chain; the
frequency is measured from the driven speed's oscillation about its mean over 0.02-0.5 s (mean
spacing of the zero crossings of the speed minus its running tooth-period mean, refined by the
peak of a Hann-windowed spectrum). The analytical estimate: the driven sprocket's inertia J_2
(plus the seated chain's m R^2 per seated roller) on the two spans in parallel, each of n
links in series with the wrap at both ends, k_span = 1 / (n / k_link + 2 / K_seat),
K_seat = (k_c + sqrt(k_c^2 + 4 k_c k_link)) / 2 (the seat ladder, docs/reduced_models.md), and
f = sqrt(R_o^2 (k_up + k_low) / J_2) / 2 pi (rigid input shaft: the driver held by the input;
a flexible one: the two-inertia system with the shaft spring, the driven sprocket's mode).

    python docs/scripts/ringdown.py                # C1 and xu2010, levels 1-3
    python docs/scripts/ringdown.py C1 1,3         # one scene, some levels
"""

from __future__ import annotations

import math
import sys
import time

import numpy as np

import chainmodel
from chainmodel.models.static_tension import seat_stiffness
from chainmodel.scene import load_scene

RPM = 5.0
DURATION = 0.5


def measured_frequency(t, w, t0=0.02, band=None):
    m = t >= t0
    t, w = t[m], w[m]
    x = w - np.polyval(np.polyfit(t, w, 1), t)
    x = x * np.hanning(len(x))
    dt = t[1] - t[0]
    n = 16 * len(x)
    spec = np.abs(np.fft.rfft(x, n))
    f = np.fft.rfftfreq(n, dt)
    spec[f < 10.0] = 0.0   # below: the 5 rpm meshing (2-3 Hz) and the start's drift
    if band is not None:   # the peak within (lo, hi) Hz
        spec[(f < band[0]) | (f > band[1])] = 0.0
    k = int(np.argmax(spec))
    return float(f[k])


def analytical(name, **kw):
    """Undamped two-inertia estimate [Hz]: the sprockets (mass matrix of level 1, chain
    inertia included) on the two spans in parallel, each span's n links in series with the
    seat ladder at both ends, and the input shaft's spring on the driver (none if rigid); the
    mode with the largest share of its kinetic energy in the driven sprocket."""
    sc = load_scene(name, fidelity=1, **kw)
    p, d = sc.parameters, sc.drive
    m1 = sc.model()
    r = m1.reference
    kl, kc = p["chain.link_stiffness"], p["contact.stiffness"]
    ks = seat_stiffness(kc, kl)
    k = sum(1.0 / (n / kl + 2.0 / ks) for n in (r["n_up"], r["n_low"]))
    rc, ro = d.driver.pitch_radius, d.driven.pitch_radius
    M = m1.mass_matrix()
    if p["input_shaft.rigid"]:
        return math.sqrt(ro * ro * k / M[1, 1]) / (2 * math.pi)
    K = k * np.array([[rc * rc, -rc * ro], [-rc * ro, ro * ro]])
    K[0, 0] += p["input_shaft.stiffness"]
    lam, vec = np.linalg.eig(np.linalg.solve(M, K))
    share = [M[1, 1] * v[1] ** 2 / (v @ M @ v) for v in np.real(vec).T]
    return math.sqrt(abs(lam[int(np.argmax(share))].real)) / (2 * math.pi)


def ring(name, level, band=None, **kw):
    """(frequency [Hz] of the driven speed's ring-down: the strongest peak above 10 Hz, or
    within ``band``; wall time [s])."""
    t0 = time.time()
    r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=RPM, ramp_time=0.0,
                            load_torque=0.0, duration=DURATION, output_interval=5e-5, **kw)
    return measured_frequency(r.time, r["driven.speed"], band=band), time.time() - t0


def main(argv):
    names = argv[1].split(",") if len(argv) > 1 else ["C1", "xu2010"]
    levels = [int(v) for v in argv[2].split(",")] if len(argv) > 2 else [1, 2, 3]
    print("strongest peak of the driven speed above 10 Hz within 0.6-1.4 x the estimate of the "
          "driven sprocket's mode")
    print(f"{'scene':8s} {'level':>5s} {'f [Hz]':>8s} {'vs L3':>7s} {'vs est.':>8s} {'wall':>6s}")
    for name in names:
        est = analytical(name)
        f3 = None
        rows = []
        for level in sorted(levels, reverse=True):
            f, wall = ring(name, level, band=(0.6 * est, 1.4 * est))
            if level == 3:
                f3 = f
            rows.append((level, f, wall))
        for level, f, wall in sorted(rows):
            vs3 = f"{100 * (f / f3 - 1):+6.1f}%" if f3 else "   n/a"
            print(f"{name:8s} {level:5d} {f:8.2f} {vs3:>7s} {100 * (f / est - 1):+7.1f}% "
                  f"{wall:5.1f}s", flush=True)
        print(f"{name:8s} {'est.':>5s} {est:8.2f}", flush=True)


if __name__ == "__main__":
    main(sys.argv)
