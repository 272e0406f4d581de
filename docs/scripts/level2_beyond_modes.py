"""Level 2 against level 3 on the running spans, with the meshing frequency over the slack
span's first string mode (docs/reduced_models.md, "Level 2 beyond its modes"; the line of
chainmodel.validity's ``span_modes_beyond`` warning).

Table 1: level 2 at its default ``modal.modes = 1`` against level 3, mean tight / slack span
over 0.5-1 s of a 1 s run, and f_m / f_1 with f_1 the moving string's first mode
(models.limits.drive_string_frequency) at level 2's own mean slack tension, on the presets,
the example scenes and two `new-scene` drives (steel-disc sprockets). Table 2: ``modal.modes``
1-12 on four of them.

Table 3 (``--judged``, alone): the tension the line is judged at since the twenty-ninth
session, on an audit's 08A 9/10 drive of 25 links without pretension, 3 N m
(level2_locked_spans.SMALL): f_m / f_1 at level 2's own mean slack tension, at level 3's and
at the still tension (level 0's quasi-static split of the mean load plus the centrifugal
tension, KinematicModel.quasi_static_spans), means over 0.6-1 s of 1 s runs.

    python docs/scripts/level2_beyond_modes.py            # about 60 s with warm kernels
    python docs/scripts/level2_beyond_modes.py --modes    # table 2 too (about 30 s more)
    python docs/scripts/level2_beyond_modes.py --judged   # table 3 alone (about 10 s)
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.models.limits import drive_string_frequency
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene
from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO

ROOT = Path(__file__).resolve().parents[2]
MIXER = str(ROOT / "examples" / "scenes" / "16b_mixer.toml")
FAN = str(ROOT / "examples" / "scenes" / "08b_fan_1500rpm.toml")
CONVEYOR = str(ROOT / "examples" / "scenes" / "12b_conveyor.toml")


def means(scene, level, rpm, **kw):
    r = chainmodel.simulate(scene, fidelity=level, duration=1.0, input_speed_rpm=rpm, **kw)
    m = r.time >= 0.5
    return r, float(np.mean(r["tight_span.tension"][m])), float(np.mean(r["slack_span.tension"][m]))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--modes", action="store_true", help="also sweep modal.modes (table 2)")
    ap.add_argument("--judged", action="store_true",
                    help="only the tension the line is judged at, on the 08A audit drive")
    args = ap.parse_args(argv)
    if args.judged:
        return judged()
    folder = Path(tempfile.mkdtemp())
    u10b, u12b = folder / "10b_11_33.toml", folder / "12b_19_57.toml"
    u10b.write_text(scene_text(11, 33, 600.0, 20.0, chain="10B", name="10B 11/33"))
    u12b.write_text(scene_text(19, 57, 300.0, 100.0, chain="12B", name="12B 19/57"))
    cases = ([("xu2010", r) for r in (15, 30, 45, 60, 75, 90, 120, 600, 2000)]
             + [("C1", r) for r in (30, 45, 60, 100, 400)]
             + [(MIXER, r) for r in (100, 200, 500)] + [(FAN, 600), (CONVEYOR, 300),
                                                         (str(u10b), 300), (str(u10b), 600),
                                                         (str(u12b), 300)])
    print(f"line: f_m / f_1 >= {LEVEL2_SPAN_MODE_RATIO:g}\n")
    print("| scene | rpm | f_m / f_1 | level 3 [N] | level 2 tight / slack | warned |")
    print("|---|---|---|---|---|---|")
    for scene, rpm in cases:
        r3, t3, s3 = means(scene, 3, rpm)
        r2, t2, s2 = means(scene, 2, rpm)
        sc = load_scene(scene, fidelity=2)
        w = float(np.mean(np.abs(r2["driver.speed"][r2.time >= 0.5])))
        f_m = sc.drive.n_driver * w / (2 * math.pi)
        f_1 = drive_string_frequency(sc.drive, sc.parameters, s2, w)
        warned = any(p.code == "span_modes_beyond" for p in r2.problems)
        print(f"| {sc.name} | {rpm} | {f_m / f_1:.2f} | {t3:.0f} / {s3:.0f} | "
              f"{100 * (t2 / t3 - 1):+.1f} / {100 * (s2 / s3 - 1):+.1f} % | "
              f"{'yes' if warned else '-'} |", flush=True)
    if not args.modes:
        return
    print("\n| scene | rpm | " + " | ".join(f"{n} mode{'s' if n > 1 else ''}"
                                             for n in (1, 2, 3, 6, 9, 12)) + " |")
    print("|---|---|" + "---|" * 6)
    for scene, rpm in (("xu2010", 120), ("xu2010", 600), (str(u10b), 600), (FAN, 600)):
        _, t3, s3 = means(scene, 3, rpm)
        cells = []
        for n in (1, 2, 3, 6, 9, 12):
            _, t2, s2 = means(scene, 2, rpm, modal_modes=n)
            cells.append(f"{100 * (t2 / t3 - 1):+.1f} / {100 * (s2 / s3 - 1):+.1f} %")
        print(f"| {load_scene(scene).name} | {rpm} | " + " | ".join(cells) + " |", flush=True)


def judged():
    """Table 3 (module docstring)."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from level2_locked_spans import SMALL
    from chainmodel.models.kinematic import KinematicModel, centrifugal_tension
    print("| rpm | level 2 tight / slack | level 3 | level 2 off | f_m / f_1 at level 2's own "
          "/ level 3's / the still tension | warned |")
    print("|---|---|---|---|---|---|")
    for rpm in (300, 450, 600):
        runs = {k: chainmodel.simulate("xu2010", fidelity=k, duration=1.0,
                                       **dict(SMALL, input_speed_rpm=rpm)) for k in (2, 3)}
        m = runs[2].time >= 0.6
        tight = {k: float(np.mean(r["tight_span.tension"][m])) for k, r in runs.items()}
        slack = {k: float(np.mean(r["slack_span.tension"][m])) for k, r in runs.items()}
        sc = runs[2].scene
        d, p = sc.drive, sc.parameters
        w = float(np.mean(np.abs(runs[2]["driver.speed"][m])))
        load = abs(sc.operating.load_torque + p["driven.damping"] * w * d.tooth_ratio)
        still = (KinematicModel(d, p).quasi_static_spans(load)[1]
                 + float(centrifugal_tension(d, p, w)))
        f_m = d.n_driver * w / (2 * math.pi)
        ratios = " / ".join(f"{f_m / drive_string_frequency(d, p, t, w):.2f}"
                            for t in (slack[2], slack[3], still))
        codes = [q.code for q in runs[2].problems if q.code.startswith("span_")]
        print(f"| {rpm} | {tight[2]:.1f} / {slack[2]:.1f} N | {tight[3]:.1f} / {slack[3]:.1f} N "
              f"| {100 * (tight[2] / tight[3] - 1):+.0f} / {100 * (slack[2] / slack[3] - 1):+.0f} % "
              f"| {ratios} | {', '.join(codes) or '-'} |", flush=True)


if __name__ == "__main__":
    main()
