#!/usr/bin/env python
"""Build the example system's plain pythonfmu FMUs: Motor.fmu and Load.fmu (sources beside this
script), with pythonfmu's own builder and binary, as a user builds theirs.

    python examples/system/build.py                 # -> examples/system/dist/{Motor,Load}.fmu
    python examples/system/build.py --out DIR
    python examples/system/build.py --launch        # and put ChainDrive's launcher in front of
                                                    # their binaries (build_fmu.py --launch):
                                                    # C hosts need no set-up, exits are clean
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

HERE = Path(__file__).resolve().parent
MODELS = ("Motor", "Load")


def build(out: Path, launch: bool = False) -> list[Path]:
    from pythonfmu import FmuBuilder
    out = Path(out).resolve()
    out.mkdir(parents=True, exist_ok=True)
    built = []
    for name in MODELS:
        with tempfile.TemporaryDirectory() as tmp:
            raw = FmuBuilder.build_FMU(HERE / f"{name}.py", dest=tmp)
            target = out / f"{name}.fmu"
            target.write_bytes(Path(raw).read_bytes())
            if launch:
                sys.path.insert(0, str(HERE.parents[1]))
                from build_fmu import launch_fmu
                launch_fmu(target, target)
            built.append(target)
    return built


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=HERE / "dist", help="folder for the FMUs")
    ap.add_argument("--launch", action="store_true",
                    help="put ChainDrive's launcher in front of each FMU's binary")
    args = ap.parse_args(argv)
    for path in build(args.out, args.launch):
        print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
