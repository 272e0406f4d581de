"""Level 1 (torsional): geometry kernel, statics (seed 004 eqs 15-17), kinematic limits, the
exact tooth ratio, slack events, bad input, and the compiled/plain-Python paths.

Every expected number comes from the papers, from physics or from an independent computation
here (chain_geometry of the foundation, the level-0 kinematics, finite differences)."""

from __future__ import annotations

import math
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import chainmodel
from chainmodel import integrate, simulation
from chainmodel.analysis.summary import tooth_ratio
from chainmodel.integrate import RK4, Adaptive
from chainmodel.kinematics import driven_rotation
from chainmodel.kinematics.wrapping import chain_geometry
from chainmodel.models import MODEL_CLASSES, Inputs
from chainmodel.kernels import spans as S
from chainmodel.models.torsional import TorsionalModel, seat_stiffness
from chainmodel.presets import reference_values

ROOT = Path(__file__).resolve().parents[1]


def _table2():
    return reference_values("dynamic_params_jsv2016_table2.csv")


# --- geometry kernel ----------------------------------------------------------------------

@pytest.mark.parametrize("name", ["xu2010", "C1", "A1"])
def test_scalar_geometry_matches_chain_geometry(name):
    """The scalar kernel is the same computation as the vectorised chain_geometry, for any pair
    of rotations (stretched, slack, forward or backward), compiled or plain Python."""
    drive = chainmodel.Scene.from_preset(name).drive
    G = S.geometry_constants(drive)
    rng = np.random.default_rng(4)
    phi1 = rng.uniform(-30, 30, 150)
    phi2 = phi1 * drive.tooth_ratio + rng.uniform(-0.6, 0.6, 150) * math.pi / drive.n_driven
    g = chain_geometry(drive, phi1, phi2)
    ref = np.column_stack([g.upper.length, g.upper.arm_start, g.upper.arm_end, g.upper_links,
                           g.lower.length, g.lower.arm_start, g.lower.arm_end, g.lower_links,
                           g.wrapped_driver, g.wrapped_driven])
    pick = [0, 1, 2, 3, 9, 10, 11, 12, 18, 19]
    for fn in (S.span_geometry, S.span_geometry.py_func):
        got = np.array([[fn(a, b, G)[k] for k in pick] for a, b in zip(phi1, phi2)])
        np.testing.assert_allclose(got, ref, rtol=0, atol=1e-12)


def test_length_derivatives_are_the_moment_arms():
    """Virtual work: dl/dphi = +arm_end on the sprocket a span runs onto, -arm_start on the one
    it leaves (central differences away from events)."""
    drive = chainmodel.Scene.from_preset("xu2010").drive
    G = S.geometry_constants(drive)
    h = 1e-7
    for phi1 in (0.013, 0.11, 0.2):
        phi2 = float(driven_rotation(drive, phi1).driven_angle)
        g = S.span_geometry(phi1, phi2, G)
        d1 = [(S.span_geometry(phi1 + h, phi2, G)[k] - S.span_geometry(phi1 - h, phi2, G)[k]) / (2 * h)
              for k in (0, 9)]
        d2 = [(S.span_geometry(phi1, phi2 + h, G)[k] - S.span_geometry(phi1, phi2 - h, G)[k]) / (2 * h)
              for k in (0, 9)]
        assert d1[0] == pytest.approx(g[2], rel=1e-6)     # upper runs onto the driver
        assert d2[0] == pytest.approx(-g[1], rel=1e-6)    # upper leaves the driven sprocket
        assert d1[1] == pytest.approx(-g[10], rel=1e-6)   # lower leaves the driver
        assert d2[1] == pytest.approx(g[11], rel=1e-6)    # lower runs onto the driven sprocket


