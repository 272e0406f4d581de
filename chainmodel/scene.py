"""Scenes: a drive, its parameters, an operating point, a fidelity level and a solver.

A scene is what a user runs. It comes from a preset name (``xu2010``, ``C1``, ...) or a TOML
file, with overrides, and turns into a ready model and stepper. TOML layout (SI units; the speed
is given in rpm because that is how drives are specified)::

    name = "my drive"
    preset = "xu2010"            # optional: start from a preset's drive and values
    fidelity = "multibody"       # or 0-3
    duration = 1.0               # s
    output_interval = 1e-4       # s, communication step
    [operating]
    input_speed_rpm = 120        # steady input-shaft speed
    ramp_time = 0.05             # s, linear ramp from rest
    load_torque = 43.2           # N.m on the driven shaft
    static_tension = 500         # N, optional: set chain.pretension to reach this at rest
    [parameters]
    "chain.link_damping" = 100   # any name of chainmodel.parameters

Every value is validated where it enters; errors name the key and the valid range.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field, replace
from functools import lru_cache
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from . import parameters as P
from .geometry import Drive, check_positive
from .integrate import Stepper, make_stepper
from .models import Inputs, Model, model_class
from .presets import INCH, preset, preset_names, reference_values

__all__ = ["Scene", "load_scene", "scene_names", "drive_from_parameters", "OperatingPoint"]

RPM = 2 * math.pi / 60


@dataclass(frozen=True)
class OperatingPoint:
    """Input-shaft speed profile and load: linear ramp from rest to ``speed`` over ``ramp_time``,
    then constant; constant load torque."""

    speed: float = 120 * RPM      # rad/s
    ramp_time: float = 0.05       # s
    load_torque: float = 43.2     # N.m

    def __post_init__(self):
        for name, v in (("input_speed", self.speed), ("load_torque", self.load_torque)):
            if not math.isfinite(v):
                raise ValueError(f"{name} must be finite, got {v!r}")
        check_positive("ramp_time", self.ramp_time, allow_zero=True)

    def inputs(self, t: float) -> Inputs:
        w, tr = self.speed, self.ramp_time
        if tr > 0 and t < tr:
            return Inputs(0.5 * w / tr * t * t, w * t / tr, self.load_torque, w / tr)
        angle = w * (t - tr) + (0.5 * w * tr if tr > 0 else 0.0)
        return Inputs(angle, w, self.load_torque, 0.0)

    def input_arrays(self, times) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """:meth:`inputs` at many times at once: arrays (angle, speed, acceleration, torque),
        the same formulas in the same order, so the same numbers."""
        t = np.asarray(times, float)
        w, tr = self.speed, self.ramp_time
        angle = w * (t - tr) + (0.5 * w * tr if tr > 0 else 0.0)
        speed = np.full(t.shape, float(w))
        acc = np.zeros(t.shape)
        if tr > 0:
            ramp = t < tr
            angle = np.where(ramp, 0.5 * w / tr * t * t, angle)
            speed = np.where(ramp, w * t / tr, speed)
            acc = np.where(ramp, w / tr, acc)
        return angle, speed, acc, np.full(t.shape, float(self.load_torque))


def drive_from_parameters(params: Mapping[str, Any], name: str = "") -> Drive:
    """The Drive the drive.* parameters describe (centre distance 0: the tight distance)."""
    return _drive(params["drive.driver_teeth"], params["drive.driven_teeth"],
                  params["drive.pitch"], params["drive.links"], params["drive.centre_distance"],
                  name)


@lru_cache(maxsize=64)
def _drive(n1, n2, p, links, a, name) -> Drive:
    # Cached: a Drive is immutable, and building one checks that the chain wraps it (the
    # wrapping length's minimum over a tooth period, ~20 ms) - which every simulate() call of
    # a scene would otherwise repeat.
    if a == 0:
        return Drive.from_links(n1, n2, p, links, name=name)
    return Drive.from_centre_distance(n1, n2, p, a, links, name=name)


def _table2_values(drive: Drive) -> dict[str, Any]:
    """Seed 004 Table 2 values for the 25.4 mm-pitch drives of seeds 000 and 004."""
    t2 = reference_values("dynamic_params_jsv2016_table2.csv")
    d1 = 15.88e-3  # ISO 606 16B roller diameter
    return {"chain.link_mass": t2["rhoA"] * drive.pitch,
            "chain.link_stiffness": t2["EA"] / drive.pitch,
            "chain.roller_radius": d1 / 2, "contact.seat_radius": 0.505 * d1,
            "driven.inertia": t2["J1"], "driven.damping": t2["d1"],
            "driver.inertia": t2["J1"], "input_shaft.rigid": True,
            # seed 004's model joins the spans rigidly to the sprockets (no seat compliance)
            "torsional.seat_compliance": False}


def _preset_scene(name: str) -> dict[str, Any]:
    if name == "xu2010":
        v = reference_values("multibody_example_xu2010.csv")
        return dict(name="xu2010", parameters={}, duration=1.0, output_interval=1e-4,
                    operating=OperatingPoint(v["input_speed"] * RPM, v["ramp_time"], v["M_load"]),
                    notes=["seed 003 section 7; centre distance 197.7 mm as in the paper"])
    drive = preset(name)
    params = {"drive.driver_teeth": drive.n_driver, "drive.driven_teeth": drive.n_driven,
              "drive.pitch": drive.pitch, "drive.centre_distance": drive.centre_distance}
    notes = []
    if drive.links is None:
        from .kinematics import wrap_length_range
        links = round(wrap_length_range(drive)[1] / drive.pitch)
        params.update({"drive.links": links, "drive.centre_distance": 0.0})
        notes.append(f"preset {name} gives no link count: {links} links (nearest the wrapping "
                     "length) at the distance where they wrap tightly")
    else:
        params["drive.links"] = drive.links
    static = None
    if abs(drive.pitch - INCH) < 1e-12:
        params.update(_table2_values(drive))
        t2 = reference_values("dynamic_params_jsv2016_table2.csv")
        static = t2["P_tot"] / 2
        load = drive.driven.pitch_radius * t2["f1"]
        op = OperatingPoint(400 * RPM, 0.05, load)
        notes.append("seed 004 Table 2 dynamic values (400 rpm, brake load 200 N, "
                     "P_tot = 1000 N shared by the two spans)")
    else:
        op = OperatingPoint()
    return dict(name=name, parameters=params, duration=1.0, output_interval=1e-4, operating=op,
                static_tension=static, notes=notes)


def scene_names() -> list[str]:
    return preset_names()


@dataclass
class Scene:
    """A runnable scene (see module docstring)."""

    name: str
    parameters: dict[str, Any]
    operating: OperatingPoint = field(default_factory=OperatingPoint)
    duration: float = 1.0
    output_interval: float = 1e-4
    notes: list[str] = field(default_factory=list)

    def __post_init__(self):
        self.parameters = P.validate(self.parameters)
        check_positive("duration", self.duration)
        check_positive("output_interval", self.output_interval)
        if self.output_interval > self.duration:
            raise ValueError(f"output_interval ({self.output_interval:g} s) must not exceed "
                             f"duration ({self.duration:g} s)")

    # --- construction --------------------------------------------------------------------
    @classmethod
    def from_preset(cls, name: str, **overrides) -> "Scene":
        if name not in preset_names():
            raise ValueError(f"unknown scene or preset {name!r}; choose one of "
                             f"{', '.join(preset_names())} or give a .toml file")
        spec = _preset_scene(name)
        scene = cls(spec["name"], dict(spec["parameters"]), spec["operating"], spec["duration"],
                    spec["output_interval"], list(spec["notes"]))
        if spec.get("static_tension") is not None:
            from .models.kinematic import static_span_tension
            geometric = static_span_tension(scene.drive, dict(scene.parameters,
                                                              **{"chain.pretension": 0.0}))
            if spec["static_tension"] >= geometric:
                scene = scene.with_static_tension(spec["static_tension"])
            else:
                scene.notes.append(f"the centre distance alone gives a static span tension of "
                                   f"{geometric:.4g} N, more than the {spec['static_tension']:g} N "
                                   "of Table 2; kept")
        return scene.with_overrides(**overrides) if overrides else scene

    @classmethod
    def from_toml(cls, path: str | Path, **overrides) -> "Scene":
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise ValueError(f"scene file {str(path)!r} does not exist") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"scene file {str(path)!r} is not valid TOML: {exc}") from None
        known = {"name", "preset", "fidelity", "duration", "output_interval", "operating",
                 "parameters"}
        unknown = set(data) - known
        if unknown:
            raise ValueError(f"scene file {path.name}: unknown keys {sorted(unknown)}; "
                             f"valid: {sorted(known)}")
        base = cls.from_preset(data["preset"]) if "preset" in data else cls("scene", {})
        kw: dict[str, Any] = dict(data.get("operating", {}))
        for key in ("fidelity", "duration", "output_interval"):
            if key in data:
                kw[key] = data[key]
        kw.update(overrides)
        scene = base.with_overrides(parameters=data.get("parameters", {}), **kw)
        scene.name = data.get("name", path.stem)
        return scene

    def with_overrides(self, parameters: Mapping[str, Any] | None = None, **kw) -> "Scene":
        """A copy with parameters and scene values replaced. Keyword names: fidelity, duration,
        output_interval, input_speed_rpm, input_speed (rad/s), ramp_time, load_torque,
        static_tension, and any parameter with its dots written as underscores
        (chain_link_mass=...)."""
        params = dict(self.parameters)
        params.update(parameters or {})
        op = self.operating
        duration, interval = self.duration, self.output_interval
        static = kw.pop("static_tension", None)
        by_underscore = {n.replace(".", "_"): n for n in P.BY_NAME}
        for key, value in kw.items():
            if value is None:
                continue
            if key == "fidelity":
                params["fidelity"] = P.fidelity_level(value)
            elif key == "duration":
                duration = value
            elif key == "output_interval":
                interval = value
            elif key == "input_speed_rpm":
                op = replace(op, speed=_finite("input_speed_rpm", value) * RPM)
            elif key == "input_speed":
                op = replace(op, speed=_finite("input_speed", value))
            elif key == "ramp_time":
                op = replace(op, ramp_time=value)
            elif key == "load_torque":
                op = replace(op, load_torque=_finite("load_torque", value))
            elif key in P.BY_NAME:
                params[key] = value
            elif key in by_underscore:
                params[by_underscore[key]] = value
            else:
                raise ValueError(f"unknown scene setting {key!r}; valid: fidelity, duration, "
                                 "output_interval, input_speed_rpm, ramp_time, load_torque, "
                                 "static_tension, or a parameter name (see chainmodel.parameters)")
        scene = Scene(self.name, params, op, duration, interval, list(self.notes))
        return scene.with_static_tension(static) if static is not None else scene

    def with_static_tension(self, tension: float) -> "Scene":
        """Set chain.pretension so that the static span tension at rest (rigid seats, no load)
        equals ``tension`` [N]; refuses a value below what the centre distance alone gives."""
        from .models.kinematic import static_span_tension
        tension = check_positive("static_tension", tension, allow_zero=True)
        params = dict(self.parameters, **{"chain.pretension": 0.0})
        drive = self.drive_for(params)
        geometric = static_span_tension(drive, params)
        if tension < geometric - 1e-9:
            raise ValueError(f"static_tension {tension:g} N is below the {geometric:.4g} N the "
                             "centre distance already gives; shorten drive.centre_distance")
        # T is affine in the pre-strain tension while it is positive (slope 1 with rigid seats,
        # less with seat compliance): solve it from a probe well inside the positive range.
        probe = tension + 1000.0
        slope = (static_span_tension(drive, dict(params, **{"chain.pretension": probe}))
                 - geometric) / probe if geometric > 0 else None
        if slope is None or slope <= 0:
            hi = dict(params, **{"chain.pretension": 2 * probe})
            t_hi = static_span_tension(drive, hi)
            t_lo = static_span_tension(drive, dict(params, **{"chain.pretension": probe}))
            slope = (t_hi - t_lo) / probe
            pre = probe + (tension - t_lo) / slope
        else:
            pre = (tension - geometric) / slope
        params["chain.pretension"] = max(0.0, pre)
        return Scene(self.name, params, self.operating, self.duration, self.output_interval,
                     self.notes + [f"chain.pretension = {params['chain.pretension']:.4g} N for a "
                                   f"static span tension of {tension:g} N"])

    # --- derived ---------------------------------------------------------------------------
    @property
    def fidelity(self) -> int:
        return self.parameters["fidelity"]

    def drive_for(self, params: Mapping[str, Any]) -> Drive:
        return drive_from_parameters(params, self.name)

    @property
    def drive(self) -> Drive:
        return self.drive_for(self.parameters)

    def model(self) -> Model:
        return model_class(self.fidelity)(self.drive, self.parameters)

    def inputs(self, t: float) -> Inputs:
        return self.operating.inputs(t)

    def input_arrays(self, times):
        """The inputs at many times: (angle, speed, acceleration, torque) arrays
        (:meth:`OperatingPoint.input_arrays`)."""
        return self.operating.input_arrays(times)

    def times(self) -> np.ndarray:
        n = max(1, round(self.duration / self.output_interval))
        return np.linspace(0.0, n * self.output_interval, n + 1)

    def stepper(self, model: Model | None = None) -> Stepper:
        model = model or self.model()
        p = self.parameters
        # the automatic fixed step follows solver.tolerance, the state's highest frequency and a
        # quarter tooth period at the current input speed, as inside the FMU (docs/numerics.md)
        return make_stepper(model, p["solver.method"], 0.0, self.inputs(0.0), step=p["solver.step"],
                            rtol=p["solver.rtol"], tolerance=p["solver.tolerance"])


def _finite(name, value):
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return float(value)


def load_scene(scene: "str | Path | Scene", **overrides) -> Scene:
    """A scene from a preset name, a .toml path, or a Scene (copied with overrides)."""
    if isinstance(scene, Scene):
        return scene.with_overrides(**overrides) if overrides else scene
    text = str(scene)
    if text.endswith(".toml") or Path(text).is_file():
        return Scene.from_toml(text, **overrides)
    return Scene.from_preset(text, **overrides)
