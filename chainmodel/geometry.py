"""Sprockets, chain and drive geometry, with validation of every input.

Conventions follow seed 000 (Fuglede & Thomsen 2016, MMT) section 2.3-2.4: the driven sprocket
O sits at the origin of the XY frame, the X axis runs along the common (upper) tangent of the
two inscribed circles, and the driver C sits at (x_c, y_c) with

    x_c = (N + 1 + f) p,    y_c = r_o - r_c                       (seed 000 eqs 2, 5; seed 004 eq 1)

where N is the number of whole pitches in the lower bound of the tight-span length, f in [0, 1)
the pitch fraction, and r the inscribed radius of a sprocket's pitch polygon (seed 000 eq 1):

    alpha = pi / n,   r = p / (2 tan alpha),   R = p / (2 sin alpha).

Both sprockets turn clockwise in this frame when the chain runs forward; the span on top (the
upper span, pulled by the driver) is the tight span.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache

__all__ = ["Sprocket", "Drive", "check_positive", "check_teeth", "check_fraction",
           "centre_distance_for_links"]


# --- input validation: chainmodel.checks (re-exported here) -------------------------------------

from .checks import (check_fraction, check_positive, check_teeth,  # noqa: E402,F401
                     check_whole, split_tangent_length)


# --- sprocket ----------------------------------------------------------------------------------

@dataclass(frozen=True)
class Sprocket:
    """A sprocket modelled as its pitch polygon (seed 000 eq 1)."""

    teeth: int
    pitch: float

    def __post_init__(self):
        object.__setattr__(self, "teeth", check_teeth("teeth", self.teeth))
        object.__setattr__(self, "pitch", check_positive("pitch", self.pitch))

    @property
    def pitch_angle(self) -> float:
        """Half the angle between neighbouring seats, alpha = pi / n [rad]."""
        return math.pi / self.teeth

    @property
    def pitch_radius(self) -> float:
        """Radius of the circle through the seat centres, R = p / (2 sin alpha) [m]."""
        return self.pitch / (2.0 * math.sin(self.pitch_angle))

    @property
    def inscribed_radius(self) -> float:
        """Radius of the circle inscribed in the pitch polygon, r = p / (2 tan alpha) [m]."""
        return self.pitch / (2.0 * math.tan(self.pitch_angle))


# --- drive -------------------------------------------------------------------------------------

@dataclass(frozen=True)
class Drive:
    """Two sprockets joined by a roller chain; the geometry of seed 000 / seed 004.

    Parameters
    ----------
    n_driver, n_driven : teeth on the driver (C, index c) and the driven sprocket (O, index o).
    pitch : chain and sprocket pitch p [m].
    span_pitches : N, whole pitches in the lower bound (N + f) p of the tight span, N >= 1.
    pitch_fraction : f in [0, 1).
    links : number of links M in the closed chain, or None when only kinematics is wanted.
    name : optional label (presets set it).
    """

    n_driver: int
    n_driven: int
    pitch: float
    span_pitches: int
    pitch_fraction: float
    links: int | None = None
    name: str = field(default="", compare=False)

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, "n_driver", check_teeth("driver sprocket n_driver (drive.driver_teeth)",
                                           self.n_driver))
        set_(self, "n_driven", check_teeth("driven sprocket n_driven (drive.driven_teeth)",
                                           self.n_driven))
        set_(self, "pitch", check_positive("pitch (drive.pitch)", self.pitch))
        set_(self, "span_pitches", check_whole("span_pitches (N)", self.span_pitches, 1))
        set_(self, "pitch_fraction", check_fraction("pitch_fraction (f)", self.pitch_fraction))
        if self.links is not None:
            set_(self, "links", check_whole("links M (drive.links)", self.links, 4))
        gap = self.centre_distance - (self.driver.pitch_radius + self.driven.pitch_radius)
        if gap <= 0.0:
            raise ValueError(
                f"the sprockets overlap: centre distance (drive.centre_distance) "
                f"{self.centre_distance:.6g} m is less than the sum of the pitch radii "
                f"{self.driver.pitch_radius + self.driven.pitch_radius:.6g} m; use a longer span "
                f"(span_pitches = {self.span_pitches}) or smaller sprockets")
        if self.links is not None:
            # Lazy import: the wrapping module needs this class.
            from .kinematics.wrapping import wrap_length_range
            lmin, _, _ = wrap_length_range(self)
            if self.links * self.pitch < lmin * (1.0 - 2e-3):
                raise ValueError(
                    f"a chain of {self.links} links (drive.links) is too short to wrap this "
                    f"drive: it needs at least {lmin / self.pitch:.3f} pitches at centre distance "
                    f"{self.centre_distance:.6g} m (more than 0.2 % stretch); use at least "
                    f"{math.ceil(lmin * (1.0 - 2e-3) / self.pitch - 1e-9)} links, a shorter "
                    f"drive.centre_distance, or drive.centre_distance = 0 (the distance at which "
                    f"the links wrap tightly)")

    # sprockets
    @property
    def driver(self) -> Sprocket:
        return Sprocket(self.n_driver, self.pitch)

    @property
    def driven(self) -> Sprocket:
        return Sprocket(self.n_driven, self.pitch)

    # centre position (seed 000 eqs 2, 5)
    @property
    def x_c(self) -> float:
        """Tangent length |T_o T_c| = (N + 1 + f) p [m]."""
        return (self.span_pitches + 1 + self.pitch_fraction) * self.pitch

    @property
    def y_c(self) -> float:
        """r_o - r_c [m]."""
        return self.driven.inscribed_radius - self.driver.inscribed_radius

    @property
    def centre_distance(self) -> float:
        """|OC| = sqrt(x_c^2 + y_c^2) [m] (seed 000 eq 13, r1)."""
        return math.hypot(self.x_c, self.y_c)

    @property
    def centre_angle(self) -> float:
        """theta_1 = atan2(y_c, x_c): direction of OC in the XY frame [rad]."""
        return math.atan2(self.y_c, self.x_c)

    @property
    def tooth_ratio(self) -> float:
        """Mean speed ratio driven / driver = n_driver / n_driven."""
        return self.n_driver / self.n_driven

    @property
    def lower_span_length(self) -> float:
        """L = (N + 1) p, the shorter of the two tight-span lengths (seed 000 eq 13)."""
        return (self.span_pitches + 1) * self.pitch

    def with_links(self, links: int | None) -> "Drive":
        return Drive(self.n_driver, self.n_driven, self.pitch, self.span_pitches,
                     self.pitch_fraction, links, self.name)

    # --- alternative constructors -----------------------------------------------------------

    @classmethod
    def from_centre_distance(cls, n_driver: int, n_driven: int, pitch: float,
                             centre_distance: float, links: int | None = None,
                             name: str = "") -> "Drive":
        """The drive whose shafts are ``centre_distance`` apart (the inverse of eq 5: N and f
        from the tangent length x_c = sqrt(|OC|^2 - y_c^2))."""
        n_driver = check_teeth("driver sprocket n_driver (drive.driver_teeth)", n_driver)
        n_driven = check_teeth("driven sprocket n_driven (drive.driven_teeth)", n_driven)
        pitch = check_positive("pitch (drive.pitch)", pitch)
        centre_distance = check_positive("centre_distance (drive.centre_distance)",
                                         centre_distance)
        y_c = Sprocket(n_driven, pitch).inscribed_radius - Sprocket(n_driver, pitch).inscribed_radius
        # Valid range: pitch circles apart (R_c + R_o) and N >= 1 (x_c >= 2 p); one bound
        # for both, so the message never suggests a distance that fails the other check.
        radii = Sprocket(n_driven, pitch).pitch_radius + Sprocket(n_driver, pitch).pitch_radius
        least = max(radii, math.hypot(2 * pitch, y_c))
        if centre_distance <= least:
            why = ("the pitch circles overlap" if centre_distance <= radii
                   else "the tight span would hold less than one whole pitch")
            raise ValueError(
                f"drive.centre_distance must exceed {least:.6g} m for sprockets of {n_driver} and "
                f"{n_driven} teeth at pitch {pitch:.6g} m, got {centre_distance:.6g} m: {why}")
        span, frac = split_tangent_length(math.sqrt(centre_distance**2 - y_c**2), pitch)
        return cls(n_driver, n_driven, pitch, span, frac, links, name)

    @classmethod
    def from_links(cls, n_driver: int, n_driven: int, pitch: float, links: int,
                   name: str = "", tight_at: str = "min") -> "Drive":
        """The drive in which a chain of ``links`` links wraps tightly (seed 004 section 2).

        The centre distance is found at which the total wrapping length of seed 004 eq (13),
        minimised over a tooth period, equals ``links * pitch``: at that instant the chain lies
        on both sprockets with both spans straight and unstretched; elsewhere in the period the
        rigid model needs the chain to stretch by L - M p (seed 004 Fig. 2, Table 1).
        ``tight_at="max"`` instead returns the distance at which the chain is nowhere stretched
        (just tight at the longest instant, slack elsewhere).
        """
        return centre_distance_for_links(n_driver, n_driven, pitch, links, name=name,
                                         tight_at=tight_at)


@lru_cache(maxsize=128)
def centre_distance_for_links(n_driver: int, n_driven: int, pitch: float, links: int,
                              name: str = "", tight_at: str = "min") -> Drive:
    """The drive whose chain of ``links`` links wraps tightly (see :meth:`Drive.from_links`)."""
    from scipy.optimize import brentq

    from .kinematics.wrapping import wrap_length_range

    n_driver = check_teeth("driver sprocket (n_driver)", n_driver)
    n_driven = check_teeth("driven sprocket (n_driven)", n_driven)
    pitch = check_positive("pitch", pitch)
    links = check_whole("links (M)", links, 4)
    if tight_at not in ("min", "max"):
        raise ValueError(f"tight_at must be 'min' or 'max', got {tight_at!r}")
    pick = 0 if tight_at == "min" else 2

    def excess(x_over_p: float) -> float:
        span, frac = split_tangent_length(x_over_p * pitch, pitch)
        d = Drive(n_driver, n_driven, pitch, span, frac)
        return wrap_length_range(d, samples=100)[pick] / pitch - links

    # smallest tangent length with N >= 1 that keeps the pitch circles apart
    rc = pitch / (2 * math.sin(math.pi / n_driver))
    ro = pitch / (2 * math.sin(math.pi / n_driven))
    yc = pitch / (2 * math.tan(math.pi / n_driven)) - pitch / (2 * math.tan(math.pi / n_driver))
    x_lo = max(2.0, math.sqrt(max((rc + ro) ** 2 - yc**2, 0.0)) / pitch + 1e-6)
    try:
        lo_val = excess(x_lo)
    except ValueError:
        lo_val = math.nan
    if not (lo_val < 0):
        need = ("" if not math.isfinite(lo_val)
                else f" (it needs at least {math.floor(lo_val + links) + 1} links there)")
        raise ValueError(
            f"a chain of {links} links (drive.links) is too short to wrap sprockets of {n_driver} and "
            f"{n_driven} teeth at any centre distance that keeps them apart{need}; use more links")
    # each extra pitch of tangent length adds about two pitches of wrapping length
    x_hi = x_lo + max(links / 2.0, 2.0)
    x = brentq(excess, x_lo, x_hi, xtol=1e-12, rtol=1e-14)
    span, frac = split_tangent_length(x * pitch, pitch)
    return Drive(n_driver, n_driven, pitch, span, frac, links, name)
