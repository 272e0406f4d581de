"""Scenes: a drive, its parameters, an operating point, a fidelity level and a solver.

A scene is what a user runs. It comes from a preset name (``xu2010``, ``C1``, ...) or a TOML
file, with overrides, and turns into a ready model and stepper. TOML layout (SI units; the speed
is given in rpm because that is how drives are specified)::

    name = "my drive"
    preset = "xu2010"            # optional: start from a preset's drive and values
    chain = "16B"                # optional: the ISO 606 chain (chainmodel.chains) sets every
                                 # chain value not given below; its pitch must be drive.pitch
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
A scene that names no chain on a pitch other than 15.875 mm (the 10B of the defaults) gets the
B-series ISO 606 chain of its pitch, with a note; :meth:`Scene.assumed` lists every value the
user did not give and where it comes from (docs/scenes.md).
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
from .models import Inputs, Model, build_model, model_class
from .presets import INCH, preset, preset_names, reference_values

__all__ = ["Scene", "load_scene", "scene_names", "drive_from_parameters", "OperatingPoint",
           "SETTINGS", "setting_names"]

from .units import RPM  # noqa: E402  (one definition: chainmodel.units)

#: the scene settings :meth:`Scene.with_overrides` takes besides the parameters
SETTINGS = ("fidelity", "duration", "output_interval", "input_speed_rpm", "input_speed",
            "ramp_time", "load_torque", "static_tension", "chain")


def setting_names() -> list[str]:
    """Every name :meth:`Scene.with_overrides` (and so ``simulate``, ``chainmodel run --set`` and
    a sweep) accepts: the scene settings, then each parameter dotted and underscored."""
    return list(SETTINGS) + list(P.BY_NAME) + list(P.BY_UNDERSCORE)


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


def _xu2010_chain_values() -> dict[str, Any]:
    """xu2010's chain: ISO 606 10B with seed 003 section 7's values - the schema defaults."""
    from .chains import CHAIN_PARAMETERS
    return {n: P.BY_NAME[n].default for n in CHAIN_PARAMETERS}


def _preset_scene(name: str) -> dict[str, Any]:
    if name == "xu2010":
        v = reference_values("multibody_example_xu2010.csv")
        params = _xu2010_chain_values()
        params.update({"drive.driver_teeth": int(v["z1"]), "drive.driven_teeth": int(v["z2"]),
                       "drive.pitch": v["pitch"], "drive.links": int(v["links"]),
                       "drive.centre_distance": v["center_distance"]})
        return dict(name="xu2010", parameters=params, duration=1.0, output_interval=1e-4,
                    operating=OperatingPoint(v["input_speed"] * RPM, v["ramp_time"], v["M_load"]),
                    notes=["seed 003 section 7; centre distance 197.7 mm as in the paper"],
                    chain="10B", origins={k: ("preset xu2010: seed 003 section 7"
                                              if k.startswith("drive.") else
                                              "preset xu2010: 10B as in seed 003 section 7")
                                          for k in params})
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
    origins = {k: f"preset {name}: seed 004 Table 1 / seed 000 Table 1" for k in params}
    chain = None
    if abs(drive.pitch - INCH) < 1e-12:
        table2 = _table2_values(drive)
        params.update(table2)
        origins.update({k: f"preset {name}: seed 004 Table 2" for k in table2})
        chain = "16B"      # the B-series ISO 606 chain of 25.4 mm (16B's d1 is Table 2's roller)
        t2 = reference_values("dynamic_params_jsv2016_table2.csv")
        static = t2["P_tot"] / 2
        load = drive.driven.pitch_radius * t2["f1"]
        op = OperatingPoint(400 * RPM, 0.05, load)
        notes.append("seed 004 Table 2 dynamic values (400 rpm, brake load 200 N, "
                     "P_tot = 1000 N shared by the two spans)")
    else:
        op = OperatingPoint()
    return dict(name=name, parameters=params, duration=1.0, output_interval=1e-4, operating=op,
                static_tension=static, notes=notes, chain=chain, origins=origins)


def scene_names() -> list[str]:
    return preset_names()


class _Slack(Exception):
    """A probe pretension left the chain slack (static tension 0)."""


def _static_tension_at(level: int, drive: Drive, params: dict, pretension: float, *,
                       exact: bool = True) -> float:
    """Model.static_tension() of ``level`` with ``chain.pretension = pretension``; 0 where the
    pretension leaves the chain slack (which the models refuse to build). ``exact=False`` at
    levels 0-2: the elastic catenary's parabola alone, without level 3's statics
    (wrap_statics.weighted_static_tension)."""
    from .models.kinematic import pretension_error
    from .models.wrap_statics import static_span_tension
    trial = dict(params, **{"chain.pretension": pretension})
    if pretension > 0 and pretension_error(drive, trial) is not None:
        return 0.0
    if level <= 2:   # the levels 0-2 share it
        return static_span_tension(drive, trial, exact=exact, fitted=False)
    return float(model_class(level)(drive, trial).static_tension())


#: a target this many times the parabola's tension at pretension 0 is above the exact one too
#: (level 3's sag term moves it by (S_3 / S)^(1/3), measured 0.95-1.01: docs/reduced_models.md)
_CLEARLY_ABOVE = 1.5


def _tension_without_pretension(level: int, drive: Drive, params: dict, target: float) -> float:
    """The static tension at pretension 0, as far as comparing ``target`` with it needs: at
    levels 0-2 the parabola's where the target is clearly above it (no level 3 statics for a
    pretensioned scene), else the level's own."""
    if level <= 2:
        cheap = _static_tension_at(level, drive, params, 0.0, exact=False)
        if target >= _CLEARLY_ABOVE * cheap:
            return cheap
    return _static_tension_at(level, drive, params, 0.0)


