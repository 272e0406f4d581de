"""The batched path of levels 1-2 (many communication points per compiled call, outputs
vectorised) against the per-point path (one Stepper.advance and one Model.outputs per point, as
the FMU steps): the same states, outputs, statistics and event log. The per-point path is the
independent computation here; nothing is compared with numbers from an earlier run."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel import _numba, simulation
from chainmodel.models import Inputs, SimulationDiverged
from chainmodel.models.span_sag import hanging_tension
from chainmodel.kernels import spans as S
from chainmodel.scene import OperatingPoint

needs_numba = pytest.mark.skipif(not _numba.enabled(), reason="the batched path is the compiled one")


def _same(a, b):
    for name in a.names:
        np.testing.assert_allclose(a[name], b[name], rtol=1e-13, atol=1e-13, err_msg=name)


@needs_numba
@pytest.mark.parametrize("name, level, overrides", [
    ("xu2010", 1, {}),                                                  # flexible shaft, events
    ("xu2010", 1, {"input_speed_rpm": -120, "load_torque": -43.2}),     # reverse: spans swap
    ("C1", 2, {"modal_modes": 2}),                                      # rigid shaft, span modes
])
def test_batched_run_equals_per_point_run(name, level, overrides, monkeypatch):
    """Whole runs from rest through the speed ramp: every output at every point, the step and
    event counts; small chunks so that chunk boundaries are crossed too."""
    sc = chainmodel.Scene.from_preset(name, fidelity=level, duration=0.08, output_interval=1e-3,
                                      **overrides)
    monkeypatch.setattr(simulation, "BATCH_POINTS", 23)
    a = simulation.run_scene(sc)
    b = simulation.run_scene(sc, batched=False)
    assert b.stats["events"] > 0
    for key in ("steps", "events"):
        assert a.stats[key] == b.stats[key], key
    # the batched loop starts a step from the evaluation that ended the last one where the
    # inputs there are the same (here: after the ramp), at most one fewer per point
    n = len(a.time) - 1
    assert b.stats["rhs_evaluations"] - n <= a.stats["rhs_evaluations"] <= b.stats["rhs_evaluations"]
    _same(a, b)


@needs_numba
def test_batched_stepper_leaves_the_per_point_state_and_event_log():
    """Stepper.advance_batch ends where per-point advance calls end (time, state, inputs) with the
    same located events, and a later per-point step continues from there identically."""
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, output_interval=2e-3)
    times = np.arange(0, 31) * 2e-3
    m = sc.model()
    a, b = sc.stepper(m), sc.stepper(m)
    states = a.advance_batch(times, *sc.input_arrays(times))
    for i, t in enumerate(times[1:], 1):
        b.advance(float(t), sc.inputs)
        np.testing.assert_allclose(states[i], b.x, rtol=1e-14, atol=1e-14)
    assert a.t == b.t and a.inputs == b.inputs
    assert len(b.event_log) > 0 and list(a.event_log) == list(b.event_log)
    out_a, out_b = a.advance(0.07, sc.inputs), b.advance(0.07, sc.inputs)
    for k in out_b:
        assert out_a[k] == pytest.approx(out_b[k], rel=1e-13, abs=1e-13), k


def test_input_arrays_are_the_scalar_inputs():
    """The vectorised ramp profile gives the scalar profile's numbers (inside, at the end of and
    after the ramp, and without a ramp)."""
    for op in (OperatingPoint(12.5, 0.05, 43.2), OperatingPoint(-40.0, 0.0, -3.0)):
        t = np.concatenate([np.linspace(0, 0.2, 201), [0.05 - 1e-12, 0.05, 0.05 + 1e-12]])
        arrays = op.input_arrays(t)
        for k, name in enumerate(("angle", "speed", "acceleration", "torque")):
            assert np.array_equal(arrays[k], [getattr(op.inputs(float(v)), name) for v in t]), name


@pytest.mark.parametrize("wrap", [False, True], ids=["seat_ladder", "wrap_statics"])
@pytest.mark.parametrize("level,gravity", [(1, 0.0), (1, 9.81), (2, 9.81)])
def test_outputs_many_equals_outputs(level, gravity, wrap):
    """Vectorised outputs at arbitrary states and inputs (both directions, a driver at rest, a
    slack span on the seat ladder - level 1's lagged sag holds a span only as far as the sag
    has followed, and these states jump - while the wrap fit's floor holds it above 0 N)
    against the scalar outputs, compiled or plain kernel alike."""
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=level, gravity=gravity,
                                      torsional_wrap_statics=wrap)
    m = sc.model()
    rng = np.random.default_rng(1)
    x0 = m.initial_state(Inputs(0.1, 0.0, 43.2))
    states = x0 + rng.normal(0, 1, (40, m.n_states)) * np.where(
        np.arange(m.n_states) < m.n_sprocket_states // 2, 2e-3, 1.0) * (np.arange(40) % 3 > 0)[:, None]
    states[:, :m.n_sprocket_states // 2] += rng.uniform(-3, 3, (40, 1))
    angle = rng.uniform(-3, 3, 40)
    speed = rng.uniform(-20, 20, 40)
    speed[5] = 0.0
    acc, torque = rng.uniform(-50, 50, 40), rng.uniform(-50, 50, 40)
    inputs = [Inputs(*v) for v in zip(angle, speed, torque, acc)]
    times = np.linspace(0, 1, 40)
    got = m.evaluate_states(times, states, inputs)
    if not wrap:
        # slack without weight and at level 2; level 1's lagged sag holds a span only as far
        # as its sag has followed: a stretch that runs out faster goes slack too. Slack is 0 N
        # without weight, else the weight along the span (span_sag.hanging_tension: xu2010's
        # spans rise a little between unequal sprockets)
        floor = hanging_tension(sc.drive, sc.parameters)
        assert (floor > 0.0) == (gravity > 0.0)
        assert np.any(np.isclose(got["slack_span.tension"], floor, rtol=1e-12, atol=1e-15))
        assert np.all(got["slack_span.tension"] >= floor * (1.0 - 1e-12))
    else:   # the wrap fit's floor
        assert np.all(got["slack_span.tension"] > 0.0)
    for i in range(40):
        ref = m.outputs(float(times[i]), states[i], inputs[i])
        for k, v in ref.items():
            assert got[k][i] == pytest.approx(v, rel=1e-13, abs=1e-13), (k, i)


@pytest.mark.parametrize("level", [1, 2])
def test_check_states_raises_for_the_first_bad_state_as_check_does(level):
    sc = chainmodel.Scene.from_preset("C1", fidelity=level)
    m = sc.model()
    x = m.initial_state(Inputs())
    states = np.tile(x, (6, 1))
    times = np.arange(6) * 0.01
    m.check_states(times, states)                       # all fine: no error
    states[4, 0] = math.nan
    if level == 2:                                      # a runaway span mode before that
        states[2, m.n_sprocket_states] = 0.2 * m.reference["l_up"]
    with pytest.raises(SimulationDiverged) as batch:
        m.check_states(times, states)
    first = 2 if level == 2 else 4
    with pytest.raises(SimulationDiverged) as single:
        m.check(float(times[first]), states[first])
    assert str(batch.value) == str(single.value)
