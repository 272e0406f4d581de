"""chainmodel.fmu_model_description: the modelDescription.xml completion build_fmu.py applies to
what pythonfmu writes (units, display units, ModelStructure with each output's dependencies),
tested on a small XML written here, and the dependency table found by perturbation."""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET

import pytest

from chainmodel import fmu_model_description as D

XML = b"""<?xml version="1.0" encoding="UTF-8"?>
<fmiModelDescription fmiVersion="2.0" modelName="X" guid="{0}" generationTool="PythonFMU">
  <CoSimulation modelIdentifier="X"/>
  <DefaultExperiment startTime="0" stopTime="1.0000000000000000" stepSize="0.0001"/>
  <ModelVariables>
    <ScalarVariable name="input_shaft.angle" valueReference="0" causality="input" description="in a">
      <Real start="0.0"/></ScalarVariable>
    <ScalarVariable name="load.torque" valueReference="1" causality="input" description="in T">
      <Real start="0.0"/></ScalarVariable>
    <ScalarVariable name="driver.speed" valueReference="2" causality="output">
      <Real/></ScalarVariable>
    <ScalarVariable name="input_shaft.torque" valueReference="3" causality="output">
      <Real/></ScalarVariable>
    <ScalarVariable name="coupling.max_step" valueReference="4" causality="calculatedParameter"
        variability="fixed" initial="calculated" description="h">
      <Real/></ScalarVariable>
  </ModelVariables>
</fmiModelDescription>
"""


def _meta(**extra):
    meta = {"version": "9.9", "levels": [0, 1], "names": {0: "kinematic", 1: "torsional"},
            "units": {"input_shaft.angle": "rad", "load.torque": "N.m", "driver.speed": "rad/s",
                      "input_shaft.torque": "N.m", "coupling.max_step": "s"},
            "display": {"driver.speed": "rpm"}, "parameters": {},
            "output_notes": {"driver.speed": "speed [rad/s]", "input_shaft.torque": "T [N.m]"}}
    meta.update(extra)
    return meta


def test_base_units_and_exact_numbers():
    assert D.base_unit("N.m.s/rad") == {"kg": 1, "m": 2, "s": -1, "rad": -1}
    assert D.base_unit("kg.m2") == {"kg": 1, "m": 2}
    assert D.base_unit("1") == {}
    with pytest.raises(ValueError, match="unknown symbol"):
        D.base_unit("furlong/s")
    for value in (0.1, 1e-4, 2.0 / 3.0, 12000.0, math.pi):
        assert float(D.fmt(value)) == value
    assert D.fmt(12000.0) == "12000"


def test_completion_writes_units_dependencies_and_initial_unknowns():
    deps = {"driver.speed": [], "input_shaft.torque": ["input_shaft.angle", "load.torque"]}
    root = ET.fromstring(D.complete_model_description(XML, _meta(dependencies=deps)))
    assert [c.tag for c in root] == ["CoSimulation", "UnitDefinitions", "DefaultExperiment",
                                     "ModelVariables", "ModelStructure"]
    units = {u.get("name"): u for u in root.find("UnitDefinitions")}
    assert units["N.m"].find("BaseUnit").attrib == {"kg": "1", "m": "2", "s": "-2"}
    rpm = units["rad/s"].find("DisplayUnit")
    assert rpm.get("name") == "rpm" and float(rpm.get("factor")) == 60 / (2 * math.pi)
    sv = {v.get("name"): v for v in root.find("ModelVariables")}
    assert sv["driver.speed"].get("description") == "speed [rad/s]"
    assert sv["driver.speed"][0].get("displayUnit") == "rpm"
    assert root.find("DefaultExperiment").get("stopTime") == "1"
    outs = root.find("ModelStructure/Outputs")
    # indices are 1-based positions in ModelVariables: inputs 1 and 2, outputs 3 and 4
    assert [(u.get("index"), u.get("dependencies")) for u in outs] == [("3", ""), ("4", "1 2")]
    init = root.find("ModelStructure/InitialUnknowns")
    assert [u.get("index") for u in init] == ["3", "4", "5"]     # outputs + calculated param


def test_completion_without_a_dependency_table_claims_every_input():
    root = ET.fromstring(D.complete_model_description(XML, _meta()))
    assert all(u.get("dependencies") is None for u in root.find("ModelStructure/Outputs"))


def test_a_real_without_unit_is_refused_naming_it():
    meta = _meta()
    del meta["units"]["input_shaft.torque"]
    with pytest.raises(D.DescriptionError, match="input_shaft.torque"):
        D.complete_model_description(XML, meta)


def test_level_0_dependencies_follow_its_kinematics():
    """Level 0: the driver follows the input angle rigidly (driver.angle = input angle,
    driver.speed = input speed), the driven sprocket's angle is a function of the input angle
    alone (the four-bar kinematics), and the torque balance takes the load torque."""
    deps = D.output_dependencies(levels=[0])
    assert deps["driver.angle"] == ["input_shaft.angle"]
    assert deps["driver.speed"] == ["input_shaft.speed"]
    assert deps["driven.angle"] == ["input_shaft.angle"]
    assert deps["input_shaft.torque"] == ["input_shaft.angle", "input_shaft.speed",
                                          "load.torque"]
