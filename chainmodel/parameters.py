"""The parameter schema: one list of every parameter a scene, the FMU and the CLI can set.

Each parameter has a structured FMI name, an SI unit, a default (the numerical example of
seed 003 section 7 where the paper gives one), a description and its valid range. The FMU
adapter generates its variables from this list and the scene validates against it, so a value
is checked the same way wherever it enters.

Values the paper does not give carry a default with its reason in the description; see
docs/parameters.md for the table.
"""

from __future__ import annotations

import math
import numbers
from dataclasses import dataclass
from typing import Any, Mapping

__all__ = ["Parameter", "PARAMETERS", "BY_NAME", "defaults", "validate", "FIDELITY_NAMES",
           "fidelity_level", "markdown_table", "canonical_name", "close_matches",
           "unknown_name_message", "BY_UNDERSCORE", "parse_text"]

FIDELITY_NAMES = ("kinematic", "torsional", "modal", "multibody")


def fidelity_level(value) -> int:
    """Fidelity as a level number; accepts 0-3 or a name (kinematic ... multibody)."""
    if isinstance(value, str):
        key = value.strip().lower()
        if key in FIDELITY_NAMES:
            return FIDELITY_NAMES.index(key)
        if key.isdigit():
            value = int(key)
        else:
            raise ValueError(f"fidelity must be 0-3 or one of {', '.join(FIDELITY_NAMES)}, "
                             f"got {value!r}")
    if isinstance(value, bool) or not isinstance(value, numbers.Integral) or not 0 <= value <= 3:
        raise ValueError(f"fidelity must be 0-3 or one of {', '.join(FIDELITY_NAMES)}, got {value!r}")
    return int(value)


@dataclass(frozen=True)
class Parameter:
    name: str
    default: Any
    unit: str
    description: str
    kind: type = float
    minimum: float | None = None
    maximum: float | None = None
    exclusive_minimum: bool = False
    choices: tuple = ()
    display_unit: str | None = None
    levels: tuple[int, ...] = (0, 1, 2, 3)
    structural: bool = True

    def check(self, value):
        """Return the value converted to this parameter's type, or raise ValueError that names
        the parameter, the value and what would be valid."""
        name = self.name
        if self.kind is bool:
            if isinstance(value, bool):
                return value
            if isinstance(value, numbers.Integral) and value in (0, 1):
                return bool(value)
            if isinstance(value, str) and value.lower() in ("true", "false", "1", "0"):
                return value.lower() in ("true", "1")
            raise ValueError(f"parameter {name} must be true or false, got {value!r}")
        if self.kind is str:
            if not isinstance(value, str) or (self.choices and value not in self.choices):
                raise ValueError(f"parameter {name} must be one of {', '.join(self.choices)}, "
                                 f"got {value!r}")
            return value
        if self.kind is int:
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not float(value).is_integer():
                raise ValueError(f"parameter {name} must be a whole number{self._range()}, got {value!r}")
            value = int(value)
        else:
            if isinstance(value, bool) or not isinstance(value, numbers.Real) or not math.isfinite(value):
                raise ValueError(f"parameter {name} must be a finite number{self._range()}, got {value!r}")
            value = float(value)
        lo_bad = self.minimum is not None and (value < self.minimum or
                                               (self.exclusive_minimum and value == self.minimum))
        hi_bad = self.maximum is not None and value > self.maximum
        if lo_bad or hi_bad:
            raise ValueError(f"parameter {name} must be{self._range()} [{self.unit or '-'}], got {value!r}")
        return value

    def valid_text(self) -> str:
        """What values are valid, for messages and docs: 'one of a, b', '> 0', '[0, 1]', or ''
        when any finite value is."""
        if self.choices:
            return "one of " + ", ".join(self.choices)
        lo, hi = self.minimum, self.maximum
        if lo is None and hi is None:
            return ""
        if hi is None:
            return f"{'>' if self.exclusive_minimum else '>='} {lo:g}"
        if lo is None:
            return f"<= {hi:g}"
        return f"{'(' if self.exclusive_minimum else '['}{lo:g}, {hi:g}]"

    def _range(self) -> str:
        text = self.valid_text()
        if not text:
            return ""
        both = self.minimum is not None and self.maximum is not None
        return (" in " if both else " ") + text


