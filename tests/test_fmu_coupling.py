"""ChainDrive.fmu in a system model, angle causality (issue 18 items 3 and 4): a Jacobi master
written here couples the example system's Motor FMU (examples/system/Motor.py: a PI-controlled
rotor fed input_shaft.torque, giving input_shaft.angle and .speed) to ChainDrive through fmpy.
At a too-large step the FMU stops with the coupling message naming a step that holds, before
the tensions pass the chain's breaking load; at that step the same system runs. ModelStructure's
dependencies are checked by perturbing each input within a communication point."""

from __future__ import annotations

import math
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from chainmodel import parameters as P
from chainmodel.cosim import stable_step
from chainmodel.scene import drive_from_parameters
from chainmodel.validity import breaking_load

pytestmark = pytest.mark.fmu

ROOT = Path(__file__).resolve().parents[1]
SET_POINT = 4 * math.pi     # Motor's default speed_reference [rad/s]


@pytest.fixture(scope="module")
def motor_fmu(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("system")
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / "system" / "build.py"),
                           "--out", str(out), "--launch"], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    return out / "Motor.fmu"


class Slave:
    """An fmpy FMU2Slave by variable names, keeping what the FMU logs."""

    def __init__(self, path, name, start):
        from fmpy import extract, read_model_description
        from fmpy.fmi2 import FMU2Slave

        from chainmodel.fmu_log import FMULog
        md = read_model_description(str(path))
        self.md = md
        self.folder = extract(str(path))
        self.vr = {v.name: v.valueReference for v in md.modelVariables}
        types = {v.name: v.type for v in md.modelVariables}
        self.log = FMULog()
        self.fmu = FMU2Slave(guid=md.guid, unzipDirectory=self.folder, instanceName=name,
                             modelIdentifier=md.coSimulation.modelIdentifier)
        self.fmu.instantiate(callbacks=self.log.callbacks, loggingOn=True)
        self.fmu.setupExperiment(startTime=0.0)
        self.fmu.enterInitializationMode()
        for key, value in start.items():
            {"Real": self.fmu.setReal, "Integer": self.fmu.setInteger,
             "Boolean": self.fmu.setBoolean, "String": self.fmu.setString}[types[key]](
                [self.vr[key]], [value])
        self.fmu.exitInitializationMode()

    def get(self, name):
        return self.fmu.getReal([self.vr[name]])[0]

    def put(self, name, value):
        self.fmu.setReal([self.vr[name]], [value])

    def step(self, t, h) -> bool:
        from fmpy.fmi1 import FMICallException
        try:
            self.fmu.doStep(currentCommunicationPoint=t, communicationStepSize=h)
            return True
        except FMICallException:
            return False

    def text(self) -> str:
        return " ".join(m for _, m in self.log.messages)

    def close(self):
        self.fmu.terminate()
        self.fmu.freeInstance()
        shutil.rmtree(self.folder, ignore_errors=True)


def jacobi(chaindrive, motor_fmu, J, h, level, duration, chain_start=None):
    """Motor + ChainDrive (load torque 10 N.m), Jacobi: both FMUs get the other's outputs of
    the same communication point, then both step. Returns (steps done, steps asked, largest
    tight-span tension read, motor speed at the end, ChainDrive's log)."""
    kp, ki = 2 * 50 * (J + 0.004), 50 ** 2 * (J + 0.004)   # Motor.py's pole placement
    motor = Slave(motor_fmu, "Motor", {"motor.inertia": J, "controller.kp": kp,
                                       "controller.ki": ki})
    chain = Slave(chaindrive, "ChainDrive", dict({"fidelity": level}, **(chain_start or {})))
    n, done, peak = round(duration / h), 0, 0.0
    try:
        chain.put("load.torque", 10.0)
        for k in range(n):
            chain.put("input_shaft.angle", motor.get("rotor.angle"))
            chain.put("input_shaft.speed", motor.get("rotor.speed"))
            motor.put("shaft.torque", chain.get("input_shaft.torque"))
            peak = max(peak, chain.get("tight_span.tension"))
            if not (chain.step(k * h, h) and motor.step(k * h, h)):
                break
            done += 1
        speed = motor.get("rotor.speed")
        text = chain.text()
    finally:
        motor.close()
        chain.close()
    return done, n, peak, speed, text


