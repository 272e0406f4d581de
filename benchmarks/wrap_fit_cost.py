"""What ``torsional.wrap_statics`` costs when a model is built (chainmodel.models.wrap_statics,
docs/reduced_models.md "One wrap and one static tension from level 3's statics").

    python benchmarks/wrap_fit_cost.py            # every scene below, levels 0-2
    python benchmarks/wrap_fit_cost.py C1 xu2010  # some scenes

Each cell is one fresh subprocess that builds the scene's level 0, then 1, then 2 model
(``load_scene(..., fidelity=L).model()``, kernels warm from the per-machine cache) and prints the
seconds each took; the first build pays level 3's statics (the fit, and a named static tension's
pretension search), the next ones only their own fit. The default path (the seat ladder) is
timed the same way beside it. Medians over ``--repeat`` processes.

    python benchmarks/wrap_fit_cost.py --vs DIR   # the option's cells of another checkout
                                                 # (its chainmodel on PYTHONPATH), run in turn
                                                 # with this one's, process by process
"""

from __future__ import annotations

import argparse
import json
import statistics
import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SCENES = ("C1", "xu2010", "examples/scenes/08b_fan_1500rpm.toml")

_CHILD = """
import json, sys, time
from chainmodel.scene import load_scene
name, option = sys.argv[1], sys.argv[2] == "1"
kw = {"torsional_wrap_statics": True} if option else {}
out = []
for level in (0, 1, 2):
    t = time.perf_counter()
    load_scene(name, fidelity=level, **kw).model()
    out.append(time.perf_counter() - t)
print(json.dumps(out))
"""


def builds(name: str, option: bool, checkout: Path = ROOT) -> list[float]:
    """Seconds to build levels 0, 1, 2 in turn in one fresh process (``checkout``'s
    chainmodel)."""
    env = dict(os.environ, PYTHONPATH=str(checkout))
    done = subprocess.run([sys.executable, "-c", _CHILD, name, "1" if option else "0"],
                          cwd=checkout, capture_output=True, text=True, check=True, env=env)
    return json.loads(done.stdout.strip().splitlines()[-1])


def _median(runs: list[list[float]]) -> str:
    return " / ".join(f"{statistics.median(r[i] for r in runs):.3f}" for i in range(3))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("scenes", nargs="*", default=list(SCENES))
    ap.add_argument("--repeat", type=int, default=3, help="processes per cell (median)")
    ap.add_argument("--vs", type=Path, default=None,
                    help="another checkout whose option cells run in turn with this one's")
    args = ap.parse_args(argv)
    print("seconds to build levels 0 / 1 / 2 in turn in one process (median of "
          f"{args.repeat} processes)")
    head = f"{'scene':40s} {'default':>22s} {'torsional.wrap_statics':>24s}"
    if args.vs is not None:
        head += f" {'option, ' + args.vs.name:>24s} {'ratio':>18s}"
    print(head)
    for name in args.scenes:
        # one untimed process per checkout first: a checkout's first run compiles its kernels
        builds(name, True)
        if args.vs is not None:
            builds(name, True, args.vs.resolve())
        default = [builds(name, False) for _ in range(args.repeat)]
        option, other = [], []
        for _ in range(args.repeat):
            option.append(builds(name, True))
            if args.vs is not None:
                other.append(builds(name, True, args.vs.resolve()))
        row = f"{name:40s} {_median(default):>22s} {_median(option):>24s}"
        if args.vs is not None:
            ratios = [statistics.median(a[i] / b[i] for a, b in zip(option, other))
                      for i in range(3)]
            row += f" {_median(other):>24s} {' / '.join(f'{r:.2f}' for r in ratios):>18s}"
        print(row, flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
