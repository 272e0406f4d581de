"""Level 3 (multibody) at the extremes of issue 10's stress matrix: speed 0 to 10000 rpm and
reversed, load steps and overload, no damping, stiffness x0.01-x100, short and long chains,
solver choice. Each case ends finite with the exact tooth ratio in steady state and tensions
>= 0, or reports what the chain does (slack links, plates bearing), or is refused with a message
naming the parameter. The full matrix with longer runs and the small-sprocket drives is
benchmarks/extremes_multibody.py (table in docs/multibody.md, "Stability at the extremes").

Reference numbers: the exact tooth ratio 25/17 (seed 003 section 7), the force balance
T_tight - T_slack = M / R_o, the centrifugal tension rho v^2 of a chain running at speed v
(every span of a chain moving at v carries it; ISO 10823 uses it for drive design), the link
law's potential against its force by finite differences.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.analysis.summary import tooth_ratio
from chainmodel.integrate import Verlet
from chainmodel.models import SimulationDiverged
from chainmodel.kernels import multibody_forces as K
from chainmodel.models.base import Inputs
from chainmodel.scene import load_scene

RATIO = 25 / 17


def _run(duration, **overrides):
    r = chainmodel.simulate("xu2010", fidelity=3, duration=duration, output_interval=2e-4,
                            **overrides)
    for name in r.names:
        assert np.all(np.isfinite(r[name])), name
    return r


def _second_half(r):
    return r.time >= r.time[-1] / 2


@pytest.mark.parametrize("rpm, duration", [(-120.0, 0.3), (1000.0, 0.2), (3000.0, 0.15),
                                           (10000.0, 0.1)])
def test_speed_range_exact_ratio_and_tension(rpm, duration):
    """Reversed and up to 10000 rpm: the driven sprocket follows 25/17 exactly over the second
    half (a skipped tooth would change the mean ratio by percent), no span and no link goes
    slack, none is compressed."""
    r = _run(duration, input_speed_rpm=rpm)
    m = _second_half(r)
    assert tooth_ratio(r["driver.angle"][m], r["driven.angle"][m], 25) == pytest.approx(
        RATIO, rel=2e-4)
    assert r["tight_span.tension"][m].min() > 0 and r["slack_span.tension"][m].min() > 0
    assert r["chain.min_link_tension"][m].min() > 0


def test_centrifugal_tension_at_10000_rpm():
    """At 10000 rpm the chain runs at v = z1 p n = 66 m/s: every link carries rho v^2 = 4.5 kN
    (rho = m / p) on top of the static and load tensions, which level 3's inertial rollers
    give without being told. The slack span's mean lies between rho v^2 and rho v^2 plus the
    static tension (528 N, with 10 % for the polygon's speed variation)."""
    r = _run(0.1, input_speed_rpm=10000.0)
    m = _second_half(r)
    p = r.scene.parameters
    v = 25 * r.scene.drive.pitch * 10000 / 60
    centrifugal = p["chain.link_mass"] / r.scene.drive.pitch * v * v
    slack = r["slack_span.tension"][m].mean()
    assert 0.9 * centrifugal <= slack <= 1.1 * (centrifugal + r.static_tension)


def test_at_rest_holds_the_load():
    """0 rpm with the load on: finite, tensions >= 0, the driven sprocket held by the chain
    (T_tight - T_slack = M / R_o within 5 % once the start has settled)."""
    r = _run(0.3, input_speed_rpm=0.0)
    m = _second_half(r)
    assert r["slack_span.tension"][m].min() >= 0 and r["chain.min_link_tension"][m].min() >= 0
    diff = (r["tight_span.tension"][m] - r["slack_span.tension"][m]).mean()
    assert diff == pytest.approx(43.2 / r.scene.drive.driven.pitch_radius, rel=0.05)


def test_load_step_force_balance():
    """The load doubles at 0.2 s (an FMU-style held input): the run stays finite, the span
    tensions stay >= 0 (the slack span now touches zero: at 2 M its static share is used up),
    and the tight span carries the new load (T_tight - T_slack = 2 M / R_o over whole tooth
    periods, within 5 %). In the 40 ms after the step one link's plates bear briefly (about
    -100 N): the step's compression wave closes a pin-bushing play."""
    scene = load_scene("xu2010", fidelity=3)
    st = Verlet(scene.model(), 0.0, None, scene.inputs(0.0), max_step=scene.model().event_step(0))
    out = []
    for i in range(1, 401):
        t = i * 1e-3
        u = scene.inputs(t)
        if t > 0.2:
            u = Inputs(u.angle, u.speed, 2 * 43.2, u.acceleration)
        out.append(st.advance(t, lambda tt, u=u: u if tt > 0.2 else scene.inputs(tt)))
    tail = out[-160:]          # 0.24-0.4 s: eight tooth periods of 20 ms
    tight = np.mean([o["tight_span.tension"] for o in tail])
    slack = np.mean([o["slack_span.tension"] for o in tail])
    assert tight - slack == pytest.approx(2 * 43.2 / scene.drive.driven.pitch_radius, rel=0.05)
    assert min(o["slack_span.tension"] for o in out[200:]) >= 0
    assert min(o["tight_span.tension"] for o in out[200:]) > 0


def test_overload_shows_slack_links():
    """10x the load: the slack span goes slack part of the time and links bounce through their
    pin-bushing play; the summary does not hide it (minimum link tension 0 or below, a nonzero
    slack time fraction) while the tight span carries the load."""
    r = _run(0.3, load_torque=432.0)
    s = r.summary()
    assert s["slack_link_time_fraction"] > 0.0
    assert s["min_link_tension_n"] <= 0.0
    assert s["min_slack_tension_n"] <= s["mean_slack_tension_n"]
    m = _second_half(r)
    assert (r["tight_span.tension"][m] - r["slack_span.tension"][m]).mean() == pytest.approx(
        432.0 / r.scene.drive.driven.pitch_radius, rel=0.05)


def test_no_damping_stays_finite_with_exact_ratio():
    """Every damper off (link, joint, contact, shaft): finite (the automatic step resolves the
    links' slack-taut impacts, MultibodyModel.event_step) and the tooth ratio exact; bounded
    energy is tests/test_multibody.py::test_energy_bounded_without_dissipation."""
    r = _run(0.3, chain_link_damping=0, contact_damping=0, input_shaft_damping=0,
             chain_joint_damping=0)
    m = _second_half(r)
    assert tooth_ratio(r["driver.angle"][m], r["driven.angle"][m], 25) == pytest.approx(
        RATIO, rel=2e-3)


@pytest.mark.parametrize("override, duration", [({"chain.link_stiffness": 5.1e9}, 0.06),
                                                ({"contact.stiffness": 8.46e8}, 0.1),
                                                ({"contact.stiffness": 8.46e4}, 0.2)])
def test_stiffness_range(override, duration):
    """x100 the link or contact stiffness (the step shrinks with omega_max) and x0.01 the
    contact stiffness: finite, the spans in tension."""
    scene = load_scene("xu2010", fidelity=3, duration=duration, output_interval=2e-4)
    r = chainmodel.simulate(scene.with_overrides(parameters=override))
    m = _second_half(r)
    assert np.all(np.isfinite(r["tight_span.tension"]))
    assert r["tight_span.tension"][m].min() > 0


def test_soft_chain_names_the_stiffness():
    """chain.link_stiffness / 1000 (the issue's case): refused at the boundary, before any
    step, by the every-level strain bound (the load would stretch a link by more than 5 %);
    the message names the chain stiffness and a stiffness that would do, not the step."""
    with pytest.raises(ValueError, match=r"chain\.link_stiffness = 51000.*chain\.link_stiffness >="):
        chainmodel.simulate("xu2010", fidelity=3, duration=0.1, chain_link_stiffness=5.1e4)


def test_short_chain_refused():
    with pytest.raises(ValueError, match=r"drive\.links"):
        chainmodel.simulate("xu2010", fidelity=3, duration=0.01, drive_links=3)


@pytest.mark.parametrize("method", ["radau", "bdf", "lsoda"])
def test_implicit_steppers_refused_naming_verlet(method):
    with pytest.raises(ValueError, match=rf"solver\.method = {method} is refused.*verlet"):
        chainmodel.simulate("xu2010", fidelity=3, duration=0.01, solver_method=method)


def test_link_law_tension_only_with_play():
    """Two rollers on one link: no force while the link is shortened within the pin-bushing
    play, k (e + play) once the plates bear; the potential's derivative is the force (finite
    differences), so the undamped law is conservative."""
    sc = load_scene("xu2010", fidelity=3)
    p = sc.parameters
    k, gap = p["chain.link_stiffness"], p["chain.joint_clearance"]
    l0 = sc.drive.pitch - p["chain.pretension"] / k
    ext = np.array([2e-5, 1e-6, -1e-6, -0.5 * gap, -gap + 1e-7, -gap - 1e-5])
    force = np.where(ext > 0, k * ext, np.where(ext < -gap, k * (ext + gap), 0.0))
    h = 1e-9
    dU = (K.link_potential(ext + h, k, gap) - K.link_potential(ext - h, k, gap)) / (2 * h)
    np.testing.assert_allclose(dU, force, rtol=1e-5, atol=1e-3)
    # the kernels: a straight chain of M rollers, every link at l0 + ext[i % 6], at rest
    model = sc.model()
    M = model.M
    spacing = l0 + ext[np.arange(M) % len(ext)]
    spacing[-1] = 0.0   # the closing link is far away; only links 0..M-2 are checked
    x = np.zeros(2 * (2 + 2 * M))
    x[2:2 + 2 * M:2] = 10.0 + np.concatenate([[0.0], np.cumsum(spacing[:-1])])
    x[3:2 + 2 * M:2] = 10.0
    model._accel(x, 0.0, 0.0, 0.0, 0.0)
    expected = force[np.arange(M - 1) % len(ext)]
    np.testing.assert_allclose(model.ws.tension[:M - 1], expected, rtol=1e-6, atol=1e-6)