def test_a_too_large_step_stops_with_the_coupling_message_and_its_step_holds(
        chaindrive_fmu, motor_fmu):
    J, level = 0.01, 1
    params = P.validate({"fidelity": level})
    done, n, peak, _, text = jacobi(chaindrive_fmu, motor_fmu, J, 1e-3, level, 0.1)
    assert done < n
    assert "co-simulation coupling unstable" in text, text[-2000:]
    assert "not the chain drive or its speed limits" in text
    assert "fidelity 3" not in text and "link_stiffness" not in text   # no wrong advice
    # stopped before absurd values: below the chain's breaking load (ISO 606 for this pitch)
    assert peak < breaking_load(drive_from_parameters(params), params)[0]
    m = re.search(r"([0-9.e-]+) s for J = 0.01 kg.m2", text)
    assert m, text[-2000:]
    h_ok = float(m.group(1))
    assert h_ok == pytest.approx(stable_step(J, params), rel=5e-3)   # printed to 3 digits
    done, n, _, speed, text = jacobi(chaindrive_fmu, motor_fmu, J, h_ok, level, 0.1)
    assert done == n, text[-2000:]
    assert abs(speed - SET_POINT) < 0.1 * SET_POINT     # the PI motor reached its set point


def test_the_fmu_reports_the_stable_step_for_the_motor_inertia_given(chaindrive_fmu):
    from fmpy import simulate_fmu
    for J in (0.001, 0.01):
        res = simulate_fmu(str(chaindrive_fmu), stop_time=1e-3, step_size=1e-4,
                           start_values={"fidelity": 1, "coupling.motor_inertia": J},
                           output=["coupling.max_step"])
        params = P.validate({"fidelity": 1})
        k, I = params["input_shaft.stiffness"], params["driver.inertia"]
        assert res["coupling.max_step"][-1] == pytest.approx(
            0.4 / math.sqrt(k * (1 / J + 1 / I)), rel=1e-12)
    res = simulate_fmu(str(chaindrive_fmu), stop_time=1e-3, step_size=1e-4,
                       start_values={"fidelity": 0, "coupling.motor_inertia": 0.01},
                       output=["coupling.max_step"])
    assert res["coupling.max_step"][-1] == 0.0      # no spring at level 0


def _level0_inertia(params) -> float:
    """The drive's inertia at the input shaft at level 0 at angle 0, from the model's own
    input_shaft.torque: its change per unit input acceleration (it is linear in it)."""
    from chainmodel.models import MODEL_CLASSES
    model = MODEL_CLASSES[0](drive_from_parameters(params), params)
    out = [model.evaluate(0.0, 1.0, a, 0.0)["input_shaft.torque"] for a in (0.0, 1.0)]
    return float(out[1] - out[0])


def test_level_0_a_light_rotor_fails_and_holds_once_the_motor_carries_the_drive_inertia(
        chaindrive_fmu, motor_fmu):
    """At level 0 input_shaft.torque carries I_eff times the backward-difference acceleration
    of the speed input: a rotor lighter than I_eff makes dw_k = -(I_eff/J) dw_(k-1), unstable
    at every step. With input_shaft.include_drive_inertia = false the torque leaves it out and
    a motor model whose rotor carries it (J + I_eff) runs at 1 ms."""
    params = P.validate({"fidelity": 0})
    I_eff = _level0_inertia(params)
    assert I_eff > params["driver.inertia"]          # driver plus the reflected driven side
    J = 0.25 * I_eff
    done, n, _, _, text = jacobi(chaindrive_fmu, motor_fmu, J, 1e-3, 0, 0.1)
    assert done < n and "co-simulation coupling unstable" in text, text[-2000:]
    assert "backward-difference acceleration" in text
    done, n, _, speed, text = jacobi(chaindrive_fmu, motor_fmu, J + I_eff, 1e-3, 0, 0.2,
                                     {"input_shaft.include_drive_inertia": False})
    assert done == n, text[-2000:]
    assert abs(speed - SET_POINT) < 0.1 * SET_POINT


