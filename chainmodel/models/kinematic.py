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
seated links being held by rigid seats; with seat compliance see :func:`static_span_tension`).
A span cannot push: if one tension would be negative it is zero and the other carries the whole
torque. With ``torsional.wrap_statics`` (the default) T0 is level 3's static tension and each
span follows levels 1-2's law with the fit's floor b under the slack span: the spans' raw
tensions T - b^2 / T keep their sum, so under load the slack span stays on the floor's knee
as at levels 1-3 instead of dropping to what a linear split leaves it
(:func:`chainmodel.kernels.kinematic.split`). The reported tensions add the centrifugal tension rho A v^2 to both spans (not to the
torques), and the tight span is the one the power flow names (kernels/span_roles.py).
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from ..kinematics import driven_rotation
from ..kinematics.wrapping import chain_geometry
from . import limits
from .base import (ALL_OUTPUTS, QUASI_STATIC, Inputs, Model, centrifugal_tension,
                   check_pretension, quasi_static_extras)
from ..kernels.kinematic import level0_outputs
from ..kernels.span_roles import lower_tight_many
from .static_tension import (loose_chain_error, pretension_error,  # noqa: F401  (re-exported)
                             seat_series_compliance, seat_stiffness, seated_tension,
                             static_span_tension)

__all__ = ["KinematicModel", "static_span_tension", "split_tensions", "seat_stiffness",
           "seat_series_compliance", "seated_tension", "pretension_error", "loose_chain_error"]


def split_tensions(sum_tension, arm_pull, arm_back, torque, floor=0.0, ks_pull=0.0,
                   ks_back=0.0, hang=0.0):
    """Tensions (T_pull, T_back) with T_pull a_pull - T_back a_back = torque and the raw
    tensions summing to ``sum_tension``; without a ``floor`` or sag the tensions are the raw
    ones, neither negative; with them each is the floored, sagging law of levels 1-2; neither
    below ``hang``, the weight along the spans' floor (vectorised
    :func:`chainmodel.kernels.kinematic.split`)."""
    from ..kernels.kinematic import split_many
    arm_pull, arm_back, torque = np.broadcast_arrays(
        *(np.ascontiguousarray(v, dtype=float) for v in (arm_pull, arm_back, torque)))
    shape = torque.shape
    t_pull, t_back = np.empty(torque.size), np.empty(torque.size)
    split_many(float(sum_tension), float(floor), arm_pull.ravel(), arm_back.ravel(),
               torque.ravel(), t_pull, t_back, float(ks_pull), float(ks_back), float(hang))
    return t_pull.reshape(shape), t_back.reshape(shape)


