"""chainmodel.cosim: the co-simulation session the FMU adapter maps FMI onto, the coupling
watch (issue 18 item 4) and the stable communication step of angle causality (item 3)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.linalg import expm

from chainmodel import parameters as P
from chainmodel.cosim import (GAUSS_SEIDEL_CONSTANT, JACOBI_CONSTANT, CosimSession,
                              CouplingUnstable, CouplingWatch, coupling_frequency, stable_step)
from chainmodel.integrate import make_stepper
from chainmodel.models import MODEL_CLASSES, Inputs
from chainmodel.scene import drive_from_parameters


def _inputs(k, h):
    """A ramp to 120 rpm over 0.05 s, constant load: the inputs at point k."""
    w_end, ramp = 4 * math.pi, 0.05
    t = k * h
    speed = w_end * min(t / ramp, 1.0)
    angle = 0.5 * w_end * t * t / ramp if t <= ramp else w_end * (t - 0.5 * ramp)
    return angle, speed, 20.0


@pytest.mark.parametrize("level", [0, 1])
def test_session_steps_as_the_stepper_with_backward_difference_acceleration(level):
    """The session's steps are the stepper's advance_held with the inputs held and the
    acceleration a_k = (w_k - w_(k-1)) / (t_k - t_(k-1)) computed here: bit-identical rows."""
    params = P.validate({"fidelity": level})
    h, n = 1e-4, 30
    session = CosimSession()
    session.set_inputs(*_inputs(0, h))
    session.build(params, 0.0)
    model = MODEL_CLASSES[level](drive_from_parameters(params, "ChainDrive"), params)
    a0, w0, T0 = _inputs(0, h)
    st = make_stepper(model, params["solver.method"], 0.0, Inputs(a0, w0, T0, 0.0),
                      step=params["solver.step"], rtol=params["solver.rtol"],
                      tolerance=params["solver.tolerance"])
    prev_w = None
    for k in range(n):
        angle, speed, torque = _inputs(k, h)
        acc = 0.0 if prev_w is None else (speed - prev_w) / (k * h - (k - 1) * h)
        session.set_inputs(angle, speed, torque)
        got = session.step(k * h, h).copy()
        want = st.advance_held(k * h + h, angle, speed, acc, torque).copy()   # as fmi2DoStep
        np.testing.assert_array_equal(got, want)
        prev_w = speed


def test_session_state_round_trip_repeats_a_step_exactly():
    params = P.validate({"fidelity": 1})
    h = 1e-4
    session = CosimSession()
    session.set_inputs(*_inputs(0, h))
    session.build(params, 0.0)
    for k in range(5):
        session.set_inputs(*_inputs(k, h))
        session.step(k * h, h)
    saved = session.get_state()
    session.set_inputs(*_inputs(5, h))
    first = session.step(5 * h, h).copy()
    session.step(6 * h, h)
    session.restore(saved, None)
    session.set_inputs(*_inputs(5, h))
    np.testing.assert_array_equal(session.step(5 * h, h), first)


# --- the coupling watch ---------------------------------------------------------------------

def _feed(watch, values):
    """Index of the first point at which the watch reports, or None."""
    for k, v in enumerate(values):
        if watch.update((v, 10.0)) is not None:
            return k
    return None


def test_watch_reports_a_growing_oscillation_of_a_few_steps_per_period():
    # what an unstable explicit coupling looks like: eigenvalue 1.1 exp(+-1.0 i) per step
    k = np.arange(200)
    speed = 12.0 + 1e-3 * np.cumsum(1.1 ** k * np.cos(1.0 * k))
    at = _feed(CouplingWatch(), speed)
    assert at is not None
    # reported while the oscillation is still small: well before the amplitude reaches 1 rad/s
    assert 1e-3 * 1.1 ** at < 1.0


def test_watch_reports_the_level_0_feedthrough_alternation():
    # level 0: dw_k = -(I_eff / J) dw_(k-1), I_eff / J = 2 (a too-light rotor)
    d = 1e-3 * (-2.0) ** np.arange(20)
    assert _feed(CouplingWatch(), 5.0 + np.cumsum(d)) is not None


@pytest.mark.parametrize("case", ["decaying", "slow controller", "ramp", "constant"])
def test_watch_keeps_quiet_on_stable_inputs(case):
    k = np.arange(3000)
    if case == "decaying":       # a stable coupling's transient: eigenvalue 0.97 exp(+-1 i)
        speed = 12.0 + np.cumsum(0.5 * 0.97 ** k * np.cos(k))
    elif case == "slow controller":   # a growing but slow (200 steps per period) oscillation
        speed = 12.0 + 0.1 * 1.002 ** k * np.sin(2 * np.pi * k / 200)
    elif case == "ramp":
        speed = np.minimum(k * 0.025, 12.566)
    else:
        speed = np.full(len(k), 12.566)
    assert _feed(CouplingWatch(), speed) is None


# --- the stable step of angle causality -------------------------------------------------------

def test_coupling_frequency_is_the_two_inertia_spring_mode():
    k, J, I = 12000.0, 0.01, 4.0108e-3
    w = coupling_frequency(J, I, k)
    # the spring between two free inertias: omega^2 = k (J + I) / (J I)
    assert w == pytest.approx(math.sqrt(k * (J + I) / (J * I)), rel=1e-14)
    with pytest.raises(ValueError, match="motor inertia"):
        coupling_frequency(0.0, I, k)


def test_stable_step_is_infinite_without_the_spring_and_refuses_bad_schemes():
    assert stable_step(0.01, P.validate({"fidelity": 0})) == math.inf
    assert stable_step(0.01, P.validate({"fidelity": 1, "input_shaft.rigid": True})) == math.inf
    with pytest.raises(ValueError, match="scheme"):
        stable_step(0.01, P.validate({"fidelity": 1}), "implicit")


def _jacobi_map(h, J, I, k, c, scheme):
    """The linear map of one communication step of a rotor J (fed the held spring torque,
    integrated exactly at constant torque) and the driver I on the spring k, c to an anchor that
    starts at the rotor's angle and advances at its held speed (integrated exactly). State:
    rotor angle and speed, driver angle and speed, anchor angle and speed at the end of the
    drive's last step (the torque the master reads is computed from those)."""
    A = np.array([[0, 1, 0, 0], [-k / I, -c / I, k / I, c / I], [0, 0, 0, 1], [0, 0, 0, 0.]])
    E = expm(A * h)
    drive = np.zeros((4, 6))
    drive[:, [2, 3, 0, 1]] = E          # [driver, anchor] after the step from [driver, rotor]
    torque_now = np.array([0, 0, -k, -c, k, c], float)
    torque_new = k * (drive[2] - drive[0]) + c * (drive[3] - drive[1])
    T = torque_now if scheme == "jacobi" else torque_new
    M = np.zeros((6, 6))
    M[0] = np.eye(6)[0] + h * np.eye(6)[1] - h * h / (2 * J) * T
    M[1] = np.eye(6)[1] - h / J * T
    M[2:] = drive
    ev = np.linalg.eigvals(M)
    return max(abs(ev[abs(ev - 1) > 1e-6]))   # the rigid-body motion (eigenvalue 1) is neutral


