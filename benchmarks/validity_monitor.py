"""Cost of the validity checks (chainmodel.validity; docs/stability.md "Where a result is valid").

    python benchmarks/validity_monitor.py

Prints a table: ``Monitor.update`` per sample as the FMU adapter calls it after every
fmi2DoStep (a row of the 15 outputs as a list; while nothing fires, and once a problem has
fired), and ``Result.problems`` of whole runs (arrays; the geometry check included, its wrapping
length cached per drive after the first call).
"""

from __future__ import annotations

import statistics
import sys
import time
import timeit
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import chainmodel  # noqa: E402
from chainmodel.models import ALL_OUTPUTS  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from chainmodel.validity import Monitor  # noqa: E402

NAMES = [o.name for o in ALL_OUTPUTS]


def per_update(reversed_speed: bool, level: int = 1, n: int = 50000, repeats: int = 5,
               slack: float = 3000.0) -> float:
    """Median microseconds per Monitor.update over ``repeats`` blocks of ``n`` samples (at
    level 3 the damper-loss balance sums every sample too). ``slack``: the slack span's
    tension; at 3000 N its first string mode (138 Hz) is high enough that levels 0-1's
    span-modes check stays quiet at 120 rpm (50 Hz meshing), at 100 N it fires."""
    sc = load_scene("xu2010")
    times = []
    for _ in range(repeats):
        mon = Monitor(sc.drive, sc.parameters, level, NAMES)
        row = [0.0] * len(NAMES)
        row[NAMES.index("driven.speed")] = -1.0 if reversed_speed else 18.5
        for name, value in (("driver.speed", 12.57), ("input_shaft.torque", 63.5),
                            ("tight_span.tension", 3100.0), ("slack_span.tension", slack)):
            row[NAMES.index(name)] = value
        ia = NAMES.index("driver.angle")
        state = {"i": 0}

        def one():
            i = state["i"] = state["i"] + 1
            row[ia] = 12.57 * i * 1e-4
            mon.update(i * 1e-4, row, 12.57, 43.2)

        times.append(timeit.timeit(one, number=n) / n * 1e6)
    return statistics.median(times)


def whole_run(level: int, duration: float) -> tuple[int, float]:
    r = chainmodel.simulate("xu2010", fidelity=level, duration=duration)
    r.problems                                  # the wrapping length's first computation
    best = []
    for _ in range(5):
        r.__dict__.pop("problems", None)
        t = time.perf_counter()
        r.problems
        best.append(time.perf_counter() - t)
    return len(r.time), min(best)


def main() -> None:
    rows = [("Monitor.update, nothing fires", f"{per_update(False):.2f} µs per sample"),
            ("Monitor.update, a problem fired", f"{per_update(True):.2f} µs per sample"),
            ("Monitor.update, the span-modes check fired (slack span 100 N)",
             f"{per_update(False, slack=100.0):.2f} µs per sample"),
            ("Monitor.update at level 3 (damper-loss sums), nothing fires",
             f"{per_update(False, level=3):.2f} µs per sample")]
    for level, duration in ((1, 1.0), (3, 0.3)):
        n, sec = whole_run(level, duration)
        rows.append((f"Result.problems, xu2010 level {level}, {duration:g} s ({n} samples)",
                     f"{1e3 * sec:.2f} ms"))
    print("| what | cost |\n|---|---:|")
    for what, cost in rows:
        print(f"| {what} | {cost} |")


if __name__ == "__main__":
    main()
