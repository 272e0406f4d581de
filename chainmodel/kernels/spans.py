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

``G`` (geometry): theta4s, theta2s, alpha_c, alpha_o, R_c, R_o, x_c, y_c, theta1, n_c, n_o, N, M,
then the seat-direction tables of both sprockets (:func:`geometry_constants`).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit, jit_noalloc
from .span_roles import lower_tight

__all__ = ["geometry_constants", "span_geometry", "G_SIZE"]

_EDGE = 1e-9          # as chainmodel.kinematics.wrapping._EDGE: an endpoint at an event is past it
_HALF_PI = 0.5 * math.pi
_TWO_PI = 2.0 * math.pi
G_SIZE = 13


def geometry_constants(drive) -> np.ndarray:
    """The constant vector ``G`` of a drive (module docstring), followed by the seat-direction
    tables cos(2 pi j / n), sin(2 pi j / n) of the driver (j < n_driver) and of the driven
    sprocket: seat positions by the angle-sum formula, without trigonometry per seat."""
    from ..kinematics import fourbar as fb
    s = fb.seating(drive)
    m = -1 if drive.links is None else drive.links
    head = np.array([s.theta4, s.theta2, math.pi / drive.n_driver, math.pi / drive.n_driven,
                     drive.driver.pitch_radius, drive.driven.pitch_radius, drive.x_c, drive.y_c,
                     drive.centre_angle, drive.n_driver, drive.n_driven, drive.span_pitches, m],
                    float)
    tables = []
    for n in (drive.n_driver, drive.n_driven):
        j = np.arange(n)
        tables += [np.cos(2 * np.pi * j / n), np.sin(2 * np.pi * j / n)]
    return np.concatenate([head] + tables)


@jit_noalloc
def _seat(cx, cy, r, cph, sph, G, table, n, j):
    """Position of seat j (cos and sin of its angle phase + 2 pi j / n too) of a sprocket at
    (cx, cy) with pitch radius r, cph and sph the cosine and sine of its phase; ``table`` the
    offset of its cos/sin table in G."""
    k = int(j)
    # k % n without an integer division for the seats a span meets (-n <= k < 2n)
    if k >= n:
        k = k - n if k < 2 * n else k % n
    elif k < 0:
        k = k + n if k >= -n else k % n
    c = cph * G[table + k] - sph * G[table + n + k]
    s = sph * G[table + k] + cph * G[table + n + k]
    return cx + r * c, cy + r * s, c, s


@jit_noalloc
def _mod_two_pi(v):
    """``v % (2 pi)`` (Python's float modulo), bitwise, without a call to fmod for the values
    _span meets (-2 pi < v < 4 pi): there fmod is exact and equals v, v - 2 pi (exact by
    Sterbenz's lemma) or v (then + 2 pi, rounded as Python rounds it). fmod was a tenth of the
    level-1 stepping time (docs/performance.md, issue 20 third pass)."""
    if 0.0 <= v < _TWO_PI:
        return v + 0.0              # -0.0 % w is +0.0
    if _TWO_PI <= v < 2.0 * _TWO_PI:
        return v - _TWO_PI
    if -_TWO_PI < v < 0.0:
        return v + _TWO_PI
    return v % _TWO_PI


