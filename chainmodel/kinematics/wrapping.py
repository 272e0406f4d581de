"""Both spans, the total wrapping length and the centre distance for a chain of M links
(seed 004 sections 2-3), plus the geometry every dynamic level shares.

Frame and seats (seed 000/004 XY frame): driven sprocket O at the origin, driver C at
(x_c, y_c). For driver rotation phi1 and driven rotation phi2 (forward positive, see
:mod:`.rotation`) the seats sit at

    driver:  theta4s - phi1 + 2 alpha_c j,     driven:  theta2s - phi2 + 2 alpha_o j,   j integer.

Chain rollers are numbered along the direction of travel, roller 0 at the upper span's driven
endpoint in the reference configuration; roller N+1 is then the upper span's driver endpoint.
The roller in driver seat j is N+1-j, the roller in driven seat j is -j (mod M).

Span endpoints (used for both spans, for any rotation, stretched or not): a span runs from an
endpoint A on the sprocket it leaves to an endpoint B on the sprocket it runs onto, in direction
theta_s = arg(B - A). A seated roller is the endpoint while the chain does not bend backwards
over it, i.e. for both ends

    pi/2 - alpha < (endpoint angle) - theta_s <= pi/2 + alpha,

which is the pair of event conditions of seed 000: the seating condition eq (16) at the upper
bound on the seat side and the release condition eq (22) at the lower bound on the leaving side.
With straight, unstretched spans this reproduces the four-bar events exactly; with elastic spans
it moves the events with the span direction, and the endpoint choice stays continuous in length
(the roller that changes sides lies on the span line at the event).

The total wrapping length (seed 004 eq 13, with the seeds README corrections: beta = 2 theta1,
driven-sprocket counts divided by 2 alpha_o, no double count of the released roller)

    L = l_a + l_b + (k_c + k_o) p,

with l_a, l_b the straight span lengths (eq 14 for l_b) and k_c, k_o the links lying on the
driver and driven sprockets between the spans' endpoints.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from typing import TYPE_CHECKING

import numpy as np

from ..checks import check_whole
from . import fourbar as fb
from .rotation import driven_rotation

if TYPE_CHECKING:       # annotations only: geometry imports this module (Drive checks its links)
    from ..geometry import Drive

__all__ = ["SpanGeometry", "ChainGeometry", "chain_geometry", "wrap_length", "wrap_length_range",
           "roller_positions", "tooth_period_samples",
           "tooth_period_geometry"]

_EDGE = 1e-9  # rad: an endpoint exactly at an event belongs to the state after the event


@dataclass(frozen=True)
class SpanGeometry:
    """One straight span for arrays of sprocket rotations.

    ``start`` is the endpoint on the sprocket the chain leaves, ``end`` the endpoint on the one it
    runs onto. Moment arms are positive: tension T gives the leaving-side sprocket a forward
    torque ``arm_start * T`` and resists the arriving-side sprocket with ``arm_end * T``.
    ``links`` counts pitches between the endpoints (filled in where the chain's M is known).
    """

    start: np.ndarray          # complex position of the endpoint roller leaving a sprocket
    end: np.ndarray            # complex position of the endpoint roller arriving on a sprocket
    seat_start: np.ndarray     # seat index j of the start endpoint on its sprocket
    seat_end: np.ndarray       # seat index j of the end endpoint on its sprocket
    angle_start: np.ndarray    # angle of the start endpoint about its sprocket centre
    angle_end: np.ndarray
    direction: np.ndarray      # theta_s = arg(end - start)
    length: np.ndarray
    arm_start: np.ndarray
    arm_end: np.ndarray


@dataclass(frozen=True)
class ChainGeometry:
    """Both spans and the links wrapped on each sprocket.

    ``upper`` runs from the driven sprocket onto the driver (tight when driving forward),
    ``lower`` from the driver onto the driven sprocket. ``wrapped_driver`` and ``wrapped_driven``
    count the pitches lying on each sprocket between the two spans. ``upper_links`` is the
    integer number of pitches in the upper span (from the roller numbering); ``lower_links``
    needs the chain's link count M and is None without it.
    """

    upper: SpanGeometry
    lower: SpanGeometry
    wrapped_driver: np.ndarray
    wrapped_driven: np.ndarray
    upper_links: np.ndarray
    lower_links: np.ndarray | None

    @property
    def wrap_length(self) -> np.ndarray:
        p = self._pitch
        return self.upper.length + self.lower.length + (self.wrapped_driver + self.wrapped_driven) * p

    _pitch: float = 0.0


def _span(c_from, radius_from, alpha_from, phase_from, c_to, radius_to, alpha_to, phase_to,
          direction0, edge=_EDGE):
    """Endpoints of a straight span between two sprockets (vectorised over the phases).

    Seats on the 'from' sprocket lie at phase_from + 2 alpha_from j, likewise 'to'. Iterates
    the window condition (module docstring) to a fixed point; two or three passes suffice
    because the span direction moves by less than a pitch angle between candidates.
    """
    phase_from, phase_to = np.broadcast_arrays(np.asarray(phase_from, float),
                                               np.asarray(phase_to, float))
    direction = np.full(phase_from.shape, float(direction0))
    j_from = j_to = None
    for _ in range(8):
        jf = np.floor((direction + math.pi / 2 + alpha_from - phase_from) / (2 * alpha_from) + edge)
        jt = np.floor((direction + math.pi / 2 + alpha_to - phase_to) / (2 * alpha_to) + edge)
        ang_f = phase_from + 2 * alpha_from * jf
        ang_t = phase_to + 2 * alpha_to * jt
        a = c_from + radius_from * np.exp(1j * ang_f)
        b = c_to + radius_to * np.exp(1j * ang_t)
        new_dir = np.angle(b - a)
        # keep the direction continuous with the initial guess (no 2 pi wrap in the window test)
        new_dir = direction0 + np.mod(new_dir - direction0 + math.pi, 2 * math.pi) - math.pi
        if j_from is not None and np.array_equal(jf, j_from) and np.array_equal(jt, j_to):
            direction = new_dir
            break
        moving = None if j_from is None else (jf != j_from) | (jt != j_to)
        j_from, j_to, direction = jf, jt, new_dir
    else:
        # Within about edge (in seat units) *before* an event the tolerant window flips between
        # the two candidate endpoints (each one's span direction selects the other); the strict
        # window settles those samples, while exactly at an event the tolerant one settles.
        if edge == 0.0 or moving is None:  # pragma: no cover
            raise RuntimeError("span endpoint search did not settle")
        sub = _span(c_from, radius_from, alpha_from, phase_from[moving], c_to, radius_to,
                    alpha_to, phase_to[moving], direction0, edge=0.0)
        jf, jt, ang_f, ang_t, a, b, direction = (np.array(v) for v in (jf, jt, ang_f, ang_t, a,
                                                                        b, direction))
        jf[moving], jt[moving] = sub.seat_start, sub.seat_end
        ang_f[moving], ang_t[moving] = sub.angle_start, sub.angle_end
        a[moving], b[moving], direction[moving] = sub.start, sub.end, sub.direction
    vec = b - a
    length = np.abs(vec)
    arm_f = radius_from * np.sin(ang_f - direction)
    arm_t = radius_to * np.sin(ang_t - direction)
    return SpanGeometry(a, b, jf.astype(np.int64), jt.astype(np.int64), ang_f, ang_t, direction,
                        length, arm_f, arm_t)


def chain_geometry(drive: Drive, driver_angle, driven_angle) -> ChainGeometry:
    """Both spans for arrays of driver and driven rotations (forward positive, rad).

    Works for any pair of rotations: the spans may be stretched or slack, the endpoints and the
    link counts follow seating and release. This is the geometry of level 0 (with the driven
    rotation from the four-bar), of level 1 (any pair) and the initial state of level 3.
    """
    s = fb.seating(drive)
    a_c, a_o = math.pi / drive.n_driver, math.pi / drive.n_driven
    R_c, R_o = drive.driver.pitch_radius, drive.driven.pitch_radius
    O, C = 0.0 + 0.0j, complex(drive.x_c, drive.y_c)
    phase_c = s.theta4 - np.asarray(driver_angle, float)
    phase_o = s.theta2 - np.asarray(driven_angle, float)
    theta1 = drive.centre_angle
    upper = _span(O, R_o, a_o, phase_o, C, R_c, a_c, phase_c, 0.0)
    lower = _span(C, R_c, a_c, phase_c, O, R_o, a_o, phase_o, math.pi + 2 * theta1)
    # lower-span seat indices taken on the wrapped side of each upper endpoint
    n_c, n_o = drive.n_driver, drive.n_driven
    j_lc = lower.seat_start - n_c * np.floor((lower.seat_start - upper.seat_end + n_c - 1) / n_c)
    j_lo = lower.seat_end - n_o * np.floor((lower.seat_end - upper.seat_start - 1) / n_o)
    lower = SpanGeometry(lower.start, lower.end, j_lc.astype(np.int64), j_lo.astype(np.int64),
                         lower.angle_start, lower.angle_end, lower.direction, lower.length,
                         lower.arm_start, lower.arm_end)
    wrapped_c = upper.seat_end - j_lc          # pitches on the driver between the spans
    wrapped_o = j_lo - upper.seat_start        # pitches on the driven sprocket
    upper_links = drive.span_pitches + 1 - upper.seat_end + upper.seat_start
    lower_links = None
    if drive.links is not None:
        lower_links = drive.links - upper_links - wrapped_c - wrapped_o
    return ChainGeometry(upper, lower, wrapped_c.astype(np.int64), wrapped_o.astype(np.int64),
                         upper_links.astype(np.int64),
                         None if lower_links is None else lower_links.astype(np.int64),
                         _pitch=drive.pitch)


def tooth_period_samples(drive: Drive, samples: int = 400) -> np.ndarray:
    """``samples`` driver rotations evenly over one tooth period [0, 2 pi / n_c)."""
    samples = check_whole("samples", samples, 2)
    return np.arange(samples) * (2 * math.pi / drive.n_driver / samples)


@lru_cache(maxsize=64)
def tooth_period_geometry(drive: Drive, samples: int = 100) -> ChainGeometry:
    """:func:`chain_geometry` of the level-0 configuration (driven rotation from the four-bar)
    at ``samples`` driver rotations over one tooth period, computed once per drive and process
    (the reduced models' tooth-period means and the static tension use it at every set-up)."""
    phi1 = tooth_period_samples(drive, samples)
    return chain_geometry(drive, phi1, driven_rotation(drive, phi1).driven_angle)


def wrap_length(drive: Drive, theta4=None, *, driver_angle=None) -> np.ndarray:
    """Total wrapping length L [m] (seed 004 eq 13) with the tight span straight and rigid.

    Give either the paper's driver contact angle ``theta4`` (as DESIGN.md's
    ``kinematics.wrap_length(drive, theta4)``) or, by keyword, the driver rotation
    ``driver_angle`` (forward positive, 0 at seating); with neither, 400 samples over one tooth
    period.
    """
    if theta4 is not None and driver_angle is not None:
        raise ValueError("give theta4 or driver_angle, not both")
    if theta4 is not None:
        s = fb.seating(drive)
        driver_angle = s.theta4 - fb.in_period(drive, theta4)
    if driver_angle is None:
        driver_angle = tooth_period_samples(drive)
    phi1 = np.asarray(driver_angle, float)
    phi2 = driven_rotation(drive, phi1).driven_angle
    return chain_geometry(drive, phi1, phi2).wrap_length


_INV_PHI = (math.sqrt(5.0) - 1.0) / 2.0


def _golden_min(f, lo: float, hi: float, xatol: float) -> tuple[float, float]:
    """(f(x*), x*) of a unimodal f on [lo, hi] by golden-section search to ``xatol``. Here
    rather than scipy.optimize.minimize_scalar: importing scipy.optimize costs ~0.7 s, which
    every process (and every FMU instantiation) paid for this one bracket."""
    c, d = hi - _INV_PHI * (hi - lo), lo + _INV_PHI * (hi - lo)
    fc, fd = f(c), f(d)
    while hi - lo > xatol:
        if fc < fd:
            hi, d, fd = d, c, fc
            c = hi - _INV_PHI * (hi - lo)
            fc = f(c)
        else:
            lo, c, fc = c, d, fd
            d = lo + _INV_PHI * (hi - lo)
            fd = f(d)
    return (fc, c) if fc < fd else (fd, d)


def _min_over_period(fun, period: float, samples: int = 200) -> tuple[float, float]:
    """Minimum of a tooth-periodic function: dense samples, then golden-section refinement."""
    x = np.arange(samples) * (period / samples)
    y = fun(x)
    i = int(np.argmin(y))
    lo, hi = x[i] - period / samples, x[i] + period / samples
    fmin, xmin = _golden_min(lambda v: float(fun(np.array([v]))[0]), lo, hi, period * 1e-9)
    return (fmin, xmin) if fmin < y[i] else (float(y[i]), float(x[i]))


def wrap_length_range(drive: Drive, samples: int = 200) -> tuple[float, float, float]:
    """(L_min, L_mean, L_max) over one tooth period [m]; min and max refined beyond the samples,
    the mean from ``samples`` evenly spaced driver angles (seed 004 Table 1 used about 100)."""
    period = 2 * math.pi / drive.n_driver
    lmin, _ = _min_over_period(lambda v: wrap_length(drive, driver_angle=v), period, samples)
    lmax, _ = _min_over_period(lambda v: -wrap_length(drive, driver_angle=v), period, samples)
    mean = float(np.mean(wrap_length(drive, driver_angle=tooth_period_samples(drive, samples))))
    return lmin, mean, -lmax


def roller_positions(drive: Drive, driver_angle: float, driven_angle: float) -> np.ndarray:
    """Positions (M x 2, m, XY frame) of all M rollers for given sprocket rotations, in roller
    order (roller 0 is the upper span's driven endpoint in the reference configuration).

    Seated rollers sit at their seats; each span's rollers are spaced evenly on the straight
    line between its endpoints. This is the rigid layout of seed 004 section 2 (exact when the
    wrapping length equals M p) and the initial state of the multibody model.
    """
    if drive.links is None:
        raise ValueError("roller_positions needs the chain's number of links (Drive.links)")
    g = chain_geometry(drive, np.atleast_1d(float(driver_angle)), np.atleast_1d(float(driven_angle)))
    M, N = drive.links, drive.span_pitches
    s = fb.seating(drive)
    a_c, a_o = math.pi / drive.n_driver, math.pi / drive.n_driven
    R_c, R_o = drive.driver.pitch_radius, drive.driven.pitch_radius
    C = complex(drive.x_c, drive.y_c)
    pos = np.empty(M, complex)
    filled = np.zeros(M, bool)

    def put(index, z):
        idx = np.mod(index, M)
        pos[idx] = z
        filled[idx] = True

    jA, jB = int(g.upper.seat_start[0]), int(g.upper.seat_end[0])
    jlc, jlo = int(g.lower.seat_start[0]), int(g.lower.seat_end[0])
    # rollers seated on the driver: seats jlc..jB, roller N+1-j
    j = np.arange(jlc, jB + 1)
    put(N + 1 - j, C + R_c * np.exp(1j * (s.theta4 - driver_angle + 2 * a_c * j)))
    # rollers seated on the driven sprocket: seats jA..jlo, roller -j
    j = np.arange(jA, jlo + 1)
    put(-j, R_o * np.exp(1j * (s.theta2 - driven_angle + 2 * a_o * j)))
    # upper span: from roller -jA (at A) forward to roller N+1-jB (at B)
    n_up = int(g.upper_links[0])
    t = np.arange(1, n_up) / n_up
    put(-jA + np.arange(1, n_up), g.upper.start[0] + t * (g.upper.end[0] - g.upper.start[0]))
    # lower span: from roller N+1-jlc (on the driver) forward to roller -jlo (on the driven)
    n_low = int(g.lower_links[0])
    if n_low < 1:
        raise ValueError(f"a chain of {M} links cannot wrap this drive (lower span would hold "
                         f"{n_low} links)")
    t = np.arange(1, n_low) / n_low
    put(N + 1 - jlc + np.arange(1, n_low), g.lower.start[0] + t * (g.lower.end[0] - g.lower.start[0]))
    if not filled.all():  # pragma: no cover - a counting error would be a bug
        raise RuntimeError("roller layout left rollers unplaced")
    return np.column_stack([pos.real, pos.imag])