def _p(*args, **kw) -> Parameter:
    return Parameter(*args, **kw)


# ISO 606 10B roller (the xu2010 chain, p = 15.875 mm): d1 = 10.16 mm.
_ROLLER_RADIUS = 10.16e-3 / 2
_SEAT_RADIUS = round(0.505 * 10.16e-3, 12)  # ISO 606 minimum seating-curve radius r_i,min = 0.505 d1
_JOINT_CLEARANCE = round(5.13e-3 - 5.08e-3, 12)  # ISO 606 10B: bush bore d3 min - pin body d2 max
# Plausibility bounds, far beyond any chain drive, so that a typo (grams as kilograms, a
# missing minus in an exponent) is refused with the range instead of overflowing the arithmetic
# or running for hours: link and contact stiffness 1e11 N/m (1000x the 16B link's 1.06e8 of
# chainmodel.chains; level 3's stable step would fall to ~1e-9 s), shaft stiffness 1e10 N.m/rad,
# inertias 1e6 kg.m2 (a 10 m steel disc 1 m wide is 1.5e6), centre distance 1 km
_STIFFNESS_MAX = 1e11
_SHAFT_STIFFNESS_MAX = 1e10
_INERTIA_MAX = 1e6
_CENTRE_DISTANCE_MAX = 1e3