@jit_noalloc
def _span(cfx, cfy, rf, af, phf, cpf, spf, tf, nf, ctx, cty, rt, at, pht, cpt, spt, tt, nt, dir0,
          G):
    """One straight span between two sprockets (scalar form of wrapping._span).

    The endpoints are the fixed point of the window condition: seats j from a direction, the
    direction from those seats, until the seats repeat (usually at the first check). Within
    about _EDGE (seat units) before an event the tolerant window flips between two candidate
    endpoints; after seven checks the strict window decides (as wrapping._span does).

    Returns (length, arm_from, arm_to, j_from, j_to, u_from, u_to, ang_from, ang_to, direction),
    u the un-floored seat coordinates whose integer crossings are the release (from) and
    seating (to) events."""
    edge = _EDGE
    d = dir0
    jf = math.floor((d + _HALF_PI + af - phf) / (2.0 * af) + edge)
    jt = math.floor((d + _HALF_PI + at - pht) / (2.0 * at) + edge)
    ax = ay = bx = by = cf = sf = ct = st = 0.0
    uf = ut = 0.0
    settled = False
    for it in range(14):
        if it == 7:
            edge = 0.0
            jf = math.floor((dir0 + _HALF_PI + af - phf) / (2.0 * af))
            jt = math.floor((dir0 + _HALF_PI + at - pht) / (2.0 * at))
        ax, ay, cf, sf = _seat(cfx, cfy, rf, cpf, spf, G, tf, nf, jf)
        bx, by, ct, st = _seat(ctx, cty, rt, cpt, spt, G, tt, nt, jt)
        nd = math.atan2(by - ay, bx - ax)
        d = dir0 + _mod_two_pi(nd - dir0 + math.pi) - math.pi
        # the seat coordinates of the direction d: once settled, d is final and so are they
        uf = (d + _HALF_PI + af - phf) / (2.0 * af)
        ut = (d + _HALF_PI + at - pht) / (2.0 * at)
        jf2 = math.floor(uf + edge)
        jt2 = math.floor(ut + edge)
        if jf2 == jf and jt2 == jt:
            settled = True
            break
        jf = jf2
        jt = jt2
    if not settled:
        ax, ay, cf, sf = _seat(cfx, cfy, rf, cpf, spf, G, tf, nf, jf)
        bx, by, ct, st = _seat(ctx, cty, rt, cpt, spt, G, tt, nt, jt)
        nd = math.atan2(by - ay, bx - ax)
        d = dir0 + _mod_two_pi(nd - dir0 + math.pi) - math.pi
        uf = (d + _HALF_PI + af - phf) / (2.0 * af)
        ut = (d + _HALF_PI + at - pht) / (2.0 * at)
    dx = bx - ax
    dy = by - ay
    length = math.hypot(dx, dy)
    # arms r sin(angle - direction), the direction's cosine and sine from the span vector
    cd = dx / length
    sd = dy / length
    return (length, rf * (sf * cd - cf * sd), rt * (st * cd - ct * sd), float(jf), float(jt), uf,
            ut, phf + 2.0 * af * jf, pht + 2.0 * at * jt, d)


