"""Level 3's driven-sprocket mode over a driver tooth, against the one mode levels 1-2 carry
(docs/reduced_models.md, "Level 3's mode over a tooth"; the warning ``torsional_mode_moves``,
chainmodel.models.wrap_statics.mode_spread).

    python docs/scripts/mode_over_tooth.py spread   # level 3's mode at wrap_fit's four driver
                                                    # positions, the trade study's scenes and
                                                    # mode_picker_fits.py's 190 cases, sorted
                                                    # by the farthest position's distance from
                                                    # their mean (about 2 min)
    python docs/scripts/mode_over_tooth.py ring     # ring-down after a sudden start, levels 1
                                                    # and 2 against level 3, on drives either
                                                    # side of the warning (about 1 min)
"""

from __future__ import annotations

import math
import sys
import warnings
from pathlib import Path

import numpy as np

from chainmodel.analysis.trade_study import SCENES, band_overrides
from chainmodel.models.wrap_statics import MODE_SPREAD, wrap_fit
from chainmodel.scene import load_scene

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from mode_picker_fits import VARIANTS, cases  # noqa: E402
from ringdown_check import ring_run, spectrum  # noqa: E402


def _coarse():
    return next(s for s in SCENES if s.name.startswith("coarse"))


def distance(fit) -> float:
    """The farthest position's mode from the mean the levels carry (mode_spread's measure)."""
    return max(fit.mode / min(fit.modes) - 1.0, 1.0 - fit.mode / max(fit.modes))


def spread():
    rows = []
    scenes = [(f"study {s.name}", s.scene(fidelity=1)) for s in SCENES]
    for name, kw in cases():
        label = f"{Path(name).stem} {'no pretension' if kw else 'as written'}"
        try:
            base = load_scene(name, fidelity=1, **kw)
        except ValueError:
            continue
        for v in VARIANTS:
            tag = "" if v is None else f" {v[0]} x{v[1]:g}"
            try:
                sc = base if v is None else load_scene(name, fidelity=1, **kw,
                                                       **band_overrides(base, *v))
            except ValueError:
                continue
            scenes.append((label + tag, sc))
    for label, sc in scenes:
        try:
            fit = wrap_fit(sc.drive, sc.parameters)
        except ValueError:
            continue
        if len(fit.modes) > 1:
            rows.append((distance(fit), label, fit))
    rows.sort(key=lambda r: r[0])
    print(f"level 3's mode at {len(rows[0][2].modes)} driver positions [Hz], the mean levels 1-2 "
          f"carry, and the farthest position's distance from it (warned above "
          f"{100 * MODE_SPREAD:.0f} %)")
    for off, label, fit in rows:
        modes = " / ".join(f"{m:.4g}" for m in fit.modes)
        print(f"{label:48s} {modes:>32s}  mean {fit.mode:8.4g}  {100 * off:6.1f} %"
              + ("  warned" if off > MODE_SPREAD else ""), flush=True)


def _peak(result, band):
    f, s = spectrum(result)
    s[(f < band[0]) | (f > band[1])] = 0.0
    return float(f[np.argmax(s)])


def ring():
    coarse = _coarse()
    start = {k: v for k, v in coarse.overrides.items()
             if k not in ("load_torque", "input_speed_rpm", "duration")}
    a2 = load_scene("A2")
    drives = [("study coarse 6/9", "xu2010", 5.0, start, None)]
    drives += [(n, n, 1.0, {}, None) for n in ("A1", "A2", "A3", "B2", "coarse", "C1", "D1")]
    drives += [(f"A2 {w} x2", "A2", 1.0, {}, band_overrides(a2, w, 2.0))
               for w in ("seat_clearance", "contact.stiffness")]
    print("strongest peak of the driven speed in 0.3-3 x the fit's mode after a sudden start "
          "(0.5 s, no load) [Hz]")
    print(f"{'drive':28s} {'rpm':>4s} {'farthest':>8s} {'level 3':>8s} {'level 1':>17s} "
          f"{'level 2':>17s}")
    for label, name, rpm, kw, over in drives:
        sc = load_scene(name, fidelity=1, **kw, **(over or {}))
        fit = wrap_fit(sc.drive, sc.parameters)
        band = (0.3 * fit.mode, 3.0 * fit.mode)
        run = dict(kw, parameters=over) if over else kw
        f3 = _peak(ring_run(name, 3, rpm, **run), band)
        cells = []
        for level in (1, 2):
            f = _peak(ring_run(name, level, rpm, **run), band)
            cells.append(f"{f:8.2f} ({100 * (f / f3 - 1):+6.1f}%)")
        print(f"{label:28s} {rpm:4g} {100 * distance(fit):7.1f}% {f3:8.2f} {cells[0]:>17s} "
              f"{cells[1]:>17s}", flush=True)


if __name__ == "__main__":
    warnings.simplefilter("ignore")
    what = sys.argv[1] if len(sys.argv) > 1 else "ring"
    {"spread": spread, "ring": ring}[what]()
