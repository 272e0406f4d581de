"""Level 3's fixed-step loops (the multibody model), compiled by numba
(:mod:`chainmodel._numba`; ``py_func`` is the plain twin): velocity Verlet and classic RK4 over
a number of steps (:func:`fixed_steps`) with the input shaft's motion from a cubic Hermite
(:func:`hermite`), and the loop through communication points with the stable-step guard and
the outputs at every point (:func:`points_loop`; :func:`held_loop` for one step with the inputs
held, the FMU's). :func:`run_fixed`, :func:`run_points` and :func:`run_held` call them
with a model's :class:`~chainmodel.kernels.multibody_layout.Workspace`.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit, jit_noalloc, quiet_when_plain
from .multibody_layout import (CF_LIMIT, CF_MAX, CF_STAB, CF_STEP, CF_THETA, I_RIGID, Workspace)
from .multibody_forces import accelerations, forces_pass, geometry_pass, omega_bound
from .multibody_outputs import outputs_row

__all__ = ["hermite", "fixed_steps", "points_loop", "held_loop", "run_fixed", "run_points",
           "run_held"]


@jit_noalloc
def hermite(t, T0, H, a0, w0, a1, w1):
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


@jit_noalloc
def fixed_steps(method, x, t0, h, nsteps, T0, H, a0, w0, a1, w1, L0, L1, P,
                acc, acc2, k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr,
                started):
    """Advance x in place by ``nsteps`` fixed steps of ``method`` (0 velocity Verlet exactly as
    chainmodel.integrate.Verlet, 1 classic RK4); inputs from :func:`hermite` and a linear load.
    Returns -1 on success or the index of the step after which the state diverged.

    Verlet evaluates the position-dependent forces once per step (:func:`geometry_pass` at
    the new positions) and the velocity-dependent pass twice (:func:`forces_pass`: at the
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
                ang, spd, ac = hermite(t, T0, H, a0, w0, a1, w1)
                ld = L0 + (L1 - L0) * ((t - T0) / H if H > 0 else 0.0)
                st, _ = accelerations(q, v, ang, spd, ac, ld, P, acc, tension, fcon, side, dist,
                                      seat_angle, scr)
            for i in range(nq):
                v[i] += 0.5 * h * acc[i]
                q[i] += h * v[i]
            ang, spd, ac = hermite(t + h, T0, H, a0, w0, a1, w1)
            ld = L0 + (L1 - L0) * ((t + h - T0) / H if H > 0 else 0.0)
            st2 = geometry_pass(q, ang, P, dist, seat_angle, scr)
            st2, _ = forces_pass(q, v, ang, spd, ac, ld, P, acc2, tension, fcon, side, seat_angle,
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
                ang2, spd2, ac2 = hermite(tn, T0, H, a0, w0, a1, w1)
                if P[I_RIGID] == 0.0 or ang2 == ang:
                    ld2 = L0 + (L1 - L0) * ((tn - T0) / H if H > 0 else 0.0)
                    forces_pass(q, v, ang2, spd2, ac2, ld2, P, acc, tension, fcon, side,
                                seat_angle, scr, 0)
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
                ang, spd, ac = hermite(tt, T0, H, a0, w0, a1, w1)
                ld = L0 + (L1 - L0) * ((tt - T0) / H if H > 0 else 0.0)
                st, _ = accelerations(xt[:nq], xt[nq:], ang, spd, ac, ld, P, acc, tension, fcon,
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


@jit_noalloc
def points_loop(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg,
                acc1, acc2, k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle,
                scr, mids, tol, tooth_ratio, spans, OUT, states):
    """The fixed-step loop (:func:`fixed_steps`, method 0 Verlet, 1 RK4) through the
    communication points ``times`` with the inputs given there (cubic Hermite through each
    step's ends, linear load), x_in untouched, the state at the last point reached in x_out.
    Each communication step H is split into ceil(H / h_max) equal steps, h_max from the state at
    its start (the stable-step guard): an explicit step cfg[CF_STEP], refused when its h omega
    exceeds the stability limit, or min(safety * limit / omega, cfg[CF_MAX]). OUT[i] receives
    the outputs (OUTPUT_NAMES order) at times[i] for i >= 1 if OUT has rows, states[i] the state
    if states has rows.

    Returns (reached, status, steps, events, evaluations, logged, t_status, omega) as
    chainmodel.kernels.rk4_loop.advance_points: status 0 fine, 1 diverged (a link outside
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
        w = omega_bound(x[:nq], P, OM)
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
            # input shaft: the input angle does not move the seats): what fixed_steps would compute
            ang, spd, ac = hermite(t0, t0, H, angle[i - 1], speed[i - 1], angle[i], speed[i])
            ld = load[i - 1] + (load[i] - load[i - 1]) * ((t0 - t0) / H if H > 0 else 0.0)
            # the outputs' pass at this point made it already when its inputs are these (the
            # acceleration does not enter with a flexible shaft): the same call, not redone
            if not (out_forces and ang == angle[i - 1] and spd == speed[i - 1]
                    and ld == load[i - 1]):
                forces_pass(x[:nq], x[nq:], ang, spd, ac, ld, P, acc1, tension, fcon, side,
                            seat_angle, scr, 0)
            started = True
        out_forces = False
        bad = fixed_steps(method, x, t0, hh, m, t0, H, angle[i - 1], speed[i - 1], angle[i],
                          speed[i], load[i - 1], load[i], P, acc1, acc2, k1, k2, k3, k4, xt,
                          tension, fcon, side, dist, seat_angle, scr, started)
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
            outputs_row(x, angle[i], speed[i], acc[i], load[i], P, acc1, tension, fcon, side, dist,
                        seat_angle, scr, mids, tol, speed[i] < 0.0, tooth_ratio, spans, OUT[i],
                        method == 0 and P[I_RIGID] == 0.0)
            out_forces = method == 0 and P[I_RIGID] == 0.0
            evals += 1
            for k in range(OUT.shape[1]):
                if not math.isfinite(OUT[i, k]):
                    return i - 1, 4, steps, 0, evals, 0, times[i], 0.0
    return times.shape[0] - 1, 0, steps, 0, evals, 0, times[-1], 0.0


@jit
def held_loop(method, x_in, x_out, t0, t1, a0, w0, accel, ld, P, OM, cfg, acc1, acc2,
              k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr, mids, tol,
              tooth_ratio, spans, OUT):
    """One communication step with the inputs held first-order (angle a0 + w0 (t - t0); speed,
    acceleration and load held): :func:`points_loop` on the two points, outputs at t1
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
    return points_loop(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, acc1, acc2,
                       k1, k2, k3, k4, xt, tension, fcon, side, dist, seat_angle, scr, mids, tol,
                       tooth_ratio, spans, OUT, states)


@quiet_when_plain
def run_fixed(method: int, x, t0, h, nsteps, T0, H, a0, w0, a1, w1, L0, L1, P,
              ws: Workspace) -> int:
    k1, k2, k3, k4 = ws.k
    return int(fixed_steps(method, x, float(t0), float(h), int(nsteps), float(T0), float(H),
                           float(a0), float(w0), float(a1), float(w1), float(L0), float(L1),
                           P, ws.acc, ws.acc2, k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon,
                           ws.side, ws.dist, ws.seat_angle, ws.scr, False))


@quiet_when_plain
def run_points(method: int, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg,
               ws: Workspace, mids, tol, tooth_ratio, spans, OUT, states):
    k1, k2, k3, k4 = ws.k
    return points_loop(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, ws.acc,
                       ws.acc2, k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon, ws.side, ws.dist,
                       ws.seat_angle, ws.scr, mids, float(tol), float(tooth_ratio), spans, OUT,
                       states)


@quiet_when_plain
def run_held(method: int, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg,
             ws: Workspace, mids, tol, tooth_ratio, spans, OUT):
    k1, k2, k3, k4 = ws.k
    return held_loop(method, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg, ws.acc, ws.acc2,
                     k1, k2, k3, k4, ws.xt, ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle,
                     ws.scr, mids, float(tol), float(tooth_ratio), spans, OUT)
