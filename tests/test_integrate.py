"""Steppers against closed-form solutions of small models that implement the model interface.

Every expected value here is an exact solution of the toy model (harmonic motion, piecewise
harmonic motion across a kink, an integral of a held input), independent of the code under test.
"""

import math

import numpy as np
import pytest

from chainmodel.geometry import Drive
from chainmodel.integrate import (RK4, Adaptive, Verlet, accuracy_step, make_stepper,
                                  stability_limit)
from chainmodel.models.base import Inputs, Model, SimulationDiverged
from chainmodel.parameters import defaults

DRIVE = Drive(12, 18, 0.0254, 11, 0.43, links=40)


class Oscillator(Model):
    """x'' = -w^2 x, or with a one-sided spring: -w1^2 x for x > 0, -w2^2 x for x < 0."""

    level = 99
    name = "oscillator"
    second_order = True

    def __init__(self, w1=2 * math.pi, w2=None, events=True):
        super().__init__(DRIVE, defaults())
        self.w1, self.w2, self.events = w1, (w1 if w2 is None else w2), events

    @property
    def state_names(self):
        return ("x", "v")

    def initial_state(self, u):
        return np.array([0.0, 1.0])

    def rhs(self, t, x, u):
        w = self.w1 if x[0] > 0 else self.w2
        return np.array([x[1], -w * w * x[0]])

    def outputs(self, t, x, u):
        return {"x": float(x[0]), "v": float(x[1])}

    def switching_functions(self, t, x, u):
        return np.array([x[0]]) if self.events and self.w1 != self.w2 else np.empty(0)

    def stable_step(self, x):
        return 1.0 / max(self.w1, self.w2)


class HeldInput(Model):
    """x' = input_shaft.angle: with a first-order hold the exact result is a0 h + s h^2 / 2."""

    level = 98
    name = "held"

    def __init__(self):
        super().__init__(DRIVE, defaults())

    @property
    def state_names(self):
        return ("x",)

    def initial_state(self, u):
        return np.zeros(1)

    def rhs(self, t, x, u):
        return np.array([u.angle])

    def outputs(self, t, x, u):
        return {"x": float(x[0])}

    def stable_step(self, x):
        return 1.0


class Blowup(Oscillator):
    """x' = x^2 from x(0) = 1 leaves every bound before t = 1."""

    second_order = False

    @property
    def state_names(self):
        return ("x",)

    def initial_state(self, u):
        return np.ones(1)

    def rhs(self, t, x, u):
        with np.errstate(over="ignore"):
            return x * x

    def outputs(self, t, x, u):
        return {"x": float(x[0])}

    def stable_step(self, x):
        return 1e-3


def run(stepper, t_end, n=10):
    for t in np.linspace(0, t_end, n + 1)[1:]:
        out = stepper.advance(float(t))
    return out


@pytest.mark.parametrize("cls,order", [(RK4, 4), (Verlet, 2)])
def test_fixed_step_order_of_accuracy(cls, order):
    """Halving the step divides the error by 2^order (harmonic oscillator, one period)."""
    errors = []
    for h in (2e-3, 1e-3):
        s = cls(Oscillator(), step=h)
        out = run(s, 1.0)
        errors.append(math.hypot(out["x"] - 0.0, out["v"] - 1.0))
    ratio = errors[0] / errors[1]
    assert ratio == pytest.approx(2**order, rel=0.2)


def test_adaptive_matches_exact_solution():
    s = Adaptive(Oscillator(), method="dop853", rtol=1e-10, atol=1e-12)
    out = run(s, 0.3)
    w = 2 * math.pi
    assert out["x"] == pytest.approx(math.sin(w * 0.3) / w, abs=1e-9)
    assert out["v"] == pytest.approx(math.cos(w * 0.3), abs=1e-9)


def test_verlet_bounded_energy_over_many_periods():
    s = Verlet(Oscillator(), step=0.01)
    w = 2 * math.pi
    e = []
    for t in np.arange(1, 201) * 0.5:
        out = s.advance(float(t))
        e.append(0.5 * out["v"] ** 2 + 0.5 * w * w * out["x"] ** 2)
    # symplectic: the energy error stays bounded (no drift) at O((h w)^2)
    assert max(abs(np.array(e) - 0.5)) < 0.5 * (0.01 * w) ** 2