@lru_cache(maxsize=128)
def _solve_pretension(level: int, drive: Drive, frozen: tuple, target: float) -> float:
    """The chain.pretension at which ``level``'s own Model.static_tension() is ``target`` [N]
    (:func:`_search_pretension`). At levels 0-2 with ``torsional.wrap_statics`` the search
    reads level 3's static tension alone; where the wrap fit then refuses the drive at the
    pretension found (wrap_statics.unavailable), the model holds the seat ladder's tension, so
    the search is redone on the ladder's."""
    params = dict(frozen)
    x = _search_pretension(level, drive, params, target)
    if (level > 2 or drive.links is None or not params.get("torsional.wrap_statics")
            or not _wrap_refused(drive, params, x)):
        return x
    x = _search_pretension(level, drive, dict(params, **{"torsional.wrap_statics": False}),
                           target)
    if not _wrap_refused(drive, params, x):
        raise ValueError(
            f"static_tension {target:g} N cannot be held at fidelity {level} with "
            "torsional.wrap_statics: the wrap fit refuses this drive at the pretension level "
            "3's statics ask for and accepts it at the seat ladder's; set "
            "torsional.wrap_statics = false, or chain.pretension instead of static_tension")
    return x


def _wrap_refused(drive: Drive, params: dict, pretension: float) -> bool:
    """Whether the wrap fit refuses this drive at ``pretension`` (fitting it, cached, as the
    model will)."""
    from .models.wrap_statics import static_span_tension, unavailable
    trial = dict(params, **{"chain.pretension": pretension})
    static_span_tension(drive, trial)
    return unavailable(drive, trial) is not None


