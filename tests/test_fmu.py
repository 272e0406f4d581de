"""The ChainDrive FMU (FMI 2.0 co-simulation), loaded and run by fmpy.

The FMU is built once per session (tests/conftest.py). References are the FMI 2.0 standard
(model description rules, SI base units), the library's own stepper and model driven with the
same inputs and the same hold (the FMU must be a transparent adapter: equal to 1e-12), and
independent computations inside the tests (the backward-difference acceleration, the display
unit factors). No number here comes from an earlier run of the FMU.
"""

from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import numpy as np
import pytest

from chainmodel import parameters as P
from chainmodel.fmu import simulate_fmu, reference_scene
from chainmodel.fmu_log import FMULog
from chainmodel.models import ALL_OUTPUTS, MODEL_CLASSES, Inputs
from chainmodel.scene import Scene

pytestmark = pytest.mark.fmu

OUTPUTS = [o.name for o in ALL_OUTPUTS]
INPUTS = ["input_shaft.angle", "input_shaft.speed", "load.torque"]
#: torque causality's input and the outputs of both causalities (issue 18 item 2)
MOTOR = ["motor.angle", "motor.speed"]
RTOL = 1e-12


# --- helpers ---------------------------------------------------------------------------------

class Slave:
    """One FMU instance through fmpy's low-level API, with its log captured."""

    def __init__(self, unzipdir, parameters=None, start=0.0, inputs=(0.0, 0.0, 0.0),
                 logging_on=True):
        from fmpy import read_model_description
        from fmpy.fmi2 import FMU2Slave
        self.md = read_model_description(str(unzipdir))
        self.var = {v.name: v for v in self.md.modelVariables}
        self.log = FMULog()
        self.fmu = FMU2Slave(guid=self.md.guid, unzipDirectory=str(unzipdir),
                             modelIdentifier=self.md.coSimulation.modelIdentifier,
                             instanceName="test")
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=logging_on)
        self.fmu.setupExperiment(startTime=start)
        self.fmu.enterInitializationMode()
        self.set_parameters(parameters or {})
        self.set_inputs(*inputs)
        self.out_vr = [self.var[n].valueReference for n in OUTPUTS]
        self.in_vr = [self.var[n].valueReference for n in INPUTS]

    def set_parameters(self, values):
        for name, value in values.items():
            v = self.var[name]
            setter = {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
                      "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[v.type]
            setter([v.valueReference], [value])

    def set_inputs(self, angle, speed, torque):
        self.fmu.setReal([self.var[n].valueReference for n in INPUTS], [angle, speed, torque])

    def outputs(self):
        return np.array(self.fmu.getReal(self.out_vr))

    def messages(self):
        return " | ".join(m for _, m in self.log.messages)

    def free(self):
        self.fmu.freeInstance()   # fmpy's own call, library unload included

    def refused_initialization(self) -> int:
        """fmi2ExitInitializationMode, which must fail; its status."""
        from fmpy.fmi1 import FMICallException
        with pytest.raises(FMICallException) as err:
            self.fmu.exitInitializationMode()
        return err.value.status


def library_outputs(model, t, x, u):
    out = model.outputs(t, x, u)
    return np.array([out[n] for n in OUTPUTS])


def assert_equal_outputs(fmu, lib, what):
    scale = np.maximum(np.abs(lib), 1e-300)
    bad = np.abs(fmu - lib) > RTOL * scale + 1e-300
    if np.any(bad):
        rows = [f"{OUTPUTS[i]}: fmu {fmu[i]!r} library {lib[i]!r}" for i in np.flatnonzero(bad)]
        pytest.fail(f"{what}: FMU differs from the library:\n  " + "\n  ".join(rows))


def ramp_profile(scene):
    def f(t):
        u = scene.inputs(t)
        return u.angle, u.speed, u.torque
    return f


def reversing_profile(t):
    """Speed oscillating through zero (forward and reverse rotation), varying load."""
    w0, f = 9.0, 3.0
    return (w0 / (2 * math.pi * f) * math.sin(2 * math.pi * f * t),
            w0 * math.cos(2 * math.pi * f * t), 30.0 + 10.0 * math.sin(2 * math.pi * 5 * t))


def run_against_library(unzipdir, scene, profile, times):
    """Drive the FMU and the library with the same inputs on the grid ``times``; compare the
    outputs after each fmi2DoStep (held inputs) and after the inputs of the new point are set
    (direct feedthrough). The acceleration estimate is computed here, independently."""
    s = Slave(unzipdir, scene.parameters, start=float(times[0]), inputs=profile(times[0]))
    try:
        s.fmu.exitInitializationMode()
        stepper = scene.stepper()      # the library's own construction path
        model = stepper.model
        a, w, tq = profile(times[0])
        u = Inputs(a, w, tq, 0.0)      # no history at the first point
        assert_equal_outputs(s.outputs(), library_outputs(model, stepper.t, stepper.x, u), "t0")
        prev_t, prev_w = None, None
        for k in range(len(times) - 1):
            t, h = float(times[k]), float(times[k + 1] - times[k])
            a, w, tq = profile(t)
            acc = 0.0 if prev_t is None else (w - prev_w) / (t - prev_t)
            s.set_inputs(a, w, tq)
            s.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            lib = stepper.advance(t + h, Inputs(a, w, tq, acc))
            assert_equal_outputs(s.outputs(), np.array([lib[n] for n in OUTPUTS]),
                                 f"after the step {t:.6g} s + {h:.3g} s")
            prev_t, prev_w = t, w
            a1, w1, tq1 = profile(t + h)
            s.set_inputs(a1, w1, tq1)
            u1 = Inputs(a1, w1, tq1, (w1 - w) / (t + h - t))
            assert_equal_outputs(s.outputs(), library_outputs(model, stepper.t, stepper.x, u1),
                                 f"inputs set at {t + h:.6g} s")
    finally:
        s.free()


def variable_grid(n, lo, hi, seed):
    steps = np.random.default_rng(seed).uniform(lo, hi, size=n)
    return np.concatenate([[0.0], np.cumsum(steps)])


# --- the model description -------------------------------------------------------------------

def test_validate_fmu_finds_no_problem(chaindrive_fmu):
    from fmpy.validation import validate_fmu
    assert validate_fmu(str(chaindrive_fmu)) == []


# SI base-unit exponents (kg, m, s, rad), written out here from the SI definitions
SI = {"1": {}, "rad": {"rad": 1}, "rad/s": {"rad": 1, "s": -1}, "rad/s2": {"rad": 1, "s": -2},
      "N.m": {"kg": 1, "m": 2, "s": -2}, "N": {"kg": 1, "m": 1, "s": -2}, "m": {"m": 1},
      "kg": {"kg": 1}, "N/m": {"kg": 1, "s": -2}, "N.s/m": {"kg": 1, "s": -1},
      "kg.m2": {"kg": 1, "m": 2}, "N.m.s/rad": {"kg": 1, "m": 2, "s": -1, "rad": -1},
      "N.m/rad": {"kg": 1, "m": 2, "s": -2, "rad": -1}, "m/s2": {"m": 1, "s": -2},
      "s": {"s": 1}}
DISPLAY = {"mm": 1000.0, "deg": 180.0 / math.pi, "rpm": 60.0 / (2.0 * math.pi)}


@pytest.fixture(scope="module")
def model_description(chaindrive_fmu):
    with zipfile.ZipFile(chaindrive_fmu) as z:
        return ET.fromstring(z.read("modelDescription.xml"))


def test_every_variable_described_and_every_real_has_a_defined_si_unit(model_description):
    root = model_description
    assert root.get("variableNamingConvention") == "structured"
    units = {}
    for u in root.find("UnitDefinitions"):
        base = {k: int(v) for k, v in u.find("BaseUnit").attrib.items()}
        units[u.get("name")] = base
        for du in u.findall("DisplayUnit"):
            assert float(du.get("factor")) == pytest.approx(DISPLAY[du.get("name")], rel=1e-15)
            assert float(du.get("offset", 0)) == 0
    for sv in root.find("ModelVariables"):
        name = sv.get("name")
        assert sv.get("description"), f"{name} has no description"
        typ = sv[0]
        if typ.tag == "Real":
            unit = typ.get("unit")
            assert unit, f"Real {name} has no unit"
            assert unit in units, f"unit {unit} of {name} is not defined"
            assert units[unit] == SI[unit], f"unit {unit}: base units {units[unit]}"
            if typ.get("displayUnit"):
                assert typ.get("displayUnit") in [d.get("name") for d in root.find(
                    "UnitDefinitions").findall(f"Unit[@name='{unit}']/DisplayUnit")]


def test_the_adapters_own_parameters_declare_the_ranges_it_checks(model_description):
    """auto.accuracy is a relative error in (0, 1] and coupling.motor_inertia >= 0, as the
    adapter refuses other values (an FMI tool range-checks min/max before initialization;
    FMI's min is inclusive, so the open end at 0 is declared 0); every speed a tool may show in
    rpm offers it, the motor rotor's too (the FMI audit of the twenty-fourth session found
    neither range declared and motor.speed without rpm)."""
    by_name = {sv.get("name"): sv[0] for sv in model_description.find("ModelVariables")}
    assert by_name["auto.accuracy"].get("min") == "0" and by_name["auto.accuracy"].get("max") == "1"
    assert by_name["coupling.motor_inertia"].get("min") == "0"
    assert by_name["coupling.motor_inertia"].get("max") is None
    for name in ("input_shaft.speed", "driver.speed", "driven.speed", "motor.speed",
                 "auto.input_speed"):
        assert by_name[name].get("displayUnit") == "rpm", name


def test_variables_follow_the_schema_and_the_contract(model_description):
    variables = list(model_description.find("ModelVariables"))
    by_name = {sv.get("name"): sv for sv in variables}
    # inputs (DESIGN.md, the FMU contract)
    for name, unit in zip(INPUTS + ["motor.torque"], ("rad", "rad/s", "N.m", "N.m")):
        sv = by_name[name]
        assert (sv.get("causality"), sv.get("variability")) == ("input", "continuous")
        assert sv[0].get("unit") == unit and sv[0].get("start") is not None
    # every output of the model interface, calculated, in ModelStructure
    outputs = [sv for sv in variables if sv.get("causality") == "output"]
    assert [sv.get("name") for sv in outputs] == OUTPUTS + MOTOR
    outputs = outputs[:len(OUTPUTS)]
    for sv, spec in zip(outputs, ALL_OUTPUTS):
        assert sv[0].get("unit") == (spec.unit or "1")
        assert sv.get("initial") == "calculated" and sv[0].get("start") is None
    index = {sv.get("name"): str(i) for i, sv in enumerate(variables, start=1)}
    structure = model_description.find("ModelStructure")
    assert [u.get("index") for u in structure.find("Outputs")] == [index[n] for n in
                                                                   OUTPUTS + MOTOR]
    # initial unknowns: the outputs and the calculated parameters (coupling.max_step)
    calculated = [sv.get("name") for sv in variables
                  if sv.get("causality") == "calculatedParameter"]
    assert calculated == ["coupling.max_step"]
    assert [u.get("index") for u in structure.find("InitialUnknowns")] == sorted(
        (index[n] for n in OUTPUTS + MOTOR + calculated), key=int)
    assert structure.find("Derivatives") is None
    # parameters: exactly the schema, typed by kind, defaults as start values
    params = {sv.get("name"): sv for sv in variables if sv.get("causality") == "parameter"}
    from chainmodel.fidelity_auto import FMU_PARAMETERS   # fidelity "auto" (issue 11)
    from chainmodel.cosim import FMU_PARAMETERS as COUPLING   # issue 18 (docs/fmu.md)
    assert set(params) == set(P.BY_NAME) | set(FMU_PARAMETERS) | set(COUPLING)
    types = {float: "Real", int: "Integer", bool: "Boolean", str: "String"}
    for p in P.PARAMETERS:
        sv = params[p.name]
        assert sv[0].tag == types[p.kind]
        assert sv.get("variability") == ("fixed" if p.structural else "tunable")
        assert sv.get("initial") == "exact"
        start = sv[0].get("start")
        if p.kind is float:
            assert float(start) == p.default
        elif p.kind is bool:
            assert start == str(p.default).lower()
        else:
            assert start == str(p.default)
    cosim = model_description.find("CoSimulation")
    for flag in ("canHandleVariableCommunicationStepSize", "canGetAndSetFMUstate",
                 "canSerializeFMUstate"):
        assert cosim.get(flag) == "true"
    de = model_description.find("DefaultExperiment")
    assert float(de.get("startTime")) == 0 and float(de.get("stepSize")) > 0


# --- equality with the library ---------------------------------------------------------------

def test_level0_equals_library_on_a_variable_step_grid(chaindrive_fmu_dir):
    scene = Scene.from_preset("xu2010", fidelity=0)
    times = variable_grid(60, 2e-5, 3e-3, seed=1)          # crosses the 0.05 s ramp end
    run_against_library(chaindrive_fmu_dir, scene, ramp_profile(scene), times)


def test_level0_equals_library_in_reverse_rotation(chaindrive_fmu_dir):
    scene = Scene.from_preset("xu2010", fidelity=0)
    times = variable_grid(60, 1e-4, 8e-3, seed=2)           # speed changes sign twice
    assert min(reversing_profile(t)[1] for t in times) < 0 < max(reversing_profile(t)[1] for t in times)
    run_against_library(chaindrive_fmu_dir, scene, reversing_profile, times)


def every_level_against_library(unzipdir):
    """Levels 0-3 (whichever are registered): fixed then variable communication steps through
    the ramp, then long ones (several internal steps, seating and release events inside)."""
    times = np.concatenate([np.arange(6) * 1e-4, 5e-4 + np.cumsum([2e-4, 5e-5, 1e-4])])
    times = np.concatenate([times, times[-1] + np.cumsum([3e-3, 7e-3, 1.1e-2, 4e-3])])
    for level in sorted(MODEL_CLASSES):
        scene = Scene.from_preset("xu2010", fidelity=level)
        run_against_library(unzipdir, scene, ramp_profile(scene), times)
    return sorted(MODEL_CLASSES)


@pytest.mark.parametrize("numba", ["0", "1"])
def test_every_level_equals_library(chaindrive_fmu_dir, numba):
    """The FMU and the library's Stepper.advance give the same outputs (to 1e-12) at every
    level, with the compiled kernels (numba) and with their plain twins (CHAINMODEL_NUMBA=0).
    In a subprocess: the FMU's own copy of the kernels compiles in its own process."""
    env = dict(os.environ, CHAINMODEL_NUMBA=numba)
    code = (f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); import test_fmu; "
            f"print(test_fmu.every_level_against_library({str(chaindrive_fmu_dir)!r}))")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          env=env, cwd=Path(__file__).parents[1], timeout=600)
    assert proc.returncode == 0, proc.stdout[-3000:] + proc.stderr[-3000:]
    assert proc.stdout.strip().splitlines()[-1] == "[0, 1, 2, 3]"     # every level ran