@jit_noalloc
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
    nc = int(n_c)
    no = int(n_o)
    tc = G_SIZE                 # the driver's cos/sin table
    to = G_SIZE + 2 * nc        # the driven sprocket's
    ph_c = th4s - phi1
    ph_o = th2s - phi2
    cpc = math.cos(ph_c)
    spc = math.sin(ph_c)
    cpo = math.cos(ph_o)
    spo = math.sin(ph_o)
    (lu, aus, aue, jus, jue, uus, uue, gus, gue, du) = _span(0.0, 0.0, r_o, a_o, ph_o, cpo, spo, to,
                                                             no, xc, yc, r_c, a_c, ph_c, cpc, spc,
                                                             tc, nc, 0.0, G)
    (ll, als, ale, jls, jle, uls, ule, gls, gle, dl) = _span(xc, yc, r_c, a_c, ph_c, cpc, spc, tc,
                                                             nc, 0.0, 0.0, r_o, a_o, ph_o, cpo,
                                                             spo, to, no, math.pi + 2.0 * th1, G)
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
P_SOFT = 27          # floor a [N] under the slack span (torsional.wrap_statics; 0: none)
P_SAG_U, P_SAG_L = 28, 29   # sag term S [N^2 m] of each straight span (level 1; 0: none)
P_SAGC_U, P_SAGC_L = 30, 31  # (S k_eff)^(1/3) [N] at the tooth-period-mean link count (0: none)
# k_eff [N/m] and c_link / n [N s/m] of each span at its tooth-period-mean link count
# (torsional.mean_link_compliance: constant, so computed once; 0: from the current count)
P_KEFF_U, P_KEFF_L, P_CN_U, P_CN_L = 32, 33, 34, 35
#: level 1's lagged sag relaxes at this share of the span's first string frequency. The string
#: frequency itself: an independent audit found that at an eighth of it a slack span took
#: seconds to hang on its new sag after a load step (a 10B drive stepped from 30 to 90 N m:
#: 3.6 N for half a second where level 3 carries 34-40 N within 0.1 s; here 0.2-0.5 s) and a
#: drive near a resonance (08B 11/45 at 1000 rpm) settled in two different states after a load
#: step and at a constant load. Its cost: a first-order lag dissipates near its corner, so a
#: torsional mode lying just above its spans' string modes is damped more (C1's 24 Hz mode:
#: 1.26 % of critical against 0.45 % without the lag and level 3's 0.47 %; on eight other
#: drives the lag moves the damping by less than 0.1 point); docs/reduced_models.md
LAG_RATE = 1.0
P_INV_J22, P_INV_DET = 36, 37   # 1 / J22 and 1 / (J11 J22 - J12^2) of the constant mass matrix
#: level 1's lagged sag (torsional.sag_lag): 1 when each straight span's sag follows its
#: stretch through a state (the tension T_q its sag hangs at, :func:`_lagged`), 0 otherwise;
#: P_LAG_QS 1: the quasi-static law, T_q the law's at the span's elastic tension (the
#: equilibrium's evaluations, and level 1's statics)
P_LAG, P_LAG_QS = 38, 39
#: the lag's rate as a share of the span's first string frequency (LAG_RATE)
P_LAG_RATE = 40
#: the span roles' hold (span_roles.lower_tight): +1 upper tight, -1 lower, 0 from the inputs
P_ROLE = 41
#: the share of level 1's lag rate the step rule counts as a frequency: a decay needs fewer
#: steps than an oscillation of its rate (RK4 is stable on it to h lambda = 2.785, and the
#: state only follows its target); at the default tolerance (h w = 0.507) h lambda <= 2
LAG_SHARE = 0.25
#: the least mean tension a span carries under the weight along it [N] (span_sag.
#: hanging_tension; 0: none): neither span's law goes below it
P_HANG = 42
P_SIZE = 43

# --- auxiliary outputs of the kernel ----------------------------------------------------------
(A_T_UP, A_T_LOW, A_TAU_IN, A_ACC1, A_ACC2, A_L_UP, A_L_LOW, A_G_UP, A_G_LOW, A_EV_US, A_EV_UE,
 A_EV_LS, A_EV_LE, A_MID_UP, A_MID_LOW, A_PHI1, A_W1, A_N_UP, A_N_LOW,
 A_LOWER_TIGHT) = range(20)
#: each span's sag tension T_q [N] (level 1's lagged sag: its state; at rest the quasi-static
#: law's), and the larger of the two spans' rates the step rule counts [1/s] (_lagged)
A_LAG_UP, A_LAG_LOW, A_LAG_W = 20, 21, 22
A_SIZE = 23


@jit_noalloc
def _galerkin_g(k):
    """G_m of seed 004 eq 59: 2 int_0^1 sin(m pi x) dx."""
    return 2.0 * (1.0 - (-1.0) ** k) / (k * math.pi)


@jit_noalloc
def _galerkin_e(k):
    """E_m of seed 004 eq 59: 2 int_0^1 x sin(m pi x) dx."""
    return -2.0 * (-1.0) ** k / (k * math.pi)


@jit_noalloc
def _coriolis(k, j):
    """Gyroscopic Galerkin coefficient of 2 s w_xt on sin modes: 2 int_0^1 sin(k pi x)
    j pi cos(j pi x) dx * 2 / 2 = 2 k j (1 - (-1)^(k+j)) / (k^2 - j^2), zero for k = j.
    (Seed 004 eq 59 prints k^2 + j^2 in the denominator; the projection gives k^2 - j^2, which
    makes the matrix skew-symmetric as a gyroscopic term must be.)"""
    if k == j:
        return 0.0
    return 2.0 * k * j * (1.0 - (-1.0) ** (k + j)) / (k * k - j * j)


