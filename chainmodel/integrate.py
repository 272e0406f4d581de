"""Steppers: advance any :class:`~chainmodel.models.base.Model` over communication steps.

One small interface in the spirit of ``scipy.integrate.OdeSolver``: build a stepper for a model,
call :meth:`Stepper.advance` with the end time and the inputs, read outputs; swap the method and
nothing else changes. Inputs are either an :class:`Inputs` held first-order over the step (the FMU
case) or a callable ``t -> Inputs`` (an analytic scene profile).

Methods
-------
``rk4``     classic fixed-step Runge-Kutta, 4 evaluations a step, stable for h w_max < 2.83.
``verlet``  fixed-step velocity Verlet for second-order models (state [q, v]): one evaluation a
            step, stable for h w_max < 2; velocity-dependent forces use the half-step velocity.
``rk45``, ``dop853``   adaptive explicit (scipy ``solve_ivp``).
``radau``, ``bdf``     adaptive implicit, with the model's Jacobian sparsity pattern.
``lsoda``   adaptive, switches between stiff and non-stiff.

Fixed steps (docs/numerics.md): the automatic step comes from the accuracy asked
(``solver.tolerance``: the relative frequency error of the fastest mode), the highest natural
frequency of the *current* state (:meth:`Model.omega_at`) and a quarter tooth period at the
current input speed (:meth:`Model.event_step`), never from the communication step, which is only
split into equal steps no longer than that; the bound is estimated again after every step and
the rest of the communication step split again when it shrank (the stable-step guard). An
explicit ``solver.step`` is used as given, and refused - at construction or when the state
changes - when it is above the stability limit. Every stepper stops on the
model's switching functions (a span going slack...): the fixed-step methods locate the first
sign change in a step on its dense output and step across it (``rk4_loop._cross``),
the adaptive ones use scipy events, so kinks are resolved rather than smeared. Every stepper
checks the state after each communication step: a diverging integration raises
:class:`SimulationDiverged`, it never returns NaN, and a step that fails leaves the stepper at its
last communication point (no state copy is made for that: the new state is built beside the old
one and committed on success).

Levels 1-3 run the fixed-step loops of their kernels, a communication step with its outputs in
one call (:meth:`FixedStepper.advance_held`, the FMU's path; :meth:`FixedStepper.advance_points`
for many points, ``simulate()``'s path): compiled with numba, and the same source as plain
Python when ``CHAINMODEL_NUMBA=0`` (the one switch, :mod:`chainmodel._numba`).
:meth:`FixedStepper._integrate` runs the same loop - rk4_loop's own functions, as plain Python
(:mod:`chainmodel.kernels.plain_loop`) - on :meth:`Model.rhs`, for any model without kernels
and for :func:`python_loop_model` (the twin the tests and benchmarks compare with): the step
rule and the crossing are written once.
Everything asked of a model is declared in :class:`~chainmodel.models.base.Model`
(docs/architecture.md).
"""

from __future__ import annotations

import math
import time
from collections import deque
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import Callable, ClassVar, Union

import numpy as np

from .models.base import Inputs, Model, SimulationDiverged
# the loops' status codes, defined once in the loop of levels 1-2 (1 diverged, 2 explicit step
# above the stable limit, 3 the model's range left, 4 non-finite outputs; level 3's loops
# (kernels.multibody_loops) use the same numbers)
from .outputs import OUTPUT_NAMES
from .kernels.rk4_loop import STATUS_OUTPUTS, STATUS_UNSTABLE
from .kernels.plain_loop import run_interval
from .kernels.span_roles import filtered_torque, role_hold

__all__ = ["Stepper", "FixedStepper", "RK4", "Verlet", "Adaptive", "StepperState", "METHODS",
           "make_stepper", "SimulationDiverged", "stability_limit", "accuracy_step", "frequency_error",
           "OUTPUT_NAMES", "DEFAULT_TOLERANCE", "python_loop_model"]

InputSource = Union[Inputs, Callable[[float], Inputs]]

#: default of solver.tolerance (chainmodel.parameters; docs/numerics.md)
DEFAULT_TOLERANCE = 5e-4
#: event times a compiled communication step keeps for the event log
EVENTS_PER_STEP = 16


@dataclass
class StepperState:
    """Everything needed to resume a stepper exactly (FMU get/set/serialize state)."""

    t: float
    x: np.ndarray
    h: float = 0.0                      # last step size (adaptive) or step (fixed)
    inputs: Inputs = field(default_factory=Inputs)
    extra: dict = field(default_factory=dict)