@pytest.mark.parametrize("name", ["xu2010", "C1", "A1", "coarse"])
def test_scalar_geometry_settles_just_before_events(name):
    """Within ~1e-9 rad before a seating the tolerant window can flip between two endpoint
    candidates (found in wrapping._span); the scalar kernel must settle on the same span as
    chain_geometry there too."""
    drive = chainmodel.Scene.from_preset(name).drive
    G = S.geometry_constants(drive)
    period = 2 * math.pi / drive.n_driver
    phi1 = (period * np.arange(1, 6)[:, None]
            - np.array([1e-8, 1e-9, 3e-10, 1e-11, 0.0])[None, :]).ravel()
    phi2 = driven_rotation(drive, phi1).driven_angle
    g = chain_geometry(drive, phi1, phi2)
    for k in range(phi1.size):
        r = S.span_geometry(phi1[k], phi2[k], G)
        assert r[0] == pytest.approx(g.upper.length[k], rel=1e-12)
        assert r[9] == pytest.approx(g.lower.length[k], rel=1e-12)
        assert r[3] == g.upper_links[k]


# --- statics: seed 004 eqs 15-17 ----------------------------------------------------------

@pytest.mark.parametrize("angle", [0.0, 0.13, 0.29, 0.41])
def test_static_split_reproduces_eqs_15_17(angle):
    """At rest under the brake load R1 f1 (Table 2) with the spans pretensioned to P_tot/2:
    P0 = (P_tot + M1/R1)/2, P0~ = (P_tot - M1/R1)/2. Eqs 15-16 take both moment arms = R1; the
    polygon's arms are R1 cos(theta) with |theta| <= pi/n_o, so T_u a_u - T_l a_l = M1 (checked
    exactly) allows T_u - T_l to differ from M1/R1 by up to (M1/R1 + T_u + T_l)(1 - cos(pi/n_o)),
    and the wrapping length makes the no-load tension itself vary with the angle; the sum of the
    two tensions is that no-load sum, up to the +-1 link difference between the spans' counts
    (12 or 13 links: +-4 % of stiffness moves +-2 % of M1/R1 between the spans). Eqs 15-16
    are a linear split: the spans' linear law, not the wrap fit's floor under the slack span
    (torsional.wrap_statics off)."""
    t2 = _table2()
    sc = chainmodel.Scene.from_preset("C1", fidelity=1, torsional_wrap_statics=False)
    m = sc.model()
    r1 = m.drive.driven.pitch_radius
    m1 = r1 * t2["f1"]
    u = Inputs(angle, 0.0, m1)
    x = m.initial_state(u)
    out = m.outputs(0.0, x, u)
    g = S.span_geometry(angle, x[0], m.G)
    assert out["tight_span.tension"] * g[1] - out["slack_span.tension"] * g[11] == pytest.approx(m1, rel=1e-9)
    bound = (m1 / r1 + out["tight_span.tension"] + out["slack_span.tension"]) * (
        1 - math.cos(math.pi / m.drive.n_driven))
    assert abs(out["tight_span.tension"] - out["slack_span.tension"] - m1 / r1) <= bound
    # the sum is the no-load tension at this angle (what the wrap length gives), eq 15 + 16
    x0 = m.initial_state(Inputs(angle, 0.0, 0.0))
    o0 = m.outputs(0.0, x0, Inputs(angle, 0.0, 0.0))
    assert out["tight_span.tension"] + out["slack_span.tension"] == pytest.approx(
        o0["tight_span.tension"] + o0["slack_span.tension"], rel=0.02)


def test_running_mean_tensions_follow_eqs_15_17_with_speed_damping():
    """Steady running (slow ramp): mean tensions over whole tooth periods are P0, P0~ of eqs
    15-16 with M1 = d1 S/R1 + R1 f1 (eq 17, S/R1 the driven speed). Eqs 15-16 are a linear
    split, so both spans must stay taut: with Table 2's P_tot = 1000 N the C1 drive's own
    wrapping-length variation (about +-130 N at rest) and the ringing left by crossing the 29 Hz
    sprocket mode (0.5 % damping) drop the slack span to zero now and then, so the test uses
    P_tot = 2000 N (static span tension 1000 N) and checks that precondition first."""
    t2 = _table2()
    static = 1000.0
    sc = chainmodel.Scene.from_preset("C1", fidelity=1, duration=1.6, ramp_time=1.0,
                                      output_interval=1e-3, static_tension=static)
    r = chainmodel.simulate(sc)
    drive = sc.drive
    period = 2 * math.pi / (sc.operating.speed * drive.n_driver)
    mask = r.time >= 1.6 - 40 * period - 1e-9
    assert np.min(r["slack_span.tension"][mask]) > 0.0      # linear regime: both spans taut
    r1 = drive.driven.pitch_radius
    w2 = sc.operating.speed * drive.tooth_ratio
    m1 = t2["d1"] * w2 + r1 * t2["f1"]
    # eqs 15-16 split what the chain holds at rest: level 3's tooth-period mean at this static
    # tension (wrap_statics.held_span_tension), the mean the running spans move about
    p_tot = 2 * sc.model().held_tension()
    p0 = 0.5 * (p_tot + m1 / r1)
    p0t = 0.5 * (p_tot - m1 / r1)
    assert np.mean(r["tight_span.tension"][mask]) == pytest.approx(p0, rel=0.02)
    assert np.mean(r["slack_span.tension"][mask]) == pytest.approx(p0t, rel=0.05)


