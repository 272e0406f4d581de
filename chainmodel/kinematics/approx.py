"""Closed-form approximations of the tight-span kinematics (seed 000 section 3) and the error
measure of its section 4.4.

Paper conventions as in :mod:`.fourbar`: contact angles theta2 (driven, OA1), theta3 (span
A1 -> B1), theta4 (driver, CB1), all decreasing for forward motion; lengths are made
non-dimensional by L = (N + 1) p (eq 35), so p_bar = 1 / (N + 1), R_bar = R / L.

Every function is vectorised over the driver contact angle theta4.

Departures from the printed equations (checked numerically in tests/test_approx.py):

* eq (49): the second term of A~ is printed with a minus sign; the linearisation of eq (28)
  gives ``A~ = -2 R_o (1 + f p) + 2 R_c R_o (theta4 - pi/2)``, which is what eq (50) uses, so
  eq (50) is implemented as printed;
* eq (51): the printed denominators ``1 - x^2`` are not the two-term Taylor series of
  cos x that the text describes; ``form="corrected"`` (the default) uses ``1 - x^2 / 2``,
  ``form="printed"`` keeps the paper's (it misses the paper's own 0.1 % bound, seeds README);
* eq (26) (step function h): see :mod:`.fourbar` (period [theta4s - 2 alpha_c, theta4s]).

The input-output approximations (50)-(53) need h(theta4), i.e. the seating and release
angles. :func:`approximate` takes them from the exact analysis by default, as the paper does
for its Fig. 4 ("with seating and release positions obtained from the exact analysis");
``events="approximate"`` uses eqs (41) and (46) instead, making the result fully closed form.
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import Drive
from . import fourbar as fb
from .fourbar import Configuration, Kinematics

__all__ = ["approximate_seating", "approximate_release", "approximate_phase", "exact_phase",
           "approximate_driven_angle", "approximate_velocity_ratio", "approximate_span_speed",
           "approximate_acceleration", "approximate", "nrmsd", "VELOCITY_FORMS"]

VELOCITY_FORMS = ("corrected", "printed")


def _check_drive(drive) -> Drive:
    if not isinstance(drive, Drive):
        raise ValueError(f"drive must be a chainmodel.Drive, got {type(drive).__name__}")
    return drive


def _nondim(drive: Drive):
    """(p_bar, R_bar_c, R_bar_o, alpha_c, alpha_o, f) of eq (35)."""
    L = drive.lower_span_length
    return (drive.pitch / L, drive.driver.pitch_radius / L, drive.driven.pitch_radius / L,
            math.pi / drive.n_driver, math.pi / drive.n_driven, drive.pitch_fraction)


# --- events ------------------------------------------------------------------------------------

def approximate_seating(drive: Drive) -> Configuration:
    """Approximate seating configuration (seed 000 eqs 41-43)::

        theta4s = pi/2 + alpha_c + p_bar alpha_o f (f - 1)          (41)
        theta3s = p_bar alpha_o f (f - 1)                           (42)
        theta2s = pi/2 + alpha_o (1 - 2 f)                          (43)
    """
    p, _, _, a_c, a_o, f = _nondim(_check_drive(drive))
    t3 = p * a_o * f * (f - 1.0)
    return Configuration(theta2=math.pi / 2 + a_o * (1.0 - 2.0 * f), theta3=t3,
                         theta4=math.pi / 2 + a_c + t3)


def approximate_release(drive: Drive) -> Configuration:
    """Approximate release configuration (seed 000 eqs 44-46)::

        theta2r = pi/2 - alpha_o - p_bar alpha_c f (f - 1)          (44)
        theta3r = -p_bar alpha_c f (f - 1)                          (45)
        theta4r = pi/2 - alpha_c (1 - 2 f)                          (46)
    """
    p, _, _, a_c, a_o, f = _nondim(_check_drive(drive))
    t3 = -p * a_c * f * (f - 1.0)
    return Configuration(theta2=math.pi / 2 - a_o + t3, theta3=t3,
                         theta4=math.pi / 2 - a_c * (1.0 - 2.0 * f))


def approximate_phase(drive: Drive) -> float:
    """Phase between seating and release, psi = theta4s - theta4r ~ 2 alpha_c (1 - f)
    (seed 000 eq 47) [rad of driver rotation]."""
    _, _, _, a_c, _, f = _nondim(_check_drive(drive))
    return 2.0 * a_c * (1.0 - f)


def exact_phase(drive: Drive) -> float:
    """psi = theta4s - theta4r from the exact events (seed 000 eq 47, left-hand side) [rad]."""
    return fb.seating(_check_drive(drive)).theta4 - fb.release(drive).theta4


# --- input-output ------------------------------------------------------------------------------

def approximate_driven_angle(drive: Drive, theta4, h):
    """Approximate driven contact angle (seed 000 eq 50)::

        theta2 = pi/2 + [p (f - h)(1 + p (f + h) / 2) - R_c (1 + f p)(theta4 - pi/2)]
                        / [R_o R_c (theta4 - pi/2) - R_o (1 + f p)]

    (non-dimensional p, R), with h the span-length step of eq (26) (0 or 1, array).
    """
    p, Rc, Ro, _, _, f = _nondim(_check_drive(drive))
    y = np.asarray(theta4, float) - math.pi / 2
    h = np.asarray(h, float)
    xf = 1.0 + f * p
    num = p * (f - h) * (1.0 + 0.5 * p * (f + h)) - Rc * xf * y
    return math.pi / 2 + num / (Ro * Rc * y - Ro * xf)


def approximate_velocity_ratio(drive: Drive, theta2, theta4, form: str = "corrected"):
    """omega2 / omega4 (seed 000 eq 51)::

        printed:    R_c (1 - (theta4 - pi/2)^2)     / (R_o (1 - (theta2 - pi/2)^2))
        corrected:  R_c (1 - (theta4 - pi/2)^2 / 2) / (R_o (1 - (theta2 - pi/2)^2 / 2))

    ``corrected`` is the two-term Taylor series of cos that the text derives (seeds README).
    """
    _check_drive(drive)
    if form not in VELOCITY_FORMS:
        raise ValueError(f"form must be one of {', '.join(VELOCITY_FORMS)}, got {form!r}")
    k = 1.0 if form == "printed" else 0.5
    x2 = np.asarray(theta2, float) - math.pi / 2
    x4 = np.asarray(theta4, float) - math.pi / 2
    return (drive.driver.pitch_radius * (1.0 - k * x4**2)
            / (drive.driven.pitch_radius * (1.0 - k * x2**2)))


def approximate_span_speed(drive: Drive, theta2, theta4, h, omega4):
    """Span angular velocity omega3 ~ omega4 R_c / (1 + h p) (theta2 - theta4)
    (seed 000 eq 52, non-dimensional R_c, p)."""
    p, Rc, _, _, _, _ = _nondim(_check_drive(drive))
    return (np.asarray(omega4, float) * Rc / (1.0 + p * np.asarray(h, float))
            * (np.asarray(theta2, float) - np.asarray(theta4, float)))


def approximate_acceleration(drive: Drive, theta2, theta4, velocity_ratio, omega4, alpha4):
    """Driven angular acceleration (seed 000 eq 53)::

        alpha2 = alpha4 omega2 / omega4 + omega2^2 (theta2 - pi/2)
                 - omega4^2 (R_c / R_o) (theta4 - pi/2)

    with omega2 / omega4 = ``velocity_ratio`` (eq 51), so omega4 = 0 needs no division.
    """
    _check_drive(drive)
    ratio, w4, a4 = (np.asarray(v, float) for v in (velocity_ratio, omega4, alpha4))
    w2 = ratio * w4
    return (a4 * ratio + w2**2 * (np.asarray(theta2, float) - math.pi / 2)
            - w4**2 * (drive.driver.pitch_radius / drive.driven.pitch_radius)
            * (np.asarray(theta4, float) - math.pi / 2))


def approximate(drive: Drive, theta4, omega4=1.0, alpha4=0.0, *, form: str = "corrected",
                events: str = "exact") -> Kinematics:
    """Closed-form kinematics with the same fields as :func:`.fourbar.exact`.

    theta2 from eq (50), velocity ratio from eq (51) (``form`` "corrected" or "printed"),
    omega3 from eq (52), alpha2 from eq (53), each with the approximate theta2 (never the exact
    one). ``events`` chooses the seating and release angles that define h (eq 26): "exact"
    (default, as in the paper's Fig. 4) or "approximate" (eqs 41 and 46). theta3 is eq (29)
    evaluated at the approximate theta2 (the paper approximates theta3 only at the events,
    eqs 42 and 45); span_length is L + h p (eq 13).

    ``theta4`` is mapped into the tooth period of the chosen events; ``omega4`` and ``alpha4``
    broadcast against it.
    """
    drive = _check_drive(drive)
    if form not in VELOCITY_FORMS:
        raise ValueError(f"form must be one of {', '.join(VELOCITY_FORMS)}, got {form!r}")
    if events == "exact":
        t4s, t4r = fb.seating(drive).theta4, fb.release(drive).theta4
    elif events == "approximate":
        t4s, t4r = approximate_seating(drive).theta4, approximate_release(drive).theta4
    else:
        raise ValueError(f"events must be 'exact' or 'approximate', got {events!r}")
    two_a = 2.0 * math.pi / drive.n_driver
    t4 = t4s - np.mod(t4s - np.asarray(theta4, float), two_a)
    h = (t4 < t4r - fb._EVENT_TOL).astype(np.int8)      # as fourbar.step_h
    t2 = approximate_driven_angle(drive, t4, h)
    ratio = approximate_velocity_ratio(drive, t2, t4, form)
    w4 = np.broadcast_to(np.asarray(omega4, float), t4.shape).copy()
    a4 = np.broadcast_to(np.asarray(alpha4, float), t4.shape).copy()
    w2 = ratio * w4
    w3 = approximate_span_speed(drive, t2, t4, h, w4)
    a2 = approximate_acceleration(drive, t2, t4, ratio, w4, a4)
    # theta3 for completeness: eq (29) at the approximate theta2 (exact geometry of the span)
    four = fb.fourbar(drive)
    t3 = four.span_angle(t2, t4)
    span = drive.lower_span_length + h * drive.pitch
    return Kinematics(t2, t3, t4, span, h, ratio, w2, w3, w4, a2, a4)


# --- error measure -----------------------------------------------------------------------------

def nrmsd(approx, exact) -> float:
    """Normalised root-mean-square deviation of ``approx`` from ``exact`` (seed 000 eq 54)::

        eps = sqrt(mean((approx - exact)^2)) / sqrt(mean(exact^2))

    Note the normalisation by the RMS of the exact values themselves: for theta2 (about pi/2)
    this is the paper's position error, not an error relative to the ripple.
    """
    a = np.asarray(approx, float).ravel()
    x = np.asarray(exact, float).ravel()
    if a.shape != x.shape:
        raise ValueError(f"approx and exact must have the same number of samples, got "
                         f"{a.size} and {x.size}")
    if x.size == 0:
        raise ValueError("nrmsd needs at least one sample")
    den = math.sqrt(float(np.mean(x**2)))
    if den == 0.0:
        raise ValueError("nrmsd is undefined when every exact value is zero")
    return math.sqrt(float(np.mean((a - x) ** 2))) / den