class Stepper(ABC):
    """Advance a model's state over communication steps."""

    method: ClassVar[str]

    def __init__(self, model: Model, t0: float = 0.0, x0: np.ndarray | None = None,
                 inputs: Inputs | None = None):
        self.model = model
        self.inputs = (inputs or Inputs()).check()
        self.t = float(t0)
        self.x = (np.array(model.initial_state(self.inputs), float) if x0 is None
                  else np.array(x0, float))
        if self.x.shape != (model.n_states,):
            raise ValueError(f"initial state has shape {self.x.shape}, the {model.name} model "
                             f"needs ({model.n_states},)")
        self.stats = {"steps": 0, "rhs_evaluations": 0, "events": 0, "rejected": 0,
                      "wall_time": 0.0}
        #: the transmitted torque's running mean over about a driver tooth period, which names
        #: the tight span where inputs arrive step by step (span_roles.filtered_torque; nan:
        #: not started, the roles then follow the inputs)
        self.role_torque = math.nan
        #: (c_2, J_2, z1 / z2, z1) of the transmitted torque and its filter, and the role the
        #: model holds now (+1 / -1, 0: from the inputs)
        self._role_constants = (*model.role_constants(), float(model.drive.n_driver))
        self._held_role = 0.0
        model.hold_role(0.0)
        #: times at which the last (up to 1000) switching events were located
        self.event_log: deque = deque(maxlen=1000)
        self._row = np.empty(len(OUTPUT_NAMES))

    # --- inputs: built lazily, so a compiled step need not make an Inputs object ------------
    @property
    def inputs(self) -> Inputs:
        """The inputs at the current time (held ones after a step with held inputs)."""
        u = self._inputs
        if u is None:
            angle, speed, torque, acc = self._held
            u = self._inputs = Inputs(angle, speed, torque, acc)
        return u

    @inputs.setter
    def inputs(self, u: Inputs) -> None:
        self._inputs = u

    def held_angle_speed(self) -> tuple[float, float]:
        """(angle, speed) of :attr:`inputs` without building an Inputs (the FMU's per-step
        angle check)."""
        u = self._inputs
        if u is None:
            return self._held[0], self._held[1]
        return u.angle, u.speed

    def _set_held(self, angle, speed, torque, acceleration) -> None:
        self._inputs = None
        self._held = (angle, speed, torque, acceleration)

    # --- public -----------------------------------------------------------------------------
    def advance(self, t_end: float, inputs: InputSource | None = None) -> dict[str, float]:
        """Integrate from the current time to ``t_end`` and return the outputs there.

        ``inputs``: an Inputs held over the step (angle advancing at the held speed), or a
        callable giving the inputs at any time; None keeps the last held inputs. A step that
        fails (ValueError for refused inputs, SimulationDiverged) leaves the stepper as it was."""
        t_end = self._check_time(t_end)
        if inputs is None:
            inputs = self.inputs
        if isinstance(inputs, Inputs):
            # refused inputs first (the one check of this path): the span roles' filter
            # divides by the speed
            self.refuse_bad_inputs(inputs.angle, inputs.speed, inputs.torque)
            saved = self._hold_role(t_end, inputs.speed, inputs.acceleration, inputs.torque)
            try:
                row = self._advance_held(t_end, inputs.angle, inputs.speed,
                                         inputs.acceleration, inputs.torque)
                if row is not None:
                    return dict(zip(OUTPUT_NAMES, row.tolist()))
                return self._advance_python(t_end, inputs)
            except Exception:
                self.role_torque = saved
                raise
        self._release_role()
        row = self._advance_source(t_end, inputs)
        if row is not None:
            return dict(zip(OUTPUT_NAMES, row.tolist()))
        return self._advance_python(t_end, inputs)

    def advance_held(self, t_end: float, angle: float, speed: float, acceleration: float,
                     torque: float) -> np.ndarray:
        """The FMU's step: integrate to ``t_end`` with the inputs held first-order from the
        current time (angle advancing at ``speed``; speed, acceleration and torque held) and
        return every output at ``t_end`` (ALL_OUTPUTS order; a buffer reused by the next call).
        One compiled call where the model and method have one; the same numbers as
        :meth:`advance` with ``Inputs(angle, speed, torque, acceleration)``."""
        t_end = self._check_time(t_end)
        self.refuse_bad_inputs(angle, speed, torque)     # the one check, before the roles' filter
        saved = self._hold_role(t_end, speed, acceleration, torque)
        try:
            row = self._advance_held(t_end, angle, speed, acceleration, torque)
            if row is None:
                out = self._advance_python(t_end, Inputs(angle, speed, torque, acceleration))
                row = self._row
                for k, name in enumerate(OUTPUT_NAMES):
                    row[k] = out[name]
        except Exception:
            self.role_torque = saved
            raise
        return row

    def outputs_held(self, angle: float, speed: float, acceleration: float, torque: float
                     ) -> np.ndarray:
        """Every output (ALL_OUTPUTS order) at the current state for the inputs given (the FMU's
        direct feedthrough when a master sets inputs at a communication point); refused inputs
        raise ValueError."""
        self.refuse_bad_inputs(angle, speed, torque)
        if math.isnan(self.role_torque):     # the first inputs start the running mean
            self._hold_role(self.t, speed, acceleration, torque)
        self.model.outputs_into(self.t, self.x, angle, speed, acceleration, torque, self._row)
        return self._row

    def advance_points(self, times, angle, speed, acceleration, torque, out) -> bool:
        """Integrate through the communication points ``times`` (``times[0]`` the current time)
        with the inputs given there as arrays, writing the outputs at times[i] into ``out[i]``
        for i >= 1 (ALL_OUTPUTS order) - the numbers :meth:`advance` gives one point at a time
        with a source that has these values, in one compiled call. False (nothing done) when
        this stepper and model have no such path."""
        return False

    def advance_batch(self, times, angle, speed, acceleration, torque) -> np.ndarray | None:
        """Like :meth:`advance_points` but returning the states at every point (``states[0]``
        the current one), or None when there is no compiled path."""
        return None

    def outputs(self) -> dict[str, float]:
        """Outputs at the current time and inputs."""
        return self.model.outputs(self.t, self.x, self.inputs)

    def get_state(self) -> StepperState:
        return StepperState(self.t, self.x.copy(), self._h_state(), self.inputs,
                            {"role_torque": self.role_torque})

    def set_state(self, state: StepperState) -> None:
        x = np.array(state.x, float)
        if x.shape != self.x.shape:
            raise ValueError(f"state has {x.shape[0]} entries, the {self.model.name} model needs "
                             f"{self.x.shape[0]}")
        self.t, self.x, self.inputs = float(state.t), x, state.inputs
        self._restore_h(state.h)
        self.role_torque = float(state.extra.get("role_torque", math.nan))
        hold = (0.0 if math.isnan(self.role_torque) else
                role_hold(self.role_torque, state.inputs.speed))
        self.model.hold_role(hold)
        self._held_role = hold

    def _hold_role(self, t_end, speed, acceleration, torque) -> float:
        """Advance the running mean of the transmitted torque to ``t_end`` with the inputs held
        over the step (span_roles.filtered_torque), and have the model name the tight span by
        its sign (span roles that do not flip with an input rippling through zero within a
        tooth period; docs/stability.md, "Tight and slack span"). Returns the mean before the
        step (restored if the step fails)."""
        saved = self.role_torque
        damping, inertia, ratio, teeth = self._role_constants
        m = torque + ratio * (damping * speed + inertia * acceleration)
        self.role_torque = filtered_torque(saved, m, t_end - self.t, speed, teeth)
        hold = role_hold(self.role_torque, speed)
        if hold != self._held_role:
            self.model.hold_role(hold)
            self._held_role = hold
        return saved

    def _release_role(self) -> None:
        """Roles from the inputs at each evaluation (whole runs' arrays, callable sources)."""
        self.role_torque = math.nan
        if self._held_role != 0.0:
            self.model.hold_role(0.0)
            self._held_role = 0.0

    def refuse_bad_inputs(self, angle, speed, torque) -> None:
        """The one place where inputs are checked before a step: raise ValueError with the
        model's sentence (:meth:`Model.input_error`) when they are not acceptable. Arrays (a
        batch of communication points) are checked at their non-finite, largest-speed and
        largest-torque points."""
        if (isinstance(angle, np.ndarray) or isinstance(speed, np.ndarray)
                or isinstance(torque, np.ndarray)):
            angle, speed, torque = (np.asarray(v, float) for v in (angle, speed, torque))
            bad = ~(np.isfinite(angle) & np.isfinite(speed) & np.isfinite(torque))
            picks = ([int(np.argmax(bad))] if bad.any() else []) + [
                int(np.argmax(np.abs(speed))), int(np.argmax(np.abs(torque)))]
            for k in picks:
                self.refuse_bad_inputs(float(angle[k]), float(speed[k]), float(torque[k]))
            return
        error = self.model.input_error(angle, speed, torque)
        if error is not None:
            raise ValueError(error)

    # --- internals --------------------------------------------------------------------------
    def _check_time(self, t_end) -> float:
        t_end = float(t_end)
        if not math.isfinite(t_end) or t_end < self.t - 1e-12 * max(1.0, abs(self.t)):
            raise ValueError(f"communication point t_end = {t_end!r} s is before the current "
                             f"time {self.t!r} s")
        return t_end

    def _advance_held(self, t_end, angle, speed, acceleration, torque) -> np.ndarray | None:
        """Compiled path for held inputs: the outputs row, or None (use _advance_python)."""
        model = self.model
        if model.n_states:
            return None
        # stateless (level 0): the outputs of the held inputs at t_end (inputs checked by the
        # callers, advance and advance_held)
        a1 = angle + speed * (t_end - self.t)
        row = self._row
        if model.outputs_into(t_end, self.x, a1, speed, acceleration, torque, row) is not True:
            self._commit_outputs(t_end, row)     # (a compiled output function says True)
        self.t = t_end
        self._set_held(a1, speed, torque, acceleration)
        return row

    def _advance_source(self, t_end, source) -> np.ndarray | None:
        """Compiled path for a callable source: the outputs row, or None."""
        return None

    def _commit_outputs(self, t, row) -> None:
        """Non-finite outputs are a divergence, never a result."""
        if not np.all(np.isfinite(row)):
            bad = [n for n, v in zip(OUTPUT_NAMES, row.tolist()) if not math.isfinite(v)]
            raise SimulationDiverged(f"{self.model.name} model produced non-finite outputs "
                                     f"{', '.join(bad[:5])} at t = {t:.6g} s")

    def _advance_python(self, t_end, inputs) -> dict[str, float]:
        """The model-interface path: integrate in Python (or scipy), outputs by Model.outputs.
        On failure the stepper keeps its time, state and inputs (the integration builds new
        arrays and assigns them at the end)."""
        source = self._source(inputs)
        for u0 in (source(self.t), source(t_end)):
            self.refuse_bad_inputs(u0.angle, u0.speed, u0.torque)
        saved = self.t, self.x, self._inputs, getattr(self, "_held", None), self._h_state()
        wall = time.perf_counter()
        try:
            if self.model.n_states and t_end > self.t:
                self._integrate(self.t, t_end, source)
                self.model.check(t_end, self.x)
            u = source(t_end)
            out = self.model.outputs(t_end, self.x, u)
            bad = [k for k, v in out.items() if not math.isfinite(v)]
            if bad:
                raise SimulationDiverged(f"{self.model.name} model produced non-finite outputs "
                                         f"{', '.join(bad[:5])} at t = {t_end:.6g} s")
        except BaseException:
            self.t, self.x, self._inputs, held, h = saved
            if held is not None:
                self._held = held
            self._restore_h(h)
            raise
        self.t = t_end
        self.inputs = u
        self.stats["wall_time"] += time.perf_counter() - wall
        return out

    def _source(self, inputs: InputSource | None) -> Callable[[float], Inputs]:
        if inputs is None:
            inputs = self.inputs
        if callable(inputs) and not isinstance(inputs, Inputs):
            return lambda t: inputs(t)
        held = inputs.check()
        t0 = self.t
        return lambda t: held.hold(t - t0)

    def _rhs(self, t, x, source):
        self.stats["rhs_evaluations"] += 1
        return self.model.rhs(t, x, source(t))

    @abstractmethod
    def _integrate(self, t0: float, t1: float, source: Callable[[float], Inputs]) -> None:
        ...

    def _h_state(self) -> float:
        return 0.0

    def _restore_h(self, h: float) -> None:
        pass


