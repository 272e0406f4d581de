"""Level 3's force law and outputs written a second time, vectorised over the rollers with
numpy: an independent computation the tests check the kernels against
(tests/test_multibody.py). It is NOT the kernels' plain twin (that is their ``py_func``, the
same source as the compiled loops, chainmodel.kernels): it was the library's numpy fallback
before the kernels' loops became their own plain path (issue 20, item 4), written from the
equations of docs/multibody.md with whole-array operations in another order, so it agrees with
the kernels to round-off and shares none of their code. Nothing in chainmodel imports it."""

from __future__ import annotations

import math

import numpy as np

from chainmodel.kernels.multibody_layout import (
    I_C, I_C2, I_CC, I_CG1, I_CG2, I_CJ, I_CR, I_CX, I_CY, I_DR, I_GAP, I_GX, I_GY, I_I1, I_I2,
    I_K, I_KC, I_KR, I_L0, I_LMAX, I_LMIN, I_M, I_ONSET, I_PAPER_CONTACT, I_PAPER_DAMP, I_PH1,
    I_PH2, I_QF, I_R1, I_R2, I_REACH1, I_REACH2, I_RIGID, I_SG1, I_SG2, I_TA1, I_TA2, I_TIP1,
    I_TIP2, Workspace)
from chainmodel.kernels.multibody_outputs import engaged_numpy
from chainmodel.kernels.span_roles import lower_tight_many
from chainmodel.kinematics import driven_rotation
from chainmodel.models import Inputs, Model
from chainmodel.models import multibody as MB


def _next(a):
    """a[i + 1] with wrap-around (np.roll(a, -1, axis=0), without its overhead)."""
    return np.concatenate((a[1:], a[:1]))


def _prev(a):
    """a[i - 1] with wrap-around (np.roll(a, 1, axis=0))."""
    return np.concatenate((a[-1:], a[:-1]))


def accel_numpy(q, v, tau, tau_d, tau_dd, load, P, ws: Workspace, out=None):
    """The accelerations, (status, shaft torque) and diagnostics (into ``ws``) of
    chainmodel.kernels.multibody_forces.accel, vectorised over the rollers (no per-roller loops)."""
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


def spans_numpy(q, dist, side, seat_angle, tol, P, mids, out):
    """Vectorised :func:`span_ends`."""
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


def _evaluate(model, t, x, u):
    """The oracle's forces at (t, x, u) and the spans (MultibodyModel._evaluate on it)."""
    n = 2 + 2 * model.M
    acc, status, shaft = accel_numpy(x[:n], x[n:], u.angle, u.speed, u.acceleration, u.torque,
                                     model.P, model.ws)
    spans = np.zeros((2, 3), np.int64)
    spans_numpy(x[:n], model.ws.dist, model.ws.side, model.ws.seat_angle, model._engaged_tol,
                model.P, model._mids, spans)
    z = x[2:n].reshape(model.M, 2)
    return acc, shaft, z, tuple(int(i) for i in spans[0]), tuple(int(i) for i in spans[1])


def outputs_numpy(self, t, x, u):
    """Every output of MultibodyModel ``self`` at (t, x, u), from the oracle's forces."""
    p = self.params
    n = 2 + 2 * self.M
    acc, shaft, z, up, low = _evaluate(self, t, x, u)
    rigid = p["input_shaft.rigid"]
    phi1 = u.angle if rigid else x[0]
    w1 = u.speed if rigid else x[n]
    phi2, w2 = x[1], x[n + 1]
    reverse = u.speed < 0
    tension = self.ws.tension
    # span roles by power flow, from the inputs (chainmodel.kernels.span_roles)
    lower = bool(lower_tight_many(u.torque, self.P[I_C2], self.P[I_I2],
                                  self.drive.tooth_ratio, u.speed, u.acceleration))
    tight, slack = (low, up) if lower else (up, low)
    centre_from = self._centres[0] if lower else self._centres[1]
    _, a, b = tight
    A, B = z[a], z[b]
    nl = (b - a) % self.M
    mid_z = (z[(a + nl // 2) % self.M] if nl % 2 == 0 else
             0.5 * (z[(a + nl // 2) % self.M] + z[(a + nl // 2 + 1) % self.M]))
    chord = B - A
    length = float(math.hypot(*chord))
    if length > 0:
        normal = np.array([-chord[1], chord[0]]) / length
        if normal @ (A - centre_from) < 0:
            normal = -normal
        deflection = float(normal @ (mid_z - A))
    else:  # pragma: no cover
        deflection = 0.0
    if abs(w1) >= MB.REST_SPEED:
        ratio = w2 / w1
    else:
        ratio = float(driven_rotation(self.drive, phi1, reverse=reverse).velocity_ratio)
    return {
        "driver.angle": float(phi1),
        "driver.speed": float(w1),
        "driven.angle": float(phi2),
        "driven.speed": float(w2),
        "driven.acceleration": float(acc[1]),
        "input_shaft.torque": float(shaft),
        "tight_span.tension": float(tension[tight[0]]),
        "slack_span.tension": float(tension[slack[0]]),
        "tight_span.length": length,
        "velocity_ratio": float(ratio),
        "transmission_error": float(phi2 - self.drive.tooth_ratio * phi1),
        "tight_span.midspan_deflection": deflection,
        "chain.max_link_tension": float(np.max(tension)),
        "contact.max_force": float(np.max(self.ws.fcon)),
        "chain.min_link_tension": float(np.min(tension)),
    }


class OracleModel(MB.MultibodyModel):
    """Level 3 on the oracle: its right-hand side and outputs from the numpy force law above,
    stepped by the steppers' own loop on the model interface (no loop kernel)."""

    def has_loop_kernel(self, method: str) -> bool:
        return False

    def rhs(self, t, x, u):
        n = 2 + 2 * self.M
        a, _, _ = accel_numpy(x[:n], x[n:], u.angle, u.speed, u.acceleration, u.torque, self.P,
                              self.ws)
        return np.concatenate([x[n:], a])

    def outputs(self, t, x, u):
        return outputs_numpy(self, t, x, u)

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out):
        Model.outputs_into(self, t, x, angle, speed, acceleration, torque, out)


__all__ = ["accel_numpy", "spans_numpy", "outputs_numpy", "OracleModel", "Inputs"]
