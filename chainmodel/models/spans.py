"""Scalar kernel shared by levels 1 (torsional) and 2 (modal): both spans' exact polygon geometry
for one pair of sprocket rotations, their tensions, the sprocket equations (seed 004 eq 50 with
the input shaft of seed 003) and the span modes (seed 004 eqs 57-61).

Why a separate kernel: a dynamic level evaluates the geometry of one state at a time, tens of
thousands of times per simulated second. :func:`chainmodel.kinematics.wrapping.chain_geometry`
is vectorised numpy and costs tens of microseconds for a single sample; the functions here do
the same computation with the ``math`` module on floats (the same window condition, the same
fixed-point iteration, the same link counting: tests/test_torsional.py checks them against
``chain_geometry`` over many random rotation pairs). They are written in the subset of Python
that numba compiles; numba (a core dependency) compiles them once per machine
(:mod:`chainmodel.numba_cache`), and without it they run as plain Python. ``CHAINMODEL_NUMBA=0`` in the
environment forces the plain-Python path (the tests run both).

Conventions: forward-positive rotations phi1 (driver) and phi2 (driven), zero in the reference
configuration of :mod:`chainmodel.kinematics.rotation`; the XY frame of seed 000/004 with the
driven sprocket O at the origin and the driver C at (x_c, y_c). The upper span runs from the
driven sprocket onto the driver (tight when driving forward), the lower span from the driver onto
the driven sprocket.

Layout of the constant vectors (built by :func:`geometry_constants` and the models):

``G`` (geometry): theta4s, theta2s, alpha_c, alpha_o, R_c, R_o, x_c, y_c, theta1, n_c, n_o, N, M.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import import_numba, njit

__all__ = ["geometry_constants", "span_geometry", "NUMBA", "jit", "G_SIZE"]

_EDGE = 1e-9          # as chainmodel.kinematics.wrapping._EDGE: an endpoint at an event is past it
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
G_SIZE = 13


_numba = import_numba()   # optional acceleration; everything below also runs as plain Python
try:
    if _numba is None:
        raise ImportError

    def jit(fn):
        """Compile with numba (cached once per machine); the plain function stays at ``.py_func``."""
        return njit(fn, fastmath=False)

    NUMBA = True
except Exception:  # pragma: no cover - exercised with CHAINMODEL_NUMBA=0
    def jit(fn):
        fn.py_func = fn
        return fn

    NUMBA = False


def geometry_constants(drive) -> np.ndarray:
    """The constant vector ``G`` of a drive (module docstring)."""
    from ..kinematics import fourbar as fb
    s = fb.seating(drive)
    m = -1 if drive.links is None else drive.links
    return np.array([s.theta4, s.theta2, math.pi / drive.n_driver, math.pi / drive.n_driven,
                     drive.driver.pitch_radius, drive.driven.pitch_radius, drive.x_c, drive.y_c,
                     drive.centre_angle, drive.n_driver, drive.n_driven, drive.span_pitches, m],
                    float)


@jit
def _span(cfx, cfy, rf, af, phf, ctx, cty, rt, at, pht, dir0):
    """One straight span between two sprockets (scalar form of wrapping._span).

    Returns (length, arm_from, arm_to, j_from, j_to, u_from, u_to, ang_from, ang_to, direction),
    u the un-floored seat coordinates whose integer crossings are the release (from) and
    seating (to) events."""
    d = dir0
    jf_old = -1.0e300
    jt_old = -1.0e300
    jf = 0.0
    jt = 0.0
    angf = 0.0
    angt = 0.0
    edge = _EDGE
    for it in range(16):
        if it == 8:
            # Within about _EDGE (seat units) before an event the tolerant window flips between
            # the two candidate endpoints; the strict window settles there (as wrapping._span).
            edge = 0.0
            d = dir0
            jf_old = -1.0e300
            jt_old = -1.0e300
        jf = math.floor((d + _HALF_PI + af - phf) / (2.0 * af) + edge)
        jt = math.floor((d + _HALF_PI + at - pht) / (2.0 * at) + edge)
        angf = phf + 2.0 * af * jf
        angt = pht + 2.0 * at * jt
        ax = cfx + rf * math.cos(angf)
        ay = cfy + rf * math.sin(angf)
        bx = ctx + rt * math.cos(angt)
        by = cty + rt * math.sin(angt)
        nd = math.atan2(by - ay, bx - ax)
        nd = dir0 + ((nd - dir0 + math.pi) % _TWO_PI) - math.pi
        if jf == jf_old and jt == jt_old:
            d = nd
            break
        jf_old = jf
        jt_old = jt
        d = nd
    ax = cfx + rf * math.cos(angf)
    ay = cfy + rf * math.sin(angf)
    bx = ctx + rt * math.cos(angt)
    by = cty + rt * math.sin(angt)
    length = math.hypot(bx - ax, by - ay)
    uf = (d + _HALF_PI + af - phf) / (2.0 * af)
    ut = (d + _HALF_PI + at - pht) / (2.0 * at)
    return (length, rf * math.sin(angf - d), rt * math.sin(angt - d), jf, jt, uf, ut, angf,
            angt, d)


@jit
def span_geometry(phi1, phi2, G):
    """Both spans for one pair of rotations (scalar form of wrapping.chain_geometry).

    Returns a tuple of 20 floats: for the upper span then the lower span
    (length, arm_start, arm_end, links, u_start, u_end, angle_start, angle_end, direction, ...)
    followed by (wrapped_driver, wrapped_driven). ``arm_start`` is the forward torque arm on
    the sprocket the span leaves, ``arm_end`` the resisting arm on the one it runs onto, so
    d(length)/d(rotation) = +arm_end for the sprocket the span runs onto and -arm_start for the
    one it leaves (virtual work; checked against finite differences in the tests).
    """
    th4s = G[0]
    th2s = G[1]
    a_c = G[2]
    a_o = G[3]
    r_c = G[4]
    r_o = G[5]
    xc = G[6]
    yc = G[7]
    th1 = G[8]
    n_c = G[9]
    n_o = G[10]
    n_span = G[11]
    m_links = G[12]
    ph_c = th4s - phi1
    ph_o = th2s - phi2
    (lu, aus, aue, jus, jue, uus, uue, gus, gue, du) = _span(0.0, 0.0, r_o, a_o, ph_o, xc, yc, r_c,
                                                             a_c, ph_c, 0.0)
    (ll, als, ale, jls, jle, uls, ule, gls, gle, dl) = _span(xc, yc, r_c, a_c, ph_c, 0.0, 0.0, r_o,
                                                             a_o, ph_o, math.pi + 2.0 * th1)
    j_lc = jls - n_c * math.floor((jls - jue + n_c - 1.0) / n_c)
    j_lo = jle - n_o * math.floor((jle - jus - 1.0) / n_o)
    wrapped_c = jue - j_lc
    wrapped_o = j_lo - jus
    n_up = n_span + 1.0 - jue + jus
    n_low = m_links - n_up - wrapped_c - wrapped_o
    return (lu, aus, aue, n_up, uus, uue, gus, gue, du,
            ll, als, ale, n_low, uls, ule, gls, gle, dl, wrapped_c, wrapped_o)


# --- parameter vector P of the dynamic kernel -------------------------------------------------
P_K_LINK, P_C_LINK, P_P_FREE, P_SEAT_C, P_SEAT_SLACK, P_RIGID, P_K_SHAFT, P_C_SHAFT = range(8)
P_D2, P_J11, P_J12, P_J22, P_RHOA, P_MODES, P_LBAR_U, P_LBAR_L = range(8, 16)
P_ZETA, P_W1_U, P_W1_L, P_IMPULSE, P_REF_U, P_REF_L, P_GN_U, P_GN_L, P_PITCH = range(16, 25)
P_NBAR_U, P_NBAR_L = range(25, 27)
P_SIZE = 27

# --- auxiliary outputs of the kernel ----------------------------------------------------------
(A_T_UP, A_T_LOW, A_TAU_IN, A_ACC1, A_ACC2, A_L_UP, A_L_LOW, A_G_UP, A_G_LOW, A_EV_US, A_EV_UE,
 A_EV_LS, A_EV_LE, A_MID_UP, A_MID_LOW, A_PHI1, A_W1, A_N_UP, A_N_LOW) = range(19)
A_SIZE = 19


@jit
def _galerkin_g(k):
    """G_m of seed 004 eq 59: 2 int_0^1 sin(m pi x) dx."""
    return 2.0 * (1.0 - (-1.0) ** k) / (k * math.pi)


@jit
def _galerkin_e(k):
    """E_m of seed 004 eq 59: 2 int_0^1 x sin(m pi x) dx."""
    return -2.0 * (-1.0) ** k / (k * math.pi)


@jit
def _coriolis(k, j):
    """Gyroscopic Galerkin coefficient of 2 s w_xt on sin modes: 2 int_0^1 sin(k pi x)
    j pi cos(j pi x) dx * 2 / 2 = 2 k j (1 - (-1)^(k+j)) / (k^2 - j^2), zero for k = j.
    (Seed 004 eq 59 prints k^2 + j^2 in the denominator; the projection gives k^2 - j^2, which
    makes the matrix skew-symmetric as a gyroscopic term must be.)"""
    if k == j:
        return 0.0
    return 2.0 * k * j * (1.0 - (-1.0) ** (k + j)) / (k * k - j * j)


@jit
def _tension(length, stretch_modal, stretch_rate, links, p_free, k_link, c_link, seat_c,
             seat_slack, length_rate, links_compliance):
    """Span tension from its stretch (a span cannot push) and the switching function whose sign
    change marks the switch: min(k delta, T_raw), continuous through both ways of going slack.

    The stretch uses the span's current link count ``links``; its compliance and damping use
    ``links_compliance`` - the same count, or the tooth-period mean (torsional.
    mean_link_compliance): a seating roller's link keeps its elongation on the sprocket, so the
    span does not stiffen by a whole link at the event and the tension stays continuous."""
    k_eff = 1.0 / (links_compliance / k_link + seat_c)
    delta = length + stretch_modal - links * p_free - seat_slack
    raw = k_eff * delta + (c_link / links_compliance) * (length_rate + stretch_rate)
    switch = min(k_eff * delta, raw)
    if switch > 0.0:
        return raw, switch
    return 0.0, switch


@jit
def evaluate(x, th_in, w_in, a_in, load, G, P, dx, aux):
    """Right-hand side ``dx`` and auxiliary quantities ``aux`` (A_* indices) of levels 1-2.

    State layout: flexible shaft [phi1, phi2, w1, w2, modes], rigid shaft [phi2, w2, modes];
    modes = [q_up(1..n), q_low(1..n), v_up(1..n), v_low(1..n)] with q the Galerkin amplitudes of
    the transverse deflection from the chord (m) and v the projections of the material transverse
    velocity (see docs/reduced_models.md, "endpoint motion"), so that dq/dt = v - (G - E) Y1' - E Y2'
    and the velocity jumps of the span endpoints at seating and release (the impulses of seed 004
    eq 63) need no state jumps.
    """
    rigid = P[P_RIGID] > 0.5
    if rigid:
        phi1 = th_in
        w1 = w_in
        phi2 = x[0]
        w2 = x[1]
        base = 2
    else:
        phi1 = x[0]
        phi2 = x[1]
        w1 = x[2]
        w2 = x[3]
        base = 4
    n = int(P[P_MODES])
    (lu, aus, aue, nu, uus, uue, gus, gue, du,
     ll, als, ale, nl, uls, ule, gls, gle, dl, wc, wo) = span_geometry(phi1, phi2, G)
    r_c = G[4]
    r_o = G[5]
    p_free = P[P_P_FREE]
    # --- span modes: endpoint transverse velocities and modal stretching (seed 004 eqs 38, 46)
    s_u = 0.0
    s_l = 0.0
    sr_u = 0.0
    sr_l = 0.0
    speed = G[9] * P[P_PITCH] * w1 / (2.0 * math.pi)   # chain speed S: pitches per second * p
    impulse = P[P_IMPULSE] > 0.5
    y1u = 0.0
    y2u = 0.0
    y1l = 0.0
    y2l = 0.0
    if n > 0:
        if impulse:
            # seed 004 eqs 63-64: endpoint velocity jumps S p / R at release (start) and seating
            # (end), as a zero-mean sawtooth whose jumps are the Dirac pulses of y''
            y1u = speed * P[P_PITCH] / r_o * (math.floor(uus) - uus + 0.5)
            y2u = speed * P[P_PITCH] / r_c * (math.floor(uue) - uue + 0.5)
            y1l = speed * P[P_PITCH] / r_c * (math.floor(uls) - uls + 0.5)
            y2l = speed * P[P_PITCH] / r_o * (math.floor(ule) - ule + 0.5)
        else:
            # the kinematic endpoint motion: d/dt of R e^{i angle} across the reference line
            y1u = -w2 * r_o * math.cos(gus - P[P_REF_U])
            y2u = -w1 * r_c * math.cos(gue - P[P_REF_U])
            y1l = -w1 * r_c * math.cos(gls - P[P_REF_L])
            y2l = -w2 * r_o * math.cos(gle - P[P_REF_L])
        lbu = P[P_LBAR_U]
        lbl = P[P_LBAR_L]
        for k in range(1, n + 1):
            gk = _galerkin_g(k)
            ek = _galerkin_e(k)
            kp2 = (k * math.pi) ** 2
            qu = x[base + k - 1]
            ql = x[base + n + k - 1]
            qdu = x[base + 2 * n + k - 1] - (gk - ek) * y1u - ek * y2u
            qdl = x[base + 3 * n + k - 1] - (gk - ek) * y1l - ek * y2l
            dx[base + k - 1] = qdu
            dx[base + n + k - 1] = qdl
            s_u += kp2 * qu * qu / (4.0 * lbu)
            s_l += kp2 * ql * ql / (4.0 * lbl)
            sr_u += kp2 * qu * qdu / (2.0 * lbu)
            sr_l += kp2 * ql * qdl / (2.0 * lbl)
    # --- tensions (seed 004 eq 37 in dimensional form, both spans)
    rate_u = aue * w1 - aus * w2
    rate_l = -als * w1 + ale * w2
    nc_u = nu if P[P_NBAR_U] <= 0.0 else P[P_NBAR_U]
    nc_l = nl if P[P_NBAR_L] <= 0.0 else P[P_NBAR_L]
    t_u, g_u = _tension(lu, s_u, sr_u, nu, p_free, P[P_K_LINK], P[P_C_LINK], P[P_SEAT_C],
                        P[P_SEAT_SLACK], rate_u, nc_u)
    t_l, g_l = _tension(ll, s_l, sr_l, nl, p_free, P[P_K_LINK], P[P_C_LINK], P[P_SEAT_C],
                        P[P_SEAT_SLACK], rate_l, nc_l)
    # --- sprockets: seed 004 eq 50 (driven), shaft spring of seed 003 eq 14 (driver)
    q2 = t_u * aus - t_l * ale - P[P_D2] * w2 - load
    j11 = P[P_J11]
    j12 = P[P_J12]
    j22 = P[P_J22]
    if rigid:
        acc1 = a_in
        acc2 = (q2 - j12 * a_in) / j22
        tau_in = j11 * a_in + j12 * acc2 + t_u * aue - t_l * als
        dx[0] = w2
        dx[1] = acc2
    else:
        tau_in = P[P_K_SHAFT] * (th_in - phi1) + P[P_C_SHAFT] * (w_in - w1)
        q1 = tau_in - t_u * aue + t_l * als
        det = j11 * j22 - j12 * j12
        acc1 = (j22 * q1 - j12 * q2) / det
        acc2 = (j11 * q2 - j12 * q1) / det
        dx[0] = w1
        dx[1] = w2
        dx[2] = acc1
        dx[3] = acc2
    # --- span modes (seed 004 eqs 58-61, dimensional; tension includes the modal stretching)
    mid_u = 0.0
    mid_l = 0.0
    if n > 0:
        rho = P[P_RHOA]
        lbu = P[P_LBAR_U]
        lbl = P[P_LBAR_L]
        for k in range(1, n + 1):
            gk = _galerkin_g(k)
            kpi = k * math.pi
            qu = x[base + k - 1]
            ql = x[base + n + k - 1]
            cor_u = 0.0
            cor_l = 0.0
            for j in range(1, n + 1):
                c = _coriolis(k, j)
                if c != 0.0:
                    cor_u += c * dx[base + j - 1]
                    cor_l += c * dx[base + n + j - 1]
            fu = P[P_GN_U] * gk - 2.0 * speed / lbu * cor_u
            fl = P[P_GN_L] * gk - 2.0 * speed / lbl * cor_l
            if impulse:
                # the pulse trains' mean (the p = 0 term of seed 004 eq 66)
                ek = _galerkin_e(k)
                rate_o = w2 / (2.0 * G[3])
                rate_c = w1 / (2.0 * G[2])
                fu += ((ek - gk) * speed * P[P_PITCH] / r_o * rate_o
                       - ek * speed * P[P_PITCH] / r_c * rate_c)
                fl += ((ek - gk) * speed * P[P_PITCH] / r_c * rate_c
                       - ek * speed * P[P_PITCH] / r_o * rate_o)
            else:
                fu -= 2.0 * speed / lbu * (y2u - y1u) * gk
                fl -= 2.0 * speed / lbl * (y2l - y1l) * gk
            # seed 004 eq 58's (T - rho A S^2) with the span's material tension T = t + rho A S^2
            # (t the elastic tension, plus the centrifugal tension; docs/stability.md): t
            wu2 = t_u / rho * (kpi / lbu) ** 2
            wl2 = t_l / rho * (kpi / lbl) ** 2
            dx[base + 2 * n + k - 1] = (fu - wu2 * qu - 2.0 * P[P_ZETA] * k * P[P_W1_U]
                                        * dx[base + k - 1])
            dx[base + 3 * n + k - 1] = (fl - wl2 * ql - 2.0 * P[P_ZETA] * k * P[P_W1_L]
                                        * dx[base + n + k - 1])
            mid_u += qu * math.sin(0.5 * kpi)
            mid_l += ql * math.sin(0.5 * kpi)
    aux[A_T_UP] = t_u
    aux[A_T_LOW] = t_l
    aux[A_TAU_IN] = tau_in
    aux[A_ACC1] = acc1
    aux[A_ACC2] = acc2
    aux[A_L_UP] = lu
    aux[A_L_LOW] = ll
    aux[A_G_UP] = g_u
    aux[A_G_LOW] = g_l
    aux[A_EV_US] = math.sin(math.pi * uus)
    aux[A_EV_UE] = math.sin(math.pi * uue)
    aux[A_EV_LS] = math.sin(math.pi * uls)
    aux[A_EV_LE] = math.sin(math.pi * ule)
    aux[A_MID_UP] = mid_u
    aux[A_MID_LOW] = mid_l
    aux[A_PHI1] = phi1
    aux[A_W1] = w1
    aux[A_N_UP] = nu
    aux[A_N_LOW] = nl


# --- compiled fixed-step integration over one communication step -----------------------------
# Inputs inside the step: the input-shaft angle as the cubic Hermite interpolant of the source's
# (angle, speed) at both ends and its acceleration the interpolant's second derivative (or the
# source's value when it is the same at both ends); the load torque linear between the ends.
# That is exact for a held input (FMU) and for the scenes' ramp profiles whenever the ramp ends on
# a communication point; the Python steppers sample the source itself.
C_T0, C_DT, C_A0, C_W0, C_A1, C_W1, C_ACC0, C_ACC1, C_L0, C_L1 = range(10)


@jit
def _inputs(t, c):
    dt = c[C_DT]
    s = (t - c[C_T0]) / dt
    s2 = s * s
    s3 = s2 * s
    a0 = c[C_A0]
    a1 = c[C_A1]
    w0 = c[C_W0]
    w1 = c[C_W1]
    th = ((2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * dt * w0 + (3 * s2 - 2 * s3) * a1
          + (s3 - s2) * dt * w1)
    w = ((6 * s2 - 6 * s) / dt * a0 + (3 * s2 - 4 * s + 1) * w0 + (6 * s - 6 * s2) / dt * a1
         + (3 * s2 - 2 * s) * w1)
    if c[C_ACC0] == c[C_ACC1]:
        acc = c[C_ACC0]     # held or constant: the source's own value
    else:
        acc = ((12 * s - 6) * a0 + (6 * s - 4) * dt * w0 + (6 - 12 * s) * a1
               + (6 * s - 2) * dt * w1) / (dt * dt)
    load = c[C_L0] + (c[C_L1] - c[C_L0]) * s
    return th, w, acc, load


@jit
def _rhs_at(t, x, c, G, P, dx, aux):
    th, w, acc, load = _inputs(t, c)
    evaluate(x, th, w, acc, load, G, P, dx, aux)


@jit
def _rk4(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, out):
    _rhs_at(t, x, c, G, P, k1, aux)
    _rk4_from(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, out)


@jit
def _rk4_from(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, out):
    """One RK4 step with k1 = f(t, x) already in ``k1`` (three new evaluations)."""
    n = x.size
    for i in range(n):
        tmp[i] = x[i] + 0.5 * h * k1[i]
    _rhs_at(t + 0.5 * h, tmp, c, G, P, k2, aux)
    for i in range(n):
        tmp[i] = x[i] + 0.5 * h * k2[i]
    _rhs_at(t + 0.5 * h, tmp, c, G, P, k3, aux)
    for i in range(n):
        tmp[i] = x[i] + h * k3[i]
    _rhs_at(t + h, tmp, c, G, P, k4, aux)
    for i in range(n):
        out[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@jit
def _switch(t, x, c, G, P, dx, aux, g):
    _rhs_at(t, x, c, G, P, dx, aux)
    for i in range(6):
        g[i] = aux[A_G_UP + i]


@jit
def _changed(g, g0):
    for i in range(g.size):
        if g[i] * g0[i] < 0.0 and g[i] != 0.0 and g0[i] != 0.0:
            return True
    return False


W_ROWS = 14     # work vectors of the state's size (see _rk4_interval)
V_ROWS = 9      # work vectors of the 6 switching functions: g0, g1, gh, gm, glo, flo, fhi, ga, gb

# Event crossing, the same constants as chainmodel.integrate (tests check they agree): the root
# tolerance on a dense output and the gap eta between the steps on either side of an event, both
# relative to the step h (docs/reduced_models.md, "Numerics").
EVENT_TOL = 1e-5
EVENT_GAP = 1e-4


@jit
def _dense(x0, f0, x1, f1, H, s, out):
    """Dense output at s of a step from (x0, f0) at 0 to (x1, f1) at H: the cubic Hermite
    interpolant (an extrapolation for s > H); for H = 0 the line x0 + s f0."""
    if H == 0.0:
        for i in range(x0.size):
            out[i] = x0[i] + s * f0[i]
        return
    th = s / H
    th2 = th * th
    th3 = th2 * th
    a = 2.0 * th3 - 3.0 * th2 + 1.0
    b = (th3 - 2.0 * th2 + th) * H
    d = (th3 - th2) * H
    for i in range(x0.size):
        out[i] = a * x0[i] + b * f0[i] + (1.0 - a) * x1[i] + d * f1[i]


@jit
def _secant(lo, hi, glo, ghi, g0):
    """Earliest secant root in [lo, hi] among the functions changed between g0 and ghi."""
    best = 1.0e300
    for i in range(6):
        if ghi[i] * g0[i] < 0.0 and ghi[i] != 0.0 and g0[i] != 0.0:
            den = glo[i] - ghi[i]
            if den != 0.0:
                r = lo + (hi - lo) * glo[i] / den
                if r < best:
                    best = r
    if best == 1.0e300 or not math.isfinite(best):
        return 0.5 * (lo + hi)
    return min(max(best, lo), hi)


@jit
def _locate(t, x0, f0, x1, f1, H, lo, hi, g_lo, g_hi, g0, tol, c, G, P, xm, dx, aux, V):
    """Earliest sign change (relative to g0) of the switching functions in [lo, hi] on the dense
    output :func:`_dense` (x0, f0; x1, f1; H), g_lo and g_hi the functions at the ends: safeguarded
    regula falsi (Illinois) to ``tol``, one evaluation per iteration. Returns (s, evaluations), s
    the secant root in the final bracket (chainmodel.integrate.FixedStepper._locate)."""
    gh = V[2]
    gm = V[3]
    glo = V[4]
    flo = V[5]
    fhi = V[6]
    for i in range(6):
        gh[i] = g_hi[i]
        glo[i] = g_lo[i]
        flo[i] = g_lo[i]
        fhi[i] = g_hi[i]
    side = 0
    evals = 0
    for _it in range(100):
        if hi - lo <= tol:
            break
        mid = 1.0e300
        for i in range(6):
            if gh[i] * g0[i] < 0.0 and gh[i] != 0.0 and g0[i] != 0.0:
                den = flo[i] - fhi[i]
                if den != 0.0:
                    r = lo + (hi - lo) * flo[i] / den
                    if r < mid:
                        mid = r
        margin = 1e-3 * (hi - lo)
        if mid == 1.0e300 or not math.isfinite(mid):
            mid = 0.5 * (lo + hi)
        elif mid < lo + margin:
            mid = lo + margin
        elif mid > hi - margin:
            mid = hi - margin
        _dense(x0, f0, x1, f1, H, mid, xm)
        _switch(t + mid, xm, c, G, P, dx, aux, gm)
        evals += 1
        if _changed(gm, g0):
            hi = mid
            for i in range(6):
                gh[i] = gm[i]
                fhi[i] = gm[i]
                if side == -1:
                    flo[i] = 0.5 * flo[i]
            side = -1
        else:
            lo = mid
            for i in range(6):
                glo[i] = gm[i]
                flo[i] = gm[i]
                if side == 1:
                    fhi[i] = 0.5 * fhi[i]
            side = 1
    return _secant(lo, hi, glo, gh, g0), evals


@jit
def _cross(t, x, h, c, G, P, W, V, aux):
    """The step [t, t + h] from ``x`` (f(t, x) in W[3]) over which a switching function changed
    sign (plain step's end state and derivative in W[0], W[8], functions at both ends in V[0],
    V[1]), redone across the first change (the algorithm of chainmodel.integrate.
    FixedStepper._cross; docs/reduced_models.md, "Numerics"):

    1. a first estimate s of the change on the step's cubic Hermite dense output;
    2. one RK4 step to sa = s - eta (eta = EVENT_GAP h), whose state must lie on the old side
       of every function (else s is searched again on the dense output of [t, t + sa]);
    3. s located again on the dense output of the old side alone, (x, f) at t and at t + sa
       extrapolated past sa - the plain step's end state straddled the kink, this does not;
       if s ends up more than 4 eta past sa, back to 2;
    4. across the change to sb = s + eta by the two one-sided slopes (the old side's f over
       [sa, s], the new side's over [s, sb]), sb widened until its state is on the new side;
    5. one RK4 step from sb to t + h, its first stage on the new side.

    No RK4 stage straddles the kink (that costs an error of order jump * h / 6, first order in
    h), and the crossing errs by order eta^2 f' + jump * (error of s). Leaves the state at t + h
    in W[0], f there in W[8], the functions there in V[1]. Returns (s, evaluations)."""
    n = x.size
    xn = W[0]
    xm = W[1]
    xb = W[2]
    k1 = W[3]
    k2 = W[4]
    k3 = W[5]
    k4 = W[6]
    tmp = W[7]
    f1 = W[8]
    xa = W[9]
    fa = W[10]
    xq = W[11]
    fq = W[12]
    fb = W[13]
    g0 = V[0]
    g1 = V[1]
    ga = V[7]
    gb = V[8]
    tol = EVENT_TOL * h
    eta = EVENT_GAP * h
    s, evals = _locate(t, x, k1, xn, f1, h, 0.0, h, g0, g1, g0, tol, c, G, P, xm, tmp, aux, V)
    sa = 0.0
    for _pass in range(8):
        # 2. to sa, on the old side
        for _it in range(20):
            sa = s - eta
            if sa <= 0.0:
                sa = 0.0
                break
            _rk4_from(t, x, sa, c, G, P, k1, k2, k3, k4, tmp, aux, xa)
            _switch(t + sa, xa, c, G, P, fa, aux, ga)
            evals += 4
            if not _changed(ga, g0):
                break
            s, e = _locate(t, x, k1, xa, fa, sa, 0.0, sa, g0, ga, g0, tol, c, G, P, xm, tmp,
                           aux, V)
            evals += e
        if sa == 0.0:
            for i in range(n):
                xa[i] = x[i]
                fa[i] = k1[i]
            for i in range(6):
                ga[i] = g0[i]
        # 3. on the old side's dense output, extrapolated past sa
        sb = min(s + eta, h)
        for _it in range(60):
            _dense(x, k1, xa, fa, sa, sb, xm)
            _switch(t + sb, xm, c, G, P, tmp, aux, gb)
            evals += 1
            if _changed(gb, g0) or sb >= h:
                break
            sb = min(sa + 2.0 * (sb - sa), h)
        if not _changed(gb, g0):
            break                      # no change on the extrapolation: keep the estimate
        if sb - sa <= 4.0 * eta:
            s = _secant(sa, sb, ga, gb, g0)
        else:
            s, e = _locate(t, x, k1, xa, fa, sa, sa, sb, ga, gb, g0, tol, c, G, P, xm, tmp,
                           aux, V)
            evals += e
        if s - sa <= 4.0 * eta:
            break
    # 4. across the change by the one-sided slopes
    if s < sa:
        s = sa
    eta_b = eta
    sb = h
    for _it in range(60):
        sb = min(s + eta_b, h)
        for i in range(n):
            xq[i] = xa[i] + (sb - sa) * fa[i]
        _rhs_at(t + sb, xq, c, G, P, fq, aux)
        for i in range(n):
            xb[i] = xa[i] + (s - sa) * fa[i] + (sb - s) * fq[i]
        _switch(t + sb, xb, c, G, P, fb, aux, gb)
        evals += 2
        if _changed(gb, g0) or sb >= h:
            break
        eta_b *= 8.0
    # 5. the rest of the step
    if sb < h:
        _rk4_from(t + sb, xb, h - sb, c, G, P, fb, k2, k3, k4, tmp, aux, xn)
        _switch(t + h, xn, c, G, P, f1, aux, g1)
        evals += 4
    else:
        for i in range(n):
            xn[i] = xb[i]
            f1[i] = fb[i]
        for i in range(6):
            g1[i] = gb[i]
    return s, evals


@jit
def _rk4_interval(x, t0, n_steps, h, c, G, P, W, V, aux, log, log_at, log_cap):
    """``n_steps`` RK4 steps of size h from (t0, x), in place on ``x``; a step over which a
    switching function changes sign is redone across the change (:func:`_cross`). The first
    ``log_cap`` located event times go to ``log[(log_at + k) % log.size]``. Stops after a step
    that leaves a non-finite state. Returns (events, rhs_evaluations, finite)."""
    n = x.size
    xn = W[0]
    k1 = W[3]
    k2 = W[4]
    k3 = W[5]
    k4 = W[6]
    tmp = W[7]
    f1 = W[8]
    g0 = V[0]
    g1 = V[1]
    evals = 0
    events = 0
    t = t0
    _switch(t, x, c, G, P, k1, aux, g0)
    evals += 1
    finite = True
    for _ in range(n_steps):
        # k1 = f(t, x): the previous evaluation at this (t, x), the switch at the step end
        _rk4_from(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, xn)
        _switch(t + h, xn, c, G, P, f1, aux, g1)
        evals += 4
        if _changed(g1, g0):
            s, e = _cross(t, x, h, c, G, P, W, V, aux)
            evals += e
            if events < log_cap:
                log[(log_at + events) % log.size] = t + s
            events += 1
        t += h
        for i in range(n):
            x[i] = xn[i]
            k1[i] = f1[i]
        for i in range(6):
            g0[i] = g1[i]
        for i in range(n):
            if not math.isfinite(x[i]):
                finite = False
        if not finite:
            break
    return events, evals, finite


@jit
def rk4_advance(x0, t0, n_steps, h, c, G, P, event_times):
    """``n_steps`` RK4 steps of size h from (t0, x0) over one communication step (inputs ``c``,
    see :func:`_inputs`). Returns (x, events, rhs_evaluations); located event times go to
    ``event_times[:events]`` (as many as fit)."""
    x = x0.copy()
    W = np.empty((W_ROWS, x.size))
    V = np.empty((V_ROWS, 6))
    aux = np.empty(A_SIZE)
    events, evals, _ = _rk4_interval(x, t0, n_steps, h, c, G, P, W, V, aux, event_times, 0,
                                     event_times.size)
    return x, events, evals


@jit
def rk4_advance_many(x0, times, steps, angle, speed, acc, load, G, P, states, log, log_cap):
    """:func:`rk4_advance` over the communication steps [times[i-1], times[i]] one after the
    other, with the inputs sampled at the communication points (angle, speed, acc, load: the
    source's values at ``times``) and cubic Hermite inside each step exactly as
    :meth:`~chainmodel.models.torsional.TorsionalModel.advance_compiled` builds them, so the
    states are those of the per-point path. ``steps[i-1]`` RK4 steps in step i; ``states[i]``
    receives the state at ``times[i]`` (``states[0] = x0``). At most ``log_cap`` event times
    per communication step go to the ring buffer ``log`` (in order, from index 0).

    Returns (reached, steps, events, rhs_evaluations, logged): ``reached`` is the index of the
    last state written - len(times) - 1, or the first communication point with a non-finite
    state (the loop stops there)."""
    x = x0.copy()
    W = np.empty((W_ROWS, x.size))
    V = np.empty((V_ROWS, 6))
    aux = np.empty(A_SIZE)
    c = np.empty(10)
    for j in range(x.size):
        states[0, j] = x[j]
    total = 0
    events = 0
    evals = 0
    logged = 0
    for i in range(1, times.size):
        t0 = times[i - 1]
        t1 = times[i]
        c[C_T0] = t0
        c[C_DT] = t1 - t0
        c[C_A0] = angle[i - 1]
        c[C_W0] = speed[i - 1]
        c[C_A1] = angle[i]
        c[C_W1] = speed[i]
        c[C_ACC0] = acc[i - 1]
        c[C_ACC1] = acc[i]
        c[C_L0] = load[i - 1]
        c[C_L1] = load[i]
        m = steps[i - 1]
        e, v, finite = _rk4_interval(x, t0, m, (t1 - t0) / m, c, G, P, W, V, aux, log, logged,
                                     log_cap)
        total += m
        events += e
        evals += v
        logged += min(e, log_cap)
        for j in range(x.size):
            states[i, j] = x[j]
        if not finite:
            return i, total, events, evals, logged
    return times.size - 1, total, events, evals, logged


@jit
def evaluate_many(X, th_in, w_in, a_in, load, G, P, AUX):
    """:func:`evaluate` at every row of X (inputs per row); AUX[i] its auxiliary quantities."""
    dx = np.empty(X.shape[1])
    for i in range(X.shape[0]):
        evaluate(X[i], th_in[i], w_in[i], a_in[i], load[i], G, P, dx, AUX[i])
