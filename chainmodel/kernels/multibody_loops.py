"""Level 3's fixed-step loops (the multibody model), compiled by numba
(:mod:`chainmodel._numba`; ``py_func`` is the plain twin): velocity Verlet and classic RK4 over
a number of steps (:func:`fixed_steps`; the steps themselves ``_verlet_from`` and ``_rk4_from``,
this level's instances of :mod:`chainmodel.kernels.stepping`'s on the force law
:func:`_rhs_at`) with the input shaft's motion from a cubic Hermite (:func:`hermite`), and the
loop through communication points with the stable-step guard (:func:`_advance`) and the outputs
at every point (:func:`_outputs`): ``_points`` and ``_held``, this level's instances of the
output sampling and status loop written once in :mod:`chainmodel.kernels.stepping`, entered
through :func:`points_loop` and :func:`held_loop` (the FMU's step, inputs held).
:func:`run_fixed`, :func:`run_points` and :func:`run_held` call them with a model's
:class:`~chainmodel.kernels.multibody_layout.Workspace`.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit, jit_inline, jit_noalloc, quiet_when_plain
from . import stepping
from .stepping import STATUS_NONFINITE, STATUS_OK, STATUS_UNSTABLE, instance
from .multibody_layout import (CF_LIMIT, CF_MAX, CF_STAB, CF_STEP, CF_THETA, I_RIGID, Workspace)
from .multibody_forces import accelerations, forces_pass, omega_bound
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


#: the inputs of one communication step in ``c`` (:func:`_rhs_at`): the Hermite's start time
#: and length, angle and speed at both ends, the load at both ends
C_T0, C_H, C_A0, C_W0, C_A1, C_W1, C_L0, C_L1 = range(8)
C_SIZE = 8


@jit_inline
def _accel_at(t, x, c, W3, P, dx, st):
    """The accelerations at (t, x) into the second half of ``dx`` (:func:`accelerations`; the
    first half, the velocities, is left alone: the Verlet step reads only this half), the
    inputs from :func:`hermite` and a linear load on the communication step ``c``; the force
    law's status (0 fine, 1 diverged) into st[0]. ``W3``: the force law's diagnostics and
    scratch (tension, fcon, side, dist, seat_angle, scr)."""
    tension, fcon, side, dist, seat_angle, scr = W3
    nq = x.shape[0] // 2
    H = c[C_H]
    ang, spd, ac = hermite(t, c[C_T0], H, c[C_A0], c[C_W0], c[C_A1], c[C_W1])
    ld = c[C_L0] + (c[C_L1] - c[C_L0]) * ((t - c[C_T0]) / H if H > 0 else 0.0)
    status, _ = accelerations(x[:nq], x[nq:], ang, spd, ac, ld, P, dx[nq:], tension, fcon, side,
                              dist, seat_angle, scr)
    st[0] = status


@jit_inline
def _rhs_at(t, x, c, W3, P, dx, st):
    """The derivative [v, a] at (t, x) into ``dx`` (:func:`_accel_at` and the velocities)."""
    _accel_at(t, x, c, W3, P, dx, st)
    nq = x.shape[0] // 2
    for i in range(nq):
        dx[i] = x[nq + i]


#: the step rules, written once in chainmodel.kernels.stepping, on this level's force law
#: (inlined into fixed_steps: a call passing a dozen arrays cost 5% of a step)
_rk4_from = instance(stepping.rk4, "_rk4_from", __name__, inline=True, _rhs_at=_rhs_at)
_verlet_from = instance(stepping.verlet, "_verlet_from", __name__, inline=True,
                        _rhs_at=_accel_at)


@jit_noalloc
def fixed_steps(method, x, t0, h, nsteps, c, P, W3, k1, k2, k3, k4, xt, st, started):
    """Advance x in place by ``nsteps`` fixed steps of ``method`` (0 velocity Verlet, 1
    classic RK4: the step rules of chainmodel.kernels.stepping) from t0, step k at
    t0 + k h; inputs on the communication step ``c`` (:func:`_rhs_at`). Returns -1 on success
    or the index of the step after which the state diverged (Verlet: the force law's status
    at the step's evaluation; RK4: a non-finite state).

    Verlet evaluates the position-dependent forces once per step (``geometry_pass`` at
    the new positions) and the velocity-dependent pass twice (:func:`forces_pass`: at the
    half-step velocity for the second half kick, at the end velocity for the next step's
    first), the numbers of two full evaluations. ``started``: the acceleration half of ``k1``
    already holds the forces at (t0, x) (the caller's pass on the geometry in ``scr``)."""
    tension, fcon, side, dist, seat_angle, scr = W3
    n = x.shape[0]
    nq = n // 2
    q = x[:nq]
    v = x[nq:]
    acc = k1[nq:]
    H = c[C_H]
    for step in range(nsteps):
        t = t0 + step * h
        if method == 0:
            if not started:
                _accel_at(t, x, c, W3, P, k1, st)
            _verlet_from(t, x, h, c, W3, P, k1, k2, k3, k4, xt, st, x)
            if st[0] != 0:
                return step
            # the next step starts with the forces at these positions and the end velocity, at
            # its own time; the positions' part (the seat search, the links' geometry) is the
            # one just made unless the input angle moves the driver (a rigid input shaft)
            # between the two times: the same numbers as a full evaluation, for less
            started = False
            if step + 1 < nsteps:
                tn = t0 + (step + 1) * h
                ang2, spd2, ac2 = hermite(tn, c[C_T0], H, c[C_A0], c[C_W0], c[C_A1], c[C_W1])
                if P[I_RIGID] == 0.0 or ang2 == hermite(t + h, c[C_T0], H, c[C_A0], c[C_W0],
                                                        c[C_A1], c[C_W1])[0]:
                    ld2 = c[C_L0] + (c[C_L1] - c[C_L0]) * ((tn - c[C_T0]) / H if H > 0 else 0.0)
                    forces_pass(q, v, ang2, spd2, ac2, ld2, P, acc, tension, fcon, side,
                                seat_angle, scr, 0)
                    started = True
        else:
            _rhs_at(t, x, c, W3, P, k1, st)
            _rk4_from(t, x, h, c, W3, P, k1, k2, k3, k4, xt, st, x)
            bad = False
            for i in range(n):
                if not (x[i] - x[i] == 0.0):
                    bad = True
            if bad:
                return step
    return -1


@jit
def _begin(K, n):
    """The work arrays of :func:`_advance`: flags (the geometry of the current state is in
    scr; the acceleration half of k1 holds the outputs' forces at the current point), the
    communication step's inputs ``c``, the force law's status (one allocation: the FMU's held
    step makes them at every communication step)."""
    buf = np.zeros(C_SIZE + 3)
    return buf[C_SIZE:C_SIZE + 2], buf[:C_SIZE], buf[C_SIZE + 2:]


@jit_inline
def _advance(i, x, times, angle, speed, acc, load, K, cfg, S, log, logged, log_cap):
    """Communication step i of :func:`stepping.points` (no switching functions at this level):
    split into ceil(H / h_max) equal steps, h_max from the state at its start (the stable-step
    guard): an explicit step cfg[CF_STEP], refused when its h omega exceeds the stability
    limit, or min(safety * limit / omega, cfg[CF_MAX]); then :func:`fixed_steps`."""
    method, P, OM, W3, k1, k2, k3, k4, xt, mids, tol, tooth_ratio, spans = K
    tension, fcon, side, dist, seat_angle, scr = W3
    flags, c, st = S
    n = x.shape[0]
    nq = n // 2
    t0 = times[i - 1]
    H = times[i] - t0
    w = omega_bound(x[:nq], P, OM)
    if cfg[CF_STEP] > 0.0:
        if cfg[CF_STEP] * w > cfg[CF_LIMIT]:
            return STATUS_UNSTABLE, 0, 0, 0, t0, w
        h_max = cfg[CF_STEP]
    else:
        h_max = min(cfg[CF_STAB] / w, cfg[CF_THETA] / w, cfg[CF_MAX])
    m = max(1, int(math.ceil(H / h_max - 1e-9)))
    hh = H / m
    c[C_T0] = t0
    c[C_H] = H
    c[C_A0] = angle[i - 1]
    c[C_W0] = speed[i - 1]
    c[C_A1] = angle[i]
    c[C_W1] = speed[i]
    c[C_L0] = load[i - 1]
    c[C_L1] = load[i]
    started = False
    if method == 0 and flags[0] != 0.0 and P[I_RIGID] == 0.0:
        # the first step's forces at (t0, x) from the geometry already in scr (a flexible
        # input shaft: the input angle does not move the seats): what fixed_steps would compute
        ang, spd, ac = hermite(t0, t0, H, angle[i - 1], speed[i - 1], angle[i], speed[i])
        ld = load[i - 1] + (load[i] - load[i - 1]) * ((t0 - t0) / H if H > 0 else 0.0)
        # the outputs' pass at this point made it already when its inputs are these (the
        # acceleration does not enter with a flexible shaft): the same call, not redone
        if not (flags[1] != 0.0 and ang == angle[i - 1] and spd == speed[i - 1]
                and ld == load[i - 1]):
            forces_pass(x[:nq], x[nq:], ang, spd, ac, ld, P, k1[nq:], tension, fcon, side,
                        seat_angle, scr, 0)
        started = True
    flags[1] = 0.0
    bad = fixed_steps(method, x, t0, hh, m, c, P, W3, k1, k2, k3, k4, xt, st, started)
    flags[0] = 1.0 if method == 0 else 0.0
    per_step = 2 if method == 0 else 4
    if bad >= 0:
        return STATUS_NONFINITE, bad + 1, 0, (bad + 1) * per_step, t0 + (bad + 1) * hh, 0.0
    return STATUS_OK, m, 0, m * per_step, times[i], 0.0


@jit_inline
def _outputs(i, x, angle, speed, acc, load, K, S, out):
    """The outputs at point i into ``out`` (:func:`outputs_row`, its forces into k1's
    acceleration half: with Verlet on a flexible input shaft they start the next step)."""
    method, P, OM, W3, k1, k2, k3, k4, xt, mids, tol, tooth_ratio, spans = K
    tension, fcon, side, dist, seat_angle, scr = W3
    flags = S[0]
    nq = x.shape[0] // 2
    reuse = method == 0 and P[I_RIGID] == 0.0
    outputs_row(x, angle[i], speed[i], acc[i], load[i], P, k1[nq:], tension, fcon, side, dist,
                seat_angle, scr, mids, tol, speed[i] < 0.0, tooth_ratio, spans, out, reuse)
    flags[1] = 1.0 if reuse else 0.0
    return 1


#: the sampling loop and the held step, written once in chainmodel.kernels.stepping
_points = instance(stepping.points, "_points", __name__, _advance=_advance, _outputs=_outputs)
_held = instance(stepping.held, "_held", __name__, noalloc=False, _points=_points,
                 _begin=_begin)


@jit
def points_loop(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, k1, k2, k3, k4,
                xt, tension, fcon, side, dist, seat_angle, scr, mids, tol, tooth_ratio, spans,
                OUT, states):
    """The fixed-step loop (method 0 Verlet, 1 RK4) through the communication points ``times``
    with the inputs given there (cubic Hermite through each step's ends, linear load), x_in
    untouched, the state at the last point reached in x_out: this level's instance of
    :func:`chainmodel.kernels.stepping.points` (:func:`_advance` for each communication step,
    :func:`_outputs` at each point). OUT[i] receives the outputs (OUTPUT_NAMES order) at
    times[i] for i >= 1 if OUT has rows, states[i] the state if states has rows.

    Returns (reached, status, steps, events, evaluations, logged, t_status, omega) as
    chainmodel.kernels.rk4_loop.advance_points: status STATUS_OK, STATUS_NONFINITE (a link
    outside [l_min, l_max] or non-finite forces, after the step ending at t_status),
    STATUS_UNSTABLE (an explicit step above the stable limit of the state at t_status, omega
    its frequency bound), STATUS_OUTPUTS (a non-finite output at t_status, its row filled)."""
    K = (method, P, OM, (tension, fcon, side, dist, seat_angle, scr), k1, k2, k3, k4, xt, mids,
         tol, tooth_ratio, spans)
    return _points(x_in, x_out, times, angle, speed, acc, load, K, _begin(K, x_in.shape[0]), cfg,
                   OUT, states, np.empty(0), 0)


@jit
def held_loop(method, x_in, x_out, t0, t1, a0, w0, accel, ld, P, OM, cfg, k1, k2, k3, k4, xt,
              tension, fcon, side, dist, seat_angle, scr, mids, tol, tooth_ratio, spans, OUT):
    """One communication step with the inputs held first-order (angle a0 + w0 (t - t0); speed,
    acceleration and load held): this level's instance of
    :func:`chainmodel.kernels.stepping.held`, outputs at t1 in OUT[1]."""
    K = (method, P, OM, (tension, fcon, side, dist, seat_angle, scr), k1, k2, k3, k4, xt, mids,
         tol, tooth_ratio, spans)
    return _held(x_in, x_out, t0, t1, a0, w0, accel, ld, K, cfg, OUT, np.empty(0))


@quiet_when_plain
def run_fixed(method: int, x, t0, h, nsteps, T0, H, a0, w0, a1, w1, L0, L1, P,
              ws: Workspace) -> int:
    k1, k2, k3, k4 = ws.k
    c = np.array([T0, H, a0, w0, a1, w1, L0, L1], dtype=float)
    W3 = (ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr)
    return int(fixed_steps(method, x, float(t0), float(h), int(nsteps), c, P, W3, k1, k2, k3, k4,
                           ws.xt, np.zeros(1), False))


@quiet_when_plain
def run_points(method: int, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg,
               ws: Workspace, mids, tol, tooth_ratio, spans, OUT, states):
    k1, k2, k3, k4 = ws.k
    return points_loop(method, x_in, x_out, times, angle, speed, acc, load, P, OM, cfg, k1, k2,
                       k3, k4, ws.xt, ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle,
                       ws.scr, mids, float(tol), float(tooth_ratio), spans, OUT, states)


@quiet_when_plain
def run_held(method: int, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg,
             ws: Workspace, mids, tol, tooth_ratio, spans, OUT):
    k1, k2, k3, k4 = ws.k
    return held_loop(method, x_in, x_out, t0, t1, a0, w0, acc, load, P, OM, cfg, k1, k2, k3, k4,
                     ws.xt, ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr, mids,
                     float(tol), float(tooth_ratio), spans, OUT)
