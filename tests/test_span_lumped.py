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

Level 3 runs with the chain's link and joint damping off (the independent model has none):
xu2010 at 30 rpm from straight spans, so the spans swing under gravity and the polygon; and a
16B 8/16 of 32 links without pretension at 200 rpm, whose spans lock on the meshing (docs/
reduced_models.md, "Level 2's spans locked on the meshing": level 3 carries there 7.7 x a rigid
chain's tension, which no other code has checked). In that locked state the same independent
model reproduces level 3's span, and the span's mean tension puts its first string mode on the
meshing: the large-amplitude branch of the hardening string's primary resonance that seed 004
(section 6, its Fig. 6 discussion) finds coexisting with the still one.
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
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene

DT = 1e-5


def _level3_record(scene, rpm, start=0.0, duration=0.12):
    """Level 3 (chain damping off) from rest at ``rpm`` held, advanced to ``start`` in one
    call, then recorded every DT for ``duration``: times, states, the spans' end rollers."""
    params = scene.parameters | {"chain.link_damping": 0.0, "chain.joint_damping": 0.0}
    model = MultibodyModel(scene.drive, params)
    w = rpm * 2 * math.pi / 60
    u0 = Inputs(0.0, w, 0.0)
    st = Verlet(model, 0.0, model.initial_state(u0), u0)
    n0 = int(round(start / DT))
    if n0:
        st.advance(n0 * DT)
    times, states, spans = [], [], []
    for i in range(n0 + 1, n0 + int(round(duration / DT)) + 1):
        st.advance(i * DT)
        x = st.x.copy()
        u = Inputs(w * i * DT, w, 0.0)
        up = model._evaluate(i * DT, x, u)[3]
        times.append(i * DT)
        states.append(x)
        spans.append(up[1:])
    return model, np.array(times), np.array(states), spans


def _span_against_lumped_model(scene, t, X, spans, after):
    """The independent model of the module docstring over the longest window after ``after``
    in which the upper span keeps its end rollers. Returns the window's length [s], the middle
    roller's path across the span's chord in both models, the middle link's force in both, and
    level 3's span: its mean link force and mean chord length."""
    p, d = scene.parameters, scene.drive
    M = d.links
    n = 2 + 2 * M
    best, start = (0, 0), None
    for i in range(len(spans)):
        if start is None or spans[i] != spans[start]:
            start = i
        if t[start] >= after and i - start > best[1] - best[0]:
            best = (start, i)
    i0, i1 = best
    a, b = spans[i0]
    inner = [(a + 1 + j) % M for j in range((b - a - 1) % M)]
    assert len(inner) >= 8
    tw = t[i0:i1 + 1]
    pos = X[i0:i1 + 1, 2:n].reshape(-1, M, 2)
    vel = X[i0:i1 + 1, n + 2:].reshape(-1, M, 2)
    end_path = [CubicSpline(tw, pos[:, e, :], axis=0) for e in (a, b)]

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
    force_ours = k * (np.hypot(*(sol.y[2 * mid + 2:2 * mid + 4].T - ours).T) - l0)
    force_theirs = k * (np.hypot(*(pos[:, inner[mid + 1], :] - theirs).T) - l0)
    lengths = np.hypot(*np.diff(pos[:, [a] + inner + [b], :], axis=1).transpose(2, 0, 1))
    span_force = float(np.mean(np.clip(k * (lengths - l0), 0.0, None)))
    return (tw[-1] - tw[0], y_ours, y_theirs, force_ours, force_theirs, span_force,
            float(np.mean(np.hypot(*chord.T))))


def test_level3_span_matches_an_independent_lumped_mass_span():
    sc = load_scene("xu2010", fidelity=3)
    _, t, X, spans = _level3_record(sc, 30.0)
    window, y_ours, y_theirs, f_ours, f_theirs, _, _ = _span_against_lumped_model(
        sc, t, X, spans, after=0.02)
    assert window >= 0.02                  # at least two tight-span periods (~90 Hz)
    swing = np.ptp(y_theirs)
    assert swing > 1e-4                      # m: the span swings (0.43 mm measured)
    # the same mechanics: they differ by the integrators' errors only (Verlet's O(h^2) at
    # level 3's step; 1e-5 of the swing measured)
    assert np.max(np.abs(y_ours - y_theirs)) <= 1e-3 * swing
    # and the tension it carries: the middle link's force, both models
    assert np.mean(f_ours) == pytest.approx(np.mean(f_theirs), rel=0.03)


def test_level3s_locked_span_is_a_lumped_mass_string_on_its_primary_resonance(tmp_path):
    """No pretension, no load, a 16B 8/16 of 32 links at 200 rpm (docs/scripts/
    level2_span_survey.py's drive): level 3's spans carry some 600 N on an 86 N static tension.
    Is that level 3's contact or integrator, or what the chain's masses and links do between
    the polygon-driven ends? The independent model answers: the latter. The ends themselves
    ride their seats; what the span takes from level 3 is then the sprockets' rotation."""
    rpm = 200.0
    path = tmp_path / "lock.toml"
    path.write_text(scene_text(8, 16, rpm, 0.0, chain="16B", links=32, static_tension=0.0))
    sc = load_scene(path, fidelity=3)
    model, t, X, spans = _level3_record(sc, rpm, start=0.6, duration=0.08)
    window, y_ours, y_theirs, f_ours, f_theirs, span_force, span_length = \
        _span_against_lumped_model(sc, t, X, spans, after=0.6)
    d, p = sc.drive, sc.parameters
    tooth_period = 60.0 / (d.n_driver * rpm)
    assert window >= 0.5 * tooth_period
    swing = np.ptp(y_theirs)
    assert swing > 0.1 * d.pitch             # it swings by centimetres (10 mm measured)
    assert np.max(np.abs(y_ours - y_theirs)) <= 1e-3 * swing
    assert np.mean(f_ours) == pytest.approx(np.mean(f_theirs), rel=0.03)
    # and its ends are the sprockets' polygons: the span's end rollers sit in a seat (within
    # the seat clearance and the contact's give, 0.17 mm measured), against the centimetre swing
    w = rpm * 2 * math.pi / 60
    off = []
    for i in range(0, len(t), 10):
        snap = model.snapshot(t[i], X[i], Inputs(w * t[i], w, 0.0))
        seats = np.vstack([snap["seat_positions_driver"], snap["seat_positions_driven"]])
        off += [np.min(np.hypot(*(seats - snap["roller_positions"][e]).T)) for e in spans[i]]
    assert max(off) < 0.01 * d.pitch
    # locked: many times the static tension, and its first string mode on the meshing. The
    # moving string's first mode (Mote): f_1 = (1 - v^2 / c^2) c / 2L, c^2 = T / rho
    assert span_force > 5 * model.static_tension()
    rho = p["chain.link_mass"] / d.pitch
    c = math.sqrt(span_force / rho)
    v = d.n_driver * d.pitch * rpm / 60.0
    f1 = (1.0 - (v / c) ** 2) * c / (2.0 * span_length)
    assert f1 == pytest.approx(d.n_driver * rpm / 60.0, rel=0.05)