# --- kinematic limits -----------------------------------------------------------------------

@pytest.mark.parametrize("stiffness_factor", [0.1, 1.0])
def test_driven_turns_exactly_one_tooth_per_driver_tooth(stiffness_factor):
    """No slip: over whole driver tooth periods in steady state the driven sprocket turns
    2 pi/n_o per driver tooth, i.e. the ratio n_c/n_o, at any span stiffness (a link-counting
    error would be off by a whole tooth, 1/17 of the ratio)."""
    # the softer chain rings down more slowly (span mode ~ 100 Hz at ~1 % damping): a longer
    # run; the ratio over whole periods is then exact up to the residual transient's drift of
    # the transmission error (~1e-6 rad per 0.1 s here) over ~6 rad of driver rotation
    # (seat compliance, on by default for xu2010, softens it further: 1.6 s)
    duration = 0.4 if stiffness_factor == 1.0 else 1.6
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, duration=duration,
                                      output_interval=5e-4,
                                      chain_link_stiffness=5.1e7 * stiffness_factor)
    r = chainmodel.simulate(sc)
    mask = r.time >= duration - 0.4
    ratio = tooth_ratio(r["driver.angle"][mask], r["driven.angle"][mask], sc.drive.n_driver)
    assert ratio == pytest.approx(25 / 17, rel=2e-5)


def test_stiff_spans_and_rigid_shaft_reproduce_level0_velocity_ratio():
    """A loose chain (nowhere stretched by the rigid kinematics: Drive.from_links tight_at='max')
    under load: the lower span hangs slack and the upper span, 100x stiffer than seed 003's
    chain, carries the torque as the rigid four-bar of level 0 does."""
    loose = chainmodel.Drive.from_links(25, 17, 0.015875, 46, tight_at="max")
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, duration=0.25, output_interval=2e-4,
                                      drive_centre_distance=loose.centre_distance,
                                      chain_link_stiffness=5.1e9, chain_link_damping=1000.0,
                                      input_shaft_rigid=True,
                                      # the level-0 limit: rigid seats as well as stiff spans
                                      torsional_seat_compliance=False,
                                      # a slack span without weight: no sag tension either
                                      gravity=0.0)
    r = chainmodel.simulate(sc)
    mask = r.time >= 0.15
    # slack: nothing but the centrifugal tension rho A v^2 (v = n_c p w / 2 pi)
    v = 25 * 0.015875 * r["driver.speed"][mask] / (2 * math.pi)
    np.testing.assert_allclose(r["slack_span.tension"][mask], 0.0162 / 0.015875 * v * v,
                               rtol=1e-12, atol=0)
    k0 = chainmodel.simulate(sc.with_overrides(fidelity=0))
    ripple = np.ptp(k0["velocity_ratio"][mask])
    assert ripple > 1e-3 * 25 / 17                       # the polygonal ripple is there
    err = r["velocity_ratio"][mask] - k0["velocity_ratio"][mask]
    # stretch ~ J2 phi2''/(k R): the span's compliance changes the ratio by well under 5 %
    # of the ripple except in the short ringing after each seating (RMS over the window)
    assert np.sqrt(np.mean(err ** 2)) < 0.05 * ripple
    assert np.max(np.abs(r["driven.angle"][mask] - k0["driven.angle"][mask])) < 1e-3 * 2 * math.pi / 17