def _search_pretension(level: int, drive: Drive, params: dict, target: float) -> float:
    """The chain.pretension at which ``level``'s static tension (:func:`_static_tension_at`)
    is ``target`` [N].

    T(pretension) is non-decreasing and piecewise affine wherever the chain is taut (the
    wrapped links' seats add a kink, level 3 its contacts): bracket the target, then regula
    falsi (Illinois) to 1e-6 relative or 1e-3 N. Refuses a target below T(0), the tension the
    centre distance gives alone, and one that needs more than the small-strain bound of
    chain.pretension."""
    from .models.kinematic import loose_chain_error
    t0 = _tension_without_pretension(level, drive, params, target)
    loose = loose_chain_error(drive, params) if target > t0 else None
    if loose is not None:
        raise ValueError(f"static_tension {target:g} N is refused: {loose}")
    tol = max(1e-3, 1e-6 * target)
    if not math.isfinite(t0):
        raise ValueError(f"static_tension cannot be set at fidelity {level}: the level reports "
                         "no static tension")
    if target < t0 - tol:
        weight = ""
        if params["gravity"] != 0.0:
            weight = (" with no pretension (the spans' weight included: a chain under gravity "
                      "carries at least its sag tension; chain.pretension = 0 instead of a "
                      "static_tension asks for exactly that)")
        if params["drive.centre_distance"] == 0.0:
            # at the tight wrap more links only lengthen the spans and raise the sag tension
            fix = (f"give drive.centre_distance below the {1e3 * drive.centre_distance:.5g} mm "
                   f"at which these {drive.links} links wrap tightly (drive.centre_distance = "
                   "0), so that the chain hangs deeper")
        else:
            fix = "shorten drive.centre_distance (or use more links)"
        raise ValueError(f"static_tension {target:g} N is below the {t0:.4g} N the centre "
                         f"distance already gives at fidelity {level}{weight}; {fix}")
    if abs(target - t0) <= tol:
        return 0.0
    limit = 0.05 * params["chain.link_stiffness"] * params["drive.pitch"] * (1 - 1e-9)
    lo, f_lo = 0.0, t0 - target
    hi = min(max(target - t0, 1.0), limit)
    f_hi = _static_tension_at(level, drive, params, hi) - target
    while f_hi < 0:
        if hi >= limit:
            raise ValueError(f"static_tension {target:g} N needs a chain.pretension beyond "
                             f"{limit:.4g} N (5 % pre-strain) at fidelity {level}; use a longer "
                             "drive.centre_distance or fewer links")
        lo, f_lo = hi, f_hi
        hi = min(2.0 * hi, limit)
        f_hi = _static_tension_at(level, drive, params, hi) - target
    side = 0
    for _ in range(60):
        x = hi if f_hi == f_lo else hi - f_hi * (hi - lo) / (f_hi - f_lo)
        x = min(max(x, lo), hi)
        f = _static_tension_at(level, drive, params, x) - target
        if abs(f) <= tol:
            return x
        if hi - lo <= 1e-9 * hi:
            # a jump: the level is already above the target where the pretension first takes
            # up the chain's slack (pretension_error refuses anything less)
            raise ValueError(
                f"static_tension {target:g} N cannot be reached at fidelity {level}: the "
                f"smallest chain.pretension that takes up this chain's slack ({hi:.6g} N) "
                f"already gives {target + f_hi:.4g} N; use fewer drive.links or a longer "
                "drive.centre_distance")
        if f > 0:
            hi, f_hi = x, f
            if side == 1:
                f_lo *= 0.5
            side = 1
        else:
            lo, f_lo = x, f
            if side == -1:
                f_hi *= 0.5
            side = -1
    return x  # pragma: no cover - regula falsi on a monotone function converges


def _chain_first(message: str, drive: Drive, params: Mapping[str, Any]) -> str:
    """``message`` of a refusal, with the chain values far from every ISO 606 chain of the
    pitch named after it (a unit slip is then the likelier cause; docs/scenes.md rule 5)."""
    from .validity import implausible_values
    odd = [p.text for p in implausible_values(drive, params)]
    return message + (f"; but check the chain first: {'; '.join(odd)}" if odd else "")


_STATIC_NOTE = "for a static span tension of"
_CHAIN_NOTE = "no chain named: ISO 606"
_CHANGED_NOTE = "drive changed from"
_ODD_NOTE = "drive.links is odd"
_INERTIA_NOTE = "default inertia:"
_SHAFT_NOTE = "default shaft:"