def _structure(md):
    """{output name: set of input names} from ModelStructure/Outputs."""
    return {u.variable.name: {d.name for d in (u.dependencies or [])} for u in md.outputs}


@pytest.mark.parametrize("level,rigid", [(0, False), (1, False), (1, True), (2, False)])
def test_model_structure_lists_exactly_what_moves_within_a_step(chaindrive_fmu, level, rigid):
    """Perturb one input at a communication point (after 20 steps of a ramp under load) and
    read the outputs again, before any step: every output that moves lists that input in
    ModelStructure (sound); and over these levels every listed dependency moves at least once
    (checked in the last case: exact)."""
    from fmpy import read_model_description
    md = read_model_description(str(chaindrive_fmu))
    listed = _structure(md)
    chain = Slave(chaindrive_fmu, "ChainDrive", {"fidelity": level, "input_shaft.rigid": rigid})
    inputs = ("input_shaft.angle", "input_shaft.speed", "load.torque")
    outputs = list(listed)
    h = 1e-4
    try:
        for k in range(20):
            t = k * h
            chain.put("input_shaft.angle", t + 100 * t * t)
            chain.put("input_shaft.speed", 1 + 200 * t)
            chain.put("load.torque", 20 + 0.1 * k)
            assert chain.step(t, h)
        values = [chain.get(n) for n in inputs]
        for name, value in zip(inputs, values):   # the same inputs again: the outputs are
            chain.put(name, value)                # recomputed as for a perturbed one (the
        base = [chain.get(n) for n in outputs]    # step's own may differ in the last bit)
        moved = {}
        for name, value in zip(inputs, values):
            chain.put(name, value + 1e-3 * (1 + abs(value)))
            row = [chain.get(n) for n in outputs]
            chain.put(name, value)
            moved[name] = {o for o, a, b in zip(outputs, base, row) if a != b}
    finally:
        chain.close()
    for name, outs in moved.items():
        for o in outs:
            assert name in listed[o], f"{o} moves with {name} at level {level} but does not list it"
    MOVED.setdefault("all", {}).update({(level, rigid): moved})
    if len(MOVED["all"]) == 4:
        for o, deps in listed.items():
            for name in deps:
                assert any(o in m[name] for m in MOVED["all"].values()), \
                    f"{o} lists {name} but never moves with it"
    # levels 1-3 with the shaft spring: the sprockets' motion is the state's, not the inputs'
    if level >= 1 and not rigid:
        for o in ("driver.angle", "driven.angle", "driven.speed"):
            assert not any(o in m for m in moved.values()), o


MOVED: dict = {}


def test_libcosim_shows_the_coupling_message(chaindrive_fmu, capfd):
    """libcosim instantiates with logging off and reports only a failed step: the FMU writes
    the unstable coupling (once per instance) to stderr. The speed input here is what an
    unstable coupling sets: an oscillation of 6.3 steps per period growing 1.2 times a step."""
    from chainmodel.fmu_hosts import HostUnavailable, run_fmu
    k = np.arange(101)
    speed = 1e-2 * np.cumsum(1.2 ** k * np.cos(k))
    try:
        with pytest.raises(RuntimeError, match="failed"):
            run_fmu(chaindrive_fmu, "libcosim", stop_time=0.05, step_size=5e-4,
                    inputs={"input_shaft.speed": speed}, start_values={"fidelity": 1})
    except HostUnavailable as exc:   # pragma: no cover - libcosimpy is in the test extra
        pytest.fail(str(exc))
    err = capfd.readouterr().err
    assert "co-simulation coupling unstable" in err and "torque causality" in err