@jit_noalloc
def _sagging(raw, s_over_d, cube_root=0.0):
    """The positive root T of T^3 - raw T^2 - s_over_d = 0 (models/span_sag.py ``tension``,
    the elastic catenary), written for the stepping loop's cost (a few divisions, no loop).
    With e = s_over_d / raw^3 and T = raw (1 + x), x (1 + x)^2 = e:

    * e < 0.02 (a taut span): x's series, a_n = (-1)^(n-1) C(3n-2, n-1) / n (Lagrange inversion,
      radius 4/27), eight terms;
    * e < 0.2: its Pade approximant [2/2], x = e (1 + 10 e / 3) / (1 + 16 e / 3 + 11 e^2 / 3)
      (within 4e-4 of x), and one Halley step (cubic convergence);
    * else (a span hanging on its sag): in units of c = s_over_d^(1/3) (``cube_root`` when the
      caller has it, else computed), y = T / c solves y^2 (y - r) = 1 with r = raw / c; a start
      within 6 % (r + 1 / (1 + r^2) for r >= 0, 1 / sqrt(1 - r) below) and two Halley steps.

    Within 3e-10 of the root everywhere (tests/test_span_sag.py), and smooth: no iteration
    count depends on the input."""
    r3 = raw * raw * raw
    if r3 > 50.0 * s_over_d:
        e = s_over_d / r3
        x = e * (1.0 + e * (-2.0 + e * (7.0 + e * (-30.0 + e * (143.0 + e * (-728.0 + e * (
            3876.0 - 21318.0 * e)))))))
        return raw * (1.0 + x)
    if r3 > 5.0 * s_over_d:
        # the Pade approximant in e = s / r3, over one denominator
        t = raw * (1.0 + s_over_d * (3.0 * r3 + 10.0 * s_over_d)
                   / (r3 * (3.0 * r3 + 16.0 * s_over_d) + 11.0 * s_over_d * s_over_d))
        steps = 1
    else:
        c = cube_root if cube_root > 0.0 else s_over_d ** (1.0 / 3.0)
        # c y's start: raw + s / (c^2 + raw^2) for raw >= 0, sqrt(s / (c - raw)) below
        if raw >= 0.0:
            t = raw + s_over_d / (c * c + raw * raw)
        else:
            t = math.sqrt(s_over_d / (c - raw))
        steps = 2
    for _ in range(steps):
        f = t * t * (t - raw) - s_over_d
        d1 = t * (3.0 * t - 2.0 * raw)
        t -= 2.0 * f * d1 / (2.0 * d1 * d1 - f * (6.0 * t - 2.0 * raw))
    return t


@jit_noalloc
def _softplus(raw, floor):
    """The wrap's floor under a span: (raw + sqrt(raw^2 + 4 b^2)) / 2, raw + b^2 / raw well
    above b, b at raw = 0, written without cancellation for raw < 0 (wrap_statics.softplus,
    its Python twin; wrap_statics.py)."""
    root = math.sqrt(raw * raw + 4.0 * floor * floor)
    return 0.5 * (raw + root) if raw > 0.0 else 2.0 * floor * floor / (root - raw)