PARAMETERS: tuple[Parameter, ...] = (
    _p("fidelity", 1, "", "model level: 0 kinematic, 1 torsional, 2 modal, 3 multibody "
       "(default 1: drivetrain torsional dynamics and span tensions at a fraction of level 3's "
       "cost; docs/fidelity.md)", kind=int, minimum=0, maximum=3),
    # drive
    _p("drive.driver_teeth", 25, "", "teeth on the driver (input) sprocket, z1",
       kind=int, minimum=3, maximum=500),
    _p("drive.driven_teeth", 17, "", "teeth on the driven (output) sprocket, z2",
       kind=int, minimum=3, maximum=500),
    _p("drive.pitch", 0.015875, "m", "chain and sprocket pitch p", minimum=0.0,
       exclusive_minimum=True, maximum=1.0, display_unit="mm"),
    _p("drive.links", 46, "", "links in the closed chain, M", kind=int, minimum=4, maximum=100000),
    _p("drive.centre_distance", 0.1977, "m",
       "shaft centre distance; 0 selects the distance at which the chain wraps tightly "
       "(seed 004 section 2)", minimum=0.0, maximum=_CENTRE_DISTANCE_MAX, display_unit="mm"),
    _p("drive.inclination", 0.0, "rad",
       "angle of the line of centres (driven to driver) above the horizontal; sets the "
       "direction of gravity", minimum=-math.pi, maximum=math.pi, display_unit="deg"),
    # chain
    _p("chain.link_mass", 0.0162, "kg", "mass of one link including one roller (seed 003)",
       minimum=0.0, exclusive_minimum=True),
    _p("chain.link_stiffness", 5.1e7, "N/m", "longitudinal stiffness of one link (seed 003)",
       minimum=0.0, exclusive_minimum=True, maximum=_STIFFNESS_MAX),
    _p("chain.link_damping", 100.0, "N.s/m", "damping of one link (seed 003)", minimum=0.0),
    _p("chain.joint_damping", 0.002, "N.m.s/rad",
       "viscous damping of the relative rotation of neighbouring links at a joint (not in seed "
       "003; stands in for joint friction: c_j times the sprocket speed equals the friction "
       "torque mu T r_pin of a slack-side joint of xu2010 at 120 rpm, mu = 0.1; damps the "
       "spans' transverse modes so that level 3 converges, docs/multibody.md \"Convergence\"); "
       "frame-indifferent, so wrapped links turning with a sprocket do not dissipate",
       minimum=0.0, levels=(3,)),
    _p("chain.joint_clearance", _JOINT_CLEARANCE, "m",
       "pin-bushing diametral clearance: a link shortens by this much without force before its "
       "plates bear in compression (ISO 606 10B: bush bore d3 min 5.13 mm - pin d2 max "
       "5.08 mm); links carry no compression across it", minimum=0.0, display_unit="mm",
       levels=(3,)),
    _p("chain.pretension", 0.0, "N",
       "pre-strain of every link, at every level: its free length is "
       "p - pretension / link_stiffness (the tension of a link held at the pitch); refused on a "
       "chain longer than its wrapping length; the scene setting static_tension solves it for "
       "a given static span tension at the level that runs (docs/stability.md)",
       minimum=0.0),
    _p("chain.breaking_load", 22.2e3, "N",
       "breaking load of the chain: ISO 606 minimum tensile strength F_u (10B: 22.2 kN); "
       "the validity monitors compare link and contact forces with it; a scene's chain sets it "
       "(chainmodel.chains)", minimum=0.0, exclusive_minimum=True),
    _p("chain.roller_radius", _ROLLER_RADIUS, "m",
       "roller radius R_r (not in seed 003; ISO 606 10B, d1 = 10.16 mm)", minimum=0.0,
       exclusive_minimum=True, display_unit="mm", levels=(3,)),
    # contact
    _p("contact.seat_radius", _SEAT_RADIUS, "m",
       "radius R_t of the circular tooth seat (not in seed 003; ISO 606 minimum 0.505 d1); "
       "R_t - R_r is the roller-seat clearance", minimum=0.0, exclusive_minimum=True,
       display_unit="mm", levels=(3,)),
    _p("contact.stiffness", 8.46e6, "N/m", "equivalent roller-tooth contact stiffness (seed 003)",
       minimum=0.0, exclusive_minimum=True, maximum=_STIFFNESS_MAX, levels=(1, 2, 3)),
    _p("contact.damping", 74.0, "N.s/m",
       "roller-tooth contact damping (not in seed 003; about 10 % of critical for one link "
       "mass on the contact spring)", minimum=0.0, levels=(3,)),
    _p("contact.seating_angle", 2 * math.pi / 3, "rad",
       "ISO 606 roller seating angle constant A: the seat circle spans A - 90 deg / z and "
       "straight flanks continue it (not in seed 003; 120 deg is ISO's minimum, the most open "
       "flanks); A >= 180 deg gives the paper's bare circular seat of eq (9)",
       minimum=math.pi / 3, maximum=math.pi, display_unit="deg", levels=(3,)),
    # sprockets
    _p("driver.inertia", 4.0108e-3, "kg.m2", "driver sprocket moment of inertia I1 (seed 003)",
       minimum=0.0, exclusive_minimum=True, maximum=_INERTIA_MAX),
    _p("driven.inertia", 9.33e-4, "kg.m2",
       "driven sprocket (and load) moment of inertia I2 (seed 003)", minimum=0.0,
       exclusive_minimum=True, maximum=_INERTIA_MAX),
    _p("driven.damping", 0.0, "N.m.s/rad",
       "viscous damping of the driven shaft d1 (seed 004 eq 50; none in seed 003)", minimum=0.0),
    # input shaft
    _p("input_shaft.stiffness", 12000.0, "N.m/rad",
       "torsional stiffness of the input shaft k_r (seed 003)", minimum=0.0,
       exclusive_minimum=True, maximum=_SHAFT_STIFFNESS_MAX, levels=(1, 2, 3)),
    _p("input_shaft.damping", 0.69, "N.m.s/rad",
       "torsional damping of the input shaft c_r (not in seed 003; 5 % of critical for the "
       "driver inertia on the shaft spring)", minimum=0.0, levels=(1, 2, 3)),
    _p("input_shaft.rigid", False, "", "couple the driver rigidly to the input-shaft angle",
       kind=bool, levels=(1, 2, 3)),
    _p("input_shaft.causality", "angle", "",
       "what drives the input shaft: angle (inputs input_shaft.angle and speed, the far end of "
       "the shaft spring follows them) or torque (input motor.torque drives a motor rotor of "
       "motor.inertia at the far end of the shaft spring, integrated with the drive; "
       "docs/fmu.md, In a system model)", kind=str, choices=("angle", "torque"),
       levels=(1, 2, 3)),
    _p("motor.inertia", 0.01, "kg.m2",
       "moment of inertia of the motor rotor at the far end of the input-shaft spring, used "
       "with input_shaft.causality = torque (not in the seeds: the 0.01 kg m2 rotor of issue "
       "18's system example; give your motor's)", minimum=0.0, exclusive_minimum=True,
       levels=(1, 2, 3)),
    # environment
    _p("gravity", 9.81, "m/s2", "gravitational acceleration (acts on the chain: its sag "
       "tension at rest at every level, its spans' sag running at levels 1-3)", minimum=0.0,
       levels=(0, 1, 2, 3)),
    # levels 1-2
    _p("torsional.chain_inertia", True, "",
       "add the chain's mass to the sprockets at levels 1-2: rollers seated on a sprocket at its "
       "pitch radius, each span as a bar moving with its endpoints (consistent mass matrix); "
       "off gives seed 004 eq 50 exactly (docs/reduced_models.md)", kind=bool, levels=(1, 2)),
    _p("torsional.seat_compliance", True, "",
       "with torsional.wrap_statics off (or where its fit is refused): "
       "put the seated rollers' contact compliance in series with each span at levels 0-2 "
       "(level 0: in its static tension only): "
       "each span end adds 1/K_seat, K_seat = (k_c + sqrt(k_c^2 + 4 k_c k_link)) / 2 (a ladder "
       "of seat springs contact.stiffness and links, loaded by the span's tension less the "
       "wrapped links' own), plus the roller-seat clearance (docs/reduced_models.md)",
       kind=bool, levels=(0, 1, 2)),
    _p("torsional.wrap_statics", True, "",
       "at levels 0-2 take each span end's compliance, free length and a floor under the slack "
       "span from level 3 of the same drive (its rollers, links, seats with clearance and "
       "flanks, gravity): the spans hold level 3's static tension, its mean over a driver "
       "tooth period (the one reported is its value at driver angle 0), the driven "
       "sprocket's torsional mode of each level linearised at rest level 3's linear one (its "
       "statics and span rollers' inertia; their means over a driver tooth period) "
       "and the loaded split at rest follows level 3's statics (docs/reduced_models.md, \"One "
       "wrap\"); where level 3's statics give no wrap to fit (a chain hanging on its sag, a "
       "negative end compliance) the result warns and the seat ladder holds the ends; off, "
       "torsional.seat_compliance decides and the spans' weight adds the elastic catenary's "
       "sag tension (docs/reduced_models.md, \"One static tension\")", kind=bool,
       levels=(0, 1, 2)),
    _p("torsional.mean_link_compliance", True, "",
       "at levels 1-2 take each span's compliance (n / link_stiffness) and damping from its "
       "tooth-period-mean link count n, while its stretch follows the current count: the tension "
       "stays continuous through seating and release as in the multibody model; off, the "
       "current count makes the tension step by T / n at each event (docs/reduced_models.md)",
       kind=bool, levels=(1, 2)),
    _p("torsional.sag_lag", True, "",
       "under gravity, levels 0-1 carry each straight span's sag (the elastic catenary, "
       "S = w_n^2 L^3 / 24): level 0 quasi-statically, level 1 through a state per span that "
       "follows the span's stretch at its first string frequency, so a slack span under load "
       "hangs on its sag as in level 3 while the torsional mode above the string modes sees "
       "the spans elastic (docs/reduced_models.md, \"Level 1's lagged sag\"); off: no sag "
       "term with torsional.wrap_statics, the quasi-static sag on the seat ladder",
       kind=bool, levels=(0, 1)),
    # level 2
    _p("modal.modes", 1, "", "transverse Galerkin modes per span (seed 004 eq 57)",
       kind=int, minimum=1, maximum=20, levels=(2,)),
    _p("modal.damping_ratio", 0.02, "",
       "modal damping ratio of the span modes (no source gives it: seed 004 Table 2's "
       "mu_m = 0.02 is the coefficient of its non-dimensional eq 60, 0.02 / (m pi) of critical "
       "at P_t = P; level 3's joint dampers damp xu2010's spans at about 0.26 %)", minimum=0.0,
       maximum=1.0, levels=(2,)),
    _p("modal.impulse_forcing", False, "",
       "add the impulse-train idealisation of the meshing impacts (seed 004 eqs 63-65)",
       kind=bool, levels=(2,)),
    # level 3
    _p("multibody.rotating_frame_forces", False, "",
       "add the appendix's centrifugal and tangential inertia forces Q on seated rollers "
       "(seed 003 appendix eqs 4-7); off is the consistent choice for inertial coordinates",
       kind=bool, levels=(3,)),
    _p("multibody.paper_damping", False, "",
       "use the appendix's isotropic dissipation function S (seed 003 eq A3: damps the rigid "
       "rotation of links and sliding in seats); off uses axial link and normal contact "
       "dampers", kind=bool, levels=(3,)),
    # solver
    _p("solver.method", "auto", "", "time stepper (see chainmodel.integrate)", kind=str,
       choices=("auto", "rk4", "verlet", "rk45", "dop853", "radau", "bdf", "lsoda"),
       levels=(1, 2, 3)),
    _p("solver.step", 0.0, "s", "fixed step; 0 chooses it automatically from solver.tolerance, the "
       "highest natural frequency of the current state and a quarter tooth period at the current "
       "input speed (docs/numerics.md)",
       minimum=0.0, levels=(1, 2, 3)),
    _p("solver.rtol", 1e-6, "", "relative tolerance of the adaptive steppers", minimum=1e-12,
       maximum=0.1, levels=(1, 2, 3)),
    _p("solver.tolerance", 5e-4, "",
       "accuracy of the automatic fixed step (rk4, verlet) at levels 1-2: the step keeps the "
       "relative frequency error of the fastest mode below this; the measured output errors "
       "stay within a few times it (docs/numerics.md)", minimum=1e-10, maximum=0.1, levels=(1, 2)),
)