@dataclass
class Scene:
    """A runnable scene (see module docstring).

    ``static_tension`` [N], when set, is the static span tension at rest with no load that the
    scene asks for: the scene solves chain.pretension against its fidelity level's own
    Model.static_tension(), so it holds at whichever level runs (docs/stability.md)."""

    name: str
    parameters: dict[str, Any]
    operating: OperatingPoint = field(default_factory=OperatingPoint)
    duration: float = 1.0
    output_interval: float = 1e-4
    notes: list[str] = field(default_factory=list)
    static_tension: float | None = None
    #: the ISO 606 chain (chainmodel.chains) whose values fill the chain parameters not given
    chain: str | None = None
    #: where each given parameter comes from ("given" for the file and overrides, "preset ...");
    #: None: every entry of ``parameters`` counts as given
    origins: dict[str, str] | None = None

    def __post_init__(self):
        self._apply_chain()
        self.parameters = P.validate(self.parameters)
        self._note_offset_link()
        self._note_defaults()
        check_positive("duration", self.duration)
        check_positive("output_interval", self.output_interval)
        if self.output_interval > self.duration:
            raise ValueError(f"output_interval ({self.output_interval:g} s) must not exceed "
                             f"duration ({self.duration:g} s)")
        if self.static_tension is not None:
            target = check_positive("static_tension", self.static_tension, allow_zero=True)
            self.static_tension = target
            params = dict(self.parameters, **{"chain.pretension": 0.0})
            drive = self.drive_for(params)
            level = params["fidelity"]
            try:
                pre = _solve_pretension(level, drive, tuple(sorted(params.items())), target)
            except ValueError as exc:
                raise ValueError(_chain_first(str(exc), drive, params)) from None
            self.parameters = P.validate({"chain.pretension": pre}, self.parameters)
            self.notes = [n for n in self.notes if _STATIC_NOTE not in n] + [
                f"chain.pretension = {pre:.6g} N {_STATIC_NOTE} {target:g} N at fidelity "
                f"{level}"]

    def _note_offset_link(self) -> None:
        """A roller chain alternates inner and outer links, so an odd link count closes only
        with an offset (cranked) link; the models give every link the same pitch, mass and
        stiffness, so say it (an even count avoids the offset link)."""
        links = self.parameters.get("drive.links")
        self.notes = [n for n in self.notes if not n.startswith(_ODD_NOTE)]
        if links and int(links) % 2:
            self.notes.append(f"{_ODD_NOTE} ({int(links)}): the chain closes only with an "
                              "offset (cranked) link, which the models do not hold (every link "
                              f"is a plain one); {int(links) + 1} or {int(links) - 1} links "
                              "need none")

    def _note_defaults(self) -> None:
        """The schema's sprocket inertias and input shaft are seed 003's xu2010 drive's (its
        default drive: 25 / 17 teeth of 15.875 mm). On another drive that leaves them, say so:
        :meth:`_note_default_inertias`, :meth:`_note_default_shaft`."""
        self.notes = [n for n in self.notes
                      if not n.startswith(_INERTIA_NOTE) and not n.startswith(_SHAFT_NOTE)]
        sources = self.value_sources()
        # the parameters, not self.drive: building the Drive checks the wrap, which a scene
        # leaves to its run (a study loads its cases before it runs them)
        p = self.parameters
        same_pitch = abs(p["drive.pitch"] - P.BY_NAME["drive.pitch"].default) < 1e-9
        teeth = {side: (int(p[f"drive.{side}_teeth"]), P.BY_NAME[f"drive.{side}_teeth"].default)
                 for side in ("driver", "driven")}
        self._note_default_inertias(sources, teeth, same_pitch)
        if not (same_pitch and all(own == xu for own, xu in teeth.values())):
            self._note_default_shaft(sources)

    def _note_default_inertias(self, sources, teeth, same_pitch) -> None:
        """A sprocket inertia left at the schema default on a sprocket other than the default
        drive's (``teeth``: side -> (this drive's, the default drive's)): the note gives the
        steel disc of this one (chainmodel.chains.sprocket_disc_inertia) for scale."""
        from . import chains as C
        name = self.chain or C.default_chain_for_pitch(self.parameters["drive.pitch"])
        for side, (own, xu) in teeth.items():
            key = f"{side}.inertia"
            if not sources[key].startswith("default:") or (own == xu and same_pitch):
                continue
            disc = ("" if name is None else
                    f"; a solid steel disc of this one would be "
                    f"{C.sprocket_disc_inertia(name, own):.3g} kg.m2")
            self.notes.append(
                f"{_INERTIA_NOTE} {key} = {self.parameters[key]:g} kg.m2 is xu2010's "
                f"{xu}-tooth sprocket (seed 003), the default, not this drive's "
                f"{own}-tooth{' ' + name if name else ''} one{disc} "
                "(chainmodel.chains.sprocket_disc_inertia, no hub or machine): give the real "
                "value")

    def _note_default_shaft(self, sources) -> None:
        """The schema's input shaft is xu2010's (seed 003: 12 kN.m/rad). On another drive left
        at it, say how far the load's torque at the driver winds it: a heavy drive on that
        shaft rings (an audit's 16A 11/55 at 9000 N.m: the driver swinging -0.9 to 16 rad/s
        about 5.3, the chain past its breaking load at level 3; rigid, 42 kN peaks)."""
        p = self.parameters
        if (not sources["input_shaft.stiffness"].startswith("default:")
                or p["input_shaft.rigid"] or p["input_shaft.causality"] != "angle"):
            return
        torque = (abs(self.operating.load_torque) * int(p["drive.driver_teeth"])
                  / int(p["drive.driven_teeth"]))
        k = p["input_shaft.stiffness"]
        self.notes.append(
            f"{_SHAFT_NOTE} input_shaft.stiffness = {k:g} N.m/rad is xu2010's input shaft "
            f"(seed 003), the default; this drive's load puts about {torque:.4g} N.m on it, "
            f"winding it {torque / k:.3g} rad ({math.degrees(torque / k):.3g} deg): give your "
            "shaft's stiffness (G pi d^4 / 32 L for a plain steel shaft) or set "
            "input_shaft.rigid = true")

    def _apply_chain(self) -> None:
        """Fill the chain values not given from the named chain (or, with none named on a pitch
        other than the defaults' 10B, from the B-series chain of the pitch); refuse a chain
        whose pitch is not drive.pitch, and a pitch no chain has unless every chain value is
        given. Records the filled values' sources for :meth:`assumed`."""
        from . import chains as C
        params = dict(self.parameters)
        origins = (dict(self.origins) if self.origins is not None
                   else {P.canonical_name(k) or k: "given" for k in params})
        if "drive.pitch" in params:     # its range first: the chain checks compare it
            params["drive.pitch"] = P.BY_NAME["drive.pitch"].check(params["drive.pitch"])
        pitch = params.get("drive.pitch", P.BY_NAME["drive.pitch"].default)
        name = self.chain
        self.notes = [n for n in self.notes if not n.startswith(_CHAIN_NOTE)]
        if name is not None and not isinstance(name, str):
            raise ValueError(f"chain must be a chain name ({', '.join(C.chain_names())}), "
                             f"got {name!r}")
        self._chain_named = bool(name)
        if not name:
            name = None
            missing = [n for n in C.CHAIN_PARAMETERS if n not in origins]
            if abs(pitch - P.BY_NAME["drive.pitch"].default) > 1e-9 and missing:
                name = C.default_chain_for_pitch(pitch)
                if name is None:
                    raise ValueError(
                        f"drive.pitch ({pitch * 1e3:g} mm) is the pitch of no ISO 606 chain "
                        f"here ({', '.join(C.chain_names())}): name a chain, or give every "
                        f"chain value; missing: {', '.join(missing)}")
                self.notes.append(f"{_CHAIN_NOTE} {name} assumed from drive.pitch "
                                  f"{pitch * 1e3:g} mm (B series; name chain = "
                                  f"\"{C.chains_of_pitch(pitch)[-1]}\" for another)")
        filled: dict[str, str] = {}
        if name is not None:
            name = C.chain(name).name
            values, sources = C.parameter_values(name), C.parameter_sources(name)
            if "drive.pitch" in origins:
                why = C.pitch_mismatch(name, pitch)
                if why is not None:
                    raise ValueError(f"scene {self.name!r}: {why}")
            for key, value in values.items():
                if key not in origins:
                    params[key] = value
                    filled[key] = f"chain {name}: {sources[key]}"
        self.chain, self.origins, self.parameters = name, origins, params
        self._filled = filled

    def value_sources(self) -> dict[str, str]:
        """Where every parameter's value comes from: "given" (the scene file or overrides),
        "preset NAME: ..." (a preset's cited values), "chain NAME: ..." (the chain's law,
        chainmodel.chains), "static_tension ..." (solved), or "default: ..." (the schema's
        default and its reason, docs/parameters.md)."""
        out = {}
        for p in P.PARAMETERS:
            if p.name in self.origins:
                out[p.name] = self.origins[p.name]
            elif p.name in self._filled:
                out[p.name] = self._filled[p.name]
            elif p.name == "chain.pretension" and self.static_tension is not None:
                out[p.name] = f"static_tension: solved for {self.static_tension:g} N at rest"
            else:
                out[p.name] = "default: " + p.description
        return out

    def assumed(self, levels: tuple[int, ...] | None = None) -> dict[str, tuple[Any, str]]:
        """Every parameter the user did not give (file or overrides): name -> (value, source),
        :meth:`value_sources`; ``levels`` keeps only the parameters those fidelity levels use
        (None: every parameter)."""
        out = {}
        for name, source in self.value_sources().items():
            spec = P.BY_NAME[name]
            if source == "given" or (levels is not None and not set(spec.levels) & set(levels)):
                continue
            out[name] = (self.parameters[name], source)
        return out

    def assumed_lines(self) -> list[str]:
        """:meth:`assumed` at this scene's level as text lines, ``name = value unit  (source)``
        with the source cut to its first clause (the CLI's ``assumed`` block)."""
        lines = []
        for name, (value, source) in self.assumed((self.fidelity,)).items():
            if name == "fidelity" or name.startswith("solver."):   # numerics, not the drive
                continue
            unit = P.BY_NAME[name].unit
            shown = f"{value:.6g}" if isinstance(value, float) else str(value).lower()
            short = source.split(";")[0]
            if len(short) > 80:
                short = short[:77] + "..."
            lines.append(f"{name} = {shown}{' ' + unit if unit else ''}  ({short})")
        return lines

    # --- construction --------------------------------------------------------------------
    @classmethod
    def from_preset(cls, name: str, **overrides) -> "Scene":
        if name not in preset_names():
            raise ValueError(f"unknown scene or preset {name!r}; choose one of "
                             f"{', '.join(preset_names())} or give a .toml file")
        spec = _preset_scene(name)
        scene = cls(spec["name"], dict(spec["parameters"]), spec["operating"], spec["duration"],
                    spec["output_interval"], list(spec["notes"]), chain=spec.get("chain"),
                    origins=dict(spec.get("origins", {})))
        scene = scene.with_overrides(**overrides) if overrides else scene
        explicit = {"static_tension", "chain_pretension", "chain.pretension"} & set(overrides)
        if spec.get("static_tension") is not None and not explicit:
            target = spec["static_tension"]
            params = dict(scene.parameters, **{"chain.pretension": 0.0})
            geometric = _tension_without_pretension(scene.fidelity, scene.drive_for(params),
                                                    params, target)
            if target >= geometric:
                scene = scene.with_overrides(static_tension=target)
            else:
                scene.notes.append(f"the centre distance alone gives a static span tension of "
                                   f"{geometric:.4g} N at fidelity {scene.fidelity}, more than "
                                   f"the {target:g} N of Table 2; kept")
        return scene

    @classmethod
    def from_toml(cls, path: str | Path, **overrides) -> "Scene":
        path = Path(path)
        try:
            data = tomllib.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise ValueError(f"scene file {str(path)!r} does not exist") from None
        except UnicodeDecodeError as exc:
            raise ValueError(f"scene file {str(path)!r} is not a text file in UTF-8 (TOML): "
                             f"{exc.reason} at byte {exc.start}") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"scene file {str(path)!r} is not valid TOML: {exc}") from None
        known = {"name", "preset", "chain", "fidelity", "duration", "output_interval",
                 "operating", "parameters"}
        unknown = set(data) - known
        if unknown:
            raise ValueError(f"scene file {path.name}: unknown keys {sorted(unknown)}; "
                             f"valid: {sorted(known)}")
        for key in ("operating", "parameters"):
            if not isinstance(data.get(key, {}), dict):
                raise ValueError(f"scene file {path.name}: {key} must be a table ([{key}] with "
                                 f"name = value lines), got {data[key]!r}")
        for key in ("name", "preset", "chain"):
            if key in data and not isinstance(data[key], str):
                raise ValueError(f"scene file {path.name}: {key} must be a string (in quotes), "
                                 f"got {data[key]!r}")
        base = cls.from_preset(data["preset"]) if "preset" in data else cls("scene", {})
        kw: dict[str, Any] = dict(data.get("operating", {}))
        for key in ("chain", "fidelity", "duration", "output_interval"):
            if key in data:
                kw[key] = data[key]
        kw.update(overrides)
        scene = base.with_overrides(parameters=data.get("parameters", {}), **kw)
        scene.name = data.get("name", path.stem)
        if "preset" not in data:   # a drive of its own: nothing was changed from
            scene.notes = [n for n in scene.notes if not n.startswith(_CHANGED_NOTE)]
        return scene

    def with_overrides(self, parameters: Mapping[str, Any] | None = None, **kw) -> "Scene":
        """A copy with parameters and scene values replaced. Keyword names: fidelity, duration,
        output_interval, input_speed_rpm, input_speed (rad/s), ramp_time, load_torque,
        static_tension (:data:`SETTINGS`), and any parameter, dotted (``**{"chain.link_mass":
        ...}``) or with its dots written as underscores (``chain_link_mass=...``); the same two
        forms in ``parameters``. An unknown name raises ValueError listing the closest names."""
        params = dict(self.parameters)
        origins = dict(self.origins) if self.origins is not None else {}
        if parameters is not None and not isinstance(parameters, Mapping):
            raise ValueError(f"parameters must be a mapping of parameter name to value (a "
                             f"dict), got {type(parameters).__name__} {parameters!r:.80}")
        for key in parameters or {}:
            if not isinstance(key, str):
                raise ValueError(f"parameter names must be strings (e.g. 'chain.link_mass'), "
                                 f"got {key!r} ({type(key).__name__})")
        for key, value in (parameters or {}).items():
            params[P.canonical_name(key) or key] = value    # unknown names: validate() refuses
            origins[P.canonical_name(key) or key] = "given"
        # an assumed chain (none named) follows the pitch; a named one stays and is checked
        named = kw.pop("chain", None)
        chain = named or (self.chain if self._chain_named else None)
        if named and self.chain and named != self.chain:
            # another chain named: its values replace those the preset or the old chain gave
            # (not the ones given by hand)
            from .chains import CHAIN_PARAMETERS
            origins = {k: v for k, v in origins.items()
                       if not (k in CHAIN_PARAMETERS and v != "given")}
        op = self.operating
        duration, interval = self.duration, self.output_interval
        static = kw.pop("static_tension", None)
        pretension_given = (any(P.canonical_name(k) == "chain.pretension"
                                for k in (parameters or {}))
                            or any(P.canonical_name(k) == "chain.pretension" and v is not None
                                   for k, v in kw.items()))
        if kw.get("input_speed_rpm") is not None and kw.get("input_speed") is not None:
            raise ValueError(f"give either input_speed_rpm ({kw['input_speed_rpm']!r}) or "
                             f"input_speed ({kw['input_speed']!r} rad/s), not both: both set "
                             "the steady input-shaft speed")
        if static is not None and pretension_given:
            raise ValueError("give either static_tension or chain.pretension, not both: "
                             "static_tension sets chain.pretension")
        if static is None and not pretension_given:
            static = self.static_tension     # keep the target: re-solved at the new level
        for key, value in kw.items():
            if value is None:
                continue
            if key == "fidelity":
                params["fidelity"] = P.fidelity_level(value)
                origins["fidelity"] = "given"
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
            elif P.canonical_name(key) is not None:
                params[P.canonical_name(key)] = value
                origins[P.canonical_name(key)] = "given"
            else:
                raise ValueError(P.unknown_name_message("scene setting or parameter", key,
                                                        setting_names())
                                 + f" (scene settings: {', '.join(SETTINGS)}; parameters: "
                                 "chainmodel.parameters, docs/parameters.md, dotted or with "
                                 "underscores)")
        notes = list(self.notes)
        if static is None:
            notes = [n for n in notes if _STATIC_NOTE not in n]
        changed = [k for k in sorted(params) if k.startswith("drive.")
                   and params[k] != self.parameters.get(k)]
        if changed:   # another drive: what the scene said of its own no longer applies
            notes = [n for n in notes if _STATIC_NOTE in n or n.startswith(_CHAIN_NOTE)
                     or n.startswith(_CHANGED_NOTE)]
            notes = [n for n in notes if not n.startswith(_CHANGED_NOTE)] + [
                f"{_CHANGED_NOTE} {self.name}'s ({', '.join(changed)} given): its notes on "
                "the drive are dropped"]
        return Scene(self.name, params, op, duration, interval, notes, static, chain=chain,
                     origins=origins)

    def with_static_tension(self, tension: float) -> "Scene":
        """A copy whose chain.pretension gives the static span tension ``tension`` [N] at rest
        with no load at this scene's fidelity level (and at any level it is moved to)."""
        return self.with_overrides(static_tension=tension)

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
        return build_model(self.fidelity, self.drive, self.parameters)

    def inputs(self, t: float) -> Inputs:
        u = self.operating.inputs(t)
        if self.parameters["input_shaft.causality"] == "torque":
            u = self._with_motor_torque(u)
        return u

    def _with_motor_torque(self, u: Inputs) -> Inputs:
        """Torque causality: the operating point's speed profile as an open-loop motor torque,
        motor.torque = J_refl * d(speed)/dt + the steady need of the load at that speed
        (models/torque_causality.py: reflected_inertia, steady_motor_torque)."""
        from .models import torque_causality as TC
        key = tuple(sorted(self.parameters.items()))
        cached = self.__dict__.get("_motor_profile")
        if cached is None or cached[0] != key:
            model = self.model()
            cached = self.__dict__["_motor_profile"] = (key, model, TC.reflected_inertia(model))
        _, model, j_refl = cached
        torque = j_refl * u.acceleration + TC.steady_motor_torque(model, u.speed, u.torque)
        return replace(u, motor_torque=torque)

    def check_operating_point(self, model: Model) -> None:
        """Refuse, before running, an operating point beyond what ``model`` holds to
        (:meth:`Model.input_error`: the level's speed limit, the small-strain load bound):
        ValueError naming the scene setting, its value and the valid range. The profile
        ramps from rest to the operating speed, so the extremes are that speed and the load."""
        op = self.operating
        why = model.input_error(0.0, op.speed, op.load_torque)
        if why is None:
            return
        setting = ("input_speed_rpm" if "input_shaft.speed" in why else
                   "load_torque" if "load.torque" in why else "operating point")
        raise ValueError(_chain_first(f"scene setting {setting} refused at fidelity "
                                      f"{model.level} ({model.name}): {why}",
                                      self.drive, self.parameters))

    def implausible_chain_values(self) -> list[str]:
        """The chain values more than validity.IMPLAUSIBLE_RATIO times above or below the
        nearest ISO 606 chain's of the drive's pitch, as sentences (:func:`chainmodel.validity.implausible_values`, which the
        run's warnings and the FMU log give too)."""
        from .validity import implausible_values
        return [p.text for p in implausible_values(self.drive, self.parameters)]

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
