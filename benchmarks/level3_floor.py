"""Level 3 (multibody) against a compiled C floor of the same model, timed in the same run
(issue 20, item 6).

The floor is benchmarks/multibody_floor.c: the force law of
kernels.multibody_forces.accelerations and its velocity-Verlet loop (one force evaluation per step) in plain C, compiled here with gcc
(-O2 -march=native -fno-math-errno; no -ffast-math, as numba's kernels have none). For each
chain length (46, 100, 144, 200 links: xu2010's sprockets, the centre distance set as
benchmarks/multibody.py does) the script times, interleaved, best of --repeat:

* "simulate()": the whole library call, 1 s of the scene at outputs every 1e-4 s (the default;
  ramp 0.05 s to 120 rpm, then steady running), after a warm-up;
* "numba loop": the compiled Verlet loop alone (kernels.multibody_loops.run_fixed: the numbers
  of two force evaluations per step - at each step's start and at its end with the half-step
  velocity - made of one position pass and two velocity passes), the same number of steps at
  the same mean step, from the library's state at 0.5 s, constant input speed;
* "C, 2 / step": the C loop computing the same numbers with two full evaluations per step, the
  same steps from the same state (it checks itself: after 2000 steps its state equals the numba
  loop's to round-off);
* "C floor, 1 / step": the C loop reusing the step-end evaluation as the next step's start
  (issue 20's floor: one force evaluation per step).

"simulate / C floor" is issue 20's ratio (target <= 1.5); "x real time" = 1 s / simulate().

    python benchmarks/level3_floor.py [--repeat 5] [--links 46 100 144 200]
"""

from __future__ import annotations

import argparse
import ctypes
import math
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent

import chainmodel  # noqa: E402
from chainmodel.kernels import multibody_layout as K  # noqa: E402
from chainmodel.kernels.multibody_loops import run_fixed  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from chainmodel.simulation import run_scene  # noqa: E402
from chainmodel.units import RPM  # noqa: E402


def scene_for(links: int, duration: float = 1.0):
    """xu2010 at level 3 with ``links`` links (benchmarks/multibody.py's scene_for)."""
    base = load_scene("xu2010", fidelity="multibody", duration=duration)
    if links == 46:
        return base
    tight46 = chainmodel.Drive.from_links(25, 17, 0.015875, 46).centre_distance
    tight = chainmodel.Drive.from_links(25, 17, 0.015875, links).centre_distance
    return base.with_overrides(parameters={"drive.links": links,
                                           "drive.centre_distance": tight + (0.1977 - tight46)})


def build_floor(tmp: Path) -> ctypes.CDLL:
    """Compile multibody_floor.c with the parameter indices of kernels.multibody_layout (I_*)."""
    index = {name: getattr(K, name) for name in dir(K)
             if name.startswith("I_") and isinstance(getattr(K, name), int)}
    header = "".join(f"#define {name} {k}\n" for name, k in sorted(index.items()))
    header += f"#define N_PARAMS {K.N_PARAMS}\n"
    (tmp / "floor_params.h").write_text(header)
    lib = tmp / "floor.so"
    subprocess.run(["gcc", "-O2", "-march=native", "-fno-math-errno", "-shared", "-fPIC",
                    f"-I{tmp}", str(HERE / "multibody_floor.c"), "-o", str(lib), "-lm"],
                   check=True)
    so = ctypes.CDLL(str(lib))
    dp = ctypes.POINTER(ctypes.c_double)
    so.verlet.argtypes = [ctypes.c_int, dp, ctypes.c_double, ctypes.c_double, ctypes.c_long,
                          ctypes.c_double, ctypes.c_double, dp, ctypes.c_int]
    so.verlet.restype = ctypes.c_long
    return so


def state_at(scene, t: float) -> np.ndarray:
    """The library's state at t (communication steps of 1 ms, the scene's inputs)."""
    st = scene.stepper()
    times = np.arange(0.0, t + 1e-12, 1e-3)
    inputs = scene.input_arrays(times)
    states = st.advance_batch(times, *inputs)
    return np.array(states[-1])