@pytest.mark.parametrize("scheme", ["jacobi", "gauss-seidel"])
@pytest.mark.parametrize("J", [0.001, 0.003, 0.01])
def test_the_stable_step_holds_and_twice_it_does_not(scheme, J):
    """C / omega_c is inside the stable region of the linear coupling for the default shaft and
    driver, and twice it is outside (so the constant is not needlessly small)."""
    params = P.validate({"fidelity": 1})
    k, c, I = params["input_shaft.stiffness"], params["input_shaft.damping"], \
        params["driver.inertia"]
    h = stable_step(J, params, scheme)
    assert _jacobi_map(h, J, I, k, c, scheme) < 1.0
    assert _jacobi_map(2 * h, J, I, k, c, scheme) > 1.0
    assert h * coupling_frequency(J, I, k) == pytest.approx(
        JACOBI_CONSTANT if scheme == "jacobi" else GAUSS_SEIDEL_CONSTANT)


def test_session_refuses_a_step_when_the_speed_input_oscillates_and_grows():
    params = P.validate({"fidelity": 1})
    session = CosimSession()
    session.motor_inertia = 0.01
    session.set_inputs(0.0, 0.0, 0.0)
    session.build(params, 0.0)
    h, angle = 5e-4, 0.0
    speeds = 1e-2 * np.cumsum(1.2 ** np.arange(60) * np.cos(1.0 * np.arange(60)))
    with pytest.raises(CouplingUnstable) as err:
        for k, w in enumerate(speeds):
            session.set_inputs(angle, float(w), 0.0)
            session.step(k * h, h)
            angle += h * w
    text = str(err.value)
    assert "coupling unstable" in text and "input_shaft.speed" in text
    assert f"{stable_step(0.01, params):.3g} s for J = 0.01 kg.m2" in text
    assert "torque causality" in text and "Step discarded" in text
    t_failed = session.t
    session.set_inputs(angle, 0.0, 0.0)   # the session stayed at the last point
    assert session.t == t_failed


