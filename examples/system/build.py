#!/usr/bin/env python
"""Build the example system's plain pythonfmu FMUs: Motor.fmu and Load.fmu (sources beside this
script), with pythonfmu's own builder and binary, as a user builds theirs.

    python examples/system/build.py                 # -> examples/system/dist/{Motor,Load}.fmu
    python examples/system/build.py --out DIR
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODELS = ("Motor", "Load")


def build(out: Path) -> list[Path]:
    from pythonfmu import FmuBuilder
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    built = []
    for name in MODELS:
        with tempfile.TemporaryDirectory() as tmp:
            raw = FmuBuilder.build_FMU(HERE / f"{name}.py", dest=tmp)
            target = out / f"{name}.fmu"
            target.write_bytes(Path(raw).read_bytes())
            built.append(target)
    return built


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=HERE / "dist", help="folder for the FMUs")
    args = ap.parse_args(argv)
    for path in build(args.out):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
