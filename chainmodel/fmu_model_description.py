"""The modelDescription.xml of ChainDrive.fmu: what pythonfmu does not write (build_fmu.py).

:func:`complete_model_description` adds unit definitions with SI base units and display units, a
unit on every Real, min/max of the parameters, explicit causality / variability / initial, output
descriptions that say at which fidelity levels each output is a quasi-static estimate,
ModelStructure (each output's direct dependencies on the inputs, :func:`output_dependencies`),
DefaultExperiment and the capability flags. :func:`library_metadata` collects what it needs from
this package. No physics here: the dependencies are found by perturbing the models' inputs.
"""

from __future__ import annotations

import math
import re
import sys
import xml.etree.ElementTree as ET


class DescriptionError(ValueError):
    """The adapter's variables cannot be described (a missing unit or description)."""


#: SI base-unit exponents of the unit symbols the schema and the outputs use
BASE = {"kg": {"kg": 1}, "m": {"m": 1}, "s": {"s": 1}, "rad": {"rad": 1}, "A": {"A": 1},
        "K": {"K": 1}, "mol": {"mol": 1}, "cd": {"cd": 1},
        "N": {"kg": 1, "m": 1, "s": -2}, "J": {"kg": 1, "m": 2, "s": -2},
        "W": {"kg": 1, "m": 2, "s": -3}, "Pa": {"kg": 1, "m": -1, "s": -2}, "Hz": {"s": -1}}
#: display units: name -> (unit, factor) with value_display = factor * value
DISPLAY = {"mm": ("m", 1000.0), "deg": ("rad", 180.0 / math.pi),
           "rpm": ("rad/s", 60.0 / (2.0 * math.pi))}
#: inputs and outputs shown in rpm by tools that honour displayUnit
SPEED_DISPLAY = {"input_shaft.speed": "rpm", "driver.speed": "rpm", "driven.speed": "rpm",
                 "motor.speed": "rpm", "auto.input_speed": "rpm"}
#: min / max of the adapter's own Real parameters (None: unbounded), as the adapter checks them:
#: auto.accuracy in (0, 1] (fidelity_auto.validate_request), coupling.motor_inertia >= 0 (0:
#: unknown). FMI's min is inclusive, so an open end at 0 is declared as 0, as for the library's
#: parameters that must be positive; the adapter refuses 0 naming the range.
ADAPTER_RANGES = {"auto.accuracy": (0.0, 1.0), "coupling.motor_inertia": (0.0, None)}
CAPABILITIES = {"needsExecutionTool": "true",   # a Python with numpy and scipy
                "canHandleVariableCommunicationStepSize": "true",
                "canInterpolateInputs": "false", "maxOutputDerivativeOrder": "0",
                "canRunAsynchronuously": "false", "canBeInstantiatedOnlyOncePerProcess": "false",
                "canNotUseMemoryManagementFunctions": "true", "canGetAndSetFMUstate": "true",
                "canSerializeFMUstate": "true", "providesDirectionalDerivative": "false"}


def base_unit(unit: str) -> dict[str, int]:
    """SI base-unit exponents of a unit written like 'N.m.s/rad', 'm/s2', 'kg.m2' ('1': none)."""
    if unit in ("", "1"):
        return {}
    if unit.count("/") > 1:
        raise ValueError(f"unit {unit!r}: write at most one '/'")
    exps: dict[str, int] = {}
    for sign, part in zip((1, -1), unit.split("/")):
        for factor in part.split("."):
            m = re.fullmatch(r"([A-Za-z]+)(-?\d+)?", factor)
            if not m or m.group(1) not in BASE:
                raise ValueError(f"unit {unit!r}: unknown symbol {factor!r}; add it to "
                                 "chainmodel.fmu_model_description.BASE")
            power = sign * int(m.group(2) or 1)
            for b, e in BASE[m.group(1)].items():
                exps[b] = exps.get(b, 0) + e * power
    return {b: e for b, e in exps.items() if e}


def fmt(value: float) -> str:
    """Shortest exact text of a float (repr), as FMI tools parse it back to the same double."""
    text = repr(float(value))
    return text[:-2] if text.endswith(".0") and "e" not in text else text


# --- metadata from the library ---------------------------------------------------------------