def _motor_on_session(h, c, steps, J=0.01):
    """A motor model T = T0 - c omega fed the rotor speed the session returns (torque causality,
    Jacobi), at xu2010's load; returns the session and the torques it was fed."""
    params = P.validate({"fidelity": 1, "input_shaft.causality": "torque",
                         "motor.inertia": J})
    session = CosimSession()
    load, w_set = 43.2, 12.0
    t0 = load * 25 / 17 + c * w_set          # the torque that holds w_set at this load
    session.set_inputs(0.0, 0.0, load, 0.0)
    session.build(params, 0.0)
    fed = []
    for k in range(steps):
        w = session.motor_values()[1]
        fed.append(t0 - c * w)
        session.set_inputs(0.0, 0.0, load, fed[-1])
        session.step(k * h, h)
    return session, fed


def test_a_motor_torque_fed_back_from_the_rotor_speed_is_watched_in_torque_causality():
    """Torque causality: the rotor J = motor.inertia is integrated inside the session at the
    held motor.torque, and a motor model whose torque falls with the speed it is fed (slope
    -c) closes an explicit loop, omega_k+1 = omega_k + h / J (T0 - c omega_k), stable for
    h < 2 J / c (the shaft's driver inertia behind the spring only adds to J at long steps).
    Past it the session refuses the step naming motor.torque and that bound with the slope
    it read off the inputs; well inside it the same motor runs to its set point."""
    c, J = 26.7, 0.01
    bound = 2 * J / c                          # 7.5e-4 s
    with pytest.raises(CouplingUnstable) as err:
        _motor_on_session(4 * bound, c, 200, J)
    text = str(err.value)
    assert "input motor.torque" in text and "2 J / |dT/domega|" in text
    slope = float(text.split("dT/domega = ")[1].split(" ")[0])
    assert slope == pytest.approx(-c, rel=1e-3)          # read off the inputs, the motor's own
    assert f"h < {2 * J / c:.3g} s" in text
    session, fed = _motor_on_session(0.25 * bound, c, 400, J)
    assert session.motor_values()[1] == pytest.approx(12.0, rel=0.05)   # at its set point
    assert max(abs(np.diff(fed[-50:]))) < 1.0            # and not oscillating


@pytest.mark.parametrize("level,rigid", [(0, False), (1, True), (1, False)])
def test_without_drive_inertia_the_torque_ignores_the_acceleration_estimate(level, rigid):
    """input_shaft.include_drive_inertia = false: input_shaft.torque is the same whatever the
    backward-difference acceleration (here changed through the speed at the last point), every other
    output unchanged; with it, the torque changes linearly in that acceleration (level 0 and the
    rigid shaft; at level 1 with the spring it does not enter the torque at all)."""
    from chainmodel.outputs import O_INPUT_SHAFT_TORQUE
    params = P.validate({"fidelity": level, "input_shaft.rigid": rigid})
    rows = {}
    for include in (True, False):
        s = CosimSession()
        s.include_drive_inertia = include
        s.set_inputs(0.1, 1.0, 10.0)
        s.build(params, 0.0)
        s.step(0.0, 1e-3)
        s.set_inputs(0.1 + 1e-3, 1.0, 10.0)
        for prev in (0.9, 0.95, 1.0):   # the speed at the last point: only the estimate moves
            s.prev_speed = prev
            rows[include, prev] = s.outputs().copy()
    T = O_INPUT_SHAFT_TORQUE
    others = [k for k in range(len(rows[True, 1.0])) if k != T]
    for prev in (0.9, 0.95):
        assert rows[False, prev][T] == rows[False, 1.0][T]
        np.testing.assert_array_equal(rows[False, prev][others], rows[True, prev][others])
    # acceleration estimates 100, 50, 0 rad/s2: equal steps of the torque with the inertia
    d1 = rows[True, 0.9][T] - rows[True, 0.95][T]
    d2 = rows[True, 0.95][T] - rows[True, 1.0][T]
    if level == 0 or rigid:
        assert d1 > 0 and d1 == pytest.approx(d2, rel=1e-6)
        assert rows[False, 1.0][T] == pytest.approx(rows[True, 1.0][T], rel=1e-12)  # a = 0
    else:
        assert d1 == 0 and d2 == 0


