"""``chainmodel sweep STUDY.toml``: run a design study (registered in
:data:`chainmodel.cli.SUBCOMMANDS` as ``("chainmodel.analysis.sweep.cli", "register")``)."""

from __future__ import annotations

import math
import sys

__all__ = ["register"]


def register(subparsers) -> None:
    p = subparsers.add_parser(
        "sweep", help="run a design study (grid or random) over scene settings, on Dask",
        description="Run every case of a study file (docs/sweep.md; example: "
                    "examples/studies/speed_pretension.toml) through the library or the FMU, "
                    "reduce each to scalar metrics (span tensions, speed ripple, dominant "
                    "frequencies, midspan deflection, resonance hit) and write a tidy table "
                    "(Parquet with pyarrow, else CSV), the spectra, a Campbell diagram and a "
                    "resonance map. Finished cases are journalled in the output directory: "
                    "running the same command again resumes an interrupted sweep.")
    p.add_argument("study", metavar="STUDY.toml", help="the study file")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--workers", type=int, metavar="N",
                       help="a LocalCluster of N worker processes (default: this machine's cores)")
    where.add_argument("--scheduler", metavar="ADDRESS",
                       help="an existing Dask cluster, e.g. tcp://10.0.0.5:8786")
    where.add_argument("--serial", action="store_true",
                       help="run the cases one after the other in this process (no Dask)")
    p.add_argument("--out", metavar="DIR",
                   help="output directory (default: <study name>_sweep); holds the journal "
                        "that a later run resumes from")
    p.add_argument("--via-fmu", nargs="?", const="", default=None, metavar="FMU_PATH",
                   help="run each case through the built FMU with fmpy (default "
                        "dist/ChainDrive.fmu)")
    p.add_argument("--set", action="append", default=[], metavar="NAME=VALUE", dest="settings",
                   help="add a setting to the study's [fixed] table (e.g. duration=0.2 for a "
                        "quick try); names as for `chainmodel run --set`; repeatable")
    p.add_argument("--chunk-size", type=int, metavar="K",
                   help="cases per task (default: about eight tasks per worker)")
    p.add_argument("--retry-failed", action="store_true",
                   help="run the failed cases of an earlier run again")
    p.add_argument("--table-format", choices=("auto", "parquet", "csv"), default="auto",
                   help="auto: Parquet where pyarrow is installed, else CSV")
    p.add_argument("--map-metric", metavar="COLUMN",
                   help="the resonance map's colour (default: midspan deflection amplitude at "
                        "the modal levels, else the tight-span tension ripple)")
    p.add_argument("--no-plots", action="store_true", help="write the tables only")
    p.add_argument("--json", action="store_true",
                   help="print one JSON object (counts, timings, files) and nothing else")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(handler=run_sweep)


def run_sweep(args) -> int:
    from ...cli_support import fmu_path as _fmu_path, parse_settings as _parse_settings, print_json
    from . import sweep
    fixed = _parse_settings(args.settings)
    fmu = None if args.via_fmu is None else _fmu_path(args.via_fmu)
    progress = not (args.quiet or args.json)
    res = sweep(args.study, args.out, serial=args.serial, workers=args.workers,
                scheduler=args.scheduler, via_fmu=fmu, chunk_size=args.chunk_size,
                retry_failed=args.retry_failed, plots=not args.no_plots,
                table_format=args.table_format, map_metric=args.map_metric,
                progress=progress, **fixed)
    run, st = res.run, res.study
    hits = sum(1 for v in res.table["resonance"] if v)
    out = {"study": st.name, "cases": len(st), "varied": list(st.varied),
           "computed": run.computed, "reused": run.reused, "failed": len(run.failed),
           "mode": run.mode, "workers": run.workers, "chunks": run.chunks,
           "startup_s": run.startup_s, "wall_s": run.wall_s, "case_seconds": run.case_seconds,
           "resonance_hits": hits, "via_fmu": st.fmu is not None,
           "files": {k: str(v) for k, v in res.files.items()}}
    if args.json:
        print_json(out)
        return 0
    varied = " x ".join(f"{v} ({len(set(map(repr, res.table[v])))} values)" for v in st.varied)
    print(f"study       {st.name}: {len(st)} cases, {st.design} over {varied}; scene "
          f"{st.base.name}{', via FMU' if st.fmu else ''}")
    busy = f"{run.case_seconds:.1f} s of cases" if run.computed else "nothing to run"
    print(f"ran         {run.computed} cases ({run.reused} reused from the journal, "
          f"{len(run.failed)} failed) on {run.mode}: {run.wall_s:.1f} s wall, {busy}"
          + (f", {run.startup_s:.1f} s cluster start" if run.startup_s else ""))
    print(f"resonances  {hits} of {len(st)} cases within {100 * st.resonance_band:g} % of a span "
          "or sprocket mode at the meshing frequency or half of it")
    for i in run.failed[:5]:
        err = res.table["error"][i]
        print(f"failed      case {i}: {err if len(err) < 160 else err[:157] + '...'}")
    if len(run.failed) > 5:
        print(f"            ... and {len(run.failed) - 5} more (column 'error' of the table)")
    if not args.no_plots and "campbell" not in res.files:
        print("plots       not written: matplotlib is not installed (pip install 'chaindrive[plot]')")
    for what, path in res.files.items():
        print(f"wrote {what} to {path}")
    sys.stdout.flush()
    return 0 if math.isfinite(run.wall_s) else 1