# --- slack events -----------------------------------------------------------------------------

def _slack_setup():
    """C1 at rest with 250 N static tension, then three times the brake load R1 f1 (600 N of
    span-tension difference) is applied: the lower span must go slack."""
    t2 = _table2()
    sc = chainmodel.Scene.from_preset("C1", fidelity=1, static_tension=250.0)
    m = sc.model()
    x0 = m.initial_state(Inputs(0.05, 0.0, 0.0))
    load = Inputs(0.05, 0.0, 3 * m.drive.driven.pitch_radius * t2["f1"])
    return m, x0, load


def test_slack_switch_is_located_as_an_event():
    """The adaptive stepper stops on the lower span going slack: an independent fine fixed-step
    run (2 us steps) sees that span's switching function min(k delta, T) change sign within
    +-2 us of the located time, and at the located time the tension is zero to within what
    2 us of motion changes it."""
    m, x0, load = _slack_setup()
    ad = Adaptive(m, 0.0, x0, load, method="rk45", rtol=1e-9)
    ad.advance(0.05, load)
    assert ad.stats["events"] >= 1
    located = []
    for t_e in sorted(ad.event_log):
        fine = RK4(m, 0.0, x0, load, step=2e-6)
        fine.advance(t_e - 2e-6, load)
        g_before = m.switching_functions(fine.t, fine.x, load)[1]
        fine.advance(t_e, load)
        g_at = m.switching_functions(fine.t, fine.x, load)[1]
        fine.advance(t_e + 2e-6, load)
        g_after = m.switching_functions(fine.t, fine.x, load)[1]
        if g_before > 0 >= g_after:
            located.append((t_e, g_before, g_at, g_after))
    assert located, "no located event is the lower span going slack"
    t_e, g_before, g_at, g_after = located[0]
    assert abs(g_at) <= abs(g_after - g_before)
    # and in physical terms: under a newton of tension at the switch
    assert abs(g_at) < 1.0


def test_adaptive_with_events_agrees_with_fine_fixed_step():
    """dop853 stopping at the events against RK4 at 20 us steps (itself converged to 1e-10 rad:
    10 and 5 us give the same driven angle). rtol 3e-11: at 1e-10 dop853's own error on this
    run is 1.3e-9 rad since the span's free length counts the tooth-period-mean links' pre-strain
    (kernels.spans.free_length; the law then has a kink at each event where it had a step)."""
    m, x0, load = _slack_setup()
    ad = Adaptive(m, 0.0, x0, load, method="dop853", rtol=3e-11)
    fine = RK4(m, 0.0, x0, load, step=2e-5)
    a_out = ad.advance(0.05, load)
    f_out = fine.advance(0.05, load)
    assert ad.stats["events"] >= 1
    assert a_out["driven.angle"] == pytest.approx(f_out["driven.angle"], abs=1e-9)
    assert a_out["tight_span.tension"] == pytest.approx(f_out["tight_span.tension"], abs=0.05)
    assert a_out["slack_span.tension"] == pytest.approx(f_out["slack_span.tension"], abs=0.05)


# --- bad input --------------------------------------------------------------------------------

def test_bad_input_is_refused_with_the_parameter_named():
    with pytest.raises(ValueError, match="chain.pretension"):
        chainmodel.Scene.from_preset("xu2010", fidelity=1, chain_pretension=-10.0)
    with pytest.raises(ValueError, match="static_tension"):
        chainmodel.Scene.from_preset("C1", fidelity=1, static_tension=-5.0)
    with pytest.raises(ValueError, match="chain.link_stiffness"):
        chainmodel.Scene.from_preset("xu2010", fidelity=1, chain_link_stiffness=0.0)
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1)
    params = dict(sc.parameters, **{"driven.inertia": -1.0})
    with pytest.raises(ValueError, match="driven.inertia"):
        TorsionalModel(sc.drive, params)
    with pytest.raises(ValueError, match="solver.step"):
        sc.with_overrides(solver_step=1.0).stepper()