@jit_noalloc
def _floored_sag(raw, floor, ks, ks_root=0.0):
    """The positive root T of T - floor^2 / T - ks / T^2 = raw: the wrap's floor and a span's
    quasi-static sag in one law, T = softplus(raw + ks / T^2, floor) (wrap_statics._floored).
    For ks = 0 or floor = 0 the closed forms (the floor's hyperbola; :func:`_sagging`, the
    elastic catenary); with both, three Halley steps on the cubic T^3 - raw T^2 - floor^2 T -
    ks = 0 from the larger of the two one-term roots, each below the root: within 1e-11
    relative over raw in [-3000, 3000] N, floor in [0.1, 500] N and ks in [1, 1e10] N^3
    (measured), at a fixed cost (no loop whose count depends on the input)."""
    if ks <= 0.0:
        return _softplus(raw, floor) if floor > 0.0 else max(raw, 0.0)
    t = _sagging(raw, ks, ks_root)
    if floor <= 0.0:
        return t
    b2 = floor * floor
    t_floor = _softplus(raw, floor)
    if t_floor > t:
        t = t_floor
    for _ in range(3):
        f = t * (t * (t - raw) - b2) - ks
        d1 = t * (3.0 * t - 2.0 * raw) - b2
        t -= 2.0 * f * d1 / (2.0 * d1 * d1 - f * (6.0 * t - 2.0 * raw))
    return t


@jit_noalloc
def _lagged(raw, raw_elastic, lagged, quasi_static, floor, ks, ks_root, rho, lbar, share):
    """Level 1's span law with a lagged sag (torsional.sag_lag; docs/reduced_models.md,
    "Level 1's lagged sag").

    A straight span's chain hangs in its sag, whose extra arc S / T^2 (S = w_n^2 L^3 / 24,
    the elastic catenary) it must cover. The sag cannot follow the span's stretch faster than
    the span's first string mode lets it. The state T_q (``lagged``) is the tension at which
    the sag hangs: the quasi-static law at a lagged elastic tension r (:func:`_floored_sag`:
    T_q - floor^2 / T_q - k S / T_q^2 = r), r relaxing to the span's own elastic tension,
    dr/dt = lambda (raw_elastic - r), lambda = s omega_1, omega_1 = pi / lbar sqrt(T_q / rho)
    the first string frequency at T_q (s = ``share``, LAG_RATE); so dT_q/dt = lambda
    (raw_elastic - r) / (1 + floor^2 / T_q^2 + 2 k S / T_q^3), r explicit in T_q (no root per
    evaluation; the exact change of variables of the linear law in r, so the same solution).
    Where a span dips slack within a tooth its T_q moves fast relative to itself; the step
    rule counts that relative rate (the fourth value), so no stage takes T_q below zero (the
    first version, at the full string frequency and without it, put an unbounded sag into C1
    at a sudden 400 rpm: 1e26 N), and a step whose span went slack after its start, moving
    T_q by more than a factor of two, is retried shorter (:func:`lag_step_kept`). The span
    carries T = softplus(raw + k S / T_q^2, floor): slowly, the quasi-static elastic catenary
    (the static sag, a slack span hanging on its sag tension under load); well above lambda the sag is frozen and the span is elastic (the
    torsional mode above the spans' string modes, which the static sag's softness would pull
    down). ``quasi_static``: T_q is the law's at raw_elastic itself (statics), dT_q/dt = 0.

    Returns (T, the sag's tension T_q, dT_q/dt, the step rule's rate [1/s])."""
    if quasi_static:
        tq = _floored_sag(raw_elastic, floor, ks, ks_root)
    else:
        tq = lagged if lagged > 1e-9 else 1e-9
    sag = ks / (tq * tq)
    total = raw + sag
    if floor > 0.0:
        t = _softplus(total, floor)
    else:
        t = total if total > 0.0 else 0.0
    rate = share * math.pi / lbar * math.sqrt(tq / rho)
    if quasi_static:
        return t, tq, 0.0, LAG_SHARE * rate
    b2 = floor * floor / (tq * tq)
    dtq = rate * (raw_elastic - tq * (1.0 - b2) + sag) / (1.0 + b2 + 2.0 * sag / tq)
    # for the step rule: the larger of the decay's (a share of its rate) and the state's own
    # relative rate |dT_q/dt| / T_q, which a span dipping slack within a tooth drives far past
    # it (rk4_loop.omega_estimate: a step then moves T_q by at most h w of itself)
    speed = abs(dtq) / tq
    return t, tq, dtq, (LAG_SHARE * rate if LAG_SHARE * rate > speed else speed)


