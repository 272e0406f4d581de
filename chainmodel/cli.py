"""The ``chainmodel`` command.

Subcommands (``chainmodel SUBCOMMAND --help`` for the flags; docs/cli.md for the JSON keys)::

    chainmodel run SCENE|PRESET [--fidelity L] [--duration S] [--json] [--csv F] [--plot F] [--via-fmu [FMU]]
    chainmodel kinematics (--preset NAME | --driver-teeth N --driven-teeth N --span-pitches N --pitch-fraction F) [--json]
    chainmodel wrap (--preset NAME | ... --links M) [--json]
    chainmodel presets [--json]
    chainmodel cache [--info | --clear] [--json]
    chainmodel fmu-test FMU [--references DIR] [--host fmpy|libcosim] [--record DIR] [--plot F] [--scene TOML]

Conventions: SI units everywhere except the flags that say otherwise (``--speed-rpm``);
``--json`` prints exactly one JSON object on stdout (snake_case keys, SI units, ``null`` for a
value that is not defined, e.g. a tooth ratio over less than one tooth period) and nothing
else. Exit status: 0 success, 2 a user mistake (bad flag, unknown preset or parameter, invalid
value, unreadable scene file, missing FMU or matplotlib: one line ``chainmodel: error: ...`` on
stderr, no traceback), 3 the simulation diverged, 130 interrupted. Anything else is a bug and
shows its traceback.

Adding a subcommand
-------------------
The parser is built from :data:`SUBCOMMANDS`, a list of ``(module, function)`` pairs. Each
function is called as ``function(subparsers)`` with the object ``add_subparsers`` returned and
adds one or more subcommands. To add one, write in your module (say the package
``chainmodel.analysis.perturbation``)::

    def register(subparsers):
        p = subparsers.add_parser("frequency-response", help="one line for `chainmodel --help`",
                                  description="what it computes, with the paper and equation")
        from chainmodel.cli_support import add_drive_arguments, add_output_arguments
        add_drive_arguments(p)          # --preset / explicit drive, as kinematics and wrap take
        add_output_arguments(p)         # --json / --csv / --plot
        p.set_defaults(handler=_run_frequency_response)

    def _run_frequency_response(args) -> int:
        from chainmodel.cli_support import drive_from_args, print_json
        drive = drive_from_args(args)   # ValueError -> one-line error, exit 2
        ...
        if args.json:
            print_json(result_dict)     # one object, numpy and nan handled
        return 0

and append ``("chainmodel.analysis.perturbation", "register")`` to :data:`SUBCOMMANDS`.
Rules: ``register`` must be cheap (it runs on every ``chainmodel`` call: import heavy
dependencies such as Dask inside the handler); the handler returns an exit status (``None``
means 0); raise ``ValueError`` (or :class:`CLIError`) with a sentence a user can act on for
their mistakes and let :class:`~chainmodel.models.SimulationDiverged` propagate — :func:`main`
turns them into one line and exit status 2 or 3. Only the CLI imports these registration
hooks, so the physics keeps not depending on the CLI. A listed module that does not exist is
skipped (so an entry can land before its module).
"""

from __future__ import annotations

import argparse
import importlib
import inspect
import math
import sys
from pathlib import Path
from typing import Any, Callable, Mapping, Sequence

import numpy as np

__all__ = ["main", "build_parser", "SUBCOMMANDS", "CLIError", "add_drive_arguments",
           "add_output_arguments", "drive_from_args", "drive_dict", "print_json", "jsonable",
           "write_csv_columns", "RPM"]

from .cli_support import (DEFAULT_PITCH, FMU_NAME, CLIError, add_drive_arguments,  # noqa: F401
                          add_output_arguments, drive_dict, drive_from_args, fmu_path,
                          jsonable, parse_settings, print_json, write_csv_columns)
from .units import RPM  # noqa: F401  (re-exported)

# the names analysis modules used before cli_support existed
_parse_settings = parse_settings
_fmu_path = fmu_path

