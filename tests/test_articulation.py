"""Level 3's teeth let the chain articulate (chainmodel.models.multibody.articulation_cut).

A roller entering or leaving a seat turns about the roller seated next to it: its centre runs
on the circle of radius p about the neighbouring seat's centre. A sprocket the chain can wrap
over has no tooth in that path. Written independently of the model in
tests/articulation_check.py:

* that path, from the seat to beyond the tooth tip;
* the straight flank of docs/multibody.md ("Contact (eqs 5-10) and the tooth flanks"): the
  seat circle (clearance dR = R_t - R_r for the roller centre) continued by flanks tangent to
  it at gamma = A/2 - 45 deg / z from the inward radial, up to a roller-centre height
  p (0.5625 - 0.4 / z) above the seat centre, and the penetration of a roller centre into it.

On small sprockets the straight flank stands in that path (by more than ISO 606's largest
seat clearance at 9 teeth), so every roller entering or leaving the sprocket was pressed into
it, even at rest. The model's tooth is cut by the path there: the kernel's penetration
(kernels.multibody_forces.geometry_pass) is nowhere positive along the path, never above the
straight flank's, equal to it away from the path, and a distance function (1-Lipschitz, its
gradient the contact normal, so the contact force stays conservative). Where the straight
flank clears the path (every sprocket of the presets) nothing changes. And the drive the
issue found "far outside its validity" at level 3, the trade study's coarse 6/9-tooth scene,
now balances its torque.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from articulation_check import (SEAT_CLEARANCE_MAX_08A, articulation_path, kernel_penetration,
                                straight_flank_penetration)
from articulation_check import model_of as _model
from chainmodel.analysis.trade_study import SCENES
from chainmodel.models.multibody import MultibodyModel
from chainmodel.scene import load_scene


def test_straight_flank_stands_in_the_articulation_path_on_small_sprockets():
    """The premise, computed here alone: on a 9-tooth 08A sprocket the straight flank reaches
    into the path by more than ISO 606's largest seat clearance; from 12 teeth it clears it."""
    model = _model("08A", 9)
    p, dR = model.drive.pitch, model.flank["clearance"]
    worst = {z: float(np.max(straight_flank_penetration(*articulation_path(z, p).T, z, p, dR)))
             for z in (9, 12, 17, 25)}
    assert worst[9] > SEAT_CLEARANCE_MAX_08A
    assert worst[12] <= 0.0 and worst[17] <= 0.0 and worst[25] <= 0.0


@pytest.mark.parametrize("chain_name", ["08A", "10B", "16B"])
@pytest.mark.parametrize("z", [6, 8, 9, 11, 12, 17])
def test_no_tooth_in_the_articulation_path(chain_name, z):
    """Along the path (both neighbours) the kernel's penetration is never positive; the cut is
    on exactly where the straight flank, computed here, would stand in the path."""
    model = _model(chain_name, z)
    p = model.drive.pitch
    dR = model.flank["clearance"]
    path = articulation_path(z, p)
    straight = straight_flank_penetration(*path.T, z, p, dR)
    for neighbour in (+1, -1):
        pen, _ = kernel_penetration(model, path, neighbour)
        assert np.max(pen) <= 1e-12
    assert model.flank["cut_driver"] == bool(np.max(straight) > 0.0)


@pytest.mark.parametrize("chain_name, z", [("08A", 9), ("16B", 6), ("10B", 11)])
def test_cut_only_lowers_the_penetration_and_stays_a_distance(chain_name, z):
    """On a grid around a seat: the kernel's penetration is never above the straight flank's,
    equal to it off the path's inner side below where the path meets the flank, 1-Lipschitz
    (a distance: no jump where the cut meets the flank), and
    its normal is its gradient (the contact force derives from the penalty potential)."""
    model = _model(chain_name, z)
    p = model.drive.pitch
    dR = model.flank["clearance"]
    tip = p * (0.5625 - 0.4 / z)
    h = 2e-3 * p
    sl, u = np.meshgrid(np.arange(-0.3 * p, tip - h, h), np.arange(0.0, 0.45 * p, h),
                        indexing="ij")
    pts = np.stack([sl.ravel(), u.ravel()], axis=1)
    pen, normal = kernel_penetration(model, pts)
    straight = straight_flank_penetration(pts[:, 0], pts[:, 1], z, p, dR)
    R = p / (2 * math.sin(math.pi / z))
    ta = 2 * math.pi / z
    a = np.array([-R * (1 - math.cos(ta)), R * math.sin(ta)])
    # off the path's inner side and below where the path first meets the straight flank by
    # more than a roller diameter (out of the reach of the tooth's rounded corner there)
    path = articulation_path(z, p)
    meets = path[straight_flank_penetration(*path.T, z, p, dR) > 0.0]
    below = pts[:, 0] < float(np.min(meets[:, 0])) - 2 * model.params["chain.roller_radius"]
    off_path = (np.hypot(*(pts - a).T) >= p) & below
    # the grid cells the nearest-seat search gives to this seat
    mine = np.abs(np.arctan2(pts[:, 1], pts[:, 0] + R)) < ta / 2 - 1e-9
    assert np.all(pen[mine] <= straight[mine] + 1e-12)
    assert np.allclose(pen[mine & off_path], straight[mine & off_path], rtol=0, atol=1e-12)
    assert np.any(pen[mine] < straight[mine] - 0.1 * dR)       # the cut does bite here
    grid = np.where(mine, pen, np.nan).reshape(sl.shape)
    for axis in (0, 1):
        step = np.abs(np.diff(grid, axis=axis))
        assert np.nanmax(step) <= h * (1 + 1e-6)
    # the normal is the gradient of the penetration where the roller touches (central
    # differences off the grid's kinks)
    touch = mine & (pen > 0.0) & (pen < 0.5 * p)
    rng = np.random.default_rng(7)
    idx = rng.choice(np.flatnonzero(touch), size=min(200, int(touch.sum())), replace=False)
    eps = 1e-4 * h
    grads = []
    for d in (np.array([eps, 0.0]), np.array([0.0, eps])):
        hi, _ = kernel_penetration(model, pts[idx] + d)
        lo, _ = kernel_penetration(model, pts[idx] - d)
        grads.append((hi - lo) / (2 * eps))
    grad = np.stack(grads, axis=1)
    smooth = np.abs(np.hypot(*grad.T) - 1.0) < 1e-3          # not on a kink of the distance
    assert smooth.sum() > 0.8 * idx.size
    assert np.allclose(grad[smooth], normal[idx][smooth], atol=1e-3)


