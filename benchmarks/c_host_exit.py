#!/usr/bin/env python
"""Exit codes of a C host running the FMU: tests/test_c_host.py's minimal FMI 2.0 master (C,
compiled here with cc), one fresh process per run, under ``env -i``.

    python benchmarks/c_host_exit.py dist/ChainDrive.fmu --level 3 --runs 20
    python benchmarks/c_host_exit.py old.fmu --recipe --runs 20      # an FMU built with
        # --no-launcher, given Python by docs/fmu.md's recipe (LD_PRELOAD, PYTHONHOME,
        # PYTHONPATH, PYTHONMALLOC=malloc); --recipe-no-malloc leaves PYTHONMALLOC out

Each run: instantiate, 0.01 s at 0.1 ms steps at --level, terminate, free, dlclose, return.
"""

from __future__ import annotations

import argparse
import collections
import subprocess
import sys
import sysconfig
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests"))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("fmu", type=Path)
    ap.add_argument("--level", type=int, default=0, choices=(0, 1, 2, 3))
    ap.add_argument("--runs", type=int, default=20)
    ap.add_argument("--recipe", action="store_true")
    ap.add_argument("--recipe-no-malloc", action="store_true")
    args = ap.parse_args(argv)
    from fmpy import extract, read_model_description
    import test_c_host as t
    md = read_model_description(str(args.fmu))
    vr = {v.name: v.valueReference for v in md.modelVariables}
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "master.c").write_text(t.MASTER_C)
        exe = Path(tmp) / "master"
        subprocess.run([t.CC or "cc", "-O2", "-I", str(t.FMI2_HEADERS), "-o", str(exe),
                        str(Path(tmp) / "master.c"), "-ldl"], check=True)
        folder = Path(extract(str(args.fmu), str(Path(tmp) / "fmu")))
        env = {}
        if args.recipe or args.recipe_no_malloc:
            libdir, so = sysconfig.get_config_var("LIBDIR"), sysconfig.get_config_var("INSTSONAME")
            env = {"LD_PRELOAD": f"{libdir}/{so}", "PYTHONHOME": sys.base_prefix,
                   "PYTHONPATH": sysconfig.get_paths()["purelib"]}
            if not args.recipe_no_malloc:
                env["PYTHONMALLOC"] = "malloc"
        counts = collections.Counter()
        for _ in range(args.runs):
            proc = t.run_master(exe, folder, (md.guid, vr), args.level, 100, env=env,
                                outputs=["driver.angle", "tight_span.tension"])
            complete = len(proc.stdout.splitlines()) == 101
            last = (proc.stderr.strip().splitlines() or [""])[-1][:60]
            counts[f"exit {proc.returncode}" + ("" if complete else ", output incomplete")
                   + (f" ({last})" if proc.returncode else "")] += 1
    print(f"{args.runs} runs, level {args.level}, "
          f"{'recipe ' + ' '.join(sorted(env)) if env else 'env -i'}: "
          + ", ".join(f"{k}: {v}" for k, v in sorted(counts.items())))
    return 0


if __name__ == "__main__":
    sys.exit(main())
