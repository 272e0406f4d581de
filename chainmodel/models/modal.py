"""Level 2: the modal model. Level 1 plus transverse Galerkin modes of both spans (seed 004
sections 5.2-5.8, eqs 57-65), in dimensional form.

Each span is an axially moving string of mass per length rho A = m_link / p moving at the chain
speed S = n_c p w1 / 2 pi, between endpoints whose transverse motion Y1, Y2 comes from the chain
geometry as the sprockets turn (the y1, y2 of eq 38). Its transverse deflection from the chord
between the endpoints is w(x, t) = sum_m q_m(t) sin(m pi x / lbar) (eq 57), lbar the span's mean
length, and the Galerkin equations (eq 58 in dimensional form) are::

    q_m'' + (2 S / lbar) sum_n C_mn q_n' + ((T - rho A S^2) / rho A) (m pi / lbar)^2 q_m
        + 2 zeta m omega_1 q_m' = -(G_m - E_m) Y1'' - E_m Y2'' - (2 S / lbar)(Y2' - Y1') G_m
                                  + g_n G_m

with T the span's material tension: the elastic tension including the modal stretching sum
(m pi)^2 q_m^2 / (4 lbar), plus the centrifugal tension rho A S^2, so that T - rho A S^2 is the
elastic tension (docs/stability.md, "Centrifugal tension"; eq 46:
the parametric coupling through the sprocket rotations, the wrapping-length variation p_o* and
the cubic stiffening kappa_m all come from this one tension), and that same tension acts on the
sprockets (eq 56's integral term). g_n: gravity across the span (0 in seed 004). The endpoint
velocities jump at every seating and release (eq 63); the state carries the projection of the
material transverse velocity, v_m = q_m' + (G_m - E_m) Y1' + E_m Y2', which does not jump, so the
impulses need no state resets (docs/reduced_models.md, "endpoint motion").

Option ``modal.impulse_forcing``: replace the kinematic endpoint motion by the impulse-train
idealisation of eqs 63-65 (pulses Q = S p / R at each release from the driven sprocket and each
seating on the driver, the s-terms dropped, the trains' mean kept as the paper's k_0 term).

Departures from the printed equations (docs/reduced_models.md): C_mn has k^2 - j^2 in its
denominator (skew-symmetric; eq 59 prints a +), and the 2 s (y2' - y1') term enters eq 58 with the
sign of eq 47.
"""

from __future__ import annotations

import math
from functools import cached_property
from typing import Any, ClassVar, Mapping

import numpy as np

from ..geometry import Drive
from ..kernels import spans as S
from .base import Inputs, SimulationDiverged
from .limits import span_string_frequency
from .span_sag import span_terms
from .torsional import TorsionalModel
from .wrap_statics import honoured, unavailable

__all__ = ["ModalModel", "galerkin_coefficients"]

#: Newton steps of :meth:`ModalModel._rest` to the strings' own sag, the step [in state
#: scales] at which they stop, the largest move of a string coordinate (and of a pitch circle)
#: per step [in amplitude limits, ModalModel._amplitude_limit], the halvings of a step that does
#: not lower the accelerations, and the regularisation of a singular Jacobian
REST_ITERATIONS, REST_TOLERANCE, REST_STEP = 100, 1e-9, 0.1
REST_HALVINGS, REST_DAMPING, REST_LOAD_STEPS = 30, 1e-8, 8


def galerkin_coefficients(modes: int) -> dict[str, np.ndarray]:
    """G_m, E_m (seed 004 eq 59) and the skew-symmetric C_mn for m, n = 1..modes."""
    m = np.arange(1, modes + 1, dtype=float)
    g = 2 * (1 - (-1.0) ** m) / (m * np.pi)
    e = -2 * (-1.0) ** m / (m * np.pi)
    k, j = np.meshgrid(m, m, indexing="ij")
    with np.errstate(divide="ignore", invalid="ignore"):
        c = np.where(k == j, 0.0, 2 * k * j * (1 - (-1.0) ** (k + j)) / (k * k - j * j))
    return {"G": g, "E": e, "C": c}


