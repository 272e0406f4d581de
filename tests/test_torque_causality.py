"""Torque causality (input_shaft.causality = torque, issue 18 item 2): a motor rotor driven by
motor.torque at the far end of the input-shaft spring, integrated with the drive.

Every expected number comes from physics computed here: the energy balance of the motor, shaft
and sprockets; an independent two-inertia integration (scipy) of rotor + driver on the shaft
spring; the limit of a very heavy rotor, which is angle causality."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

import chainmodel
from chainmodel.integrate import make_stepper
from chainmodel.models import Inputs, build_model, model_class
from chainmodel.models.torque_causality import TorqueCausalModel
from chainmodel.scene import load_scene

TORQUE = {"input_shaft.causality": "torque"}


def _scene(fidelity=1, **params):
    return load_scene("xu2010").with_overrides(fidelity=fidelity, parameters=dict(TORQUE, **params))


def _run(model, x0, u, dt, n):
    st = make_stepper(model, "rk4", 0.0, u, x0=x0)
    xs, outs = [st.x.copy()], [st.outputs()]
    for k in range(1, n + 1):
        outs.append(st.advance(k * dt, u))
        xs.append(st.x.copy())
    return np.arange(n + 1) * dt, np.array(xs), outs


def _trapezoid(y, dt):
    return float(np.sum(y[1:] + y[:-1]) * dt / 2)


def test_energy_balance_at_the_load_steady_need():
    """Constant motor torque = the load's steady need r M_load (power balance, r = z1/z2), from
    a running state: over 0.5 s, motor work = load work + shaft damper dissipation + kinetic
    energy change (rotor, sprockets) + shaft spring energy change. Without chain damping,
    chain inertia and seat compliance, what is left is the spans' elastic energy change, which
    the test bounds from the tension outputs: (T_max^2 - T_min^2) n / (2 k_link), n <= links."""
    # (no lagged sag: its relaxation dissipates, and the state is laid out by hand below)
    sc = _scene(**{"chain.link_damping": 0.0, "torsional.chain_inertia": False,
                   "torsional.seat_compliance": False, "driven.damping": 0.0,
                   "torsional.sag_lag": False})
    p, d = sc.parameters, sc.drive
    model = sc.model()
    assert isinstance(model, TorqueCausalModel)
    r = d.n_driver / d.n_driven
    w, load = sc.operating.speed, sc.operating.load_torque
    t_m = r * load
    xi = model.inner.initial_state(Inputs(0.0, 0.0, load, 0.0))
    xi[2], xi[3] = w, r * w                 # driver, driven speeds
    x0 = np.concatenate([xi[:2], [0.0], xi[2:], [w]])
    dt, n = 1e-4, 5000
    _, X, outs = _run(model, x0, Inputs(0.0, 0.0, load, 0.0, motor_torque=t_m), dt, n)
    phi1, _, th_m, w1, w2, w_m = X.T
    j1, j2, j_m = p["driver.inertia"], p["driven.inertia"], p["motor.inertia"]
    k_r, c_r = p["input_shaft.stiffness"], p["input_shaft.damping"]
    motor_work = _trapezoid(t_m * w_m, dt)
    load_work = _trapezoid(load * w2, dt)
    dissipation = _trapezoid(c_r * (w_m - w1) ** 2, dt)
    kinetic = 0.5 * (j1 * w1 ** 2 + j2 * w2 ** 2 + j_m * w_m ** 2)
    spring = 0.5 * k_r * (th_m - phi1) ** 2
    residual = (motor_work - load_work - dissipation - (kinetic[-1] - kinetic[0])
                - (spring[-1] - spring[0]))
    span_bound = sum((max(o[k] for o in outs) ** 2 - min(o[k] for o in outs) ** 2)
                     * d.links / (2 * p["chain.link_stiffness"])
                     for k in ("tight_span.tension", "slack_span.tension"))
    assert motor_work > 100.0                  # the drive ran: ~ r M w 0.5 s
    assert abs(residual) <= span_bound
    assert span_bound < 2e-3 * motor_work
    # the rotor's momentum: J_m dw_m = integral of (T_m - T_shaft) (the shaft torque output)
    shaft = np.array([o["input_shaft.torque"] for o in outs])
    assert j_m * (w_m[-1] - w_m[0]) == pytest.approx(_trapezoid(t_m - shaft, dt), abs=2e-3)
    # the drive holds its speed: neither runs away nor stalls at the steady need
    assert np.mean(w_m) == pytest.approx(w, rel=0.01)


def test_torque_step_matches_an_independent_two_inertia_model():
    """A 1 N m torque step on the rotor at rest, no load, the chain hanging slack (centre
    distance 4 mm short of the 46-link chain's 0.1977 m, no gravity: the spans carry no tension, the drive
    side is the driver's inertia I1): rotor J_m and driver I1 on the shaft spring k_r, c_r,
    integrated here with scipy, give the motor speed and shaft twist over 20 ms (six shaft
    oscillation periods)."""
    sc = _scene(**{"drive.centre_distance": 0.1937, "driven.inertia": 1e-5,
                   "torsional.chain_inertia": False, "driven.damping": 0.0,
                   "gravity": 0.0})   # with gravity the spans would carry their sag tension
    p = sc.parameters
    model = sc.model()
    x0 = model.initial_state(Inputs(0.0, 0.0, 0.0, 0.0))
    dt, n = 1e-4, 200
    t, X, _ = _run(model, x0, Inputs(0.0, 0.0, 0.0, 0.0, motor_torque=1.0), dt, n)
    j_m, j1 = p["motor.inertia"], p["driver.inertia"] + \
        (sc.drive.n_driver / sc.drive.n_driven) ** 2 * p["driven.inertia"]
    k_r, c_r = p["input_shaft.stiffness"], p["input_shaft.damping"]
    q0 = X[0, 2] - X[0, 0]

    def two_inertia(_, y):
        th_m, phi1, w_m, w1 = y
        ts = k_r * (th_m - phi1) + c_r * (w_m - w1)
        return [w_m, w1, (1.0 - ts) / j_m, ts / j1]

    ref = solve_ivp(two_inertia, (0.0, t[-1]), [X[0, 2], X[0, 0], 0.0, 0.0], t_eval=t,
                    rtol=1e-10, atol=1e-12, method="DOP853")
    w_m, twist = X[:, 5], X[:, 2] - X[:, 0] - q0
    ref_w_m, ref_twist = ref.y[2], ref.y[0] - ref.y[1] - q0
    assert np.max(np.abs(w_m - ref_w_m)) <= 0.01 * np.max(np.abs(ref_w_m))
    assert np.max(np.abs(twist - ref_twist)) <= 0.01 * np.max(np.abs(ref_twist))
    # and the mean motion follows the total inertia: (J_m + I1) w = T t
    assert (j_m * w_m[-1] + j1 * X[-1, 3]) == pytest.approx(1.0 * t[-1], rel=0.01)
    assert np.max(np.abs(X[:, 4])) == 0.0          # the slack chain leaves the driven at rest


def test_heavy_rotor_is_angle_causality():
    """A rotor far heavier than the drive (1e4 kg m2) driven by the scene's feed-forward torque
    follows the speed profile, so the drive's outputs are those of angle causality."""
    kw = dict(fidelity=1, duration=0.2, output_interval=1e-3)
    angle = chainmodel.simulate("xu2010", **kw)
    torque = chainmodel.simulate("xu2010", **kw, parameters=dict(TORQUE, **{"motor.inertia": 1e4}))
    for name in ("driver.speed", "driven.speed", "tight_span.tension"):
        scale = np.max(np.abs(angle[name]))
        assert np.max(np.abs(torque[name] - angle[name])) <= 0.01 * scale, name


def test_angle_causality_builds_the_level_class():
    sc = load_scene("xu2010").with_overrides(fidelity=1)
    assert type(sc.model()) is model_class(1)
    assert sc.parameters["input_shaft.causality"] == "angle"


def test_refusals_name_the_parameter():
    sc = load_scene("xu2010").with_overrides(fidelity=0)
    with pytest.raises(ValueError, match="input_shaft.causality = torque needs fidelity 1-3"):
        build_model(0, sc.drive, dict(sc.parameters, **TORQUE))
    with pytest.raises(ValueError, match="input_shaft.rigid = true"):
        build_model(1, sc.drive, dict(sc.parameters, **TORQUE, **{"input_shaft.rigid": True}))
    with pytest.raises(ValueError, match="input_shaft.causality must be one of angle, torque"):
        _scene(**{"input_shaft.causality": "speed"})
    with pytest.raises(ValueError, match="motor.inertia"):
        _scene(**{"motor.inertia": 0.0})


def test_runaway_motor_is_a_divergence_with_its_cause():
    """A motor torque far above the load's need: the rotor runs away and the stepper stops
    with a sentence naming motor.speed and the torque, not the chain."""
    sc = _scene()
    model = sc.model()
    st = make_stepper(model, "rk4", 0.0, Inputs(), x0=model.initial_state(Inputs()))
    with pytest.raises(chainmodel.SimulationDiverged, match="motor.speed"):
        for k in range(1, 2000):
            st.advance(k * 1e-3, Inputs(0.0, 0.0, 0.0, 0.0, motor_torque=200.0))