def test_step_refused_by_the_stable_step_guard_is_discarded(chaindrive_fmu_dir):
    """An explicit solver.step that the loaded state makes unstable (C1 at level 2, the tight
    span stiffening under load; tests/test_stable_step_guard.py) is refused: fmi2Discard, a
    message naming solver.step, the FMU at its last communication point with finite outputs."""
    from fmpy.fmi1 import FMICallException
    scene = Scene.from_preset("C1", fidelity=2, load_torque=0.0, solver_step=0.012)
    s = Slave(chaindrive_fmu_dir, scene.parameters, inputs=(0.0, 0.0, 0.0))
    try:
        s.fmu.exitInitializationMode()
        t, h = 0.0, 0.01
        with pytest.raises(FMICallException) as err:
            for _ in range(100):
                s.set_inputs(0.0, 0.0, 400.0)
                s.fmu.doStep(t, h)
                good, t = s.outputs(), t + h
        assert err.value.status == 2                               # fmi2Discard
        assert "solver.step" in s.messages() and "stable limit" in s.messages()
        assert f"stays at t = {t:.9g} s" in s.messages()
        assert np.array_equal(s.outputs(), good) and np.all(np.isfinite(good))
    finally:
        s.free()


def test_fmpy_simulate_fmu_equals_library(chaindrive_fmu):
    """fmpy's own master: inputs from a table, outputs recorded after each step."""
    from fmpy import simulate_fmu as fmpy_simulate
    h, n = 1e-3, 80
    grid = [n_ * h for n_ in range(n + 1)]                # fmpy's communication points
    scene = Scene.from_preset("xu2010", fidelity=0)
    profile = ramp_profile(scene)
    table = np.array([(t, *profile(t)) for t in grid],
                     dtype=[("time", float)] + [(name, float) for name in INPUTS])
    res = fmpy_simulate(str(chaindrive_fmu), fmi_type="CoSimulation", start_time=0.0,
                        stop_time=n * h, output_interval=h, input=table, output=OUTPUTS,
                        start_values={"chain.pretension": scene.parameters["chain.pretension"],
                                      "fidelity": 0})
    assert len(res) == n + 1
    stepper = scene.stepper()
    prev = None
    for k, t in enumerate(grid):
        a, w, tq = profile(t)
        if k == 0:
            lib = library_outputs(stepper.model, t, stepper.x, Inputs(a, w, tq, 0.0))
        else:
            t0 = grid[k - 1]
            a0, w0, tq0 = profile(t0)
            acc = 0.0 if prev is None else (w0 - prev[1]) / (t0 - prev[0])
            out = stepper.advance(t, Inputs(a0, w0, tq0, acc))
            lib = np.array([out[n_] for n_ in OUTPUTS])
            prev = (t0, w0)
        assert res["time"][k] == pytest.approx(t, rel=1e-12, abs=1e-15)
        assert_equal_outputs(np.array([res[n_][k] for n_ in OUTPUTS]), lib, f"fmpy t = {t:g}")