# --- fixed step ------------------------------------------------------------------------------



def stability_limit(method: str) -> float:
    """Stability interval on the imaginary axis, h * omega_max, of a fixed-step method."""
    return {"rk4": 2.0 * math.sqrt(2.0), "verlet": 2.0}[method]


def frequency_error(method: str, theta: float) -> float:
    """Relative error of a fixed-step method's numerical frequency on x'' = -omega^2 x at
    h omega = theta (docs/numerics.md): RK4 advances the phase by arg R(i theta) per step, R its
    amplification factor 1 + z + z^2/2 + z^3/6 + z^4/24, so it lags by 1 - arg R / theta
    (~ theta^4 / 120); velocity Verlet's frequency is 2 asin(theta / 2) / h, too high by
    2 asin(theta / 2) / theta - 1 (~ theta^2 / 24)."""
    if method == "rk4":
        return 1.0 - math.atan2(theta - theta**3 / 6.0,
                                1.0 - theta**2 / 2.0 + theta**4 / 24.0) / theta
    if method == "verlet":
        return 2.0 * math.asin(min(theta / 2.0, 1.0)) / theta - 1.0
    raise ValueError(f"no accuracy rule for the {method!r} stepper")


def accuracy_step(method: str, tolerance: float) -> float:
    """h omega at which :func:`frequency_error` equals ``tolerance`` (bisection; both errors
    grow monotonically with the step inside the stability interval)."""
    lo, hi = 0.0, 0.999 * stability_limit(method)
    if frequency_error(method, hi) <= tolerance:
        return hi
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        if frequency_error(method, mid) > tolerance:
            hi = mid
        else:
            lo = mid
    return lo