@pytest.mark.parametrize("make", [lambda m: RK4(m, step=2e-3),
                                  lambda m: Adaptive(m, method="rk45", rtol=1e-9, atol=1e-12)])
def test_switching_function_resolves_the_kink(make):
    """One-sided spring: after a positive half-period pi/w1 and a negative one pi/w2 the state
    returns exactly to (0, 1). Stopping on the switch keeps the full order of the method."""
    w1, w2 = 2 * math.pi, 6 * math.pi
    period = math.pi / w1 + math.pi / w2
    with_events = make(Oscillator(w1, w2, events=True))
    out = run(with_events, period, n=7)
    err_events = math.hypot(out["x"], out["v"] - 1.0)
    without = make(Oscillator(w1, w2, events=False))
    out = run(without, period, n=7)
    err_plain = math.hypot(out["x"], out["v"] - 1.0)
    assert err_events < 1e-6
    assert with_events.stats["events"] >= 1  # the crossing at pi/w1 (the other is the end point)
    assert err_events < err_plain


class ForceJump(Oscillator):
    """x'' = -w^2 x - a sign(x): a restoring force that jumps by 2a where x changes sign. From
    x = 0, v = 1 the positive half is x = -a/w^2 + (a/w^2) cos(w t) + sin(w t)/w, back at 0 with
    v = -1 after T = (2/w) atan(w/a); the negative half mirrors it (period 2T)."""

    def __init__(self, w, a):
        super().__init__(w)
        self.a = a
        self.half = 2.0 / w * math.atan(w / a)

    def exact(self, t):
        k, r = divmod(t, self.half)
        sign = 1.0 if int(k) % 2 == 0 else -1.0
        w, a = self.w1, self.a
        return sign * np.array([-a / w**2 + a / w**2 * math.cos(w * r) + math.sin(w * r) / w,
                                -a / w * math.sin(w * r) + math.cos(w * r)])

    def initial_state(self, u):
        return self.exact(0.5 * self.half)        # start inside a half-period, off the switch

    def rhs(self, t, x, u):
        return np.array([x[1], -self.w1**2 * x[0] - (self.a if x[0] > 0 else -self.a)])

    def switching_functions(self, t, x, u):
        return np.array([x[0]])


@pytest.mark.parametrize("cls", [RK4, Verlet])
def test_steps_across_a_jump_of_the_right_hand_side_keep_their_order(cls):
    """Where the force jumps (2a = 40 against w^2 |x| < 2), a step that straddles the switch
    errs by order jump * h; stepping across it (FixedStepper._cross) keeps the method's order:
    halving the step divides the error after six crossings by about 2^order, and RK4's crossing
    times are the exact ones to a small fraction of the step."""
    m = ForceJump(2 * math.pi, 20.0)
    t_end = 6.37 * m.half - 0.5 * m.half
    ref = m.exact(t_end + 0.5 * m.half)
    order = 4 if cls is RK4 else 2
    errors = []
    for h in (m.half / 7.3, m.half / 14.6):
        s = cls(m, step=h)
        out = s.advance(t_end)
        errors.append(math.hypot(out["x"] - ref[0], (out["v"] - ref[1]) / m.w1))
        assert s.stats["events"] == 6
        if cls is RK4:   # (Verlet's own second-order phase error moves its crossings more)
            crossings = (np.arange(6) + 0.5) * m.half
            assert np.max(np.abs(np.array(s.event_log) - crossings)) < 1e-4 * h
    assert errors[0] / errors[1] > 0.5 * 2**order
    if cls is RK4:
        assert errors[1] < 1e-7


def test_fixed_step_above_stable_limit_is_refused():
    w = 2 * math.pi
    limit = stability_limit("rk4") / w
    with pytest.raises(ValueError, match="stable limit"):
        RK4(Oscillator(), step=1.01 * limit)
    # automatic: the tolerance's step (accuracy_step), which here is below 90 % of the limit
    s = RK4(Oscillator(), tolerance=1e-3)
    assert s.h == pytest.approx(accuracy_step("rk4", 1e-3) / w)
    assert s.h < 0.9 * limit