class ModalModel(TorsionalModel):
    """Level 2 (see module docstring)."""

    level: ClassVar[int] = 2
    name: ClassVar[str] = "modal"
    preferred_method: ClassVar[str] = "rk4"
    second_order: ClassVar[bool] = False

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        from ..parameters import BY_NAME
        params = dict(params)
        for name in ("modal.modes", "modal.damping_ratio", "modal.impulse_forcing"):
            params[name] = BY_NAME[name].check(params[name])
        self.n_modes = int(params["modal.modes"])
        super().__init__(drive, params)

    def _complete_parameters(self) -> None:
        """Refuse a chain without tension at rest, then fill the string modes' parameters."""
        drive = self.drive
        t0 = self.held_tension()
        from .kinematic import loose_chain_error
        loose = loose_chain_error(drive, self.params)
        # a chain longer than its wrap: refused unless level 3's statics hold its ends (its
        # slack span hangs in a sag that turns deep under load, past the strings' validity);
        # where the wrap fit refused the drive, the seat ladder holds them and cannot
        if not t0 > 0.0 or (loose is not None and not honoured(drive, self.params)):
            if loose is not None:
                why = ("torsional.wrap_statics = true holds one on level 3's statics"
                       if not self.params["torsional.wrap_statics"] else
                       "torsional.wrap_statics could not hold it on level 3's statics: "
                       + unavailable(drive, self.params).rstrip("."))
                raise ValueError(f"the modal model (level 2) needs both spans in tension at rest "
                                 f"(its spans are taut strings, not a chain hanging in a sag; "
                                 f"{why}), but {loose}")
            raise ValueError(
                f"the modal model (level 2) needs both spans in tension at rest, but the static "
                f"span tension is {t0:g} N (a string without tension has no transverse "
                f"stiffness): raise chain.pretension (now {self.params['chain.pretension']:g} N) "
                f"or shorten drive.centre_distance")
        self._fill_modal_parameters(t0)

    @cached_property
    def _sag_terms(self) -> tuple[float, float]:
        """The string modes' sag under gravity stretches each span by S_N / T^2 (S_N the modal
        sum of the elastic catenary's sag term, :func:`~chainmodel.models.span_sag.
        span_terms`): at rest the span law's ends give it away again, so the static tension is
        held once (wrap_statics.span_ends), and with torsional.wrap_statics the slack span's
        floor is fitted with it (the kernel's straight-span sag is level 1's: not written)."""
        return span_terms(self.drive, self.params, modes=self.n_modes)

    def _fill_modal_parameters(self, t0: float) -> None:
        p, d, r, P = self.params, self.drive, self.reference, self.P
        rho = p["chain.link_mass"] / d.pitch
        P[S.P_LBAR_U], P[S.P_LBAR_L] = r["l_up"], r["l_low"]
        P[S.P_ZETA] = p["modal.damping_ratio"]
        P[S.P_W1_U] = math.pi / r["l_up"] * math.sqrt(t0 / rho)
        P[S.P_W1_L] = math.pi / r["l_low"] * math.sqrt(t0 / rho)
        P[S.P_IMPULSE] = 1.0 if p["modal.impulse_forcing"] else 0.0
        P[S.P_REF_U], P[S.P_REF_L] = r["dir_up"], r["dir_low"]
        # gravity in the XY frame: the line of centres OC (angle theta1 in XY) is inclined by
        # drive.inclination above the horizontal, so "up" is i exp(i (theta1 - inclination))
        up = 1j * np.exp(1j * (d.centre_angle - p["drive.inclination"]))
        g_vec = -p["gravity"] * up
        for idx, ref in ((S.P_GN_U, r["dir_up"]), (S.P_GN_L, r["dir_low"])):
            normal = 1j * np.exp(1j * ref)          # positive away from the line of centres
            P[idx] = float((np.conj(normal) * g_vec).real)

    @property
    def state_names(self) -> tuple[str, ...]:
        n = self.n_modes
        names = list(super().state_names)
        k = len(names) // 2
        modal = ([f"tight_span.q{i}" for i in range(1, n + 1)]
                 + [f"slack_span.q{i}" for i in range(1, n + 1)]
                 + [f"tight_span.v{i}" for i in range(1, n + 1)]
                 + [f"slack_span.v{i}" for i in range(1, n + 1)])
        return tuple(names[:k] + names[k:] + modal)

    def modal_frequencies(self, tension: float, speed: float = 0.0, span: str = "upper") -> np.ndarray:
        """Linear frequencies of the span modes at a given tension and chain speed [rad/s]:
        omega_m = (m pi / lbar) sqrt((T - rho A S^2) / rho A) (seed 004 eq 61, dimensional)."""
        rho = self.params["chain.link_mass"] / self.drive.pitch
        lbar = self.reference["l_up" if span == "upper" else "l_low"]
        m = np.arange(1, self.n_modes + 1)
        return 2.0 * math.pi * m * span_string_frequency(lbar, tension, speed, rho)

    def initial_state(self, u: Inputs) -> np.ndarray:
        """Rest in static equilibrium (level 1's :meth:`TorsionalModel.initial_state`) with the
        strings hanging at the sag of their own tension there (:meth:`_rest`); ValueError
        where that sag lies beyond the string model's amplitude limit (the run would stop at
        its first step), and :attr:`start_fallback` set where the rest could not be found."""
        x = super().initial_state(u)
        self.start_fallback = None
        if self.params["gravity"] == 0.0 or not self.n_modes:
            return x             # no sag: the strings rest straight
        y = self._rest(x, u)
        if y is None and float(u.torque) != 0.0:
            y = self._rest_by_load(u)
        if y is None:
            self.start_fallback = (
                f"level 2 found no rest with its strings at their own sag (driver angle "
                f"{float(u.angle):.4g} rad, load.torque = {float(u.torque):g} N.m), so they "
                f"started at the sag of the held tension ({self.held_tension():.4g} N) and "
                f"ring from there: the first tenths of a second carry that ring, not the "
                f"inputs' (docs/reduced_models.md, \"Level 2\", Rest)")
            return x
        sag = self._amplitude(y)
        if sag > self._amplitude_limit():
            raise ValueError(
                f"level 2 at rest under load.torque = {float(u.torque):g} N.m: a span's string "
                f"hangs {1e3 * sag:.3g} mm, beyond {1e3 * self._amplitude_limit():.3g} mm (a "
                f"tenth of the shorter span) where the string model holds: the load leaves the "
                f"slack span on too little tension for level 2 (static tension "
                f"{self.held_tension():.4g} N); add pretension (chain.pretension), lower the "
                f"load, or run level 3 (or level 1, whose spans keep their sag quasi-statically)")
        return y

    def _rest(self, x: np.ndarray, u: Inputs) -> np.ndarray | None:
        """From the sprockets' equilibrium ``x`` (each string at the sag of the held tension,
        :meth:`_modal_initial`), Newton steps on every position (sprocket angles and string
        coordinates) to zero acceleration, the Jacobian from central differences of the
        right-hand side (:func:`~chainmodel.models.torsional_mode.linear_positions`); None where
        they do not settle. A string's sag takes up chain as 1 / T^2, so where the polygon
        shortens the path over a tooth a string held at the held tension's sag leaves the
        sprockets' equilibrium on almost no tension: a 12B 8/16 drive of 32 links without
        pretension rested at 0.16 N at two of four driver positions where level 3 rests at
        19-21 N and level 1 at 22 N (with it, level 2 at 22 N).

        Globalised, since a string near no tension is nearly free and a span near no tension
        soft on one side and stiff on the other (an audit's 08B 6/8 drive inclined 88 deg cycled
        between 0.34 N and 67 kN; equal-tooth drives without pretension under load start with
        a slack span at 1e-15 N and a singular Jacobian): each step is scaled so that no string
        coordinate moves by more than ``REST_STEP`` of the strings' amplitude limit and no
        sprocket's pitch circle by more than that length; the Jacobian is regularised by
        ``REST_DAMPING`` times its largest diagonal where it is singular; and a step is halved
        (up to ``REST_HALVINGS`` times) until the accelerations, each over the first
        Jacobian's diagonal (floored at 1e-9 of its largest), shrink."""
        from .torsional_mode import linear_positions, position_states
        pos_idx, acc = position_states(self)
        ns = self.n_sprocket_states
        scale = self.state_scale()[pos_idx]
        cap = REST_STEP * self._amplitude_limit()
        radii = [self.drive.driver.pitch_radius, self.drive.driven.pitch_radius]
        # each position's largest move in one step: the strings' cap as a length on the pitch
        # circles (the driven sprocket alone where the driver is held rigid)
        limit = np.array([cap / r for r in radii[-(ns // 2):]]
                         + [cap] * (len(pos_idx) - ns // 2))
        y = x.copy()
        _, a = linear_positions(self, y, u)
        diag = np.abs(np.diag(a))
        weight = 1.0 / np.maximum(diag, 1e-9 * max(float(np.max(diag)), 1e-300))

        def merit(z):
            r = self.rhs(0.0, z, u)[acc]
            return float(np.linalg.norm(r * weight)), r

        m0, r = merit(y)
        for _ in range(REST_ITERATIONS):
            try:
                dy = np.linalg.solve(a, r)
            except np.linalg.LinAlgError:      # a string with no tension: its row is zero
                dy = np.linalg.solve(a + REST_DAMPING * float(np.max(np.abs(np.diag(a))))
                                     * np.eye(len(r)), r)
            if not np.all(np.isfinite(dy)):
                return None
            dy *= min(1.0, float(np.min(limit / np.maximum(np.abs(dy), 1e-300))))
            if np.max(np.abs(dy) / scale) < REST_TOLERANCE:     # a full step within it: there
                y[pos_idx] += dy
                return y
            for _ in range(REST_HALVINGS + 1):
                z = y.copy()
                z[pos_idx] += dy
                m1, r1 = merit(z)
                if m1 < m0:                  # (False for nan)
                    break
                dy *= 0.5
            else:
                return None                  # no step along Newton's lowers the accelerations
            y, m0, r = z, m1, r1
            _, a = linear_positions(self, y, u)
        return None

    def _rest_by_load(self, u: Inputs) -> np.ndarray | None:
        """:meth:`_rest` under ``u.torque`` reached in ``REST_LOAD_STEPS`` equal steps of the
        load from the unloaded rest, each from the last (a 16B 8/8 drive without pretension
        under 80 N m starts its slack span at 1e-15 N, from where no step along Newton's
        direction lowers the accelerations; from the unloaded rest its string sags already)."""
        y = self._rest(super().initial_state(Inputs(u.angle, 0.0, 0.0)),
                       Inputs(u.angle, 0.0, 0.0))
        for k in range(1, REST_LOAD_STEPS + 1):
            if y is None:
                return None
            y = self._rest(y, Inputs(u.angle, 0.0, float(u.torque) * k / REST_LOAD_STEPS))
        return y

    def _modal_initial(self, u: Inputs) -> np.ndarray:
        """Static sag under gravity at the static tension (linear), zero velocities."""
        n, P = self.n_modes, self.P
        g = galerkin_coefficients(n)["G"]
        t0 = self.held_tension()
        q_u = P[S.P_GN_U] * g / self.modal_frequencies(t0, 0.0, "upper") ** 2
        q_l = P[S.P_GN_L] * g / self.modal_frequencies(t0, 0.0, "lower") ** 2
        return np.concatenate([q_u, q_l, np.zeros(2 * n)])

    def omega_max(self, x=None) -> float:
        # span modes at four times the static tension (the tight span carries the load too)
        w_modes = float(np.max(self.modal_frequencies(4.0 * self.held_tension(), 0.0, "upper")))
        w_modes = max(w_modes, float(np.max(self.modal_frequencies(4.0 * self.held_tension(),
                                                                     0.0, "lower"))))
        return max(super().omega_max(x), w_modes)

    def state_scale(self) -> np.ndarray:
        n = self.n_modes
        return np.concatenate([super().state_scale(), np.full(2 * n, 1e-4), np.full(2 * n, 1e-2)])

    def _amplitude_limit(self) -> float:
        """A tenth of the shorter span: beyond it the string model does not hold (check)."""
        return 0.1 * min(self.reference["l_up"], self.reference["l_low"])

    def _amplitude(self, x: np.ndarray) -> float:
        """The largest string coordinate |q_m| [m] of state ``x`` (0 without modes)."""
        base = self.n_sprocket_states
        q = np.abs(x[base:base + 2 * self.n_modes])
        return float(np.max(q)) if q.size else 0.0

    def check(self, t: float, x: np.ndarray) -> None:
        super().check(t, x)
        q = self._amplitude(x)
        if q > self._amplitude_limit():
            raise SimulationDiverged(
                f"modal model: a span's transverse amplitude reached {q:.3g} m at "
                f"t = {t:.6g} s, beyond a tenth of its length where the string model holds; "
                + self._divergence_cause(x))

    def _divergence_cause(self, x: np.ndarray) -> str:
        """The likeliest cause of a span amplitude beyond the string model, in words, from the
        state (with a rigid shaft the driver speed is not in it: then all candidates)."""
        d, r = self.drive, self.reference
        t0 = self.held_tension()
        f1 = float(np.min([self.modal_frequencies(t0, 0.0, s)[0] for s in ("upper", "lower")])
                   ) / (2 * math.pi)
        kick = max(R * (1 - math.cos(math.pi / n)) for R, n in
                   ((d.driver.pitch_radius, d.n_driver), (d.driven.pitch_radius, d.n_driven)))
        kick_ratio = kick / min(r["l_up"], r["l_low"])
        polygon = (f"the polygonal action: the span ends move across the span by up to "
                   f"{1e3 * kick:.3g} mm ({100 * kick_ratio:.2g} % of its length) at every "
                   "seating, more than a string of small slope takes at this speed (few teeth, "
                   "high speed: use fidelity 3)")
        parametric = (f"a parametric resonance of the span's first mode ({f1:.4g} Hz at the "
                      f"static tension) with the meshing frequency near twice it, without "
                      "enough damping (raise modal.damping_ratio)")
        slack = ("a span gone slack (its tension, less the centrifugal part, at zero: raise the "
                 "static tension or lower load.torque)")
        if self.rigid:
            return f"causes: {slack}; {parametric}; or {polygon}"
        f_mesh = d.n_driver * abs(float(x[2])) / (2 * math.pi)
        if f_mesh > 0 and abs(f_mesh - 2 * f1) <= 0.25 * 2 * f1:
            return (f"meshing frequency {f_mesh:.4g} Hz: likely {parametric}; else {slack}")
        if kick_ratio > 0.01:
            return f"meshing frequency {f_mesh:.4g} Hz: likely {polygon}; else {slack}"
        return f"meshing frequency {f_mesh:.4g} Hz: likely {slack}; else {parametric}"

    def output_descriptions(self) -> dict[str, str]:
        d = super().output_descriptions()
        from .base import EXTRA_OUTPUTS
        d["tight_span.midspan_deflection"] = next(
            o.description for o in EXTRA_OUTPUTS if o.name == "tight_span.midspan_deflection") + (
            " (sum of the span's Galerkin modes at its middle)")
        return d

    def check_states(self, times, states) -> None:
        """:meth:`check` for many states (vectorised): raises for the first that fails."""
        base = self.n_sprocket_states
        q = np.abs(states[:, base:base + 2 * self.n_modes])
        limit = self._amplitude_limit()
        bad = ~np.all(np.isfinite(states), axis=1)
        if q.shape[1]:
            bad |= np.max(q, axis=1) > limit
        if bad.any():
            i = int(np.argmax(bad))
            self.check(float(times[i]), states[i])