class FixedStepper(Stepper):
    """Common part of the fixed-step methods: the step rule, its guard, the compiled path and
    event crossing."""

    safety: ClassVar[float] = 0.9

    def __init__(self, model: Model, t0=0.0, x0=None, inputs=None, step: float = 0.0,
                 max_step: float = math.inf, tolerance: float = DEFAULT_TOLERANCE):
        super().__init__(model, t0, x0, inputs)
        if not (isinstance(tolerance, (int, float)) and 0 < tolerance <= 0.1):
            raise ValueError(f"solver.tolerance must be in (0, 0.1], got {tolerance!r}")
        self.tolerance = float(tolerance)
        self.fixed_step = float(step) if step and step > 0 else 0.0
        self.max_step = float(max_step) if max_step and max_step > 0 else math.inf
        self.limit = stability_limit(self.method)
        w = model.omega_at(self.t, self.x, self.inputs)
        limit = self.limit / w
        if self.fixed_step:
            if self.fixed_step > limit:
                raise ValueError(self._unstable_text(self.fixed_step, w, None))
        elif not math.isfinite(limit):
            raise ValueError(f"the {model.name} model reports no stability limit; give "
                             f"solver.step explicitly for the {self.method} stepper")
        self.stable_limit = limit
        #: the step rule for the compiled loops (rk4_loop.CF_*): explicit step, tolerance's
        #: h omega, safety times the stability limit, the limit, an outer bound
        theta = (accuracy_step(self.method, self.tolerance)
                 if model.tolerance_applies else math.inf)
        self.cfg = np.array([self.fixed_step, theta, self.safety * self.limit, self.limit,
                             self.max_step])
        #: the step bound at the initial state and input speed (the step itself follows the
        #: state and the input speed)
        self.h = (self.fixed_step or
                  self.step_bound(w, model.event_step(abs(self.inputs.speed))))
        self._spare = np.empty_like(self.x)
        self._out = np.empty((2, len(OUTPUT_NAMES)))
        self._log = np.empty(EVENTS_PER_STEP)
        self._log_python = np.empty(1000)
        self._empty_states = np.empty((0, self.x.size))

    def step_bound(self, omega: float, h_event: float = math.inf) -> float:
        """The automatic step bound for a state whose highest natural frequency is ``omega``
        and an event step ``h_event`` (rk4_loop._step_bound: min of the tolerance's step, 90 %
        of the stability limit, max_step and the event step)."""
        theta, stab = self.cfg[1], self.cfg[2]
        h = min(theta / omega, stab / omega) if omega > 0 else math.inf
        return min(h, self.max_step, h_event)

    def _unstable_text(self, step, omega, t) -> str:
        limit = self.limit / omega
        where = "" if t is None else f" at t = {t:.6g} s"
        return (f"solver.step = {step:.6g} s is above the stable limit {limit:.6g} s of the "
                f"{self.method} stepper for this {self.model.name} model{where} (highest natural "
                f"frequency {omega / (2 * math.pi):.6g} Hz); use a step <= {limit:.6g} s or 0 "
                "for automatic")

    def _has_compiled(self) -> bool:
        """The model's kernels hold the loop of this method (``advance_held`` /
        ``advance_points``, :meth:`Model.has_loop_kernel`: levels 1-3, compiled with numba and
        their plain source without); otherwise rk4_loop's loop runs on Model.rhs
        (:func:`python_loop_model` asks for that)."""
        can = self.__dict__.get("_can_compile")
        if can is None:     # what the model offers for this method (fixed once built)
            model = self.model
            can = self._can_compile = (model.n_states > 0
                                       and self.method in model.compiled_methods
                                       and model.has_loop_kernel(self.method))
        return can

    # --- compiled paths ---------------------------------------------------------------------
    def _advance_held(self, t_end, angle, speed, acceleration, torque):
        if not self._has_compiled():
            if self.model.n_states:
                return None
            return super()._advance_held(t_end, angle, speed, acceleration, torque)
        t0 = self.t       # inputs checked by the callers, advance and advance_held
        a1 = angle + speed * (t_end - t0)
        if t_end <= t0:
            row = self._row
            self.model.outputs_into(t_end, self.x, a1, speed, acceleration, torque, row)
            self._commit_outputs(t_end, row)
            self.t = t_end
            self._set_held(a1, speed, torque, acceleration)
            return row
        wall = time.perf_counter()
        out = self._out
        res = self.model.advance_held(self.method, self.x, self._spare, t0, t_end, float(angle),
                                      float(speed), float(acceleration), float(torque),
                                      self.cfg, out, self._log)
        self._finish(res, t_end, self._log, out)
        self.stats["wall_time"] += time.perf_counter() - wall
        self._set_held(a1, speed, torque, acceleration)
        return out[1]

    def _advance_source(self, t_end, source):
        if not self.model.n_states or not self._has_compiled() or t_end <= self.t:
            return None
        u0, u1 = source(self.t), source(t_end)
        times = np.array([self.t, t_end])
        arrays = [np.array([getattr(u0, k), getattr(u1, k)], float)
                  for k in ("angle", "speed", "acceleration", "torque")]
        out = self._out
        self._run_points(times, arrays, out, self._empty_states)
        self.inputs = u1
        return out[1]

    def advance_points(self, times, angle, speed, acceleration, torque, out) -> bool:
        if not self._has_compiled():
            return False
        times = self._check_times(times)
        self._release_role()
        arrays = [np.ascontiguousarray(a, float) for a in (angle, speed, acceleration, torque)]
        self._run_points(times, arrays, out, self._empty_states)
        self._set_held(float(arrays[0][-1]), float(arrays[1][-1]), float(arrays[3][-1]),
                       float(arrays[2][-1]))
        return True

    def advance_batch(self, times, angle, speed, acceleration, torque):
        if not self._has_compiled() or np.size(times) < 2:
            return None
        times = self._check_times(times)
        self._release_role()
        arrays = [np.ascontiguousarray(a, float) for a in (angle, speed, acceleration, torque)]
        states = np.empty((times.size, self.x.size))
        self._run_points(times, arrays, np.empty((0, len(OUTPUT_NAMES))), states)
        self._set_held(float(arrays[0][-1]), float(arrays[1][-1]), float(arrays[3][-1]),
                       float(arrays[2][-1]))
        return states

    def _check_times(self, times) -> np.ndarray:
        times = np.ascontiguousarray(times, float)
        if (times.size < 2 or abs(times[0] - self.t) > 1e-12 * max(1.0, abs(self.t))
                or np.any(np.diff(times) <= 0)):
            raise ValueError("advance_points needs increasing times starting at the current "
                             f"time {self.t!r} s")
        return times

    def _run_points(self, times, arrays, out, states) -> None:
        angle, speed, acceleration, torque = arrays
        self.refuse_bad_inputs(angle, speed, torque)
        wall = time.perf_counter()
        log = np.empty(1000)
        res = self.model.advance_points(self.method, self.x, self._spare, times, angle, speed,
                                        acceleration, torque, self.cfg, out, states, log,
                                        EVENTS_PER_STEP)
        reached, status, steps, events, evals, logged = res[:6]
        if logged > log.size:
            log = np.roll(log, -(logged % log.size))
        self._finish(res, float(times[-1]), log, out)
        self.stats["wall_time"] += time.perf_counter() - wall

    def _finish(self, res, t_end, log, out) -> None:
        """Book a compiled call's result: on success commit the new state (swap the buffers);
        otherwise raise the model's message and keep the old state. ``out``: the outputs
        array of the call (rows from 1), named in the message when they are not finite."""
        reached, status, steps, events, evals, logged, t_status, omega = res
        self.stats["steps"] += steps
        self.stats["events"] += events
        self.stats["rhs_evaluations"] += evals
        if status:
            if status == STATUS_OUTPUTS:
                self._commit_outputs(t_status, out[reached + 1])      # raises, naming them
            self._raise(int(status), float(t_status), float(omega), self._spare)
        if logged:
            self.event_log.extend(log[:min(int(logged), log.size)].tolist())
        self.x, self._spare = self._spare, self.x
        self.t = t_end

    def _raise(self, status, t, omega, x):
        if status == STATUS_UNSTABLE:
            raise SimulationDiverged(self._unstable_text(self.fixed_step, omega, t))
        self.model.check(t, x)   # the model's own sentence (non-finite state, amplitude, ...)
        raise SimulationDiverged(f"{self.model.name} model diverged at t = {t:.6g} s "
                                 f"(non-finite state); try a smaller solver.step or "
                                 "solver.tolerance")

    # --- the loop on the model interface (rk4_loop's source; chainmodel.kernels.plain_loop) ----------
    def _integrate(self, t0, t1, source):
        """The step rule of the module docstring over [t0, t1] on the model interface:
        rk4_loop's own loop run as plain Python (:mod:`chainmodel.kernels.plain_loop`), on a copy of
        the state so that a failure leaves the stepper where it was."""
        model = self.model
        x = self.x.copy()
        n_switch = np.asarray(model.switching_functions(t0, x, source(t0))).size
        log = self._log_python
        status, steps, events, evals, t, omega = run_interval(
            self.method, model, source, x, t0, t1, self.cfg, n_switch, log, 1 << 60)
        self.stats["steps"] += steps
        self.stats["events"] += events
        self.stats["rhs_evaluations"] += evals
        if status:
            self._raise(int(status), float(t), float(omega), x)
        if events:
            if events > log.size:
                log = np.roll(log, -(events % log.size))
            self.event_log.extend(log[:min(events, log.size)].tolist())
        self.x = x

    def _h_state(self) -> float:
        return self.h


