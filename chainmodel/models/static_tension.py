"""The chain at rest, shared by every level: the seats' stiffness and the wrapped links'
tension, the static span tension a pre-strain gives, and the refusal of a pretension that
cannot be a pre-strain (docs/stability.md, "Pretension"; docs/reduced_models.md, "equivalent
series stiffness"). A module of its own so that the Model base class (which refuses such a
pretension for every level) and the levels import it without importing each other;
:mod:`chainmodel.models.kinematic` re-exports every name."""

from __future__ import annotations

import math
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from ..kinematics.wrapping import tooth_period_geometry

__all__ = ["static_span_tension", "seat_stiffness", "seat_series_compliance", "seated_tension",
           "pretension_error", "loose_chain_error", "rest_geometry", "static_numerator"]


def seat_stiffness(contact_stiffness: float, link_stiffness: float) -> float:
    """Stiffness with which the chain wrapped on a sprocket holds a span end [N/m].

    The span's endpoint roller sits on a seat spring k_c and is tied by a link k_l to the next
    seated roller, which sits on its own seat spring and so on: a ladder whose input stiffness K
    satisfies K = k_c + k_l K / (k_l + K), i.e. K = (k_c + sqrt(k_c^2 + 4 k_c k_l)) / 2
    (docs/reduced_models.md, "equivalent series stiffness")."""
    kc, kl = float(contact_stiffness), float(link_stiffness)
    return 0.5 * (kc + math.sqrt(kc * kc + 4.0 * kc * kl))


def seated_tension(params: Mapping[str, Any], teeth: int) -> float:
    """Tension [N] of the links wrapped on a sprocket of ``teeth`` teeth at rest, with the
    seats' compliance (``torsional.seat_compliance``; with rigid seats the links are held at the
    pitch and carry ``chain.pretension``).

    A wrapped roller pulled by two links of tension T sits at the bottom of its seat, the
    clearance s = R_t - R_r inside the pitch circle and further in by the contact spring's
    2 T sin(alpha) / k_c (alpha = pi / teeth), so a seated link spans
    p - 2 (s + 2 T sin(alpha) / k_c) sin(alpha) and, pre-strained to the free length
    p - pretension / k_link, carries
    T = (pretension - 2 k_link s sin(alpha)) / (1 + 4 k_link sin^2(alpha) / k_c), >= 0
    (a link does not push: below that the roller lies loose in its seat)."""
    pre = params["chain.pretension"]
    if not params["torsional.seat_compliance"]:
        return pre
    k, kc = params["chain.link_stiffness"], params["contact.stiffness"]
    clearance = max(0.0, params["contact.seat_radius"] - params["chain.roller_radius"])
    sa = math.sin(math.pi / teeth)
    return max(0.0, (pre - 2.0 * k * clearance * sa) / (1.0 + 4.0 * k * sa * sa / kc))


def seat_series_compliance(params: Mapping[str, Any], drive: Drive | None = None
                           ) -> tuple[float, float]:
    """(extra compliance per span [m/N], extra free length per span [m]) of the seats when
    ``torsional.seat_compliance`` is on; (0, 0) with rigid seats.

    A span end is held by the chain wrapped on its sprocket: the end roller on a seat spring,
    tied by a link to the next seated roller and so on, a ladder of stiffness K_seat
    (:func:`seat_stiffness`). The ladder gives way to the difference between the span's
    tension T and the wrapped links' own tension T_w (:func:`seated_tension`, the pre-strain
    they carry): the end moves towards the span by s + (T - T_w) / K_seat, s = R_t - R_r the
    roller-seat clearance. Per span (one end on each sprocket) that is the compliance
    2 / K_seat and the free length 2 s - (T_w,driver + T_w,driven) / K_seat; without ``drive``
    the wrapped links are taken as unstrained (T_w = 0)."""
    if not params["torsional.seat_compliance"]:
        return 0.0, 0.0
    k_seat = seat_stiffness(params["contact.stiffness"], params["chain.link_stiffness"])
    clearance = max(0.0, params["contact.seat_radius"] - params["chain.roller_radius"])
    wrapped = 0.0
    if drive is not None:
        wrapped = seated_tension(params, drive.n_driver) + seated_tension(params, drive.n_driven)
    return 2.0 / k_seat, 2.0 * clearance - wrapped / k_seat


