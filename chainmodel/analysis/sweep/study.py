"""A study: one base scene, settings fixed for every case, and a design (a grid or a random
sample) over any scene setting - the cases of a sweep.

A study file (TOML; every key but ``[vary]`` is optional)::

    name = "speed_pretension"
    scene = "xu2010"              # a preset, or a scene .toml (relative to this file)
    design = "grid"               # "grid": every combination; "random": `samples` draws
    samples = 40                  # random design: number of cases
    seed = 1                      # random design: generator seed (the cases are reproducible)
    resonance_band = 0.05         # relative half-width of the resonance band (metrics.py)
    spectrum_max_hz = 1000        # highest frequency kept of each case's tension spectrum

    [fixed]                       # applied to every case
    fidelity = "modal"
    duration = 1.0

    [vary]                        # grid: a list, or {start, stop, step} / {start, stop, num}
    input_speed_rpm = {start = 60, stop = 600, step = 20}
    static_tension = [600, 900, 1200]
    # random: {min, max} (uniform; whole numbers for integer parameters), {min, max, log = true}
    # (log-uniform), or a list to choose from

A name is anything :meth:`chainmodel.scene.Scene.with_overrides` takes - the scene settings
(``input_speed_rpm``, ``load_torque``, ``static_tension``, ``fidelity``, ``duration`` ...) and
every parameter of :mod:`chainmodel.parameters`, dotted or underscored - plus two drive
settings that move the centre distance the way the papers count it: ``drive.pitch_fraction``
(f) and ``drive.span_pitches`` (N), the tight span's tangent length x_c = (N + 1 + f) p of seed
000 eq 5. (To vary ``drive.links`` at the distance where the chain wraps tightly, fix
``drive.centre_distance = 0``.)

:func:`load_study` checks everything before any case runs: unknown names (with the closest
names), empty grids, bad ranges, and every case's scene (the library's own validation names the
parameter and the value).
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import numbers
import tomllib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

import numpy as np

from ... import parameters as P
from ...geometry import Drive
from ...scene import Scene, load_scene, setting_names

__all__ = ["Study", "load_study", "DRIVE_SETTINGS", "case_scene"]

#: drive settings a study may vary besides the scene's: they set drive.centre_distance
DRIVE_SETTINGS = ("drive.pitch_fraction", "drive.span_pitches")
_DRIVE_UNDERSCORE = {n.replace(".", "_"): n for n in DRIVE_SETTINGS}

_KEYS = ("name", "scene", "design", "samples", "seed", "resonance_band", "spectrum_max_hz",
         "fixed", "vary")


@dataclass(frozen=True)
class FMUBlob:
    """An FMU carried inside a study (its bytes and their SHA-256), so that workers on other
    machines get it with the study and nothing else."""

    name: str
    sha256: str
    data: bytes = field(repr=False)

    @classmethod
    def from_path(cls, path: str | Path) -> "FMUBlob":
        path = Path(path)
        if not path.is_file():
            raise ValueError(f"FMU {str(path)!r} does not exist; build it with "
                             "`python build_fmu.py`")
        data = path.read_bytes()
        return cls(path.name, hashlib.sha256(data).hexdigest(), data)


@dataclass(frozen=True)
class Study:
    """A checked study: ``base`` (the scene), ``fixed`` (settings of every case), ``cases`` (one
    dict of settings per case; canonical names) and the options of the metrics. Everything a
    worker needs; nothing refers to the client's files (``fmu`` carries the FMU's bytes).
    A case's scene is ``base`` with its fixed and case settings applied together, so a fixed
    static_tension is met with each case's stiffness or geometry."""

    name: str
    base: Scene
    varied: tuple[str, ...]
    cases: tuple[dict, ...]
    fixed: dict = field(default_factory=dict)
    design: str = "grid"
    resonance_band: float = 0.05
    spectrum_max_hz: float = 1000.0
    fmu: FMUBlob | None = None

    def __len__(self) -> int:
        return len(self.cases)

    def scene(self, index: int) -> Scene:
        """The scene of case ``index``."""
        return case_scene(self.base, {**self.fixed, **self.cases[index]})

    def with_fmu(self, fmu: str | Path | FMUBlob | None) -> "Study":
        """This study run through an FMU (a path or an :class:`FMUBlob`), or the library (None)."""
        blob = fmu if isinstance(fmu, FMUBlob) or fmu is None else FMUBlob.from_path(fmu)
        return Study(self.name, self.base, self.varied, self.cases, self.fixed, self.design,
                     self.resonance_band, self.spectrum_max_hz, blob)

    def fingerprint(self) -> str:
        """What makes a case's result: the base scene, the metric options, the FMU (by hash)
        and the library version - part of every case key, so a resumed sweep reuses a stored
        result only if it would compute the same."""
        from ..._version import __version__
        b = self.base
        text = json.dumps({"parameters": b.parameters, "operating": [b.operating.speed,
                           b.operating.ramp_time, b.operating.load_torque],
                           "duration": b.duration, "output_interval": b.output_interval,
                           "fixed": self.fixed, "band": self.resonance_band, "fmax": self.spectrum_max_hz,
                           "fmu": self.fmu.sha256 if self.fmu else None,
                           "version": __version__}, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()

    def case_keys(self) -> list[str]:
        """One key per case: a hash of its settings and :meth:`fingerprint`."""
        fp = self.fingerprint()
        return [hashlib.sha256((fp + json.dumps(c, sort_keys=True, default=repr)).encode())
                .hexdigest()[:24] for c in self.cases]


def case_scene(base: Scene, settings: Mapping[str, Any]) -> Scene:
    """``base`` with one case's settings applied; the drive settings f and N become the centre
    distance of seed 000 eq 5 (applied after the others, so varied teeth or pitch count)."""
    drive_kw = {k: v for k, v in settings.items() if k in DRIVE_SETTINGS}
    other = {k: v for k, v in settings.items() if k not in DRIVE_SETTINGS}
    scene = base.with_overrides(**other) if other else base
    if drive_kw:
        d = scene.drive
        n_span = drive_kw.get("drive.span_pitches", d.span_pitches)
        f = drive_kw.get("drive.pitch_fraction", d.pitch_fraction)
        if isinstance(n_span, bool) or not isinstance(n_span, numbers.Integral):
            raise ValueError(f"drive.span_pitches must be a whole number, got {n_span!r}")
        new = Drive(d.n_driver, d.n_driven, d.pitch, int(n_span), f, d.links)
        scene = scene.with_overrides(**{"drive.centre_distance": new.centre_distance})
    return scene


def _canonical(name: str, where: str) -> str:
    if name in DRIVE_SETTINGS or name in _DRIVE_UNDERSCORE:
        return _DRIVE_UNDERSCORE.get(name, name)
    canon = P.canonical_name(name)
    if canon is not None:
        return canon
    valid = setting_names() + list(DRIVE_SETTINGS) + list(_DRIVE_UNDERSCORE)
    if name in valid:
        return name
    raise ValueError(P.unknown_name_message(f"parameter in [{where}]", name, valid)
                     + " (a scene setting, a chainmodel.parameters name, drive.pitch_fraction "
                       "or drive.span_pitches)")


def _grid_values(name: str, spec) -> list:
    if isinstance(spec, list):
        values = spec
    elif isinstance(spec, Mapping):
        keys = set(spec)
        if keys not in ({"start", "stop", "step"}, {"start", "stop", "num"}):
            raise ValueError(f"[vary] {name}: give a list, or {{start, stop, step}} or "
                             f"{{start, stop, num}}, got keys {sorted(keys)}")
        for k in keys:
            v = spec[k]
            if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
                raise ValueError(f"[vary] {name}: {k} must be a finite number, got {v!r}")
        start, stop = spec["start"], spec["stop"]
        if "num" in spec:
            num = spec["num"]
            if not isinstance(num, numbers.Integral) or num < 1:
                raise ValueError(f"[vary] {name}: num must be a whole number >= 1, got {num!r}")
            values = np.linspace(start, stop, int(num)).tolist()
        else:
            step = spec["step"]
            if step == 0 or (stop - start) * step < 0:
                raise ValueError(f"[vary] {name}: step {step!r} does not lead from {start!r} "
                                 f"to {stop!r}")
            count = int(math.floor((stop - start) / step + 1e-9)) + 1
            values = [start + k * step for k in range(count)]
            if all(isinstance(v, numbers.Integral) for v in (start, step)):
                values = [int(v) for v in values]
            else:
                values = [float(round(v, 12)) for v in values]
    else:
        raise ValueError(f"[vary] {name}: a grid needs a list of values or {{start, stop, step}}, "
                         f"got {spec!r}")
    if len(values) == 0:
        raise ValueError(f"[vary] {name}: the grid is empty; give at least one value")
    return list(values)


def _random_values(name: str, spec, samples: int, rng: np.random.Generator) -> list:
    if isinstance(spec, list):
        if not spec:
            raise ValueError(f"[vary] {name}: the list to choose from is empty")
        return [spec[int(k)] for k in rng.integers(0, len(spec), samples)]
    if not isinstance(spec, Mapping) or not {"min", "max"} <= set(spec) \
            or not set(spec) <= {"min", "max", "log"}:
        raise ValueError(f"[vary] {name}: a random design needs {{min, max}} (optionally "
                         f"log = true) or a list to choose from, got {spec!r}")
    lo, hi = spec["min"], spec["max"]
    for k, v in (("min", lo), ("max", hi)):
        if isinstance(v, bool) or not isinstance(v, numbers.Real) or not math.isfinite(v):
            raise ValueError(f"[vary] {name}: {k} must be a finite number, got {v!r}")
    if hi < lo:
        raise ValueError(f"[vary] {name}: max {hi!r} is below min {lo!r}")
    spec_p = P.BY_NAME.get(name)
    whole = (name == "drive.span_pitches" or (spec_p is not None and spec_p.kind is int))
    if spec.get("log"):
        if lo <= 0:
            raise ValueError(f"[vary] {name}: log = true needs min > 0, got {lo!r}")
        draws = np.exp(rng.uniform(math.log(lo), math.log(hi), samples))
    elif whole:
        return [int(v) for v in rng.integers(int(math.ceil(lo)), int(math.floor(hi)) + 1, samples)]
    else:
        draws = rng.uniform(lo, hi, samples)
    return [int(round(v)) for v in draws] if whole else [float(v) for v in draws]


def load_study(study: "str | Path | Mapping[str, Any] | Study", *, check: bool = True,
               **fixed_overrides) -> Study:
    """A checked :class:`Study` from a TOML file, a dict of the same layout, or a Study.

    ``fixed_overrides`` are added to ``[fixed]`` (``chainmodel sweep --set``: e.g. a shorter
    ``duration`` to try a study quickly). With ``check`` (the default) every case's scene is
    built once here, so an invalid value is refused - naming the parameter - before any case
    runs."""
    if isinstance(study, Study):
        if fixed_overrides:
            raise ValueError("fixed overrides apply to a study file or dict, not a loaded Study")
        return study
    where = Path(".")
    if isinstance(study, (str, Path)):
        path = Path(study)
        try:
            data = tomllib.loads(path.read_text())
        except FileNotFoundError:
            raise ValueError(f"study file {str(path)!r} does not exist") from None
        except tomllib.TOMLDecodeError as exc:
            raise ValueError(f"study file {str(path)!r} is not valid TOML: {exc}") from None
        data.setdefault("name", path.stem)
        where = path.parent
    elif isinstance(study, Mapping):
        data = dict(study)
    else:
        raise ValueError(f"a study is a .toml path, a dict or a Study, got {type(study).__name__}")

    unknown = [k for k in data if k not in _KEYS]
    if unknown:
        raise ValueError(P.unknown_name_message("study key", unknown[0], _KEYS)
                         + f" (valid: {', '.join(_KEYS)})")
    name = str(data.get("name", "study"))
    design = data.get("design", "grid")
    if design not in ("grid", "random"):
        raise ValueError(f"study design must be 'grid' or 'random', got {design!r}")
    band = data.get("resonance_band", 0.05)
    if isinstance(band, bool) or not isinstance(band, numbers.Real) or not 0 < band < 1:
        raise ValueError(f"resonance_band must be a number in (0, 1), got {band!r}")
    fmax = data.get("spectrum_max_hz", 1000.0)
    if isinstance(fmax, bool) or not isinstance(fmax, numbers.Real) or not fmax > 0:
        raise ValueError(f"spectrum_max_hz must be a positive number, got {fmax!r}")

    for table in ("fixed", "vary"):
        if not isinstance(data.get(table, {}), Mapping):
            raise ValueError(f"[{table}] must be a table of NAME = VALUE")
    fixed = {_canonical(k, "fixed"): v for k, v in data.get("fixed", {}).items()}
    fixed.update({_canonical(k, "--set"): v for k, v in fixed_overrides.items()})
    vary_in = data.get("vary", {})
    if not vary_in:
        raise ValueError("the study varies nothing: give at least one parameter in [vary]")
    vary: dict[str, Any] = {}
    for k, spec in vary_in.items():
        canon = _canonical(k, "vary")
        if canon in vary:
            raise ValueError(f"[vary] names {canon} twice ({k!r})")
        vary[canon] = spec
    both = sorted(set(fixed) & set(vary))
    if both:
        raise ValueError(f"{both[0]} is both fixed and varied; keep it in one of [fixed] and [vary]")

    if design == "grid":
        if "samples" in data or "seed" in data:
            raise ValueError("samples and seed belong to design = 'random'")
        axes = {k: _grid_values(k, spec) for k, spec in vary.items()}
        cases = tuple(dict(zip(axes, combo)) for combo in itertools.product(*axes.values()))
    else:
        samples, seed = data.get("samples"), data.get("seed", 0)
        if isinstance(samples, bool) or not isinstance(samples, numbers.Integral) or samples < 1:
            raise ValueError(f"a random design needs samples = a whole number >= 1, got {samples!r}")
        if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
            raise ValueError(f"seed must be a whole number, got {seed!r}")
        rng = np.random.default_rng(int(seed))
        axes = {k: _random_values(k, spec, int(samples), rng) for k, spec in vary.items()}
        cases = tuple({k: axes[k][i] for k in axes} for i in range(int(samples)))

    scene_ref = data.get("scene", "xu2010")
    if not isinstance(scene_ref, str):
        raise ValueError(f"scene must be a preset name or a .toml path, got {scene_ref!r}")
    if scene_ref.endswith(".toml") and not Path(scene_ref).is_absolute():
        scene_ref = str(where / scene_ref)
    base = load_scene(scene_ref)
    try:
        case_scene(base, fixed)
    except ValueError as exc:
        raise ValueError(f"[fixed]: {exc}") from None
    out = Study(name, base, tuple(vary), cases, fixed, design, float(band), float(fmax))
    if check:
        for i, case in enumerate(cases):
            try:
                out.scene(i)
            except ValueError as exc:
                desc = ", ".join(f"{k} = {v!r}" for k, v in case.items())
                raise ValueError(f"study {name}, case {i} ({desc}): {exc}") from None
    return out