def _c_run(so, x, t0, h, steps, w_in, load, P, evals_per_step) -> int:
    dp = ctypes.POINTER(ctypes.c_double)
    return so.verlet(x.size // 2, x.ctypes.data_as(dp), t0, h, steps, w_in, load,
                     P.ctypes.data_as(dp), evals_per_step)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--links", type=int, nargs="+", default=[46, 100, 144, 200])
    args = ap.parse_args(argv)
    la = os.getloadavg()
    print(f"machine: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}; load average before: "
          f"{la[0]:.2f} {la[1]:.2f} {la[2]:.2f}")
    rows = []
    with tempfile.TemporaryDirectory(prefix="level3_floor_") as tmp:
        so = build_floor(Path(tmp))
        for links in args.links:
            sc = scene_for(links)
            model = sc.model()
            run_scene(sc.with_overrides(duration=0.01))          # compile / warm up
            r = run_scene(sc)
            steps, evals = r.stats["steps"], r.stats["rhs_evaluations"]
            h = 1.0 / steps
            x0 = state_at(sc, 0.5)
            w_in, load = sc.operating.speed, sc.operating.load_torque
            P = np.ascontiguousarray(model.P)
            hermite = (0.5, 1.0, w_in * 0.5, w_in, w_in * 1.5, w_in, load, load)

            def numba_loop(x, m):
                return run_fixed(0, x, 0.5, h, m, *hermite, model.P, model.ws)

            # the C loop with the library's scheme computes what the compiled loop does
            xa, xb = x0.copy(), x0.copy()
            numba_loop(xa, 2000)
            _c_run(so, xb, 0.5, h, 2000, w_in, load, P, 2)
            agree = float(np.max(np.abs(xa - xb) / (1e-3 + np.abs(xa))))
            best = {"sim": math.inf, "numba": math.inf, "c2": math.inf, "c1": math.inf}
            for _ in range(args.repeat):
                t = time.perf_counter()
                run_scene(sc)
                best["sim"] = min(best["sim"], time.perf_counter() - t)
                x = x0.copy()
                t = time.perf_counter()
                numba_loop(x, steps)
                best["numba"] = min(best["numba"], time.perf_counter() - t)
                for e in (2, 1):
                    x = x0.copy()
                    t = time.perf_counter()
                    bad = _c_run(so, x, 0.5, h, steps, w_in, load, P, e)
                    best[f"c{e}"] = min(best[f"c{e}"], time.perf_counter() - t)
                    if bad >= 0:
                        raise SystemExit(f"the C loop diverged at step {bad} ({links} links)")
            rows.append((links, steps, evals, best, agree))
            print(f"  {links} links done", file=sys.stderr, flush=True)
    la = os.getloadavg()
    print(f"load average after: {la[0]:.2f} {la[1]:.2f} {la[2]:.2f}; input speed "
          f"{sc.operating.speed / RPM:g} rpm, 1 s simulated, outputs every 1e-4 s\n")
    print("| links | steps / s | evaluations (simulate) | simulate() [s] | x real time | "
          "numba loop [s] | C, 2 full evaluations / step [s] | C floor, 1 / step [s] | "
          "simulate / C floor | numba loop / C (same scheme) | C vs numba state after 2000 "
          "steps | C per evaluation [us] |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for links, steps, evals, b, agree in rows:
        print(f"| {links} | {steps} | {evals} | {b['sim']:.3f} | {1 / b['sim']:.1f} | "
              f"{b['numba']:.3f} | {b['c2']:.3f} | {b['c1']:.3f} | {b['sim'] / b['c1']:.2f} | "
              f"{b['numba'] / b['c2']:.2f} | {agree:.1e} | {1e6 * b['c1'] / (steps + 1):.2f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