def test_a_step_failing_during_a_fast_growing_oscillation_blames_the_coupling():
    """Far past the stable step the speed input alternates and grows so fast (6 times a step)
    that level 1's speed limit (236 rad/s) refuses a step before four whole cycles are seen:
    the message is the coupling's, quoting the refusal without its advice."""
    params = P.validate({"fidelity": 1})
    session = CosimSession()
    session.set_inputs(0.0, 1.0, 0.0)
    session.build(params, 0.0)
    h, angle, speed = 1e-3, 0.0, 1.0
    with pytest.raises(CouplingUnstable) as err:
        for k in range(12):
            session.set_inputs(angle, speed, 0.0)
            session.step(k * h, h)
            angle += h * speed
            speed += 0.01 * (-6.0) ** k
    text = str(err.value)
    assert "coupling unstable" in text and "The step itself failed" in text
    assert "lower speed" not in text and "fidelity 3" not in text


# --- the angle input: restarts of its count and jumps its speed does not explain ----------------

def _run_session(level, angles, h=1e-4, w=4 * math.pi, torque=20.0):
    """Step a session at constant speed ``w`` with the angle input ``angles[k]`` at point k;
    the rows after each step."""
    session = CosimSession()
    session.set_inputs(angles[0], w, torque)
    session.build(P.validate({"fidelity": level}), 0.0)
    rows = []
    for k, a in enumerate(angles):
        session.set_inputs(a, w, torque)
        rows.append(session.step(k * h, h).copy())
    return session, np.array(rows)


@pytest.mark.parametrize("level", [0, 1])
def test_a_restart_of_the_angle_count_by_whole_turns_is_the_same_motion(level):
    """A master wrapping its rotor angle (-1 turn at point 10, -2 at point 20, as a counter kept
    within one turn does): the same motion as the continuous angle, so the same outputs."""
    h, w, n = 1e-4, 4 * math.pi, 30
    angles = w * h * np.arange(n)
    wrapped = angles - 2 * math.pi * (np.arange(n) >= 10) - 2 * math.pi * (np.arange(n) >= 20)
    _, want = _run_session(level, angles, h, w)
    session, got = _run_session(level, wrapped, h, w)
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-6)
    assert session.turns_removed == -2


def test_an_angle_jump_its_speed_does_not_explain_is_refused_naming_the_input():
    """Half a driver tooth (pi / 25 = 0.126 rad on xu2010) is the tolerance at constant speed:
    0.05 rad off passes (a master's hold error), 0.3 rad is refused, the session stays at its
    point and goes on with a consistent angle."""
    h, w = 1e-4, 4 * math.pi
    session, _ = _run_session(1, w * h * np.arange(5), h, w)
    t, held = session.t, session.stepper.inputs.angle
    session.set_inputs(held + 0.3, w, 20.0)
    with pytest.raises(ValueError) as err:
        session.step(t, h)
    text = str(err.value)
    assert "input_shaft.angle" in text and "+0.3 rad" in text and "0.126 rad" in text
    assert session.t == t
    session.set_inputs(held + 0.05, w, 20.0)
    row = session.step(t, h)
    assert np.all(np.isfinite(row)) and session.turns_removed == 0
    assert session.jump_noted == (pytest.approx(0.05), t)    # followed, and noted for a warning


