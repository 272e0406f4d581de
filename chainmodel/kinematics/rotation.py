"""Continuous sprocket rotations from the four-bar's contact angles.

The papers' contact angles theta2 and theta4 jump at release and seating; a sprocket does not.
Here the *driver rotation* phi1 and *driven rotation* phi2 are measured positive in the forward
(chain-driving) direction, i.e. clockwise in the seed 000 frame, and both are zero in the
reference configuration: a roller has just seated on the driver from the tight span
(theta4 = theta4s) and the driven endpoint is at theta2 = theta2s. Then, with
k = floor(phi1 / 2 alpha_c) whole tooth periods completed,

    theta4 = theta4s - (phi1 mod 2 alpha_c)
    phi2   = theta2s - theta2(theta4) + 2 alpha_o (k + h(theta4)),

because each release moves the driven endpoint one seat back (theta2 jumps by +2 alpha_o) and
exactly one release happens per driver tooth period. Over one period phi2 therefore grows by
exactly 2 pi / n_o.

Reverse rotation is handled by mirror symmetry: reflecting the drive about the line of centres
OC maps it onto itself with the spans exchanged and the sense of rotation reversed, so the lower
span (tight in reverse) follows the same four-bar. See :func:`driven_rotation`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from typing import TYPE_CHECKING

if TYPE_CHECKING:       # annotations only: geometry imports the wrapping, which imports this
    from ..geometry import Drive
from . import fourbar as fb

__all__ = ["Rotation", "driven_rotation", "driver_contact_angle", "reverse_offset"]


@dataclass(frozen=True)
class Rotation:
    """Driven-sprocket motion for prescribed driver motion (forward-positive, SI units)."""

    driver_angle: np.ndarray
    driven_angle: np.ndarray
    driven_speed: np.ndarray
    driven_acceleration: np.ndarray
    velocity_ratio: np.ndarray
    span_length: np.ndarray       # tight-span length, m
    theta2: np.ndarray            # contact angles of the tight span's four-bar (paper frame of
    theta3: np.ndarray            # the tight span: XY forward, mirrored XY in reverse)
    theta4: np.ndarray
    h: np.ndarray
    periods: np.ndarray           # whole driver tooth periods completed (k)


def driver_contact_angle(drive: Drive, driver_angle):
    """theta4 for a driver rotation phi1 (forward positive) and the completed periods k."""
    s = fb.seating(drive)
    two_a = 2 * math.pi / drive.n_driver
    phi = np.asarray(driver_angle, float)
    k = np.floor(phi / two_a)
    raw = s.theta4 - (phi - k * two_a)
    # Round-off can leave phi - k two_a a hair outside [0, two_a) (phi / two_a rounds to a whole
    # number from below); exact() maps theta4 into its period with fb.in_period, so count k
    # from the period that mapping picks, or phi2 is off by a whole driven tooth at that sample.
    t4 = fb.in_period(drive, raw)
    k = k - np.round((raw - t4) / two_a)
    return t4, k.astype(np.int64)


def _forward(drive: Drive, phi, speed, accel) -> Rotation:
    s = fb.seating(drive)
    alpha_o = math.pi / drive.n_driven
    t4, k = driver_contact_angle(drive, phi)
    # paper convention: theta decreases for forward motion, so omega4 = -speed, alpha4 = -accel
    kin = fb.exact(drive, t4, omega4=-np.asarray(speed, float), alpha4=-np.asarray(accel, float))
    phi2 = s.theta2 - kin.theta2 + 2 * alpha_o * (k + kin.h)
    return Rotation(np.asarray(phi, float) + 0 * phi2, phi2, -kin.omega2, -kin.alpha2,
                    kin.velocity_ratio, kin.span_length, kin.theta2, kin.theta3, kin.theta4,
                    kin.h, k)


@lru_cache(maxsize=256)
def reverse_offset(drive: Drive) -> tuple[float, float]:
    """Constants (d, c) of the reverse relation phi2 = c - F(d - phi1) (see module docstring).

    Mirroring about OC maps a seat at angle a to 2 theta1 - a, so the mirrored drive is at
    driver rotation d - phi1 with d = 2 (theta4s - theta1), and its driven rotation phi2' maps
    back to phi2 = 2 (theta2s - theta1) - phi2' - 2 alpha_o m. The integer m is the one that
    keeps the mean of phi2_reverse - phi2_forward within half a tooth of zero: the chain whose
    link count is nearest the wrapping length (no backlash beyond that).
    """
    s = fb.seating(drive)
    t1 = drive.centre_angle
    d = 2 * (s.theta4 - t1)
    c0 = 2 * (s.theta2 - t1)
    phi = np.linspace(0.0, 2 * math.pi / drive.n_driver, 200, endpoint=False)
    delta = c0 - _forward(drive, d - phi, 0.0, 0.0).driven_angle - _forward(drive, phi, 0.0, 0.0).driven_angle
    two_ao = 2 * math.pi / drive.n_driven
    m = round(float(np.mean(delta)) / two_ao)
    return d, c0 - two_ao * m


def driven_rotation(drive: Drive, driver_angle, driver_speed=0.0, driver_acceleration=0.0,
                    reverse: bool = False) -> Rotation:
    """Driven-sprocket angle, speed and acceleration for a prescribed driver motion.

    All quantities are forward-positive and may be arrays (broadcast together); the driver may
    accelerate. ``reverse=False`` takes the upper span as the tight one (seed 000 four-bar);
    ``reverse=True`` takes the lower span (the driver running backwards pulls on it), through
    the mirror symmetry described in :func:`reverse_offset`. The speeds' signs do not choose the
    branch: the caller does (a kinematic model has no slack to take up when the load reverses).
    """
    phi, w, a = np.broadcast_arrays(np.asarray(driver_angle, float),
                                    np.asarray(driver_speed, float),
                                    np.asarray(driver_acceleration, float))
    if not reverse:
        return _forward(drive, phi, w, a)
    d, c = reverse_offset(drive)
    m = _forward(drive, d - phi, -w, -a)
    return Rotation(phi.copy(), c - m.driven_angle, -m.driven_speed, -m.driven_acceleration,
                    m.velocity_ratio, m.span_length, m.theta2, m.theta3, m.theta4, m.h, m.periods)
