"""``chainmodel run``: simulate a scene (a preset or a scene file) through the library, or the
built FMU with ``--via-fmu``, and print a summary table or one JSON object (docs/cli.md)."""

from __future__ import annotations

import inspect
import math
import sys
from typing import Any, Mapping, Sequence

from ..cli_support import (FMU_NAME, CLIError, add_output_arguments, drive_dict, fmu_path,
                           parse_settings, print_json)
from ._shared import check_outputs, describe_drive, g, table

__all__ = ["register_run", "cmd_run"]


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
    from ..models import SimulationDiverged
    from ..scene import load_scene
    from ..simulation import resolve, simulate
    scene_arg, fmu_arg = args.scene, args.via_fmu
    if scene_arg is None:
        # `run --via-fmu xu2010`: argparse gave the scene to --via-fmu
        if fmu_arg and not fmu_arg.lower().endswith(".fmu"):
            scene_arg, fmu_arg = fmu_arg, ""
        else:
            raise CLIError("give a scene: a preset name (chainmodel presets) or a .toml file")
    check_outputs(args)
    kw = parse_settings(args.settings)
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
        # the chosen scene and its model, built once by the choice and run as they are
        scene, choice = resolve(scene, outputs=args.outputs, accuracy=args.accuracy,
                                fidelity="auto")
        sys.stderr.write(f"chainmodel: {choice.message}\n")
    # before anything is allocated (scene.times() alone is 8 bytes a sample), FMU runs too
    from ..run_memory import check_run_memory
    check_run_memory(scene.duration, scene.output_interval, scene.fidelity)
    progress = not (args.quiet or args.json)
    if fmu_arg is not None:
        path = fmu_path(fmu_arg)
        try:
            from .. import fmu
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
        stale = fmu.differing_files(path)
    else:
        n = len(scene.times())
        snapshot_every = max(1, math.ceil(n / 2000)) if args.plot and scene.fidelity >= 1 else 0
        try:
            result = simulate(scene, progress=progress, snapshot_every=snapshot_every,
                              choice=choice)
        except SimulationDiverged:
            if progress:
                sys.stderr.write("\n")     # end the progress line the run left open
            raise
    summary = result.summary()
    out = dict(summary)
    if fmu_arg is not None and stale:
        out["warnings"] = list(out.get("warnings", ())) + [
            f"the FMU {path} was not built from this chainmodel: {len(stale)} of its package "
            f"files differ ({', '.join(stale[:3])}{', ...' if len(stale) > 3 else ''}), so its "
            "results are another version's; rebuild it with `python build_fmu.py`"]
    out.update({"input_speed_rad_s": scene.operating.speed,
                "fidelity_level": int(result.fidelity), "via_fmu": fmu_arg is not None,
                "samples": len(result.time), "output_interval_s": scene.output_interval,
                "drive": drive_dict(scene.drive), "notes": list(scene.notes)})
    out["assumed"] = scene.assumed_lines()    # values not given, with their sources
    if choice is not None:
        out["fidelity_auto"] = {"config": choice.config, "expected_error": choice.expected_error,
                                "nominal_error": choice.nominal_error,
                                "figures": list(choice.figures), "met": choice.met,
                                "source_scene": choice.source_scene,
                                "extrapolated": choice.extrapolated, "message": choice.message,
                                "promised": choice.promised, "why_not": choice.why_not}
    written = []
    if args.csv:
        written.append(("time series", result.to_csv(args.csv)))
    if args.plot:
        from ..plots import plot_run
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
        ("drive", describe_drive(drive)),
        ("run", f"{s['duration_s']:g} s in {s['samples']} samples, steady state from "
                f"{s['steady_from_s']:g} s"),
        ("operating point", f"{s['input_speed_rpm']:.5g} rpm input, load {s['load_torque_nm']:.5g} N.m"),
        ("static tension", f"{g(s['static_span_tension_n'])} N"),
        ("tight span", f"mean {g(s['mean_tight_tension_n'])} N, peak {g(s['peak_tight_tension_n'])} N, "
                       f"min {g(s['min_tight_tension_n'])} N"),
        ("slack span", f"mean {g(s['mean_slack_tension_n'])} N, peak {g(s['peak_slack_tension_n'])} N, "
                       f"min {g(s['min_slack_tension_n'])} N"),
        ("weakest link", f"min {g(s['min_link_tension_n'])} N; a link slack "
                         f"{100 * s['slack_link_time_fraction']:.3g} % of the time"),
        ("input torque", f"mean {g(s['mean_input_torque_nm'])} N.m"
                         + ("; power flows back into the input shaft "
                            f"({g(-s['mean_input_power_w'])} W): an overrunning load drives "
                            "the chain" if s['mean_input_power_w'] < 0 else "")),
        ("tooth ratio", f"{g(ratio, 10)}  (exact {drive.n_driver}/{drive.n_driven} = "
                        f"{exact:.10g}{err})"),
        ("dominant freq.", f"{g(s['dominant_frequency_hz'])} Hz of the driven speed  (meshing "
                           f"{g(s['meshing_frequency_hz'])} Hz, resolution "
                           f"{g(s['frequency_resolution_hz'], 3)} Hz)"),
        ("span modes", f"tight {g(s['tight_span_mode_hz'])} Hz, slack "
                       f"{g(s['slack_span_mode_hz'])} Hz (first string modes at the mean "
                       f"tensions); nearest: {s['span_resonance']}"
                       + (f", {100 * s['span_resonance_detuning']:+.3g} %"
                          if math.isfinite(s['span_resonance_detuning']) else "")),
        ("wall time", f"{s['wall_time_s']:.3g} s  (real-time factor {g(rtf, 3)}"
                      + (f"; {s['startup_time_s']:.2g} s of it instantiating and initializing "
                         "the FMU)" if s.get("startup_time_s") is not None else ")")),
    ]
    for k, note in enumerate(s["notes"]):
        rows.append(("notes" if k == 0 else "", note))
    for k, text in enumerate(_assumed_rows(s.get("assumed", ()))):
        rows.append(("assumed" if k == 0 else "", text))
    for k, text in enumerate(s.get("warnings", ())):
        rows.append(("WARNING" if k == 0 else "", text))
    return table(rows)


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