@pytest.mark.parametrize("name", ["xu2010", "C1", "coarse", "examples/scenes/08b_fan_1500rpm.toml",
                                  "examples/scenes/16b_mixer.toml",
                                  "examples/scenes/12b_conveyor.toml"])
def test_cut_where_the_straight_flank_is_in_the_path(name):
    """On the presets and example scenes, the cut is on for a sprocket exactly where the
    straight flank, computed here, stands in the path: on none of the dynamic scenes (their
    results are the straight flank's), on both of the 6/9-tooth 'coarse' drive's."""
    from pathlib import Path
    root = Path(__file__).resolve().parent.parent
    sc = load_scene(str(root / name) if name.endswith(".toml") else name, fidelity=3)
    flank = MultibodyModel(sc.drive, sc.parameters).flank
    p = sc.drive.pitch
    dR = sc.parameters["contact.seat_radius"] - sc.parameters["chain.roller_radius"]
    for key, z in (("cut_driver", sc.drive.n_driver), ("cut_driven", sc.drive.n_driven)):
        in_path = float(np.max(straight_flank_penetration(*articulation_path(z, p).T, z, p,
                                                          dR))) > 0.0
        assert flank[key] == in_path, (name, key)
        assert in_path == (name == "coarse")


def test_coarse_6_9_drive_balances_its_torque_at_level_3():
    """The issue's case: the trade study's coarse 6/9-tooth scene (10B, 300 rpm, 5 N m) at
    level 3 gave 42 kN contact forces, a driven sprocket swinging between -60 and +95 rad/s
    and 14.9 N m mean input torque for a load that needs 3.3 N m. With teeth the chain can
    wrap over: no validity problem, no reversal, the mean driven speed the tooth ratio's, and
    the mean input torque the load's through the tooth ratio, plus damper losses below 10 %."""
    spec = next(s for s in SCENES if s.name.startswith("coarse 6/9"))
    sc = spec.scene(fidelity=3)
    r = chainmodel.simulate(sc)
    assert r.problems == [] and r.valid
    s = r.summary()
    m = r.time >= s["steady_from_s"]
    w1 = float(np.mean(r["driver.speed"][m]))
    w2 = r["driven.speed"][m]
    assert np.min(w2) > 0.0
    assert float(np.mean(w2)) == pytest.approx(w1 * 6 / 9, rel=0.01)
    load = sc.operating.load_torque + sc.parameters["driven.damping"] * float(np.mean(w2))
    need = load * 6 / 9
    torque = float(np.mean(r["input_shaft.torque"][m]))
    assert need <= torque <= 1.10 * need
    assert float(np.max(r["contact.max_force"][m])) < sc.parameters["chain.breaking_load"] / 10


def test_three_tooth_driver_keeps_the_tooth_ratio():
    """The issue's other case: a 3-tooth driver at level 3 'skipped teeth' (mean driven speed
    6.4 rad/s against 2.2 kinematic). On a taut chain over teeth it can wrap over it keeps the
    exact tooth ratio: at every whole driver tooth period the driven sprocket is within half a
    driven tooth, pi / 17, of 3/17 of the driver's turn. (Its 50 % polygonal speed swing still
    makes level 3 warn: driven-speed reversal, docs/stability.md.)"""
    r = chainmodel.simulate("xu2010", fidelity=3, drive_driver_teeth=3,
                            drive_centre_distance=0.0, duration=0.8)
    assert "teeth_skipped" not in {p.code for p in r.problems}
    phi1, phi2 = r["driver.angle"], r["driven.angle"]
    period = 2 * math.pi / 3
    turns = int((phi1.max() - phi1[0]) // period)
    assert turns >= 3
    for k in range(1, turns + 1):
        i = int(np.argmax(phi1 >= phi1[0] + k * period))
        assert abs(phi2[i] - phi2[0] - 3 / 17 * (phi1[i] - phi1[0])) < math.pi / 17