def test_simulate_fmu_samples_the_scene_like_run_scene(chaindrive_fmu):
    """chainmodel.fmu.simulate_fmu (the CLI's --via-fmu) against the library's vectorised
    run_scene. They differ only by the acceleration the FMU estimates by backward difference;
    on a linear speed ramp that estimate is exact, so the samples must agree except at t = 0
    (no history) and the first point after the ramp (the estimate still sees the ramp)."""
    from chainmodel.simulation import run_scene
    scene = reference_scene()
    fmu = simulate_fmu(chaindrive_fmu, scene)
    lib = run_scene(scene)
    assert np.array_equal(fmu.time, lib.time) and fmu.names == lib.names
    tr = scene.operating.ramp_time
    after_ramp = int(np.argmax(fmu.time >= tr - 1e-12))
    keep = np.ones(len(fmu.time), bool)
    keep[[0, after_ramp]] = False
    for name in OUTPUTS:
        np.testing.assert_allclose(fmu[name][keep], lib[name][keep], rtol=1e-8,
                                   atol=1e-8 * np.max(np.abs(lib[name])), err_msg=name)
    for name in ("driver.angle", "driver.speed", "driven.angle", "driven.speed",
                 "tight_span.length", "velocity_ratio"):   # do not depend on the acceleration
        np.testing.assert_allclose(fmu[name], lib[name], rtol=1e-12, atol=1e-15, err_msg=name)
    assert fmu.stats["communication_steps"] == len(fmu.time) - 1