BY_NAME: dict[str, Parameter] = {p.name: p for p in PARAMETERS}

#: every parameter by its name with the dots written as underscores (chain_link_damping), the
#: form Python keyword arguments need; both forms are accepted wherever a name is.
BY_UNDERSCORE: dict[str, str] = {p.name.replace(".", "_"): p.name for p in PARAMETERS}


def canonical_name(name: str) -> str | None:
    """The schema name (dotted, ``chain.link_damping``) of ``name`` given in either form
    (dotted, or with its dots as underscores: ``chain_link_damping``); None if neither."""
    if name in BY_NAME:
        return name
    return BY_UNDERSCORE.get(name)


def close_matches(name: str, candidates, n: int = 3) -> list[str]:
    """Up to ``n`` of ``candidates`` that look like ``name`` (a typo, a missing prefix such as
    ``link_mass`` for ``chain.link_mass``, or the other of the dotted/underscore forms): names
    with the same last component first, then difflib's closest, without repeats."""
    import difflib
    candidates = list(dict.fromkeys(candidates))
    same_tail = [c for c in candidates if "." in c and c.split(".")[-1] == name.split(".")[-1]]
    fuzzy = difflib.get_close_matches(name, candidates, n=n + len(same_tail), cutoff=0.6)
    fuzzy += difflib.get_close_matches(name.replace("_", "."), candidates, n=n, cutoff=0.6)
    out = []
    for c in same_tail + fuzzy:
        c = canonical_name(c) or c           # report a parameter by its schema name
        if c not in out:
            out.append(c)
    return out[:n]


