"""Levels 0-2 warn where the load leaves the slack span hanging on its weight
(chainmodel.validity, "slack span hanging"; an independent audit of the twenty-fifth session:
level 2 read a 16B drive's slack span 11-37 % low at 45-88 deg with no word).

The measure is computed here: the slack span's weight w L (w = chain.link_mass / p x g, L the
tangent between the pitch circles, sqrt(a^2 - (R2 - R1)^2) with R = p / (2 sin(pi / z))) over
the run's mean slack tension from the second driver tooth period on, where the load holds that
mean below 0.8 of the static tension; each point at least 15 % away from the line."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.new_scene import scene_text
from chainmodel.scene import load_scene
from chainmodel.validity import SLACK_HANGING_SHARE, SLACK_LOADED_SHARE

CODE = "slack_span_hanging"


@pytest.fixture(scope="module")
def drive16b(tmp_path_factory):
    path = tmp_path_factory.mktemp("hang") / "16b.toml"
    path.write_text(scene_text(21, 21, 5.0, 0.0, chain="16B", static_tension=0.0))
    return str(path)


@pytest.mark.parametrize("load,degrees", [(0.0, 45.0), (30.0, 0.0), (100.0, 70.0)])
@pytest.mark.parametrize("level", [0, 1, 2])
def test_a_slack_span_hanging_on_its_weight_under_load_is_warned(drive16b, level, load,
                                                                 degrees):
    tilt = math.radians(degrees)
    r = chainmodel.simulate(drive16b, fidelity=level, duration=3.0, load_torque=load,
                            drive_inclination=tilt)
    sc = load_scene(drive16b, fidelity=level, drive_inclination=tilt)
    d, p = sc.drive, sc.parameters
    r1, r2 = (d.pitch / (2 * math.sin(math.pi / z)) for z in (d.n_driver, d.n_driven))
    length = math.sqrt(d.centre_distance ** 2 - (r2 - r1) ** 2)
    weight = p["chain.link_mass"] / d.pitch * 9.81 * length
    turned = np.abs(r["driver.angle"] - r["driver.angle"][0]) >= 2 * 2 * math.pi / d.n_driver
    slack = float(np.mean(r["slack_span.tension"][turned]))
    loaded = slack < SLACK_LOADED_SHARE * r.static_tension
    ratio = weight / slack
    if loaded:
        assert abs(ratio / SLACK_HANGING_SHARE - 1.0) > 0.15, ratio
    warned = CODE in {q.code for q in r.problems}
    assert warned == (loaded and ratio >= SLACK_HANGING_SHARE), (ratio, loaded, r.warnings)
    assert warned == (load == 100.0)     # the cases: unloaded, loaded but taut, hanging


def test_level3_does_not_warn_of_it(drive16b):
    r = chainmodel.simulate(drive16b, fidelity=3, duration=1.0, load_torque=100.0,
                            drive_inclination=math.radians(70.0))
    assert CODE not in {q.code for q in r.problems}