# --- interface, paths, outputs ------------------------------------------------------------

def test_runs_through_simulate_with_all_outputs_finite():
    r = chainmodel.simulate("xu2010", fidelity="torsional", duration=0.06, output_interval=1e-3)
    assert MODEL_CLASSES[1] is TorsionalModel
    for name in r.names:
        assert np.all(np.isfinite(r[name])), name
    assert "quasi-static" in r.descriptions["tight_span.midspan_deflection"]
    assert "quasi-static" not in r.descriptions["tight_span.tension"]
    # the driver lags the input through the shaft spring by the transmitted torque / k_s
    tau = r["input_shaft.torque"][-1]
    assert tau > 0


def test_compiled_and_python_steppers_agree():
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, duration=0.04, output_interval=1e-3)
    a = chainmodel.simulate(sc)
    b = simulation.run_scene(sc, model=integrate.python_loop_model(sc.model()))
    assert a.stats["steps"] > 0 and b.stats["steps"] > 0
    assert a.stats["events"] == b.stats["events"] > 0
    np.testing.assert_allclose(a["driven.angle"], b["driven.angle"], rtol=0, atol=1e-11)
    np.testing.assert_allclose(a["tight_span.tension"], b["tight_span.tension"], rtol=0, atol=1e-5)


def test_kernel_plain_python_equals_compiled():
    sc = chainmodel.Scene.from_preset("C1", fidelity=2, modal_modes=3)
    m = sc.model()
    x = m.initial_state(Inputs(0.2, 0.0, 0.0)) + 1e-4
    for fn in (S.evaluate, S.evaluate.py_func):
        dx, aux = np.empty(m.n_states), np.empty(S.A_SIZE)
        fn(x, 0.2, 40.0, 0.0, 10.0, m.G, m.P, dx, aux)
        if fn is S.evaluate:
            ref = (dx.copy(), aux.copy())
    np.testing.assert_allclose(dx, ref[0], rtol=1e-13, atol=1e-12)
    np.testing.assert_allclose(aux, ref[1], rtol=1e-13, atol=1e-12)


def test_runs_without_numba():
    """The plain-Python fallback (CHAINMODEL_NUMBA=0) runs a scene and agrees with the compiled
    run, steps spanning output points included (C1's step bound is 2.85 ms, 14 of these
    output intervals: the same steps in both)."""
    code = ("import chainmodel, json; from chainmodel import _numba;"
            "r = chainmodel.simulate('C1', fidelity=1, duration=0.02, output_interval=2e-4);"
            "print(json.dumps([_numba.enabled(), float(r['driven.angle'][-1]), "
            "float(r['tight_span.tension'][-1]), r.stats['steps']]))")
    env = dict(os.environ, CHAINMODEL_NUMBA="0", PYTHONPATH=str(ROOT))
    res = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         timeout=120, cwd=ROOT)
    assert res.returncode == 0, res.stderr
    import json
    numba_used, angle, tension, steps = json.loads(res.stdout.strip().splitlines()[-1])
    assert numba_used is False
    r = chainmodel.simulate("C1", fidelity=1, duration=0.02, output_interval=2e-4)
    assert steps == r.stats["steps"] < len(r.time) - 1
    assert angle == pytest.approx(float(r["driven.angle"][-1]), abs=1e-10)
    assert tension == pytest.approx(float(r["tight_span.tension"][-1]), abs=1e-4)