class RK4(FixedStepper):
    """Classic RK4 (its step: rk4_loop._rk4_from)."""

    method = "rk4"


class Verlet(FixedStepper):
    """Velocity Verlet (kick-drift-kick) for models with state [q, v] (its step:
    rk4_loop._verlet_from)."""

    method = "verlet"

    def __init__(self, model: Model, *args, **kwargs):
        if not model.second_order:
            why = getattr(model, "first_order_states", "")
            raise ValueError(f"the verlet stepper needs a second-order model (state [q, v]); "
                             f"the {model.name} model is not{why}; use rk4 or an adaptive "
                             f"method")
        super().__init__(model, *args, **kwargs)


# --- adaptive -----------------------------------------------------------------------------------

class Adaptive(Stepper):
    """scipy ``solve_ivp`` per communication step, with the model's switching functions as
    terminal events (restarted just past each) and its Jacobian sparsity for implicit methods."""

    SCIPY = {"rk45": "RK45", "dop853": "DOP853", "radau": "Radau", "bdf": "BDF", "lsoda": "LSODA"}
    method = "adaptive"

    def __init__(self, model: Model, t0=0.0, x0=None, inputs=None, method: str = "rk45",
                 rtol: float = 1e-6, atol: float | np.ndarray | None = None,
                 max_step: float = math.inf):
        super().__init__(model, t0, x0, inputs)
        if method not in self.SCIPY:
            raise ValueError(f"unknown adaptive method {method!r}; choose one of {', '.join(self.SCIPY)}")
        self.method = method
        self.rtol = rtol
        self.atol = atol if atol is not None else self._default_atol()
        self.max_step = max_step
        self.h_last = 0.0

    def _default_atol(self):
        scale = self.model.state_scale()
        return 1e-9 if scale is None else self.rtol * np.asarray(scale, float)

    #: an event storm: this many events in a row, each within STORM_GAP x (t1 - t0) of the
    #: previous one, is a switching function chattering (not the seating and release events,
    #: which come a fraction of a tooth period apart)
    STORM_EVENTS = 200
    STORM_GAP = 1e-6

    def _integrate(self, t0, t1, source):
        """Integrate from t0 to t1 exactly, restarting solve_ivp just past every event.

        There is no cap on the number of events: a communication step of 1 s at 10000 rpm on
        a 25-tooth driver holds 4 x 4167 x 1 = 16700 genuine seating and release events (four
        per tooth period), and stopping at a cap returned the state from before t1. A storm of
        events closer than STORM_GAP of the step raises SimulationDiverged instead."""
        from scipy.integrate import solve_ivp

        model = self.model
        g0 = model.switching_functions(t0, self.x, source(t0))
        events = [self._event(i, source) for i in range(g0.size)]
        kwargs = dict(method=self.SCIPY[self.method], rtol=self.rtol, atol=self.atol,
                      max_step=min(self.max_step, t1 - t0))
        if self.method in ("radau", "bdf") and model.jacobian_sparsity() is not None:
            kwargs["jac_sparsity"] = model.jacobian_sparsity()
        eps = max(1e-12, 1e-9 * (t1 - t0))
        gap = self.STORM_GAP * (t1 - t0)
        t, x = t0, self.x
        close, last = 0, -math.inf
        while t < t1:
            if self.h_last > 0 and self.method != "lsoda":
                kwargs["first_step"] = min(self.h_last, t1 - t)
            sol = solve_ivp(lambda tt, xx: self._rhs(tt, xx, source), (t, t1), x,
                            events=events or None, **kwargs)
            self.stats["steps"] += max(len(sol.t) - 1, 0)
            if sol.status == -1:
                self.x = x
                raise SimulationDiverged(f"{model.name} model: the {self.method} solver failed at "
                                         f"t = {sol.t[-1]:.6g} s ({sol.message}); try a tighter "
                                         "solver.rtol or an implicit method (radau)")
            if len(sol.t) > 1:
                self.h_last = float(sol.t[-1] - sol.t[-2])
            t, x = float(sol.t[-1]), sol.y[:, -1]
            if sol.status == 0:
                break
            # an event: step just past it so the next segment starts on the new side
            self.stats["events"] += 1
            self.event_log.append(t)
            close = close + 1 if t - last <= gap else 0
            last = t
            if close >= self.STORM_EVENTS:
                self.x = np.array(x, float)
                fired = [i for i, e in enumerate(sol.t_events) if len(e)]
                names = model.switching_names
                which = (", ".join(names[i] for i in fired) if names else
                         ", ".join(f"switching function {i}" for i in fired))
                raise SimulationDiverged(
                    f"{model.name} model: event storm at t = {t:.9g} s: {close} events within "
                    f"{close * gap:.3g} s ({which} changing sign back and forth), so the "
                    f"{self.method} solver cannot get past it; the model chatters about a switch "
                    "(a span at zero tension): add damping (chain.link_damping) or use the "
                    "fixed-step rk4 solver")
            h = min(eps, t1 - t)
            x = x + h * self._rhs(t, x, source)
            t = t + h if t + h < t1 else t1
        if t != t1:  # pragma: no cover - solve_ivp status 0 means t_bound reached
            raise SimulationDiverged(f"{model.name} model: the {self.method} solver stopped at "
                                     f"t = {t!r} s before the communication point {t1!r} s")
        self.x = np.array(x, float)

    def _event(self, i, source):
        def g(t, x):
            return self.model.switching_functions(t, x, source(t))[i]
        g.terminal = True
        g.direction = 0
        return g

    def _h_state(self) -> float:
        return self.h_last

    def _restore_h(self, h: float) -> None:
        self.h_last = float(h)


