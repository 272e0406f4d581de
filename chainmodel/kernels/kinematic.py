"""Scalar compiled evaluation of level 0 (the kinematic model) for one sample: what the FMU
evaluates once per communication step, where the vectorised library functions cost tens of
microseconds of numpy overhead for a single angle.

It is the same computation, in the same order, as the vectorised path
(:meth:`chainmodel.models.kinematic.KinematicModel.evaluate`):

* :func:`driven_rotation` - seed 000 eqs 26-32 through the continuous rotations of
  :func:`chainmodel.kinematics.driven_rotation` (driver contact angle and whole tooth periods,
  the four-bar's driven angle, span angle, velocity ratio, speeds and accelerations; reverse
  rotation by the mirror symmetry of :func:`chainmodel.kinematics.rotation.reverse_offset`);
* both spans' moment arms from the scalar span geometry of :mod:`.spans` (the twin of
  :func:`chainmodel.kinematics.wrapping.chain_geometry`);
* the quasi-static tensions of :func:`chainmodel.models.kinematic.split_tensions`, the input
  torque and :func:`chainmodel.models.base.quasi_static_extras`.

tests/test_level0.py checks it against the vectorised library to 1e-12 over many angles, forward
and reverse, compiled and plain Python (``.py_func``).
"""

from __future__ import annotations

import math

import numpy as np

from .._numba import jit
from ..outputs import (O_CHAIN_MAX_LINK_TENSION, O_CHAIN_MIN_LINK_TENSION, O_CONTACT_MAX_FORCE,
                       O_DRIVEN_ACCELERATION, O_DRIVEN_ANGLE, O_DRIVEN_SPEED, O_DRIVER_ANGLE,
                       O_DRIVER_SPEED, O_INPUT_SHAFT_TORQUE, O_SLACK_SPAN_TENSION,
                       O_TIGHT_SPAN_LENGTH, O_TIGHT_SPAN_MIDSPAN_DEFLECTION, O_TIGHT_SPAN_TENSION,
                       O_TRANSMISSION_ERROR, O_VELOCITY_RATIO)
from .spans import span_geometry
from .span_roles import lower_tight

__all__ = ["fourbar_constants", "driven_rotation", "level0_outputs", "split", "split_many",
           "K_SIZE", "C_SIZE"]

# --- four-bar constants (fourbar_constants) -----------------------------------------------------
(K_TH4S, K_TH2S, K_TH4R, K_TWO_AC, K_AO, K_R1, K_R2, K_R4, K_TH1, K_L, K_PITCH, K_REV_D,
 K_REV_C) = range(13)
K_SIZE = 13

# --- level-0 constants (KinematicModel._kernel_constants) --------------------------------------
#: driver inertia, driven inertia, driven damping, sum of the spans' raw tensions (2 T0; 2 (T0 -
#: b^2 / T0) under a floor), rho * g_n for the sag, tooth ratio n_driver / n_driven, centrifugal
#: tension per (rad/s)^2 of the driver, the wrap fit's floor b (0: none; :func:`split`)
C_I1, C_I2, C_D2, C_SUM, C_RHO_G, C_RATIO, C_CENTRIFUGAL, C_FLOOR = range(8)
#: each span's sag term times its stiffness, k_eff S [N^3] (torsional.sag_lag; 0: none)
C_KS_UP, C_KS_LOW = 8, 9
#: the span roles' hold (span_roles.lower_tight): +1 upper tight, -1 lower, 0 from the inputs
C_ROLE = 10
#: the least mean tension a span carries under the weight along it [N] (span_sag.
#: hanging_tension; 0: none)
C_HANG = 11
C_SIZE = 12

_EVENT_TOL = 1e-12   # chainmodel.kinematics.fourbar._EVENT_TOL


def fourbar_constants(drive) -> np.ndarray:
    """The constant vector of :func:`driven_rotation` for ``drive``."""
    from ..kinematics import fourbar as fb
    from ..kinematics.rotation import reverse_offset
    f = fb.fourbar(drive)
    s, r = fb.seating(drive), fb.release(drive)
    d, c = reverse_offset(drive)
    return np.array([s.theta4, s.theta2, r.theta4, 2 * math.pi / drive.n_driver,
                     math.pi / drive.n_driven, f.r1, f.r2, f.r4, f.theta1, f.L, f.pitch, d, c],
                    float)


@jit
def _solve_trig(a, b, c, near):
    """fourbar.solve_trig for one sample; nan when the linkage cannot be assembled."""
    rho = math.hypot(a, b)
    ratio = -c / rho
    if abs(ratio) > 1.0 + 1e-12:
        return math.nan
    delta = math.atan2(b, a)
    spread = math.acos(min(max(ratio, -1.0), 1.0))
    two_pi = 2.0 * math.pi
    plus = near + ((delta + spread - near + math.pi) % two_pi) - math.pi
    minus = near + ((delta - spread - near + math.pi) % two_pi) - math.pi
    if abs(minus - near) < abs(plus - near):
        return minus
    return plus


@jit
def _in_period(theta4, K):
    return K[K_TH4S] - ((K[K_TH4S] - theta4) % K[K_TWO_AC])


