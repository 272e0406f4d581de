"""Power level 3 dissipates inside the chain, against the joint friction of the same drive: the
figures of the validity check ``damper_losses`` (chainmodel/loss_balance.py, whose docstring
has the formulas) for whole runs of 1 s or three driver revolutions if longer, printed for each scene whether the check fires or not.

Level 3's chain loses power only in its dampers (links, roller-seat contacts and the joint
dampers ``chain.joint_damping``, a viscous stand-in for pin-bushing friction sized on xu2010's
slack side at 120 rpm: docs/multibody.md "Convergence and default damping"); the friction it
stands in for is mu r_pin z1 (1/z1 + 1/z2) w1 (T_tight + T_slack), mu = 0.1, r_pin = d2 / 2 of
the scene's ISO 606 chain.

    python docs/scripts/chain_losses.py                  # the presets and example scenes
    python docs/scripts/chain_losses.py scene.toml ...   # your own
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.loss_balance import balance_duration, run_shares

ROOT = Path(__file__).resolve().parents[2]
CASES = (("xu2010", 30.0), ("xu2010", 120.0), ("C1", 100.0),
         (str(ROOT / "examples/scenes/08b_fan_1500rpm.toml"), None),
         (str(ROOT / "examples/scenes/12b_conveyor.toml"), None),
         (str(ROOT / "examples/scenes/16b_mixer.toml"), None))


def losses(scene, rpm=None):
    """(scene, mean driver speed [rad/s], loss, friction as shares of the input work)."""
    kw = {} if rpm is None else {"input_speed_rpm": rpm}
    sc = chainmodel.load_scene(scene, fidelity=3, **kw)
    r = chainmodel.simulate(sc, duration=balance_duration(sc, 1.0))
    loss, friction = run_shares(r)
    return sc, float(np.mean(r["driver.speed"][r.time >= 0.5 * r.time[-1]])), loss, friction


def main(argv):
    cases = [(a, None) for a in argv[1:]] or CASES
    print(f"{'scene':22s} {'chain':5s} {'rpm':>6s} {'level 3 loss':>12s} "
          f"{'joint friction':>14s} {'ratio':>6s}")
    for scene, rpm in cases:
        sc, w, loss, friction = losses(scene, rpm)
        print(f"{sc.name[:22]:22s} {sc.chain:5s} {w * 30 / np.pi:6.0f} {100 * loss:11.2f}% "
              f"{100 * friction:13.2f}% {loss / friction:6.2f}", flush=True)


if __name__ == "__main__":
    main(sys.argv)