@jit_noalloc
def lag_index(P):
    """Index of the upper span's sag tension T_q in the state (the lower span's follows it):
    after the sprockets' states (2 rigid, 4 elastic) and any span modes' (4 per mode)."""
    return (2 if P[P_RIGID] > 0.5 else 4) + 4 * int(P[P_MODES])


@jit_noalloc
def lag_step_kept(x, xn, P):
    """False when a step took a span's sag tension T_q (level 1's lagged sag) to below half or
    above twice its value at the step's start: the step rule's rate (:func:`_lagged`) is the
    start's, and a span going slack within the step can drive an RK4 stage of T_q through
    zero, after which its sag term k S / T_q^2 is unbounded (C1 started suddenly at 400 rpm
    through the FMU at 2-10 ms communication steps: 1e24 N). The loop then retries the step
    at a quarter of its length (rk4_loop._interval); a step the rule bounds moves T_q by at
    most h w = 0.5 of itself, so this only catches the rule's start-of-step estimate failing."""
    if P[P_LAG] < 0.5:
        return True
    k = lag_index(P)
    for i in range(k, k + 2):
        if not (0.5 * x[i] <= xn[i] <= 2.0 * x[i]):
            return False
    return True


@jit_noalloc
def span_stiffness(links_compliance, k_link, c_link, seat_c):
    """(k_eff [N/m], c_link / n [N s/m]) of a span of ``links_compliance`` links with the seats'
    compliance in series (:func:`_tension`); the model precomputes them where the count is the
    tooth-period mean (P_KEFF_*, P_CN_*), the kernel otherwise."""
    return 1.0 / (links_compliance / k_link + seat_c), c_link / links_compliance


@jit_noalloc
def free_length(links, nbar, pitch, p_free):
    """The free length of the chain in a span of ``links`` links (its current count), whose
    stretch delta = l - free_length - f the span law takes up.

    With the span's stiffness from its own count (``nbar`` 0) that is n p_free: at a seating or
    release the chord l changes by a pitch, the free length by p_free and k_link / n by a link,
    so the tension is continuous where each link carries the pretension T_pre =
    chain.pretension (at rest) and jumps by the rest, (T - T_pre) / (n - 1), under load. With
    the tooth-period-mean count n_bar (torsional.mean_link_compliance: a seating roller's link
    keeps its elongation on the sprocket) the free length is n p - n_bar (p - p_free): the
    stretch is continuous through every event. With n p_free there it jumped by p - p_free at
    every event, a tension step of T_pre / n_bar at the meshing frequency (the 16B mixer at a
    20 kN static tension: 721 N; at its own 1200 N, 79 N), which pumped a driver oscillation
    4.7 times level 3's and made the chain return 3.4 W more than it took in (the
    twenty-fourth session's audit; docs/reduced_models.md). The tooth-period means are the
    same either way."""
    if nbar > 0.0:
        return links * pitch - nbar * (pitch - p_free)
    return links * p_free


@jit_noalloc
def _tension(length, stretch_modal, stretch_rate, free, k_eff, c_n,
             seat_slack, length_rate, soft=0.0, sag=0.0, sag_root=0.0):
    """Span tension from its stretch (a span cannot push) and the switching function whose sign
    change marks the switch: min(k delta, T_raw), continuous through both ways of going slack.

    The stretch is the span's chord beyond the free length of the chain in it (``free``,
    :func:`free_length`); its stiffness k_eff and damping c_n (:func:`span_stiffness`) use the
    span's current count, or the tooth-period mean (torsional.mean_link_compliance): a seating
    roller's link keeps its elongation on the sprocket, so the span does not stiffen by a whole
    link at the event and the tension stays continuous.

    ``sag`` > 0 (level 1's straight spans under their weight, S = w_n^2 L^3 / 24): the span's
    chord is shorter than the chain in it by its quasi-static sag S / T^2, so
    T^3 - T_raw T^2 - S k_eff = 0 (:func:`_sagging`; ``sag_root`` its (S k_eff)^(1/3) where
    the caller has it): a span whose stretch runs out hangs on its sag tension instead of going
    slack (docs/reduced_models.md, "One static tension")."""
    delta = length + stretch_modal - free - seat_slack
    raw = k_eff * delta + c_n * (length_rate + stretch_rate)
    switch = min(k_eff * delta, raw)
    if sag > 0.0:
        return _sagging(raw, sag * k_eff, sag_root), switch
    if soft > 0.0:
        # the wrap's floor under the slack span (wrap_statics.py)
        return _softplus(raw, soft), switch
    if switch > 0.0:
        return raw, switch
    return 0.0, switch


