"""``chainmodel wrap``: the total chain wrapping length over one tooth period (seed 004 eq 13,
Table 1)."""

from __future__ import annotations

from typing import Any

from ..cli_support import (add_drive_arguments, add_output_arguments, drive_dict, drive_from_args,
                           print_json, write_csv_columns)
from ._shared import check_outputs, describe_drive, table, tooth_period

__all__ = ["register_wrap", "cmd_wrap", "wrap_data"]


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
    from ..kinematics import seating, wrap_length, wrap_length_range
    frac, phi1 = tooth_period(drive, samples)
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
    check_outputs(args)
    drive = drive_from_args(args)
    data = wrap_data(drive, args.samples)
    written = []
    if args.csv:
        cols = {k: data[k] for k in ("tooth_period_fraction", "driver_angle", "theta4", "wrap_length")}
        written.append(("curve", write_csv_columns(
            args.csv, cols, {"driver_angle": "rad", "theta4": "rad", "wrap_length": "m"})))
    if args.plot:
        from ..plots import plot_wrap
        written.append(("figure", plot_wrap(data, args.plot)))
    if args.json:
        print_json({**data, "files": [str(path) for _, path in written]})
        return 0
    rows = [("drive", describe_drive(drive)),
            ("L_min / p", f"{data['l_min_over_p']:.6f}"),
            ("L_mean / p", f"{data['l_mean_over_p']:.6f}  (mean of {data['samples']} samples)"),
            ("L_max / p", f"{data['l_max_over_p']:.6f}"),
            ("variation", f"{data['l_max_over_p'] - data['l_min_over_p']:.6f} pitches")]
    if drive.links is not None:
        rows.append(("chain", f"{drive.links} links: L_max / p - M = "
                              f"{data['l_max_over_p'] - drive.links:+.6f} (positive: the rigid "
                              "model must stretch the chain)"))
    print(table(rows))
    for what, path in written:
        print(f"wrote {what} to {path}")
    return 0
