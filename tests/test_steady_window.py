"""The summary's steady window is called not steady where its means break the driven
sprocket's torque balance (chainmodel.analysis.summary.unsteady_window; an independent audit of
the twenty-fifth session: a 12B drive with a 2 kg.m2 machine on the driven shaft read -19 to
-31 % off the load in a 1 s run, with no word at levels 2-3).

The balance is computed here: in a steady state mean(tight - slack) = |load + c2 w2| / r with
r = z2 p / (2 pi), the driven sprocket's mean lever arm over a tooth period (the pitch radius
p / (2 sin(pi / z2)) times sin(pi / z2) / (pi / z2))."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.new_scene import scene_text

TEXT = "is not steady"


def _balance_miss(r) -> float:
    """(mean(tight - slack) - need) / need over the summary's window, computed here."""
    sc = r.scene
    m = r.time >= r.summary()["steady_from_s"]
    w2 = float(np.mean(r["driven.speed"][m]))
    arm = sc.drive.n_driven * sc.drive.pitch / (2 * math.pi)
    need = abs(sc.operating.load_torque + sc.parameters["driven.damping"] * w2) / arm
    got = float(np.mean(r["tight_span.tension"][m] - r["slack_span.tension"][m]))
    return got / need - 1.0


@pytest.fixture(scope="module")
def machine(tmp_path_factory):
    path = tmp_path_factory.mktemp("steady") / "machine.toml"
    path.write_text(scene_text(17, 34, 200.0, 60.0, chain="12B", static_tension=3000.0,
                               driven_inertia=2.0))
    return str(path)


@pytest.mark.parametrize("level,duration", [(1, 1.0), (2, 1.0), (3, 1.0), (1, 4.0),
                                            (2, 4.0)])
def test_a_window_that_breaks_the_torque_balance_is_called_not_steady(machine, level,
                                                                      duration):
    """A 2 kg.m2 driven machine still ringing from the start after 1 s: warned where the
    balance computed here misses by more than 10 %, and not after 4 s, where it holds (each
    point at least 3 points of a percent away from the line)."""
    r = chainmodel.simulate(machine, fidelity=level, duration=duration)
    miss = _balance_miss(r)
    assert abs(abs(miss) - 0.10) > 0.03, miss
    warned = [w for w in r.warnings if TEXT in w]
    assert bool(warned) == (abs(miss) > 0.10), (miss, r.warnings)
    if warned:
        assert "driven.inertia = 2 kg.m2" in warned[0] and "run longer" in warned[0]
    if duration == 1.0:
        assert warned


@pytest.mark.parametrize("name,rpm", [("xu2010", 120.0), ("C1", 100.0)])
def test_steady_presets_hold_the_balance_and_are_not_warned(name, rpm):
    """At C1's torsional resonance and on xu2010 the balance holds within half the line at
    levels 1-2 in 1 s runs (C1 level 2: -2.9 %; -1.3 % over longer windows, the issue's
    torque-balance figures), so nothing is said."""
    for level in (1, 2):
        r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, duration=1.0)
        assert abs(_balance_miss(r)) < 0.05
        assert not any(TEXT in w for w in r.warnings)