def _accelerating(h, a=251.3, steps=None, level=1):
    """A master feeding the exact angle of a constant acceleration a from rest (the angle the
    integral of its speed) at communication step h, for 0.04 s."""
    session = CosimSession()
    session.set_inputs(0.0, 0.0, 20.0)
    session.build(P.validate({"fidelity": level}), 0.0)
    for k in range(steps or int(round(0.04 / h))):
        t = k * h
        session.set_inputs(0.5 * a * t * t, a * t, 20.0)
        session.step(t, h)
    return session


def test_an_accelerating_input_at_coarse_steps_is_warned_with_what_the_hold_missed():
    """The FMU holds the speed over a step: an input accelerating at a runs a h^2 / 2 ahead of
    the held angle by the next point, which the shaft spring takes at once (0.05 s to 120 rpm
    at 10 ms steps: 150 N.m peaks, the audit of the twenty-fourth session). That miss is within
    the jump tolerance (it is not a jump), but beyond a milliradian it is warned of once, with
    the miss, the acceleration and the step that keeps it small; below it nothing is said."""
    a, h = 251.3, 5e-3
    session = _accelerating(h, a)
    assert session.jump_warning() is None                     # no jump: the speed explains it
    text = session.hold_warning()
    assert text is not None and "accelerated" in text and "input_shaft.angle" in text
    miss = float(text.split(" was ")[1].split(" rad")[0])
    assert miss == pytest.approx(0.5 * a * h * h, rel=0.01)  # a h^2 / 2, exact for constant a
    assert f"{math.sqrt(2 * 1e-3 / a):.2g} s" in text
    assert f"{12000 * 0.5 * a * h * h:.3g} N.m" in text       # k_r times the miss
    assert _accelerating(1e-3, a).hold_warning() is None      # 0.13 mrad: quiet


def test_the_angle_may_be_set_again_before_the_first_step():
    """A master that reads outputs in initialization mode (a model is built for them) and then
    sets the motor's start angle: no step has held any angle yet, so nothing is a jump."""
    session = CosimSession()
    session.set_inputs(0.0, 0.0, 20.0)
    session.build(P.validate({"fidelity": 1}), 0.0)
    session.outputs()
    session.set_inputs(1.0, 0.0, 20.0)
    session.build(P.validate({"fidelity": 1}), 0.0)           # fmi2ExitInitializationMode
    assert np.all(np.isfinite(session.outputs()))
    assert np.all(np.isfinite(session.step(0.0, 1e-4)))


def test_a_consistent_speed_step_at_a_coarse_communication_step_is_not_a_jump():
    """The first-order hold misses the angle a speed step gains within a communication step
    (here 4 pi rad/s a quarter into a 20 ms step: 0.188 rad, more than half a tooth); the
    tolerance counts the speed change times the step, so the exact integral of that speed
    passes."""
    h, w = 0.02, 4 * math.pi
    session = CosimSession()
    session.set_inputs(0.0, 0.0, 0.0)
    session.build(P.validate({"fidelity": 1}), 0.0)
    session.step(0.0, h)
    session.set_inputs(0.0, 0.0, 0.0)
    session.step(h, h)                                  # the speed jumps at 1.25 h:
    session.set_inputs(w * 0.75 * h, w, 0.0)            # its integral at 2 h, 0.188 rad,
    assert w * 0.75 * h > math.pi / 25                  # beyond half a tooth alone
    assert np.all(np.isfinite(session.step(2 * h, h)))


def test_without_the_watch_prescribed_growing_inputs_run():
    """coupling.watch = false: the inputs of the refused case above, prescribed open loop, run
    (the watch cannot tell them from a coupling's; the user can)."""
    params = P.validate({"fidelity": 1})
    h, n = 5e-4, 30
    speeds = 1e-2 * np.cumsum(1.2 ** np.arange(n) * np.cos(1.0 * np.arange(n)))
    for watch in (True, False):
        session = CosimSession()
        session.watch_coupling = watch
        session.set_inputs(0.0, 0.0, 0.0)
        session.build(params, 0.0)
        angle, refused = 0.0, False
        for k, w in enumerate(speeds):
            session.set_inputs(angle, float(w), 0.0)
            try:
                row = session.step(k * h, h)
            except CouplingUnstable:
                refused = True
                break
            assert np.all(np.isfinite(row))
            angle += h * w
        assert refused is watch

