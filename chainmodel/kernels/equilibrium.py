"""Static equilibrium of levels 1 (torsional) and 2 (modal) at rest, compiled: the initial state
of every run (:meth:`chainmodel.models.torsional.TorsionalModel.initial_state`).

With the input shaft held at angle theta and the load torque M applied, the driven sprocket turns
until the span tensions balance M (rigid shaft: its acceleration from seed 004 eq 50 vanishes;
flexible shaft: the net generalised torque J12 phi1'' + J22 phi2'' on it vanishes with the driver
held), and with a flexible shaft the driver turns until the shaft spring balances the spans
(phi1'' = 0), each driven rotation solved for the driver's. Both are one-dimensional roots,
bracketed by widening half-tooth steps from the level-0 configuration and then found by Brent's
method (:func:`_brent_next`, a line-by-line port of scipy's ``brentq``, to xtol = rtol = 1e-15),
all inside one compiled call: the nested search through Python calls of the kernel took ~3 ms
per run. Under ``CHAINMODEL_NUMBA=0`` the same functions run as plain Python.
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit
from .spans import A_ACC1, A_ACC2, A_SIZE, P_J12, P_J22, P_RIGID, evaluate

__all__ = ["static_state", "STATUS_OK", "STATUS_NO_DRIVEN", "STATUS_NO_DRIVER"]

STATUS_OK = 0
STATUS_NO_DRIVEN = 1    # no bracket of the driven sprocket's equilibrium
STATUS_NO_DRIVER = 2    # no bracket of the driver's

_XTOL = 1e-15
_RTOL = 1e-15
# Brent state: previous, current and blocking points and their residuals, previous and current
# step
B_XPRE, B_XCUR, B_XBLK, B_FPRE, B_FCUR, B_FBLK, B_SPRE, B_SCUR = range(8)


@jit
def _brent_next(B):
    """One iteration of scipy's brentq (scipy/optimize/Zeros/brentq.c) on the state B after the
    residual of B[B_XCUR] went into B[B_FCUR]: returns (done, x) - the root when done, else the
    next point to evaluate (already in B[B_XCUR])."""
    if B[B_FPRE] != 0.0 and B[B_FCUR] != 0.0 and ((B[B_FPRE] < 0.0) != (B[B_FCUR] < 0.0)):
        B[B_XBLK] = B[B_XPRE]
        B[B_FBLK] = B[B_FPRE]
        B[B_SPRE] = B[B_XCUR] - B[B_XPRE]
        B[B_SCUR] = B[B_SPRE]
    if abs(B[B_FBLK]) < abs(B[B_FCUR]):
        B[B_XPRE] = B[B_XCUR]
        B[B_XCUR] = B[B_XBLK]
        B[B_XBLK] = B[B_XPRE]
        B[B_FPRE] = B[B_FCUR]
        B[B_FCUR] = B[B_FBLK]
        B[B_FBLK] = B[B_FPRE]
    xcur = B[B_XCUR]
    fcur = B[B_FCUR]
    delta = (_XTOL + _RTOL * abs(xcur)) / 2.0
    sbis = (B[B_XBLK] - xcur) / 2.0
    if fcur == 0.0 or abs(sbis) < delta:
        return True, xcur
    if abs(B[B_SPRE]) > delta and abs(fcur) < abs(B[B_FPRE]):
        if B[B_XPRE] == B[B_XBLK]:
            stry = -fcur * (xcur - B[B_XPRE]) / (fcur - B[B_FPRE])        # interpolate
        else:                                                             # extrapolate
            dpre = (B[B_FPRE] - fcur) / (B[B_XPRE] - xcur)
            dblk = (B[B_FBLK] - fcur) / (B[B_XBLK] - xcur)
            stry = -fcur * (B[B_FBLK] * dblk - B[B_FPRE] * dpre) / (
                dblk * dpre * (B[B_FBLK] - B[B_FPRE]))
        if 2.0 * abs(stry) < min(abs(B[B_SPRE]), 3.0 * abs(sbis) - delta):
            B[B_SPRE] = B[B_SCUR]                                         # good short step
            B[B_SCUR] = stry
        else:
            B[B_SPRE] = sbis                                              # bisect
            B[B_SCUR] = sbis
    else:
        B[B_SPRE] = sbis
        B[B_SCUR] = sbis
    B[B_XPRE] = xcur
    B[B_FPRE] = fcur
    if abs(B[B_SCUR]) > delta:
        B[B_XCUR] = xcur + B[B_SCUR]
    else:
        B[B_XCUR] = xcur + (delta if sbis > 0 else -delta)
    return False, B[B_XCUR]


@jit
def _brent_start(B, lo, hi, flo, fhi):
    B[B_XPRE] = lo
    B[B_XCUR] = hi
    B[B_XBLK] = 0.0
    B[B_FPRE] = flo
    B[B_FCUR] = fhi
    B[B_FBLK] = 0.0
    B[B_SPRE] = 0.0
    B[B_SCUR] = 0.0


@jit
def _driven_residual(phi1, phi2, theta, load, x, G, P, dx, aux):
    """Rigid shaft: the driven sprocket's acceleration; flexible: the net generalised torque
    J12 phi1'' + J22 phi2'' on it with the driver held at phi1 (state at rest, x's modal part
    kept)."""
    if P[P_RIGID] > 0.5:
        x[0] = phi2
        evaluate(x, phi1, 0.0, 0.0, load, G, P, dx, aux)
        return aux[A_ACC2]
    x[0] = phi1
    x[1] = phi2
    evaluate(x, theta, 0.0, 0.0, load, G, P, dx, aux)
    return P[P_J12] * aux[A_ACC1] + P[P_J22] * aux[A_ACC2]


@jit
def _solve_driven(phi1, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B):
    """The driven rotation of equilibrium for the driver at phi1 (nan if none is bracketed
    within 20 half-tooth widenings)."""
    centre = phi2_kin + (phi1 - theta) * ratio
    lo = centre - 0.5 * a_o
    hi = centre + 0.5 * a_o
    flo = _driven_residual(phi1, lo, theta, load, x, G, P, dx, aux)
    fhi = _driven_residual(phi1, hi, theta, load, x, G, P, dx, aux)
    found = False
    for _ in range(20):
        if flo >= 0.0 >= fhi:
            found = True
            break
        lo = lo - a_o
        hi = hi + a_o
        flo = _driven_residual(phi1, lo, theta, load, x, G, P, dx, aux)
        fhi = _driven_residual(phi1, hi, theta, load, x, G, P, dx, aux)
    if not found:
        return math.nan
    if flo == 0.0:
        return lo
    if fhi == 0.0:
        return hi
    _brent_start(B, lo, hi, flo, fhi)
    for _ in range(100):
        done, v = _brent_next(B)
        if done:
            return v
        B[B_FCUR] = _driven_residual(phi1, v, theta, load, x, G, P, dx, aux)
    return B[B_XCUR]


@jit
def _shaft_residual(phi1, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B):
    """The driver's acceleration with the driven sprocket in its equilibrium for phi1."""
    phi2 = _solve_driven(phi1, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B)
    x[0] = phi1
    x[1] = phi2
    evaluate(x, theta, 0.0, 0.0, load, G, P, dx, aux)
    return aux[A_ACC1]


