"""``chainmodel new-scene``: write a commented scene file for one's own drive from its teeth,
its chain (or pitch), speed and load - the layout docs/scenes.md documents. Also
``python -m chainmodel.new_scene``.

What the file gets when not given (each written as a comment in the file):

* links: the even number nearest above the chain length for a centre distance of 40 pitches
  (the middle of the usual 30-50 p), L/p = 2 a/p + (z1 + z2)/2 + ((z2 - z1)/(2 pi))^2 p/a
  (the chain-length formula of chain-drive design, e.g. ISO 10823 Annex); the scene then runs
  at the centre distance where these links wrap tightly (drive.centre_distance = 0);
* static_tension: 2 % of the chain's breaking load (an installation pretension; the models
  need some - a tight chain at zero tension has no stiffness across its spans);
* chain: the B-series ISO 606 chain of the pitch (chainmodel.chains);
* driver.inertia, driven.inertia: each sprocket as a solid steel disc of its pitch diameter and
  the ISO 606 tooth width (:func:`chainmodel.chains.sprocket_disc_inertia`, the example scenes'
  rule) - no hub, shaft or machine, so give the real ones when known.
"""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

__all__ = ["register", "main", "scene_text", "chain_length_links"]

#: centre distance the link count is chosen for, in pitches (30-50 p is the usual range)
CENTRE_DISTANCE_PITCHES = 40
#: static span tension written when none is given, as a fraction of the breaking load
STATIC_TENSION_FRACTION = 0.02


def chain_length_links(n_driver: int, n_driven: int, centre_pitches: float) -> int:
    """The even link count nearest above L/p = 2 a/p + (z1 + z2)/2 + ((z2 - z1)/(2 pi))^2 p/a
    at a centre distance of ``centre_pitches`` pitches."""
    a = centre_pitches
    length = 2 * a + (n_driver + n_driven) / 2 + ((n_driven - n_driver) / (2 * math.pi)) ** 2 / a
    links = math.ceil(length)
    return links + (links % 2)


def _toml_string(text: str) -> str:
    """``text`` as a TOML basic string (JSON's escapes are TOML's for these characters)."""
    return json.dumps(str(text), ensure_ascii=False)


def scene_text(driver_teeth: int, driven_teeth: int, speed_rpm: float, load_torque: float,
               chain: str | None = None, pitch: float | None = None, links: int | None = None,
               centre_distance: float | None = None, static_tension: float | None = None,
               name: str = "my drive", fidelity: str = "torsional", duration: float = 1.0,
               output_interval: float = 1e-4, driver_inertia: float | None = None,
               driven_inertia: float | None = None) -> str:
    """The commented TOML of a scene; ValueError (naming the option) on bad input. The text is
    checked by loading it (:class:`chainmodel.scene.Scene`) before it is returned."""
    from . import chains as C
    from .geometry import Sprocket
    from .parameters import BY_NAME, fidelity_level
    for opt, v in (("driver_teeth", driver_teeth), ("driven_teeth", driven_teeth)):
        BY_NAME[f"drive.{opt}"].check(v)
    for opt, v in (("speed_rpm", speed_rpm), ("load_torque", load_torque)):
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
            raise ValueError(f"{opt} must be a finite number, got {v!r}")
    fidelity_level(fidelity)
    if chain is None and pitch is None:
        raise ValueError("give the chain (chain, e.g. 08B) or the pitch (pitch [m]); chains: "
                         + ", ".join(C.chain_names()))
    notes = []
    if chain is None:
        BY_NAME["drive.pitch"].check(pitch)
        chain = C.default_chain_for_pitch(pitch)
        if chain is None:
            raise ValueError(f"pitch {pitch * 1e3:g} mm is the pitch of no ISO 606 chain here "
                             f"({', '.join(C.chain_names())}); name a chain")
        notes.append(f"chain {chain}: the B-series ISO 606 chain of pitch {pitch * 1e3:g} mm "
                     f"(assumed; {', '.join(C.chains_of_pitch(pitch))} have this pitch)")
    c = C.chain(chain)
    p = c.size.pitch
    if pitch is not None and abs(pitch - p) > 1e-9:
        raise ValueError(C.pitch_mismatch(c.name, pitch))
    values = C.parameter_values(c.name)
    if links is None:
        links = chain_length_links(driver_teeth, driven_teeth, CENTRE_DISTANCE_PITCHES)
        notes.append(f"links {links}: the even count nearest above the chain length at a "
                     f"{CENTRE_DISTANCE_PITCHES}-pitch centre distance (assumed)")
    BY_NAME["drive.links"].check(links)
    if static_tension is None:
        static_tension = round(STATIC_TENSION_FRACTION * values["chain.breaking_load"], 1)
        notes.append(f"static_tension {static_tension:g} N: {100 * STATIC_TENSION_FRACTION:g} % "
                     f"of the {c.name} breaking load (assumed installation pretension)")
    inertias = {}
    for side, teeth, given in (("driver", driver_teeth, driver_inertia),
                               ("driven", driven_teeth, driven_inertia)):
        key = f"{side}.inertia"
        if given is not None:
            inertias[key] = BY_NAME[key].check(given)
            continue
        inertias[key] = float(f"{C.sprocket_disc_inertia(c.name, teeth):.4g}")
        d = 2.0 * Sprocket(teeth, p).pitch_radius
        notes.append(f"{key} {inertias[key]:g} kg.m2: a solid steel disc of the {teeth}-tooth "
                     f"sprocket's pitch diameter {d * 1e3:.2f} mm and the ISO 606 tooth width "
                     f"{C.tooth_width(c) * 1e3:.2f} mm (no hub, shaft or machine: give yours)")
    a_line = (f"\"drive.centre_distance\" = {centre_distance!r}   # m" if centre_distance else
              "\"drive.centre_distance\" = 0.0   # m; 0: where the chain wraps tightly")
    lines = [
        f"# Scene file for chainmodel (docs/scenes.md), written by `chainmodel new-scene`.",
        f"# Run it: chainmodel run THIS_FILE [--fidelity 0-3]",
        *[f"# assumed: {n}" for n in notes],
        f"name = {_toml_string(name)}",
        f"chain = \"{c.name}\"                # ISO 606 chain: sets link mass, stiffness, radii,",
        f"                              # clearances, contact stiffness, breaking load",
        f"fidelity = \"{fidelity}\"       # 0 kinematic, 1 torsional, 2 modal, 3 multibody",
        f"duration = {duration!r}                # s of simulated time",
        f"output_interval = {output_interval!r}       # s between output samples",
        "",
        "[operating]",
        f"input_speed_rpm = {speed_rpm!r}      # steady input-shaft speed [rpm]",
        f"ramp_time = 0.05             # s, linear ramp from rest",
        f"load_torque = {load_torque!r}         # N.m on the driven shaft",
        (f"static_tension = {static_tension!r}      # N at rest: sets chain.pretension"
         if static_tension else "# no static_tension: chain.pretension = 0 below"),
        "",
        "[parameters]                  # any name of docs/parameters.md; given values win",
        f"\"drive.driver_teeth\" = {driver_teeth}",
        f"\"drive.driven_teeth\" = {driven_teeth}",
        f"\"drive.pitch\" = {p!r}        # m, ISO 606 {c.name}",
        f"\"drive.links\" = {links}",
        a_line,
        *[f"\"{k}\" = {v!r}   # kg.m2" for k, v in inertias.items()],
        *(["\"chain.pretension\" = 0.0     # no pretension: the chain carries the tension its "
           "own weight gives (its sag)"] if not static_tension else []),
        "# the chain's values, for reference (uncomment one to replace it):",
        *[f"# \"{k}\" = {v:.6g}" for k, v in values.items() if k != "drive.pitch"],
        "# values no chain gives keep their defaults (shaft, damping), e.g.:",
        "# \"input_shaft.stiffness\" = 12000  # N.m/rad",
    ]
    text = "\n".join(lines) + "\n"
    _check(text)
    return text