# --- state -------------------------------------------------------------------------------------

def test_get_set_and_serialized_state_replay_identically(chaindrive_fmu_dir):
    scene = Scene.from_preset("xu2010", fidelity=0)
    profile = ramp_profile(scene)
    s = Slave(chaindrive_fmu_dir, scene.parameters, inputs=profile(0.0))
    other = None
    try:
        s.fmu.exitInitializationMode()
        times = variable_grid(30, 1e-4, 1e-3, seed=3)

        def run(slave, ks):
            rows = []
            for k in ks:
                slave.set_inputs(*profile(times[k]))
                rows.append(slave.outputs())      # feedthrough outputs at t_k
                slave.fmu.doStep(times[k], times[k + 1] - times[k])
                rows.append(slave.outputs())      # held outputs at t_k+1
            return np.array(rows)

        run(s, range(0, 10))
        state = s.fmu.getFMUstate()
        first = run(s, range(10, 25))
        s.fmu.setFMUstate(state)
        again = run(s, range(10, 25))
        assert np.array_equal(first, again)
        blob = s.fmu.serializeFMUstate(state)
        s.fmu.freeFMUstate(state)
        # a fresh instance with other parameters takes the whole state, parameters included
        other = Slave(chaindrive_fmu_dir, {"load.torque": 0.0, "driven.inertia": 1.0,
                                           "chain.pretension": 0.0})
        other.fmu.exitInitializationMode()
        restored = other.fmu.deSerializeFMUstate(blob)
        other.fmu.setFMUstate(restored)
        replay = run(other, range(10, 25))
        assert np.array_equal(first, replay)
        other.fmu.freeFMUstate(restored)
    finally:
        s.free()
        if other is not None:
            other.free()


# --- errors ------------------------------------------------------------------------------------

def _initialization_error(unzipdir, parameters):
    s = Slave(unzipdir, parameters)
    try:
        # fmi2Error, returned and logged: pythonfmu 0.7 reports every Python exception as
        # fmi2Fatal, which concerns all instances (FMI 2.0 section 2.1.3); the launcher mends it
        assert s.refused_initialization() == 3
        assert all(status != 4 for status, _ in s.log.messages)
        # pythonfmu 0.7's own line for the exception carries no text of it ("unknown error");
        # the launcher says which call failed and that the error before says why
        log = s.messages()
        assert "unknown error" not in log
        assert "raised an exception in [exitInitializationMode]" in log
        assert log.index("initialization failed") < log.index("raised an exception in")
        return log
    finally:
        s.free()


