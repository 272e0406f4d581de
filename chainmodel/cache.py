"""``chainmodel cache``: show or clear the per-machine cache of compiled numba kernels
(:mod:`chainmodel.numba_cache`, docs/numba_cache.md). Also ``python -m chainmodel.cache``."""

from __future__ import annotations

import argparse
import json
import sys

__all__ = ["register", "main"]


def _add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--clear", action="store_true",
                   help="remove every compiled kernel (they are recompiled on next use)")
    p.add_argument("--info", action="store_true",
                   help="where the cache is and what it holds (the default)")
    p.add_argument("--json", action="store_true", help="print the information as one JSON object")


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "cache", help="show or clear the compiled-kernel cache",
        description="numba compiles the level 1-3 kernels once per machine and keeps them in a "
                    "per-user cache folder (CHAINMODEL_CACHE_DIR moves it); see "
                    "docs/numba_cache.md.")
    _add_arguments(p)
    p.set_defaults(handler=run)


def run(args) -> int:
    from . import numba_cache
    removed = numba_cache.clear() if args.clear else None
    data = numba_cache.info()
    if args.json:
        if removed is not None:
            data["removed_files"] = removed
        print(json.dumps(data))
        return 0
    if removed is not None:
        print(f"removed {removed} file(s) from {data['path']}")
    if args.info or removed is None:
        print(numba_cache.format_info(data))
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m chainmodel.cache", description=__doc__)
    _add_arguments(ap)
    return run(ap.parse_args(argv))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