#: (module, function) pairs that add subcommands, in the order ``--help`` lists them.
SUBCOMMANDS: list[tuple[str, str]] = [
    ("chainmodel.cli", "register_run"),
    ("chainmodel.cli", "register_kinematics"),
    ("chainmodel.cli", "register_wrap"),
    ("chainmodel.cli", "register_presets"),
    ("chainmodel.analysis.perturbation.cli", "register"),
    ("chainmodel.analysis.tradeoff", "register"),
    ("chainmodel.analysis.sweep.cli", "register"),
    ("chainmodel.cache", "register"),
    ("chainmodel.new_scene", "register"),
    ("chainmodel.analysis.fmu_test", "register"),
]


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors (``chainmodel: error: ...``, exit status 2)."""

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"chainmodel: error: {message} (see '{self.prog} --help')\n")


# --- shared helpers: chainmodel.cli_support (re-exported here) ----------------------------


def _describe_drive(drive) -> str:
    links = f", {drive.links} links" if drive.links is not None else ""
    return (f"{drive.name + ': ' if drive.name else ''}{drive.n_driver}/{drive.n_driven} teeth, "
            f"p = {drive.pitch * 1e3:.5g} mm, N = {drive.span_pitches}, "
            f"f = {drive.pitch_fraction:.5g}{links}, centre distance "
            f"{drive.centre_distance * 1e3:.5g} mm")


def _check_outputs(args) -> None:
    """Fail before any work if --plot is asked for without matplotlib or with an extension
    other than .png, .pdf and .svg, or if an output file's directory does not exist."""
    if getattr(args, "plot", None):
        from .plots import check_plot_path
        check_plot_path(args.plot)
    for flag in ("csv", "plot"):
        path = getattr(args, flag, None)
        if path and not Path(path).resolve().parent.is_dir():
            raise CLIError(f"--{flag} {path}: directory {Path(path).parent} does not exist")
    if getattr(args, "plot", None):
        from .plots import require_matplotlib
        require_matplotlib()


def _table(rows: Sequence[tuple[str, str]]) -> str:
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def _g(x: float, digits: int = 5) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


# --- run --------------------------------------------------------------------------------------

def register_run(subparsers) -> None:
    p = subparsers.add_parser(
        "run", help="simulate a scene (library, or the built FMU with --via-fmu)",
        description="Simulate a scene (a preset name or a scene .toml file) and print a summary "
                    "table; --json prints the summary as one JSON object instead.")
    p.add_argument("scene", nargs="?", metavar="SCENE|PRESET",
                   help="preset name (chainmodel presets) or a scene .toml file")
    p.add_argument("--fidelity", metavar="LEVEL",
                   help="0-3 or kinematic, torsional, modal, multibody (default: the scene's); "
                        "'auto': the cheapest level meeting --accuracy on --outputs by the "
                        "measured trade table (docs/tradeoff.md)")
    p.add_argument("--outputs", metavar="NAMES", default=None,
                   help="with --fidelity auto: comma-separated outputs the choice must get "
                        "right (e.g. driven.speed,tight_span.tension; default: all measured)")
    p.add_argument("--accuracy", type=float, metavar="REL", default=None,
                   help="with --fidelity auto: relative error target (default 0.05)")
    p.add_argument("--duration", type=float, metavar="S", help="simulated time [s]")
    p.add_argument("--output-interval", type=float, metavar="S",
                   help="communication step / sampling interval [s]")
    p.add_argument("--speed-rpm", type=float, metavar="R", help="steady input-shaft speed [rpm]")
    p.add_argument("--load-torque", type=float, metavar="T", help="load torque on the driven shaft [N.m]")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", dest="settings",
                   help="set a parameter (chainmodel.parameters names, dotted or underscored: "
                        "chain.link_damping=50 or chain_link_damping=50) or a scene setting "
                        "(input_speed_rpm, ramp_time, load_torque, static_tension, ...), as the "
                        "Python API takes them; repeatable")
    p.add_argument("--solver", metavar="METHOD",
                   help="time stepper: auto, rk4, verlet, rk45, dop853, radau, bdf, lsoda")
    p.add_argument("--via-fmu", nargs="?", const="", default=None, metavar="FMU_PATH",
                   help=f"run the built FMU through fmpy (default dist/{FMU_NAME}; build it with "
                        "python build_fmu.py)")
    p.add_argument("--quiet", action="store_true",
                   help="no progress line and no summary table (files are still written)")
    add_output_arguments(p, csv_help="write every output's time series as CSV",
                         plot_help="write a figure: tensions, transmission error, torsional "
                                   "vibration and spectra (+ midspan deflection at levels 2-3, "
                                   "chain snapshots at the multibody level)")
    p.set_defaults(handler=cmd_run)