def library_metadata() -> dict:
    """Units, display units and output notes from the chainmodel being vendored."""
    from . import __version__
    from . import parameters as P
    from .models import ALL_OUTPUTS, MODEL_CLASSES
    from .models.base import QUASI_STATIC
    from .scene import drive_from_parameters

    units = {o.name: o.unit or "1" for o in ALL_OUTPUTS}
    units.update({"input_shaft.angle": "rad", "input_shaft.speed": "rad/s", "load.torque": "N.m"})
    from .models.torque_causality import MOTOR_INPUT, MOTOR_OUTPUTS
    units.update({o.name: o.unit for o in (MOTOR_INPUT, *MOTOR_OUTPUTS)})
    from .fidelity_auto import FMU_UNITS    # the adapter's auto.* parameters
    units.update(FMU_UNITS)
    from .cosim import FMU_UNITS as COUPLING_UNITS    # the adapter's coupling.* variables
    units.update(COUPLING_UNITS)
    display = dict(SPEED_DISPLAY)
    for p in P.PARAMETERS:
        if p.kind is float:
            units[p.name] = p.unit or "1"
            if p.display_unit:
                display[p.name] = p.display_unit
    params = P.validate({})
    drive = drive_from_parameters(params, "defaults")
    quasi = {o.name: [] for o in ALL_OUTPUTS}
    levels = sorted(MODEL_CLASSES)
    for level in levels:
        try:
            descriptions = MODEL_CLASSES[level](drive, dict(params, fidelity=level)).output_descriptions()
        except Exception as exc:  # a level under construction must not break the build
            print(f"warning: cannot describe fidelity {level}: {exc}", file=sys.stderr)
            continue
        for name, text in descriptions.items():
            if name in quasi and text.startswith(QUASI_STATIC):
                quasi[name].append(level)
    notes = {}
    for o in ALL_OUTPUTS:
        text = f"{o.description} [{o.unit or '1'}]"
        q = quasi[o.name]
        computed = [k for k in levels if k not in q]
        if q:
            text += ("; quasi-static estimate at fidelity " + ", ".join(map(str, q))
                     + (", computed at " + ", ".join(map(str, computed)) if computed else ""))
        notes[o.name] = text
    notes.update({o.name: f"{o.description} [{o.unit}]" for o in MOTOR_OUTPUTS})
    return {"units": units, "display": display, "output_notes": notes, "levels": levels,
            "names": P.FIDELITY_NAMES, "version": __version__,
            "parameters": {p.name: p for p in P.PARAMETERS}}


def complete_model_description(xml: bytes, meta: dict) -> bytes:
    """Add what pythonfmu does not write (see the module docstring)."""
    root = ET.fromstring(xml)
    root.set("variableNamingConvention", "structured")
    root.set("generationTool", root.get("generationTool", "PythonFMU") + " + build_fmu.py")
    root.set("version", meta["version"])
    levels = ", ".join(f"{k} ({meta['names'][k]})" for k in meta["levels"])
    root.set("description", root.get("description", "") + f" Levels in this build: {levels}.")
    cosim = root.find("CoSimulation")
    for key, value in CAPABILITIES.items():
        cosim.set(key, value)

    variables = root.find("ModelVariables").findall("ScalarVariable")
    units, display, params = meta["units"], meta["display"], meta["parameters"]
    used: dict[str, set] = {}
    outputs = []
    calculated = []      # calculated parameters: initial unknowns too
    inputs: dict[str, int] = {}
    for index, sv in enumerate(variables, start=1):
        name = sv.get("name")
        typ = next(iter(sv))
        causality = sv.get("causality") or "local"
        if causality == "output":
            outputs.append(index)
            sv.set("description", meta["output_notes"][name])
            sv.set("variability", "continuous")
            sv.set("initial", "calculated")
        elif causality == "input":
            inputs[name] = index
            sv.set("variability", "continuous")
            sv.attrib.pop("initial", None)
        elif causality == "parameter":
            sv.set("initial", "exact")
        elif causality == "calculatedParameter":
            calculated.append(index)
        if not sv.get("description"):
            raise DescriptionError(f"variable {name} has no description")
        if typ.tag == "Real":
            unit = units.get(name)
            if unit is None:
                raise DescriptionError(f"no unit known for Real variable {name}")
            typ.set("unit", unit)
            used.setdefault(unit, set())
            if name in display:
                du = display[name]
                if du not in DISPLAY or DISPLAY[du][0] != unit:
                    raise DescriptionError(f"display unit {du!r} of {name} is not defined "
                                     f"for unit {unit!r}; add it to chainmodel.fmu_model_description.DISPLAY")
                typ.set("displayUnit", du)
                used[unit].add(du)
            if name in params:   # exact default (pythonfmu rounds to 16 digits)
                typ.set("start", fmt(meta.get("defaults", {}).get(name, params[name].default)))
            elif typ.get("start") is not None:
                typ.set("start", fmt(float(typ.get("start"))))
        if name in ADAPTER_RANGES and typ.tag == "Real":
            low, high = ADAPTER_RANGES[name]
            if low is not None:
                typ.set("min", fmt(low))
            if high is not None:
                typ.set("max", fmt(high))
        if name in params and typ.tag in ("Real", "Integer"):
            p = params[name]
            conv = fmt if typ.tag == "Real" else (lambda v: str(int(v)))
            if p.minimum is not None:
                typ.set("min", conv(p.minimum))
            if p.maximum is not None:
                typ.set("max", conv(p.maximum))
    # every unit the build knows a display unit for offers it
    for du, (unit, _) in DISPLAY.items():
        if unit in used:
            used[unit].add(du)

    unit_defs = ET.Element("UnitDefinitions")
    for unit in sorted(used):
        u = ET.SubElement(unit_defs, "Unit", name=unit)
        ET.SubElement(u, "BaseUnit", {k: str(v) for k, v in sorted(base_unit(unit).items())})
        for du in sorted(used[unit]):
            ET.SubElement(u, "DisplayUnit", name=du, factor=fmt(DISPLAY[du][1]))

    structure = ET.Element("ModelStructure")
    outs = ET.SubElement(structure, "Outputs")
    init = ET.SubElement(structure, "InitialUnknowns")
    deps = meta.get("dependencies")
    for index in outputs:
        # Outputs: the inputs each output depends on directly (output_dependencies); without
        # that table no attribute, i.e. every input. InitialUnknowns: no attribute (parameters
        # and inputs all matter before the first step).
        attrs = {"index": str(index)}
        if deps is not None:
            name = variables[index - 1].get("name")
            attrs["dependencies"] = " ".join(str(inputs[n]) for n in deps.get(name, ())
                                             if n in inputs)
        ET.SubElement(outs, "Unknown", attrs)
    for index in sorted(outputs + calculated):
        ET.SubElement(init, "Unknown", index=str(index))

    default = root.find("DefaultExperiment")
    if default is None:
        raise DescriptionError("the adapter defines no default experiment")
    for key in ("startTime", "stopTime", "stepSize", "tolerance"):
        if default.get(key) is not None:
            default.set(key, fmt(float(default.get(key))))

    # schema order: CoSimulation, UnitDefinitions, LogCategories, DefaultExperiment,
    # ModelVariables, ModelStructure
    keep = {child.tag: child for child in root}
    for child in list(root):
        root.remove(child)
    for tag in ("CoSimulation", "UnitDefinitions", "LogCategories", "DefaultExperiment",
                "ModelVariables", "ModelStructure"):
        node = {"UnitDefinitions": unit_defs, "ModelStructure": structure}.get(tag, keep.get(tag))
        if node is not None:
            root.append(node)
    ET.indent(root, space="  ")
    return b'<?xml version="1.0" encoding="UTF-8"?>\n' + ET.tostring(root, encoding="utf-8")


