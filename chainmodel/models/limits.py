"""Where the levels stop being valid: physical bounds of the inputs and the speed limits of the
quasi-static levels (docs/stability.md, "Speed limits").

A level that treats a part of the drive as quasi-static (massless, or following another part
rigidly) is valid while the polygonal action excites that part well below its lowest natural
frequency. The forcing's fundamental is the meshing frequency f_z = n_driver |w| / 2 pi; at
f_z = f_n / 2 a single mode of frequency f_n amplifies it by 1 / (1 - 1/4) = 4/3, a third more
than the quasi-static level reports, which we take as the edge of validity:

* level 0 (rigid chain, driver on the input shaft): the driven sprocket's torsional mode on the
  spans' axial stiffness (the driver held) and the spans' first axial mode;
* levels 1-2 (massless axial spans, seed 004 section 5.3's "N_,x = 0"): the spans' first axial
  mode; level 2's transverse modes are modelled and level 1's only enter the tensions at second
  order (span excess length; docs/reduced_models.md).

Every level, level 3 included, holds to small strain: a span tension of at most 5 % of the
link stiffness times the pitch (the bound chain.pretension already has), which bounds the load
torque (the tight span carries load.torque / R_driven) and the speed (the centrifugal tension
rho A v^2 of every link). Angles beyond 1e9 rad are refused because a double then resolves
them to no better than 0.2 micro-radian.
"""

from __future__ import annotations

import math
from typing import Any, Mapping

from ..geometry import Drive

__all__ = ["STRAIN_LIMIT", "ANGLE_LIMIT", "QUASI_STATIC_RATIO", "RPM", "meshing_frequency",
           "chain_speed", "tension_limit", "centrifugal_speed_limit", "span_axial_frequency",
           "speed_for_meshing", "span_string_frequency", "drive_string_frequency",
           "nearest_span_resonance"]

#: largest span strain T / (k_link p) the models hold to
STRAIN_LIMIT = 0.05
#: largest |input_shaft.angle| [rad]
ANGLE_LIMIT = 1e9
#: meshing frequency / lowest neglected natural frequency at the edge of a level's validity
QUASI_STATIC_RATIO = 0.5
from ..units import RPM  # noqa: E402  (one definition: chainmodel.units)


def meshing_frequency(drive: Drive, speed: float) -> float:
    """Tooth (meshing) frequency [Hz] at driver speed ``speed`` [rad/s]: n_driver |w| / 2 pi."""
    return drive.n_driver * abs(speed) / (2 * math.pi)


def speed_for_meshing(drive: Drive, frequency: float) -> float:
    """Driver speed [rad/s] at which the meshing frequency is ``frequency`` [Hz]."""
    return 2 * math.pi * frequency / drive.n_driver


def chain_speed(drive: Drive, speed):
    """Mean chain speed [m/s] at driver speed ``speed`` [rad/s]: n_driver p w / 2 pi (signed;
    the polygon makes the instantaneous span speed vary about it by a factor cos alpha)."""
    return drive.n_driver * drive.pitch * speed / (2 * math.pi)


def tension_limit(drive: Drive, params: Mapping[str, Any]) -> float:
    """Largest span tension [N] the models hold to: STRAIN_LIMIT k_link p."""
    return STRAIN_LIMIT * params["chain.link_stiffness"] * drive.pitch


def centrifugal_speed_limit(drive: Drive, params: Mapping[str, Any]) -> float:
    """Driver speed [rad/s] at which the centrifugal tension rho A v^2 alone reaches
    :func:`tension_limit`."""
    rho = params["chain.link_mass"] / drive.pitch
    v = math.sqrt(tension_limit(drive, params) / rho)
    return 2 * math.pi * v / (drive.n_driver * drive.pitch)