@jit
def _forward(phi, w, a, K):
    """rotation._forward for one sample: (phi2, speed2, acc2, velocity_ratio, span_length)."""
    two_a = K[K_TWO_AC]
    # driver_contact_angle
    k = math.floor(phi / two_a)
    raw = K[K_TH4S] - (phi - k * two_a)
    t4 = _in_period(raw, K)
    k = k - round((raw - t4) / two_a)
    # fourbar.exact (which maps theta4 into the period once more)
    t4 = _in_period(t4, K)
    h = 1.0 if t4 < K[K_TH4R] - _EVENT_TOL else 0.0
    r1 = K[K_R1]
    r2 = K[K_R2]
    r4 = K[K_R4]
    t1 = K[K_TH1]
    r3 = K[K_L] + h * K[K_PITCH]
    cos4 = math.cos(t4)
    sin4 = math.sin(t4)
    ca = -2 * r1 * r2 * math.cos(t1) - 2 * r4 * r2 * cos4
    cb = -2 * r1 * r2 * math.sin(t1) - 2 * r4 * r2 * sin4
    cc = r1**2 + r4**2 + r2**2 - r3 ** 2 + 2 * r1 * r4 * math.cos(t1 - t4)
    t2 = _solve_trig(ca, cb, cc, 0.5 * math.pi)
    t3 = math.atan2(r1 * math.sin(t1) + r4 * sin4 - r2 * math.sin(t2),
                    r1 * math.cos(t1) + r4 * cos4 - r2 * math.cos(t2))
    s23 = math.sin(t2 - t3)
    ratio = r4 * math.sin(t4 - t3) / (r2 * s23)
    w4 = -w
    a4 = -a
    w2 = ratio * w4
    w3 = w4 * r4 * math.sin(t2 - t4) / (r3 * s23)
    a2 = a4 * ratio + (w4**2 * r4 * math.cos(t4 - t3) - w2**2 * r2 * math.cos(t2 - t3)
                       - w3**2 * r3) / (r2 * s23)
    phi2 = K[K_TH2S] - t2 + 2 * K[K_AO] * (k + h)
    return phi2, -w2, -a2, ratio, r3


@jit
def driven_rotation(phi, w, a, reverse, K):
    """chainmodel.kinematics.driven_rotation for one sample (forward, or reverse through the
    mirror symmetry): (driven angle, driven speed, driven acceleration, velocity ratio,
    tight-span length)."""
    if not reverse:
        return _forward(phi, w, a, K)
    phi2, w2, a2, ratio, r3 = _forward(K[K_REV_D] - phi, -w, -a, K)
    return K[K_REV_C] - phi2, -w2, -a2, ratio, r3


@jit
def split(total, floor, arm_pull, arm_back, load, ks_pull=0.0, ks_back=0.0, hang=0.0):
    """:func:`_split`, neither span below ``hang`` [N], the least mean tension a span carries
    under the weight along it (span_sag.hanging_tension): a span whose law would leave it
    below hangs from its upper end, its lower end looping off the sprocket, and the other
    span carries the torque balance on top of it."""
    t_pull, t_back = _split(total, floor, arm_pull, arm_back, load, ks_pull, ks_back)
    if t_back >= hang and t_pull >= hang:
        return t_pull, t_back
    # one span at the floor, the other by the torque balance: the one the balance leaves at or
    # above it
    on_back = (load + hang * arm_back) / arm_pull
    if on_back >= hang:
        return on_back, hang
    return hang, (hang * arm_pull - load) / arm_back


@jit
def _split(total, floor, arm_pull, arm_back, load, ks_pull=0.0, ks_back=0.0):
    """Quasi-static span tensions (T_pull, T_back) of a rigid chain: T_pull a_pull - T_back
    a_back = load, the spans' linear (raw) tensions summing to ``total``.

    Without a floor or sag (``floor`` = ``ks_*`` = 0: the seat ladder's linear law) the
    tensions are the raw ones, T_pull + T_back = total, and a span that would push carries 0
    (seed 004 eqs 15-16). With the wrap fit's floor b (torsional.wrap_statics: levels 1-2's
    span law, kernels/spans.py ``_tension``) and each span's sag k_eff S (torsional.sag_lag:
    the elastic catenary, level 1's lagged sag held quasi-statically) each tension is
    T = softplus(raw + k_eff S / T^2, b), whose inverse is raw = T - b^2 / T - k_eff S / T^2.
    With the torque balance giving one tension from the other, the raw sum g = sum (T - b^2 /
    T - k_eff S / T^2) - total is increasing and concave in either, and -> -inf where it -> 0,
    so Newton's method from a point where g <= 0 rises monotonically to the root."""
    if floor <= 0.0 and ks_pull <= 0.0 and ks_back <= 0.0:
        t_pull = (load + total * arm_back) / (arm_pull + arm_back)
        t_back = total - t_pull
        if t_back < 0:
            t_pull = load / arm_pull
            t_back = 0.0
        if t_pull < 0:
            t_back = -load / arm_back
            t_pull = 0.0
        return t_pull, t_back
    # Newton on the span that carries less (the back span when the load is positive): its
    # tension s has lower bound 0 and the other follows without cancellation
    if load >= 0.0:
        s, q = _floored_root(total, floor, arm_back / arm_pull, load / arm_pull, ks_back,
                             ks_pull)
        return q, s
    return _floored_root(total, floor, arm_pull / arm_back, -load / arm_back, ks_pull, ks_back)


