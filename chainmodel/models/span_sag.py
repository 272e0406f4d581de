"""The spans' own weight in levels 0-2's static tension: the elastic catenary (issue 21 item 4;
docs/reduced_models.md, "One static tension, gravity included").

A span of chord L under the weight w_n per metre normal to it hangs in a shallow parabola whose
arc is longer than its chord by w_n^2 L^3 / (24 T^2) (Irvine, *Cable Structures*, 1981, eq 2.9
with the sag d = w_n L^2 / (8 T)). At rest both spans carry the same tension T, so the chain's
compatibility - the excess the span links and their ends must take up - becomes

    T D - S / T^2 = X - 2 f,   S = sum over spans of w_n^2 L^3 / 24,

with X - 2 f and D = (n_u + n_l) / k + 2 c the seat ladder's (static_tension.static_numerator):
the ladder's own tension T_raw = (X - 2 f) / D is raised to the root of

    T^3 - T_raw T^2 - S / D = 0                                            (:func:`tension`)

one positive root for every T_raw, continuous and increasing in it: a chain with no pretension
carries its sag tension, a pretensioned one T_raw plus a term that fades as S / (D T_raw^2).

Level 2's string modes sag under gravity themselves and their stretching adds the same term in
its span law (seed 004 eq 46): with N modes the sag's modal sum gives S_N = sum w_n^2 L^3 (4 /
pi^4) sum_{odd m <= N} m^-4 (:func:`sag_term` with ``modes``; 97 % of S with one mode, 99.7 %
with three), so level 2's span ends give away that stretch again (wrap_statics.span_ends).
"""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from ..kinematics.wrapping import tooth_period_geometry

__all__ = ["sag_term", "span_terms", "tension", "normal_weights", "along_weights",
           "hanging_tension", "deep", "SHALLOW"]

#: the largest sag-to-chord ratio w_n L / (8 T) for which the shallow parabola is the span's
#: shape (Irvine 1981, ch. 2: a flat-sag cable to about 1:8; here held to 1:10)
SHALLOW = 0.1


def normal_weights(drive: Drive, params: Mapping[str, Any]) -> tuple[tuple[float, float], ...]:
    """((w_n [N/m], L [m]) of the upper span, the same of the lower): the weight per metre
    normal to each span's tooth-period-mean chord, and its mean length. The line of centres is
    inclined by ``drive.inclination`` above the horizontal (the modal model's P_GN)."""
    return _weights(drive, params, 1j)


def along_weights(drive: Drive, params: Mapping[str, Any]) -> tuple[tuple[float, float], ...]:
    """((w_t [N/m], L [m]) of the upper span, the same of the lower): as
    :func:`normal_weights`, the weight per metre along each span's chord."""
    return _weights(drive, params, 1.0)


def _weights(drive, params, turn):
    g = tooth_period_geometry(drive, 100)
    w = params["gravity"] * params["chain.link_mass"] / drive.pitch
    up = 1j * np.exp(1j * (drive.centre_angle - params["drive.inclination"]))
    out = []
    for span in (g.upper, g.lower):
        axis = turn * np.exp(1j * float(np.mean(span.direction)))
        out.append((abs(w * float((np.conj(axis) * up).real)), float(np.mean(span.length))))
    return tuple(out)


def hanging_tension(drive: Drive, params: Mapping[str, Any]) -> float:
    """The least mean tension [N] a span carries at rest under the weight along it, the larger
    of the two spans' w_t L / 2: a hanging chain's tension rises along it by the weight per
    metre times the height climbed (Irvine, *Cable Structures*, 1981, ch. 1: T = H + w y on
    the catenary), and its lower end cannot push, so a span rising h = L w_t / w carries at
    least w h / 2 on the mean over its links, whatever the chain's length asks. What the
    lower end carries (the lower sprocket's hanging wrap, the chain's fit) comes on top: level
    3's statics hold it (wrap_statics._hanging). 0 without weight or a link count; it matters
    where the spans rise steeply (a near-vertical drive, whose spans' normal weight, and with
    it :func:`sag_term`, vanishes)."""
    if drive.links is None or params["gravity"] == 0.0:
        return 0.0
    return max(0.5 * wt * length for wt, length in along_weights(drive, params))


def sag_term(drive: Drive, params: Mapping[str, Any], modes: int | None = None) -> float:
    """S [N^2 m] of the module docstring: sum over spans of w_n^2 L^3 / 24, or with ``modes``
    the part N string modes hold, sum w_n^2 L^3 (4 / pi^4) sum_{odd m <= N} m^-4."""
    return sum(span_terms(drive, params, modes))


def span_terms(drive: Drive, params: Mapping[str, Any],
               modes: int | None = None) -> tuple[float, float]:
    """(S_upper, S_lower) [N^2 m]: :func:`sag_term` per span; (0, 0) without weight."""
    if drive.links is None or params["gravity"] == 0.0:
        return 0.0, 0.0
    share = 1.0 / 24.0
    if modes is not None:
        share = 4.0 / math.pi ** 4 * sum(1.0 / m ** 4 for m in range(1, int(modes) + 1, 2))
    up, low = (share * wn * wn * length ** 3 for wn, length in normal_weights(drive, params))
    return up, low


def tension(raw: float, s_over_d: float) -> float:
    """The positive root T of T^3 - raw T^2 - s_over_d = 0 [N] (module docstring); max(raw, 0)
    without weight (s_over_d = 0)."""
    if s_over_d <= 0.0:
        return max(raw, 0.0)
    # T >= max(raw, 0) and T^3 >= s_over_d; Newton from above the root converges monotonically
    # (the cubic is convex there)
    t = max(raw, 0.0) + s_over_d ** (1.0 / 3.0)
    for _ in range(100):
        f = t * t * (t - raw) - s_over_d
        step = f / (t * (3.0 * t - 2.0 * raw))
        t -= step
        if abs(step) <= 1e-13 * t:
            break
    return t


def deep(drive: Drive, params: Mapping[str, Any], t: float) -> bool:
    """True where a span at tension t [N] sags by more than ``SHALLOW`` of its chord (or t is
    0 under weight): no shallow parabola, so no :func:`tension`. A span with no weight normal
    to it (rounding's, on a vertical drive) does not sag."""
    w = abs(params["gravity"]) * params["chain.link_mass"] / drive.pitch
    return any(wn > 1e-9 * w and wn * length > 8.0 * SHALLOW * t
               for wn, length in normal_weights(drive, params))
