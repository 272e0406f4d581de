"""Level 3 on small sprockets, with the straight flank and with the tooth cut by the
articulation path (chainmodel.models.multibody.articulation_cut; docs/multibody.md, "Teeth the
chain can wrap over"), against level 1.

    python docs/scripts/small_sprockets.py        # about 40 s with compiled kernels

Per drive and speed: the steady-window means of the tight and slack spans, the driven speed's
range, the mean input torque against the load's need through the tooth ratio, and level 3's
validity codes. "straight" runs level 3 with the cut switched off here (the model before the
cut); the drives are 08A 8/24, 9/27 and 11/33 teeth built as `chainmodel new-scene` builds them
(400 N static tension, 5 N m) and the trade study's coarse 6/9-tooth scene.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import chainmodel
import chainmodel.models.multibody as MB
from chainmodel.analysis.trade_study import SCENES
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene

CUT = MB.articulation_cut


def straight(*args):
    return (False, 0.0, 0.0, 0.0, 0.0)


def drives(tmp: Path):
    for z1, rpms in ((9, (5, 30, 100)), (8, (100,)), (11, (100,))):
        path = tmp / f"08a_{z1}_{3 * z1}.toml"
        path.write_text(scene_text(z1, 3 * z1, 100, 5.0, chain="08A", name=path.stem,
                                   static_tension=400.0))
        for rpm in rpms:
            yield f"08A {z1}/{3 * z1}", rpm, load_scene(str(path), input_speed_rpm=rpm,
                                                        duration=1.0)
    spec = next(s for s in SCENES if s.name.startswith("coarse 6/9"))
    yield "10B 6/9 (trade study)", 300, spec.scene()


def row(sc, level):
    r = chainmodel.simulate(sc.with_overrides(fidelity=level))
    s = r.summary()
    m = r.time >= s["steady_from_s"]
    w2 = r["driven.speed"][m]
    need = (sc.operating.load_torque + sc.parameters["driven.damping"] * float(np.mean(w2))) \
        * sc.drive.n_driver / sc.drive.n_driven
    return (f"{np.mean(r['tight_span.tension'][m]):7.1f} / {np.mean(r['slack_span.tension'][m]):6.1f}"
            f" | {w2.min():7.2f} .. {w2.max():6.2f} | {np.mean(r['input_shaft.torque'][m]):6.2f}"
            f" / {need:5.2f} | {', '.join(p.code for p in r.problems) or '-'}")


def main() -> None:
    import tempfile
    print("| drive | rpm | model | tight / slack [N] | driven speed [rad/s] | input torque / "
          "need [N m] | validity |")
    print("|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for name, rpm, sc in drives(Path(tmp)):
            for label, level, cut in (("level 3, straight flank", 3, straight),
                                      ("level 3", 3, CUT), ("level 1", 1, CUT)):
                MB.articulation_cut = cut
                MB._STATIC_CACHE.clear()
                print(f"| {name} | {rpm} | {label} | {row(sc, level)} |", flush=True)
    MB.articulation_cut = CUT


if __name__ == "__main__":
    sys.exit(main())