@jit
def _floored_root(total, floor, ratio, offset, ks_s=0.0, ks_q=0.0):
    """(s, q) with q = offset + ratio s, offset >= 0, s - b^2 / s - ks_s / s^2 + q - b^2 / q -
    ks_q / q^2 = total: Newton from the left of the root (:func:`split`)."""
    b2 = floor * floor
    s = (total - offset) / (1.0 + ratio)           # the linear split's, or b
    if s < floor:
        s = floor
    if s <= 0.0:
        s = 1e-9 * (abs(total) + offset + floor + 1.0)
    for _ in range(1100):                          # a start with g <= 0: halve toward 0
        q = offset + ratio * s
        if s - b2 / s - ks_s / (s * s) + q - b2 / q - ks_q / (q * q) - total <= 0.0:
            break
        s *= 0.5
    for _ in range(200):
        q = offset + ratio * s
        g = s - b2 / s - ks_s / (s * s) + q - b2 / q - ks_q / (q * q) - total
        step = -g / (1.0 + b2 / (s * s) + 2.0 * ks_s / (s * s * s)
                     + ratio * (1.0 + b2 / (q * q) + 2.0 * ks_q / (q * q * q)))
        s += step
        if step <= 1e-14 * (s + floor):
            break
    return s, offset + ratio * s


@jit
def split_many(total, floor, arm_pull, arm_back, load, t_pull, t_back, ks_pull=0.0,
               ks_back=0.0, hang=0.0):
    """:func:`split` over arrays, into ``t_pull`` and ``t_back``."""
    for i in range(load.shape[0]):
        t_pull[i], t_back[i] = split(total, floor, arm_pull[i], arm_back[i], load[i], ks_pull,
                                     ks_back, hang)


@jit
def level0_outputs(angle, speed, acc, torque, K, G, C, out):
    """Every output of level 0 (ALL_OUTPUTS order) for the input-shaft motion (angle, speed,
    acc) and the load torque into ``out``: the tight span is the one the driver pulls for the
    direction of the transmitted torque (chainmodel.kernels.span_roles), and the reported span
    and link tensions include the centrifugal tension C[C_CENTRIFUGAL] speed^2, the sag and the seat
    force not (KinematicModel.evaluate). True when every output is finite."""
    rev = speed < 0.0
    phi2, w2, a2, ratio, length = driven_rotation(angle, speed, acc, rev, K)
    g = span_geometry(angle, phi2, G)
    up_start = g[1]
    up_end = g[2]
    low_start = g[10]
    low_end = g[11]
    load = C[C_I2] * a2 + C[C_D2] * w2 + torque
    t_up, t_low = split(C[C_SUM], C[C_FLOOR], up_start, low_end, load, C[C_KS_UP],
                        C[C_KS_LOW], C[C_HANG])
    tau_in = C[C_I1] * acc + t_up * up_end - t_low * low_start
    if not lower_tight(torque, C[C_D2], C[C_I2], C[C_RATIO], speed, acc, C[C_ROLE]):
        tight = t_up
        slack = t_low
        length = g[0]
    else:
        tight = t_low
        slack = t_up
        length = g[9]
    centrifugal = C[C_CENTRIFUGAL] * speed * speed
    out[O_DRIVER_ANGLE] = angle
    out[O_DRIVER_SPEED] = speed
    out[O_DRIVEN_ANGLE] = phi2
    out[O_DRIVEN_SPEED] = w2
    out[O_DRIVEN_ACCELERATION] = a2
    out[O_INPUT_SHAFT_TORQUE] = tau_in
    out[O_TIGHT_SPAN_TENSION] = tight + centrifugal
    out[O_SLACK_SPAN_TENSION] = slack + centrifugal
    out[O_TIGHT_SPAN_LENGTH] = length
    out[O_VELOCITY_RATIO] = ratio
    out[O_TRANSMISSION_ERROR] = phi2 - C[C_RATIO] * angle
    # quasi_static_extras: static sag of the tight span, reported negative
    sag = math.inf
    if tight != 0.0:
        sag = C[C_RHO_G] * length ** 2 / (8.0 * tight)
    if tight > 0 and math.isfinite(sag):
        out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = -min(sag, length / 2)
    else:
        out[O_TIGHT_SPAN_MIDSPAN_DEFLECTION] = -(length / 2)
    out[O_CHAIN_MAX_LINK_TENSION] = max(tight, slack) + centrifugal
    out[O_CONTACT_MAX_FORCE] = tight
    out[O_CHAIN_MIN_LINK_TENSION] = min(tight, slack) + centrifugal
    for k in range(out.shape[0]):
        if not math.isfinite(out[k]):
            return False
    return True
