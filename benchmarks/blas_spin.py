"""When OpenBLAS's worker threads spin beside a level 0-2 run (docs/performance.md, "The
OpenBLAS spin, measured").

After a multi-threaded BLAS call OpenBLAS keeps its worker threads busy-waiting for a while
before they sleep. The process then uses more CPU than one core while the compiled loop runs on
one. This measures, per scene, the other threads' CPU (process CPU time over wall time while
the main thread sleeps, in 10 ms slices):

* after the first build of the scene's level-1 model in the process (imports, the wrap fit's
  statics and their caches);
* after a second build of the same scene (the wrap fit cached);
* around warm 1 s ``simulate()`` calls, CPU over wall time of each call: five calls straight
  after building a new variant of the drive (``contact.stiffness`` 1 % higher: a wrap fit of
  its own), and five more after a 0.5 s pause.

    python benchmarks/blas_spin.py [--slices 20]

Run it without OPENBLAS_NUM_THREADS set: with OPENBLAS_NUM_THREADS=1 there is no pool to spin.
"""

from __future__ import annotations

import argparse
import os
import time

import chainmodel
from chainmodel import simulation


def other_threads(slices: int) -> list[float]:
    """CPU of the threads other than this one, in cores, over ``slices`` sleeps of 10 ms."""
    out = []
    for _ in range(slices):
        w, c = time.perf_counter(), time.process_time()
        time.sleep(0.01)
        out.append((time.process_time() - c) / (time.perf_counter() - w))
    return out


def calls(sc, n: int = 5) -> list[float]:
    """CPU over wall time of ``n`` whole simulate() calls in a row."""
    out = []
    for _ in range(n):
        w, c = time.perf_counter(), time.process_time()
        simulation.run_scene(sc)
        out.append((time.process_time() - c) / (time.perf_counter() - w))
    return out


def spun(samples: list[float]) -> str:
    """How long the other threads ran (slices above half a core), in ms."""
    busy = [i for i, x in enumerate(samples) if x > 0.5]
    return f"{10 * (busy[-1] + 1)} ms" if busy else "0 ms"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--slices", type=int, default=20)
    ap.add_argument("--scenes", nargs="*", default=["xu2010", "C1"])
    args = ap.parse_args(argv)
    print(f"OPENBLAS_NUM_THREADS={os.environ.get('OPENBLAS_NUM_THREADS', '(unset)')}; "
          f"{os.cpu_count()} cores; load average "
          f"{' '.join(f'{v:.2f}' for v in os.getloadavg())}\n")
    print("| scene | first build [ms] | others spin after it | second build [ms] | others spin "
          "after it | 5 warm 1 s calls right after a new variant's build, CPU / wall | the same "
          "after a 0.5 s pause |")
    print("|---|---|---|---|---|---|---|")
    for name in args.scenes:
        sc = chainmodel.Scene.from_preset(name, fidelity=1, duration=1.0)
        t = time.perf_counter()
        sc.model()
        first = time.perf_counter() - t
        after_first = other_threads(args.slices)
        t = time.perf_counter()
        chainmodel.Scene.from_preset(name, fidelity=1, duration=1.0).model()
        second = time.perf_counter() - t
        after_second = other_threads(args.slices)
        simulation.run_scene(sc.with_overrides(duration=0.01))          # warm-up
        time.sleep(0.5)
        k = sc.parameters["contact.stiffness"]
        variant = sc.with_overrides(contact_stiffness=1.01 * k)
        variant.model()
        busy = calls(variant)
        time.sleep(0.5)
        quiet = calls(variant)
        print(f"| {name} | {1e3 * first:.0f} | {spun(after_first)} | {1e3 * second:.0f} | "
              f"{spun(after_second)} | {' '.join(f'{x:.2f}' for x in busy)} | "
              f"{' '.join(f'{x:.2f}' for x in quiet)} |", flush=True)


if __name__ == "__main__":
    main()