def test_a_host_without_logging_hears_the_errors_and_warnings_not_the_debug_lines(
        chaindrive_fmu_dir):
    """FMI 2.0's loggingOn (and fmi2SetDebugLogging) switches debug logging; the messages that
    explain a non-OK status or a result outside the model's validity reach the host whatever
    it says, as the Modelica Reference-FMUs log their errors. pythonfmu 0.7 forwards nothing
    without loggingOn, errors included; the launcher asks it for everything and filters."""
    from fmpy.fmi1 import FMICallException
    s = Slave(chaindrive_fmu_dir, {"drive.driver_teeth": 2}, logging_on=False)
    try:
        s.refused_initialization()
        assert {status for status, _ in s.log.messages} == {3}
        log = s.messages()
        assert "drive.driver_teeth" in log and "raised an exception in" in log
    finally:
        s.free()

    def init_lines(logging_on, categories=None):
        """The messages of a good initialization, debug logging as given."""
        s = Slave(chaindrive_fmu_dir, {"fidelity": 0}, logging_on=logging_on)
        try:
            if categories is not None:
                s.fmu.setDebugLogging(True, categories)
            s.fmu.exitInitializationMode()
            return s.log.messages
        finally:
            s.free()

    # the FMU's one debug line at initialization names the level (category logAll)
    def debug(messages):
        return [m for status, m in messages if status == 0 and m.startswith("fidelity 0")]

    assert debug(init_lines(True)) and not debug(init_lines(False))
    assert debug(init_lines(False, ["logAll"]))
    assert not debug(init_lines(False, ["logStatusError"]))

    # fmi2SetDebugLogging(c, true, 1, NULL) is the host's error: refused and said, not a crash
    s = Slave(chaindrive_fmu_dir, {"fidelity": 0}, logging_on=False)
    try:
        with pytest.raises(FMICallException) as err:
            s.fmu.fmi2SetDebugLogging(s.fmu.component, 1, 1, None)
        assert err.value.status == 3
        assert "nCategories = 1 but categories is NULL" in s.messages()
    finally:
        s.free()


def test_two_instances_alive_keep_their_own_messages(chaindrive_fmu_dir):
    """fmpy's logger proxy passes every message of the process to one logger (the last given
    to it); chainmodel.fmu_log.FMULog tells its instances apart by the component environment."""
    bad = Slave(chaindrive_fmu_dir, {"drive.driver_teeth": 2})
    good = Slave(chaindrive_fmu_dir, {"fidelity": 0})      # made last: the proxy's last logger
    try:
        bad.refused_initialization()
        good.fmu.exitInitializationMode()
        assert "drive.driver_teeth" in bad.messages()
        assert "drive.driver_teeth" not in good.messages() and "fidelity 0" in good.messages()
        assert "fidelity 0" not in bad.messages()
    finally:
        bad.free()
        good.free()


def test_bad_parameter_fails_initialization_naming_it(chaindrive_fmu_dir):
    log = _initialization_error(chaindrive_fmu_dir, {"drive.driver_teeth": 2})
    assert "drive.driver_teeth" in log and "2" in log


def test_after_a_refused_initialization_reset_gives_a_fresh_instance(chaindrive_fmu_dir):
    """FMI 2.0 section 2.1.3: after fmi2Error the instance may be reset (or freed). pythonfmu
    releases its Python objects after an exception; the reset instance must start from the
    model description's start values, not from the refused ones, and run."""
    s = Slave(chaindrive_fmu_dir, {"drive.driver_teeth": 2})
    try:
        teeth = s.var["drive.driver_teeth"]
        s.refused_initialization()
        s.fmu.reset()
        assert s.fmu.getInteger([teeth.valueReference]) == [int(teeth.start)]
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        s.set_parameters({"fidelity": 0})
        s.set_inputs(0.0, 1.0, 0.0)
        s.fmu.exitInitializationMode()
        s.fmu.doStep(0.0, 1e-3)
        assert np.all(np.isfinite(s.outputs()))
    finally:
        s.free()


def test_bad_real_parameter_fails_initialization_naming_it(chaindrive_fmu_dir):
    log = _initialization_error(chaindrive_fmu_dir, {"drive.pitch": -0.01})
    assert "drive.pitch" in log


def test_an_error_sentence_with_a_percent_sign_reaches_the_host_as_words(chaindrive_fmu_dir):
    """FMI log messages are printf formats (fmpy's proxy formats them, as C hosts do): the
    pretension error's "5 % or more" arrives as "5 percent or more", no conversion in any
    message (tests/test_fmu_embedding.py checks the exception's own text)."""
    log = _initialization_error(chaindrive_fmu_dir, {"chain.pretension": 1e9})
    assert "chain.pretension" in log and "5 percent or more" in log
    assert "%" not in log


def test_fidelity_out_of_range_or_missing_is_named(chaindrive_fmu_dir):
    assert "fidelity" in _initialization_error(chaindrive_fmu_dir, {"fidelity": 7})
    missing = [k for k in range(4) if k not in MODEL_CLASSES]
    for level in missing[:1]:
        log = _initialization_error(chaindrive_fmu_dir, {"fidelity": level})
        assert f"fidelity = {level}" in log and "not available" in log


