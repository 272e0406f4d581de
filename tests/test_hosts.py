"""Independent importers: the FMU through libcosim gives the same outputs as through fmpy,
bit for bit, at every fidelity level (chainmodel.fmu_hosts drives both with one call sequence,
libcosim's)."""

from __future__ import annotations

import numpy as np
import pytest

from chainmodel.models import ALL_OUTPUTS
from chainmodel.fmu_hosts import HostUnavailable, grid, host_versions, run_fmu

pytestmark = pytest.mark.fmu

VERSIONS = host_versions()
needs_libcosim = pytest.mark.skipif(
    VERSIONS["libcosim"] is None,
    reason="libcosimpy has no wheel for this platform (pip install libcosimpy): the libcosim "
           "comparison did NOT run")

SPEED, LOAD = 12.0, 20.0
RUN = dict(stop_time=0.004, step_size=1e-4,
           inputs={"input_shaft.angle": lambda t: SPEED * t, "input_shaft.speed": SPEED,
                   "load.torque": LOAD})


@needs_libcosim
@pytest.mark.parametrize("level", [0, 1, 2, 3])
def test_libcosim_and_fmpy_agree_bit_for_bit(chaindrive_fmu, level):
    a = run_fmu(chaindrive_fmu, "fmpy", start_values={"fidelity": level}, **RUN)
    b = run_fmu(chaindrive_fmu, "libcosim", start_values={"fidelity": level}, **RUN)
    assert (a.host, b.host) == ("fmpy", "libcosim")
    np.testing.assert_array_equal(a.time, b.time)
    # every output of the FMU: the library's and the rotor's (motor.angle, motor.speed)
    assert set(a.outputs) == set(b.outputs) and len(a.outputs) == len(ALL_OUTPUTS) + 2
    differing = [n for n in a.outputs if not np.array_equal(a.outputs[n], b.outputs[n])]
    assert not differing, differing
    # the run did something: the input shaft turned the driver forward
    assert np.all(np.diff(a.outputs["driver.angle"]) > 0)
    if level == 0:   # rigid driver at level 0: the input angle held first-order over each step
        np.testing.assert_allclose(a.outputs["driver.angle"], SPEED * a.time, rtol=0, atol=1e-15)


def test_grid_is_libcosims_nanosecond_grid():
    times, step_ns = grid(0.003, 1e-4)
    assert step_ns == 100_000 and len(times) == 31
    assert times[3] == 300_000 / 1e9          # not 3 * 1e-4
    with pytest.raises(ValueError, match="step_size"):
        grid(1.0, 1e-10 / 3)
    with pytest.raises(ValueError, match="stop_time"):
        grid(0.00025, 1e-4)


def test_unknown_host_and_variables_are_refused(chaindrive_fmu):
    with pytest.raises(ValueError, match="host must be one of fmpy, libcosim"):
        run_fmu(chaindrive_fmu, "ecos", **RUN)
    with pytest.raises(ValueError, match="no variable.*input_shaft.torqeu"):
        run_fmu(chaindrive_fmu, "fmpy", stop_time=1e-3, step_size=1e-4,
                inputs={"input_shaft.torqeu": 1.0})
    if VERSIONS["libcosim"] is None:
        with pytest.raises(HostUnavailable, match="pip install libcosimpy"):
            run_fmu(chaindrive_fmu, "libcosim", **RUN)


def test_an_fmpy_run_keeps_the_fmus_messages_and_names_them_when_it_fails(chaindrive_fmu):
    """The fmpy path instantiates without loggingOn, as libcosim does; the FMU's warnings and
    errors reach it all the same (docs/fmu.md, "Log messages"): a refused initialization is
    raised with the FMU's reason, and a run's warnings are kept in HostRun.messages."""
    with pytest.raises(RuntimeError, match="fidelity must be 0-3"):
        run_fmu(chaindrive_fmu, "fmpy", stop_time=0.002, step_size=1e-3,
                start_values={"fidelity": 7})
    # a speed without its angle: the driver jumps by the angle the speed implies, and the FMU
    # warns once (docs/fmu.md, "The angle input")
    run = run_fmu(chaindrive_fmu, "fmpy", stop_time=0.003, step_size=1e-3,
                  start_values={"fidelity": 0}, inputs={"input_shaft.speed": 10.0})
    assert [status for status, _ in run.messages] == [1]
    assert "input_shaft.angle jumped" in run.messages[0][1]
