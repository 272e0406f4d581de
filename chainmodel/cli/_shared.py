"""Formatting and checks shared by the CLI's own commands (run, kinematics, wrap, presets).

Helpers other packages use (argument groups, JSON/CSV, --set, the FMU's path, CLIError) are public
in :mod:`chainmodel.cli_support`; these are the commands' table and file checks."""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from ..cli_support import CLIError


def describe_drive(drive) -> str:
    links = f", {drive.links} links" if drive.links is not None else ""
    return (f"{drive.name + ': ' if drive.name else ''}{drive.n_driver}/{drive.n_driven} teeth, "
            f"p = {drive.pitch * 1e3:.5g} mm, N = {drive.span_pitches}, "
            f"f = {drive.pitch_fraction:.5g}{links}, centre distance "
            f"{drive.centre_distance * 1e3:.5g} mm")


def check_outputs(args) -> None:
    """Fail before any work if --plot is asked for without matplotlib or with an extension
    other than .png, .pdf and .svg, or if an output file's directory does not exist."""
    if getattr(args, "plot", None):
        from ..plots import check_plot_path
        check_plot_path(args.plot)
    for flag in ("csv", "plot"):
        path = getattr(args, flag, None)
        if path and not Path(path).resolve().parent.is_dir():
            raise CLIError(f"--{flag} {path}: directory {Path(path).parent} does not exist")
    if getattr(args, "plot", None):
        from ..plots import require_matplotlib
        require_matplotlib()


def table(rows: Sequence[tuple[str, str]]) -> str:
    width = max(len(k) for k, _ in rows)
    return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def g(x: float, digits: int = 5) -> str:
    return "n/a" if x is None or not math.isfinite(x) else f"{x:.{digits}g}"


def tooth_period(drive, samples: int) -> tuple[np.ndarray, np.ndarray]:
    """(fraction in [0, 1), driver rotation from seating [rad]) at ``samples`` points."""
    from ..geometry import check_whole
    samples = check_whole("--samples", samples, 2)
    frac = np.arange(samples) / samples
    return frac, frac * (2 * math.pi / drive.n_driver)
