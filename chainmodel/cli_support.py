"""The helpers every ``chainmodel`` subcommand uses (the CLI and the analysis packages'
commands alike): argument groups, the drive from flags, JSON and CSV writers, ``--set``
parsing, the FMU's path, and :class:`CLIError`. A module of its own so that the analysis
packages import them without importing :mod:`chainmodel.cli` (which imports them by name:
no cycle). ``chainmodel.cli`` re-exports every name."""

from __future__ import annotations

import argparse
import csv
import json
import math
import sys
from pathlib import Path
from typing import Any, Mapping, Sequence

import numpy as np

__all__ = ["CLIError", "DEFAULT_PITCH", "FMU_NAME", "add_drive_arguments", "add_output_arguments",
           "drive_dict", "drive_from_args", "fmu_path", "jsonable", "parse_settings",
           "print_json", "write_csv_columns"]

DEFAULT_PITCH = 0.0254          # m, the pitch of seeds 000 and 004
FMU_NAME = "ChainDrive.fmu"


class CLIError(Exception):
    """A user mistake found by the CLI itself (printed as one line, exit status 2)."""


# --- shared helpers for subcommands---------------------------------------------------------

def jsonable(value: Any) -> Any:
    """``value`` with numpy arrays and scalars turned into lists and floats, and nan/inf into
    None (JSON has no nan)."""
    if isinstance(value, Mapping):
        return {str(k): jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    if isinstance(value, np.ndarray):
        return [jsonable(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        v = float(value)
        return v if math.isfinite(v) else None
    if value is None or isinstance(value, str):
        return value
    if isinstance(value, Path):
        return str(value)
    raise TypeError(f"cannot write {type(value).__name__} as JSON")


def print_json(obj: Mapping[str, Any]) -> None:
    """Print ``obj`` as one JSON object on stdout (strict JSON: no NaN)."""
    sys.stdout.write(json.dumps(jsonable(obj), allow_nan=False) + "\n")


def write_csv_columns(path: str | Path, columns: Mapping[str, Sequence[float]],
                      units: Mapping[str, str]) -> Path:
    """Write equal-length columns as CSV: a header row of names, a row of units, then values
    (the layout of :meth:`chainmodel.simulation.Result.to_csv`)."""
    path = Path(path)
    names = list(columns)
    arrays = [np.asarray(columns[n], float) for n in names]
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        w.writerow([units.get(n, "") for n in names])
        for row in zip(*arrays):
            w.writerow([repr(float(v)) for v in row])
    return path


def add_output_arguments(p: argparse.ArgumentParser, csv_help: str = "write the arrays as CSV",
                         plot_help: str = "write a figure (needs matplotlib)") -> None:
    g = p.add_argument_group("output")
    g.add_argument("--json", action="store_true",
                   help="print one JSON object (snake_case keys, SI units) and nothing else")
    g.add_argument("--csv", metavar="PATH", help=csv_help)
    g.add_argument("--plot", metavar="FILE", help=plot_help + "; .png, .pdf or .svg, by the "
                   "file's extension")


def add_drive_arguments(p: argparse.ArgumentParser) -> None:
    """--preset NAME, or an explicit drive; explicit values override a preset's."""
    g = p.add_argument_group(
        "drive", "a preset (chainmodel presets lists them), or the explicit geometry; explicit "
                 "values given with --preset override the preset's")
    g.add_argument("--preset", metavar="NAME", help="named drive, e.g. medium, C1, xu2010")
    g.add_argument("--driver-teeth", type=int, metavar="N", help="teeth on the driver, n_c")
    g.add_argument("--driven-teeth", type=int, metavar="N", help="teeth on the driven sprocket, n_o")
    g.add_argument("--span-pitches", type=int, metavar="N",
                   help="N: whole pitches in the tight span, x_c = (N + 1 + f) p")
    g.add_argument("--pitch-fraction", type=float, metavar="F", help="f in [0, 1)")
    g.add_argument("--pitch", type=float, metavar="P",
                   help=f"chain pitch [m] (default {DEFAULT_PITCH}, the seeds' 25.4 mm)")
    g.add_argument("--centre-distance", type=float, metavar="A",
                   help="shaft centre distance [m], instead of --span-pitches/--pitch-fraction")
    g.add_argument("--links", type=int, metavar="M",
                   help="links in the chain; alone (no N, f or distance) it sets the centre "
                        "distance at which the chain wraps tightly")


_DRIVE_FLAGS = {"driver_teeth": "n_driver", "driven_teeth": "n_driven", "pitch": "pitch",
                "span_pitches": "span_pitches", "pitch_fraction": "pitch_fraction",
                "centre_distance": "centre_distance", "links": "links"}


def drive_from_args(args: argparse.Namespace):
    """The :class:`chainmodel.Drive` that ``add_drive_arguments`` flags describe."""
    from .geometry import Drive
    from .presets import preset
    given = {key: getattr(args, flag) for flag, key in _DRIVE_FLAGS.items()
             if getattr(args, flag, None) is not None}
    if "centre_distance" in given and ({"span_pitches", "pitch_fraction"} & set(given)):
        raise CLIError("give either --centre-distance or --span-pitches/--pitch-fraction, not both")
    if args.preset is not None:
        return preset(args.preset, **given)
    missing = [f"--{f.replace('_', '-')}" for f in ("driver_teeth", "driven_teeth")
               if getattr(args, f) is None]
    if missing:
        raise CLIError("give --preset NAME, or an explicit drive: --driver-teeth, --driven-teeth "
                       "and --span-pitches with --pitch-fraction (or --centre-distance, or "
                       f"--links); missing {' and '.join(missing)}")
    n1, n2 = given["n_driver"], given["n_driven"]
    pitch, links = given.get("pitch", DEFAULT_PITCH), given.get("links")
    if "centre_distance" in given:
        return Drive.from_centre_distance(n1, n2, pitch, given["centre_distance"], links)
    if "span_pitches" in given and "pitch_fraction" in given:
        return Drive(n1, n2, pitch, given["span_pitches"], given["pitch_fraction"], links)
    if links is not None and not ({"span_pitches", "pitch_fraction"} & set(given)):
        return Drive.from_links(n1, n2, pitch, links)
    lacking = "--pitch-fraction" if "span_pitches" in given else "--span-pitches"
    raise CLIError(f"the explicit drive needs {lacking} too (or --centre-distance, or --links "
                   "alone for the tight centre distance)")


def drive_dict(drive) -> dict[str, Any]:
    """The drive's defining values (SI units), as every JSON output reports them."""
    return {"name": drive.name, "n_driver": drive.n_driver, "n_driven": drive.n_driven,
            "pitch_m": drive.pitch, "span_pitches": drive.span_pitches,
            "pitch_fraction": drive.pitch_fraction, "links": drive.links,
            "centre_distance_m": drive.centre_distance, "tooth_ratio": drive.tooth_ratio}


#: scene settings that --set reads as numbers (fidelity takes a name or a level)
_NUMERIC_SETTINGS = ("duration", "output_interval", "input_speed_rpm", "input_speed",
                     "ramp_time", "load_torque", "static_tension")


def parse_settings(items: Sequence[str]) -> dict[str, Any]:
    """--set NAME=VALUE items -> keyword overrides for :meth:`Scene.with_overrides`, which
    accepts exactly what the Python API does: the scene settings (input_speed_rpm,
    static_tension, ...) and every parameter, dotted (chain.link_damping) or underscored
    (chain_link_damping). Unknown names are left for the scene to refuse with the closest
    names."""
    from .parameters import BY_NAME, canonical_name
    out: dict[str, Any] = {}
    for item in items:
        name, sep, text = item.partition("=")
        name, text = name.strip(), text.strip()
        if not sep or not name or not text:
            raise CLIError(f"--set expects NAME=VALUE, got {item!r}")
        canon = canonical_name(name)
        spec = BY_NAME.get(canon) if canon else None
        if name in _NUMERIC_SETTINGS or (spec is not None and canon != "fidelity"
                                         and spec.kind not in (bool, str)):
            out[canon or name] = _number(name, text)
        else:
            out[canon or name] = text       # fidelity, booleans, choices: the scene parses them
    return out


def _number(name: str, text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise CLIError(f"--set {name}: {text!r} is not a number") from None
    return value


def fmu_path(given: str) -> Path:
    if given:
        path = Path(given)
        if not path.is_file():
            raise CLIError(f"FMU {given} not found; build it with `python build_fmu.py` or give "
                           "the path of a built ChainDrive.fmu")
        return path
    candidates = [Path("dist") / FMU_NAME,
                  Path(__file__).resolve().parent.parent / "dist" / FMU_NAME]
    for path in candidates:
        if path.is_file():
            return path
    raise CLIError(f"FMU dist/{FMU_NAME} not found; build it first with `python build_fmu.py`")