def cmd_run(args) -> int:
    from .models import SimulationDiverged
    from .scene import load_scene
    from .simulation import simulate
    scene_arg, fmu_arg = args.scene, args.via_fmu
    if scene_arg is None:
        # `run --via-fmu xu2010`: argparse gave the scene to --via-fmu
        if fmu_arg and not fmu_arg.lower().endswith(".fmu"):
            scene_arg, fmu_arg = fmu_arg, ""
        else:
            raise CLIError("give a scene: a preset name (chainmodel presets) or a .toml file")
    _check_outputs(args)
    kw = _parse_settings(args.settings)
    if args.solver is not None:
        kw["solver.method"] = args.solver
    for key, value in (("fidelity", args.fidelity), ("duration", args.duration),
                       ("output_interval", args.output_interval),
                       ("input_speed_rpm", args.speed_rpm), ("load_torque", args.load_torque)):
        if value is not None:
            kw[key] = value
    auto = isinstance(kw.get("fidelity"), str) and kw["fidelity"].strip().lower() == "auto"
    if auto:
        kw.pop("fidelity")
    elif args.outputs is not None or args.accuracy is not None:
        raise CLIError("--outputs and --accuracy are only used with --fidelity auto")
    scene = load_scene(scene_arg)
    if kw:
        scene = scene.with_overrides(**kw)
    choice = None
    if auto:
        from .fidelity_auto import choose
        choice = choose(scene, args.outputs, args.accuracy)
        scene = scene.with_overrides(**choice.overrides)
        sys.stderr.write(f"chainmodel: {choice.message}\n")
    # before anything is allocated (scene.times() alone is 8 bytes a sample), FMU runs too
    from .run_memory import check_run_memory
    check_run_memory(scene.duration, scene.output_interval, scene.fidelity)
    progress = not (args.quiet or args.json)
    if fmu_arg is not None:
        path = _fmu_path(fmu_arg)
        try:
            from . import fmu
        except ImportError as exc:
            raise CLIError(f"--via-fmu is not available: {exc}") from None
        kw_fmu = ({"progress": progress}
                  if "progress" in inspect.signature(fmu.simulate_fmu).parameters else {})
        fmu_error = getattr(fmu, "FMUError", None)
        try:
            result = fmu.simulate_fmu(path, scene, **kw_fmu)
        except Exception as exc:
            if fmu_error is not None and isinstance(exc, fmu_error):
                raise CLIError(f"the FMU {path} failed: {exc} (rebuild it with "
                               "`python build_fmu.py`)") from None
            raise
    else:
        n = len(scene.times())
        snapshot_every = max(1, math.ceil(n / 2000)) if args.plot and scene.fidelity >= 1 else 0
        try:
            result = simulate(scene, progress=progress, snapshot_every=snapshot_every)
        except SimulationDiverged:
            if progress:
                sys.stderr.write("\n")     # end the progress line the run left open
            raise
    summary = result.summary()
    out = dict(summary)
    out.update({"input_speed_rad_s": scene.operating.speed,
                "fidelity_level": int(result.fidelity), "via_fmu": fmu_arg is not None,
                "samples": len(result.time), "output_interval_s": scene.output_interval,
                "drive": drive_dict(scene.drive), "notes": list(scene.notes)})
    out["assumed"] = scene.assumed_lines()    # values not given, with their sources
    if choice is not None:
        out["fidelity_auto"] = {"config": choice.config, "expected_error": choice.expected_error,
                                "figures": list(choice.figures), "met": choice.met,
                                "source_scene": choice.source_scene,
                                "extrapolated": choice.extrapolated, "message": choice.message,
                                "promised": choice.promised, "why_not": choice.why_not}
    written = []
    if args.csv:
        written.append(("time series", result.to_csv(args.csv)))
    if args.plot:
        from .plots import plot_run
        written.append(("figure", plot_run(result, args.plot, summary)))
    out["files"] = [str(path) for _, path in written]
    if args.json:
        print_json(out)
    elif not args.quiet:
        print(_run_table(out, scene))
    if args.quiet or args.json:   # the table shows them; otherwise they go to stderr
        for text in out.get("warnings", ()):
            sys.stderr.write(f"chainmodel: warning: {text}\n")
    if not args.json and not args.quiet:
        for what, path in written:
            print(f"wrote {what} to {path}")
    if not out.get("valid", True):
        # the figures are printed (and written) for inspection, but they are not a drive's
        why = ", ".join(p.cause for p in result.problems if p.invalid)
        sys.stderr.write(f"chainmodel: error: the result is not valid ({why}); the warnings "
                         "say why and what to change\n")
        return 3
    return 0


