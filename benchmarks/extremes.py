"""The extremes that take too long for tests/test_extremes.py, and the figures docs/stability.md
quotes. Four tables (Markdown):

1. speed limits per preset and level (levels 0-2: models/limits.py; level 3: none enforced);
2. static span tension from chain.pretension: levels 0-2 (models/kinematic.py
   static_span_tension) against level 3 (MultibodyModel.static_tension, dynamic relaxation)
   over drives from 6 to 120 teeth, link stiffness x0.1 and x10, contact stiffness x0.1, x10;
3. centrifugal tension: mean span tensions of levels 1 and 3 against speed (xu2010, 43.2 N.m
   and a short-span 9/9 drive with 500 N static tension), with rho A v^2;
4. the matrix cases of the test at longer durations (levels 0-2), and the cases that stop.

    python benchmarks/extremes.py [--quick]          # --quick: tables 1 and 2 only
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.analysis.summary import steady_window
from chainmodel.models.limits import RPM
from chainmodel.scene import _static_tension_at, load_scene

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests"))
from test_extremes import MATRIX, BASE, check_plausible, drive_overrides  # noqa: E402


def table(head, rows):
    out = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    out += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return "\n".join(out)


def speed_limits():
    rows = []
    for name in ("xu2010", "coarse", "medium", "fine", "A1", "C1", "D3"):
        sc = load_scene(name)
        cells = [name]
        for level in (0, 1, 2):
            try:
                m = sc.with_overrides(fidelity=level).model()
                w, why = m.speed_limit()
                cells.append(f"{w / RPM:.0f} rpm")
            except ValueError as exc:
                cells.append(f"refused: {str(exc)[:40]}")
        f_t, f_ax = sc.with_overrides(fidelity=0).model()._frequencies
        cells += [f"{f_t:.0f}", f"{f_ax:.0f}"]
        rows.append(cells)
    return table(["preset", "level 0", "level 1", "level 2", "driven torsional f [Hz]",
                  "span axial f [Hz]"], rows)


def static_tensions():
    base = load_scene("xu2010")
    cases = [("xu2010", {}, p) for p in (0, 500, 2000, 5000, 20000)]
    cases += [("xu2010, link stiffness x0.1", dict(chain_link_stiffness=5.1e6), p)
              for p in (0, 2000)]
    cases += [("xu2010, link stiffness x10", dict(chain_link_stiffness=5.1e8), p)
              for p in (0, 2000)]
    cases += [("xu2010, contact stiffness x0.1", dict(contact_stiffness=8.46e5), 2000),
              ("xu2010, contact stiffness x10", dict(contact_stiffness=8.46e7), 2000)]
    for n1, n2, M in ((6, 9, 30), (9, 6, 30), (12, 120, 200), (120, 12, 200), (17, 25, 46),
                      (25, 25, 60), (8, 40, 90)):
        cases += [(f"{n1}/{n2}, {M} links (tight)", drive_overrides(n1, n2, links=M), p)
                  for p in (0, 2000)]
    rows = []
    for label, over, pre in cases:
        sc = base.with_overrides(**over)
        p, d = dict(sc.parameters), sc.drive
        t = time.perf_counter()
        t3 = _static_tension_at(3, d, p, pre)
        cost = time.perf_counter() - t
        t02 = _static_tension_at(1, d, p, pre)
        geo = _static_tension_at(1, d, p, 0.0)
        dev = f"{100 * (t02 / t3 - 1):+.1f} %" if t3 > 1 else "-"
        rows.append([label, f"{pre:g}", f"{geo:.0f}", f"{t02:.0f}", f"{t3:.0f}", dev,
                     f"{cost:.1f}"])
    return table(["drive", "pretension [N]", "levels 0-2 at pretension 0 [N]",
                  "levels 0-2 [N]", "level 3 [N]", "levels 0-2 vs 3", "level 3 cost [s]"],
                 rows)


def centrifugal():
    rows = []
    cases = [("xu2010", {}, (120, 1000, 2000, 3000, 6000, 10000))]
    cases.append(("9/9, 20 links, static 1000 N", dict(drive_overrides(9, 9, links=20),
                                                        static_tension=1000.0, load_torque=10.0),
                  (1000, 3000, 6000, 10000)))
    for label, over, speeds in cases:
        for rpm in speeds:
            sc = load_scene("xu2010", input_speed_rpm=rpm, **over)
            c = float(sc.parameters["chain.link_mass"] / sc.drive.pitch
                      * (sc.drive.n_driver * sc.drive.pitch * rpm * RPM / (2 * math.pi)) ** 2)
            cells = [label, rpm, f"{c:.0f}"]
            for level in (1, 3):
                dur = 0.2 if rpm < 2000 else 0.08
                try:
                    r = chainmodel.simulate(sc.with_overrides(fidelity=level), duration=dur,
                                            output_interval=1e-5, ramp_time=0.02)
                    m = steady_window(r.time, 0.02, dur)
                    cells.append(f"{np.mean(r['tight_span.tension'][m]):.0f} / "
                                 f"{np.mean(r['slack_span.tension'][m]):.0f}")
                except (ValueError, chainmodel.SimulationDiverged) as exc:
                    cells.append("refused" if isinstance(exc, ValueError) else "diverged")
            rows.append(cells)
    return table(["drive", "rpm", "rho A v^2 [N]", "level 1 tight / slack [N]",
                  "level 3 tight / slack [N]"], rows)


def matrix_long():
    rows = []
    for case_id, levels, over, refusal, tol in MATRIX:
        for level in levels:
            kw = dict(BASE, **over)
            if refusal is None:
                kw["duration"] = 2 * kw["duration"]
            t = time.perf_counter()
            try:
                r = chainmodel.simulate("xu2010", fidelity=level, **kw)
                check_plausible(r, tol)
                s = r.summary()
                out = (f"runs: tight {s['mean_tight_tension_n']:.0f} N, slack "
                       f"{s['mean_slack_tension_n']:.0f} N, tooth ratio error "
                       f"{abs(s['tooth_ratio'] / s['exact_tooth_ratio'] - 1):.1e}"
                       if math.isfinite(s["tooth_ratio"]) else "runs (no whole tooth period)")
            except ValueError as exc:
                out = "refused: " + str(exc)[:110]
            except chainmodel.SimulationDiverged as exc:
                out = "diverged: " + str(exc)[:110]
            except AssertionError as exc:
                out = "IMPLAUSIBLE: " + str(exc)[:110]
            rows.append([case_id, level, out, f"{time.perf_counter() - t:.2f}"])
    # the case level 2 cannot take: a 6-tooth drive's polygon at 10000 rpm
    try:
        chainmodel.simulate("xu2010", fidelity=2, **drive_overrides(6, 6, links=11),
                            static_tension=500, input_speed_rpm=10000, load_torque=2.0,
                            duration=0.03, output_interval=2e-5, ramp_time=0.01)
        out = "runs"
    except chainmodel.SimulationDiverged as exc:
        out = "diverged: " + str(exc)[:200]
    rows.append(["6/6, 11 links, 10000 rpm", 2, out, ""])
    return table(["case (x2 duration)", "level", "outcome", "wall [s]"], rows)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="tables 1 and 2 only")
    args = ap.parse_args(argv)
    print(f"load average {' '.join(f'{v:.2f}' for v in os.getloadavg())}\n")
    print("## Speed limits\n\n" + speed_limits() + "\n")
    print("## Static tension from chain.pretension\n\n" + static_tensions() + "\n")
    if args.quick:
        return 0
    print("## Centrifugal tension\n\n" + centrifugal() + "\n")
    print("## Matrix, doubled durations\n\n" + matrix_long() + "\n")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
