"""Power level 3 dissipates inside the chain, against the joint friction of the same drive.

Level 3's chain loses power only in its dampers (links, roller-seat contacts and the joint
dampers ``chain.joint_damping``, a viscous stand-in for pin-bushing friction sized on xu2010's
slack side at 120 rpm: docs/multibody.md "Convergence and default damping"). Loss = mean power
into the driver from the input shaft minus the mean power into the load and the driven damping,
minus the sprockets' kinetic-energy change, over the second half of a 1 s run.

The joint friction it stands in for, estimated for the same drive at the run's mean span
tensions: every link articulates through 2 pi / z entering and leaving each sprocket, under the
tension of the span it joins, against Coulomb friction mu T r_pin (mu = 0.1, lubricated steel;
r_pin = d2 / 2 of ISO 606 for the scene's chain), at z1 w1 / 2 pi links per second:

    P_f = mu r_pin w1 z1 (T_tight + T_slack) (1 / z1 + 1 / z2)

    python docs/scripts/chain_losses.py                  # the presets and example scenes
    python docs/scripts/chain_losses.py scene.toml ...   # your own
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.chains import DIMENSIONS

MU = 0.1
ROOT = Path(__file__).resolve().parents[2]
CASES = (("xu2010", 30.0), ("xu2010", 120.0), ("C1", 100.0),
         (str(ROOT / "examples/scenes/08b_fan_1500rpm.toml"), None),
         (str(ROOT / "examples/scenes/12b_conveyor.toml"), None),
         (str(ROOT / "examples/scenes/16b_mixer.toml"), None))


def losses(scene, rpm=None):
    kw = {} if rpm is None else {"input_speed_rpm": rpm}
    r = chainmodel.simulate(scene, fidelity=3, duration=1.0, **kw)
    sc, p, t = r.scene, r.scene.parameters, r.time
    d = sc.drive
    m = t >= 0.5 * t[-1]
    w1, w2, ts = r["driver.speed"], r["driven.speed"], r["input_shaft.torque"]
    load = sc.operating.load_torque
    p_in = np.trapezoid((ts * w1)[m], t[m])
    p_out = np.trapezoid(((load + p["driven.damping"] * w2) * w2)[m], t[m])
    i0 = int(np.argmax(m))

    def ke(i):
        return 0.5 * (p["driver.inertia"] * w1[i] ** 2 + p["driven.inertia"] * w2[i] ** 2)

    loss = (p_in - p_out - (ke(-1) - ke(i0))) / p_in
    tight = float(np.mean(r["tight_span.tension"][m]))
    slack = float(np.mean(r["slack_span.tension"][m]))
    r_pin = 0.5 * DIMENSIONS[sc.chain].pin_diameter
    w = float(np.mean(w1[m]))
    friction = (MU * r_pin * w * d.n_driver * (tight + slack) * (1 / d.n_driver + 1 / d.n_driven)
                / (p_in / (t[m][-1] - t[m][0])))
    return sc, w, tight, slack, loss, friction


def main(argv):
    cases = [(a, None) for a in argv[1:]] or CASES
    print(f"{'scene':22s} {'chain':5s} {'rpm':>6s} {'tight/slack [N]':>16s} "
          f"{'level 3 loss':>12s} {'joint friction':>14s} {'ratio':>6s}")
    for scene, rpm in cases:
        sc, w, tight, slack, loss, friction = losses(scene, rpm)
        print(f"{sc.name[:22]:22s} {sc.chain:5s} {w * 30 / np.pi:6.0f} "
              f"{tight:7.0f} / {slack:6.0f} {100 * loss:11.2f}% {100 * friction:13.2f}% "
              f"{loss / friction:6.2f}", flush=True)


if __name__ == "__main__":
    main(sys.argv)
