"""Level 0: the kinematic model. No states; the driver follows the input shaft rigidly.

Motion: the driven sprocket follows the exact four-bar kinematics of the tight span (seed 000
eqs 26-32 through :func:`chainmodel.kinematics.driven_rotation`), forward or, when the input
speed is negative, reverse (mirror symmetry: the lower span is then the tight one).

Quasi-static (kinetostatic) forces, derived in docs/kinematics.md section "Level 0 forces": with
the prescribed motion, the sprocket inertias' d'Alembert torques are known, and the spans are
straight two-force members. A span with tension T acting on a seated endpoint roller at angle
theta about its sprocket, the span running in direction theta_s, has the moment arm
R sin(theta - theta_s) (seed 000 eq 30's numerator and denominator). Torque balance:

    driven:  T_u a_uO - T_l a_lO = I2 a2 + d2 w2 + M_load          (seed 004 eq 50, static form)
    driver:  tau_in = I1 a1 + T_u a_uC - T_l a_lC

with u/l the upper and lower span. A rigid chain cannot split these two unknowns; as in seed 004
eqs (15)-(16) we close the system with the sum T_u + T_l = 2 T0, T0 the static span tension
(the chain's pre-strain plus the stretch the centre distance forces on the span links, the
seated links being held by rigid seats). A span cannot push: if one tension would be negative
it is zero and the other carries the whole torque.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from ..kinematics import driven_rotation
from ..kinematics.wrapping import chain_geometry, tooth_period_geometry
from .base import (ALL_OUTPUTS, QUASI_STATIC, Inputs, Model, quasi_static_extras)
from .kinematic_kernel import level0_outputs

__all__ = ["KinematicModel", "static_span_tension", "split_tensions", "seat_stiffness",
           "seat_series_compliance"]


def seat_stiffness(contact_stiffness: float, link_stiffness: float) -> float:
    """Stiffness with which the chain wrapped on a sprocket holds a span end [N/m].

    The span's endpoint roller sits on a seat spring k_c and is tied by a link k_l to the next
    seated roller, which sits on its own seat spring and so on: a ladder whose input stiffness K
    satisfies K = k_c + k_l K / (k_l + K), i.e. K = (k_c + sqrt(k_c^2 + 4 k_c k_l)) / 2
    (docs/reduced_models.md, "equivalent series stiffness")."""
    kc, kl = float(contact_stiffness), float(link_stiffness)
    return 0.5 * (kc + math.sqrt(kc * kc + 4.0 * kc * kl))


def seat_series_compliance(params: Mapping[str, Any]) -> tuple[float, float]:
    """(extra compliance per span [m/N], extra free length per span [m]) of the seats when
    ``torsional.seat_compliance`` is on: two span ends, each 1/K_seat (:func:`seat_stiffness`),
    and the roller-seat clearance R_t - R_r taken up towards the span at each. (0, 0) with
    rigid seats."""
    if not params["torsional.seat_compliance"]:
        return 0.0, 0.0
    k_seat = seat_stiffness(params["contact.stiffness"], params["chain.link_stiffness"])
    clearance = max(0.0, params["contact.seat_radius"] - params["chain.roller_radius"])
    return 2.0 / k_seat, 2.0 * clearance


def static_span_tension(drive: Drive, params: Mapping[str, Any]) -> float:
    """Static span tension at rest, no load [N] (levels 0-2).

    At rest the free driven sprocket turns until both spans carry the same tension. With rigid
    seats only the span links stretch, so the centre distance's excess wrapping length L - M p
    spreads over the n_u + n_l span links:
    T0 = pretension + k_link * <(L - M p) / (n_u + n_l)> over a tooth period, and >= 0.
    With ``torsional.seat_compliance`` the same stretch X = T0 (n_u + n_l) / k_link is shared
    with the four seat compliances c and reduced by the four clearances s
    (:func:`seat_series_compliance`): T = (X - 2 s) / ((n_u + n_l) / k_link + 2 c), >= 0.
    """
    pre = params["chain.pretension"]
    if drive.links is None:
        return pre
    g = tooth_period_geometry(drive, 100)
    links = g.upper_links + g.lower_links
    stretch = (g.wrap_length - drive.links * drive.pitch) / links
    t0 = max(0.0, pre + params["chain.link_stiffness"] * float(np.mean(stretch)))
    c, slack = seat_series_compliance(params)
    if c == 0.0 and slack == 0.0:
        return t0
    flex = float(np.mean(links)) / params["chain.link_stiffness"]
    return max(0.0, (t0 * flex - 2.0 * slack) / (flex + 2.0 * c))


def split_tensions(sum_tension, arm_pull, arm_back, torque):
    """Tensions (T_pull, T_back) with T_pull a_pull - T_back a_back = torque and
    T_pull + T_back = sum_tension, neither negative (vectorised)."""
    t_pull = (torque + sum_tension * arm_back) / (arm_pull + arm_back)
    t_back = sum_tension - t_pull
    t_pull = np.where(t_back < 0, torque / arm_pull, t_pull)
    t_back = np.where(t_back < 0, 0.0, t_back)
    t_back = np.where(t_pull < 0, -torque / arm_back, t_back)
    t_pull = np.where(t_pull < 0, 0.0, t_pull)
    return t_pull, t_back


class KinematicModel(Model):
    """Level 0 (see module docstring)."""

    level = 0
    name = "kinematic"

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        # Level 0 runs without a link count (tensions then come from the pre-strain only).
        self.drive = drive
        self.params = dict(params)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ()

    def initial_state(self, u: Inputs) -> np.ndarray:
        return np.empty(0)

    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        return np.empty(0)

    @cached_property
    def _static_tension(self) -> float:
        return static_span_tension(self.drive, self.params)

    def static_tension(self) -> float:
        return self._static_tension

    def output_descriptions(self) -> dict[str, str]:
        d = super().output_descriptions()
        for name in ("tight_span.tension", "slack_span.tension", "input_shaft.torque"):
            d[name] = QUASI_STATIC + d[name] + " (rigid chain, inertia torques of the prescribed motion)"
        d["tight_span.midspan_deflection"] = (QUASI_STATIC + "static sag of the tight span under "
                                              "gravity at its tension")
        d["chain.max_link_tension"] = QUASI_STATIC + "the larger span tension"
        d["contact.max_force"] = QUASI_STATIC + "the tight-span tension (rigid seats)"
        return d

    def evaluate(self, angle, speed, acceleration, torque, reverse=None) -> dict[str, np.ndarray]:
        """All outputs for arrays of input-shaft motion (vectorised form of :meth:`outputs`).
        ``reverse`` defaults to ``speed < 0`` sample by sample."""
        p, drive = self.params, self.drive
        angle, speed, acceleration, torque = np.broadcast_arrays(
            *(np.asarray(v, float) for v in (angle, speed, acceleration, torque)))
        if reverse is None:
            reverse = speed < 0
        reverse = np.broadcast_to(np.asarray(reverse, bool), angle.shape)
        out = {o.name: np.empty(angle.shape) for o in ALL_OUTPUTS}
        for rev in (False, True):
            sel = reverse == rev
            if not np.any(sel):
                continue
            rot = driven_rotation(drive, angle[sel], speed[sel], acceleration[sel], reverse=rev)
            g = chain_geometry(drive, angle[sel], rot.driven_angle)
            load = (p["driven.inertia"] * rot.driven_acceleration
                    + p["driven.damping"] * rot.driven_speed + torque[sel])
            t_up, t_low = split_tensions(2 * self._static_tension, g.upper.arm_start,
                                         g.lower.arm_end, load)
            tau_in = (p["driver.inertia"] * acceleration[sel] + t_up * g.upper.arm_end
                      - t_low * g.lower.arm_start)
            tight, slack = (t_low, t_up) if rev else (t_up, t_low)
            out["driver.angle"][sel] = angle[sel]
            out["driver.speed"][sel] = speed[sel]
            out["driven.angle"][sel] = rot.driven_angle
            out["driven.speed"][sel] = rot.driven_speed
            out["driven.acceleration"][sel] = rot.driven_acceleration
            out["input_shaft.torque"][sel] = tau_in
            out["tight_span.tension"][sel] = tight
            out["slack_span.tension"][sel] = slack
            out["tight_span.length"][sel] = rot.span_length
            out["velocity_ratio"][sel] = rot.velocity_ratio
            out["transmission_error"][sel] = rot.driven_angle - drive.tooth_ratio * angle[sel]
        out.update(quasi_static_extras(drive, p, out["tight_span.tension"],
                                       out["slack_span.tension"], out["tight_span.length"]))
        return out

    @cached_property
    def _kernel_constants(self):
        """(K, G, C) of the scalar compiled evaluation (:mod:`.kinematic_kernel`)."""
        from . import kinematic_kernel as KK
        from .spans import geometry_constants
        p, d = self.params, self.drive
        C = np.empty(KK.C_SIZE)
        C[KK.C_I1], C[KK.C_I2], C[KK.C_D2] = (p["driver.inertia"], p["driven.inertia"],
                                              p["driven.damping"])
        C[KK.C_SUM] = 2 * self._static_tension
        C[KK.C_RHO_G] = p["chain.link_mass"] / d.pitch * (p["gravity"]
                                                          * math.cos(p["drive.inclination"]))
        C[KK.C_RATIO] = d.tooth_ratio
        return KK.fourbar_constants(d), geometry_constants(d), C

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out) -> None:
        """Every output (ALL_OUTPUTS order) into ``out``: the scalar compiled twin of
        :meth:`evaluate` (:func:`.kinematic_kernel.level0_outputs`), one call; True when all
        are finite."""
        K, G, C = self._kernel_constants
        return level0_outputs(float(angle), float(speed), float(acceleration), float(torque), K, G, C,
                       out)

    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        out = np.empty(len(ALL_OUTPUTS))
        self.outputs_into(t, x, u.angle, u.speed, u.acceleration, u.torque, out)
        return {o.name: float(v) for o, v in zip(ALL_OUTPUTS, out)}