@pytest.mark.parametrize("bad", [math.nan, math.inf])
def test_non_finite_input_discards_the_step_and_never_gives_nan(chaindrive_fmu_dir, bad):
    from fmpy.fmi1 import FMICallException
    scene = Scene.from_preset("xu2010", fidelity=0)
    profile = ramp_profile(scene)
    s = Slave(chaindrive_fmu_dir, scene.parameters, inputs=profile(0.0))
    try:
        s.fmu.exitInitializationMode()
        h = 1e-3
        for k in range(3):
            s.set_inputs(*profile(k * h))
            s.fmu.doStep(k * h, h)
        good = s.outputs()
        a, w, tq = profile(3 * h)
        s.set_inputs(a, bad, tq)
        assert np.array_equal(s.outputs(), good)          # not recomputed from a bad input
        with pytest.raises(FMICallException) as err:
            s.fmu.doStep(3 * h, h)
        assert err.value.status == 2                      # fmi2Discard
        assert "input_shaft.speed" in s.messages()
        assert np.all(np.isfinite(s.outputs())) and np.array_equal(s.outputs(), good)
        s.set_inputs(a, w, tq)                            # the master fixes its input: go on
        s.fmu.doStep(3 * h, h)
        assert np.all(np.isfinite(s.outputs()))
    finally:
        s.free()


def test_a_discarded_step_does_not_ask_the_master_to_end_the_run(chaindrive_fmu_dir):
    """FMI 2.0 section 4.2.3: after fmi2Discard a master may ask fmi2Terminated, and true ends
    the run. The FMU discards a step to have it retried (docs/fmu.md), so the answer is false
    and the same point, stepped again with good inputs, goes on."""
    from fmpy.fmi1 import FMICallException
    from fmpy.fmi2 import fmi2Terminated
    w = 4 * math.pi
    s = Slave(chaindrive_fmu_dir, {"fidelity": 1}, inputs=(0.0, w, 20.0))
    try:
        s.fmu.exitInitializationMode()
        h = 1e-4
        s.fmu.doStep(0.0, h)
        assert s.fmu.getBooleanStatus(fmi2Terminated) is False
        s.set_inputs(w * h, w, math.nan)
        with pytest.raises(FMICallException) as err:
            s.fmu.doStep(h, h)
        assert err.value.status == 2
        assert s.fmu.getBooleanStatus(fmi2Terminated) is False
        s.set_inputs(w * h, w, 20.0)
        s.fmu.doStep(h, h)
        assert np.all(np.isfinite(s.outputs()))
    finally:
        s.free()


def test_do_step_outside_the_stepping_phase_is_an_error(chaindrive_fmu_dir):
    """FMI 2.0 section 4.2.4: fmi2DoStep belongs between fmi2ExitInitializationMode and
    fmi2Terminate; elsewhere the FMU answers fmi2Error and says why."""
    from fmpy.fmi1 import FMICallException
    s = Slave(chaindrive_fmu_dir, {"fidelity": 0}, inputs=(0.0, 1.0, 0.0))
    try:
        with pytest.raises(FMICallException) as err:          # in initialization mode
            s.fmu.doStep(0.0, 1e-3)
        assert err.value.status == 3 and "initialization mode" in s.messages()
        s.fmu.exitInitializationMode()
        s.fmu.doStep(0.0, 1e-3)
        stepping = s.fmu.getFMUstate()
        s.fmu.terminate()
        ended = s.fmu.getFMUstate()
        with pytest.raises(FMICallException) as err:
            s.fmu.doStep(1e-3, 1e-3)
        assert err.value.status == 3 and "after fmi2Terminate" in s.messages()
        # a state restores the phase it was taken in
        s.fmu.setFMUstate(stepping)
        s.fmu.doStep(1e-3, 1e-3)
        s.fmu.setFMUstate(ended)
        with pytest.raises(FMICallException) as err:
            s.fmu.doStep(1e-3, 1e-3)
        assert err.value.status == 3
        s.fmu.freeFMUstate(stepping)
        s.fmu.freeFMUstate(ended)
        s.fmu.reset()                                         # and the instance is reusable
        s.fmu.setupExperiment(startTime=0.0)
        s.fmu.enterInitializationMode()
        s.set_inputs(0.0, 1.0, 0.0)
        s.fmu.exitInitializationMode()
        s.fmu.doStep(0.0, 1e-3)
    finally:
        s.free()


def test_bad_step_and_time_mismatch_are_discarded(chaindrive_fmu_dir):
    from fmpy.fmi1 import FMICallException
    s = Slave(chaindrive_fmu_dir, {}, inputs=(0.0, 1.0, 0.0))
    try:
        s.fmu.exitInitializationMode()
        for t, h in ((0.0, 0.0), (0.0, -1e-3), (0.5, 1e-3)):
            with pytest.raises(FMICallException) as err:
                s.fmu.doStep(t, h)
            assert err.value.status == 2
        s.fmu.doStep(0.0, 1e-3)                           # the right call still works
    finally:
        s.free()


def test_fixed_parameter_cannot_change_after_initialization(chaindrive_fmu_dir):
    s = Slave(chaindrive_fmu_dir, {}, inputs=(0.0, 0.0, 10.0))
    try:
        s.fmu.exitInitializationMode()
        before = s.outputs()
        s.set_parameters({"driven.inertia": 5.0})
        assert "fixed after initialization" in s.messages()
        assert s.fmu.getReal([s.var["driven.inertia"].valueReference]) == [P.BY_NAME["driven.inertia"].default]
        assert np.array_equal(s.outputs(), before)
    finally:
        s.free()


# --- packaging ---------------------------------------------------------------------------------

