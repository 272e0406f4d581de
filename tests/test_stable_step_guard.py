"""The stable-step guard of the fixed-step loops (issue 10, "Also"; docs/numerics.md): the highest
natural frequency is estimated from the *current* state, the automatic step follows it, and an
explicit solver.step that the state makes unstable is refused with a message - the stepper then
stays at its last communication point.

C1 at level 2 (seed 004 Table 2; rigid input shaft, 28.7 Hz sprocket mode) at rest, then loaded:
the tight span's tension rises from its static 500 N towards 2.8 kN and its string modes stiffen
with it, omega_1 = (pi / l) sqrt(T / rho A) (seed 004 eq 61), above the sprocket mode - and above
the bound the model used to assume (four times the static tension)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.integrate import stability_limit
from chainmodel.models import Inputs, SimulationDiverged
from chainmodel import _numba
from chainmodel.kernels.multibody_forces import omega_bound

LOAD = 400.0     # N.m on the driven sprocket (its pitch radius is 73 mm)


def c1_at_rest(**overrides):
    return chainmodel.Scene.from_preset("C1", fidelity=2, load_torque=0.0, **overrides)


def test_frequency_estimate_follows_the_span_tension():
    """omega_at is the larger of the sprockets' bound and each span's highest mode at its
    current tension, here computed independently from seed 004 eq 61."""
    sc = c1_at_rest()
    st = sc.stepper()
    m = st.model
    for k in range(30):
        st.advance_held((k + 1) * 0.01, 0.0, 0.0, 0.0, LOAD)
    u = Inputs(0.0, 0.0, LOAD)
    out = m.outputs(st.t, st.x, u)
    rho = m.params["chain.link_mass"] / m.drive.pitch
    spans = [(out["tight_span.tension"], m.reference["l_up"]),
             (out["slack_span.tension"], m.reference["l_low"])]
    modes = max(math.pi / length * math.sqrt(max(t, 0.0) / rho) for t, length in spans)
    expected = max(float(np.max(m.sprocket_frequencies())), modes)
    assert m.omega_at(st.t, st.x, u) == pytest.approx(expected, rel=1e-12)
    assert expected > m.omega_max()           # above the old static bound (4 T0)
    assert out["tight_span.tension"] > 4 * m.static_tension()


def test_explicit_step_made_unstable_by_the_state_is_refused_and_the_stepper_kept():
    sc = c1_at_rest()
    m = sc.model()
    at_rest = m.omega_at(0.0, m.initial_state(sc.inputs(0.0)), sc.inputs(0.0))
    h = 0.012
    assert h * at_rest < stability_limit("rk4")           # accepted when built
    st = c1_at_rest(solver_step=h).stepper(m)
    with pytest.raises(SimulationDiverged, match=r"solver.step = 0.012 s is above the stable "
                                                 r"limit .* at t = .*use a step <="):
        for k in range(100):
            t_before, x_before = st.t, st.x.copy()
            st.advance_held((k + 1) * 0.01, 0.0, 0.0, 0.0, LOAD)
    assert st.t == t_before > 0                           # the step refused, the ones before kept
    assert np.array_equal(st.x, x_before)
    assert np.all(np.isfinite(st.x))


def test_automatic_step_adapts_to_the_stiffening_span():
    """The same load with the automatic step runs, and takes more internal steps once loaded:
    the bound theta / omega follows omega of the current state. Each step is bounded by the
    state it starts from (rk4_loop: omega at every step), so the last interval's mean step is
    at most the largest bound among its steps' states: the interval's first or last (omega
    still moves monotonically as the drive settles under the load)."""
    st = c1_at_rest().stepper()
    u = Inputs(0.0, 0.0, LOAD)
    counts = []
    for k in range(30):
        before = st.stats["steps"]
        w_start = st.model.omega_at(st.t, st.x, u)
        out = st.advance_held((k + 1) * 0.01, 0.0, 0.0, 0.0, LOAD)
        counts.append(st.stats["steps"] - before)
    assert np.all(np.isfinite(out))
    assert counts[-1] > counts[0]
    h_now = 0.01 / counts[-1]
    w_end = st.model.omega_at(st.t, st.x, u)
    assert h_now <= st.step_bound(min(w_start, w_end)) * (1 + 1e-9)


@pytest.mark.skipif(not _numba.enabled(), reason="compares the compiled guard with Python")
def test_level3_guard_frequency_is_the_models_bound():
    """The compiled loop's estimate (kernels.multibody_forces.omega_bound) is MultibodyModel.omega_max
    of the same state, the stretched links counted with their current stiffness."""
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=3)
    m = sc.model()
    x = m.initial_state(sc.inputs(0.0))
    n = 2 + 2 * m.M
    for scale in (1.0, 1.3, 0.4):
        # scaling the rollers about O scales every link; at 0.4 |k (L - l0)| / L = 1.5 k
        y = x.copy()
        y[2:n] *= scale
        compiled = omega_bound(y[:n], m.P, m._omega_constants)
        assert compiled == pytest.approx(m.omega_max(y), rel=1e-12)
        assert omega_bound.py_func(y[:n], m.P, m._omega_constants) == pytest.approx(compiled,
                                                                                 rel=1e-12)
    assert m.omega_max(y) > m.omega_max(x)
