"""Regenerate the command-line examples of docs/cli.md and README.md from the real commands.

    python docs/scripts/cli_examples.py [--fmu PATH] [--check] [FILE ...]

An example is a fenced block between two markers::

    <!-- BEGIN CLI EXAMPLE -->            (or "BEGIN CLI EXAMPLE json", "... fmu", "... json fmu")
    ```
    $ chainmodel wrap --preset C1
    ...its output...
    ```
    <!-- END CLI EXAMPLE -->

Each ``$ chainmodel ...`` line is run (in this process, ``chainmodel.cli.main``, in an empty
temporary working directory, so relative output files land there) and the block is rewritten
as the command lines, each followed by what a user sees: stdout, and the ``chainmodel: error``
and ``chainmodel: warning`` lines of stderr (not the progress line, not the one-time compile
notice). ``json``: each command's JSON object is printed one top-level key a line. ``fmu``: the
working directory holds ``dist/ChainDrive.fmu`` (the FMU given with ``--fmu``, else one built
with ``python build_fmu.py`` into a temporary folder), as after the README's quick start.

``--check`` rewrites nothing and exits 1 if a block differs from its command's output beyond
what legitimately varies between runs (:func:`mask`); tests/test_cli_docs.py runs the same
check in the test suite.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import math
import os
import re
import shlex
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any, Callable

ROOT = Path(__file__).resolve().parents[2]
FILES = [ROOT / "docs" / "cli.md", ROOT / "README.md"]

BLOCK = re.compile(r"(<!-- BEGIN CLI EXAMPLE(?P<options>[^>]*?)-->\n```[^\n]*\n)(?P<body>.*?)"
                   r"(```\n<!-- END CLI EXAMPLE -->)", re.S)

#: JSON keys whose values differ from run to run (timings)
VARYING_KEYS = ("wall_time_s", "real_time_factor", "startup_time_s")
#: table rows whose text differs from run to run (the wall-time row: times, real-time factor)
VARYING_ROWS = ("wall time",)
#: relative tolerance on a JSON number: its last digits depend on the CPU and on the BLAS
#: kernels the set-up's linear algebra runs on (xu2010's 0.2 s JSON on an AMD EPYC: bit for bit
#: the Intel machine's with OpenBLAS's own kernel choice, 6.2e-9 apart in min_slack_tension_n
#: with OPENBLAS_CORETYPE=Haswell set); a change to a command's output moves them far more
JSON_REL = 1e-6
#: a tooth ratio's error at round-off level (below 1e-9): its digits depend on the CPU's
#: floating-point path (e.g. "error 3.4e-13"), not on the model
ROUND_OFF = re.compile(r"error \d(?:\.\d+)?e-(?:1\d|[2-9]\d)\b")


def blocks(text: str) -> list[dict[str, Any]]:
    """The examples of a document: options, commands and the body as written."""
    out = []
    for m in BLOCK.finditer(text):
        commands = [line[2:] for line in m["body"].splitlines() if line.startswith("$ ")]
        out.append({"options": set(m["options"].split()), "commands": commands,
                    "body": m["body"], "span": m.span("body")})
    return out


def format_json(obj: dict) -> str:
    """One top-level key a line (nested values compact), valid JSON as a whole."""
    items = [f"{json.dumps(k)}: {json.dumps(v)}" for k, v in obj.items()]
    return "{" + ",\n ".join(items) + "}"


def run_command(command: str, workdir: Path, as_json: bool = False) -> str:
    """What a user sees for ``command`` (a ``chainmodel ...`` line) run in ``workdir``."""
    from chainmodel import cli
    argv = shlex.split(command)
    if not argv or argv[0] != "chainmodel":
        raise ValueError(f"an example must run chainmodel, got {command!r}")
    out, err = io.StringIO(), io.StringIO()
    here = os.getcwd()
    os.chdir(workdir)
    try:
        with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
            cli.main(argv[1:])
    finally:
        os.chdir(here)
    text = out.getvalue()
    if as_json and text.strip():
        text = format_json(json.loads(text)) + "\n"
    shown = [line + "\n" for line in err.getvalue().replace("\r", "\n").splitlines()
             if line.startswith(("chainmodel: error", "chainmodel: warning"))]
    return text + "".join(shown)


def render_block(block: dict[str, Any], fmu: Callable[[], Path] | None) -> str:
    """The block's body as the commands print it now."""
    with tempfile.TemporaryDirectory(prefix="chaindrive_cli_examples_") as tmp:
        work = Path(tmp)
        if "fmu" in block["options"]:
            if fmu is None:
                raise ValueError("this example needs a built FMU (--fmu PATH)")
            (work / "dist").mkdir()
            os.symlink(fmu(), work / "dist" / "ChainDrive.fmu")
        return "".join(f"$ {c}\n" + run_command(c, work, "json" in block["options"])
                       for c in block["commands"])