VENDORED_CHECK = textwrap.dedent(r"""
    import importlib.abc, json, sys
    sys.path.insert(0, FAKE_DIR)
    import chainmodel                      # another chainmodel, first on sys.path, imported
    assert chainmodel.FAKE
    from fmpy import read_model_description, extract
    from fmpy.fmi2 import FMU2Slave
    md = read_model_description(FMU)
    unzipdir = extract(FMU, UNZIP)

    allowed = set(sys.stdlib_module_names) | {"numpy", "scipy", "pythonfmu"}
    blocked = []

    class OnlyNumpyScipy(importlib.abc.MetaPathFinder):
        # from here on a Python with only the standard library, numpy, scipy and pythonfmu
        def find_spec(self, name, path=None, target=None):
            top = name.split(".")[0]
            if (top in allowed or top.startswith(("_chaindrive_", "chaindrive_"))
                    or top.startswith("_sysconfigdata_")):   # the platform part of the stdlib
                return None
            blocked.append(name)
            raise ModuleNotFoundError(f"blocked import {name}")

    sys.meta_path.insert(0, OnlyNumpyScipy())
    vr = {v.name: v.valueReference for v in md.modelVariables}
    fmu = FMU2Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier="ChainDrive",
                    instanceName="vendored")
    fmu.instantiate()
    fmu.setupExperiment(startTime=0.0)
    fmu.enterInitializationMode()
    fmu.setInteger([vr["fidelity"]], [0])
    fmu.setReal([vr["input_shaft.angle"], vr["input_shaft.speed"], vr["load.torque"]],
                [0.3, 10.0, 20.0])
    fmu.exitInitializationMode()
    fmu.doStep(0.0, 1e-3)
    out = dict(zip(["driver.angle", "driver.speed", "driven.speed"],
                   fmu.getReal([vr["driver.angle"], vr["driver.speed"], vr["driven.speed"]])))
    fmu.terminate()
    fmu.freeInstance()
    vendored = [m for m in sys.modules if m.startswith("_chaindrive_") and "." not in m
                and not m.endswith("_adapter")]
    print(json.dumps({"out": out, "blocked": blocked,
                      "chainmodel_file": sys.modules["chainmodel"].__file__,
                      "vendored": sorted(vendored),
                      "vendored_file": sys.modules[min(vendored)].__file__ if vendored else None,
                      "stray": sorted(m for m in sys.modules if m.startswith("chainmodel."))}))
    # The checks are done: leave without the interpreter's teardown, which with pythonfmu's
    # wrapper loaded aborts now and then ("corrupted double-linked list", the at-exit heap
    # corruption of PythonFMU #228; whether it shows depends on the heap layout, e.g. on the
    # length of the checkout's path)
    import os
    sys.stdout.flush()
    os._exit(0)
""")


def test_fmu_uses_its_vendored_chainmodel_and_needs_only_numpy_scipy(chaindrive_fmu, tmp_path):
    fake = tmp_path / "fake" / "chainmodel"
    fake.mkdir(parents=True)
    (fake / "__init__.py").write_text("FAKE = True  # not the ChainDrive library\n")
    script = (f"FAKE_DIR = {str(fake.parent)!r}\nFMU = {str(chaindrive_fmu)!r}\n"
              f"UNZIP = {str(tmp_path / 'unzipped')!r}\n" + VENDORED_CHECK)
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          cwd=tmp_path, timeout=120)
    assert proc.returncode == 0, proc.stderr[-3000:]
    res = json.loads(proc.stdout.strip().splitlines()[-1])
    assert res["chainmodel_file"] == str(fake / "__init__.py")     # the host's copy untouched
    assert res["stray"] == []                                       # nothing mixed into it
    assert res["vendored_file"].startswith(str(tmp_path / "unzipped" / "resources" / "_vendor"))
    # (optional imports that numpy, scipy or the library try and survive without, e.g. numba,
    # were refused by the blocker above; the FMU ran regardless: that is the point)
    # level 0: the driver follows the input shaft rigidly, the angle held at the input speed
    assert res["out"]["driver.angle"] == pytest.approx(0.3 + 10.0 * 1e-3, rel=1e-14)
    assert res["out"]["driver.speed"] == 10.0
    assert res["out"]["driven.speed"] > 0