@jit_noalloc
def _tension_lagged(length, free, k_eff, c_n, seat_slack, length_rate, lagged,
                    quasi_static, floor, sag, sag_root, rho, lbar, share):
    """:func:`_tension` with level 1's lagged sag (:func:`_lagged`): (T, switch, the sag's
    tension T_q, dT_q/dt, lag rate). Without a floor the switch min(k delta, T_raw) + the
    sag's offset changes sign where the span goes slack (the law's kink); under a floor the
    law has no kink and the switch is the tension itself, never zero (no event to locate)."""
    delta = length - free - seat_slack
    elastic = k_eff * delta
    raw = elastic + c_n * length_rate
    ks = sag * k_eff
    t, tq, dtq, rate = _lagged(raw, elastic, lagged, quasi_static, floor, ks, sag_root, rho,
                               lbar, share)
    if floor > 0.0:
        return t, t, tq, dtq, rate
    return t, min(elastic, raw) + ks / (tq * tq), tq, dtq, rate


@jit_noalloc
def evaluate(x, th_in, w_in, a_in, load, G, P, dx, aux):
    """Right-hand side ``dx`` and auxiliary quantities ``aux`` (A_* indices) of levels 1-2
    (:func:`_evaluate`)."""
    _evaluate(x, th_in, w_in, a_in, load, G, P, dx, aux, True)


@jit_noalloc
def evaluate_rate(x, th_in, w_in, a_in, load, G, P, dx, aux):
    """:func:`evaluate` for a stage of a step, whose auxiliary quantities nobody reads: ``dx``
    bitwise the same, but aux's seat-event functions (A_EV_*), midspan deflections and span
    roles are not computed (left as they were) - four sines of the five of a level-1
    evaluation, the costliest part after the two spans' atan2 (docs/performance.md)."""
    _evaluate(x, th_in, w_in, a_in, load, G, P, dx, aux, False)