METHODS = ("rk4", "verlet", "rk45", "dop853", "radau", "bdf", "lsoda")


def make_stepper(model: Model, method: str = "auto", t0: float = 0.0, inputs: Inputs | None = None,
                 step: float = 0.0, rtol: float = 1e-6, x0=None, max_step: float = math.inf,
                 tolerance: float = DEFAULT_TOLERANCE, **options) -> Stepper:
    """A stepper for ``model``. ``method="auto"`` lets the model choose
    (:attr:`Model.preferred_method`, rk45 by default). Fixed-step methods take ``step``
    (0: automatic, from ``tolerance`` and the dynamics) and ``max_step`` (an outer bound on the
    automatic step); adaptive ones ``rtol``."""
    if method == "auto":
        method = model.preferred_method
    reason = model.refuse_method(method)
    if reason:
        raise ValueError(reason)
    if method == "rk4":
        return RK4(model, t0, x0, inputs, step=step, max_step=max_step, tolerance=tolerance)
    if method == "verlet":
        return Verlet(model, t0, x0, inputs, step=step, max_step=max_step, tolerance=tolerance)
    if method in Adaptive.SCIPY:
        # max_step: a bound on the step (a scene's quarter tooth period) so that no step
        # spans a seating and the release after it unseen by scipy's event detection
        return Adaptive(model, t0, x0, inputs, method=method, rtol=rtol, max_step=max_step,
                        **options)
    raise ValueError(f"unknown solver method {method!r}; choose auto or one of {', '.join(METHODS)}")


_PYTHON_LOOP_CLASSES: dict = {}


def python_loop_model(model: Model) -> Model:
    """A copy of ``model`` (its arrays shared) that offers no loop kernel
    (:meth:`Model.has_loop_kernel` False), so the fixed steppers run rk4_loop's loop as plain
    Python on its :meth:`Model.rhs` (:mod:`chainmodel.kernels.plain_loop`): the twin of the
    kernels' loop that the tests and benchmarks/reduced.py run beside it in one process. Not a
    switch: the model it is given and every other model keep their kernels' loop."""
    import copy
    cls = type(model)
    sub = _PYTHON_LOOP_CLASSES.get(cls)
    if sub is None:
        sub = _PYTHON_LOOP_CLASSES[cls] = type(
            f"{cls.__name__}OnPythonLoop", (cls,),
            {"has_loop_kernel": lambda self, method: False, "__module__": cls.__module__})
    twin = copy.copy(model)
    twin.__class__ = sub
    return twin
