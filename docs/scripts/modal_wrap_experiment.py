"""Experiment (not a model option): levels 1-2 with ``torsional.wrap_statics`` and the condensed
stiffness K_3 scaled by F, to put their driven-sprocket mode on level 3's linear one instead of
its static condensation (docs/reduced_models.md, "What the static wrap leaves out"). Patches
``wrap_statics._compliance`` for the run; prints the ring-down (docs/scripts/ringdown.py's
``ring``) and, on xu2010, the running span means at 30 and 60 rpm (0.3-0.6 s).

F from level 3's linearisation (tests/linearised.py): xu2010 598.2 Hz against the two-inertia
system's 559.8 Hz on K_3 gives F = 1.16 with the input shaft's coupling; C1 25.28 against
23.83 Hz gives F = 1.125 (rigid input shaft: (25.28 / 23.83)^2).

    python docs/scripts/modal_wrap_experiment.py     # about 15 s with warm kernels
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.models import wrap_statics as W

sys.path.insert(0, str(Path(__file__).resolve().parent))
from ringdown import ring  # noqa: E402

BANDS = {"xu2010": (360.0, 840.0), "C1": (15.0, 35.0)}


def run(name, factor, speeds=()):
    original = W._compliance
    W._CACHE.clear()
    W._compliance = lambda target, *rest: original(factor * target, *rest)
    try:
        rings = [ring(name, level, band=BANDS[name], torsional_wrap_statics=True)[0]
                 for level in (1, 2)]
        print(f"{name:7s} F = {factor:5.3f}  ring-down L1 {rings[0]:7.2f} Hz  L2 {rings[1]:7.2f} Hz",
              flush=True)
        for rpm in speeds:
            cells = []
            for level in (1, 2):
                r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, duration=0.6,
                                        output_interval=2e-4, torsional_wrap_statics=True)
                m = r.time >= 0.3
                cells.append(f"L{level} {r['tight_span.tension'][m].mean():7.1f} / "
                             f"{r['slack_span.tension'][m].mean():6.1f} N")
            print(f"{'':7s} {rpm:4.0f} rpm tight / slack  " + "  ".join(cells), flush=True)
    finally:
        W._compliance = original
        W._CACHE.clear()


def main():
    for factor in (1.0, 1.16):
        run("xu2010", factor, (30.0, 60.0))
    for factor in (1.0, 1.125):
        run("C1", factor)


if __name__ == "__main__":
    main()
