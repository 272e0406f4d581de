"""Step convergence of level 3 (multibody) in every output a trade study uses.

    python benchmarks/convergence.py                       # xu2010 defaults, h, h/2, h/4, h/8
    python benchmarks/convergence.py --set chain.joint_damping=0 --duration 1.5
    python benchmarks/convergence.py --rpm 600 --steps 1,0.5,0.25

Runs xu2010 (seed 003 section 7: 0.05 s ramp to 120 rpm, 43.2 N m) with the fixed Verlet step h
that level 3 chooses itself (``solver.step = 0``) and with h/2, h/4, h/8, and prints for each the
figures of docs/multibody.md "Convergence": mean and peak span tensions, the driven-speed ripple
(RMS), the input-shaft torque ripple (RMS), the driven-speed amplitude at the meshing frequency,
the transmission error (RMS about its mean), the smallest link tension and the time fraction with
a slack link, over the steady window (t >= --steady). The last columns give each figure's change
against the next finer step; the order estimate is log2(|f(h) - f(h/2)| / |f(h/2) - f(h/4)|).
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import chainmodel  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from chainmodel.simulation import run_scene  # noqa: E402

FIGURES = ("tight_mean", "tight_peak", "slack_mean", "slack_peak", "speed_ripple",
           "torque_ripple", "mesh_amplitude", "te_rms", "min_link", "slack_fraction")
UNITS = ("N", "N", "N", "N", "rad/s", "N.m", "rad/s", "mrad", "N", "")


def figures(result, steady):
    """The trade-study figures of one run (see module docstring)."""
    t = result.time
    m = t >= steady - 1e-12
    tight, slack = result["tight_span.tension"][m], result["slack_span.tension"][m]
    w2 = result["driven.speed"][m]
    w1 = result["driver.speed"][m]
    f_mesh = float(np.mean(w1)) * result.scene.drive.n_driver / (2 * math.pi)
    tt = t[m]
    # amplitude of the meshing-frequency line: least-squares sine/cosine fit at f_mesh
    basis = np.column_stack([np.cos(2 * math.pi * f_mesh * tt), np.sin(2 * math.pi * f_mesh * tt),
                             np.ones_like(tt)])
    coef = np.linalg.lstsq(basis, w2, rcond=None)[0]
    te = result["transmission_error"][m]
    out = {"tight_mean": tight.mean(), "tight_peak": tight.max(), "slack_mean": slack.mean(),
           "slack_peak": slack.max(), "speed_ripple": w2.std(),
           "torque_ripple": result["input_shaft.torque"][m].std(),
           "mesh_amplitude": math.hypot(coef[0], coef[1]), "te_rms": 1e3 * te.std()}
    low = np.array([s["link_tension"].min() for tt_, s in result.snapshots if tt_ >= steady - 1e-12])
    out["min_link"] = low.min()
    out["slack_fraction"] = float(np.mean(low <= 0.0))
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=1.0)
    ap.add_argument("--steady", type=float, default=0.5)
    ap.add_argument("--rpm", type=float, default=120.0)
    ap.add_argument("--load", type=float, default=43.2)
    ap.add_argument("--steps", default="1,0.5,0.25,0.125", help="fractions of the automatic step")
    ap.add_argument("--set", action="append", default=[], help="parameter=value overrides")
    args = ap.parse_args(argv)
    params = {}
    for kv in args.set:
        k, v = kv.split("=", 1)
        params[k] = float(v) if v.replace(".", "", 1).replace("e-", "", 1).replace("-", "", 1).isdigit() else v
    scene = load_scene("xu2010", fidelity=3, duration=args.duration, output_interval=1e-4,
                       input_speed_rpm=args.rpm, load_torque=args.load).with_overrides(parameters=params)
    stepper = scene.stepper()
    h0 = stepper.h
    print(f"xu2010 level 3, {args.rpm:g} rpm, {args.load:g} N m, {args.duration:g} s, steady from "
          f"{args.steady:g} s; automatic Verlet step h = {h0:.4g} s; overrides {params or 'none'}; "
          f"load average {os.getloadavg()[0]:.2f}")
    rows = []
    for frac in (float(f) for f in args.steps.split(",")):
        c0 = time.process_time()
        r = run_scene(scene.with_overrides(parameters={**params, "solver.step": h0 * frac}), snapshot_every=1)
        rows.append((frac, figures(r, args.steady), time.process_time() - c0))
    head = "| step | " + " | ".join(f"{f} [{u}]" if u else f for f, u in zip(FIGURES, UNITS)) + " | CPU s |"
    print(head)
    print("|" + "---|" * (len(FIGURES) + 2))
    for frac, f, cpu in rows:
        print(f"| h/{1 / frac:g} | " + " | ".join(f"{f[k]:.5g}" for k in FIGURES) + f" | {cpu:.1f} |")
    print("\nrelative change against the next finer step [%] (order estimate from the last three)")
    for i in range(len(rows) - 1):
        a, b = rows[i][1], rows[i + 1][1]
        print(f"| h/{1 / rows[i][0]:g} vs h/{1 / rows[i + 1][0]:g} | " + " | ".join(
            f"{100 * (a[k] - b[k]) / abs(b[k]):.3g}" if b[k] else "-" for k in FIGURES) + " |")
    if len(rows) >= 3:
        a, b, c = (rows[i][1] for i in (-3, -2, -1))
        print("| order | " + " | ".join(
            f"{math.log2(abs(a[k] - b[k]) / abs(b[k] - c[k])):.2g}" if abs(b[k] - c[k]) > 0 and abs(a[k] - b[k]) > 0 else "-"
            for k in FIGURES) + " |")


if __name__ == "__main__":
    main()
