"""Level 1: the torsional model. Driver and driven sprocket rotations and speeds are the states;
both spans are massless, straight and elastic (seed 004 sections 5.1-5.5 without span modes; the
input shaft of seed 003).

Equations (derivation and the reduction to seed 004 eq 56 in docs/reduced_models.md)::

    driven:  J22 phi2'' + J12 phi1'' = T_u a_uO - T_l a_lO - d2 phi2' - M_load      (eq 50)
    driver:  J11 phi1'' + J12 phi2'' = k_s (theta_in - phi1) + c_s (w_in - phi1')
                                       - T_u a_uC + T_l a_lC                      (seed 003 eq 14)

with the rigid-shaft option phi1 = theta_in (the driver follows the input exactly). Each span's
length l, moment arms a and link count n come from the exact polygon geometry for the *current*
pair of rotations (:func:`chainmodel.kinematics.wrapping.chain_geometry`, here through its scalar
twin in :mod:`.spans`): the endpoint rollers and the links in each span follow seating and
release. Its tension comes from its stretch::

    T = k_eff (l - n p_free) + (c_link / n) dl/dt   if that and the stretch are positive, else 0

with p_free = p - pretension / k_link the free link length and k_eff = k_link / n (links in
series; with ``torsional.seat_compliance`` the seats' ladder compliance is added in series).
With ``torsional.mean_link_compliance`` (the default) k_eff takes the tooth-period-mean count
n_bar and the free length is n p - n_bar (p - p_free), so the stretch is continuous through the
seating and release events (:func:`chainmodel.kernels.spans.free_length`). A span
cannot push: at zero stretch or zero tension it goes slack (the outputs add the centrifugal
tension rho A v^2 on top, docs/stability.md), and that switch is an event of the
steppers (:meth:`TorsionalModel.switching_functions`), as are the seating and release events at
all four span ends. Under gravity each straight span also hangs in its quasi-static sag, whose
arc S / T^2 (S = w_n^2 L^3 / 24, the elastic catenary of :mod:`.span_sag`) the chain in it must
cover: T^3 - T_raw T^2 - S k_eff = 0 with T_raw the law above, so a span whose stretch runs out
keeps its sag tension instead of going slack (level 2's string modes hold their sag
themselves; docs/reduced_models.md, "One static tension, gravity included"). At zero stretch
the spans lie exactly where level 0 puts them, so polygonal action and the varying wrapping
length excite the drive by themselves.

J11, J12, J22: the sprocket inertias plus, with ``torsional.chain_inertia`` (default), the chain's
mass: rollers on a sprocket at its pitch radius and each span's rollers moving with their
endpoints (docs/reduced_models.md, "chain inertia"). Without it this is seed 004 eq 50 exactly.

The pretension split of seed 004 eqs 15-17 is what the static solution of these equations gives:
a driven sprocket turned by dphi2 stretches one span by R dphi2 and relaxes the other as much,
so with equal span stiffness T_u + T_l stays 2 T0 = P_tot while T_u - T_l = M_1 / R_1.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from ..geometry import Drive
from ..kernels import rk4_loop as L
from ..kernels import spans as S
from . import limits
from .chain_inertia import reference_geometry, sprocket_mass_matrix, two_inertia_stiffness
from .base import (ALL_OUTPUTS, QUASI_STATIC, Inputs, Model, SimulationDiverged,
                   centrifugal_tension)
from .span_sag import hanging_tension
from .static_tension import seat_series_compliance, seat_stiffness
from .wrap_statics import (held_span_tension, honoured, span_ends, span_sag_terms,
                           straight_span_sags,
                           static_span_tension)

__all__ = ["TorsionalModel", "seat_stiffness"]

OUTPUT_NAMES = tuple(o.name for o in ALL_OUTPUTS)

#: names of the switching functions, in order
SWITCH_NAMES = ("upper span slack", "lower span slack", "release from driven (upper span)",
                "seating on driver (upper span)", "release from driver (lower span)",
                "seating on driven (lower span)")


class TorsionalModel(Model):
    """Level 1 (see module docstring)."""

    level: ClassVar[int] = 1
    name: ClassVar[str] = "torsional"
    preferred_method: ClassVar[str] = "rk4"
    second_order: ClassVar[bool] = True
    n_modes: int = 0
    #: names of switching_functions' entries (for messages)
    switching_names: ClassVar[tuple[str, ...]] = SWITCH_NAMES

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        super().__init__(drive, params)
        p = self.params
        from ..parameters import BY_NAME
        for name in ("chain.link_stiffness", "chain.link_damping", "chain.pretension",
                     "chain.link_mass", "driver.inertia", "driven.inertia", "driven.damping",
                     "input_shaft.stiffness", "input_shaft.damping", "input_shaft.rigid",
                     "contact.stiffness", "torsional.chain_inertia", "torsional.seat_compliance",
                     "torsional.mean_link_compliance", "torsional.sag_lag",
                     "gravity"):
            p[name] = BY_NAME[name].check(p[name])
        self.rigid = bool(p["input_shaft.rigid"])
        # level 1's lagged sag: a state per span (not with string modes, which sag themselves)
        self.lag = (self.n_modes == 0 and bool(p["torsional.sag_lag"])
                    and max(self._sag_terms) > 0.0)
        if self.lag:
            self.second_order = False     # [angles, speeds, T_q,up, T_q,low]: not [q, v]
            self.first_order_states = (" (level 1's lagged sag adds a first-order state per "
                                       "span; torsional.sag_lag = false leaves it [q, v])")
        self.G = S.geometry_constants(drive)
        self.P = self._parameter_vector()
        self._dx = None
        self._cache_key = None
        self._cache = None
        self._out_row = np.empty(len(OUTPUT_NAMES))
        self._dx_row = np.empty(self.n_states)
        self._aux_row = np.empty(S.A_SIZE)
        self._complete_parameters()
        self._fit_wrap_to_own_mode()

    # --- construction ----------------------------------------------------------------------
    @cached_property
    def reference(self) -> dict[str, float]:
        """Tooth-period means of the level-0 configuration (chain_inertia.reference_geometry)."""
        return reference_geometry(self.drive)

    def mass_matrix(self) -> np.ndarray:
        """[[J11, J12], [J12, J22]] of the sprocket rotations [kg m^2], the chain's inertia
        included (:func:`~chainmodel.models.chain_inertia.sprocket_mass_matrix`)."""
        return sprocket_mass_matrix(self.drive, self.params, self.reference)

    def series_compliance(self) -> tuple[float, float]:
        """(extra compliance per span [m/N], extra free length per span [m]) from the seats
        (option ``torsional.seat_compliance``; :func:`~chainmodel.models.kinematic.
        seat_series_compliance`), or with ``torsional.wrap_statics`` from level 3's statics
        (:func:`~chainmodel.models.wrap_statics.span_ends`)."""
        return self._span_ends[:2]

    @cached_property
    def _span_ends(self) -> tuple[float, float, float]:
        """(compliance, free length, slack-span floor) of the span law, once per model."""
        return span_ends(self.drive, self.params, stretch=sum(self._sag_terms))

    def _complete_parameters(self) -> None:
        """What a level adds to the parameter vector before the wrap is fitted (level 2: its
        string modes)."""

    def _fit_wrap_to_own_mode(self) -> None:
        """With ``torsional.wrap_statics``: refit the span ends so that this level's own
        driven-sprocket mode at rest is level 3's (:mod:`.torsional_mode`)."""
        if not honoured(self.drive, self.params):
            return
        from .torsional_mode import fitted_ends
        ends = fitted_ends(self)
        if ends is None:
            ends = self._span_ends
        self.__dict__["_span_ends"] = ends
        self._write_span_ends(self.P, ends)

    @cached_property
    def _sag_terms(self) -> tuple[float, float]:
        """(S_upper, S_lower) [N^2 m] the span law holds itself: each straight span's sag
        (level 2's string modes hold theirs, :class:`~chainmodel.models.modal.ModalModel`).
        With ``torsional.sag_lag`` (the default) through the lagged sag of
        :func:`chainmodel.kernels.spans._lagged`, the terms of
        :func:`~chainmodel.models.wrap_statics.straight_span_sags` (on level 3's wrap the
        parabola's, over which the wrap's ends and floor are fitted). Without it: none on the
        wrap, the quasi-static sag on the seat ladder (before the twentieth session of issue
        21)."""
        p = self.params
        if p["torsional.wrap_statics"] or p["torsional.sag_lag"]:
            return straight_span_sags(self.drive, p)
        return span_sag_terms(self.drive, p)      # the quasi-static sag on the ladder

    def _parameter_vector(self) -> np.ndarray:
        p, d = self.params, self.drive
        P = np.zeros(S.P_SIZE)
        P[S.P_K_LINK] = p["chain.link_stiffness"]
        P[S.P_C_LINK] = p["chain.link_damping"]
        P[S.P_P_FREE] = d.pitch - p["chain.pretension"] / p["chain.link_stiffness"]
        P[S.P_RIGID] = 1.0 if self.rigid else 0.0
        P[S.P_K_SHAFT] = p["input_shaft.stiffness"]
        P[S.P_C_SHAFT] = p["input_shaft.damping"]
        P[S.P_D2] = p["driven.damping"]
        mm = self.mass_matrix()
        P[S.P_J11], P[S.P_J12], P[S.P_J22] = mm[0, 0], mm[0, 1], mm[1, 1]
        # divisions the kernel would repeat at every evaluation (the matrix is constant)
        P[S.P_INV_J22] = 1.0 / mm[1, 1]
        P[S.P_INV_DET] = 1.0 / (mm[0, 0] * mm[1, 1] - mm[0, 1] * mm[0, 1])
        P[S.P_RHOA] = p["chain.link_mass"] / d.pitch
        P[S.P_MODES] = self.n_modes
        P[S.P_PITCH] = d.pitch
        if p["torsional.mean_link_compliance"]:
            P[S.P_NBAR_U], P[S.P_NBAR_L] = self.reference["n_up"], self.reference["n_low"]
        if self.n_modes == 0:
            P[S.P_SAG_U], P[S.P_SAG_L] = self._sag_terms
        if self.lag:
            P[S.P_LAG] = 1.0
            P[S.P_LAG_RATE] = S.LAG_RATE
            P[S.P_LBAR_U], P[S.P_LBAR_L] = self.reference["l_up"], self.reference["l_low"]
        P[S.P_HANG] = hanging_tension(d, p)
        self._write_span_ends(P, self._span_ends)
        return P

    def _write_span_ends(self, P: np.ndarray, ends: tuple[float, float, float]) -> None:
        """Put the span law's ends (compliance, free length, floor) into ``P``, with what the
        kernel takes from them: the constant span stiffness and damping of the mean link counts
        and the sag law's root."""
        P[S.P_SEAT_C], P[S.P_SEAT_SLACK], P[S.P_SOFT] = ends
        if self.params["torsional.mean_link_compliance"]:
            # constant span stiffness and damping, computed once instead of per evaluation
            for nbar, keff, cn in ((S.P_NBAR_U, S.P_KEFF_U, S.P_CN_U),
                                   (S.P_NBAR_L, S.P_KEFF_L, S.P_CN_L)):
                P[keff], P[cn] = S.span_stiffness(P[nbar], P[S.P_K_LINK], P[S.P_C_LINK],
                                                  P[S.P_SEAT_C])
        for sag, keff, root in ((S.P_SAG_U, S.P_KEFF_U, S.P_SAGC_U),
                                (S.P_SAG_L, S.P_KEFF_L, S.P_SAGC_L)):
            if P[sag] > 0.0 and P[keff] > 0.0:
                P[root] = (P[sag] * P[keff]) ** (1.0 / 3.0)

    # --- state -----------------------------------------------------------------------------
    @property
    def n_sprocket_states(self) -> int:
        return 2 if self.rigid else 4

    @property
    def state_names(self) -> tuple[str, ...]:
        lag = ("upper_span.sag_tension", "lower_span.sag_tension") if self.lag else ()
        if self.rigid:
            return ("driven.angle", "driven.speed") + lag
        return ("driver.angle", "driven.angle", "driver.speed", "driven.speed") + lag

    def _kernel(self, x, th_in, w_in, a_in, load):
        dx = np.empty(self.n_states)
        aux = np.empty(S.A_SIZE)
        S.evaluate(np.asarray(x, float), float(th_in), float(w_in), float(a_in), float(load),
                   self.G, self.P, dx, aux)
        return dx, aux

    def _eval(self, t, x, u: Inputs):
        key = (t, u.angle, u.speed, u.acceleration, u.torque, x.tobytes())
        if key != self._cache_key:
            self._cache = self._kernel(x, u.angle, u.speed, u.acceleration, u.torque)
            self._cache_key = key
        return self._cache

    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        dx = np.empty(self.n_states)
        aux = np.empty(S.A_SIZE)
        S.evaluate(x, float(u.angle), float(u.speed), float(u.acceleration), float(u.torque),
                   self.G, self.P, dx, aux)
        return dx

    def switching_functions(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        """Six functions (SWITCH_NAMES): each span's min(k delta, T_raw) (slack when it turns
        negative) and sin(pi u) of the four span ends' seat coordinates u, whose integer crossings
        are the release and seating events (a continuous function, so each event is a sign
        change rather than a jump)."""
        aux = self._eval(t, np.asarray(x, float), u)[1]
        return aux[S.A_G_UP:S.A_EV_LE + 1].copy()

    def _modal_initial(self, u: Inputs) -> np.ndarray:
        return np.empty(0)

    def _static_P(self) -> np.ndarray:
        """A copy of the parameter vector with the lagged sag quasi-static (spans.P_LAG_QS):
        the law the equilibrium holds, each span's lagged tension its elastic one (a copy per
        call: the wrap fit rewrites the span ends in P as it goes)."""
        P = self.P.copy()
        P[S.P_LAG_QS] = 1.0
        return P

    def initial_state(self, u: Inputs) -> np.ndarray:
        """Rest, in static equilibrium under the load torque ``u.torque`` with the input shaft
        held at ``u.angle``: the driven (and, with a flexible shaft, the driver) rotation that
        balances the span tensions, found by bracketing from the level-0 configuration
        (:func:`chainmodel.kernels.equilibrium.static_state`, one compiled call)."""
        from ..kernels import equilibrium as E
        from ..kernels.kinematic import driven_rotation as scalar_rotation
        from ..kernels.kinematic import fourbar_constants
        d = self.drive
        modal = self._modal_initial(u)
        x = np.concatenate([np.zeros(self.n_sprocket_states), modal,
                            np.zeros(2 if self.lag else 0)])
        K = self.__dict__.get("_fourbar_constants")
        if K is None:
            K = self.__dict__["_fourbar_constants"] = fourbar_constants(d)
        phi2_kin = scalar_rotation(float(u.angle), 0.0, 0.0, False, K)[0]
        P = self._static_P() if self.lag else self.P
        status = E.static_state(float(u.angle), float(u.torque), phi2_kin, d.tooth_ratio,
                                math.pi / d.n_driven, math.pi / d.n_driver, x, self.G, P)
        if status == E.STATUS_NO_DRIVEN:
            p = self.params
            raise ValueError(
                f"no static equilibrium of the driven sprocket within 20 teeth of the "
                f"kinematic position under load.torque = {u.torque:g} N.m: the spans "
                f"(chain.link_stiffness = {p['chain.link_stiffness']:g} N/m per link, "
                f"static tension {self.static_tension():.4g} N) cannot carry "
                f"{abs(u.torque) / d.driven.pitch_radius:.4g} N of tension difference "
                "without stretching by more than that; use a stiffer chain or a smaller "
                "load")
        if status == E.STATUS_NO_DRIVER:  # pragma: no cover - the shaft spring always brackets
            raise ValueError("no static equilibrium of the driver on input_shaft.stiffness "
                             f"= {self.params['input_shaft.stiffness']:g} N.m/rad")
        if self.lag:
            # the sags at rest hang at the quasi-static law's tension (they have followed)
            dx, aux = np.empty(self.n_states), np.empty(S.A_SIZE)
            S.evaluate(x, float(u.angle), 0.0, 0.0, float(u.torque), self.G, P, dx, aux)
            x[-2], x[-1] = aux[S.A_LAG_UP], aux[S.A_LAG_LOW]
        return x

    def _driven_torque(self, x, u):
        """Net static torque on the driven sprocket (flexible shaft, driver held)."""
        dx, aux = self._kernel(x, u.angle, 0.0, 0.0, u.torque)
        mm = self.P
        # generalised force on the driven sprocket: J21 acc1 + J22 acc2
        return mm[S.P_J12] * aux[S.A_ACC1] + mm[S.P_J22] * aux[S.A_ACC2]

    # --- compiled stepping (chainmodel.kernels.rk4_loop) -------------------------------------
    #: fixed-step methods with a compiled loop (numba): advance_points / advance_held
    compiled_methods: ClassVar[tuple[str, ...]] = ("rk4",)

    @cached_property
    def loop_constants(self) -> np.ndarray:
        """The constant vector Q of the compiled loop and outputs (rk4_loop.Q_*)."""
        p, d = self.params, self.drive
        Q = np.empty(L.Q_SIZE)
        Q[L.Q_W_SPROCKET] = float(np.max(self.sprocket_frequencies()))
        Q[L.Q_RATIO] = d.tooth_ratio
        Q[L.Q_SAG] = (p["chain.link_mass"] / d.pitch) * p["gravity"] * math.cos(
            p["drive.inclination"]) / 8.0
        Q[L.Q_AMP_LIMIT] = self._amplitude_limit()
        Q[L.Q_EVENT_ANGLE] = 0.25 * 2.0 * math.pi / d.n_driver
        Q[L.Q_CENTRIFUGAL] = float(centrifugal_tension(d, p, 1.0))   # times w1^2
        return Q

    def _amplitude_limit(self) -> float:
        return math.inf

    def has_loop_kernel(self, method: str) -> bool:
        """rk4: rk4_loop's loop, compiled with numba and run as its plain Python source without
        (one source for the step rule, the event crossing and the outputs)."""
        return method in self.compiled_methods

    def advance_points(self, method, x_in, x_out, times, angle, speed, acceleration, torque, cfg,
                       out, states, log, log_cap):
        """The fixed-step loop of ``method`` through the communication points ``times`` in one
        compiled call (:func:`chainmodel.kernels.rk4_loop.advance_points`: step rule, guard,
        events, outputs into ``out`` rows 1.., states into ``states``; x_in untouched, the
        final state in x_out), or None when there is none (another method)."""
        if not self.has_loop_kernel(method):
            return None
        return L.advance_points(x_in, x_out, times, angle, speed, acceleration, torque, self.G,
                                self.P, self.loop_constants, cfg, out, states, log, log_cap)

    def advance_held(self, method, x_in, x_out, t0, t1, angle, speed, acceleration, torque, cfg,
                     out, log):
        """:meth:`advance_points` over one communication step with the inputs held first-order
        (the FMU's hold), outputs at t1 in out[1]; None when there is no compiled path."""
        if not self.has_loop_kernel(method):
            return None
        return L.advance_held(x_in, x_out, t0, t1, angle, speed, acceleration, torque, self.G,
                              self.P, self.loop_constants, cfg, out, log)

    def omega_at(self, t: float, x: np.ndarray, u: Inputs) -> float:
        """Highest natural frequency of the state x [rad/s] (:func:`~chainmodel.kernels.rk4_loop.
        omega_estimate`: the sprockets' bound; at level 2 also the span modes at their current
        tension): the stable-step guard's estimate."""
        aux = self._eval(t, np.asarray(x, float), u)[1]
        return float(L.omega_estimate(aux, self.G, self.P, self.loop_constants))

    def step_kept(self, x: np.ndarray, x_next: np.ndarray) -> bool:
        """False when a step moved level 1's lagged sag by more than a factor of two
        (:func:`~chainmodel.kernels.spans.lag_step_kept`)."""
        return bool(S.lag_step_kept(np.asarray(x, float), np.asarray(x_next, float), self.P))

    # --- span roles ------------------------------------------------------------------------
    def role_constants(self) -> tuple[float, float, float]:
        """Model.role_constants with this level's J_2 (the wrapped chain's share in it, as
        the kernel's role takes it)."""
        return float(self.P[S.P_D2]), float(self.P[S.P_J22]), float(self.drive.tooth_ratio)

    def hold_role(self, hold: float) -> None:
        self.P[S.P_ROLE] = float(hold)

    # --- capabilities ----------------------------------------------------------------------
    def static_tension(self) -> float:
        """Static span tension at rest with no load [N], the drive's (driver at angle 0; with
        ``torsional.wrap_statics`` level 3's there), shared with level 0
        (:func:`~chainmodel.models.wrap_statics.static_span_tension`). What the spans carry
        at rest is :meth:`held_tension`. Computed once per model (its parameters are fixed)."""
        cached = self.__dict__.get("_static_tension_value")
        if cached is None:
            cached = self.__dict__["_static_tension_value"] = static_span_tension(
                self.drive, self.params)
        return cached

    def held_tension(self) -> float:
        """The tension the spans carry at rest, no load [N] (over a tooth period the polygon
        moves them about it): with ``torsional.wrap_statics`` level 3's tooth-period mean
        (:func:`~chainmodel.models.wrap_statics.held_span_tension`), which differs from
        :meth:`static_tension` (level 3's at driver angle 0) by level 3's own polygonal
        variation; else the static tension."""
        cached = self.__dict__.get("_held_tension_value")
        if cached is None:
            cached = self.__dict__["_held_tension_value"] = held_span_tension(
                self.drive, self.params)
        return cached

    def axial_frequency(self) -> float:
        """Lowest axial natural frequency [Hz] of the longer span (its largest link count over a
        tooth period; the seats' elastic series compliance at its ends): the mode levels 1-2
        treat as quasi-static (:func:`~chainmodel.models.limits.span_axial_frequency`).

        The ends are the loaded seats' (:func:`~chainmodel.models.static_tension.
        seat_series_compliance`) also with ``torsional.wrap_statics``: the wrap fit's softer
        ends at rest are mostly clearance taken up and sag, which the running load takes out of
        the tight span (docs/stability.md, "Speed limits")."""
        r = self.reference
        n = math.ceil(max(r["n_up"], r["n_low"]) - 1e-9)
        return limits.span_axial_frequency(n, self.params, self.loaded_seat_compliance())

    def loaded_seat_compliance(self) -> float:
        """Compliance [m/N] per span of its loaded seats (the seat ladder, clearance taken up;
        0 with ``torsional.seat_compliance`` off): what the speed limits read."""
        return seat_series_compliance(self.params, self.drive)[0]

    def speed_limit(self) -> tuple[float, str]:
        """Levels 1-2 take the spans' axial motion as quasi-static (seed 004 section 5.3,
        N_,x = 0; the span mass lumped on the sprockets): valid while the meshing frequency is
        below limits.QUASI_STATIC_RATIO of the spans' first axial frequency (and below the
        centrifugal strain bound of every level)."""
        w_c, why_c = super().speed_limit()
        f_ax = self.axial_frequency()
        w = limits.speed_for_meshing(self.drive, limits.QUASI_STATIC_RATIO * f_ax)
        if w_c < w:
            return w_c, why_c
        return w, (f"the meshing frequency would exceed {limits.QUASI_STATIC_RATIO:g} x the "
                   f"spans' first axial natural frequency ({f_ax:.4g} Hz), which this level "
                   "treats as quasi-static; use fidelity 3 (multibody) or a lower speed")

    def stiffness_bound(self) -> np.ndarray:
        """Linear stiffness matrix of the sprocket rotations with both spans taut, their
        shortest link counts and arms equal to the pitch radii (an upper bound for stable_step)."""
        p, r = self.params, self.reference
        c, _ = self.series_compliance()
        return self.two_inertia_stiffness(sum(1.0 / (max(n, 1.0) / p["chain.link_stiffness"] + c)
                                              for n in (r["n_up_min"], r["n_low_min"])))

    def two_inertia_stiffness(self, k: float) -> np.ndarray:
        """Stiffness matrix [N m/rad] of the sprocket rotations on spans of total stiffness
        ``k`` [N/m] (:func:`~chainmodel.models.chain_inertia.two_inertia_stiffness`)."""
        return two_inertia_stiffness(self.drive, self.params, k)

    def sprocket_frequencies(self) -> np.ndarray:
        """Undamped natural frequencies of the linearised sprocket equations [rad/s] with the
        bound stiffness (ascending); rigid shaft: the driven sprocket alone."""
        K, M = self.stiffness_bound(), self.mass_matrix()
        if self.rigid:
            return np.array([math.sqrt(K[1, 1] / M[1, 1])])
        ev = np.linalg.eigvals(np.linalg.solve(M, K)).real
        return np.sqrt(np.sort(np.abs(ev)))

    def omega_max(self, x=None) -> float:
        return float(np.max(self.sprocket_frequencies()))

    def stable_step(self, x: np.ndarray) -> float:
        return 1.0 / self.omega_max(x)

    def event_step(self, speed: float) -> float:
        """A quarter of the driver's tooth period 2 pi / (n_driver |speed|): each tooth period
        has four seating and release events (two per span), and a fixed step crosses only the
        first event inside it."""
        speed = abs(float(speed))
        if speed == 0.0 or not math.isfinite(speed):
            return math.inf
        return 0.25 * 2.0 * math.pi / (self.drive.n_driver * speed)

    def state_scale(self) -> np.ndarray:
        """Typical magnitudes of the states (absolute tolerances of adaptive steppers are
        rtol times these): 1e-3 rad and 1 rad/s for the sprockets."""
        scale = [1e-3] * (self.n_sprocket_states // 2) + [1.0] * (self.n_sprocket_states // 2)
        if self.lag:     # the tensions the spans' sags hang at [N]
            scale += [max(self.held_tension(), 1.0)] * 2
        return np.array(scale)

    # --- outputs ---------------------------------------------------------------------------
    def output_descriptions(self) -> dict[str, str]:
        d = super().output_descriptions()
        d["tight_span.midspan_deflection"] = (QUASI_STATIC + "static sag of the tight span under "
                                              "gravity at its tension (level 1 spans are straight)")
        d["chain.max_link_tension"] = QUASI_STATIC + "the larger span tension"
        d["contact.max_force"] = QUASI_STATIC + "the tight-span tension (the seats are not modelled)"
        d["chain.min_link_tension"] = QUASI_STATIC + "the smaller span tension"
        return d

    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        out = self._out_row
        L.outputs_into(np.asarray(x, float), float(u.angle), float(u.speed),
                       float(u.acceleration), float(u.torque), self.G, self.P,
                       self.loop_constants, self._dx_row, self._aux_row, out)
        return dict(zip(OUTPUT_NAMES, out.tolist()))

    def outputs_into(self, t, x, angle, speed, acceleration, torque, out) -> None:
        """Every output (ALL_OUTPUTS order) into ``out``, one compiled call; True when all are
        finite."""
        return L.outputs_into(x, float(angle), float(speed), float(acceleration), float(torque), self.G,
                       self.P, self.loop_constants, self._dx_row, self._aux_row, out)

    def outputs_many(self, times, states, angle, speed, acceleration, torque
                     ) -> dict[str, np.ndarray]:
        """:meth:`outputs` at many samples at once: ``states[i]`` at ``times[i]`` with the inputs
        (angle, speed, acceleration, torque)[i]; the same compiled function per sample."""
        states = np.ascontiguousarray(states, float).reshape(len(times), self.n_states)
        OUT = np.empty((states.shape[0], len(OUTPUT_NAMES)))
        L.outputs_many(states, *(np.ascontiguousarray(a, float) for a in
                                 (angle, speed, acceleration, torque)),
                       self.G, self.P, self.loop_constants, OUT)
        return {name: OUT[:, k].copy() for k, name in enumerate(OUTPUT_NAMES)}

    def evaluate_states(self, times, states, inputs) -> dict[str, np.ndarray]:
        """Outputs for a sequence of (t, x, u) (convenience for post-processing); ``inputs`` a
        sequence of :class:`Inputs` or a tuple of arrays (angle, speed, acceleration, torque)."""
        if len(inputs) == 4 and not isinstance(inputs[0], Inputs):
            arrays = inputs
        else:
            arrays = [np.array([getattr(u, k) for u in inputs], float)
                      for k in ("angle", "speed", "acceleration", "torque")]
        out = self.outputs_many(np.asarray(times, float), states, *arrays)
        return {o.name: out[o.name] for o in ALL_OUTPUTS}

    def check(self, t: float, x: np.ndarray) -> None:
        """The finite check, and level 1's lagged sag tensions positive: a step that took one
        through zero (faster than the step rule's rate) has no meaning."""
        super().check(t, x)
        if self.lag:
            k = S.lag_index(self.P)
            for name, value in zip(("upper", "lower"), x[k:k + 2]):
                if not value > 0.0:
                    raise SimulationDiverged(
                        f"{self.name} model diverged at t = {t:.6g} s: the {name} span's sag "
                        f"tension (torsional.sag_lag's state) fell to {value:.3g} N, a step "
                        "faster than its rate; try a smaller solver.tolerance or solver.step, "
                        "or torsional.sag_lag = false")

    def check_states(self, times, states) -> None:
        """:meth:`check` for many states (vectorised): raises for the first that fails."""
        bad = ~np.all(np.isfinite(states), axis=1)
        if self.lag:
            k = S.lag_index(self.P)
            bad |= ~np.all(states[:, k:k + 2] > 0.0, axis=1)
        if bad.any():
            i = int(np.argmax(bad))
            self.check(float(times[i]), states[i])
