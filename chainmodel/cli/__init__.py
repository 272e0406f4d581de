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

Layout: this package holds the parser and :func:`main`; one module per own command
(:mod:`.run`, :mod:`.kinematics`, :mod:`.wrap`, :mod:`.presets`), their shared table and file
checks in :mod:`._shared`; ``cache`` and ``new-scene`` live in :mod:`chainmodel.cache` and
:mod:`chainmodel.new_scene`, the analysis commands in :mod:`chainmodel.analysis`. Every public
name the single-module CLI had is re-exported here.
"""

from __future__ import annotations

import argparse
import re
import importlib
import sys
from typing import Callable, Sequence

__all__ = ["main", "build_parser", "SUBCOMMANDS", "CLIError", "add_drive_arguments",
           "add_output_arguments", "drive_from_args", "drive_dict", "print_json", "jsonable",
           "write_csv_columns", "RPM", "register_run", "cmd_run", "register_kinematics",
           "cmd_kinematics", "kinematics_data", "register_wrap", "cmd_wrap", "wrap_data",
           "register_presets", "cmd_presets"]

from ..cli_support import (DEFAULT_PITCH, FMU_NAME, CLIError, add_drive_arguments,  # noqa: F401
                           add_output_arguments, drive_dict, drive_from_args, fmu_path,
                           jsonable, parse_settings, print_json, write_csv_columns)
from ..units import RPM  # noqa: F401  (re-exported)
from .kinematics import cmd_kinematics, kinematics_data, register_kinematics  # noqa: F401
from .presets import cmd_presets, register_presets  # noqa: F401
from .run import cmd_run, register_run  # noqa: F401
from .wrap import cmd_wrap, register_wrap, wrap_data  # noqa: F401

# the names analysis modules used before cli_support existed
_parse_settings = parse_settings
_fmu_path = fmu_path

#: (module, function) pairs that add subcommands, in the order ``--help`` lists them.
SUBCOMMANDS: list[tuple[str, str]] = [
    ("chainmodel.cli.run", "register_run"),
    ("chainmodel.cli.kinematics", "register_kinematics"),
    ("chainmodel.cli.wrap", "register_wrap"),
    ("chainmodel.cli.presets", "register_presets"),
    ("chainmodel.analysis.perturbation.cli", "register"),
    ("chainmodel.analysis.tradeoff", "register"),
    ("chainmodel.analysis.sweep.cli", "register"),
    ("chainmodel.cache", "register"),
    ("chainmodel.new_scene", "register"),
    ("chainmodel.analysis.fmu_test", "register"),
]


class _Parser(argparse.ArgumentParser):
    """argparse with one-line usage errors (``chainmodel: error: ...``, exit status 2), and
    negative numbers in exponent form (``--load-torque -1e6``) read as values, not options
    (argparse before Python 3.13 knows only ``-1`` and ``-1.5``)."""

    def __init__(self, *args, **kw):
        super().__init__(*args, **kw)
        self._negative_number_matcher = re.compile(r"^-(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?$")

    def error(self, message: str):  # noqa: D401 - argparse API
        self.exit(2, f"chainmodel: error: {message} (see '{self.prog} --help')\n")


# --- entry point ------------------------------------------------------------------------------

def build_parser() -> argparse.ArgumentParser:
    from .. import __version__
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
    from ..models import SimulationDiverged
    from ..plots import PlottingUnavailable
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

