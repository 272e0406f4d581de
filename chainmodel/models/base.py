"""The one interface every fidelity level implements.

A model is a first-order ODE system dx/dt = f(t, x, u) (no states at level 0) driven by the
three inputs of the FMU contract, and a map from (t, x, u) to the outputs of DESIGN.md. The
steppers in :mod:`chainmodel.integrate` only ever talk to this interface, so any level runs with
any stepper, in the library, in the CLI and inside the FMU.

Sign conventions (DESIGN.md): angles and speeds are positive in the forward direction (the input
shaft turning positively drives the chain forward; the span the driver pulls is the tight span).
``load.torque`` opposes forward motion of the driven sprocket when positive. ``input_shaft.torque``
is the torque the drive takes from the input shaft (what a master feeds back to a motor model).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, replace
from typing import Any, ClassVar, Mapping

import numpy as np

from ..geometry import Drive
from . import limits

_ANGLE_LIMIT = limits.ANGLE_LIMIT

__all__ = ["Inputs", "OutputSpec", "CORE_OUTPUTS", "EXTRA_OUTPUTS", "ALL_OUTPUTS", "Model",
           "SimulationDiverged", "quasi_static_extras", "QUASI_STATIC", "centrifugal_tension"]


class SimulationDiverged(RuntimeError):
    """The integration left the physically meaningful range (non-finite or runaway state).

    The message says when, in which quantity, and what to try."""


@dataclass(frozen=True)
class Inputs:
    """The three FMU inputs, plus the input shaft's angular acceleration where it is known
    (an analytic speed profile; the FMU estimates it by backward difference of the speed)."""

    angle: float = 0.0         # input_shaft.angle [rad]
    speed: float = 0.0         # input_shaft.speed [rad/s]
    torque: float = 0.0        # load.torque [N.m]
    acceleration: float = 0.0  # d(speed)/dt [rad/s^2]
    #: motor.torque [N.m]: the torque driving the motor rotor in torque causality
    #: (input_shaft.causality = torque, models/torque_causality.py); unused in angle causality
    motor_torque: float = 0.0

    def hold(self, dt: float) -> "Inputs":
        """First-order hold over a communication step: the angle advances at the held speed."""
        return replace(self, angle=self.angle + self.speed * dt)

    def check(self) -> "Inputs":
        for name, value in (("input_shaft.angle", self.angle), ("input_shaft.speed", self.speed),
                            ("load.torque", self.torque),
                            ("input_shaft.acceleration", self.acceleration),
                            ("motor.torque", self.motor_torque)):
            if not math.isfinite(value):
                raise ValueError(f"input {name} must be finite, got {value!r}")
        return self


# the outputs of DESIGN.md: chainmodel.outputs (re-exported here)
from ..outputs import ALL_OUTPUTS, CORE_OUTPUTS, EXTRA_OUTPUTS, OutputSpec  # noqa: E402

QUASI_STATIC = "quasi-static estimate at this fidelity level: "


def quasi_static_extras(drive: Drive, params: Mapping[str, Any], tight, slack,
                        tight_length, centrifugal=0.0) -> dict[str, np.ndarray]:
    """Level 2-3 outputs estimated from the span tensions, for the levels that do not model them
    (vectorised over samples). ``tight`` and ``slack`` are the effective (elastic) tensions,
    without the centrifugal tension ``centrifugal`` = rho A v^2 that the spans carry on top
    (docs/stability.md, "Centrifugal tension"):

    * midspan deflection: static sag of a string of mass per length m/p under its own weight,
      g cos(inclination) (m/p) l^2 / (8 T), reported negative (towards gravity); a span without
      tension reports the geometric bound l / 2. A moving string sags under the effective
      tension (T - rho A v^2 of the moving-string equation);
    * largest / smallest link tension: the larger / smaller span tension, centrifugal tension
      included;
    * largest contact force: with rigid seats the first seated roller on the driver takes at
      most the tight-span tension (the effective one: the centrifugal part is balanced by the
      wrapped chain's centripetal acceleration, not by the seats), which is what we report.
    """
    tight, slack, tight_length = (np.asarray(v, float) for v in (tight, slack, tight_length))
    rho = params["chain.link_mass"] / drive.pitch
    g_n = params["gravity"] * math.cos(params["drive.inclination"])
    with np.errstate(divide="ignore", invalid="ignore"):
        sag = rho * g_n * tight_length**2 / (8.0 * tight)
    sag = np.where((tight > 0) & np.isfinite(sag), np.minimum(sag, tight_length / 2),
                   tight_length / 2)
    return {"tight_span.midspan_deflection": -sag,
            "chain.max_link_tension": np.maximum(tight, slack) + centrifugal,
            "contact.max_force": tight.copy(),
            "chain.min_link_tension": np.minimum(tight, slack) + centrifugal}


def centrifugal_tension(drive: Drive, params: Mapping[str, Any], driver_speed):
    """Centrifugal tension rho A v^2 [N] of a chain running at the mean chain speed
    v = n_driver p w / 2 pi (ISO 10823's F_c = q v^2; derivation in docs/stability.md):
    added to both spans' tension at levels 0-2, not to the sprocket torques."""
    v = drive.n_driver * drive.pitch * np.asarray(driver_speed, float) / (2 * math.pi)
    return params["chain.link_mass"] / drive.pitch * v * v


def check_pretension(drive: Drive, params: Mapping[str, Any]) -> None:
    """Every level refuses a ``chain.pretension`` that leaves the chain slack at rest
    (:func:`chainmodel.models.kinematic.pretension_error`; one definition of pretension)."""
    if "chain.pretension" not in params:
        return
    from .static_tension import pretension_error
    why = pretension_error(drive, params)
    if why is not None:
        raise ValueError(why)


class Model(ABC):
    """One fidelity level of the chain drive.

    Subclasses set ``level``, ``name`` and implement the abstract methods. ``params`` is the
    validated parameter dict of :mod:`chainmodel.parameters` (all names present).
    """

    level: ClassVar[int]
    name: ClassVar[str]
    #: state layout [q, v] with dq/dt = v for the first half (enables symplectic steppers)
    second_order: ClassVar[bool] = False

    # --- the stepper contract: everything chainmodel.integrate asks of a model is declared
    # here with its default (no attribute probing in the steppers) ----------------------------
    #: the stepper ``solver.method = auto`` picks (make_stepper)
    preferred_method: ClassVar[str] = "rk45"
    #: names of the entries of :meth:`switching_functions`, for messages (empty: by index)
    switching_names: ClassVar[tuple[str, ...]] = ()
    #: fixed-step methods for which :meth:`advance_points` / :meth:`advance_held` run the
    #: loop in the model's kernels (when :meth:`has_loop_kernel` also says so)
    compiled_methods: ClassVar[tuple[str, ...]] = ()
    #: False where ``solver.tolerance`` does not set the automatic step (level 3: its step is
    #: the stability bound; docs/numerics.md)
    tolerance_applies: ClassVar[bool] = True
    #: why the last :meth:`initial_state` could not start where the level starts its runs
    #: (level 3: its loaded statics), None where it did (validity.start_problems reports it)
    start_fallback: str | None = None

    def __init__(self, drive: Drive, params: Mapping[str, Any]):
        if drive.links is None:
            raise ValueError("a dynamic scene needs the chain's number of links (drive.links)")
        self.drive = drive
        self.params = dict(params)
        check_pretension(drive, self.params)

    # --- state ---------------------------------------------------------------------------
    @property
    @abstractmethod
    def state_names(self) -> tuple[str, ...]:
        """Names of the state vector's entries (SI units)."""

    @property
    def n_states(self) -> int:
        return len(self.state_names)

    @abstractmethod
    def initial_state(self, u: Inputs) -> np.ndarray:
        """State at rest consistent with the input-shaft angle ``u.angle``."""

    @abstractmethod
    def rhs(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        """dx/dt."""

    @abstractmethod
    def outputs(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, float]:
        """Every output of ALL_OUTPUTS, by name, in SI units."""

    # --- optional capabilities (defaults are safe) ----------------------------------------
    def output_descriptions(self) -> dict[str, str]:
        """Description of each output at this level; outputs the level cannot compute say that
        they are quasi-static estimates."""
        return {o.name: o.description for o in ALL_OUTPUTS}

    def switching_functions(self, t: float, x: np.ndarray, u: Inputs) -> np.ndarray:
        """Smooth functions whose sign changes mark kinks in rhs (a span going slack, a contact
        opening). Steppers stop on them instead of smearing the switch."""
        return np.empty(0)

    def stable_step(self, x: np.ndarray) -> float:
        """Largest stable step of an explicit scheme (per unit of the scheme's stability
        interval on the imaginary axis, i.e. 1 / omega_max); inf when unknown."""
        return math.inf

    def omega_at(self, t: float, x: np.ndarray, u: Inputs) -> float:
        """Highest natural frequency of the state x under the inputs u [rad/s], for the
        fixed-step rule and its stable-step guard (chainmodel.integrate); by default the
        bound 1 / stable_step(x)."""
        return 1.0 / self.stable_step(x)

    def step_kept(self, x: np.ndarray, x_next: np.ndarray) -> bool:
        """False when the fixed step from x to x_next outran the step rule's estimate at its
        start and is to be retried shorter (chainmodel.kernels.rk4_loop._interval); by default
        every step is kept."""
        return True

    def event_step(self, speed: float) -> float:
        """Largest fixed step that resolves the switching functions' sign changes one at a
        time when the driver turns at ``speed`` [rad/s]; inf for a model without events."""
        return math.inf

    def jacobian_sparsity(self):
        """Sparsity pattern of d(rhs)/dx for implicit steppers (None: dense)."""
        return None

    #: True where :meth:`evaluate` gives every output at many samples at once (the stateless
    #: level 0; simulate() then skips the stepper)
    vectorised: ClassVar[bool] = False

    def evaluate(self, angle, speed, acceleration, torque) -> dict[str, np.ndarray]:
        """Every output at many input samples at once (arrays), for a :attr:`vectorised`
        model."""
        raise NotImplementedError(f"the {self.name} model has no vectorised evaluation")

    def state_scale(self) -> np.ndarray | None:
        """Typical magnitude of each state entry (the adaptive steppers' atol = rtol * scale);
        None: no scale (atol 1e-9)."""
        return None

    def refuse_method(self, method: str) -> str | None:
        """Why the stepper ``method`` is refused for this model (one sentence naming
        solver.method and what to use instead), or None when it is accepted."""
        return None

    def has_loop_kernel(self, method: str) -> bool:
        """True when :meth:`advance_points` / :meth:`advance_held` run the fixed-step loop of
        ``method`` in the model's kernels (``method`` in :attr:`compiled_methods`; compiled
        when the numba switch is on, their plain source otherwise); the steppers otherwise run
        their own loop on :meth:`rhs` (chainmodel.integrate.FixedStepper)."""
        return False

    def advance_points(self, method, x_in, x_out, times, angle, speed, acceleration, torque,
                       cfg, out, states, log, log_cap):
        """The fixed-step loop of ``method`` through the communication points ``times`` in one
        compiled call (step rule ``cfg``, outputs into ``out`` rows 1.., states into
        ``states``; x_in untouched, the final state in x_out). Returns (reached, status, steps,
        events, evaluations, logged, t_status, omega); only called when
        :meth:`has_loop_kernel` is True."""
        raise NotImplementedError(f"the {self.name} model has no compiled {method} loop")

    def advance_held(self, method, x_in, x_out, t0, t1, angle, speed, acceleration, torque,
                     cfg, out, log):
        """:meth:`advance_points` over one communication step with the inputs held first-order
        (the FMU's hold), outputs at t1 in out[1]; only called when :meth:`has_loop_kernel`
        is True."""
        raise NotImplementedError(f"the {self.name} model has no compiled {method} loop")

    def check(self, t: float, x: np.ndarray) -> None:
        """Raise SimulationDiverged if the state is not physical. Default: finite check."""
        if not np.all(np.isfinite(x)):
            bad = [n for n, v in zip(self.state_names, x) if not math.isfinite(v)]
            raise SimulationDiverged(
                f"{self.name} model diverged at t = {t:.6g} s: non-finite state {', '.join(bad[:5])}; "
                "try a smaller step or an implicit solver (solver.method = radau)")

    def check_states(self, times, states) -> None:
        """:meth:`check` for many states, in order (a model whose check is vectorisable may do
        it at once, raising for the same first state)."""
        for t, x in zip(times, states):
            self.check(float(t), x)

    def outputs_into(self, t: float, x: np.ndarray, angle: float, speed: float,
                     acceleration: float, torque: float, out: np.ndarray) -> None:
        """Every output of ALL_OUTPUTS, in that order, into ``out`` (the FMU's buffer). Levels
        with a compiled output function override this; the default goes through outputs()."""
        res = self.outputs(t, x, Inputs(angle, speed, torque, acceleration))
        for k, spec in enumerate(ALL_OUTPUTS):
            out[k] = res[spec.name]

    def snapshot(self, t: float, x: np.ndarray, u: Inputs) -> dict[str, np.ndarray]:
        """Extra arrays for plots (e.g. roller positions); empty by default."""
        return {}

    # --- span roles (chainmodel.kernels.span_roles) ------------------------------------------
    def role_constants(self) -> tuple[float, float, float]:
        """(c_2 [N m s/rad], J_2 [kg m^2], z1 / z2) of the transmitted torque M = load +
        (z1 / z2) (c_2 w_in + J_2 a_in) that names the tight span (span_roles.
        transmitted_torque; J_2 as this level has it: ``driven.inertia`` unless overridden)."""
        p = self.params
        return (float(p["driven.damping"]), float(p["driven.inertia"]),
                float(self.drive.tooth_ratio))

    def hold_role(self, hold: float) -> None:
        """Name the tight span in this level's outputs until told otherwise: +1 the upper span,
        -1 the lower, 0 from the inputs at each evaluation (span_roles.lower_tight). A stepper
        taking inputs step by step holds the role its filtered transmitted torque names
        (chainmodel.integrate, span_roles.filtered_torque). Levels with compiled outputs
        override it; here nothing to hold (outputs() decides from the inputs)."""

    def static_tension(self) -> float:
        """Static span tension at rest with no load [N] (what the centre distance and
        pre-strain give this level); nan where not defined."""
        return math.nan

    # --- where the level is valid (models/limits.py, docs/stability.md) ---------------------
    def speed_limit(self) -> tuple[float, str]:
        """(largest |input_shaft.speed| [rad/s] this level is valid to, the reason in words).
        Default, every level: the speed at which the centrifugal tension rho A v^2 alone
        strains the chain by limits.STRAIN_LIMIT."""
        w = limits.centrifugal_speed_limit(self.drive, self.params)
        return w, (f"the centrifugal tension rho A v^2 would strain the chain by more than "
                   f"{100 * limits.STRAIN_LIMIT:g} %")

    def torque_limit(self) -> float:
        """Largest |load.torque| [N.m]: the tight span would carry torque / R_driven, at most
        limits.tension_limit (small strain)."""
        return limits.tension_limit(self.drive, self.params) * self.drive.driven.pitch_radius

    def input_error(self, angle: float, speed: float, torque: float) -> str | None:
        """None if the inputs are acceptable, else one sentence naming the input, its value and
        what is valid: finite values, |input_shaft.angle| <= limits.ANGLE_LIMIT,
        |input_shaft.speed| <= :meth:`speed_limit`, |load.torque| <= :meth:`torque_limit`.
        The steppers and the FMU call it before every step."""
        bounds = self.__dict__.get("_input_bounds")
        try:
            ok = (bounds is not None and abs(angle) <= _ANGLE_LIMIT
                  and abs(speed) <= bounds[0] and abs(torque) <= bounds[2])
        except TypeError:
            ok = False
        if ok:                 # the common case, cheaply (called before every step)
            return None
        for name, value in (("input_shaft.angle", angle), ("input_shaft.speed", speed),
                            ("load.torque", torque)):
            if not isinstance(value, (int, float, np.floating, np.integer)) or \
                    not math.isfinite(value):
                return f"input {name} must be a finite number, got {value!r}"
        if abs(angle) > limits.ANGLE_LIMIT:
            return (f"input input_shaft.angle = {angle:.6g} rad is beyond +-{limits.ANGLE_LIMIT:g}"
                    " rad, where a double no longer resolves a micro-radian; restart the angle "
                    "count (it is periodic)")
        if bounds is None:   # the parameters are fixed for a model's life: compute once
            bounds = self.__dict__["_input_bounds"] = (*self.speed_limit(), self.torque_limit())
        w_max, why, t_max = bounds
        if abs(torque) > t_max:
            force = abs(torque) / self.drive.driven.pitch_radius
            breaking = self.params.get("chain.breaking_load") or math.inf
            if force > breaking:     # a stiffer link would not make such a chain hold
                return (f"input load.torque = {torque:.6g} N.m is beyond +-{t_max:.4g} N.m: "
                        f"the tight span would carry {force:.4g} N, above the chain's breaking "
                        f"load (chain.breaking_load = {breaking:.4g} N) and beyond "
                        f"{100 * limits.STRAIN_LIMIT:g} % strain of a link, where the models "
                        f"hold; use a load below {breaking * self.drive.driven.pitch_radius:.4g} "
                        f"N.m (the breaking load on the driven pitch radius) or a larger chain")
            return (f"input load.torque = {torque:.6g} N.m is beyond +-{t_max:.4g} N.m: the tight "
                    f"span would carry {force:.4g} N, "
                    f"more than {100 * limits.STRAIN_LIMIT:g} % strain of a link of "
                    f"chain.link_stiffness = {self.params['chain.link_stiffness']:g} N/m where "
                    f"the models hold; use a smaller load or chain.link_stiffness >= "
                    f"{force / (limits.STRAIN_LIMIT * self.drive.pitch):.3g} N/m")
        if abs(speed) > w_max:
            return (f"input input_shaft.speed = {speed:.6g} rad/s ({speed / limits.RPM:.6g} rpm)"
                    f" is beyond the {self.name} model's (level {self.level}) limit of "
                    f"{w_max:.6g} rad/s ({w_max / limits.RPM:.6g} rpm): {why}")
        return None
