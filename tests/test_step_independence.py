"""Results do not depend on the communication step (issue 8, "accuracy set by a tolerance, not by
the host"): the same run driven through the FMU's path (Stepper.advance_held, inputs held
first-order) at communication steps of 1e-5, 1e-4, 1e-3 and 1e-2 s agrees at the common points
within what solver.tolerance promises (docs/numerics.md): the tight-span tension within 1 % of
its peak, the driven speed within 10 % of its ripple amplitude.

The inputs are the same function of time at every communication step - a constant input speed
from t = 0 (the input shaft jumps to speed; the drive starts from its static equilibrium) and a
constant load, which first-order hold represents exactly - so what is compared is the
numerics, not the sampling of the inputs. The 1e-5 s run is the reference: there the
communication step, not the tolerance, limits the internal step (it is 13x finer on xu2010).
The numbers compared come from the runs themselves; nothing is taken from an earlier run.
"""

from __future__ import annotations

import numpy as np
import pytest

import chainmodel
from chainmodel.integrate import OUTPUT_NAMES
from chainmodel import _numba

STEPS = (1e-5, 1e-4, 1e-3, 1e-2)
DURATION = 0.3          # s; compared from 0.1 s on, every 10 ms (the coarsest step's points)
T_TIGHT = OUTPUT_NAMES.index("tight_span.tension")
W_DRIVEN = OUTPUT_NAMES.index("driven.speed")


def held_run(scene, h, speed):
    """(times, tight-span tension, driven speed) at the points every 10 ms, the stepper driven
    as the FMU drives it: one advance_held per communication step."""
    st = scene.stepper()
    load = scene.operating.load_torque
    n = round(DURATION / h)
    every = round(1e-2 / h)
    rows = []
    for k in range(n):
        row = st.advance_held((k + 1) * h, speed * k * h, speed, 0.0, load)
        if (k + 1) % every == 0:
            rows.append(((k + 1) * h, row[T_TIGHT], row[W_DRIVEN]))
    return np.array(rows)


CASES = [
    # xu2010 (seed 003) at 124 rpm: tooth passing at 51.7 Hz, so the 10 ms points fall on
    # different phases of the meshing cycle
    pytest.param("xu2010", 1, 13.0, {}, id="xu2010-torsional"),
    pytest.param("xu2010", 2, 13.0, {}, id="xu2010-modal"),
    # C1 at 400 rpm: the quarter-tooth cap from the current input speed is what binds
    pytest.param("C1", 1, 41.9, {}, id="C1-torsional"),
    # level 3's span modes are undamped by default and its ripple is then not converged in the
    # step at all (issue 10); with the joint dampers at 2 % it is
    pytest.param("xu2010", 3, 13.0, {"chain_joint_damping": 0.02}, id="xu2010-multibody",
                 marks=pytest.mark.skipif(not _numba.enabled(),
                                          reason="level 3 over 0.3 s needs the compiled loop")),
]


@pytest.mark.parametrize("name, level, speed, overrides", CASES)
def test_results_agree_across_communication_steps(name, level, speed, overrides):
    scene = chainmodel.Scene.from_preset(name, fidelity=level, **overrides)
    runs = {h: held_run(scene, h, speed) for h in STEPS}
    ref = runs[STEPS[0]]
    window = ref[:, 0] >= 0.1 - 1e-9
    peak = np.max(np.abs(ref[window, 1]))
    ripple = 0.5 * (np.max(ref[window, 2]) - np.min(ref[window, 2]))
    assert peak > 0 and ripple > 0
    for h, run in runs.items():
        np.testing.assert_allclose(run[:, 0], ref[:, 0], rtol=1e-9)
        d_tension = np.max(np.abs(run[window, 1] - ref[window, 1])) / peak
        d_speed = np.max(np.abs(run[window, 2] - ref[window, 2])) / ripple
        assert d_tension < 0.01, f"communication step {h:g} s: tension off by {d_tension:.2%}"
        assert d_speed < 0.10, f"communication step {h:g} s: speed off by {d_speed:.1%}"


def test_internal_step_does_not_follow_the_communication_step():
    """The internal steps taken over the same 30 ms are set by the tolerance and the dynamics:
    communication steps of 1, 3 and 10 ms all take the same number of internal steps to within
    the rounding up of each communication step, and a tighter tolerance takes more."""
    scene = chainmodel.Scene.from_preset("xu2010", fidelity=1)
    counts = {}
    for h in (1e-3, 3e-3, 1e-2):
        st = scene.stepper()
        for k in range(round(0.03 / h)):
            st.advance_held((k + 1) * h, 13.0 * k * h, 13.0, 0.0, 43.2)
        counts[h] = st.stats["steps"]
    bound = scene.stepper().h
    assert max(counts.values()) - min(counts.values()) <= 0.03 / 1e-3      # one per point at most
    assert min(counts.values()) >= 0.03 / bound - 1
    tight = scene.with_overrides(solver_tolerance=scene.parameters["solver.tolerance"] / 16)
    st = tight.stepper()
    for k in range(3):
        st.advance_held((k + 1) * 1e-2, 0.13 * k, 13.0, 0.0, 43.2)
    assert st.stats["steps"] >= 1.9 * counts[1e-2]        # (1/16)^(1/4) = 1/2 the step


def test_a_state_the_model_refuses_is_refused_at_any_communication_step():
    """Level 2 on seed 004's A2 drive, its input shaft jumping to 400 rpm: a span's transverse
    amplitude leaves the string model's range (ModalModel.check) within 0.3 s. The 0.1 ms run
    refuses it, and so must a run through 10 and 50 ms communication steps: the check runs
    after every internal step, not only at communication points (at 50 ms it passed through
    and returned a tight span of 17 kN where level 1 carries 55 N)."""
    from chainmodel.models.base import SimulationDiverged
    scene = chainmodel.Scene.from_preset("A2", fidelity=2)
    speed, load = 41.9, scene.operating.load_torque
    for h in (1e-4, 1e-2, 5e-2):
        st = scene.stepper()
        with pytest.raises(SimulationDiverged, match="transverse amplitude"):
            for k in range(round(DURATION / h)):
                st.advance_held((k + 1) * h, speed * k * h, speed, 0.0, load)