def _run_table(s: Mapping[str, Any], scene) -> str:
    drive = scene.drive
    ratio, exact = s["tooth_ratio"], s["exact_tooth_ratio"]
    err = f", error {abs(ratio - exact):.2g}" if math.isfinite(ratio) else ""
    rtf = s["real_time_factor"]
    rows = [
        ("scene", f"{s['scene']}  (fidelity {s['fidelity_level']}, {s['fidelity']}; "
                  f"{'FMU via fmpy' if s['via_fmu'] else 'library'})"),
        ("drive", _describe_drive(drive)),
        ("run", f"{s['duration_s']:g} s in {s['samples']} samples, steady state from "
                f"{s['steady_from_s']:g} s"),
        ("operating point", f"{s['input_speed_rpm']:.5g} rpm input, load {s['load_torque_nm']:.5g} N.m"),
        ("static tension", f"{_g(s['static_span_tension_n'])} N"),
        ("tight span", f"mean {_g(s['mean_tight_tension_n'])} N, peak {_g(s['peak_tight_tension_n'])} N, "
                       f"min {_g(s['min_tight_tension_n'])} N"),
        ("slack span", f"mean {_g(s['mean_slack_tension_n'])} N, peak {_g(s['peak_slack_tension_n'])} N, "
                       f"min {_g(s['min_slack_tension_n'])} N"),
        ("weakest link", f"min {_g(s['min_link_tension_n'])} N; a link slack "
                         f"{100 * s['slack_link_time_fraction']:.3g} % of the time"),
        ("input torque", f"mean {_g(s['mean_input_torque_nm'])} N.m"),
        ("tooth ratio", f"{_g(ratio, 10)}  (exact {drive.n_driver}/{drive.n_driven} = "
                        f"{exact:.10g}{err})"),
        ("dominant freq.", f"{_g(s['dominant_frequency_hz'])} Hz of the driven speed  (meshing "
                           f"{_g(s['meshing_frequency_hz'])} Hz, resolution "
                           f"{_g(s['frequency_resolution_hz'], 3)} Hz)"),
        ("wall time", f"{s['wall_time_s']:.3g} s  (real-time factor {_g(rtf, 3)}"
                      + (f"; {s['startup_time_s']:.2g} s of it instantiating and initializing "
                         "the FMU)" if s.get("startup_time_s") is not None else ")")),
    ]
    for k, note in enumerate(s["notes"]):
        rows.append(("notes" if k == 0 else "", note))
    for k, text in enumerate(_assumed_rows(s.get("assumed", ()))):
        rows.append(("assumed" if k == 0 else "", text))
    for k, text in enumerate(s.get("warnings", ())):
        rows.append(("WARNING" if k == 0 else "", text))
    return _table(rows)


def _assumed_rows(lines: Sequence[str]) -> list[str]:
    """The table's ``assumed`` block: a preset's cited values counted on one line per source
    (the user chose them by naming the preset; ``--json`` lists each), every other assumed
    value (a chain's law, a schema default) on a line of its own."""
    rows, by_preset = [], {}
    for text in lines:
        source = text[text.index("  (") + 3:-1] if "  (" in text else ""
        if source.startswith("preset "):
            by_preset.setdefault(source, []).append(text.split(" = ")[0])
        else:
            rows.append(text)
    head = [f"{len(names)} values from {source}: {', '.join(names)}"
            for source, names in by_preset.items()]
    return head + rows


# --- kinematics -------------------------------------------------------------------------------

def register_kinematics(subparsers) -> None:
    p = subparsers.add_parser(
        "kinematics", help="exact (and approximate) kinematics over one tooth period",
        description="Seating and release configurations and the driven sprocket's position, "
                    "velocity ratio and acceleration over one driver tooth period, starting when "
                    "a roller seats on the driver, for a driver at constant speed (seed 000).")
    add_drive_arguments(p)
    p.add_argument("--samples", type=int, default=400, metavar="K",
                   help="driver angles over the tooth period (default 400)")
    p.add_argument("--speed-rpm", type=float, default=100.0, metavar="R",
                   help="constant driver speed [rpm] (default 100, as seed 000)")
    add_output_arguments(p, plot_help="write a figure like seed 000 Fig. 4")
    p.set_defaults(handler=cmd_kinematics)


