"""Named drives from the papers and ISO 606 roller chains.

* ``coarse``, ``medium``, ``fine``: seed 000 Table 1 (pitch 25.4 mm as in its section 5; the
  paper varies f, we default to f = 0.5 for coarse and fine and to the f = 0.43, 40-link chain
  of its multibody comparison for medium);
* ``A1`` ... ``D3``: seed 004 Table 1 (pitch 25.4 mm, its section 6);
* ``xu2010``: seed 003 section 7, 25/17 teeth, p = 15.875 mm, 46 links at 197.7 mm.

The tables are read from ``chainmodel/data`` (copies of ``shared/reference``).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from importlib import resources

from .geometry import Drive

__all__ = ["preset", "preset_names", "reference_table", "reference_values", "ISO606",
           "ChainSize", "iso606", "iso606_matches"]

INCH = 0.0254


def _read(name: str) -> list[dict[str, str]]:
    # relative to this package, so a vendored copy (inside the FMU) reads its own data
    text = resources.files(__package__).joinpath("data", name).read_text()
    lines = [ln for ln in text.splitlines() if ln.strip() and not ln.startswith("#")]
    return list(csv.DictReader(lines))


@lru_cache(maxsize=None)
def reference_table(name: str) -> tuple[dict[str, str], ...]:
    """Rows of a reference CSV in ``chainmodel/data`` (header comment lines dropped)."""
    return tuple(_read(name))


@lru_cache(maxsize=None)
def reference_values(name: str) -> dict[str, float]:
    """A name,value,... CSV (Table 2, xu2010) as a dict of floats."""
    return {row["name"]: float(row["value"]) for row in reference_table(name)}


def _table1_drives() -> dict[str, dict]:
    out = {}
    for row in reference_table("wrap_length_jsv2016_table1.csv"):
        out[row["id"]] = dict(n_driver=int(row["n_c"]), n_driven=int(row["n_o"]), pitch=INCH,
                              span_pitches=int(row["N"]), pitch_fraction=float(row["f"]),
                              links=int(row["M"]))
    return out


def _mmt_drives() -> dict[str, dict]:
    out = {}
    default_f = {"coarse": 0.5, "medium": 0.43, "fine": 0.5}
    links = {"medium": 40}
    for row in reference_table("kinematic_configs_mmt2016_table1.csv"):
        name = row["name"]
        out[name] = dict(n_driver=int(row["n_c"]), n_driven=int(row["n_o"]), pitch=INCH,
                         span_pitches=int(row["N"]), pitch_fraction=default_f[name],
                         links=links.get(name))
    return out


def _xu2010() -> dict:
    v = reference_values("multibody_example_xu2010.csv")
    return dict(n_driver=int(v["z1"]), n_driven=int(v["z2"]), pitch=v["pitch"],
                centre_distance=v["center_distance"], links=int(v["links"]))


@lru_cache(maxsize=None)
def _catalogue() -> dict[str, dict]:
    cat = {}
    cat.update(_mmt_drives())
    cat.update(_table1_drives())
    cat["xu2010"] = _xu2010()
    return cat


def preset_names() -> list[str]:
    """All preset names, in the order: seed 000, seed 004 Table 1, seed 003."""
    return list(_catalogue())


def preset(name: str, **overrides) -> Drive:
    """The named drive; keyword overrides replace any of its defining values
    (n_driver, n_driven, pitch, links, and span_pitches/pitch_fraction or centre_distance)."""
    cat = _catalogue()
    if name not in cat:
        raise ValueError(f"unknown preset {name!r}; choose one of: {', '.join(cat)}")
    spec = dict(cat[name])
    if "centre_distance" in overrides:
        spec.pop("span_pitches", None)
        spec.pop("pitch_fraction", None)
    if "span_pitches" in overrides or "pitch_fraction" in overrides:
        spec.pop("centre_distance", None)
    unknown = set(overrides) - {"n_driver", "n_driven", "pitch", "links", "span_pitches",
                                "pitch_fraction", "centre_distance"}
    if unknown:
        raise ValueError(f"preset {name!r} cannot override {sorted(unknown)}; valid overrides: "
                         "n_driver, n_driven, pitch, links, span_pitches, pitch_fraction, "
                         "centre_distance")
    spec.update(overrides)
    if "centre_distance" in spec:
        return Drive.from_centre_distance(spec["n_driver"], spec["n_driven"], spec["pitch"],
                                          spec["centre_distance"], spec.get("links"), name=name)
    if "span_pitches" not in spec or "pitch_fraction" not in spec:
        # a preset defined by its centre distance (xu2010) with only N or only f overridden:
        # the other one comes from the preset's own geometry
        base = preset(name)
        spec.setdefault("span_pitches", base.span_pitches)
        spec.setdefault("pitch_fraction", base.pitch_fraction)
    return Drive(spec["n_driver"], spec["n_driven"], spec["pitch"], spec["span_pitches"],
                 spec["pitch_fraction"], spec.get("links"), name=name)


@dataclass(frozen=True)
class ChainSize:
    """An ISO 606 roller chain: pitch p, roller diameter d1 and minimum tensile strength."""

    name: str
    pitch: float              # m
    roller_diameter: float    # m
    tensile_strength: float   # N, ISO 606 minimum for the simplex chain

    @property
    def roller_radius(self) -> float:
        return self.roller_diameter / 2

    def seat_radius_range(self) -> tuple[float, float]:
        """ISO 606 seating-curve radius limits r_i (min, max) [m]:
        0.505 d1 and 0.505 d1 + 0.069 d1^(1/3) (d1 in mm)."""
        d1 = self.roller_diameter * 1e3
        return 0.505 * d1 * 1e-3, (0.505 * d1 + 0.069 * d1 ** (1 / 3)) * 1e-3


# ISO 606 simplex chains (A series = ANSI sizes, B series = European), common sizes.
ISO606 = {c.name: c for c in (
    ChainSize("08A", 12.70e-3, 7.92e-3, 13.9e3),
    ChainSize("10A", 15.875e-3, 10.16e-3, 21.8e3),
    ChainSize("12A", 19.05e-3, 11.91e-3, 31.3e3),
    ChainSize("16A", 25.40e-3, 15.88e-3, 55.6e3),
    ChainSize("08B", 12.70e-3, 8.51e-3, 17.8e3),
    ChainSize("10B", 15.875e-3, 10.16e-3, 22.2e3),
    ChainSize("12B", 19.05e-3, 12.07e-3, 28.9e3),
    ChainSize("16B", 25.40e-3, 15.88e-3, 60.0e3),
)}


def iso606_matches(pitch: float, roller_diameter: float) -> tuple[list[ChainSize], bool]:
    """The ISO 606 chains of this pitch [m] (to 0.1 %) and, of those, the ones whose roller
    diameter [m] matches to 10 um if any does (else all of the pitch); and whether the roller
    matched. ([], False) for a pitch ISO 606 does not list here."""
    sizes = [c for c in ISO606.values() if abs(c.pitch - pitch) <= 1e-3 * c.pitch]
    same = [c for c in sizes if abs(c.roller_diameter - roller_diameter) <= 1e-5]
    return (same, True) if same else (sizes, False)


def iso606(name: str) -> ChainSize:
    if name not in ISO606:
        raise ValueError(f"unknown ISO 606 chain {name!r}; choose one of: {', '.join(ISO606)}")
    return ISO606[name]
