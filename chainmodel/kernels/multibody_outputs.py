"""Level 3's outputs (the multibody model) as explicit loops, compiled by numba
(:func:`chainmodel._numba.jit_noalloc`; ``py_func`` is the plain twin): which rollers are
seated (:func:`roller_engaged`), where each span starts, ends and has its middle link
(:func:`span_ends`), and the row of every output at a state (:func:`outputs_row`, order
:data:`chainmodel.outputs.OUTPUT_NAMES`); :func:`engaged_numpy` is the vectorised seating test
the snapshots use.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit_noalloc, quiet_when_plain
from ..outputs import (O_CHAIN_MAX_LINK_TENSION, O_CHAIN_MIN_LINK_TENSION, O_CONTACT_MAX_FORCE,
                       O_DRIVEN_ACCELERATION, O_DRIVEN_ANGLE, O_DRIVEN_SPEED,
                       O_DRIVER_ANGLE, O_DRIVER_SPEED, O_INPUT_SHAFT_TORQUE, O_SLACK_SPAN_TENSION,
                       O_TIGHT_SPAN_LENGTH, O_TIGHT_SPAN_MIDSPAN_DEFLECTION, O_TIGHT_SPAN_TENSION,
                       O_TRANSMISSION_ERROR, O_VELOCITY_RATIO)
from .multibody_forces import accelerations, forces_pass
from .multibody_layout import (I_C2, I_CX, I_CY, I_DR, I_I2, I_R1, I_R2, I_RIGID, I_ROLE,
                               Workspace)
from .span_roles import lower_tight

__all__ = ["roller_engaged", "span_ends", "outputs_row", "fill_outputs", "engaged_numpy"]


@jit_noalloc
def roller_engaged(q, dist, side, seat_angle, tol, P, s, r):
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


@jit_noalloc
def span_ends(q, dist, side, seat_angle, tol, P, mids, out):
    """Span bookkeeping of the outputs: for span s (0 upper: driven -> driver, 1 lower: driver
    -> driven) the link whose midpoint is nearest mids[s], the last roller engaged
    (:func:`roller_engaged`) on the sprocket it leaves, going back from that link, and the first
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
            if roller_engaged(q, dist, side, seat_angle, tol, P, s_from, r):
                a = r
                break
        b = mid
        for k in range(M):
            r = (mid + 1 + k) % M
            if roller_engaged(q, dist, side, seat_angle, tol, P, s_to, r):
                b = r
                break
        out[span, 0] = mid
        out[span, 1] = a
        out[span, 2] = b


@jit_noalloc
def outputs_row(x, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side, dist, seat_angle,
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
        status, shaft = forces_pass(q, v, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side,
                                    seat_angle, scr, 0)
    else:
        status, shaft = accelerations(q, v, tau, tau_d, tau_dd, load, P, acc, tension, fcon, side,
                                      dist, seat_angle, scr)
    span_ends(q, dist, side, seat_angle, tol, P, mids, spans)
    rigid = P[I_RIGID] != 0.0
    phi1 = tau if rigid else q[0]
    w1 = tau_d if rigid else v[0]
    # span roles by power flow, from the inputs (chainmodel.kernels.span_roles); ``reverse``
    # is kept in the signature for the callers
    t_span = 1 if lower_tight(load, P[I_C2], P[I_I2], tooth_ratio, tau_d, tau_dd,
                              P[I_ROLE]) else 0
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


@quiet_when_plain
def fill_outputs(x, tau, tau_d, tau_dd, load, P, ws: Workspace, mids, tol, reverse,
                 tooth_ratio, spans, out):
    return int(outputs_row(x, float(tau), float(tau_d), float(tau_dd), float(load), P, ws.acc,
                           ws.tension, ws.fcon, ws.side, ws.dist, ws.seat_angle, ws.scr, mids,
                           float(tol), bool(reverse), float(tooth_ratio), spans, out, False))


def engaged_numpy(q, dist, side, seat_angle, tol, P):
    """(2, M) bool: :func:`roller_engaged` for every roller and both sprockets."""
    M = (q.shape[0] - 2) // 2
    z = q[2:].reshape(M, 2)
    r2 = np.stack([(z[:, 0] - P[I_CX]) ** 2 + (z[:, 1] - P[I_CY]) ** 2,
                   z[:, 0] ** 2 + z[:, 1] ** 2])
    R = np.array([P[I_R1], P[I_R2]])[:, None] + P[I_DR]
    touch = side[None, :] == np.array([[1], [2]])
    return (dist <= tol) | (touch & (r2 <= R * R))
