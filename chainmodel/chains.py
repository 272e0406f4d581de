"""Chain parameters that belong to the chain: every ISO 606 simplex chain the presets know
carries its own dimensions, link mass, link stiffness, roller and seat radii, clearances,
roller-seat contact stiffness and damping and breaking load, each with its source.

Sources, per value (docs/scenes.md "Chains" has the table and the numbers):

* dimensions - ISO 606:2004 Table 1 (simplex chains): pitch p, roller diameter d1 max, inner
  width b1 min (the roller width), pin diameter d2 max, bush bore d3 min, inner plate depth
  h2 max, inner link outer width b2 max, minimum tensile strength F_u (the breaking load);
  pitch, d1 and F_u are :data:`chainmodel.presets.ISO606`'s;
* ``chain.roller_radius`` = d1 / 2; ``contact.seat_radius`` = ISO 606 minimum seating-curve
  radius r_i = 0.505 d1 (so the roller-seat clearance is 0.005 d1);
* ``chain.joint_clearance`` = d3 min - d2 max (pin-bushing diametral clearance, ISO 606);
* ``chain.link_mass``: steel volume of one pitch (two plates of thickness t = (b2 - b1) / 2 as
  stadiums p x h2 with round ends of diameter h2; the roller with bush and pin inside it as one
  solid cylinder d1 x b1) times rho = 7850 kg/m^3 - :func:`link_mass_law`. 10B: 17.6 g against
  seed 003's 16.2 g (+9 %);
* ``chain.link_stiffness``: seed 003 section 7's measured 10B value (51 kN/mm) carried to the
  chain by the tension stiffness of its two plates, 2 E t h2 / p (:func:`plate_stiffness`):
  k = 51 kN/mm x plate(chain) / plate(10B). The plate law alone gives 10B 707 kN/mm, 14x the
  measurement: a real link's compliance sits in its joints (pin bending, pin-bush contact), so
  the law serves for the ratio between sizes, not for the magnitude;
* ``contact.stiffness``: Hertzian line contact of the roller (radius d1 / 2) in its concave
  seat (radius r_i) over the roller width b1, steel on steel, linearised at a reference load
  of 5 % of F_u (:func:`hertz_line_contact_stiffness`, Johnson, *Contact Mechanics*, 1985,
  pp. 99-104: approach of the axes of two cylinders in line contact), carried from seed 003's
  10B value (8.46 kN/mm, its eq 16: pin-bush, bush-roller and roller-tooth contacts in series)
  by the ratio of that law between the chain and 10B. The Hertz law alone gives 10B about
  784 kN/mm, 93x seed 003's equivalent stiffness (tests/test_chains.py checks the ratio
  and docs/scenes.md): as for the link, the law gives the size dependence, the paper the level;
* ``contact.damping``: 10 % of critical for one link mass on the contact spring,
  0.1 x 2 sqrt(k_c m) (the schema default's rule for 10B);
* ``chain.breaking_load`` = F_u (ISO 606 minimum tensile strength).

A scene names its chain (``chain = "16B"``); :func:`parameter_values` gives every value above
as schema parameters, :func:`parameter_sources` where each comes from.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

from .presets import ISO606, ChainSize, reference_values

__all__ = ["ChainDimensions", "DIMENSIONS", "chain", "chain_names", "parameter_values",
           "parameter_sources", "chains_of_pitch", "default_chain_for_pitch", "CHAIN_PARAMETERS",
           "hertz_line_contact_approach", "hertz_line_contact_stiffness", "plate_stiffness",
           "link_mass_law", "STEEL_E", "STEEL_NU", "STEEL_DENSITY", "REFERENCE_LOAD_FRACTION",
           "pitch_mismatch", "tooth_width", "sprocket_disc_inertia"]

STEEL_E = 210e9          # Pa, Young's modulus of carbon steel
STEEL_NU = 0.3           # Poisson's ratio of steel
STEEL_DENSITY = 7850.0   # kg/m^3
#: the roller-seat contact is linearised at this fraction of the chain's breaking load F_u
#: (5 %: about xu2010's tight-span tension, 1.1 kN on a 22.2 kN chain)
REFERENCE_LOAD_FRACTION = 0.05

#: the schema parameters a chain sets (drive.pitch is checked against the chain, not set)
CHAIN_PARAMETERS = ("chain.link_mass", "chain.link_stiffness", "chain.joint_clearance",
                    "chain.roller_radius", "chain.breaking_load", "contact.seat_radius",
                    "contact.stiffness", "contact.damping")


@dataclass(frozen=True)
class ChainDimensions:
    """ISO 606:2004 Table 1 dimensions of a simplex chain not already in
    :class:`chainmodel.presets.ChainSize` [m]."""

    name: str
    inner_width: float        # b1 min, between the inner plates = roller width
    pin_diameter: float       # d2 max
    bush_bore: float          # d3 min
    plate_depth: float        # h2 max, inner plate depth
    inner_link_width: float   # b2 max, over the inner plates

    @property
    def size(self) -> ChainSize:
        return ISO606[self.name]

    @property
    def plate_thickness(self) -> float:
        """t = (b2 max - b1 min) / 2: the inner plate thickness ISO 606's widths leave (ISO
        gives no plate thickness; the outer plates are taken as thick)."""
        return (self.inner_link_width - self.inner_width) / 2


_MM = 1e-3
# name: b1 min, d2 max, d3 min, h2 max, b2 max [mm] (ISO 606:2004 Table 1)
DIMENSIONS: dict[str, ChainDimensions] = {d.name: d for d in (
    ChainDimensions("08A", 7.85 * _MM, 3.98 * _MM, 4.00 * _MM, 12.07 * _MM, 11.17 * _MM),
    ChainDimensions("10A", 9.40 * _MM, 5.09 * _MM, 5.11 * _MM, 15.09 * _MM, 13.84 * _MM),
    ChainDimensions("12A", 12.57 * _MM, 5.96 * _MM, 5.98 * _MM, 18.08 * _MM, 17.75 * _MM),
    ChainDimensions("16A", 15.75 * _MM, 7.94 * _MM, 7.96 * _MM, 24.13 * _MM, 22.61 * _MM),
    ChainDimensions("08B", 7.75 * _MM, 4.45 * _MM, 4.50 * _MM, 11.81 * _MM, 11.30 * _MM),
    ChainDimensions("10B", 9.65 * _MM, 5.08 * _MM, 5.13 * _MM, 14.73 * _MM, 13.28 * _MM),
    ChainDimensions("12B", 11.68 * _MM, 5.72 * _MM, 5.77 * _MM, 16.13 * _MM, 15.62 * _MM),
    ChainDimensions("16B", 17.02 * _MM, 8.28 * _MM, 8.33 * _MM, 21.08 * _MM, 25.45 * _MM),
)}


def chain_names() -> list[str]:
    return list(DIMENSIONS)


def chain(name: str) -> ChainDimensions:
    """The chain called ``name`` (08A ... 16B); ValueError naming the valid ones."""
    key = str(name).strip().upper()
    if key not in DIMENSIONS:
        raise ValueError(f"unknown chain {name!r}; choose one of: {', '.join(DIMENSIONS)} "
                         "(ISO 606 simplex chains)")
    return DIMENSIONS[key]


def chains_of_pitch(pitch: float) -> list[str]:
    """The chains whose pitch is ``pitch`` [m] (to 1 um), B series first."""
    found = [n for n in DIMENSIONS if abs(ISO606[n].pitch - pitch) < 1e-6]
    return sorted(found, key=lambda n: (not n.endswith("B"), n))


def default_chain_for_pitch(pitch: float) -> str | None:
    """The B-series chain of ``pitch`` (else an A-series one), None if no chain has it."""
    found = chains_of_pitch(pitch)
    return found[0] if found else None


# --- laws -----------------------------------------------------------------------------------
def hertz_line_contact_approach(load: float, length: float, radius: float,
                                seat_radius: float | None = None, E: float = STEEL_E,
                                nu: float = STEEL_NU) -> float:
    """Approach [m] of the axes of a cylinder (``radius``) and a concave seat (``seat_radius``;
    None: a flat) pressed together by ``load`` [N] over ``length`` [m], both of one elastic
    material (Johnson, Contact Mechanics, 1985, pp. 99-104):

        P' = load / length,  1/R = 1/radius - 1/seat_radius,  E* = E / (2 (1 - nu^2)),
        b = sqrt(4 P' R / (pi E*))          (semi-width of the contact),
        delta = P' (1 - nu^2) / (pi E) * [2 ln(4 radius / b) - 1 + 2 ln(4 R_s / b) - 1]

    with R_s = seat_radius (radius for a flat)."""
    line = load / length
    inv_r = 1 / radius - (1 / seat_radius if seat_radius else 0.0)
    if inv_r <= 0:
        raise ValueError(f"seat_radius ({seat_radius!r} m) must exceed radius ({radius!r} m)")
    e_star = E / (2 * (1 - nu * nu))
    b = math.sqrt(4 * line / inv_r / (math.pi * e_star))
    outer = seat_radius if seat_radius else radius
    return line * (1 - nu * nu) / (math.pi * E) * (2 * math.log(4 * radius / b) - 1
                                                   + 2 * math.log(4 * outer / b) - 1)


def hertz_line_contact_stiffness(load: float, length: float, radius: float,
                                 seat_radius: float | None = None) -> float:
    """Tangent stiffness d(load)/d(approach) [N/m] of :func:`hertz_line_contact_approach` at
    ``load`` (central difference, +-0.1 %)."""
    h = 1e-3 * load
    d = (hertz_line_contact_approach(load + h, length, radius, seat_radius)
         - hertz_line_contact_approach(load - h, length, radius, seat_radius))
    return 2 * h / d


def plate_stiffness(c: ChainDimensions) -> float:
    """Tension stiffness of a link's two plates as bars of section t x h2 over the pitch,
    2 E t h2 / p [N/m]."""
    return 2 * STEEL_E * c.plate_thickness * c.plate_depth / c.size.pitch


def link_mass_law(c: ChainDimensions) -> float:
    """Steel mass of one pitch [kg]: two plates (stadium p x h2 with round ends of diameter
    h2, thickness t) and the roller with its bush and pin as one solid cylinder d1 x b1."""
    p, h, t = c.size.pitch, c.plate_depth, c.plate_thickness
    plates = 2 * t * (p * h + math.pi * h * h / 4)
    roller = math.pi * c.size.roller_diameter ** 2 / 4 * c.inner_width
    return STEEL_DENSITY * (plates + roller)


def tooth_width(c: ChainDimensions) -> float:
    """ISO 606 sprocket tooth width bf1 of a simplex sprocket [m]: 0.93 b1 up to 12.7 mm pitch,
    0.95 b1 above."""
    return (0.93 if c.size.pitch <= 12.7e-3 + 1e-9 else 0.95) * c.inner_width


def sprocket_disc_inertia(name: str, teeth: int) -> float:
    """Polar moment of inertia [kg m^2] of a ``teeth``-tooth sprocket for chain ``name`` taken
    as a solid steel disc of its pitch diameter d = p / sin(pi / z) and the ISO 606 tooth
    width w (:func:`tooth_width`): I = rho pi w d^4 / 32. No hub, shaft or machine: an
    estimate for a drive whose real inertias are not yet known (the example scenes' rule)."""
    from .geometry import Sprocket
    c = chain(name)
    d = 2.0 * Sprocket(teeth, c.size.pitch).pitch_radius
    return STEEL_DENSITY * math.pi * tooth_width(c) * d ** 4 / 32


def _seat_contact_law(c: ChainDimensions) -> float:
    d1 = c.size.roller_diameter
    return hertz_line_contact_stiffness(REFERENCE_LOAD_FRACTION * c.size.tensile_strength,
                                        c.inner_width, d1 / 2, 0.505 * d1)


@lru_cache(maxsize=None)
def parameter_values(name: str) -> dict[str, float]:
    """The schema parameters chain ``name`` sets (:data:`CHAIN_PARAMETERS`) and its pitch as
    ``drive.pitch``, in SI units."""
    c = chain(name)
    ref = DIMENSIONS["10B"]
    seed = reference_values("multibody_example_xu2010.csv")    # seed 003 section 7 (10B)
    d1 = c.size.roller_diameter
    mass = link_mass_law(c)
    k_contact = seed["k_contact"] * _seat_contact_law(c) / _seat_contact_law(ref)
    return {
        "drive.pitch": c.size.pitch,
        "chain.link_mass": mass,
        "chain.link_stiffness": seed["k_link"] * plate_stiffness(c) / plate_stiffness(ref),
        "chain.joint_clearance": round(c.bush_bore - c.pin_diameter, 12),
        "chain.roller_radius": d1 / 2,
        "chain.breaking_load": c.size.tensile_strength,
        "contact.seat_radius": round(0.505 * d1, 12),
        "contact.stiffness": k_contact,
        "contact.damping": 0.1 * 2 * math.sqrt(k_contact * mass),
    }


def parameter_sources(name: str) -> dict[str, str]:
    """Where each of :func:`parameter_values` comes from, one short phrase per parameter."""
    c = chain(name)
    return {
        "drive.pitch": f"ISO 606 {c.name} pitch",
        "chain.link_mass": f"steel volume of ISO 606 {c.name} plates and roller x 7850 kg/m3",
        "chain.link_stiffness": f"seed 003's 10B 51 kN/mm x plate stiffness {c.name}/10B",
        "chain.joint_clearance": f"ISO 606 {c.name} bush bore d3 min - pin d2 max",
        "chain.roller_radius": f"ISO 606 {c.name} roller d1 / 2",
        "chain.breaking_load": f"ISO 606 {c.name} minimum tensile strength",
        "contact.seat_radius": f"ISO 606 r_i min = 0.505 d1 ({c.name})",
        "contact.stiffness": (f"seed 003's 10B 8.46 kN/mm x Hertz roller-in-seat line contact "
                              f"{c.name}/10B (Johnson 1985)"),
        "contact.damping": "10 % of critical for one link mass on the contact spring",
    }


def pitch_mismatch(name: str, pitch: float) -> str | None:
    """None if chain ``name`` has pitch ``pitch`` [m], else why not (naming the parameters)."""
    c = chain(name)
    if abs(c.size.pitch - pitch) <= 1e-9:
        return None
    others = chains_of_pitch(pitch)
    fix = (f"name a chain of that pitch ({', '.join(others)})" if others else
           "no ISO 606 chain here has that pitch: give no chain and every chain value")
    return (f"drive.pitch ({pitch * 1e3:g} mm) does not match chain {c.name} (pitch "
            f"{c.size.pitch * 1e3:g} mm); set drive.pitch to {c.size.pitch * 1e3:g} mm or {fix}")


def _main(argv=None) -> int:
    """``python -m chainmodel.chains``: the table of every chain's values (docs/scenes.md);
    ``python -m chainmodel.chains 16B``: that chain's values as ``build_fmu.py --default``
    arguments (an FMU whose start values are the chain's)."""
    import sys
    args = list(sys.argv[1:] if argv is None else argv)
    if args:
        try:
            values = parameter_values(args[0])
        except ValueError as exc:
            sys.stderr.write(f"chainmodel: error: {exc}\n")
            return 2
        print(" ".join(f"--default {k}={v!r}" for k, v in values.items()))
        return 0
    names = chain_names()
    print("| parameter | " + " | ".join(names) + " |")
    print("|---" * (len(names) + 1) + "|")
    for key in ("drive.pitch",) + CHAIN_PARAMETERS:
        print(f"| `{key}` | " + " | ".join(f"{parameter_values(n)[key]:.4g}" for n in names)
              + " |")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(_main())
