"""Exact kinematics of the tight span as a four-bar mechanism (seed 000, sections 2.5-2.13).

Paper conventions (seed 000 Fig. 2): driven sprocket O at the origin, driver C at (x_c, y_c),
both turning clockwise, so the contact angles theta2 (driven, vector OA1) and theta4 (driver,
vector CB1) *decrease* with time. theta3 is the direction of the span A1 -> B1 (the direction
the chain travels). All functions here are vectorised over theta4.

Departures from the printed equations (each checked numerically in tests/test_fourbar.py):

* eq (26): one tooth period is theta4 in [theta4s - 2 alpha_c, theta4s] (the printed lower limit
  has the wrong sign); h = 0 on [theta4r, theta4s] and h = 1 below theta4r;
* eqs (21), (25), (29): atan2 instead of arctan, which folds angles beyond pi/2;
* eqs (19)-(20): of the two roots of A cos x + B sin x + C = 0 we take the one closest to pi/2
  (the same-direction branch); written as x = atan2(B, A) +- arccos(-C / hypot(A, B)), which is
  the same pair of roots as the half-angle form without its division by C - A.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from typing import TYPE_CHECKING

if TYPE_CHECKING:       # annotations only: geometry imports the wrapping, which imports this
    from ..geometry import Drive

__all__ = ["Configuration", "FourBar", "fourbar", "seating", "release", "exact", "Kinematics",
           "solve_trig"]


def solve_trig(a, b, c, near=math.pi / 2):
    """Root of ``a cos x + b sin x + c = 0`` closest to ``near`` (seed 000 eqs 19-20).

    Raises ValueError when no real root exists (the linkage cannot be assembled)."""
    a, b, c = np.broadcast_arrays(np.asarray(a, float), np.asarray(b, float), np.asarray(c, float))
    rho = np.hypot(a, b)
    ratio = -c / rho
    if np.any(np.abs(ratio) > 1.0 + 1e-12):
        raise ValueError("the four-bar linkage cannot be assembled for this geometry "
                         "(the span cannot reach between the sprockets)")
    delta = np.arctan2(b, a)
    spread = np.arccos(np.clip(ratio, -1.0, 1.0))
    # bring each root to within pi of `near`, then pick the closer one (the first on a tie)
    plus = near + np.mod(delta + spread - near + np.pi, 2 * np.pi) - np.pi
    minus = near + np.mod(delta - spread - near + np.pi, 2 * np.pi) - np.pi
    out = np.where(np.abs(minus - near) < np.abs(plus - near), minus, plus)
    return out if out.ndim else float(out)


@dataclass(frozen=True)
class Configuration:
    """Angles of the four-bar at an event [rad], paper conventions."""

    theta2: float
    theta3: float
    theta4: float


@dataclass(frozen=True)
class FourBar:
    """Link lengths and fixed angle of the tight-span four-bar O A1 B1 C (seed 000 eq 13).

    ``n_release`` teeth on the sprocket at the origin (the chain leaves it: the driven sprocket O
    for the upper span), ``n_seat`` teeth on the other (the chain seats on it: the driver C).
    ``links_after_seating`` is the span's link count right after a seating event (N + 1 in the
    paper; N only for the degenerate f = 0 drives where release lags seating).
    """

    n_release: int
    n_seat: int
    pitch: float
    x_c: float
    links_after_seating: int

    @property
    def alpha_o(self) -> float:
        return math.pi / self.n_release

    @property
    def alpha_c(self) -> float:
        return math.pi / self.n_seat

    @property
    def r1(self) -> float:
        return math.hypot(self.x_c, self.y_c)

    @property
    def y_c(self) -> float:
        return (self.pitch / (2 * math.tan(self.alpha_o))
                - self.pitch / (2 * math.tan(self.alpha_c)))

    @property
    def theta1(self) -> float:
        return math.atan2(self.y_c, self.x_c)

    @property
    def r2(self) -> float:
        return self.pitch / (2 * math.sin(self.alpha_o))

    @property
    def r4(self) -> float:
        return self.pitch / (2 * math.sin(self.alpha_c))

    @property
    def L(self) -> float:
        """Span length right after seating (h = 0), seed 000 eq (13)."""
        return self.links_after_seating * self.pitch

    # --- events -------------------------------------------------------------------------

    def seating(self) -> Configuration:
        """Roller just seated on the driver (seed 000 eqs 16-21)."""
        r1, r2, r3, r4, t1 = self.r1, self.r2, self.L, self.r4, self.theta1
        gamma = math.pi / 2 + self.alpha_c
        a = 2 * r1 * r4 * math.cos(t1) - 2 * r1 * r3 * math.cos(t1 + gamma)      # eq 18
        b = 2 * r1 * r4 * math.sin(t1) - 2 * r1 * r3 * math.sin(t1 + gamma)
        c = r1**2 + r4**2 + r3**2 - r2**2 - 2 * r4 * r3 * math.cos(gamma)
        t4 = solve_trig(a, b, c)                                                  # eqs 19-20
        t3 = t4 - gamma                                                           # eq 16
        t2 = math.atan2(r1 * math.sin(t1) + r4 * math.sin(t4) - r3 * math.sin(t3),  # eq 21
                        r1 * math.cos(t1) + r4 * math.cos(t4) - r3 * math.cos(t3))
        return Configuration(t2, t3, t4)

    def release(self) -> Configuration:
        """Roller just released from the driven sprocket (seed 000 eqs 22-25)."""
        r1, r2, r3, r4, t1 = self.r1, self.r2, self.L, self.r4, self.theta1
        mu = math.pi / 2 + self.alpha_o
        a = -2 * r2 * r1 * math.cos(t1) - 2 * r3 * r1 * (                          # eq 24
            math.cos(t1) * math.cos(mu - math.pi) + math.sin(t1) * math.sin(mu - math.pi))
        b = -2 * r2 * r1 * math.sin(t1) + 2 * r3 * r1 * (
            math.cos(t1) * math.sin(mu - math.pi) - math.sin(t1) * math.cos(mu - math.pi))
        c = r2**2 + r3**2 + r1**2 - r4**2 + 2 * r2 * r3 * math.cos(mu - math.pi)
        t2 = solve_trig(a, b, c)
        t3 = mu + t2 - math.pi                                                    # eq 22
        t4 = math.atan2(r2 * math.sin(t2) + r3 * math.sin(t3) - r1 * math.sin(t1),  # eq 25
                        r2 * math.cos(t2) + r3 * math.cos(t3) - r1 * math.cos(t1))
        return Configuration(t2, t3, t4)

    # --- input-output ---------------------------------------------------------------------

    def driven_angle(self, theta4, span_length, cos4=None, sin4=None):
        """theta2 for given theta4 and span length r3 (seed 000 eqs 27-28).
        ``cos4``, ``sin4``: cos and sin of theta4 when the caller has them already."""
        r1, r2, r4, t1 = self.r1, self.r2, self.r4, self.theta1
        theta4 = np.asarray(theta4, float)
        cos4 = np.cos(theta4) if cos4 is None else cos4
        sin4 = np.sin(theta4) if sin4 is None else sin4
        a = -2 * r1 * r2 * math.cos(t1) - 2 * r4 * r2 * cos4
        b = -2 * r1 * r2 * math.sin(t1) - 2 * r4 * r2 * sin4
        c = r1**2 + r4**2 + r2**2 - np.asarray(span_length) ** 2 + 2 * r1 * r4 * np.cos(t1 - theta4)
        return solve_trig(a, b, c)

    def span_angle(self, theta2, theta4, cos4=None, sin4=None):
        """theta3, direction of A1 -> B1 (seed 000 eq 29, with atan2)."""
        r1, r2, r4, t1 = self.r1, self.r2, self.r4, self.theta1
        cos4 = np.cos(theta4) if cos4 is None else cos4
        sin4 = np.sin(theta4) if sin4 is None else sin4
        return np.arctan2(r1 * math.sin(t1) + r4 * sin4 - r2 * np.sin(theta2),
                          r1 * math.cos(t1) + r4 * cos4 - r2 * np.cos(theta2))


def _consistent(fb: FourBar) -> tuple[Configuration, Configuration] | None:
    s, r = fb.seating(), fb.release()
    tol = 1e-9
    if s.theta4 - 2 * fb.alpha_c - tol <= r.theta4 <= s.theta4 + tol:
        return s, r
    return None


@lru_cache(maxsize=256)
def _fourbar_cached(n_release: int, n_seat: int, pitch: float, x_c: float, span_pitches: int):
    # Ordinary drives: N + 1 links right after seating (seed 000 eq 13). At f = 0 some extreme
    # drives release *after* the next seating; then the lengths alternate N p, (N + 1) p.
    for links in (span_pitches + 1, span_pitches, span_pitches + 2):
        fb = FourBar(n_release, n_seat, pitch, x_c, links)
        try:
            ev = _consistent(fb)
        except ValueError:
            continue
        if ev is not None:
            return fb, ev[0], ev[1]
    raise ValueError(
        f"no consistent seating/release sequence for n_release={n_release}, n_seat={n_seat}, "
        f"x_c={x_c:.6g} m: the tight span cannot be assembled for this geometry")


def fourbar(drive: Drive, lower: bool = False) -> FourBar:
    """The tight-span four-bar of ``drive`` (``lower=True``: the lower span's four-bar, seed 004
    section 2.2: the roles of the sprockets swap, n_c <-> n_o, in the X'Y' frame)."""
    return _events(drive, lower)[0]


def _events(drive: Drive, lower: bool = False):
    n_rel, n_seat = (drive.n_driver, drive.n_driven) if lower else (drive.n_driven, drive.n_driver)
    return _fourbar_cached(n_rel, n_seat, drive.pitch, drive.x_c, drive.span_pitches)


def seating(drive: Drive, lower: bool = False) -> Configuration:
    """Exact configuration (theta2s, theta3s, theta4s) at which a roller seats on the driver
    (seed 000 eqs 16-21). ``lower=True`` gives the lower span's in its X'Y' frame, where the
    roller seats on the driven sprocket (seed 004 section 2.2)."""
    return _events(drive, lower)[1]


def release(drive: Drive, lower: bool = False) -> Configuration:
    """Exact configuration (theta2r, theta3r, theta4r) at which a roller leaves the driven
    sprocket (seed 000 eqs 22-25); ``lower=True`` as in :func:`seating`."""
    return _events(drive, lower)[2]


_EVENT_TOL = 1e-12  # rad of driver angle


@dataclass(frozen=True)
class Kinematics:
    """Four-bar state over an array of driver contact angles (paper conventions, SI units).

    ``omega*`` and ``alpha*`` are d/dt of the paper's angles; both sprockets turning forward
    makes omega2 and omega4 negative. ``velocity_ratio = omega2 / omega4`` is sign-free.
    """

    theta2: np.ndarray
    theta3: np.ndarray
    theta4: np.ndarray
    span_length: np.ndarray
    h: np.ndarray
    velocity_ratio: np.ndarray
    omega2: np.ndarray
    omega3: np.ndarray
    omega4: np.ndarray
    alpha2: np.ndarray
    alpha4: np.ndarray


def in_period(drive: Drive, theta4) -> np.ndarray:
    """Map any theta4 into the tooth period (theta4s - 2 alpha_c, theta4s] (seed 000 eq 26 as
    corrected); theta4s itself stays (a roller has just seated)."""
    fb, s, _ = _events(drive)
    two_a = 2 * fb.alpha_c
    return s.theta4 - np.mod(s.theta4 - np.asarray(theta4, float), two_a)


def step_h(drive: Drive, theta4) -> np.ndarray:
    """h(theta4) of seed 000 eq (26), corrected: 0 on [theta4r, theta4s], 1 below theta4r."""
    _, _, r = _events(drive)
    # strictly past release: at f = 0 release coincides with the next seating and round-off can
    # leave a sliver below theta4r where h = 1 would give a spurious (N + 2) p span
    return (in_period(drive, theta4) < r.theta4 - _EVENT_TOL).astype(np.int8)


def exact(drive: Drive, theta4, omega4=1.0, alpha4=0.0) -> Kinematics:
    """Exact position, velocity and acceleration of the tight-span four-bar (seed 000 eqs 26-32).

    ``theta4`` may be any array of driver contact angles; each is first mapped into one tooth
    period. ``omega4`` and ``alpha4`` (scalars or arrays broadcasting against ``theta4``) are the
    driver's d(theta4)/dt and d^2(theta4)/dt^2; the driver may accelerate.
    """
    fb, _, rel = _events(drive)
    t4 = in_period(drive, theta4)
    # h of step_h, from t4 itself: mapping t4 into the period a second time can move a sample
    # at the period's end (just before seating) by an ulp onto theta4s, pairing it with h = 0
    h = (t4 < rel.theta4 - _EVENT_TOL).astype(np.int8)
    r3 = fb.L + h * fb.pitch                                                     # eq 13
    cos4, sin4 = np.cos(t4), np.sin(t4)
    t2 = fb.driven_angle(t4, r3, cos4, sin4)                                     # eqs 27-28
    t3 = fb.span_angle(t2, t4, cos4, sin4)                                       # eq 29
    r2, r4 = fb.r2, fb.r4
    s23 = np.sin(t2 - t3)
    ratio = r4 * np.sin(t4 - t3) / (r2 * s23)                                    # eq 30
    w4 = np.broadcast_to(np.asarray(omega4, float), t4.shape)
    a4 = np.broadcast_to(np.asarray(alpha4, float), t4.shape)
    w2 = ratio * w4
    w3 = w4 * r4 * np.sin(t2 - t4) / (r3 * s23)                                  # eq 31
    a2 = a4 * ratio + (w4**2 * r4 * np.cos(t4 - t3) - w2**2 * r2 * np.cos(t2 - t3)
                       - w3**2 * r3) / (r2 * s23)                                # eq 32
    return Kinematics(t2, t3, t4, r3, h, ratio, w2, w3, w4.copy(), a2, a4.copy())