class KinematicModel(Model):
    """Level 0 (see module docstring)."""

    level = 0
    name = "kinematic"
    vectorised = True

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        # Level 0 runs without a link count (tensions then come from the pre-strain only).
        self.drive = drive
        self.params = dict(params)
        check_pretension(drive, self.params)

    @property
    def state_names(self) -> tuple[str, ...]:
        return ()

    def initial_state(self, u: Inputs) -> np.ndarray:
        return np.empty(0)

    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        return np.empty(0)

    @cached_property
    def _frequencies(self) -> tuple[float, float]:
        """(driven sprocket's torsional frequency with the driver held, spans' first axial
        frequency) [Hz]: the modes this level treats as rigid. From the level-1 model of the
        same drive (its mass matrix and span stiffness with the mean link counts); a drive
        without a link count takes both spans at the upper span's N + 1 links."""
        from .torsional import TorsionalModel
        p = self.params
        if self.drive.links is not None:
            # the loaded seats' elastic ends (TorsionalModel.axial_frequency), so no wrap fit
            m1 = TorsionalModel(self.drive, dict(p, **{"input_shaft.rigid": True,
                                                       "torsional.wrap_statics": False}))
            r, c = m1.reference, m1.loaded_seat_compliance()
            j22 = float(m1.mass_matrix()[1, 1])
            n_up, n_low = r["n_up_min"], r["n_low_min"]
            f_ax = m1.axial_frequency()
        else:
            c = seat_series_compliance(p)[0]
            j22 = p["driven.inertia"]
            n_up = n_low = self.drive.span_pitches + 1
            f_ax = limits.span_axial_frequency(n_up, p, c)
        k = sum(1.0 / (max(n, 1.0) / p["chain.link_stiffness"] + c) for n in (n_up, n_low))
        ro = self.drive.driven.pitch_radius
        return math.sqrt(k * ro * ro / j22) / (2 * math.pi), f_ax

    def speed_limit(self) -> tuple[float, str]:
        """Level 0 takes the chain as rigid and the driven sprocket as following it: valid while
        the meshing frequency is below limits.QUASI_STATIC_RATIO of the driven sprocket's
        torsional frequency on the spans and of the spans' first axial frequency (and below
        the centrifugal strain bound of every level)."""
        w_c, why_c = super().speed_limit()
        f_t, f_ax = self._frequencies
        which = ("driven sprocket's torsional" if f_t <= f_ax else "spans' first axial")
        f = min(f_t, f_ax)
        w = limits.speed_for_meshing(self.drive, limits.QUASI_STATIC_RATIO * f)
        if w_c < w:
            return w_c, why_c
        return w, (f"the meshing frequency would exceed {limits.QUASI_STATIC_RATIO:g} x the "
                   f"{which} natural frequency ({f:.4g} Hz), which the rigid chain of this level "
                   "cannot follow; use fidelity 1 or higher, or a lower speed")

    @cached_property
    def _static_tension(self) -> float:
        from .wrap_statics import static_span_tension as with_wrap   # the seat ladder or level 3's
        return with_wrap(self.drive, self.params)

    def static_tension(self) -> float:
        return self._static_tension

    @cached_property
    def _held_tension(self) -> float:
        from .wrap_statics import held_span_tension
        return held_span_tension(self.drive, self.params)

    def held_tension(self) -> float:
        """The tension the spans carry at rest, no load [N] (level 1's :meth:`~chainmodel.
        models.torsional.TorsionalModel.held_tension`: with ``torsional.wrap_statics`` level
        3's tooth-period mean, else the static tension)."""
        return self._held_tension

    @cached_property
    def _floor(self) -> float:
        """The wrap fit's floor b [N] under the slack span (torsional.wrap_statics, where
        honoured; span_ends gives 0, the linear law, everywhere else)."""
        from .wrap_statics import span_ends
        return 0.0 if self.drive.links is None else float(span_ends(self.drive, self.params)[2])

    @cached_property
    def _hang(self) -> float:
        """The least mean tension a span carries under the weight along it [N]
        (:func:`~chainmodel.models.span_sag.hanging_tension`): neither span goes below it."""
        from .span_sag import hanging_tension
        return hanging_tension(self.drive, self.params)

    @cached_property
    def _sag_ks(self) -> tuple[float, float]:
        """(upper, lower) span's sag term times its stiffness, k_eff S [N^3]
        (:func:`~chainmodel.models.wrap_statics.straight_span_sags`, ``torsional.sag_lag``):
        level 1's lagged sag held quasi-statically, so a slack span under load hangs on its sag
        tension as in level 3 (docs/reduced_models.md, "Level 1's lagged sag"); k_eff =
        1 / (n / k + c) with n the tooth-period-mean link count and c the span ends'
        compliance. (0, 0) without it."""
        from .wrap_statics import span_ends, straight_span_sags
        p, d = self.params, self.drive
        if d.links is None or not p.get("torsional.sag_lag", True):
            return 0.0, 0.0
        sags = straight_span_sags(d, p)
        if not max(sags) > 0.0:
            return 0.0, 0.0
        from ..kernels.spans import span_stiffness
        from .chain_inertia import reference_geometry
        r = reference_geometry(d)
        c = span_ends(d, p, stretch=sum(sags))[0]
        k = p["chain.link_stiffness"]
        return tuple(s * span_stiffness(n, k, 0.0, c)[0]
                     for s, n in zip(sags, (r["n_up"], r["n_low"])))

    @cached_property
    def _raw_sum(self) -> float:
        """The sum of the spans' raw (linear-law) tensions, which a rigid chain keeps: 2 T_h,
        less b^2 / T_h per span under the floor b and k_eff S / T_h^2 per span with its sag
        (the raw tension whose law gives T_h), T_h the tension the spans hold at rest
        (:meth:`held_tension`)."""
        from .wrap_statics import raw_tension
        t = self._held_tension
        sag = sum(self._sag_ks) / (t * t) if t > 0 else 0.0
        return 2.0 * raw_tension(t, self._floor) - sag

    def quasi_static_spans(self, load: float) -> tuple[float, float]:
        """(pulling, back) span tensions [N] of this level's rigid chain carrying the driven
        torque ``load`` [N m] (load, damping and inertia torques together) on arms of the
        driven pitch radius, centrifugal tension left out: the spans' law and raw sum of
        :meth:`evaluate` (seed 004 eqs 15-16 with the sag and floor of levels 1-2) without the
        polygon's swing of the arms, what the spans hold where they do not vibrate
        (chainmodel.validity judges level 2's span-modes line at it)."""
        from ..kernels.kinematic import split
        r = self.drive.driven.pitch_radius
        return split(self._raw_sum, self._floor, r, r, float(load), *self._sag_ks, self._hang)

    def output_descriptions(self) -> dict[str, str]:
        d = super().output_descriptions()
        for name in ("tight_span.tension", "slack_span.tension", "input_shaft.torque"):
            d[name] = QUASI_STATIC + d[name] + " (rigid chain, inertia torques of the prescribed motion)"
        d["tight_span.midspan_deflection"] = (QUASI_STATIC + "static sag of the tight span under "
                                              "gravity at its tension")
        d["chain.max_link_tension"] = QUASI_STATIC + "the larger span tension"
        d["chain.min_link_tension"] = QUASI_STATIC + "the smaller span tension"
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
            t_up, t_low = split_tensions(self._raw_sum, g.upper.arm_start,
                                         g.lower.arm_end, load, self._floor, *self._sag_ks,
                                         self._hang)
            tau_in = (p["driver.inertia"] * acceleration[sel] + t_up * g.upper.arm_end
                      - t_low * g.lower.arm_start)
            # span roles by power flow, from the inputs (chainmodel.kernels.span_roles)
            upper = ~lower_tight_many(torque[sel], p["driven.damping"], p["driven.inertia"],
                                      drive.tooth_ratio, speed[sel], acceleration[sel])
            out["driver.angle"][sel] = angle[sel]
            out["driver.speed"][sel] = speed[sel]
            out["driven.angle"][sel] = rot.driven_angle
            out["driven.speed"][sel] = rot.driven_speed
            out["driven.acceleration"][sel] = rot.driven_acceleration
            out["input_shaft.torque"][sel] = tau_in
            out["tight_span.tension"][sel] = np.where(upper, t_up, t_low)
            out["slack_span.tension"][sel] = np.where(upper, t_low, t_up)
            out["tight_span.length"][sel] = np.where(upper, g.upper.length, g.lower.length)
            out["velocity_ratio"][sel] = rot.velocity_ratio
            out["transmission_error"][sel] = rot.driven_angle - drive.tooth_ratio * angle[sel]
        centrifugal = centrifugal_tension(drive, p, speed)
        out.update(quasi_static_extras(drive, p, out["tight_span.tension"],
                                       out["slack_span.tension"], out["tight_span.length"],
                                       centrifugal))
        out["tight_span.tension"] += centrifugal
        out["slack_span.tension"] += centrifugal
        return out

    @cached_property
    def _kernel_constants(self):
        """(K, G, C) of the scalar compiled evaluation (:mod:`chainmodel.kernels.kinematic`)."""
        from ..kernels import kinematic as KK
        from ..kernels.spans import geometry_constants
        p, d = self.params, self.drive
        C = np.empty(KK.C_SIZE)
        C[KK.C_I1], C[KK.C_I2], C[KK.C_D2] = (p["driver.inertia"], p["driven.inertia"],
                                              p["driven.damping"])
        C[KK.C_SUM], C[KK.C_FLOOR] = self._raw_sum, self._floor
        C[KK.C_KS_UP], C[KK.C_KS_LOW] = self._sag_ks
        C[KK.C_ROLE] = 0.0         # span roles from the inputs (hold_role)
        C[KK.C_HANG] = self._hang
        C[KK.C_RHO_G] = p["chain.link_mass"] / d.pitch * (p["gravity"]
                                                          * math.cos(p["drive.inclination"]))
        C[KK.C_RATIO] = d.tooth_ratio
        C[KK.C_CENTRIFUGAL] = float(centrifugal_tension(d, p, 1.0))   # times speed^2
        return KK.fourbar_constants(d), geometry_constants(d), C

    def hold_role(self, hold: float) -> None:
        from ..kernels import kinematic as KK
        self._kernel_constants[2][KK.C_ROLE] = float(hold)

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out) -> None:
        """Every output (ALL_OUTPUTS order) into ``out``: the scalar compiled twin of
        :meth:`evaluate` (:func:`chainmodel.kernels.kinematic.level0_outputs`), one call; True when all
        are finite."""
        K, G, C = self._kernel_constants
        return level0_outputs(float(angle), float(speed), float(acceleration), float(torque), K, G, C,
                       out)

    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        out = np.empty(len(ALL_OUTPUTS))
        self.outputs_into(t, x, u.angle, u.speed, u.acceleration, u.torque, out)
        return {o.name: float(v) for o, v in zip(ALL_OUTPUTS, out)}

