"""Levels 0-2 on level 3's statics (``torsional.wrap_statics``; issue 21 items 3-4,
docs/reduced_models.md "One wrap and one static tension from level 3's statics").

* item 4: the 08B fan drive with no pretension near and away from its tight wrap (its spans
  sag; tests/test_span_sag.py for the pretension taking it up): levels 0, 1 and 2 report the static tension level 3's dynamic model holds at rest when
  started from the static equilibrium (0.1 s at rest, its own force law deciding), within 5 %;
  level 1 run at rest holds it too;
* item 3: C1's driven-sprocket mode (ring-down after a sudden start to 5 rpm) at levels 1 and
  2 within 3 % of level 3's and of the two-inertia estimate with the condensed stiffness K_3;
  xu2010's is a strict xfail: level 3 rings at its linear mode, 5 % above the static
  condensation K_3 (tests/test_top_rung_modes.py: its spans' inertia at 600 Hz, which no static
  wrap holds; docs/reduced_models.md); xu2010's loaded split, turned quasi-statically, against
  level 3's statics.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.integrate import Verlet
from chainmodel.models import Inputs
from chainmodel.models.multibody_statics import static_state
from chainmodel.models.wrap_statics import wrap_fit
from chainmodel.scene import load_scene
from ringdown_check import ring, two_inertia_frequency

FAN = "examples/scenes/08b_fan_1500rpm.toml"
ON = {"torsional_wrap_statics": True}


def _fan_scene(dc, level, **kw):
    a0 = load_scene(FAN, fidelity=1, static_tension=None).drive.centre_distance
    return load_scene(FAN, fidelity=level, static_tension=None, drive_centre_distance=a0 + dc,
                      **kw)


def _level3_at_rest(dc):
    """Mean span tension of level 3's dynamic model over 0.1 s at rest, started from the
    static equilibrium (driver held at 0, no load)."""
    model = _fan_scene(dc, 3).model()
    x = static_state(model).state.copy()
    u = Inputs(0.0, 0.0, 0.0)
    st = Verlet(model, 0.0, x, u)
    rows = [st.advance(i * 1e-3, u) for i in range(1, 101)]
    return float(np.mean([0.5 * (r["tight_span.tension"] + r["slack_span.tension"])
                          for r in rows]))


@pytest.mark.parametrize("options", [{}, ON], ids=["default", "wrap_statics"])
@pytest.mark.parametrize("dc", [0.0, -0.5e-3, -2e-3, -5e-3])
def test_fan_without_pretension_static_tension_agrees_at_every_level(dc, options):
    """By default too: a chain with no pretension that the seat ladder leaves slack hangs on
    its sag, and levels 0-2 carry that tension (wrap_statics.weighted_static_tension: the
    elastic catenary, its sag term from level 3's statics where the weight carries the
    tension); level 2 refuses a chain longer than its wrap (dc < 0) unless the option holds
    its ends, and says so."""
    t3 = _level3_at_rest(dc)
    assert t3 > 1.0                     # the sag tension, not a slack 0
    for level in (0, 1, 2):
        if level == 2 and dc < 0 and not options:
            # longer than its wrap: level 2's strings refuse it unless the option holds it
            with pytest.raises(ValueError, match="torsional.wrap_statics"):
                _fan_scene(dc, level).model()
            continue
        t = _fan_scene(dc, level, **options).model().static_tension()
        assert t == pytest.approx(t3, rel=0.05), level
    if not options:
        # by default the ends keep the seat ladder's stiffness, so level 1 at rest at driver
        # angle 0 sits ~5 N below its tooth-period mean (polygon action on stiff ends;
        # docs/reduced_models.md): only the option's run at rest is held to level 3's
        return
    # level 1 run at rest from its own initial state holds it (its span law, not a number)
    r = chainmodel.simulate(_fan_scene(dc, 1, **options), input_speed_rpm=0.0, load_torque=0.0,
                            duration=0.05, output_interval=1e-3)
    mean = 0.5 * (r["tight_span.tension"][-10:].mean() + r["slack_span.tension"][-10:].mean())
    assert mean == pytest.approx(t3, rel=0.05)


def _estimate_k3(name, **kw):
    """Two-inertia estimate [Hz] with the condensed stiffness K_3 of level 3's statics: the
    spans' stiffness K_3 / R_o^2 on the sprockets' pitch radii (ringdown_check)."""
    sc = load_scene(name, fidelity=1, **kw)
    return two_inertia_frequency(sc, wrap_fit(sc.drive, sc.parameters).stiffness
                                 / sc.drive.driven.pitch_radius ** 2)


_XU_GAP = pytest.mark.xfail(strict=True, reason=(
    "issue 21 item 3 not met on xu2010 with torsional.wrap_statics: levels 1-2 ring at 560 Hz, "
    "level 3 at 596 Hz, its linear mode (598 Hz); the static condensation they take (568 Hz "
    "on level 3's own linearisation) leaves out the spans' inertia, which at 600 Hz does not "
    "follow the static span shapes (tests/test_top_rung_modes.py). Until 2026-11-24 this case "
    "ran with the joint dampers off and passed on a spectral peak of several undamped modes "
    "(569.5 Hz) that was not level 3's mode"))


@pytest.mark.parametrize("name,level", [
    ("C1", 1), ("C1", 2),
    pytest.param("xu2010", 1, marks=_XU_GAP), pytest.param("xu2010", 2, marks=_XU_GAP)])
def test_torsional_mode_levels_1_2_on_level3s_wrap(name, level):
    est = _estimate_k3(name, **ON)
    band = (0.6 * est, 1.4 * est)
    f = ring(name, level, band, **ON)
    # levels 1-2 are the two-inertia system on K_3 (their own dynamics hold what they are given)
    assert f == pytest.approx(est, rel=0.03)
    # and that is level 3's mode
    assert f == pytest.approx(ring(name, 3, band), rel=0.03)


@pytest.mark.parametrize("load", [20.0, 43.2])
def test_xu2010_quasi_static_split_follows_level3s_statics(load):
    """Level 1 turned at 1 rpm under a load (driver held by a rigid shaft, the driven sprocket
    damped so that it follows quasi-statically; its damping torque taken off the load), mean
    over the last tooth period, against the mean of level 3's static equilibria under the same
    load at 8 driver positions over a tooth: the tight span within 3 %, the slack span within
    12 % (the seat ladder: +20 % and +26 %). The floor is fitted at 34 N m (0.75 x 2 T_0 R_o),
    neither of these loads."""
    model = load_scene("xu2010", fidelity=3).model()
    tooth = 2 * math.pi / model.drive.n_driver
    sols = [static_state(model, tooth * j / 8, load) for j in range(8)]
    t3 = np.mean([s.tension_upper for s in sols])
    s3 = np.mean([s.tension_lower for s in sols])
    c2, w_in = 20.0, 2 * math.pi / 60
    r = chainmodel.simulate("xu2010", fidelity=1, input_speed_rpm=1.0,
                            load_torque=load - c2 * w_in * model.drive.tooth_ratio,
                            ramp_time=1.0, duration=1.0 + 1.0 + 60.0 / model.drive.n_driver,
                            output_interval=1e-3, input_shaft_rigid=True, driven_damping=c2,
                            **ON)
    m = r.time >= 2.0
    assert r["tight_span.tension"][m].mean() == pytest.approx(t3, rel=0.03)
    assert r["slack_span.tension"][m].mean() == pytest.approx(s3, rel=0.12)


def test_an_option_that_could_not_be_honoured_is_reported(monkeypatch):
    """Where level 3's statics find no equilibrium, torsional.wrap_statics falls back to the
    seat ladder and the result says so (a warning naming the option), never silently."""
    from chainmodel.models import static_tension as ST
    from chainmodel.models import wrap_statics as W

    def no_equilibrium(drive, params):
        raise ValueError("level 3 statics did not converge (forced by the test)")

    monkeypatch.setattr(W, "wrap_fit", no_equilibrium)
    monkeypatch.setattr(W, "_FAILED", {})
    sc = load_scene("xu2010", fidelity=1, **ON)
    r = chainmodel.simulate(sc, duration=0.05, output_interval=1e-3)
    found = [w for w in r.warnings if "torsional.wrap_statics = true was not honoured" in w]
    assert len(found) == 1 and "forced by the test" in found[0]
    # the fallback is the option-less law: the seat ladder with its weight
    assert r.summary()["static_span_tension_n"] == pytest.approx(
        W.weighted_static_tension(sc.drive, sc.parameters), rel=1e-12)
    # and with the option honoured there is no such warning
    monkeypatch.undo()
    r = chainmodel.simulate(load_scene("xu2010", fidelity=1, **ON), duration=0.05,
                            output_interval=1e-3)
    assert not any("torsional.wrap_statics" in w for w in r.warnings)
