"""Level 3's span against an independent lumped-mass model of one span (issue 21 item 6).

The independent model, written here: the rollers strictly inside level 3's upper span, point
masses m (chain.link_mass) joined by links that pull with k (L - l0) when longer than their
free length l0 = p - pretension / k, push with k (L - l0 + gap) when shorter by more than the
joint play, and carry nothing in between (a roller chain's link; docs/multibody.md), under
gravity g in the drive's frame; its two end rollers (the last one seated on the driven
sprocket, the first one seated on the driver) move as level 3 moves them: the polygon-driven
ends, interpolated from level 3's record. It is integrated with scipy's DOP853 from level 3's
state at the start of a window in which no roller seats or leaves (the span keeps its
rollers), and its middle roller's path is compared with level 3's.

Level 3 runs xu2010 at 30 rpm from straight spans with the chain's link and joint damping off
(the independent model has none), so the spans swing under gravity and the polygon.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp
from scipy.interpolate import CubicSpline

from chainmodel.integrate import Verlet
from chainmodel.models import Inputs
from chainmodel.models.multibody import MultibodyModel
from chainmodel.scene import load_scene

RPM = 30.0
DT = 1e-5


def _level3_record(duration=0.12):
    sc = load_scene("xu2010", fidelity=3)
    params = sc.parameters | {"chain.link_damping": 0.0, "chain.joint_damping": 0.0}
    model = MultibodyModel(sc.drive, params)
    w = RPM * 2 * math.pi / 60
    u0 = Inputs(0.0, w, 0.0)
    st = Verlet(model, 0.0, model.initial_state(u0), u0)
    times, states, spans = [], [], []
    for i in range(1, int(round(duration / DT)) + 1):
        st.advance(i * DT)
        x = st.x.copy()
        u = Inputs(w * i * DT, w, 0.0)
        up = model._evaluate(i * DT, x, u)[3]
        times.append(i * DT)
        states.append(x)
        spans.append(up[1:])
    return sc, model, np.array(times), np.array(states), spans


def test_level3_span_matches_an_independent_lumped_mass_span():
    sc, model, t, X, spans = _level3_record()
    p, d = sc.parameters, sc.drive
    M = d.links
    n = 2 + 2 * M
    # the longest window after 0.02 s in which the upper span keeps its end rollers
    best, start = (0, 0), None
    for i in range(len(spans)):
        if start is None or spans[i] != spans[start]:
            start = i
        if t[start] >= 0.02 and i - start > best[1] - best[0]:
            best = (start, i)
    i0, i1 = best
    assert t[i1] - t[i0] >= 0.02           # at least two tight-span periods (~90 Hz)
    a, b = spans[i0]
    inner = [(a + 1 + j) % M for j in range((b - a - 1) % M)]
    assert len(inner) >= 8
    ends = [a, b]
    tw = t[i0:i1 + 1]
    pos = X[i0:i1 + 1, 2:n].reshape(-1, M, 2)
    vel = X[i0:i1 + 1, n + 2:].reshape(-1, M, 2)
    end_path = [CubicSpline(tw, pos[:, e, :], axis=0) for e in ends]

    m, k = p["chain.link_mass"], p["chain.link_stiffness"]
    l0 = d.pitch - p["chain.pretension"] / k
    gap = p["chain.joint_clearance"]
    incl, th1, g = p["drive.inclination"], d.centre_angle, p["gravity"]
    grav = np.array([g * math.sin(th1 - incl), -g * math.cos(th1 - incl)])   # up is i e^{i(th1-incl)}
    N = len(inner)

    def rhs(tt, y):
        z = y[:2 * N].reshape(N, 2)
        chain = np.vstack([end_path[0](tt), z, end_path[1](tt)])
        dz = np.diff(chain, axis=0)
        L = np.hypot(dz[:, 0], dz[:, 1])
        ext = L - l0
        T = np.where(ext > 0, k * ext, np.where(ext < -gap, k * (ext + gap), 0.0))
        f = (T / L)[:, None] * dz
        acc = (f[1:] - f[:-1]) / m + grav
        return np.concatenate([y[2 * N:], acc.ravel()])

    y0 = np.concatenate([pos[0, inner].ravel(), vel[0, inner].ravel()])
    sol = solve_ivp(rhs, (tw[0], tw[-1]), y0, method="DOP853", t_eval=tw, rtol=1e-9,
                    atol=1e-12, max_step=2e-5)
    assert sol.success
    mid = N // 2
    ours = sol.y[2 * mid:2 * mid + 2].T
    theirs = pos[:, inner[mid], :]
    # transverse to the span's chord, from the chord's start
    chord = pos[:, b, :] - pos[:, a, :]
    normal = np.column_stack([-chord[:, 1], chord[:, 0]]) / np.hypot(*chord.T)[:, None]
    y_ours = np.einsum("ij,ij->i", ours - pos[:, a, :], normal)
    y_theirs = np.einsum("ij,ij->i", theirs - pos[:, a, :], normal)
    swing = np.ptp(y_theirs)
    assert swing > 1e-4                      # m: the span swings (0.43 mm measured)
    # the same mechanics: they differ by the integrators' errors only (Verlet's O(h^2) at
    # level 3's step; 1e-5 of the swing measured)
    assert np.max(np.abs(y_ours - y_theirs)) <= 1e-3 * swing
    # and the tension it carries: the middle link's force, both models
    L_ours = np.hypot(*(sol.y[2 * mid + 2:2 * mid + 4].T - ours).T)
    L_theirs = np.hypot(*(pos[:, inner[mid + 1], :] - theirs).T)
    assert np.mean(k * (L_ours - l0)) == pytest.approx(np.mean(k * (L_theirs - l0)), rel=0.03)