@jit
def static_state(theta, load, phi2_kin, ratio, a_o, a_c, x, G, P):
    """Fill the state at rest ``x`` (its modal part given) with the equilibrium rotations for
    the input shaft at ``theta`` and the load torque ``load``; phi2_kin the level-0 driven
    rotation at theta, ratio = n_driver / n_driven, a_o and a_c half the sprockets' pitch
    angles. Returns STATUS_OK, STATUS_NO_DRIVEN or STATUS_NO_DRIVER."""
    dx = np.empty(x.size)
    aux = np.empty(A_SIZE)
    B = np.empty(8)
    if P[P_RIGID] > 0.5:
        phi2 = _solve_driven(theta, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B)
        x[0] = phi2
        x[1] = 0.0
        return STATUS_NO_DRIVEN if math.isnan(phi2) else STATUS_OK
    x[2] = 0.0
    x[3] = 0.0
    B2 = np.empty(8)
    lo = theta - 0.5 * a_c
    hi = theta + 0.5 * a_c
    found = False
    flo = 0.0
    fhi = 0.0
    for _ in range(20):
        flo = _shaft_residual(lo, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B)
        fhi = _shaft_residual(hi, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B)
        if math.isnan(flo) or math.isnan(fhi):
            return STATUS_NO_DRIVEN
        if flo >= 0.0 >= fhi:
            found = True
            break
        lo = lo - a_c
        hi = hi + a_c
    if not found:
        return STATUS_NO_DRIVER
    if flo == 0.0:
        phi1 = lo
    elif fhi == 0.0:
        phi1 = hi
    else:
        _brent_start(B2, lo, hi, flo, fhi)
        phi1 = hi
        for _ in range(100):
            done, v = _brent_next(B2)
            phi1 = v
            if done:
                break
            B2[B_FCUR] = _shaft_residual(v, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux,
                                         B)
    phi2 = _solve_driven(phi1, theta, phi2_kin, ratio, a_o, load, x, G, P, dx, aux, B)
    x[0] = phi1
    x[1] = phi2
    x[2] = 0.0
    x[3] = 0.0
    return STATUS_NO_DRIVEN if math.isnan(phi2) else STATUS_OK