def rest_geometry(drive: Drive) -> tuple[float, float]:
    """(excess L - M p, span link count n_u + n_l) at rest (four-bar), as tooth-period means:
    the excess as <(L - M p) / (n_u + n_l)> <n_u + n_l>, the mean stretch of a span link."""
    g = tooth_period_geometry(drive, 100)
    links = g.upper_links + g.lower_links
    n = float(np.mean(links))
    return float(np.mean((g.wrap_length - drive.links * drive.pitch) / links)) * n, n


def static_numerator(drive: Drive, params: Mapping[str, Any]) -> tuple[float, float]:
    """(X, D) with the static span tension T = max(0, X / D) (:func:`static_span_tension`)."""
    k = params["chain.link_stiffness"]
    excess, links = rest_geometry(drive)
    c, free = seat_series_compliance(params, drive)
    x = excess + links * params["chain.pretension"] / k - 2.0 * free
    return x, links / k + 2.0 * c


def static_span_tension(drive: Drive, params: Mapping[str, Any]) -> float:
    """Static span tension at rest, no load [N] (levels 0-2; docs/stability.md, "Pretension").

    ``chain.pretension`` is a pre-strain of every link: its free length is
    p - pretension / k_link (the same at every level; level 3 builds its links so). At rest the
    free driven sprocket turns until both spans carry the same tension T. The n_u + n_l span
    links must stretch over the wrapping length's excess L - M p (tooth-period mean; the
    rigid layout of seed 004 section 2) less their pre-strain, and each span's two ends give
    way as :func:`seat_series_compliance` says (free length f, compliance c per span), so

        T = max(0, (L - M p + (n_u + n_l) pretension / k_link - 2 f) / ((n_u + n_l) / k_link + 2 c)).

    With rigid seats (f = c = 0) that is pretension + k_link (L - M p) / (n_u + n_l): the wrapped
    links, held at the pitch, carry the pre-strain and the span links all of the excess. The
    clamp at zero comes last (a slack chain; :func:`pretension_error` refuses a pretension
    that does not take the slack up).
    """
    if drive.links is None:
        return params["chain.pretension"]
    x, d = static_numerator(drive, params)
    return max(0.0, x / d)


def loose_chain_error(drive: Drive, params: Mapping[str, Any]) -> str | None:
    """A sentence if the chain is longer than its wrapping length (tooth-period mean) by more
    than the seats' clearances (2 (R_t - R_r) per span) take up, else None: such a chain hangs
    slack at rest, and no pre-strain is a model of its tension (docs/stability.md)."""
    if drive.links is None:
        return None
    excess, _ = rest_geometry(drive)
    clearance = max(0.0, params["contact.seat_radius"] - params["chain.roller_radius"])
    if excess + 4.0 * clearance > 0.0:
        return None
    from ..geometry import Drive as _Drive
    try:
        tight = _Drive.from_links(drive.n_driver, drive.n_driven, drive.pitch, drive.links)
        where = (f"drive.centre_distance = {tight.centre_distance:.6g} m (or 0) holds "
                 f"{drive.links} links taut")
    except ValueError:  # pragma: no cover - from_links refuses only impossible chains
        where = "use a longer drive.centre_distance"
    return (f"a chain of drive.links = {drive.links} is {-1e3 * excess:.3g} mm longer than its "
            f"wrapping length at centre distance {drive.centre_distance:.6g} m, so it hangs "
            f"slack at rest; {where}, or use fewer links")


def pretension_error(drive: Drive, params: Mapping[str, Any]) -> str | None:
    """A sentence if ``chain.pretension`` > 0 cannot be a pre-strain of this chain, else None;
    every level refuses it (one definition of pretension, docs/stability.md): the chain is
    longer than its wrapping length (:func:`loose_chain_error`), so a pre-strain would have
    to take up whole links' slack, which the wrapped links then carry and the levels' seat
    models treat too differently (xu2010 with 47 links: 1.2 kN at levels 0-2, 4.2 kN at
    level 3 for the same 27 kN pretension). The criterion is geometric, the same at every
    level."""
    pre = params["chain.pretension"]
    if pre <= 0.0 or drive.links is None:
        return None
    loose = loose_chain_error(drive, params)
    if loose is not None:
        return f"chain.pretension = {pre:g} N is refused: {loose}"
    return None