def test_level1_steps_span_output_points_where_its_bound_allows():
    """C1 at 400 rpm, outputs every 0.1 ms, its automatic step bound 2.85 ms (the tolerance's
    h w = 0.507 on its 27.6 Hz bound frequency): steps spanning output points (rk4_loop.
    _span_step) against one step per point (solver.step = the interval). The points in
    between take the step's cubic Hermite dense output, whose error is of order
    (h w)^4 / 384 = 2e-4 of a mode's amplitude, and the step's own phase error is the
    tolerance's 5e-4 per step: the outputs stay within 3 % of their ripple (RMS) and the means
    within 0.2 %, at fewer than 3 evaluations per point against more than 4, and no seating or
    release event is lost."""
    sc = chainmodel.Scene.from_preset("C1", fidelity=1, duration=1.0, output_interval=1e-4)
    spanning = chainmodel.simulate(sc)
    one = chainmodel.simulate(sc.with_overrides(solver_step=1e-4))
    points = len(spanning.time) - 1
    assert spanning.stats["rhs_evaluations"] < 3.0 * points < 4.0 * points < one.stats[
        "rhs_evaluations"]
    assert abs(spanning.stats["events"] - one.stats["events"]) <= 3
    m = spanning.time >= 0.5
    for name in ("driven.speed", "tight_span.tension", "slack_span.tension"):
        a, b = spanning[name][m], one[name][m]
        assert np.sqrt(np.mean((a - b) ** 2)) < 0.03 * np.std(b), name
        assert np.mean(a) == pytest.approx(np.mean(b), rel=2e-3), name


def test_a_step_spans_points_only_where_the_inputs_lie_on_one_cubic():
    """rk4_loop._on_one_cubic: a held speed and a constant-acceleration ramp lie on the cubic
    Hermite through the span's ends; a speed that changes slope at a point inside does not
    (the step there would see other inputs than the steps point by point), nor does a load
    that steps."""
    from chainmodel.kernels import rk4_loop as L
    times = np.linspace(0.0, 1e-3, 11)
    c = np.empty(L.C_SIZE)

    def lies(angle, speed, acc, load):
        L._set_interval(c, times, angle, speed, acc, load, 0, 10)
        return L._on_one_cubic(1, 10, times, angle, speed, acc, load, c)

    held = np.full(11, 40.0)
    zero = np.zeros(11)
    assert lies(0.3 + 40.0 * times, held, zero, np.full(11, 43.2))
    ramp_acc = np.full(11, 500.0)
    assert lies(0.3 + 40.0 * times + 250.0 * times ** 2, 40.0 + 500.0 * times, ramp_acc, zero)
    # the ramp ends at the sixth point: speed held from there
    speed = np.minimum(40.0 + 500.0 * times, 40.0 + 500.0 * times[5])
    angle = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) * np.diff(times))])
    acc = np.where(times < times[5], 500.0, 0.0)
    assert not lies(angle, speed, acc, zero)
    load = np.where(times < times[5], 0.0, 10.0)
    assert not lies(0.3 + 40.0 * times, held, zero, load)


def test_xu2010_level1_steps_point_by_point_where_its_bound_is_the_interval():
    """xu2010's step bound (0.127 ms on its 619 Hz bound frequency) is under two 0.1 ms output
    intervals: no step spans points, and the run is bit for bit the one with solver.step at
    the interval."""
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, duration=0.1, output_interval=1e-4)
    a = chainmodel.simulate(sc)
    b = chainmodel.simulate(sc.with_overrides(solver_step=1e-4))
    assert a.stats["steps"] == b.stats["steps"] == len(a.time) - 1
    for name in a.names:
        assert np.array_equal(a[name], b[name]), name


def test_reverse_rotation_swaps_the_tight_span():
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=1, duration=0.15, output_interval=1e-3,
                                      input_speed_rpm=-120, load_torque=-43.2)
    r = chainmodel.simulate(sc)
    mask = r.time > 0.1
    assert np.mean(r["tight_span.tension"][mask]) > np.mean(r["slack_span.tension"][mask])
    assert np.all(r["driven.speed"][mask] < 0)


def test_seat_stiffness_ladder():
    """K = k_c + k_l K/(k_l + K) (a seat spring in parallel with the link to the next seated
    roller on the rest of the ladder); the closed form solves it."""
    kc, kl = 8.46e6, 5.1e7
    K = seat_stiffness(kc, kl)
    assert K == pytest.approx(kc + kl * K / (kl + K), rel=1e-12)
    # and it is what a long finite ladder converges to
    k = kc
    for _ in range(200):
        k = kc + kl * k / (kl + k)
    assert K == pytest.approx(k, rel=1e-12)


