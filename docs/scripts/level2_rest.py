"""Level 2's rest: its strings at the sag of their own tension (docs/reduced_models.md, "Level
2", *Rest*; chainmodel.models.modal.ModalModel.initial_state).

    python docs/scripts/level2_rest.py table   # the 12B 8/16 drive of 32 links without
                                               # pretension: levels 1-3's static tension and
                                               # levels 2-3's linear mode at four driver
                                               # positions in a tooth (about 20 s)
    python docs/scripts/level2_rest.py sweep   # rests at four driver positions on 54 drives
                                               # (8 chains, 6-40 teeth, short chains, with and
                                               # without pretension) x 11 variants
                                               # (inclination, string modes, load, gravity):
                                               # how many settle, say they found no rest, or
                                               # are refused beyond the string model
                                               # (about 5 min)
"""

from __future__ import annotations

import math
import sys
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

from chainmodel.models import Inputs
from chainmodel.models.wrap_statics import tooth_positions, wrap_fit
from chainmodel.models.torsional_mode import _two_inertia_shape, tooth_modes
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene

DEG = math.pi / 180


def _scene(root: Path, label: str, *args, **kw) -> str:
    path = root / f"{label}.toml"
    path.write_text(scene_text(*args, **kw))
    return str(path)


def table(root: Path) -> None:
    path = _scene(root, "12b_8_16", 8, 16, 5.0, 0.0, chain="12B", links=32, static_tension=0.0)
    sc1 = load_scene(path, fidelity=1)
    fit = wrap_fit(sc1.drive, sc1.parameters)
    print("driver position (of 4)      " + "".join(f"{k:>10d}" for k in range(4)))
    print("level 3 static tension [N]  " + "".join(f"{t:10.1f}" for t in fit.tensions))
    for level in (1, 2):
        sc = load_scene(path, fidelity=level)
        m = sc.model()
        row = []
        for a in tooth_positions(sc.drive):
            u = Inputs(float(a), 0.0, 0.0)
            row.append(m.outputs(0.0, m.initial_state(u), u)["tight_span.tension"])
        print(f"level {level} static tension [N]  " + "".join(f"{t:10.1f}" for t in row))
    print("level 3 linear mode [Hz]    " + "".join(f"{f:10.1f}" for f in fit.modes))
    m = load_scene(path, fidelity=2).model()
    shape = _two_inertia_shape(m, fit.modal_stiffness, 2 * math.pi * fit.mode)
    own = [w / (2 * math.pi) for w in tooth_modes(m, shape)]
    print("level 2 own mode [Hz]       " + "".join(f"{f:10.1f}" for f in own))


def _drives():
    out = []
    for chain in ("08A", "10A", "12A", "16A", "08B", "10B", "12B", "16B"):
        for st in (None, 0.0):
            out.append((f"{chain}_17_34_st{st}", (17, 34, 100.0, 0.0),
                        dict(chain=chain, static_tension=st)))
    for z1, z2 in ((6, 6), (6, 18), (8, 8), (9, 10), (8, 16), (11, 45), (12, 12), (13, 40),
                   (19, 38), (25, 25), (40, 40), (40, 12)):
        for chain in ("08B", "16B"):
            for st in (None, 0.0):
                out.append((f"{chain}_{z1}_{z2}_st{st}", (z1, z2, 100.0, 0.0),
                            dict(chain=chain, static_tension=st)))
    for chain, z1, z2, links in (("12B", 8, 16, 32), ("12B", 8, 16, 30), ("16B", 6, 12, 24),
                                 ("08B", 6, 8, 20), ("10B", 7, 14, 28), ("12B", 6, 6, 16),
                                 ("16A", 6, 9, 18)):
        for st in (None, 0.0):
            out.append((f"{chain}_{z1}_{z2}_L{links}_st{st}", (z1, z2, 5.0, 0.0),
                        dict(chain=chain, links=links, static_tension=st)))
    return out


VARIANTS = ([("base", {}, 0.0)]
            + [(f"inclined {d} deg", {"drive_inclination": d * DEG}, 0.0)
               for d in (30, 60, 80, 88, 90)]
            + [(f"{n} modes", {"modal_modes": n}, 0.0) for n in (3, 6)]
            + [(f"load {f} x torque limit", {}, f) for f in (0.3, 0.95)]
            + [("no gravity", {"gravity": 0.0}, 0.0)])


def sweep(root: Path) -> None:
    counts = {"settled": 0, "no rest (said)": 0, "refused": 0, "drive refused": 0}
    worst, said, refused = 0.0, [], {}
    t0 = time.time()
    drives = _drives()
    for i, (label, args, kw) in enumerate(drives):
        path = _scene(root, label, *args, **kw)
        for name, over, share in VARIANTS:
            try:
                sc = load_scene(path, fidelity=2, **over)
                m = sc.model()
                torque = share * m.torque_limit()
            except ValueError:
                counts["drive refused"] += 1
                continue
            for k, a in enumerate(tooth_positions(sc.drive)):
                u = Inputs(float(a), 0.0, torque)
                try:
                    x = m.initial_state(u)
                except ValueError:
                    counts["refused"] += 1
                    refused[name] = refused.get(name, 0) + 1
                    continue
                if m.start_fallback:
                    counts["no rest (said)"] += 1
                    said.append(f"{label}, {name}, position {k}")
                    continue
                counts["settled"] += 1
                worst = max(worst, float(np.max(np.abs(m.rhs(0.0, x, u)))))
        print(f"  {i + 1}/{len(drives)} drives, {time.time() - t0:.0f} s", file=sys.stderr,
              flush=True)
    print(", ".join(f"{k}: {v}" for k, v in counts.items())
          + f"; largest acceleration where settled {worst:.2g}")
    print("refused (the rest beyond the string model's amplitude limit), by variant: "
          + ", ".join(f"{k} {v}" for k, v in refused.items()))
    for s in said:
        print("no rest:", s)


def main(argv) -> int:
    warnings.simplefilter("ignore")
    with tempfile.TemporaryDirectory() as tmp:
        {"table": table, "sweep": sweep}[argv[0] if argv else "table"](Path(tmp))
    return 0


if __name__ == "__main__":
    raise SystemExit(main(sys.argv[1:]))