def unknown_name_message(what: str, name: str, candidates) -> str:
    """``unknown <what> 'name'; did you mean a, b or c?`` (or no suggestion if none is close)."""
    close = close_matches(name, candidates)
    if not close:
        return f"unknown {what} {name!r}"
    listed = close[0] if len(close) == 1 else ", ".join(close[:-1]) + " or " + close[-1]
    return f"unknown {what} {name!r}; did you mean {listed}?"


def defaults() -> dict[str, Any]:
    """Every parameter at its default value."""
    return {p.name: p.default for p in PARAMETERS}


def validate(values: Mapping[str, Any], base: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Merge ``values`` over ``base`` (defaults if None) and check every entry.

    Names may be dotted (``chain.link_damping``) or underscored (``chain_link_damping``).
    Unknown names and invalid values raise ValueError naming the parameter (an unknown one with
    the names closest to it)."""
    out = dict(defaults() if base is None else base)
    for given, value in values.items():
        name = canonical_name(given)
        if name is None:
            raise ValueError(unknown_name_message("parameter", given, list(BY_NAME)
                                                  + list(BY_UNDERSCORE)) +
                             " (names: chainmodel.parameters, docs/parameters.md)")
        if name == "fidelity":
            out[name] = fidelity_level(value)
            continue
        out[name] = BY_NAME[name].check(value)
    if out["contact.seat_radius"] < out["chain.roller_radius"]:
        raise ValueError(
            f"parameter contact.seat_radius ({out['contact.seat_radius']:g} m) must be at least "
            f"chain.roller_radius ({out['chain.roller_radius']:g} m): the roller must fit its seat")
    if 2.0 * out["chain.roller_radius"] >= out["drive.pitch"]:
        raise ValueError(
            f"parameter chain.roller_radius ({out['chain.roller_radius']:g} m) must be below half "
            f"of drive.pitch ({out['drive.pitch']:g} m): adjacent rollers would overlap (ISO 606 "
            "rollers are about 0.6 pitch in diameter)")
    stale = _stale_10b_values(out)
    if stale:
        raise ValueError(
            f"parameter drive.pitch ({out['drive.pitch'] * 1e3:g} mm) is not the 15.875 mm of "
            f"the ISO 606 10B chain whose seed 003 values {', '.join(stale)} all still hold; "
            "give the values of a chain of this pitch (a scene's chain key; chainmodel.chains, "
            "docs/scenes.md) or your own")
    if out["chain.pretension"] >= out["chain.link_stiffness"] * out["drive.pitch"] * 0.05:
        raise ValueError(
            f"parameter chain.pretension ({out['chain.pretension']:g} N) would pre-strain the "
            f"chain by 5 % or more; use less than {0.05 * out['chain.link_stiffness'] * out['drive.pitch']:g} N")
    return out



#: the defaults that belong to seed 003's 10B chain (pitch 15.875 mm): all kept on a drive of
#: another pitch, no chain was ever applied to it and it would run on a 10B chain's values
#: silently (not chain.joint_clearance: every B-series chain has d3 - d2 = 0.05 mm). Some of
#: them kept is a choice (the trade study varies one value at a time) and passes.
_CHAIN_SIZE_DEFAULTS = ("chain.link_mass", "chain.link_stiffness", "chain.breaking_load",
                        "chain.roller_radius", "contact.seat_radius", "contact.stiffness",
                        "contact.damping")


def _stale_10b_values(values: Mapping[str, Any]) -> list[str]:
    """The 10B chain values on a drive whose pitch is not 10B's, if every one of them is still
    at its default; else []."""
    if abs(values["drive.pitch"] - BY_NAME["drive.pitch"].default) <= 1e-9:
        return []
    stale = [n for n in _CHAIN_SIZE_DEFAULTS if values[n] == BY_NAME[n].default]
    return stale if len(stale) == len(_CHAIN_SIZE_DEFAULTS) else []


def markdown_table() -> str:
    """The schema as a Markdown table (docs/parameters.md is generated from it)."""
    def fmt(p: Parameter) -> str:
        v = p.default
        if p.kind is float:
            return f"{v:g}"
        return str(v).lower() if p.kind is bool else str(v)

    def rng(p: Parameter) -> str:
        if p.kind is bool:
            return "true, false"
        return p.valid_text() or "any finite"

    lines = ["| name | default | unit | valid | levels | description |",
             "|---|---|---|---|---|---|"]
    for p in PARAMETERS:
        levels = ", ".join(str(k) for k in p.levels)
        unit = p.unit or "-"
        if p.display_unit:
            unit += f" (shown in {p.display_unit})"
        lines.append(f"| `{p.name}` | {fmt(p)} | {unit} | {rng(p)} | {levels} | "
                     f"{p.description.replace('|', '/')} |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":  # pragma: no cover
    print(markdown_table(), end="")


def parse_text(text: str) -> Any:
    """A value written as text (a NAME=VALUE option, a reference's start values): true/false
    (any case) as a bool, else an int, else a float, else the text itself; :func:`validate`
    then checks it against the schema."""
    t = text.strip()
    if t.lower() in ("true", "false"):
        return t.lower() == "true"
    for kind in (int, float):
        try:
            return kind(t)
        except ValueError:
            pass
    return t
