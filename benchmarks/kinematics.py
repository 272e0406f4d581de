"""Throughput of the kinematics library on one core: driver angles per second, vectorised.

    python benchmarks/kinematics.py                # measure and print the table
    python benchmarks/kinematics.py --write-doc    # ... and rewrite "## Kinematics" in docs/performance.md
    python benchmarks/kinematics.py --quick        # smaller batches and fewer repeats (a smoke run)

For the coarse, medium and fine drives of seed 000 Table 1 and batches of 1e4, 1e5 and 1e6
driver angles (spread over many tooth periods, so both span lengths occur), it times

* ``kinematics.exact``           the four-bar: theta2, theta3, span length, omega2/3, alpha2
                                 (seed 000 eqs 26-32) - the DESIGN target is >= 1e6 angles/s;
* ``kinematics.driven_rotation`` the same plus the continuous forward-positive rotations;
* ``kinematics.approximate``     the closed forms (eqs 50-53);
* ``kinematics.wrap_length``     both spans and the total wrapping length (seed 004 eq 13).

The process is pinned to one CPU and BLAS/OpenMP threads are limited to one before numpy is
imported; each entry is the best of several repeats after a warm-up call (the seating and
release events are computed once per drive and cached).

The FMU's cost per communication step is a separate measurement (benchmarks/fmu_cost.py);
:func:`fmu_step_cost` below is the hook where that measurement plugs into this table.
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMEXPR_NUM_THREADS"):
    os.environ.setdefault(_var, "1")

import argparse  # noqa: E402
import datetime  # noqa: E402
import math  # noqa: E402
import platform  # noqa: E402
import subprocess  # noqa: E402
import sys  # noqa: E402
import time  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import chainmodel  # noqa: E402
from chainmodel import kinematics as K  # noqa: E402

DOC = ROOT / "docs" / "performance.md"
SECTION = "## Kinematics"
COMMAND = "python benchmarks/kinematics.py --write-doc"
DRIVES = ("coarse", "medium", "fine")
BATCHES = (10_000, 100_000, 1_000_000)
TARGET = 1e6  # driver angles per second, DESIGN.md / issue 2


def _pin_one_core() -> str:
    try:
        cpu = min(os.sched_getaffinity(0))
        os.sched_setaffinity(0, {cpu})
        return f"pinned to CPU {cpu}"
    except (AttributeError, OSError):  # pragma: no cover - not Linux
        return "not pinned (no sched_setaffinity)"


def _best_time(fn, repeats: int, budget: float) -> tuple[float, float]:
    """Best wall time and best CPU time of ``fn()`` over ``repeats`` calls (fewer if
    ``budget`` s runs out). CPU time is what a dedicated core would see when other processes
    share the machine."""
    fn()  # warm-up
    best_wall = best_cpu = math.inf
    start = time.perf_counter()
    for _ in range(repeats):
        t0, c0 = time.perf_counter(), time.process_time()
        fn()
        best_cpu = min(best_cpu, time.process_time() - c0)
        best_wall = min(best_wall, time.perf_counter() - t0)
        if time.perf_counter() - start > budget:
            break
    return best_wall, best_cpu


def measure(drives=DRIVES, batches=BATCHES, repeats: int = 7, budget: float = 3.0):
    """{(function, drive, batch): (driver angles per wall second, per CPU second)}."""
    rng = np.random.default_rng(0)
    rates = {}
    for name in drives:
        d = chainmodel.preset(name)
        s = K.seating(d)
        P = 2 * math.pi / d.n_driver
        for n in batches:
            phi = rng.uniform(0.0, 50 * P, n)          # driver rotations over 50 tooth periods
            theta4 = s.theta4 - phi                    # the same angles as contact angles
            w = np.full(n, 10.47)
            a = np.full(n, 5.0)
            cases = {
                "exact": lambda: K.exact(d, theta4, -w, -a),
                "driven_rotation": lambda: K.driven_rotation(d, phi, w, a),
                "approximate": lambda: K.approximate(d, theta4, -w, -a),
                "wrap_length": lambda: K.wrap_length(d, phi),
            }
            for fn_name, fn in cases.items():
                if fn_name == "wrap_length" and n > 100_000:
                    continue   # memory-heavy; 1e5 shows its rate
                wall, cpu = _best_time(fn, repeats, budget)
                rates[(fn_name, name, n)] = (n / wall, n / max(cpu, 1e-9))
    return rates


def fmu_step_cost():
    """Hook for the FMU helper: cost per communication step of the level-0 FMU through fmpy,
    next to a bare pythonfmu FMU, measured in the same run.

    Return a dict such as ``{"chaindrive_us": ..., "bare_us": ..., "library_us": ...}``, or
    None when not measured. The measurement is benchmarks/fmu_cost.py's (it builds both FMUs
    in a temporary directory); None, with the reason on stderr, if it cannot run."""
    try:
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from fmu_cost import fmu_step_cost as measure
        res = measure(steps=500, repeats=3, levels=(0,))["levels"][0]
    except Exception as exc:  # the FMU toolchain is optional for this benchmark
        print(f"FMU step cost not measured: {type(exc).__name__}: {exc}", file=sys.stderr)
        return None
    return {"chaindrive_us": round(res["chaindrive_s"] * 1e6, 1),
            "bare_us": round(res["bare_s"] * 1e6, 1),
            "library_us": round(res["library_s"] * 1e6, 1)}


# --- reporting --------------------------------------------------------------------------------

def _cpu_model() -> str:
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True, check=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return line.split(":", 1)[1].strip()
    except (OSError, subprocess.CalledProcessError):
        pass
    return platform.processor() or "unknown CPU"


def table(rates, drives=DRIVES, batches=BATCHES) -> str:
    fns = []
    for key in rates:
        if key[0] not in fns:
            fns.append(key[0])
    head = "| function | drive | " + " | ".join(f"{n:.0e} angles" for n in batches) + " |"
    lines = [head, "|---|---|" + "---:|" * len(batches)]
    for fn in fns:
        for name in drives:
            cells = []
            for n in batches:
                r = rates.get((fn, name, n))
                cells.append("-" if r is None else f"{r[0] / 1e6:.2f} ({r[1] / 1e6:.2f})")
            lines.append(f"| `{fn}` | {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def _load() -> str:
    try:
        return ", ".join(f"{v:.1f}" for v in os.getloadavg())
    except OSError:  # pragma: no cover
        return "unknown"


def section_text(rates, pin: str, fmu=None, load: str = "") -> str:
    wall = [r[0] for (fn, _, _), r in rates.items() if fn == "exact"]
    cpu = [r[1] for (fn, _, _), r in rates.items() if fn == "exact"]
    verdict = "meets" if min(wall) >= TARGET else "MISSES"
    machine = f"{_cpu_model()}, {os.cpu_count()} cores ({pin})"
    text = [
        SECTION,
        "",
        "Driver angles per second through the kinematics library on one core, vectorised over",
        "the angles (best of several repeats; the seating/release events are cached per drive).",
        f"`kinematics.exact` {verdict} the target of 1e6 angles/s at every batch size in wall "
        f"time: slowest {min(wall) / 1e6:.2f} M/s (CPU time: slowest {min(cpu) / 1e6:.2f} M/s).",
        "",
        f"Command: `{COMMAND}`  ",
        f"Machine: {machine}; Python {platform.python_version()}, numpy {np.__version__}; "
        f"load average during the run {load or _load()}  ",
        f"Date: {datetime.date.today().isoformat()}",
        "",
        "Cells: million angles per second of wall time (in brackets: per second of CPU time,",
        "which is what a dedicated core gives when other processes share the machine).",
        "",
        table(rates),
        "",
        "`exact` is seed 000 eqs 26-32 (theta2, theta3, span length, velocity ratio, omega2,",
        "omega3, alpha2); `driven_rotation` adds the continuous forward-positive rotations;",
        "`approximate` the closed forms of eqs 50-53 (with h from the exact events);",
        "`wrap_length` both spans and seed 004 eq 13 (measured up to 1e5 angles). Other",
        "processes shared the machine during the run, so rates can vary by tens of percent",
        "between runs.",
    ]
    text += [
        "",
        "`fourbar.exact` was profiled and made 10-25 % faster with bit-identical results (root",
        "choice by `np.where` instead of stack/argmin, cos/sin of theta4 shared by eqs 28-29, no",
        "second mapping into the period); processing 1e6-angle batches in cache-sized blocks",
        "gave nothing in CPU time and was left out. A *scalar* call is another matter: level 0",
        "evaluates one angle per FMU step, and there the numpy call overhead of",
        "`driven_rotation` + `chain_geometry` (about 0.8 ms of CPU per call) dominates, not the",
        "arithmetic (see the FMU section).",
    ]
    if fmu:
        parts = {"chaindrive_us": "ChainDrive FMU at level 0", "bare_us": "bare pythonfmu FMU",
                 "library_us": "library level 0 per output (whole simulate())"}
        cells = ", ".join(f"{parts.get(k, k)} {v:,.0f} µs" for k, v in fmu.items())
        text += ["", f"FMU cost per communication step in the same run (`fmu_step_cost()`, "
                     f"benchmarks/fmu_cost.py, see the FMU section): {cells}."]
    return "\n".join(text) + "\n"


def write_section(text: str, path: Path = DOC) -> None:
    """Replace (or append) the '## Kinematics' section of docs/performance.md, leaving the
    other sections as they are."""
    old = path.read_text() if path.exists() else "# Performance\n"
    lines = old.splitlines(keepends=True)
    start = next((i for i, ln in enumerate(lines) if ln.rstrip() == SECTION), None)
    if start is None:
        new = old.rstrip("\n") + "\n\n" + text
    else:
        end = next((i for i in range(start + 1, len(lines)) if lines[i].startswith("## ")),
                   len(lines))
        new = "".join(lines[:start]) + text + ("\n" if end < len(lines) else "") + "".join(lines[end:])
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(new)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write-doc", action="store_true",
                    help=f"rewrite the '{SECTION}' section of docs/performance.md")
    ap.add_argument("--quick", action="store_true", help="small batches, few repeats")
    args = ap.parse_args(argv)
    pin = _pin_one_core()
    batches = (10_000, 100_000) if args.quick else BATCHES
    rates = measure(batches=batches, repeats=3 if args.quick else 7,
                    budget=0.5 if args.quick else 3.0)
    load = _load()
    print(f"kinematics throughput, one core ({pin}), million driver angles per second of "
          f"wall time (CPU time); load average {load}")
    print(table(rates, batches=batches))
    exact = [r[0] for (fn, _, _), r in rates.items() if fn == "exact"]
    print(f"exact: min {min(exact):.3g}/s wall, target {TARGET:.0e}/s: "
          f"{'met' if min(exact) >= TARGET else 'NOT met'}")
    fmu = fmu_step_cost()
    print("FMU step cost: " + ("not measured here (benchmarks/fmu_cost.py)" if fmu is None
                                else str(fmu)))
    if args.write_doc:
        if args.quick:
            print("--write-doc ignored with --quick", file=sys.stderr)
        else:
            write_section(section_text(rates, pin, fmu, load))
            print(f"wrote {SECTION!r} in {DOC.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