def _tooth_period(drive, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(fraction in [0, 1), driver rotation from seating [rad]) at ``samples`` points."""
    from .geometry import check_whole
    samples = check_whole("--samples", samples, 2)
    frac = np.arange(samples) / samples
    return frac, frac * (2 * math.pi / drive.n_driver)


def _config(c) -> dict[str, float]:
    return {"theta2": c.theta2, "theta3": c.theta3, "theta4": c.theta4}


def _approximate(drive, theta4, omega4) -> tuple[dict[str, np.ndarray] | None, str]:
    """Closed-form curves (seed 000 eqs 50, 51, 53) if this version has
    ``chainmodel.kinematics.approximate``, and a note saying why not otherwise."""
    from . import kinematics
    approx = getattr(kinematics, "approximate", None)
    if approx is None:
        try:
            from .kinematics.approx import approximate as approx
        except ImportError:
            return None, "closed-form approximations not available in this version"
    try:
        a = approx(drive, theta4, omega4=omega4, alpha4=0.0)
    except ValueError as exc:
        return None, f"closed-form approximations not available for this drive: {exc}"
    out = {}
    if getattr(a, "theta2", None) is not None:
        out["theta2"] = np.asarray(a.theta2, float)
    if getattr(a, "velocity_ratio", None) is not None:
        out["velocity_ratio"] = np.asarray(a.velocity_ratio, float)
    if getattr(a, "alpha2", None) is not None:
        out["driven_acceleration"] = -np.asarray(a.alpha2, float)   # forward positive
    return (out, "") if out else (None, "closed-form approximations gave no curves")


def kinematics_data(drive, samples: int = 400, speed_rpm: float = 100.0) -> dict[str, Any]:
    """What ``chainmodel kinematics --json`` prints (see docs/cli.md)."""
    from .kinematics import driven_rotation, release, seating
    if not (isinstance(speed_rpm, (int, float)) and math.isfinite(speed_rpm) and speed_rpm > 0):
        raise CLIError(f"--speed-rpm must be a positive number, got {speed_rpm!r}")
    frac, phi1 = _tooth_period(drive, samples)
    w = speed_rpm * RPM
    s, r = seating(drive), release(drive)
    rot = driven_rotation(drive, phi1, w, 0.0)
    two_alpha_c = 2 * math.pi / drive.n_driver
    out: dict[str, Any] = {
        "drive": drive_dict(drive),
        "driver_speed_rpm": float(speed_rpm),
        "driver_speed_rad_s": w,
        "tooth_period_s": two_alpha_c / w,
        "samples": len(frac),
        "seating": _config(s),
        "release": _config(r),
        "release_fraction": (s.theta4 - r.theta4) / two_alpha_c,
        "velocity_ratio_min": float(np.min(rot.velocity_ratio)),
        "velocity_ratio_max": float(np.max(rot.velocity_ratio)),
        "velocity_ratio_mean": float(np.mean(rot.velocity_ratio)),
        "driven_acceleration_min": float(np.min(rot.driven_acceleration)),
        "driven_acceleration_max": float(np.max(rot.driven_acceleration)),
        "driven_acceleration_mean": float(np.mean(rot.driven_acceleration)),
        "tooth_period_fraction": frac,
        "driver_angle": phi1,
        "theta4": rot.theta4,
        "theta2": rot.theta2,
        "theta3": rot.theta3,
        "span_length": rot.span_length,
        "velocity_ratio": rot.velocity_ratio,
        "driven_angle": rot.driven_angle,
        "driven_speed": rot.driven_speed,
        "driven_acceleration": rot.driven_acceleration,
    }
    approx, note = _approximate(drive, rot.theta4, -w)
    if approx:
        out["approximate"] = approx
    else:
        out["approximate_note"] = note
    return out


_KIN_UNITS = {"tooth_period_fraction": "", "driver_angle": "rad", "theta4": "rad", "theta2": "rad",
              "theta3": "rad", "span_length": "m", "velocity_ratio": "", "driven_angle": "rad",
              "driven_speed": "rad/s", "driven_acceleration": "rad/s2"}


def cmd_kinematics(args) -> int:
    _check_outputs(args)
    drive = drive_from_args(args)
    data = kinematics_data(drive, args.samples, args.speed_rpm)
    written = []
    if args.csv:
        cols = {k: data[k] for k in _KIN_UNITS}
        units = dict(_KIN_UNITS)
        for k, v in (data.get("approximate") or {}).items():
            cols[f"approximate_{k}"] = v
            units[f"approximate_{k}"] = _KIN_UNITS[k]
        written.append(("curves", write_csv_columns(args.csv, cols, units)))
    if args.plot:
        from .plots import plot_kinematics
        written.append(("figure", plot_kinematics(data, args.plot)))
    if args.json:
        print_json({**data, "files": [str(path) for _, path in written]})
        return 0
    s, r = data["seating"], data["release"]
    deg = 180 / math.pi
    rows = [
        ("drive", _describe_drive(drive)),
        ("driver speed", f"{data['driver_speed_rpm']:g} rpm = {data['driver_speed_rad_s']:.5g} rad/s, "
                         f"tooth period {data['tooth_period_s'] * 1e3:.4g} ms, "
                         f"{data['samples']} samples from seating"),
        ("", f"{'theta2':>20} {'theta3':>20} {'theta4':>20}   [rad (deg)]"),
    ]
    for name, c in (("seating", s), ("release", r)):
        rows.append((name, " ".join(f"{c[k]:>10.6f} ({c[k] * deg:7.3f})" for k in
                                    ("theta2", "theta3", "theta4"))))
    rows.append(("release phase", f"{data['release_fraction']:.5f} of a tooth period after "
                                  f"seating (approximately 1 - f = {1 - drive.pitch_fraction:.5f}, seed 000 eq 47)"))
    rows.append(("", f"{'min':>14} {'max':>14} {'mean':>14}"))
    for label, key, unit in (("velocity ratio", "velocity_ratio", "-"),
                             ("driven accel.", "driven_acceleration", "rad/s^2")):
        rows.append((label, f"{data[key + '_min']:>14.7g} {data[key + '_max']:>14.7g} "
                            f"{data[key + '_mean']:>14.7g}   [{unit}]  exact"))
        approx = (data.get("approximate") or {}).get(key)
        if approx is not None:
            rows.append(("", f"{np.min(approx):>14.7g} {np.max(approx):>14.7g} "
                             f"{np.mean(approx):>14.7g}   [{unit}]  approximate"))
    sl = np.asarray(data["span_length"])
    rows.append(("span length", f"{np.min(sl):>14.7g} {np.max(sl):>14.7g} {np.mean(sl):>14.7g}   [m]"))
    if "approximate" not in data:
        rows.append(("note", data["approximate_note"]))
    print(_table(rows))
    for what, path in written:
        print(f"wrote {what} to {path}")
    return 0


# --- wrap -------------------------------------------------------------------------------------

def register_wrap(subparsers) -> None:
    p = subparsers.add_parser(
        "wrap", help="total wrapping length over one tooth period (seed 004)",
        description="The total chain wrapping length L (seed 004 eq 13, both spans straight) "
                    "over one driver tooth period from seating, and its min, mean and max "
                    "divided by the pitch (seed 004 Table 1).")
    add_drive_arguments(p)
    p.add_argument("--samples", type=int, default=200, metavar="K",
                   help="driver angles over the tooth period; the mean is over these "
                        "(default 200; min and max are refined beyond the samples)")
    add_output_arguments(p, plot_help="write a figure like seed 004 Fig. 2")
    p.set_defaults(handler=cmd_wrap)


def wrap_data(drive, samples: int = 200) -> dict[str, Any]:
    """What ``chainmodel wrap --json`` prints (see docs/cli.md)."""
    from .kinematics import seating, wrap_length, wrap_length_range
    frac, phi1 = _tooth_period(drive, samples)
    lmin, lmean, lmax = wrap_length_range(drive, samples=len(frac))
    p = drive.pitch
    return {
        "drive": drive_dict(drive),
        "samples": len(frac),
        "l_min_over_p": lmin / p,
        "l_mean_over_p": lmean / p,
        "l_max_over_p": lmax / p,
        "tooth_period_fraction": frac,
        "driver_angle": phi1,
        "theta4": seating(drive).theta4 - phi1,
        "wrap_length": wrap_length(drive, driver_angle=phi1),
    }


def cmd_wrap(args) -> int:
    _check_outputs(args)
    drive = drive_from_args(args)
    data = wrap_data(drive, args.samples)
    written = []
    if args.csv:
        cols = {k: data[k] for k in ("tooth_period_fraction", "driver_angle", "theta4", "wrap_length")}
        written.append(("curve", write_csv_columns(
            args.csv, cols, {"driver_angle": "rad", "theta4": "rad", "wrap_length": "m"})))
    if args.plot:
        from .plots import plot_wrap
        written.append(("figure", plot_wrap(data, args.plot)))
    if args.json:
        print_json({**data, "files": [str(path) for _, path in written]})
        return 0
    rows = [("drive", _describe_drive(drive)),
            ("L_min / p", f"{data['l_min_over_p']:.6f}"),
            ("L_mean / p", f"{data['l_mean_over_p']:.6f}  (mean of {data['samples']} samples)"),
            ("L_max / p", f"{data['l_max_over_p']:.6f}"),
            ("variation", f"{data['l_max_over_p'] - data['l_min_over_p']:.6f} pitches")]
    if drive.links is not None:
        rows.append(("chain", f"{drive.links} links: L_max / p - M = "
                              f"{data['l_max_over_p'] - drive.links:+.6f} (positive: the rigid "
                              "model must stretch the chain)"))
    print(_table(rows))
    for what, path in written:
        print(f"wrote {what} to {path}")
    return 0


# --- presets ----------------------------------------------------------------------------------

def register_presets(subparsers) -> None:
    p = subparsers.add_parser("presets", help="list the named drives",
                              description="The named drives: seed 000 Table 1 (coarse, medium, "
                                          "fine), seed 004 Table 1 (A1-D3), seed 003 (xu2010).")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    p.set_defaults(handler=cmd_presets)


def cmd_presets(args) -> int:
    from .presets import preset, preset_names
    drives = [preset(name) for name in preset_names()]
    if args.json:
        print_json({"presets": [drive_dict(d) for d in drives]})
        return 0
    print(f"{'name':<8} {'n_c':>4} {'n_o':>4} {'N':>4} {'f':>8} {'M':>5} {'p [mm]':>8} "
          f"{'centre distance [mm]':>21}")
    for d in drives:
        print(f"{d.name:<8} {d.n_driver:>4} {d.n_driven:>4} {d.span_pitches:>4} "
              f"{d.pitch_fraction:>8.4f} {d.links if d.links is not None else '-':>5} "
              f"{d.pitch * 1e3:>8.3f} {d.centre_distance * 1e3:>21.3f}")
    return 0


# --- entry point ------------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    from . import __version__
    parser = _Parser(prog="chainmodel",
                     description="ChainDrive: roller chain drive kinematics and simulation.",
                     epilog="JSON keys, units and exit codes: docs/cli.md")
    parser.add_argument("--version", action="version", version=f"chainmodel {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    for module_name, function_name in SUBCOMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ModuleNotFoundError as exc:
            if exc.name == module_name:
                continue            # listed before its module landed
            raise
        register: Callable = getattr(module, function_name)
        register(sub)
    return parser


def _one_line(exc: BaseException) -> str:
    if isinstance(exc, OSError) and exc.filename is not None and exc.strerror:
        return f"cannot use {exc.filename}: {exc.strerror}"
    return " ".join(str(exc).split()) or type(exc).__name__


def main(argv: Sequence[str] | None = None) -> int:
    """Run the CLI with ``argv`` (default ``sys.argv[1:]``); returns the exit status."""
    from .models import SimulationDiverged
    from .plots import PlottingUnavailable
    try:
        parser = build_parser()
        args = parser.parse_args(argv)
        status = args.handler(args)
        return 0 if status is None else int(status)
    except SystemExit as exc:          # argparse: --help, --version, usage errors
        code = exc.code
        return code if isinstance(code, int) else (0 if code is None else 2)
    except SimulationDiverged as exc:
        sys.stderr.write(f"chainmodel: error: {_one_line(exc)}\n")
        return 3
    except (CLIError, PlottingUnavailable, ValueError, OSError) as exc:
        sys.stderr.write(f"chainmodel: error: {_one_line(exc)}\n")
        return 2
    except KeyboardInterrupt:
        sys.stderr.write("chainmodel: interrupted\n")
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