def mask(body: str) -> list:
    """A block's body with what varies between runs taken out: the wall-time row of a table,
    a tooth ratio's error below 1e-9 (round-off), and the timing keys of a JSON object; JSON numbers are kept as numbers (compared to JSON_REL
    relative by :func:`same`, the last digits of a float may differ between CPUs)."""
    out: list = []
    lines = body.splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.startswith("{"):                    # a JSON object, to its closing line
            j = i
            while not _parses(lines[i:j + 1]):
                j += 1
                if j >= len(lines):
                    raise ValueError(f"unterminated JSON object from: {line[:60]}")
            obj = json.loads("\n".join(lines[i:j + 1]))
            out.append({k: (None if k in VARYING_KEYS else v) for k, v in obj.items()})
            i = j + 1
            continue
        if any(line.startswith(row) for row in VARYING_ROWS):
            line = line.split()[0] + " " + line.split()[1] + " <varies>"
        line = ROUND_OFF.sub("error <round-off>", line)
        out.append(line.rstrip())
        i += 1
    return out


def _parses(lines: list[str]) -> bool:
    try:
        json.loads("\n".join(lines))
        return True
    except ValueError:
        return False


def same(a: Any, b: Any, rel: float = JSON_REL) -> bool:
    """Equal, numbers to ``rel`` (masked bodies)."""
    if isinstance(a, float) or isinstance(b, float):
        if isinstance(a, (int, float)) and isinstance(b, (int, float)) \
                and not isinstance(a, bool) and not isinstance(b, bool):
            return math.isclose(a, b, rel_tol=rel, abs_tol=1e-12)
        return False
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k], rel) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y, rel) for x, y in zip(a, b))
    return a == b


def build_fmu(folder: Path) -> Path:
    out = folder / "ChainDrive.fmu"
    subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out", str(out), "-q"],
                   check=True, cwd=ROOT)
    return out


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="*", type=Path, default=FILES)
    ap.add_argument("--fmu", type=Path, help="a built ChainDrive.fmu for the 'fmu' examples "
                                             "(default: build one into a temporary folder)")
    ap.add_argument("--check", action="store_true",
                    help="rewrite nothing; exit 1 if an example is stale")
    args = ap.parse_args(argv)
    sys.path.insert(0, str(ROOT))
    with tempfile.TemporaryDirectory(prefix="chaindrive_fmu_") as tmp:
        built: list[Path] = [args.fmu] if args.fmu else []

        def fmu() -> Path:
            if not built:
                built.append(build_fmu(Path(tmp)))
            return built[0].resolve()

        stale = 0
        for path in args.files:
            text = path.read_text()
            pieces, last = [], 0
            for block in blocks(text):
                body = render_block(block, fmu)
                start, end = block["span"]
                pieces += [text[last:start], body]
                last = end
                if not same(mask(body), mask(block["body"])):
                    stale += 1
                    print(f"{path.name}: stale example: $ {block['commands'][0]}")
            pieces.append(text[last:])
            if not args.check:
                path.write_text("".join(pieces))
                print(f"rewrote {path}")
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