def test_automatic_step_is_capped_at_a_quarter_tooth_period_of_the_current_input_speed():
    """C1 (J1 = 0.6 kg m^2, a 28 Hz sprocket mode) has a stability bound above its 12.5 ms tooth
    period at 400 rpm; a fixed step crosses only the first event inside it, so the automatic
    step is at most a quarter tooth period at the input speed of the communication step (four
    seating/release events per tooth period) - in the library and in the FMU's held-input path
    alike, with nothing known in advance about the speed."""
    sc = chainmodel.Scene.from_preset("C1", fidelity=1, duration=0.5, output_interval=1e-2,
                                      solver_tolerance=0.05,    # loose: the cap binds
                                      # the cap's accuracy on the linear span law: with the
                                      # weight C1's slack span dips to 16 N here, the knee of
                                      # its sag law, whose curvature this deliberately loose
                                      # step follows to 1.5e-4 rad (measured), not 1e-4;
                                      # likewise the wrap fit's floor (4e-4 rad)
                                      gravity=0.0, torsional_wrap_statics=False)
    w = 400 * 2 * math.pi / 60
    quarter = 2 * math.pi / (w * sc.drive.n_driver) / 4.0
    m = sc.model()
    st = sc.stepper(m)
    assert st.stable_limit > 2 * quarter            # the stability bound alone would not do it
    assert st.step_bound(m.omega_at(0.0, st.x, sc.inputs(0.0))) > 2 * quarter  # nor the tolerance
    st.advance_held(0.01, 0.0, w, 0.0, sc.operating.load_torque)
    assert st.stats["steps"] == math.ceil(0.01 / quarter)
    rest = sc.stepper(m)                             # at rest nothing caps it
    rest.advance_held(0.01, 0.0, 0.0, 0.0, sc.operating.load_torque)
    assert rest.stats["steps"] < st.stats["steps"]
    r = chainmodel.simulate(sc)
    ref = chainmodel.simulate(sc.with_overrides(solver_step=quarter / 8))
    late = r.time >= 0.25
    # 1.28e-4 rad measured since the span's free length counts the mean links' pre-strain
    # (kernels.spans.free_length, twenty-fourth session), 1e-4 before
    assert np.max(np.abs(r["driven.angle"][late] - ref["driven.angle"][late])) < 1.5e-4
    # an explicit solver.step is the user's choice and is kept
    assert sc.with_overrides(solver_step=2 * quarter).stepper().h == pytest.approx(2 * quarter)

@pytest.mark.parametrize("name, level, load", [("xu2010", 1, 43.2), ("xu2010", 2, -20.0),
                                               ("C1", 1, 100.0), ("C1", 2, 0.0)])
def test_compiled_static_equilibrium_is_at_rest_and_equals_its_twin(name, level, load):
    """The initial state (kernels/equilibrium.py, one compiled call) is an equilibrium - every
    acceleration of the model's own right-hand side vanishes to round-off relative to the
    accelerations one degree of rotation away would cause - and the plain-Python twin of the
    same functions finds the same state."""
    from chainmodel.kernels import equilibrium as E
    from chainmodel.kernels.kinematic import driven_rotation, fourbar_constants
    m = chainmodel.Scene.from_preset(name, fidelity=level).model()
    u = Inputs(0.37, 0.0, load)
    x = m.initial_state(u)
    k = m.n_sprocket_states // 2
    acc = m.rhs(0.0, x, u)[k:m.n_sprocket_states]
    nudged = x.copy()
    nudged[k - 1] += math.radians(1.0)                  # driven sprocket turned by a degree
    scale = np.max(np.abs(m.rhs(0.0, nudged, u)[k:m.n_sprocket_states]))
    assert np.max(np.abs(acc)) < 1e-9 * scale
    twin = np.concatenate([np.zeros(m.n_sprocket_states), x[m.n_sprocket_states:]])
    phi2_kin = driven_rotation(0.37, 0.0, 0.0, False, fourbar_constants(m.drive))[0]
    d = m.drive
    status = E.static_state.py_func(0.37, load, phi2_kin, d.tooth_ratio, math.pi / d.n_driven,
                                    math.pi / d.n_driver, twin, m.G, m.P)
    assert status == E.STATUS_OK
    np.testing.assert_allclose(twin, x, rtol=0, atol=1e-14)