@jit_noalloc
def _evaluate(x, th_in, w_in, a_in, load, G, P, dx, aux, full):
    """Right-hand side ``dx`` and auxiliary quantities ``aux`` (A_* indices) of levels 1-2
    (``full`` False: :func:`evaluate_rate`).

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
    if P[P_KEFF_U] > 0.0:
        ke_u, cn_u = P[P_KEFF_U], P[P_CN_U]
    else:
        ke_u, cn_u = span_stiffness(nu, P[P_K_LINK], P[P_C_LINK], P[P_SEAT_C])
    if P[P_KEFF_L] > 0.0:
        ke_l, cn_l = P[P_KEFF_L], P[P_CN_L]
    else:
        ke_l, cn_l = span_stiffness(nl, P[P_K_LINK], P[P_C_LINK], P[P_SEAT_C])
    free_u = free_length(nu, P[P_NBAR_U], P[P_PITCH], p_free)
    free_l = free_length(nl, P[P_NBAR_L], P[P_PITCH], p_free)
    if P[P_LAG] > 0.5:
        # level 1's lagged sag: states T_q,up, T_q,low after the sprockets' (and any modes')
        lag = lag_index(P)
        qs = P[P_LAG_QS] > 0.5
        rho = P[P_RHOA]
        t_u, g_u, q_u, dx[lag], w_u = _tension_lagged(
            lu, free_u, ke_u, cn_u, P[P_SEAT_SLACK], rate_u, x[lag], qs, P[P_SOFT],
            P[P_SAG_U], P[P_SAGC_U], rho, P[P_LBAR_U], P[P_LAG_RATE])
        t_l, g_l, q_l, dx[lag + 1], w_l = _tension_lagged(
            ll, free_l, ke_l, cn_l, P[P_SEAT_SLACK], rate_l, x[lag + 1], qs, P[P_SOFT],
            P[P_SAG_L], P[P_SAGC_L], rho, P[P_LBAR_L], P[P_LAG_RATE])
        aux[A_LAG_UP] = q_u
        aux[A_LAG_LOW] = q_l
        aux[A_LAG_W] = w_u if w_u > w_l else w_l
    else:
        t_u, g_u = _tension(lu, s_u, sr_u, free_u, ke_u, cn_u, P[P_SEAT_SLACK], rate_u,
                            P[P_SOFT], P[P_SAG_U], P[P_SAGC_U])
        t_l, g_l = _tension(ll, s_l, sr_l, free_l, ke_l, cn_l, P[P_SEAT_SLACK], rate_l,
                            P[P_SOFT], P[P_SAG_L], P[P_SAGC_L])
        aux[A_LAG_UP] = 0.0
        aux[A_LAG_LOW] = 0.0
        aux[A_LAG_W] = 0.0
    # a span whose law would leave it below the weight along it hangs from its upper end, its
    # lower end looping off the sprocket (span_sag.hanging_tension)
    hang = P[P_HANG]
    if t_u < hang:
        t_u = hang
    if t_l < hang:
        t_l = hang
    # --- sprockets: seed 004 eq 50 (driven), shaft spring of seed 003 eq 14 (driver)
    q2 = t_u * aus - t_l * ale - P[P_D2] * w2 - load
    j11 = P[P_J11]
    j12 = P[P_J12]
    j22 = P[P_J22]
    if rigid:
        acc1 = a_in
        acc2 = (q2 - j12 * a_in) * P[P_INV_J22]
        tau_in = j11 * a_in + j12 * acc2 + t_u * aue - t_l * als
        dx[0] = w2
        dx[1] = acc2
    else:
        tau_in = P[P_K_SHAFT] * (th_in - phi1) + P[P_C_SHAFT] * (w_in - w1)
        q1 = tau_in - t_u * aue + t_l * als
        inv_det = P[P_INV_DET]
        acc1 = (j22 * q1 - j12 * q2) * inv_det
        acc2 = (j11 * q2 - j12 * q1) * inv_det
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
            if full:
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
    aux[A_PHI1] = phi1
    aux[A_W1] = w1
    aux[A_N_UP] = nu
    aux[A_N_LOW] = nl
    if not full:
        return
    aux[A_EV_US] = math.sin(math.pi * uus)
    aux[A_EV_UE] = math.sin(math.pi * uue)
    aux[A_EV_LS] = math.sin(math.pi * uls)
    aux[A_EV_LE] = math.sin(math.pi * ule)
    aux[A_MID_UP] = mid_u
    aux[A_MID_LOW] = mid_l
    # span roles by power flow, from the inputs (chainmodel.kernels.span_roles)
    aux[A_LOWER_TIGHT] = 1.0 if lower_tight(load, P[P_D2], P[P_J22], G[9] / G[10], w_in,
                                            a_in, P[P_ROLE]) else 0.0


@jit
def evaluate_many(X, th_in, w_in, a_in, load, G, P, AUX):
    """:func:`evaluate` at every row of X (inputs per row); AUX[i] its auxiliary quantities."""
    dx = np.empty(X.shape[1])
    for i in range(X.shape[0]):
        evaluate(X[i], th_in[i], w_in[i], a_in[i], load[i], G, P, dx, AUX[i])