def output_dependencies(levels=None) -> dict[str, list[str]]:
    """Each output's direct dependencies on the FMU's inputs (``cosim.INPUTS``): the inputs whose
    change at a communication point changes the output at that point, before any step (what
    ModelStructure/Outputs lists). Found, not assumed: at every level (levels 1-3 with and
    without ``input_shaft.rigid``) the session is brought to a generic state (a ramp under load,
    20 steps of 0.1 ms), then each input is perturbed alone and the outputs that move are
    recorded; the union over the configurations is returned. The speed input moves outputs
    also through the acceleration estimate (backward difference), as in the FMU."""
    from . import parameters as P
    from .cosim import INPUTS, CosimSession
    from .models import ALL_OUTPUTS, MODEL_CLASSES
    from .models.torque_causality import MOTOR_OUTPUTS
    # motor.angle/motor.speed: in angle causality the inputs as set (torque causality: the
    # rotor's state, and motor.torque drives only its acceleration: no output depends on it
    # directly, so it is no input of this table)
    names = [o.name for o in ALL_OUTPUTS] + [o.name for o in MOTOR_OUTPUTS]

    def outputs(session):
        return list(session.outputs()) + list(session.motor_values(fresh=True))

    deps: dict[str, set] = {n: set() for n in names}
    for level in (sorted(MODEL_CLASSES) if levels is None else levels):
        for rigid in ((False,) if level == 0 else (False, True)):
            params = P.validate({"fidelity": level, "input_shaft.rigid": rigid})
            session = CosimSession()
            h = 1e-4
            for k in range(21):
                speed = 200.0 * k * h + 1.0
                session.set_inputs(k * h + 100.0 * (k * h) ** 2, speed, 20.0 + 0.1 * k)
                if k == 0:
                    session.build(params, 0.0)
                if k < 20:
                    session.step(k * h, h)
            base = outputs(session)
            values = [session.angle, session.speed, session.torque]
            for j, name in enumerate(INPUTS):
                moved = list(values)
                moved[j] += 1e-3 * (1.0 + abs(moved[j]))
                session.set_inputs(*moved)
                row = outputs(session)
                for n, a, b in zip(names, base, row):
                    if a != b:
                        deps[n].add(name)
            session.set_inputs(*values)
    return {n: [i for i in INPUTS if i in deps[n]] for n in names}