@pytest.mark.parametrize("cls", [RK4, Verlet])
@pytest.mark.parametrize("tolerance", [1e-2, 1e-4])
def test_automatic_step_keeps_the_frequency_error_at_the_tolerance(cls, tolerance):
    """solver.tolerance bounds the relative frequency error of the fastest mode: on
    x'' = -w^2 x the automatic step's numerical frequency, measured from the phase after 20
    periods, is the method's exact discrete frequency (RK4: the argument of its amplification
    factor R(i hw) = 1 - (hw)^2/2 + (hw)^4/24 + i (hw - (hw)^3/6); Verlet: 2 asin(hw / 2)),
    and that errs by the tolerance."""
    w = 2 * math.pi
    s = cls(Oscillator(events=False), tolerance=tolerance)
    theta = w * s.h
    if cls is RK4:
        exact_rel = 1.0 - math.atan2(theta - theta**3 / 6, 1 - theta**2 / 2 + theta**4 / 24) / theta
    else:
        exact_rel = 1.0 - 2.0 * math.asin(theta / 2) / theta
    n = round(20 / s.h)                 # whole steps of exactly s.h
    out = s.advance(n * s.h)
    phase = math.atan2(w * out["x"], out["v"])         # exact motion: sin(w t) / w, cos(w t)
    total = w * n * s.h
    drift = (total - phase + math.pi) % (2 * math.pi) - math.pi
    measured = drift / total                           # > 0: the numerical motion lags
    assert measured == pytest.approx(exact_rel, rel=0.02)
    assert abs(measured) == pytest.approx(tolerance, rel=0.02)


def test_verlet_refuses_first_order_models():
    with pytest.raises(ValueError, match="second-order"):
        Verlet(HeldInput(), step=1e-3)


def test_first_order_hold_of_the_angle_is_exact():
    s = RK4(HeldInput(), step=0.01)
    a0, w, h = 0.3, 2.0, 0.5
    out = s.advance(h, Inputs(angle=a0, speed=w))
    assert out["x"] == pytest.approx(a0 * h + w * h * h / 2, rel=1e-12)


def test_divergence_is_reported_not_returned_as_nan():
    for s in (RK4(Blowup(), step=1e-3), Adaptive(Blowup(), method="rk45")):
        with pytest.raises(SimulationDiverged, match="t ="):
            run(s, 2.0, n=4)


def test_state_get_set_round_trip_is_exact():
    for s in (RK4(Oscillator(), step=1e-3), Adaptive(Oscillator(), method="rk45", rtol=1e-8)):
        s.advance(0.1)
        saved = s.get_state()
        first = s.advance(0.25)
        s.advance(0.4)
        s.set_state(saved)
        again = s.advance(0.25)
        assert again == first


def test_time_cannot_go_backwards():
    s = RK4(Oscillator(), step=1e-3)
    s.advance(0.1)
    with pytest.raises(ValueError, match="before the current time"):
        s.advance(0.05)


def test_make_stepper_names_valid_methods():
    with pytest.raises(ValueError, match="rk4"):
        make_stepper(Oscillator(), "euler")
    assert isinstance(make_stepper(Oscillator(), "verlet", step=1e-3), Verlet)


# --- the input hook (Model.input_error) ---------------------------------------------------------

class Picky(HeldInput):
    """Refuses input speeds above 5 rad/s, as a model with a speed limit would."""

    def input_error(self, angle, speed, torque):
        if abs(speed) > 5.0:
            return f"input input_shaft.speed = {speed:g} rad/s is above this model's 5 rad/s"
        return super().input_error(angle, speed, torque)


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_inputs_are_refused_before_the_step_naming_them(bad):
    for s in (RK4(HeldInput(), step=0.01), Adaptive(HeldInput(), method="rk45")):
        s.advance(0.1, Inputs(0.0, 1.0, 0.0))
        before = (s.t, s.x.copy())
        with pytest.raises(ValueError, match="load.torque"):
            s.advance(0.2, Inputs(0.0, 1.0, bad))
        assert s.t == before[0] and np.array_equal(s.x, before[1])


def test_the_models_input_hook_is_asked_before_every_step():
    s = RK4(Picky(), step=0.01)
    s.advance(0.1, Inputs(0.0, 4.0, 0.0))
    with pytest.raises(ValueError, match="above this model's 5 rad/s"):
        s.advance(0.2, Inputs(0.0, 6.0, 0.0))
    with pytest.raises(ValueError, match="above this model's 5 rad/s"):
        s.advance(0.2, lambda t: Inputs(0.0, 60.0 * t, 0.0))        # a source, at its end
    assert s.t == 0.1
