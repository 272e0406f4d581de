"""Level 3's force law (the multibody model) as explicit loops, compiled by numba
(:func:`chainmodel._numba.jit_noalloc`; their plain twin, ``py_func``, is the same source run as
Python): the positions' pass (:func:`geometry_pass`: link lengths and directions, spring forces,
seat search and penetrations), the velocities' pass (:func:`forces_pass`: dampers, contact
forces, sprockets, gravity) and the two in a row (:func:`accelerations`); the frequency bound
of the stable-step guard (:func:`omega_bound`) and the links' potential (:func:`link_potential`).

The equations are derived in docs/multibody.md from the Lagrangian of seed 003's appendix
(kinetic energy T eq A1, deformation energy U eq A2, dissipation S eq A3; Lagrange's equation
eq 11); :mod:`chainmodel.models.multibody` explains the choices. Layout of the arrays:
:mod:`chainmodel.kernels.multibody_layout`.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit_noalloc, quiet_when_plain
from .multibody_layout import (I_C, I_C2, I_CC, I_CG1, I_CG2, I_CJ, I_CR, I_CX, I_CY, I_DR, I_GAP,
                               I_GX, I_GY, I_I1, I_I2, I_K, I_KC, I_KR, I_L0, I_LMAX, I_LMIN, I_M,
                               I_ONSET, I_PAPER_CONTACT, I_PAPER_DAMP, I_PH1, I_PH2, I_QF, I_R1,
                               I_R2, I_REACH1, I_REACH2, I_RIGID, I_SG1, I_SG2, I_TA1, I_TA2,
                               I_TIP1, I_TIP2, I_RR, I_PITCH, I_CUT1, I_ASL1, I_AU1, I_KSL1,
                               I_KU1, I_CUT2, I_ASL2, I_AU2, I_KSL2, I_KU2, I_Z1, I_Z2,
                               N_PARAMS, R_BRANCH, R_CL, R_CONTACT, R_DX, R_DY, R_EX, R_EY, R_L,
                               R_OMEGA, R_TS, Workspace)

__all__ = ["geometry_pass", "forces_pass", "accelerations", "omega_bound", "accel",
           "link_potential"]


@jit_noalloc
def accelerations(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, dist, seat_angle,
                  scr):
    """Accelerations ``a`` (same layout as q) and diagnostics; returns (status, shaft torque).

    status 0: fine; 1: a link is stretched or compressed beyond [l_min, l_max] or a
    coordinate is not finite (the integration has diverged).
    tension[i]: axial force of link i (roller i to roller i+1), positive in tension.
    fcon[i]: normal contact force on roller i; side[i]: 0 free, 1 driver, 2 driven.
    dist[s, i]: distance of roller i from the nearest seat centre of sprocket s.
    seat_angle[s, i]: angle of that seat about the sprocket centre.
    scr: scratch, SCR_ROWS rows of M (the angular velocity of link i in its first row).

    Two passes: :func:`geometry_pass` (everything the positions give: link lengths and
    directions, spring forces, seat search and penetrations) and :func:`forces_pass` (the
    forces with the velocities), the same arithmetic in the same order as one pass; the Verlet
    loop runs the second pass again at a step's end velocity without the first.
    """
    status = geometry_pass(q, tau, P, dist, seat_angle, scr)
    return forces_pass(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, seat_angle, scr,
                       status)


@jit_noalloc
def geometry_pass(q, tau, P, dist, seat_angle, scr):
    """The position-dependent part of :func:`accelerations` into ``scr`` (rows R_*), ``dist``
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
                cut = P[I_CUT1]
                asl = P[I_ASL1]
                au = P[I_AU1]
                ksl = P[I_KSL1]
                ku = P[I_KU1]
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
                cut = P[I_CUT2]
                asl = P[I_ASL2]
                au = P[I_AU2]
                ksl = P[I_KSL2]
                ku = P[I_KU2]
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
                        u = abs(tl)
                        if cut != 0.0 and sl * au - u * asl > 0.0:
                            # the tooth cut by the articulation path (articulation_cut): on the
                            # side of the line neighbour-seat the path sweeps, its circle about
                            # the neighbour seat and the rounded corner where it meets the
                            # flank; each only lowers the penetration
                            gs = 0.0
                            gu = 0.0
                            ks = sl - ksl
                            kt = u - ku
                            # in the corner's normal cone: between the flank's outward normal
                            # (cg, -sg) and the circle's, (ksl - asl, ku - au) / (p - R_r),
                            # on their side of the corner (not the opposite cone, inside)
                            cs = ksl - asl
                            cu = ku - au
                            if (cg * kt + sg * ks >= 0.0 and ks * cu - kt * cs >= 0.0
                                    and (ks * cg - kt * sg) * (P[I_PITCH] - P[I_RR])
                                    + ks * cs + kt * cu > 0.0):
                                dk = math.sqrt(ks * ks + kt * kt)
                                if dk > 0.0:
                                    pen = P[I_RR] - dk
                                    gs = -ks / dk
                                    gu = -kt / dk
                            else:
                                es = sl - asl
                                et = u - au
                                da = math.sqrt(es * es + et * et)
                                if P[I_PITCH] - da < pen:
                                    pen = P[I_PITCH] - da
                                    gs = -es / da
                                    gu = -et / da
                            if gs != 0.0 or gu != 0.0:
                                nx = gs * ct - sgn * gu * st
                                ny = gs * st + sgn * gu * ct
            scr[row] = pen
            scr[row + M] = nx
            scr[row + 2 * M] = ny
            scr[row + 3 * M] = rx
            scr[row + 4 * M] = ry
            scr[row + 5 * M] = st
            scr[row + 6 * M] = ct
    return status


@jit_noalloc
def forces_pass(q, v, tau, tau_d, tau_dd, load, P, a, tension, fcon, side, seat_angle, scr,
                status):
    """The forces of :func:`accelerations` at the velocities ``v``, from the positions' part
    that :func:`geometry_pass` left in ``scr``; ``status`` its status. Returns (status,
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


@jit_noalloc
def omega_bound(q, P, OM):
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


@quiet_when_plain
def accel(q, v, tau, tau_d, tau_dd, load, P, ws: Workspace, out=None):
    """Compiled kernel: accelerations (new array unless ``out``) and (status, shaft torque);
    diagnostics land in ``ws``."""
    a = np.empty(q.shape[0]) if out is None else out
    status, shaft = accelerations(q, v, float(tau), float(tau_d), float(tau_dd), float(load), P, a,
                                  ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr)
    return a, int(status), float(shaft)


def link_potential(ext, k, gap):
    """Potential energy [J] of links with extension ``ext`` = L - l0 under the link law of
    :func:`accelerations`: k e^2 / 2 in tension, 0 over the pin-bushing play -gap <= e <= 0,
    k (e + gap)^2 / 2 once the plates bear."""
    ext = np.asarray(ext, float)
    s = np.where(ext > 0.0, ext, np.minimum(ext + gap, 0.0))
    return 0.5 * k * s * s
