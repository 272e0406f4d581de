"""``chainmodel kinematics``: the exact (and closed-form approximate) kinematics over one driver
tooth period from seating, for a driver at constant speed (seed 000)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ..cli_support import (CLIError, add_drive_arguments, add_output_arguments, drive_dict,
                           drive_from_args, print_json, write_csv_columns)
from ..units import RPM
from ._shared import check_outputs, describe_drive, table, tooth_period

__all__ = ["register_kinematics", "cmd_kinematics", "kinematics_data"]


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


def _config(c) -> dict[str, float]:
    return {"theta2": c.theta2, "theta3": c.theta3, "theta4": c.theta4}


def _approximate(drive, theta4, omega4) -> tuple[dict[str, np.ndarray] | None, str]:
    """Closed-form curves (seed 000 eqs 50, 51, 53) if this version has
    ``chainmodel.kinematics.approximate``, and a note saying why not otherwise."""
    from .. import kinematics
    approx = getattr(kinematics, "approximate", None)
    if approx is None:
        try:
            from ..kinematics.approx import approximate as approx
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
    from ..kinematics import driven_rotation, release, seating
    if not (isinstance(speed_rpm, (int, float)) and math.isfinite(speed_rpm) and speed_rpm > 0):
        raise CLIError(f"--speed-rpm must be a positive number, got {speed_rpm!r}")
    frac, phi1 = tooth_period(drive, samples)
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
    check_outputs(args)
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
        from ..plots import plot_kinematics
        written.append(("figure", plot_kinematics(data, args.plot)))
    if args.json:
        print_json({**data, "files": [str(path) for _, path in written]})
        return 0
    s, r = data["seating"], data["release"]
    deg = 180 / math.pi
    rows = [
        ("drive", describe_drive(drive)),
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
    print(table(rows))
    for what, path in written:
        print(f"wrote {what} to {path}")
    return 0