def span_axial_frequency(links: float, params: Mapping[str, Any], seat_compliance: float = 0.0
                         ) -> float:
    """Lowest axial natural frequency [Hz] of a span of ``links`` links held at both ends:
    n - 1 roller masses m between n link springs k, omega = 2 sqrt(k' / m) sin(pi / 2n), with
    k' = 1 / (1/k + c / n) spreading the ends' series compliance c (both ends together, m/N)
    over the links."""
    n = max(float(links), 1.0)
    k = params["chain.link_stiffness"]
    k_eff = 1.0 / (1.0 / k + seat_compliance / n)
    m = params["chain.link_mass"]
    return 2.0 * math.sqrt(k_eff / m) * math.sin(math.pi / (2.0 * n)) / (2.0 * math.pi)


def span_string_frequency(length: float, tension: float, speed: float, rho: float,
                          moving: bool = False) -> float:
    """First transverse natural frequency [Hz] of a span: a string of ``length`` [m] and mass
    ``rho`` [kg/m] moving at the chain speed ``speed`` [m/s] under the material tension
    ``tension`` [N] (the reported span tension, centrifugal part rho v^2 included):
    (1 / 2 l) sqrt((T - rho v^2) / rho), seed 004 eq 61 in dimensional form (its omega_1, the
    Galerkin frequency without the gyroscopic term). With ``moving``, the axially moving
    string's own, lower by the gyroscopic factor sqrt(1 - rho v^2 / T): (c^2 - v^2) / (2 l c),
    c^2 = T / rho (the travelling string's exact modes; Wickert & Mote, "Classical vibration
    analysis of axially moving continua", J. Appl. Mech. 57 (1990) 738-744); for xu2010's
    slack span 0.4 % lower at 120 rpm, 8 % at 600 rpm. 0 where the span carries no more than
    its centrifugal tension."""
    elastic = tension - rho * speed * speed
    if not elastic > 0.0:
        return 0.0
    f = math.sqrt(elastic / rho) / (2.0 * length)
    return f * math.sqrt(elastic / tension) if moving else f


def drive_string_frequency(drive: Drive, params: Mapping[str, Any], tension: float,
                           speed: float) -> float:
    """First transverse natural frequency [Hz] of a span of ``drive`` at the reported tension
    ``tension`` [N] with the driver turning at ``speed`` [rad/s]: :func:`span_string_frequency`
    of the moving string over the spans' tooth-period-mean length
    (:func:`chainmodel.models.chain_inertia.mean_span_length`)."""
    from .chain_inertia import mean_span_length
    return span_string_frequency(mean_span_length(drive), tension, chain_speed(drive, speed),
                                 params["chain.link_mass"] / drive.pitch, moving=True)


def nearest_span_resonance(meshing: float, first_modes: Mapping[str, float],
                           harmonics: int = 2, modes: int = 3) -> tuple[str, int, int, float]:
    """The meshing harmonic k f_m (k = 1..``harmonics``) nearest a span's string mode n f_1
    (n = 1..``modes``, f_1 of each span in ``first_modes``, keyed by its name), as
    (span, k, n, detuning) with detuning = k f_m / (n f_1) - 1; ("", 0, 0, nan) at rest or
    without a span mode. Where it is small the polygonal action drives that mode at resonance
    (k = 1, 2: the meshing's first two harmonics; seed 004 section 6 on tuning the span tension
    away from them), and level 3's spans bow there, which lifts both spans' tension and which
    levels 0-1, without span modes, do not follow (docs/reduced_models.md, "Level 1's running
    slack span: the meshing on the slack span's string modes")."""
    best = ("", 0, 0, math.nan)
    if not meshing > 0.0:
        return best
    for span, f_1 in first_modes.items():
        if not f_1 > 0.0:
            continue
        for k in range(1, harmonics + 1):
            for n in range(1, modes + 1):
                detuning = k * meshing / (n * f_1) - 1.0
                if math.isnan(best[3]) or abs(detuning) < abs(best[3]):
                    best = (span, k, n, detuning)
    return best