def _check(text: str) -> None:
    import tempfile
    from .scene import Scene
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "scene.toml"
        path.write_text(text)
        Scene.from_toml(path)


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--driver-teeth", type=int, required=True, help="teeth on the driver, z1")
    p.add_argument("--driven-teeth", type=int, required=True, help="teeth on the driven sprocket, z2")
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--chain", help="ISO 606 chain: 08A 10A 12A 16A 08B 10B 12B 16B")
    g.add_argument("--pitch", type=float, help="pitch [mm]; the B-series chain of it is assumed")
    p.add_argument("--speed-rpm", type=float, required=True, help="input-shaft speed [rpm]")
    p.add_argument("--load-torque", type=float, required=True, help="load on the driven shaft [N.m]")
    p.add_argument("--links", type=int, help="links in the chain (default: for 40 pitches of "
                                             "centre distance)")
    p.add_argument("--centre-distance", type=float, metavar="MM",
                   help="shaft centre distance [mm] (default: where the links wrap tightly)")
    p.add_argument("--static-tension", type=float, metavar="N",
                   help="static span tension at rest [N] (default 2 %% of the breaking load; "
                        "0: no pretension, the chain carries what its own weight gives)")
    p.add_argument("--driver-inertia", type=float, metavar="KG_M2",
                   help="driver side's inertia [kg.m2] (default: a solid steel disc of the "
                        "sprocket)")
    p.add_argument("--driven-inertia", type=float, metavar="KG_M2",
                   help="driven side's inertia [kg.m2] (default: a solid steel disc of the "
                        "sprocket)")
    p.add_argument("--name", default="my drive", help="scene name")
    p.add_argument("--fidelity", default="torsional", help="0-3 or kinematic ... multibody")
    p.add_argument("-o", "--out", metavar="FILE.toml",
                   help="write here (refuses to overwrite); default: print the file")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "new-scene", help="write a commented scene file for your own drive",
        description="Write a commented scene TOML (docs/scenes.md) from teeth, chain or pitch, "
                    "speed and load; every value it assumes is said in the file.")
    _add_arguments(p)
    p.set_defaults(handler=run)


def run(args) -> int:
    from .cli_support import CLIError
    out = Path(args.out) if args.out else None
    if out is not None and out.exists():
        raise CLIError(f"--out {out}: the file exists; give another name")
    if out is not None and out.suffix != ".toml":
        raise CLIError(f"--out {out}: a scene file must end in .toml")
    try:
        text = scene_text(args.driver_teeth, args.driven_teeth, args.speed_rpm, args.load_torque,
                          chain=args.chain,
                          pitch=None if args.pitch is None else args.pitch * 1e-3,
                          links=args.links,
                          centre_distance=(None if args.centre_distance is None
                                           else args.centre_distance * 1e-3),
                          static_tension=args.static_tension, name=args.name,
                          fidelity=args.fidelity, driver_inertia=args.driver_inertia,
                          driven_inertia=args.driven_inertia)
    except ValueError as exc:
        raise CLIError(str(exc)) from None
    if out is None:
        sys.stdout.write(text)
    else:
        out.write_text(text)
        print(f"wrote scene to {out}; run it with: chainmodel run {out}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m chainmodel.new_scene", description=__doc__)
    _add_arguments(ap)
    from .cli_support import CLIError
    try:
        return run(ap.parse_args(argv))
    except CLIError as exc:
        ap.exit(2, f"chainmodel: error: {exc}\n")


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

