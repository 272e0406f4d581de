"""Steppers: advance any :class:`~chainmodel.models.base.Model` over communication steps.

One small interface in the spirit of ``scipy.integrate.OdeSolver``: build a stepper for a model,
call :meth:`Stepper.advance` with the end time and the inputs, read outputs; swap the method and
nothing else changes. Inputs are either an :class:`Inputs` held first-order over the step (the FMU
case) or a callable ``t -> Inputs`` (an analytic scene profile).

Methods
-------
``rk4``     classic fixed-step Runge-Kutta, 4 evaluations a step, stable for h w_max < 2.78.
``verlet``  fixed-step velocity Verlet for second-order models (state [q, v]): one evaluation a
            step, stable for h w_max < 2; velocity-dependent forces use the half-step velocity.
``rk45``, ``dop853``   adaptive explicit (scipy ``solve_ivp``).
``radau``, ``bdf``     adaptive implicit, with the model's Jacobian sparsity pattern.
``lsoda``   adaptive, switches between stiff and non-stiff.

Fixed steps default to 90 % of the stable limit the model reports (:meth:`Model.stable_step`);
a larger requested step is refused with the limit in the message. Every stepper stops on the
model's switching functions (a span going slack...): the fixed-step methods locate the first
sign change in a step on its dense output and step across it (:meth:`FixedStepper._cross`),
the adaptive ones use scipy events, so kinks are resolved rather than smeared. Every stepper
checks the state after each communication step: a diverging integration raises
:class:`SimulationDiverged`, it never returns NaN.
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

__all__ = ["Stepper", "FixedStepper", "RK4", "Verlet", "Adaptive", "StepperState", "METHODS",
           "make_stepper", "SimulationDiverged", "stability_limit"]

InputSource = Union[Inputs, Callable[[float], Inputs]]


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
        #: times at which the last (up to 1000) switching events were located
        self.event_log: deque = deque(maxlen=1000)

    # --- public -----------------------------------------------------------------------------
    def advance(self, t_end: float, inputs: InputSource | None = None) -> dict[str, float]:
        """Integrate from the current time to ``t_end`` and return the outputs there.

        ``inputs``: an Inputs held over the step (angle advancing at the held speed), or a
        callable giving the inputs at any time; None keeps the last held inputs."""
        if not math.isfinite(t_end) or t_end < self.t - 1e-12 * max(1.0, abs(self.t)):
            raise ValueError(f"communication point t_end = {t_end!r} s is before the current "
                             f"time {self.t!r} s")
        source = self._source(inputs)
        u = source(t_end)       # the model's input bounds (Model.input_error); a held input's
        why = self.model.input_error(u.angle, u.speed, u.torque)   # speed and load are the
        if why is not None:                                        # start's, its angle is last
            raise ValueError(f"step to t = {t_end:.9g} s refused: {why}")
        wall = time.perf_counter()
        if self.model.n_states and t_end > self.t:
            self._integrate(self.t, t_end, source)
            self.model.check(t_end, self.x)
        self.t = float(t_end)
        u = source(self.t)
        self.inputs = u
        self.stats["wall_time"] += time.perf_counter() - wall
        out = self.model.outputs(self.t, self.x, u)
        bad = [k for k, v in out.items() if not math.isfinite(v)]
        if bad:
            raise SimulationDiverged(f"{self.model.name} model produced non-finite outputs "
                                     f"{', '.join(bad[:5])} at t = {self.t:.6g} s")
        return out

    def advance_batch(self, times, angle, speed, acceleration, torque) -> np.ndarray | None:
        """Integrate through the communication points ``times`` (``times[0]`` the current time)
        in one call, the inputs given there as arrays (the source's values: angle, speed,
        acceleration, torque); the states at every point, as ``advance`` would leave them one
        point at a time, or None when this stepper and model have no such path (then call
        ``advance`` per point). Raises SimulationDiverged as ``advance`` does; outputs are the
        caller's (e.g. the model's vectorised ``outputs_many``)."""
        return None

    def outputs(self) -> dict[str, float]:
        """Outputs at the current time and inputs."""
        return self.model.outputs(self.t, self.x, self.inputs)

    def get_state(self) -> StepperState:
        return StepperState(self.t, self.x.copy(), self._h_state(), self.inputs)

    def set_state(self, state: StepperState) -> None:
        x = np.array(state.x, float)
        if x.shape != self.x.shape:
            raise ValueError(f"state has {x.shape[0]} entries, the {self.model.name} model needs "
                             f"{self.x.shape[0]}")
        self.t, self.x, self.inputs = float(state.t), x, state.inputs
        self._restore_h(state.h)

    # --- internals --------------------------------------------------------------------------
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

#: event crossing of the fixed-step methods (FixedStepper._cross; the compiled loop of levels 1-2
#: uses the same values, models/spans.py): root tolerance on a dense output, and the gap eta
#: between the steps on either side of an event, both relative to the step
EVENT_TOL = 1e-5
EVENT_GAP = 1e-4


def _changed(g, g0) -> bool:
    """Has any switching function changed sign (both values nonzero)?"""
    return bool(np.any((g * g0 < 0) & (g != 0) & (g0 != 0)))


def _dense(x0, f0, x1, f1, H, s):
    """Dense output at s of a step from (x0, f0) at 0 to (x1, f1) at H: the cubic Hermite
    interpolant (an extrapolation for s > H); for H = 0 the line x0 + s f0."""
    if H == 0.0:
        return x0 + s * f0
    th = s / H
    th2 = th * th
    th3 = th2 * th
    a = 2.0 * th3 - 3.0 * th2 + 1.0
    return a * x0 + ((th3 - 2.0 * th2 + th) * H) * f0 + (1.0 - a) * x1 + ((th3 - th2) * H) * f1


def _secant(lo, hi, g_lo, g_hi, g0) -> float:
    """Earliest secant root in [lo, hi] among the functions changed between g0 and g_hi."""
    changed = (g_hi * g0 < 0) & (g_hi != 0) & (g0 != 0)
    with np.errstate(divide="ignore", invalid="ignore"):
        roots = lo + (hi - lo) * g_lo[changed] / (g_lo[changed] - g_hi[changed])
    roots = roots[np.isfinite(roots)]
    if not roots.size:
        return 0.5 * (lo + hi)
    return min(max(float(np.min(roots)), lo), hi)


def stability_limit(method: str) -> float:
    """Stability interval on the imaginary axis, h * omega_max, of a fixed-step method."""
    return {"rk4": 2.0 * math.sqrt(2.0), "verlet": 2.0}[method]


class FixedStepper(Stepper):
    """Common part of the fixed-step methods: step choice and event crossing."""

    safety: ClassVar[float] = 0.9

    def __init__(self, model: Model, t0=0.0, x0=None, inputs=None, step: float = 0.0,
                 max_step: float = math.inf):
        super().__init__(model, t0, x0, inputs)
        limit = stability_limit(self.method) * model.stable_step(self.x)
        if step and step > 0:
            if step > limit:
                f_max = 1.0 / (2 * math.pi * model.stable_step(self.x))
                raise ValueError(
                    f"solver.step = {step:.6g} s is above the stable limit {limit:.6g} s of the "
                    f"{self.method} stepper for this {model.name} model (highest natural "
                    f"frequency {f_max:.6g} Hz); use a step <= {limit:.6g} s or 0 for automatic")
            self.h = float(step)
        else:
            if not math.isfinite(limit):
                raise ValueError(f"the {model.name} model reports no stability limit; give "
                                 f"solver.step explicitly for the {self.method} stepper")
            # max_step: a bound from outside stability, e.g. one event per step
            self.h = min(self.safety * limit, float(max_step))
        self.stable_limit = limit

    #: let a model that offers ``advance_compiled`` (a compiled loop of this method over the
    #: communication step, e.g. levels 1-2 with numba) do the stepping; False forces Python
    compiled: bool = True

    def _integrate(self, t0, t1, source):
        fast = getattr(self.model, "advance_compiled", None) if self.compiled else None
        if fast is not None:
            res = fast(self.method, t0, t1, self.x, self.h, source)
            if res is not None:
                x, steps, events, evals, times = res
                self.stats["steps"] += steps
                self.stats["events"] += events
                self.stats["rhs_evaluations"] += evals
                self.event_log.extend(times)
                self.x = x
                if not np.all(np.isfinite(x)):
                    self.model.check(t1, x)
                return
        n = max(1, math.ceil((t1 - t0) / self.h - 1e-9))
        h = (t1 - t0) / n
        switch = self.model.switching_functions
        t, x = t0, self.x
        g0 = switch(t, x, source(t))
        for _ in range(n):
            x_new = self._step(t, x, h, source)
            g1 = switch(t + h, x_new, source(t + h)) if g0.size else g0
            if g0.size and _changed(g1, g0):
                x_new = self._cross(t, x, h, x_new, g0, g1, source)
                self.stats["events"] += 1
                g1 = switch(t + h, x_new, source(t + h))
            t, x, g0 = t + h, x_new, g1
            self.stats["steps"] += 1
            if not np.all(np.isfinite(x)):
                self.x = x
                self.model.check(t, x)
        self.x = x

    def advance_batch(self, times, angle, speed, acceleration, torque):
        fast = getattr(self.model, "advance_compiled_many", None) if self.compiled else None
        times = np.asarray(times, float)
        if fast is None or times.size < 2 or self.model.n_states == 0:
            return None
        if abs(times[0] - self.t) > 1e-12 * max(1.0, abs(self.t)) or np.any(np.diff(times) <= 0):
            raise ValueError("advance_batch needs increasing times starting at the current "
                             f"time {self.t!r} s")
        wall = time.perf_counter()
        res = fast(self.method, times, self.x, self.h, angle, speed, acceleration, torque)
        if res is None:
            return None
        states, reached, steps, events, evals, log = res
        self.stats["steps"] += steps
        self.stats["events"] += events
        self.stats["rhs_evaluations"] += evals
        self.event_log.extend(log)
        self.model.check_states(times[1:reached + 1], states[1:reached + 1])
        if reached < times.size - 1:  # pragma: no cover - check_states raises first
            raise SimulationDiverged(f"{self.model.name} model diverged at "
                                     f"t = {times[reached]:.6g} s (non-finite state)")
        self.t = float(times[-1])
        self.x = states[-1].copy()
        self.inputs = Inputs(float(angle[-1]), float(speed[-1]), float(torque[-1]),
                             float(acceleration[-1]))
        self.stats["wall_time"] += time.perf_counter() - wall
        return states

    def _cross(self, t, x, h, x1, g0, g1, source):
        """The state at t + h when a switching function changes sign over the step [t, t + h]
        (x1 the plain step's end state, g0 and g1 the functions at both ends), the step redone
        across the first change:

        1. a first estimate s of the change on the step's cubic Hermite dense output;
        2. one step to sa = s - eta (eta = EVENT_GAP h), whose state must lie on the old side
           of every function (else s is searched again on the dense output of [t, t + sa]);
        3. s located again on the dense output of the old side alone, (x, f) at t and at
           t + sa extrapolated past sa - the plain step's end state straddled the kink, this
           does not; if s ends up more than 4 eta past sa, back to 2;
        4. across the change to sb = s + eta by the two one-sided slopes (the old side's f over
           [sa, s], the new side's over [s, sb]), sb widened until its state is on the new side;
        5. one step from sb to t + h.

        No stage of the method straddles the kink (an error of order jump * h / 6, first order
        in h), and the crossing errs by order eta^2 f' + jump * (error of s). The compiled loop
        of levels 1-2 (models/spans.py, _cross) does the same."""
        switch = self.model.switching_functions
        rhs = self.model.rhs

        def g(tt, xx):
            return np.asarray(switch(tt, xx, source(tt)), float)

        def f(tt, xx):
            self.stats["rhs_evaluations"] += 1
            return rhs(tt, xx, source(tt))

        g0 = np.asarray(g0, float)
        f0 = f(t, x)
        tol, eta = EVENT_TOL * h, EVENT_GAP * h
        s = self._locate(t, (x, f0, x1, f(t + h, x1), h), 0.0, h, g0, np.asarray(g1, float),
                         g0, tol, source)
        sa, xa, fa, ga = 0.0, x, f0, g0
        for _pass in range(8):
            for _it in range(20):                    # 2. to sa, on the old side
                sa = s - eta
                if sa <= 0.0:
                    sa = 0.0
                    break
                xa = self._step(t, x, sa, source)
                fa, ga = f(t + sa, xa), g(t + sa, xa)
                if not _changed(ga, g0):
                    break
                s = self._locate(t, (x, f0, xa, fa, sa), 0.0, sa, g0, ga, g0, tol, source)
            if sa == 0.0:
                xa, fa, ga = x, f0, g0
            sb = min(s + eta, h)                     # 3. on the old side's dense output
            while True:
                gb = g(t + sb, _dense(x, f0, xa, fa, sa, sb))
                if _changed(gb, g0) or sb >= h:
                    break
                sb = min(sa + 2.0 * (sb - sa), h)
            if not _changed(gb, g0):
                break
            if sb - sa <= 4.0 * eta:
                s = _secant(sa, sb, ga, gb, g0)
            else:
                s = self._locate(t, (x, f0, xa, fa, sa), sa, sb, ga, gb, g0, tol, source)
            if s - sa <= 4.0 * eta:
                break
        s = max(s, sa)                               # 4. across by the one-sided slopes
        self.event_log.append(t + s)
        eta_b = eta
        while True:
            sb = min(s + eta_b, h)
            fq = f(t + sb, xa + (sb - sa) * fa)
            xb = xa + (s - sa) * fa + (sb - s) * fq
            if _changed(g(t + sb, xb), g0) or sb >= h:
                break
            eta_b *= 8.0
        return self._step(t + sb, xb, h - sb, source) if sb < h else xb   # 5. the rest

    def _locate(self, t, dense, lo, hi, g_lo, g_hi, g0, tol, source):
        """Earliest sign change (relative to g0) of the switching functions in [lo, hi] on the
        dense output ``_dense(*dense)``, g_lo and g_hi the functions at the ends; returns the
        secant root in the final bracket (width ``tol``).

        Safeguarded regula falsi (Illinois variant): the trial point is the earliest secant
        root among the functions that change sign in the bracket, and an end kept twice in a
        row has its values halved, so both ends converge; a trial outside the bracket falls
        back to bisection. Each trial costs one evaluation of the switching functions on the
        dense output, not a step of the method."""
        switch = self.model.switching_functions
        g_lo, g_hi = np.asarray(g_lo, float), np.asarray(g_hi, float)
        f_lo, f_hi = g_lo.copy(), g_hi.copy()
        side = 0
        for _ in range(100):
            if hi - lo <= tol:
                break
            changed = (g_hi * g0 < 0) & (g_hi != 0) & (g0 != 0)
            with np.errstate(divide="ignore", invalid="ignore"):
                roots = lo + (hi - lo) * f_lo[changed] / (f_lo[changed] - f_hi[changed])
            roots = roots[np.isfinite(roots)]
            mid = float(np.min(roots)) if roots.size else math.nan
            margin = 1e-3 * (hi - lo)
            if not (lo + margin <= mid <= hi - margin):
                mid = min(max(mid, lo + margin), hi - margin) if math.isfinite(mid) else 0.5 * (lo + hi)
            g_mid = np.asarray(switch(t + mid, _dense(*dense[:4], dense[4], mid),
                                      source(t + mid)), float)
            if _changed(g_mid, g0):
                hi, g_hi, f_hi = mid, g_mid, g_mid.copy()
                if side == -1:
                    f_lo = 0.5 * f_lo
                side = -1
            else:
                lo, g_lo, f_lo = mid, g_mid, g_mid.copy()
                if side == 1:
                    f_hi = 0.5 * f_hi
                side = 1
        return _secant(lo, hi, g_lo, g_hi, g0)

    @abstractmethod
    def _step(self, t, x, h, source) -> np.ndarray:
        ...

    def _h_state(self) -> float:
        return self.h


class RK4(FixedStepper):
    method = "rk4"

    def _step(self, t, x, h, source):
        k1 = self._rhs(t, x, source)
        k2 = self._rhs(t + h / 2, x + h / 2 * k1, source)
        k3 = self._rhs(t + h / 2, x + h / 2 * k2, source)
        k4 = self._rhs(t + h, x + h * k3, source)
        return x + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)


class Verlet(FixedStepper):
    """Velocity Verlet (kick-drift-kick) for models with state [q, v]."""

    method = "verlet"

    def __init__(self, model: Model, *args, **kwargs):
        if not model.second_order:
            raise ValueError(f"the verlet stepper needs a second-order model (state [q, v]); "
                             f"the {model.name} model is not; use rk4 or an adaptive method")
        super().__init__(model, *args, **kwargs)

    def _step(self, t, x, h, source):
        n = x.size // 2
        q, v = x[:n], x[n:]
        a0 = self._rhs(t, x, source)[n:]
        v_half = v + 0.5 * h * a0
        q1 = q + h * v_half
        a1 = self._rhs(t + h, np.concatenate([q1, v_half]), source)[n:]
        return np.concatenate([q1, v_half + 0.5 * h * a1])


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
        scale = getattr(self.model, "state_scale", None)
        scale = scale() if callable(scale) else None
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
                names = getattr(model, "switching_names", None)
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
                 **options) -> Stepper:
    """A stepper for ``model``. ``method="auto"`` lets the model choose
    (its ``preferred_method`` attribute; rk45 otherwise). ``max_step`` bounds the automatic
    step of the fixed-step methods (an explicit ``step`` is kept as given)."""
    if method == "auto":
        method = getattr(model, "preferred_method", "rk45")
    refuse = getattr(model, "refuse_method", None)
    reason = refuse(method) if refuse is not None else None
    if reason:
        raise ValueError(reason)
    if method == "rk4":
        return RK4(model, t0, x0, inputs, step=step, max_step=max_step)
    if method == "verlet":
        return Verlet(model, t0, x0, inputs, step=step, max_step=max_step)
    if method in Adaptive.SCIPY:
        # max_step: a bound on the step (a scene's quarter tooth period) so that no step
        # spans a seating and the release after it unseen by scipy's event detection
        return Adaptive(model, t0, x0, inputs, method=method, rtol=rtol, max_step=max_step,
                        **options)
    raise ValueError(f"unknown solver method {method!r}; choose auto or one of {', '.join(METHODS)}")
