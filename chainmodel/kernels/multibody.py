"""Force kernels and fixed-step loops of the multibody model (level 3), in two implementations
that compute the same thing: explicit loops compiled by numba (fast path) and vectorised numpy
(fallback for environments without numba, and the tested twin of the compiled path).

The equations are derived in docs/multibody.md from the Lagrangian of seed 003's appendix
(kinetic energy T eq A1, deformation energy U eq A2, dissipation S eq A3; Lagrange's equation
eq 11); :mod:`chainmodel.models.multibody` explains the choices. Coordinates (lead's XY frame of
seed 000/004): q = [phi1, phi2, x_0, y_0, x_1, y_1, ...], v = dq/dt, with phi1 (driver) and phi2
(driven) forward-positive, i.e. clockwise in XY. A seat j of sprocket s sits at angle
``phase0_s - phi_s + (2 pi / z_s) j`` about the sprocket centre.

Set the environment variable ``CHAINMODEL_NUMBA=0`` to force the numpy path (chainmodel._numba).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import ENABLED, enabled, njit
from .span_roles import lower_tight
from ..outputs import OUTPUT_NAMES  # noqa: F401  (re-exported: MultibodyModel reads it here)
from ..outputs import (O_CHAIN_MAX_LINK_TENSION, O_CHAIN_MIN_LINK_TENSION, O_CONTACT_MAX_FORCE,
                      O_DRIVEN_ACCELERATION, O_DRIVEN_ANGLE, O_DRIVEN_SPEED,
                      O_DRIVER_ANGLE, O_DRIVER_SPEED, O_INPUT_SHAFT_TORQUE, O_SLACK_SPAN_TENSION,
                      O_TIGHT_SPAN_LENGTH, O_TIGHT_SPAN_MIDSPAN_DEFLECTION, O_TIGHT_SPAN_TENSION,
                      O_TRANSMISSION_ERROR, O_VELOCITY_RATIO)

__all__ = ["HAVE_NUMBA", "numba_enabled", "accel_numpy", "accel_numba", "run_fixed_numba",
           "PARAM_FIELDS", "N_PARAMS"]

# layout of the float64 parameter vector handed to the kernels
PARAM_FIELDS = (
    "m", "k", "c", "l0", "kc", "cc", "clearance", "gx", "gy", "I1", "I2", "kr", "cr", "c2",
    "cx", "cy", "R1", "R2", "phase1", "phase2", "pitch_angle1", "pitch_angle2",
    "sin_gamma1", "cos_gamma1", "sin_gamma2", "cos_gamma2", "tip1", "tip2", "paper_contact",
    "paper_damping", "q_forces", "rigid_shaft", "l_min", "l_max", "z1", "z2", "reach1",
    "reach2", "cj", "gap", "onset",
)
(I_M, I_K, I_C, I_L0, I_KC, I_CC, I_DR, I_GX, I_GY, I_I1, I_I2, I_KR, I_CR, I_C2,
 I_CX, I_CY, I_R1, I_R2, I_PH1, I_PH2, I_TA1, I_TA2, I_SG1, I_CG1, I_SG2, I_CG2, I_TIP1, I_TIP2,
 I_PAPER_CONTACT, I_PAPER_DAMP, I_QF, I_RIGID, I_LMIN, I_LMAX, I_Z1, I_Z2, I_REACH1,
 I_REACH2, I_CJ, I_GAP, I_ONSET) = range(len(PARAM_FIELDS))
#: P holds these scalars, then the tables cos(2 pi j / z1), sin(...) (j < z1), then the same
#: for z2 (see :func:`pack_tables`): seat directions without trigonometry in the hot loop
N_PARAMS = len(PARAM_FIELDS)


def pack_tables(P: np.ndarray) -> np.ndarray:
    """P with the seat-direction tables appended (z1, z2 taken from P)."""
    z1, z2 = int(P[I_Z1]), int(P[I_Z2])
    j1, j2 = np.arange(z1), np.arange(z2)
    return np.concatenate([P[:N_PARAMS], np.cos(2 * np.pi * j1 / z1), np.sin(2 * np.pi * j1 / z1),
                           np.cos(2 * np.pi * j2 / z2), np.sin(2 * np.pi * j2 / z2)])

#: the one numba switch (chainmodel._numba.ENABLED), under its old name
HAVE_NUMBA = ENABLED


def numba_enabled() -> bool:
    """chainmodel._numba.enabled(): the compiled kernels exist and CHAINMODEL_NUMBA does not
    switch them off."""
    return enabled()


# --- explicit-loop kernel (compiled by numba) -------------------------------------------------

#: rows of the scratch vector ``scr`` (each M long): the links' angular speed, then what the
#: positions give and the velocities reuse (:func:`_geometry_loops`): per link its direction,
#: chord, length, spring force, damping coefficient and branch (1 stretched, -1 bearing, 0 in
#: the play); per roller and sprocket the seat penetration (<= 0: no contact), contact normal,
#: position relative to the sprocket centre and seat direction
(R_OMEGA, R_EX, R_EY, R_DX, R_DY, R_L, R_TS, R_CL, R_BRANCH) = range(9)
R_CONTACT = 9           # + 7 s + (0 pen, 1 nx, 2 ny, 3 rx, 4 ry, 5 st, 6 ct), s = 0 driver, 1 driven
SCR_ROWS = R_CONTACT + 14


def _accel_loops(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, dist, seat_angle,
                 scr):
    """Accelerations ``a`` (same layout as q) and diagnostics; returns (status, shaft torque).

    status 0: fine; 1: a link is stretched or compressed beyond [l_min, l_max] or a
    coordinate is not finite (the integration has diverged).
    tension[i]: axial force of link i (roller i to roller i+1), positive in tension.
    fcon[i]: normal contact force on roller i; side[i]: 0 free, 1 driver, 2 driven.
    dist[s, i]: distance of roller i from the nearest seat centre of sprocket s.
    seat_angle[s, i]: angle of that seat about the sprocket centre.
    scr: scratch, SCR_ROWS rows of M (the angular velocity of link i in its first row).

    Two passes: :func:`_geometry_loops` (everything the positions give: link lengths and
    directions, spring forces, seat search and penetrations) and :func:`_forces_loops` (the
    forces with the velocities), the same arithmetic in the same order as one pass; the Verlet
    loop runs the second pass again at a step's end velocity without the first.
    """
    status = _GEOM(q, tau, P, dist, seat_angle, scr)
    return _FORCES(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, seat_angle, scr,
                   status)


def _geometry_loops(q, tau, P, dist, seat_angle, scr):
    """The position-dependent part of :func:`_accel_loops` into ``scr`` (rows R_*), ``dist``
    and ``seat_angle``; returns 1 if a link is outside [l_min, l_max], else 0."""
    n = q.shape[0]
    M = (n - 2) // 2
    k = P[I_K]
    c = P[I_C]
    l0 = P[I_L0]
    dR = P[I_DR]
    paper_contact = P[I_PAPER_CONTACT] != 0.0
    rigid = P[I_RIGID] != 0.0
    lmin = P[I_LMIN]
    lmax = P[I_LMAX]
    if rigid:
        phi1 = tau
    else:
        phi1 = q[0]
    phi2 = q[1]
    status = 0
    # links (tension-only with the joints' free play, docs/multibody.md "Links carry no
    # compression"): U = k/2 e^2 for e = |d| - l0 > 0, 0 over the pin-bushing play
    # -gap <= e <= 0, k/2 (e + gap)^2 beyond it (plates bearing); the damping rises from 0
    # over the first ``onset`` of engagement (Hunt-Crossley: no force jump when a link snaps
    # taut)
    gap = P[I_GAP]
    onset = P[I_ONSET]
    for i in range(M):
        j = i + 1
        if j == M:
            j = 0
        dx = q[2 + 2 * j] - q[2 + 2 * i]
        dy = q[3 + 2 * j] - q[3 + 2 * i]
        L = math.sqrt(dx * dx + dy * dy)
        if not (L > lmin and L < lmax):
            status = 1
            if not L > 0.0:
                L = 1e-300
        e = L - l0
        if e > 0.0:
            Ts = k * e
            cl = c if e >= onset else c * e / onset
            branch = 1.0
        elif e < -gap:
            Ts = k * (e + gap)
            cl = c if -gap - e >= onset else c * (-gap - e) / onset
            branch = -1.0
        else:
            Ts = 0.0
            cl = 0.0
            branch = 0.0
        scr[R_EX * M + i] = dx / L
        scr[R_EY * M + i] = dy / L
        scr[R_DX * M + i] = dx
        scr[R_DY * M + i] = dy
        scr[R_L * M + i] = L
        scr[R_TS * M + i] = Ts
        scr[R_CL * M + i] = cl
        scr[R_BRANCH * M + i] = branch
    # roller-seat contact (eqs 5-10 with the seat/flank profile, see module docstring)
    z1 = int(P[I_Z1])
    z2 = int(P[I_Z2])
    ph1 = P[I_PH1] - phi1
    ph2 = P[I_PH2] - phi2
    cph1 = math.cos(ph1)
    sph1 = math.sin(ph1)
    cph2 = math.cos(ph2)
    sph2 = math.sin(ph2)
    for i in range(M):
        x = q[2 + 2 * i]
        y = q[3 + 2 * i]
        for s in range(2):
            row = (R_CONTACT + 7 * s) * M + i
            if s == 0:
                cx = P[I_CX]
                cy = P[I_CY]
                R = P[I_R1]
                ph = ph1
                cph = cph1
                sph = sph1
                ta = P[I_TA1]
                tip = P[I_TIP1]
                sg = P[I_SG1]
                cg = P[I_CG1]
                zt = z1
                tab = N_PARAMS
                reach = P[I_REACH1]
            else:
                cx = 0.0
                cy = 0.0
                R = P[I_R2]
                ph = ph2
                cph = cph2
                sph = sph2
                ta = P[I_TA2]
                tip = P[I_TIP2]
                sg = P[I_SG2]
                cg = P[I_CG2]
                zt = z2
                tab = N_PARAMS + 2 * z1
                reach = P[I_REACH2]
            rx = x - cx
            ry = y - cy
            if rx * rx + ry * ry > reach * reach:
                # beyond the tooth tips: no seat can touch this roller
                dist[s, i] = math.inf
                seat_angle[s, i] = 0.0
                scr[row] = -1.0
                continue
            jj = math.floor((math.atan2(ry, rx) - ph) / ta + 0.5)
            th = ph + ta * jj
            jm = jj % zt
            ct = cph * P[tab + jm] - sph * P[tab + zt + jm]
            st = sph * P[tab + jm] + cph * P[tab + zt + jm]
            dx = rx - R * ct
            dy = ry - R * st
            d = math.sqrt(dx * dx + dy * dy)
            dist[s, i] = d
            seat_angle[s, i] = th
            pen = -1.0
            nx = 0.0
            ny = 0.0
            if paper_contact:
                if rx * rx + ry * ry <= R * R and d > dR:
                    pen = d - dR
                    nx = dx / d
                    ny = dy / d
            else:
                sl = dx * ct + dy * st
                if sl <= tip and d > 0.0:
                    if -sl >= d * cg:
                        pen = d - dR
                        nx = dx / d
                        ny = dy / d
                    else:
                        tl = -dx * st + dy * ct
                        sgn = 1.0 if tl >= 0.0 else -1.0
                        pen = abs(tl) * sg - sl * cg - dR
                        nx = -sgn * sg * st - cg * ct
                        ny = sgn * sg * ct - cg * st
            scr[row] = pen
            scr[row + M] = nx
            scr[row + 2 * M] = ny
            scr[row + 3 * M] = rx
            scr[row + 4 * M] = ry
            scr[row + 5 * M] = st
            scr[row + 6 * M] = ct
    return status


def _forces_loops(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, seat_angle, scr,
                  status):
    """The forces of :func:`_accel_loops` at the velocities ``v``, from the positions' part
    that :func:`_geometry_loops` left in ``scr``; ``status`` its status. Returns (status,
    shaft torque)."""
    n = q.shape[0]
    M = (n - 2) // 2
    m = P[I_M]
    kc = P[I_KC]
    cc = P[I_CC]
    paper_damp = P[I_PAPER_DAMP] != 0.0
    rigid = P[I_RIGID] != 0.0
    if rigid:
        w1 = tau_d
    else:
        w1 = v[0]
    w2 = v[1]
    for i in range(2, n):
        a[i] = 0.0
    # link dampers: S = c/2 (e . dv)^2 (axial) or c/2 |dv|^2 (paper) while the spring is
    # engaged; a damper does not push a taut link nor pull a bearing one
    for i in range(M):
        j = i + 1
        if j == M:
            j = 0
        ex = scr[R_EX * M + i]
        ey = scr[R_EY * M + i]
        dx = scr[R_DX * M + i]
        dy = scr[R_DY * M + i]
        L = scr[R_L * M + i]
        Ts = scr[R_TS * M + i]
        cl = scr[R_CL * M + i]
        branch = scr[R_BRANCH * M + i]
        dvx = v[2 + 2 * j] - v[2 + 2 * i]
        dvy = v[3 + 2 * j] - v[3 + 2 * i]
        rate = ex * dvx + ey * dvy
        if branch > 0.0:
            T = Ts + cl * rate
            if T < 0.0:
                T = 0.0
        elif branch < 0.0:
            T = Ts + cl * rate
            if T > 0.0:
                T = 0.0
        else:
            T = 0.0
        if paper_damp:
            fx = Ts * ex + cl * dvx
            fy = Ts * ey + cl * dvy
            tension[i] = Ts + cl * rate
        else:
            fx = T * ex
            fy = T * ey
            tension[i] = T
        a[2 + 2 * i] += fx
        a[3 + 2 * i] += fy
        a[2 + 2 * j] -= fx
        a[3 + 2 * j] -= fy
        scr[R_OMEGA * M + i] = (dx * dvy - dy * dvx) / (L * L)
    # joint dampers: S = cj/2 sum (w_i - w_{i-1})^2 over the joints, w_i link i's angular speed
    cj = P[I_CJ]
    if cj > 0.0:
        for i in range(M):
            j = i + 1
            if j == M:
                j = 0
            im = i - 1
            if im < 0:
                im = M - 1
            Tj = cj * (2.0 * scr[i] - scr[im] - scr[j])
            dx = q[2 + 2 * j] - q[2 + 2 * i]
            dy = q[3 + 2 * j] - q[3 + 2 * i]
            L2 = dx * dx + dy * dy
            if not L2 > 0.0:
                L2 = 1e-300
            fx = -Tj * dy / L2
            fy = Tj * dx / L2
            a[2 + 2 * i] += fx
            a[3 + 2 * i] += fy
            a[2 + 2 * j] -= fx
            a[3 + 2 * j] -= fy
    # roller-seat contact forces
    torque1 = 0.0
    torque2 = 0.0
    for i in range(M):
        vx = v[2 + 2 * i]
        vy = v[3 + 2 * i]
        side[i] = 0
        fcon[i] = 0.0
        for s in range(2):
            row = (R_CONTACT + 7 * s) * M + i
            pen = scr[row]
            if pen > 0.0:
                if s == 0:
                    R = P[I_R1]
                    w = w1
                else:
                    R = P[I_R2]
                    w = w2
                nx = scr[row + M]
                ny = scr[row + 2 * M]
                rx = scr[row + 3 * M]
                ry = scr[row + 4 * M]
                cross = rx * ny - ry * nx
                if paper_damp:
                    st = scr[row + 5 * M]
                    ct = scr[row + 6 * M]
                    Fn = kc * pen
                    dvx = w * R * st - vx
                    dvy = -w * R * ct - vy
                    fx = -Fn * nx + cc * dvx
                    fy = -Fn * ny + cc * dvy
                    tq = -Fn * cross - cc * R * (dvx * st - dvy * ct)
                else:
                    # normal rate relative to the sprocket body at the roller: w (ry, -rx)
                    pend = nx * (vx - w * ry) + ny * (vy + w * rx)
                    Fn = kc * pen + cc * pend
                    if Fn < 0.0:
                        Fn = 0.0
                    fx = -Fn * nx
                    fy = -Fn * ny
                    tq = -Fn * cross
                a[2 + 2 * i] += fx
                a[3 + 2 * i] += fy
                if s == 0:
                    torque1 += tq
                else:
                    torque2 += tq
                side[i] = s + 1
                fcon[i] += Fn
    # sprockets
    if rigid:
        a[0] = tau_dd
        shaft = P[I_I1] * tau_dd - torque1
    else:
        shaft = P[I_KR] * (tau - q[0]) + P[I_CR] * (tau_d - v[0])
        a[0] = (shaft + torque1) / P[I_I1]
    a[1] = (torque2 - load - P[I_C2] * w2) / P[I_I2]
    # gravity, the appendix's rotating-frame forces (eqs A4-A7) if switched on, and 1/m
    gx = P[I_GX] * m
    gy = P[I_GY] * m
    qf = P[I_QF] != 0.0
    for i in range(M):
        fx = gx
        fy = gy
        if qf and side[i] > 0:
            s = side[i] - 1
            th = seat_angle[s, i]
            if s == 0:
                R = P[I_R1]
                w = w1
                al = a[0]
            else:
                R = P[I_R2]
                w = w2
                al = a[1]
            fx += m * R * (w * w * math.cos(th) - al * math.sin(th))
            fy += m * R * (w * w * math.sin(th) + al * math.cos(th))
        a[2 + 2 * i] = (a[2 + 2 * i] + fx) / m
        a[3 + 2 * i] = (a[3 + 2 * i] + fy) / m
    for i in range(n):
        if not (a[i] - a[i] == 0.0):
            status = 1
    return status, shaft


def _hermite(t, T0, H, a0, w0, a1, w1):
    """Input-shaft angle, speed, acceleration at t from a cubic Hermite through (a0, w0) at T0
    and (a1, w1) at T0 + H: exact for the linear (held) and quadratic (ramp) profiles."""
    if H <= 0.0:
        return a0, w0, 0.0
    s = (t - T0) / H
    s2 = s * s
    s3 = s2 * s
    ang = (2 * s3 - 3 * s2 + 1) * a0 + (s3 - 2 * s2 + s) * H * w0 + (-2 * s3 + 3 * s2) * a1 \
        + (s3 - s2) * H * w1
    spd = ((6 * s2 - 6 * s) * a0 + (-6 * s2 + 6 * s) * a1) / H + (3 * s2 - 4 * s + 1) * w0 \
        + (3 * s2 - 2 * s) * w1
    acc = ((12 * s - 6) * a0 + (-12 * s + 6) * a1) / (H * H) + ((6 * s - 4) * w0
                                                              + (6 * s - 2) * w1) / H
    return ang, spd, acc


def _run_fixed_loops(method, x, t0, h, nsteps, T0, H, a0, w0, a1, w1, L0, L1, P,
                     acc, acc2, k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr,
                     started):
    """Advance x in place by ``nsteps`` fixed steps of ``method`` (0 velocity Verlet exactly as
    chainmodel.integrate.Verlet, 1 classic RK4); inputs from :func:`_hermite` and a linear load.
    Returns -1 on success or the index of the step after which the state diverged.

    Verlet evaluates the position-dependent forces once per step (:func:`_geometry_loops` at
    the new positions) and the velocity-dependent pass twice (:func:`_forces_loops`: at the
    half-step velocity for the second half kick, at the end velocity for the next step's
    first), the numbers of two full evaluations. ``started``: ``acc`` already holds the forces
    at (t0, x) (the caller's pass on the geometry in ``scr``)."""
    n = x.shape[0]
    nq = n // 2
    q = x[:nq]
    v = x[nq:]
    for step in range(nsteps):
        t = t0 + step * h
        if method == 0:
            if not started:
                ang, spd, ac = _HERMITE(t, T0, H, a0, w0, a1, w1)
                ld = L0 + (L1 - L0) * ((t - T0) / H if H > 0 else 0.0)
                st, _ = _ACCEL(q, v, ang, spd, ac, ld, P, acc, tension, fcon, side, dist,
                               seat_angle, scr)
            for i in range(nq):
                v[i] += 0.5 * h * acc[i]
                q[i] += h * v[i]
            ang, spd, ac = _HERMITE(t + h, T0, H, a0, w0, a1, w1)
            ld = L0 + (L1 - L0) * ((t + h - T0) / H if H > 0 else 0.0)
            st2 = _GEOM(q, ang, P, dist, seat_angle, scr)
            st2, _ = _FORCES(q, v, ang, spd, ac, ld, P, acc2, tension, fcon, side, seat_angle,
                             scr, st2)
            for i in range(nq):
                v[i] += 0.5 * h * acc2[i]
            if st2 != 0:
                return step
            # the next step starts with the forces at these positions and the end velocity, at
            # its own time; the positions' part (the seat search, the links' geometry) is the
            # one just made unless the input angle moves the driver (a rigid input shaft)
            # between the two times: the same numbers as a full evaluation, for less
            started = False
            if step + 1 < nsteps:
                tn = t0 + (step + 1) * h
                ang2, spd2, ac2 = _HERMITE(tn, T0, H, a0, w0, a1, w1)
                if P[I_RIGID] == 0.0 or ang2 == ang:
                    ld2 = L0 + (L1 - L0) * ((tn - T0) / H if H > 0 else 0.0)
                    _FORCES(q, v, ang2, spd2, ac2, ld2, P, acc, tension, fcon, side, seat_angle,
                            scr, 0)
                    started = True
        else:
            for stage in range(4):
                if stage == 0:
                    tt = t
                    for i in range(n):
                        xt[i] = x[i]
                    kk = k1
                elif stage == 1:
                    tt = t + 0.5 * h
                    for i in range(n):
                        xt[i] = x[i] + 0.5 * h * k1[i]
                    kk = k2
                elif stage == 2:
                    tt = t + 0.5 * h
                    for i in range(n):
                        xt[i] = x[i] + 0.5 * h * k2[i]
                    kk = k3
                else:
                    tt = t + h
                    for i in range(n):
                        xt[i] = x[i] + h * k3[i]
                    kk = k4
                ang, spd, ac = _HERMITE(tt, T0, H, a0, w0, a1, w1)
                ld = L0 + (L1 - L0) * ((tt - T0) / H if H > 0 else 0.0)
                st, _ = _ACCEL(xt[:nq], xt[nq:], ang, spd, ac, ld, P, acc, tension, fcon,
                               side, dist, seat_angle, scr)
                for i in range(nq):
                    kk[i] = xt[nq + i]
                    kk[nq + i] = acc[i]
            for i in range(n):
                x[i] += h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            st = 0
            for i in range(n):
                if not (x[i] - x[i] == 0.0):
                    st = 1
            if st != 0:
                return step
    return -1


def _engaged_loops(q, dist, side, seat_angle, tol, P, s, r):
    """Roller r is engaged (seated) on sprocket s: within tol of a seat centre (tol = clearance
    plus a little), or touching a seat of s while no farther from the sprocket centre than the
    pitch radius plus the clearance (eq 9's second condition with the clearance added); a
    roller riding a flank beyond that is entering or leaving."""
    if dist[s, r] <= tol:
        return True
    if side[r] != s + 1:
        return False
    if s == 0:
        dx = q[2 + 2 * r] - P[I_CX]
        dy = q[3 + 2 * r] - P[I_CY]
        R = P[I_R1] + P[I_DR]
    else:
        dx = q[2 + 2 * r]
        dy = q[3 + 2 * r]
        R = P[I_R2] + P[I_DR]
    return dx * dx + dy * dy <= R * R


def _spans_loops(q, dist, side, seat_angle, tol, P, mids, out):
    """Span bookkeeping of the outputs: for span s (0 upper: driven -> driver, 1 lower: driver
    -> driven) the link whose midpoint is nearest mids[s], the last roller engaged
    (:func:`_engaged_loops`) on the sprocket it leaves, going back from that link, and the first
    engaged on the sprocket it runs onto, going forward. out[s] = (mid, start, end)."""
    M = (q.shape[0] - 2) // 2
    for span in range(2):
        mx = mids[span, 0]
        my = mids[span, 1]
        best = 1e300
        mid = 0
        for i in range(M):
            j = i + 1
            if j == M:
                j = 0
            ex = 0.5 * (q[2 + 2 * i] + q[2 + 2 * j]) - mx
            ey = 0.5 * (q[3 + 2 * i] + q[3 + 2 * j]) - my
            dd = ex * ex + ey * ey
            if dd < best:
                best = dd
                mid = i
        s_from = 1 if span == 0 else 0
        s_to = 1 - s_from
        a = (mid + 1) % M
        for k in range(M):
            r = (mid - k) % M
            if _ENGAGED(q, dist, side, seat_angle, tol, P, s_from, r):
                a = r
                break
        b = mid
        for k in range(M):
            r = (mid + 1 + k) % M
            if _ENGAGED(q, dist, side, seat_angle, tol, P, s_to, r):
                b = r
                break
        out[span, 0] = mid
        out[span, 1] = a
        out[span, 2] = b


def engaged_numpy(q, dist, side, seat_angle, tol, P):
    """(2, M) bool: :func:`_engaged_loops` for every roller and both sprockets."""
    M = (q.shape[0] - 2) // 2
    z = q[2:].reshape(M, 2)
    r2 = np.stack([(z[:, 0] - P[I_CX]) ** 2 + (z[:, 1] - P[I_CY]) ** 2,
                   z[:, 0] ** 2 + z[:, 1] ** 2])
    R = np.array([P[I_R1], P[I_R2]])[:, None] + P[I_DR]
    touch = side[None, :] == np.array([[1], [2]])
    return (dist <= tol) | (touch & (r2 <= R * R))


def spans_numpy(q, dist, side, seat_angle, tol, P, mids, out):
    """Vectorised :func:`_spans_loops`."""
    M = (q.shape[0] - 2) // 2
    z = q[2:].reshape(M, 2)
    eng = engaged_numpy(q, dist, side, seat_angle, tol, P)
    mp = 0.5 * (z + np.roll(z, -1, axis=0))
    for span in range(2):
        mid = int(np.argmin((mp[:, 0] - mids[span, 0]) ** 2 + (mp[:, 1] - mids[span, 1]) ** 2))
        s_from = 1 if span == 0 else 0
        back = (mid - np.arange(M)) % M
        fwd = (mid + 1 + np.arange(M)) % M
        eb, ef = eng[s_from][back], eng[1 - s_from][fwd]
        out[span] = (mid, back[np.argmax(eb)] if eb.any() else (mid + 1) % M,
                     fwd[np.argmax(ef)] if ef.any() else mid)




def _outputs_loops(x, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side, dist, seat_angle,
                   scr, mids, tol, reverse, tooth_ratio, spans, out, geometry):
    """Every output (order OUTPUT_NAMES) at state x; the same as MultibodyModel's numpy path.
    velocity_ratio is driven / driver speed (the caller replaces it while the driver rests).
    ``geometry``: ``scr``, ``dist`` and ``seat_angle`` already hold the positions' part at x
    and the input angle does not move the seats (a flexible input shaft): only the forces'
    pass is made (the same numbers; the status returned is then the forces' alone)."""
    n = x.shape[0] // 2
    M = (n - 2) // 2
    q = x[:n]
    v = x[n:]
    if geometry:
        status, shaft = _FORCES(q, v, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side,
                                seat_angle, scr, 0)
    else:
        status, shaft = _ACCEL(q, v, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side,
                               dist, seat_angle, scr)
    _SPANS(q, dist, side, seat_angle, tol, P, mids, spans)
    rigid = P[I_RIGID] != 0.0
    phi1 = tau if rigid else q[0]
    w1 = tau_d if rigid else v[0]
    # span roles by power flow, from the inputs (chainmodel.models.span_roles); ``reverse``
    # is kept in the signature for the callers
    t_span = 1 if lower_tight(load, P[I_C2], P[I_I2], tooth_ratio, tau_d, tau_dd) else 0
    s_span = 1 - t_span
    a = spans[t_span, 1]
    b = spans[t_span, 2]
    ax = q[2 + 2 * a]
    ay = q[3 + 2 * a]
    cx = ax - (P[I_CX] if t_span == 1 else 0.0)
    cy = ay - (P[I_CY] if t_span == 1 else 0.0)
    chx = q[2 + 2 * b] - ax
    chy = q[3 + 2 * b] - ay
    length = math.sqrt(chx * chx + chy * chy)
    nl = (b - a) % M
    i0 = (a + nl // 2) % M
    mx = q[2 + 2 * i0]
    my = q[3 + 2 * i0]
    if nl % 2 == 1:
        i1 = (i0 + 1) % M
        mx = 0.5 * (mx + q[2 + 2 * i1])
        my = 0.5 * (my + q[3 + 2 * i1])
    deflection = 0.0
    if length > 0.0:
        nx = -chy / length
        ny = chx / length
        if nx * cx + ny * cy < 0.0:
            nx = -nx
            ny = -ny
        deflection = nx * (mx - ax) + ny * (my - ay)
    tmax = tension[0]
    tmin = tension[0]
    fmax = fcon[0]
    for i in range(M):
        if tension[i] > tmax:
            tmax = tension[i]
        if tension[i] < tmin:
            tmin = tension[i]
        if fcon[i] > fmax:
            fmax = fcon[i]
    out[O_DRIVER_ANGLE] = phi1
    out[O_DRIVER_SPEED] = w1
    out[O_DRIVEN_ANGLE] = q[1]
    out[O_DRIVEN_SPEED] = v[1]
    out[O_DRIVEN_ACCELERATION] = acc[1]
    out[O_INPUT_SHAFT_TORQUE] = shaft
    out[O_TIGHT_SPAN_TENSION] = tension[spans[t_span, 0]]
    out[O_SLACK_SPAN_TENSION] = tension[spans[s_span, 0]]
    out[O_TIGHT_SPAN_LENGTH] = length
    out[O_VELOCITY_RATIO] = v[1] / w1 if w1 != 0.0 else 0.0
    out[O_TRANSMISSION_ERROR] = q[1] - tooth_ratio * phi1
    out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = deflection
    out[O_CHAIN_MAX_LINK_TENSION] = tmax
    out[O_CONTACT_MAX_FORCE] = fmax
    out[O_CHAIN_MIN_LINK_TENSION] = tmin
    return status


def _omega_loops(q, P, OM):
    """Highest natural frequency bound [rad/s] of the positions q (MultibodyModel.omega_max,
    whose constant parts are OM = [4 / m, kc / m + largest seat coupling, largest sprocket
    term, damping rate]): the link term takes the stiffest link, k or |k (L - l0)| / L."""
    M = (q.shape[0] - 2) // 2
    k = P[I_K]
    l0 = P[I_L0]
    k_link = k
    for i in range(M):
        j = i + 1
        if j == M:
            j = 0
        dx = q[2 + 2 * j] - q[2 + 2 * i]
        dy = q[3 + 2 * j] - q[3 + 2 * i]
        L = math.sqrt(dx * dx + dy * dy)
        if L > 0.0:
            kl = abs(k * (L - l0)) / L
            if kl > k_link:
                k_link = kl
    w2 = OM[0] * k_link + OM[1]
    if OM[2] > w2:
        w2 = OM[2]
    w = math.sqrt(w2)
    if OM[3] > w:
        w = OM[3]
    return w


#: step rule vector (chainmodel.integrate.FixedStepper.cfg): explicit step, the tolerance's
#: h omega (not used at level 3), safety times the stability limit, the limit, an outer bound
CF_STEP, CF_THETA, CF_STAB, CF_LIMIT, CF_MAX = range(5)


def _advance_points_loops(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg,
                          acc1, acc2, k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle,
                          scr, mids, tol, tooth_ratio, spans, OUT, states):
    """The fixed-step loop (:func:`_run_fixed_loops`, method 0 Verlet, 1 RK4) through the
    communication points ``times`` with the inputs given there (cubic Hermite through each
    step's ends, linear load), x_in untouched, the state at the last point reached in x_out.
    Each communication step H is split into ceil(H / h_max) equal steps, h_max from the state at
    its start (the stable-step guard): an explicit step cfg[CF_STEP], refused when its h omega
    exceeds the stability limit, or min(safety * limit / omega, cfg[CF_MAX]). OUT[i] receives
    the outputs (OUTPUT_NAMES order) at times[i] for i >= 1 if OUT has rows, states[i] the state
    if states has rows.

    Returns (reached, status, steps, events, evaluations, logged, t_status, omega) as
    chainmodel.models.rk4_loop.advance_points: status 0 fine, 1 diverged (a link outside
    [l_min, l_max] or non-finite forces, after the step ending at t_status), 2 an explicit step
    above the stable limit of the state at t_status (omega its frequency bound), 4 a
    non-finite output at t_status (its row filled)."""
    n = x_in.shape[0]
    nq = n // 2
    x = x_out
    for j in range(n):
        x[j] = x_in[j]
    want_out = OUT.shape[0] > 0
    want_states = states.shape[0] > 0
    if want_states:
        for j in range(n):
            states[0, j] = x[j]
    per_step = 2 if method == 0 else 4
    steps = 0
    evals = 0
    geometry = False        # scr holds the position-dependent part at x (its last step's end)
    out_forces = False      # acc1, tension, fcon, side hold the forces at x from the outputs'
                            # pass at the last point (a flexible input shaft, Verlet)
    for i in range(1, times.shape[0]):
        t0 = times[i - 1]
        H = times[i] - t0
        w = _OMEGA(x[:nq], P, OM)
        if cfg[CF_STEP] > 0.0:
            if cfg[CF_STEP] * w > cfg[CF_LIMIT]:
                return i - 1, 2, steps, 0, evals, 0, t0, w
            h_max = cfg[CF_STEP]
        else:
            h_max = min(cfg[CF_STAB] / w, cfg[CF_THETA] / w, cfg[CF_MAX])
        m = max(1, int(math.ceil(H / h_max - 1e-9)))
        hh = H / m
        started = False
        if method == 0 and geometry and P[I_RIGID] == 0.0:
            # the first step's forces at (t0, x) from the geometry already in scr (a flexible
            # input shaft: the input angle does not move the seats): what _RUN would compute
            ang, spd, ac = _HERMITE(t0, t0, H, angle[i - 1], speed[i - 1], angle[i], speed[i])
            ld = load[i - 1] + (load[i] - load[i - 1]) * ((t0 - t0) / H if H > 0 else 0.0)
            # the outputs' pass at this point made it already when its inputs are these (the
            # acceleration does not enter with a flexible shaft): the same call, not redone
            if not (out_forces and ang == angle[i - 1] and spd == speed[i - 1]
                    and ld == load[i - 1]):
                _FORCES(x[:nq], x[nq:], ang, spd, ac, ld, P, acc1, tension, fcon, side,
                        seat_angle, scr, 0)
            started = True
        out_forces = False
        bad = _RUN(method, x, t0, hh, m, t0, H, angle[i - 1], speed[i - 1], angle[i], speed[i],
                   load[i - 1], load[i], P, acc1, acc2, k1, k2, k3, k4, xt, tension, fcon, side,
                   dist, seat_angle, scr, started)
        geometry = method == 0
        if bad >= 0:
            return i - 1, 1, steps + bad + 1, 0, evals + (bad + 1) * per_step, 0, \
                t0 + (bad + 1) * hh, 0.0
        steps += m
        evals += m * per_step
        if want_states:
            for j in range(n):
                states[i, j] = x[j]
        if want_out:
            _OUT(x, angle[i], speed[i], acc[i], load[i], P, acc1, tension, fcon, side, dist,
                 seat_angle, scr, mids, tol, speed[i] < 0.0, tooth_ratio, spans, OUT[i],
                 method == 0 and P[I_RIGID] == 0.0)
            out_forces = method == 0 and P[I_RIGID] == 0.0
            evals += 1
            for k in range(OUT.shape[1]):
                if not math.isfinite(OUT[i, k]):
                    return i - 1, 4, steps, 0, evals, 0, times[i], 0.0
    return times.shape[0] - 1, 0, steps, 0, evals, 0, times[-1], 0.0


def _advance_held_loops(method, x_in, x_out, t0, t1, a0, w0, accel, ld, P, OM, cfg, acc1, acc2,
                        k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr, mids, tol,
                        tooth_ratio, spans, OUT):
    """One communication step with the inputs held first-order (angle a0 + w0 (t - t0); speed,
    acceleration and load held): :func:`_advance_points_loops` on the two points, outputs at t1
    in OUT[1]."""
    times = np.empty(2)
    angle = np.empty(2)
    speed = np.empty(2)
    acc = np.empty(2)
    load = np.empty(2)
    times[0] = t0
    times[1] = t1
    angle[0] = a0
    angle[1] = a0 + w0 * (t1 - t0)
    speed[0] = w0
    speed[1] = w0
    acc[0] = accel
    acc[1] = accel
    load[0] = ld
    load[1] = ld
    states = np.empty((0, x_in.shape[0]))
    return _POINTS(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, acc1, acc2,
                   k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr, mids, tol,
                   tooth_ratio, spans, OUT, states)


if HAVE_NUMBA:  # pragma: no branch
    # numba resolves the loop's callees by their global names at compile time. Every kernel
    # but _HELD allocates no array and returns none: compiled without reference counting
    # (_nrt=False, as chainmodel._numba.jit_noalloc; its callers hold the arrays), which only
    # removes the atomic increments and decrements of the arrays passed down (no arithmetic
    # change)
    _GEOM = njit(_geometry_loops, _nrt=False)
    _FORCES = njit(_forces_loops, _nrt=False)
    _ACCEL = njit(_accel_loops, _nrt=False)
    _HERMITE = njit(_hermite, _nrt=False)
    _run_fixed_jit = njit(_run_fixed_loops, _nrt=False)
    _ENGAGED = njit(_engaged_loops, _nrt=False)
    _SPANS = njit(_spans_loops, _nrt=False)
    _outputs_jit = njit(_outputs_loops, _nrt=False)
    _RUN = _run_fixed_jit
    _OUT = _outputs_jit
    _OMEGA = njit(_omega_loops, _nrt=False)
    _POINTS = njit(_advance_points_loops, _nrt=False)
    _HELD = njit(_advance_held_loops)
else:  # pragma: no cover - plain Python (slow; for debugging only)
    _GEOM, _FORCES = _geometry_loops, _forces_loops
    _ACCEL, _HERMITE, _run_fixed_jit, _SPANS, _outputs_jit, _ENGAGED = (
        _accel_loops, _hermite, _run_fixed_loops, _spans_loops, _outputs_loops, _engaged_loops)
    _RUN, _OUT, _OMEGA, _POINTS, _HELD = (_run_fixed_loops, _outputs_loops, _omega_loops,
                                          _advance_points_loops, _advance_held_loops)
spans_numba = _SPANS
_accel_jit = _ACCEL


class Workspace:
    """Preallocated arrays for the kernels (one per model)."""

    def __init__(self, n_rollers: int):
        M = n_rollers
        n = 2 + 2 * M
        self.acc = np.zeros(n)
        self.acc2 = np.zeros(n)
        self.k = [np.zeros(2 * n) for _ in range(4)]
        self.xt = np.zeros(2 * n)
        self.tension = np.zeros(M)
        self.fcon = np.zeros(M)
        self.side = np.zeros(M, np.int64)
        self.dist = np.zeros((2, M))
        self.seat_angle = np.zeros((2, M))
        self.scr = np.zeros(SCR_ROWS * M)

    def diagnostics(self):
        return self.tension, self.fcon, self.side, self.dist, self.seat_angle


def accel_numba(q, v, tau, tau_d, tau_dd, load, P, ws: Workspace, out=None):
    """Compiled kernel: accelerations (new array unless ``out``) and (status, shaft torque);
    diagnostics land in ``ws``."""
    a = np.empty(q.shape[0]) if out is None else out
    status, shaft = _accel_jit(q, v, float(tau), float(tau_d), float(tau_dd), float(load), P, a,
                               ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr)
    return a, int(status), float(shaft)


def outputs_numba(x, tau, tau_d, tau_dd, load, P, ws: Workspace, mids, tol, reverse,
                  tooth_ratio, spans, out):
    return int(_outputs_jit(x, float(tau), float(tau_d), float(tau_dd), float(load), P, ws.acc,
                            ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr, mids,
                            float(tol), bool(reverse), float(tooth_ratio), spans, out, False))


def run_fixed_numba(method: int, x, t0, h, nsteps, T0, H, a0, w0, a1, w1, L0, L1, P,
                    ws: Workspace) -> int:
    k1, k2, k3, k4 = ws.k
    return int(_run_fixed_jit(method, x, float(t0), float(h), int(nsteps), float(T0), float(H),
                              float(a0), float(w0), float(a1), float(w1), float(L0), float(L1),
                              P, ws.acc, ws.acc2, k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon,
                              ws.side, ws.dist, ws.seat_angle, ws.scr, False))


def advance_points_numba(method: int, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg,
                         ws: Workspace, mids, tol, tooth_ratio, spans, OUT, states):
    k1, k2, k3, k4 = ws.k
    return _POINTS(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, ws.acc,
                   ws.acc2, k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon, ws.side, ws.dist,
                   ws.seat_angle, ws.scr, mids, float(tol), float(tooth_ratio), spans, OUT,
                   states)


def advance_held_numba(method: int, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg,
                       ws: Workspace, mids, tol, tooth_ratio, spans, OUT):
    k1, k2, k3, k4 = ws.k
    return _HELD(method, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg, ws.acc, ws.acc2,
                 k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle,
                 ws.scr, mids, float(tol), float(tooth_ratio), spans, OUT)


# --- vectorised numpy kernel (fallback) -------------------------------------------------------

def _next(a):
    """a[i + 1] with wrap-around (np.roll(a, -1, axis=0), without its overhead)."""
    return np.concatenate((a[1:], a[:1]))


def _prev(a):
    """a[i - 1] with wrap-around (np.roll(a, 1, axis=0))."""
    return np.concatenate((a[-1:], a[:-1]))


def link_potential(ext, k, gap):
    """Potential energy [J] of links with extension ``ext`` = L - l0 under the link law of
    :func:`_accel_loops`: k e^2 / 2 in tension, 0 over the pin-bushing play -gap <= e <= 0,
    k (e + gap)^2 / 2 once the plates bear."""
    ext = np.asarray(ext, float)
    s = np.where(ext > 0.0, ext, np.minimum(ext + gap, 0.0))
    return 0.5 * k * s * s


def accel_numpy(q, v, tau, tau_d, tau_dd, load, P, ws: Workspace, out=None):
    """Same as :func:`accel_numba`, vectorised over rollers with numpy (no per-roller loops)."""
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    n = q.shape[0]
    M = (n - 2) // 2
    m, k, c, l0 = P[I_M], P[I_K], P[I_C], P[I_L0]
    kc, cc, dR = P[I_KC], P[I_CC], P[I_DR]
    sg = np.array([P[I_SG1], P[I_SG2]])[:, None]
    cg = np.array([P[I_CG1], P[I_CG2]])[:, None]
    paper_contact = P[I_PAPER_CONTACT] != 0.0
    paper_damp = P[I_PAPER_DAMP] != 0.0
    rigid = P[I_RIGID] != 0.0
    phi1, w1 = (tau, tau_d) if rigid else (q[0], v[0])
    phi2, w2 = q[1], v[1]
    z = q[2:].reshape(M, 2)
    zv = v[2:].reshape(M, 2)
    F = np.zeros((M, 2))
    # links
    d = _next(z) - z
    with np.errstate(invalid="ignore", divide="ignore"):
        L = np.hypot(d[:, 0], d[:, 1])
        status = int(not np.all((L > P[I_LMIN]) & (L < P[I_LMAX])))
        Ls = np.where(L > 0, L, 1e-300)
        e = d / Ls[:, None]
    dv = _next(zv) - zv
    rate = np.einsum("ij,ij->i", e, dv)
    ext = L - l0
    taut, bear = ext > 0.0, ext < -P[I_GAP]
    Ts = np.where(taut, k * ext, np.where(bear, k * (ext + P[I_GAP]), 0.0))
    engaged = np.where(taut, ext, np.where(bear, -P[I_GAP] - ext, 0.0))
    cl = c * np.minimum(engaged / P[I_ONSET], 1.0)
    if paper_damp:
        f = Ts[:, None] * e + cl[:, None] * dv
        ws.tension[:] = Ts + cl * rate
    else:
        T = Ts + cl * rate
        T = np.where(taut, np.maximum(T, 0.0), np.where(bear, np.minimum(T, 0.0), 0.0))
        f = T[:, None] * e
        ws.tension[:] = T
    F += f
    F -= _prev(f)
    if P[I_CJ] > 0.0:
        L2 = Ls * Ls
        omega = (d[:, 0] * dv[:, 1] - d[:, 1] * dv[:, 0]) / L2
        Tj = P[I_CJ] * (2.0 * omega - _prev(omega) - _next(omega))
        fj = np.column_stack([-Tj * d[:, 1] / L2, Tj * d[:, 0] / L2])
        F += fj
        F -= _prev(fj)
    # contact, both sprockets at once: arrays (2, M)
    cen = np.array([[P[I_CX], P[I_CY]], [0.0, 0.0]])
    R = np.array([P[I_R1], P[I_R2]])[:, None]
    ph = np.array([P[I_PH1] - phi1, P[I_PH2] - phi2])[:, None]
    ta = np.array([P[I_TA1], P[I_TA2]])[:, None]
    tip = np.array([P[I_TIP1], P[I_TIP2]])[:, None]
    w = np.array([w1, w2])[:, None]
    rx = z[None, :, 0] - cen[:, 0, None]
    ry = z[None, :, 1] - cen[:, 1, None]
    near = rx * rx + ry * ry <= np.array([P[I_REACH1], P[I_REACH2]])[:, None] ** 2
    jj = np.floor((np.arctan2(ry, rx) - ph) / ta + 0.5)
    th = ph + ta * jj
    ct, st = np.cos(th), np.sin(th)
    dx = rx - R * ct
    dy = ry - R * st
    dd = np.hypot(dx, dy)
    ws.dist[:] = np.where(near, dd, np.inf)
    ws.seat_angle[:] = np.where(near, th, 0.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        ux, uy = dx / dd, dy / dd
        if paper_contact:
            on = (rx * rx + ry * ry <= R * R) & (dd > dR)
            pen = dd - dR
            nx, ny = ux, uy
        else:
            sl = dx * ct + dy * st
            tl = -dx * st + dy * ct
            arc = -sl >= dd * cg
            sgn = np.where(tl >= 0, 1.0, -1.0)
            pen = np.where(arc, dd - dR, np.abs(tl) * sg - sl * cg - dR)
            nx = np.where(arc, ux, -sgn * sg * st - cg * ct)
            ny = np.where(arc, uy, sgn * sg * ct - cg * st)
            on = (sl <= tip) & (dd > 0)
    on &= near & (pen > 0)
    pen = np.where(on, pen, 0.0)
    nx = np.where(on, nx, 0.0)
    ny = np.where(on, ny, 0.0)
    cross = rx * ny - ry * nx
    vx, vy = zv[None, :, 0], zv[None, :, 1]
    if paper_damp:
        Fn = kc * pen
        dvx = np.where(on, w * R * st - vx, 0.0)
        dvy = np.where(on, -w * R * ct - vy, 0.0)
        fx = -Fn * nx + cc * dvx
        fy = -Fn * ny + cc * dvy
        tq = -Fn * cross - cc * R * (dvx * st - dvy * ct)
    else:
        pend = nx * (vx - w * ry) + ny * (vy + w * rx)
        Fn = np.where(on, np.maximum(kc * pen + cc * pend, 0.0), 0.0)
        fx, fy, tq = -Fn * nx, -Fn * ny, -Fn * cross
    F[:, 0] += fx.sum(axis=0)
    F[:, 1] += fy.sum(axis=0)
    torque1, torque2 = float(tq[0].sum()), float(tq[1].sum())
    side = np.where(on[1], 2, np.where(on[0], 1, 0))
    ws.side[:] = side
    ws.fcon[:] = Fn.sum(axis=0)
    a = np.empty(n) if out is None else out
    if rigid:
        a[0] = tau_dd
        shaft = P[I_I1] * tau_dd - torque1
    else:
        shaft = P[I_KR] * (tau - q[0]) + P[I_CR] * (tau_d - v[0])
        a[0] = (shaft + torque1) / P[I_I1]
    a[1] = (torque2 - load - P[I_C2] * w2) / P[I_I2]
    F[:, 0] += P[I_GX] * m
    F[:, 1] += P[I_GY] * m
    if P[I_QF] != 0.0:
        s = np.clip(side - 1, 0, 1)
        thc = th[s, np.arange(M)]
        Rc = np.array([P[I_R1], P[I_R2]])[s]
        wc = np.array([w1, w2])[s]
        alc = np.array([a[0], a[1]])[s]
        h = side > 0
        F[:, 0] += np.where(h, m * Rc * (wc * wc * np.cos(thc) - alc * np.sin(thc)), 0.0)
        F[:, 1] += np.where(h, m * Rc * (wc * wc * np.sin(thc) + alc * np.cos(thc)), 0.0)
    a[2:] = (F / m).ravel()
    if not np.all(np.isfinite(a)):
        status = 1
    return a, status, float(shaft)