@pytest.mark.parametrize("value", ["4", "1,x", "-1"])
def test_build_refuses_a_bad_warm_list(value, tmp_path):
    """build_fmu.py --warm takes fidelity levels 0-3 or 'none'; anything else is a usage error
    (exit 2) naming the option, before anything is built."""
    root = Path(__file__).resolve().parent.parent
    proc = subprocess.run([sys.executable, str(root / "build_fmu.py"), "--out",
                           str(tmp_path / "X.fmu"), "--warm", value],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert "--warm" in proc.stderr and value in proc.stderr
    assert not (tmp_path / "X.fmu").exists()


def test_fidelity_auto_parameters_choose_the_level_and_log_why(chaindrive_fmu_dir):
    """auto.enabled with auto.outputs / auto.accuracy (issue 11): the FMU builds the level that
    chainmodel.fidelity_auto.choose_parameters picks for the same parameters and operating
    point, and logs the choice with its expected error and source; a bad accuracy fails
    initialization naming it."""
    from chainmodel import fidelity_auto
    speed, load = 120 * math.pi / 30, 43.2
    expected, choice = fidelity_auto.choose_parameters(P.validate({}), speed, load,
                                                       "tight_span.tension", 0.2)
    s = Slave(chaindrive_fmu_dir, {"auto.enabled": True, "auto.outputs": "tight_span.tension",
                                   "auto.accuracy": 0.2, "auto.input_speed": speed,
                                   "auto.load_torque": load})
    try:
        s.fmu.exitInitializationMode()
        log = s.messages()
    finally:
        s.free()
    level = expected["fidelity"]
    assert f"fidelity {level} ({P.FIDELITY_NAMES[level]})" in log
    assert "fidelity auto: " + choice.config in log and "tradeoff.csv" in log
    log = _initialization_error(chaindrive_fmu_dir, {"auto.enabled": True, "auto.accuracy": 3.0})
    assert "accuracy" in log and "3" in log


def test_fidelity_auto_warns_when_its_target_is_not_met(chaindrive_fmu_dir):
    """An accuracy no measured configuration meets (or an error auto cannot promise) reaches
    the tool as fmi2Warning, not as an fmi2OK note in logAll a tool may hide; a met and
    promised choice stays fmi2OK. Which it is comes from the library's own choice for the same
    point (chainmodel.fidelity_auto), so the test follows the table, not a fixed answer."""
    from fmpy.fmi2 import fmi2OK, fmi2Warning
    from chainmodel import fidelity_auto
    speed, load = 120 * math.pi / 30, 43.2
    seen = {}
    for accuracy in (1e-4, 0.5):
        _, choice = fidelity_auto.choose_parameters(P.validate({}), speed, load,
                                                    "tight_span.tension", accuracy)
        s = Slave(chaindrive_fmu_dir, {"auto.enabled": True, "auto.outputs": "tight_span.tension",
                                       "auto.accuracy": accuracy, "auto.input_speed": speed,
                                       "auto.load_torque": load})
        try:
            s.fmu.exitInitializationMode()
            status = [st for st, m in s.log.messages if m.startswith("fidelity auto")]
        finally:
            s.free()
        assert len(status) == 1
        ok = choice.met and choice.promised
        seen[ok] = True
        assert status[0] == (fmi2OK if ok else fmi2Warning), (accuracy, choice.message)
    assert seen == {False: True, True: True}   # both kinds were exercised


def _initialization_warnings(fmu_dir, scene, needle, required, extra=None) -> list[str]:
    """The fmi2Warning messages holding ``needle`` that the FMU logs at initialization with
    ``scene``'s Real and Integer parameters set where they differ from its starts (``required``
    among them) and ``extra`` on top."""
    s = Slave(fmu_dir)
    try:
        values = {}
        for name, value in scene.parameters.items():
            v = s.var.get(name)
            if v is None or v.causality != "parameter" or v.type not in ("Real", "Integer"):
                continue
            cast = float if v.type == "Real" else int
            if value is not None and cast(v.start) != cast(value):
                values[name] = cast(value)
        assert required <= set(values)
        s.set_parameters(dict(values, **(extra or {})))
        s.fmu.exitInitializationMode()
        return [m for status, m in s.log.messages if status == 1 and needle in m]
    finally:
        s.free()


def test_a_chain_hanging_on_its_sag_logs_the_slack_span_warning(chaindrive_fmu_dir, tmp_path):
    """The FMU logs levels 0-1's slack_span_sag warning (chainmodel.validity) as fmi2Warning at
    initialization, for the 08B 13/39 drive with no pretension set through its parameters and
    the spans' sag off (torsional.sag_lag = false: with it, the default, levels 0-1 keep the
    slack span and nothing is warned; tests/test_wrap_statics.py checks the claim in the
    runs)."""
    from chainmodel.scene import load_scene
    from test_wrap_statics import _SAGGING_08B
    path = tmp_path / "sagging.toml"
    path.write_text(_SAGGING_08B)
    warned = _initialization_warnings(
        chaindrive_fmu_dir, load_scene(str(path), fidelity=1), "falls short of level 3's",
        {"drive.links", "drive.pitch", "chain.link_stiffness"}, {"torsional.sag_lag": False})
    assert len(warned) == 1 and "level 2 or 3" in warned[0]


def test_a_mode_moving_over_a_tooth_is_logged_as_a_warning(chaindrive_fmu_dir):
    """The trade study's 6/9-tooth drive set through the FMU's parameters at level 1: level
    3's driven-sprocket mode moves over a tooth beyond what one mode stands for, and the FMU
    logs chainmodel.validity's torsional_mode_moves as fmi2Warning at initialization, as the
    library's warnings (tests/test_mode_over_tooth.py checks the claim in the runs)."""
    from test_mode_over_tooth import COARSE
    from chainmodel.scene import load_scene
    warned = _initialization_warnings(
        chaindrive_fmu_dir, load_scene("xu2010", fidelity=1, **COARSE),
        "moves over a driver tooth", {"drive.driver_teeth", "drive.driven_teeth", "drive.links"})
    assert len(warned) == 1 and "Run level 3" in warned[0]


def test_a_chain_value_far_from_its_chain_is_logged_as_a_warning(chaindrive_fmu_dir):
    """A link mass typed in grams set through the FMU's parameters (xu2010's 15.875 mm pitch,
    whose ISO 606 chains have about 0.02 kg per link) is logged as fmi2Warning at
    initialization: chainmodel.validity's implausible_value, as the library's warnings."""
    s = Slave(chaindrive_fmu_dir)
    try:
        s.set_parameters({"chain.link_mass": 16.2, "fidelity": 0})
        s.fmu.exitInitializationMode()
        warned = [m for status, m in s.log.messages if status == 1 and "a unit slip?" in m]
        assert len(warned) == 1 and "chain.link_mass = 16.2 kg" in warned[0]
    finally:
        s.free()
