"""Level 2 (modal): linearised eigenfrequencies against seed 004 eqs (27), (30), (53), (61),
(71) computed here from Table 2, the Galerkin coefficients against quadrature, the endpoint
impulses of eqs 63-64, the static sag against the string formula, and bad input."""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.kinematics import chain_geometry
from chainmodel.kinematics import driven_rotation
from chainmodel.models import MODEL_CLASSES, Inputs
from chainmodel.kernels import spans as S
from chainmodel.models.modal import ModalModel, galerkin_coefficients
from chainmodel.presets import reference_values


def _t2():
    return reference_values("dynamic_params_jsv2016_table2.csv")


def _undamped_c1(**kw):
    """C1 with Table 2 values as seed 004 models it: no chain inertia in eq 50, no gravity, the
    driver prescribed (rigid), no damping (so the eigenvalues are purely imaginary), linear
    spans between rigid seats (not level 3's wrap: torsional.wrap_statics off)."""
    return chainmodel.Scene.from_preset(
        "C1", fidelity=2, torsional_chain_inertia=False, gravity=0.0, driven_damping=0.0,
        chain_link_damping=0.0, modal_damping_ratio=0.0, torsional_wrap_statics=False, **kw)


def _jacobian(m, x, u):
    n = x.size
    J = np.empty((n, n))
    for i in range(n):
        h = 1e-7 * max(1e-3, abs(x[i]))
        e = np.zeros(n)
        e[i] = h
        J[:, i] = (m.rhs(0.0, x + e, u) - m.rhs(0.0, x - e, u)) / (2 * h)
    return J


def test_linearised_frequencies_equal_eqs_61_and_71():
    """Linearisation at rest (finite-difference Jacobian of rhs about the static equilibrium).
    At rest rather than at the running operating point because with polygonal action steady
    running is a tooth-periodic orbit, not an equilibrium; the transport term -s^2 of eq 61 is
    checked at speed in the next test.

    Expected values from the paper's non-dimensional forms, with P_t = the span tension P
    (so alpha gamma = 1, eq 30) and l = |OC| (eq 26):
      omega_theta = sqrt(2 alpha / J), J = J1 / (rho A l R1^2)  (eqs 53, 71)
      omega_m = m pi sqrt(alpha gamma - s^2)                    (eq 61), s = 0 at rest
    times the time scale sqrt(P_t / (rho A l^2)) of eq 27.
    The spans' tension at rest varies over a tooth period with the wrapping length, and the
    polygon's moment arms are R1 cos(theta), |theta| <= pi/n_o, where eq 56 takes R1: so
    omega_m is compared at each angle with the span tension there, and omega_theta^2
    averaged over the tooth period (mean arm^2 = R1^2 (1 - (pi/n_o)^2/3), a 1 % effect)."""
    t2 = _t2()
    sc = _undamped_c1(modal_modes=2)
    m = sc.model()
    drive = m.drive
    R1 = drive.driven.pitch_radius
    l = drive.centre_distance
    rho, EA, J1 = t2["rhoA"], t2["EA"], t2["J1"]
    w_theta_sq = []
    for th in np.linspace(0, 2 * math.pi / drive.n_driver, 8, endpoint=False):
        u = Inputs(th, 0.0, 0.0)
        x = m.initial_state(u)
        ev = np.linalg.eigvals(_jacobian(m, x, u))
        assert np.max(np.abs(ev.real)) < 1e-6 * np.max(np.abs(ev.imag))   # undamped
        freqs = np.sort(ev.imag[ev.imag > 0])
        out = m.outputs(0.0, x, u)
        expected_modes = []
        for P in (out["tight_span.tension"], out["slack_span.tension"]):
            alpha, gamma = EA / P, P / EA
            scale = math.sqrt(P / (rho * l * l))
            for mode in (1, 2):
                expected_modes.append(mode * math.pi * math.sqrt(alpha * gamma) * scale)
        # the sprocket frequency is the one not matching a span mode
        matched = []
        for w in expected_modes:
            dist = np.abs(freqs - w)
            dist[matched] = np.inf
            k = int(np.argmin(dist))
            # l = |OC| (paper) versus the mean span length (model): 0.15 % for C1
            assert freqs[k] == pytest.approx(w, rel=3e-3)
            matched.append(k)
        rest = [f for i, f in enumerate(freqs) if i not in matched]
        assert len(rest) == 1
        w_theta_sq.append(rest[0] ** 2)
    P_t = t2["P_tot"] / 2
    alpha = EA / P_t
    J = J1 / (rho * l * R1 ** 2)
    omega_theta = math.sqrt(2 * alpha / J) * math.sqrt(P_t / (rho * l * l))
    assert math.sqrt(np.mean(w_theta_sq)) == pytest.approx(omega_theta, rel=0.015)


def test_transport_speed_lowers_modal_stiffness_as_eq_61():
    """At speed the modal stiffness is (alpha gamma - s^2)(m pi)^2 (eq 61): the block
    d(v_m')/d(q_m) of the Jacobian, with S the chain speed, at 400 rpm (Table 2's case)."""
    sc = _undamped_c1()
    m = sc.model()
    w1 = 400 * 2 * math.pi / 60
    th = 0.1
    rot = driven_rotation(m.drive, th, w1)
    u = Inputs(th, w1, 0.0)
    x = np.array([float(rot.driven_angle), float(rot.driven_speed), 0.0, 0.0, 0.0, 0.0])
    J = _jacobian(m, x, u)
    out = m.outputs(0.0, x, u)
    rho = _t2()["rhoA"]
    S_chain = m.drive.n_driver * m.drive.pitch * w1 / (2 * math.pi)
    lbar = m.reference["l_up"]
    # the upper span's tension (the material tension: centrifugal tension included), whichever
    # of the two outputs reports it (the tight span is the one with the larger tension)
    l_up = float(chain_geometry(m.drive, np.array([th]), np.array([x[0]])).upper.length[0])
    up = out["tight_span.length"] == pytest.approx(l_up, rel=1e-12)
    P = out["tight_span.tension"] if up else out["slack_span.tension"]
    expected = (P - rho * S_chain ** 2) / rho * (math.pi / lbar) ** 2
    assert -J[4, 2] == pytest.approx(expected, rel=1e-5)
    assert rho * S_chain ** 2 / P > 0.01   # the s^2 term is visible at this speed


def test_galerkin_coefficients_against_quadrature():
    """G_m, E_m of eq 59 and the gyroscopic C_mn as 2 int_0^1 projections (trapezoid rule)."""
    n = 4
    c = galerkin_coefficients(n)
    x = np.linspace(0, 1, 200001)
    for m in range(1, n + 1):
        phi = np.sin(m * np.pi * x)
        assert c["G"][m - 1] == pytest.approx(2 * np.trapezoid(phi, x), abs=1e-9)
        assert c["E"][m - 1] == pytest.approx(2 * np.trapezoid(x * phi, x), abs=1e-9)
        for k in range(1, n + 1):
            proj = 2 * np.trapezoid(phi * k * np.pi * np.cos(k * np.pi * x), x)
            assert c["C"][m - 1, k - 1] == pytest.approx(proj, abs=1e-8)
    np.testing.assert_allclose(c["C"], -c["C"].T)       # skew-symmetric (gyroscopic)


def _endpoint_jump(impulse: bool):
    """dq_m/dt of the tight span just before and just after a roller seats on the driver
    (driver rotation 0 is the seating instant of the reference configuration)."""
    sc = chainmodel.Scene.from_preset("C1", fidelity=2, modal_modes=3, gravity=0.0,
                                      modal_impulse_forcing=impulse)
    m = sc.model()
    w1 = 400 * 2 * math.pi / 60
    rates = []
    for th in (-1e-7, 1e-7):
        rot = driven_rotation(m.drive, th, w1)
        x = np.array([float(rot.driven_angle), float(rot.driven_speed)] + [0.0] * 12)
        rates.append(m.rhs(0.0, x, Inputs(th, w1, 0.0))[2:5])
    return m, w1, rates[1] - rates[0]


def test_seating_impulse_is_eq_64():
    """Impulse-train option: at a seating on the driver the modal velocity jumps by
    -E_m Q2 with Q2 = S p / R2 (eqs 64-65), S the chain speed."""
    m, w1, jump = _endpoint_jump(True)
    S_chain = m.drive.n_driver * m.drive.pitch * w1 / (2 * math.pi)
    Q2 = S_chain * m.drive.pitch / m.drive.driver.pitch_radius
    E = galerkin_coefficients(3)["E"]
    np.testing.assert_allclose(jump, -E * Q2, rtol=1e-6)


def test_kinematic_endpoint_jump_is_the_chord_velocity_change():
    """Kinematic endpoint motion (default): at seating the driver-side endpoint's transverse
    velocity jumps by w1 R2 (cos(pi/2 - a - d) - cos(pi/2 + a - d)) = 2 w1 R2 sin a cos d,
    a = pi/n_c and d the span's angle to its mean direction (< 0.2 % here)."""
    m, w1, jump = _endpoint_jump(False)
    a = math.pi / m.drive.n_driver
    dq = 2 * w1 * m.drive.driver.pitch_radius * math.sin(a)
    E = galerkin_coefficients(3)["E"]
    np.testing.assert_allclose(jump, -E * dq, rtol=2e-3)


def test_static_sag_matches_the_string_formula():
    """Gravity only: the modes' midspan deflection at rest against the sag of a string,
    rho A g l^2 / (8 T) (level 1's quasi-static estimate); the one-mode Galerkin gives
    4/pi^3 instead of 1/8 (+3.2 %), more modes converge to it."""
    for modes, tol in ((1, 0.04), (5, 0.005)):
        sc = chainmodel.Scene.from_preset("xu2010", fidelity=2, modal_modes=modes)
        m = sc.model()
        u = Inputs(0.0, 0.0, 1.0)     # a small load makes the upper span the tight one
        x = m.initial_state(u)
        out = m.outputs(0.0, x, u)
        rho = sc.parameters["chain.link_mass"] / sc.drive.pitch
        l = m.reference["l_up"]
        # (the initial state's modes hold the sag at the tension the span holds at rest)
        sag = rho * 9.81 * l * l / (8 * out["tight_span.tension"])
        assert out["tight_span.midspan_deflection"] == pytest.approx(-sag, rel=tol)


@pytest.fixture(scope="module")
def short_12b(tmp_path_factory):
    """A 12B 8/16 drive of 32 links without pretension (an independent audit's, twenty-sixth
    session of issue 21): its path length swings over a driver tooth, and its chain hangs on
    tens of newtons."""
    from chainmodel.new_scene import scene_text
    path = tmp_path_factory.mktemp("rest") / "12b.toml"
    path.write_text(scene_text(8, 16, 5.0, 0.0, chain="12B", links=32, static_tension=0.0))
    return str(path)


def test_rest_is_an_equilibrium_with_each_string_at_its_own_sag(short_12b):
    """At four driver positions over a tooth, level 2's rest has no acceleration in any
    coordinate, and each string hangs at the sag of the tension its span holds there (the
    string formula as above, one mode's 4/pi^3 against 1/8). With each string held at the
    sag of the tooth-period-mean tension instead, the sprockets' equilibrium left the spans on
    0.16 N at two positions, accelerations up to 36 m/s^2."""
    sc = chainmodel.scene.load_scene(short_12b, fidelity=2)
    m = sc.model()
    rho = sc.parameters["chain.link_mass"] / sc.drive.pitch
    l = m.reference["l_up"]
    for k in range(4):
        # 0.05 N m makes the upper span the tight one (the one whose sag is an output)
        u = Inputs(2 * math.pi / sc.drive.n_driver * k / 4, 0.0, 0.05)
        x = m.initial_state(u)
        assert np.max(np.abs(m.rhs(0.0, x, u))) < 1e-5, k
        out = m.outputs(0.0, x, u)
        t = out["tight_span.tension"]
        assert out["tight_span.midspan_deflection"] == pytest.approx(
            -rho * 9.81 * l * l / (8 * t), rel=0.04), (k, t)


def test_runs_and_reports_midspan_from_modes():
    r = chainmodel.simulate("C1", fidelity="modal", duration=0.05, output_interval=1e-3)
    assert MODEL_CLASSES[2] is ModalModel
    for name in r.names:
        assert np.all(np.isfinite(r[name])), name
    assert "quasi-static" not in r.descriptions["tight_span.midspan_deflection"]
    assert np.ptp(r["tight_span.midspan_deflection"]) > 0


def test_slack_span_without_pretension_is_refused():
    """Without gravity a chain nowhere stretched has no tension at rest, so no string
    stiffness; with gravity it carries its sag tension (tests/test_span_sag.py) and runs."""
    loose = chainmodel.Drive.from_links(25, 17, 0.015875, 46, tight_at="max")
    with pytest.raises(ValueError, match="chain.pretension"):
        chainmodel.simulate("xu2010", fidelity=2, duration=0.01, gravity=0.0,
                            drive_centre_distance=loose.centre_distance)
    r = chainmodel.simulate("xu2010", fidelity=2, duration=0.01,
                            drive_centre_distance=loose.centre_distance)
    assert r.static_tension > 0.0
    # level 1 runs the same slack chain (its spans may go slack)
    chainmodel.simulate("xu2010", fidelity=1, duration=0.01,
                        drive_centre_distance=loose.centre_distance)


@pytest.mark.parametrize("modes", [0, -1, 2.5, "two", 21])
def test_nonsense_mode_counts_are_refused(modes):
    with pytest.raises(ValueError, match="modal.modes"):
        chainmodel.Scene.from_preset("C1", fidelity=2, modal_modes=modes)
    sc = chainmodel.Scene.from_preset("C1", fidelity=2)
    with pytest.raises(ValueError, match="modal.modes"):
        ModalModel(sc.drive, dict(sc.parameters, **{"modal.modes": modes}))


def test_negative_damping_ratio_is_refused():
    with pytest.raises(ValueError, match="modal.damping_ratio"):
        chainmodel.Scene.from_preset("C1", fidelity=2, modal_damping_ratio=-0.1)


def test_more_modes_run_with_the_gyroscopic_coupling():
    """Three modes per span at speed: runs, and the coupled modal energy stays bounded."""
    r = chainmodel.simulate("C1", fidelity=2, modal_modes=3, duration=0.1, output_interval=1e-3)
    assert np.max(np.abs(r["tight_span.midspan_deflection"])) < 0.01


@pytest.fixture(scope="module")
def equal_teeth(tmp_path_factory):
    """Equal-tooth drives without pretension (an independent audit's, twenty-seventh session):
    under load their slack span starts at 1e-15 N with the strings at the held tension's sag,
    where the Jacobian is singular."""
    from chainmodel.new_scene import scene_text
    root = tmp_path_factory.mktemp("equal")
    paths = {}
    for chain, z in (("08B", 12), ("16B", 8)):
        paths[chain] = root / f"{chain}.toml"
        paths[chain].write_text(scene_text(z, z, 5.0, 0.0, chain=chain, static_tension=0.0))
    return {k: str(v) for k, v in paths.items()}


@pytest.mark.parametrize("chain, torque", [("08B", 5.0), ("08B", 40.0), ("16B", 80.0)])
def test_a_loaded_rest_without_pretension_is_an_equilibrium(equal_teeth, chain, torque):
    """Under load, at four driver positions: no acceleration in any coordinate, the slack span
    carrying tension (its string hangs on it), and no fallback reported. Before, each was a
    silent fallback (accelerations 38-1600 m/s^2); the 16B drive at 80 N m needs the load in
    steps from the unloaded rest."""
    sc = chainmodel.scene.load_scene(equal_teeth[chain], fidelity=2)
    m = sc.model()
    for k in range(4):
        u = Inputs(2 * math.pi / sc.drive.n_driver * k / 4, 0.0, torque)
        x = m.initial_state(u)
        assert m.start_fallback is None, k
        assert np.max(np.abs(m.rhs(0.0, x, u))) < 1e-5, k
        assert m.outputs(0.0, x, u)["slack_span.tension"] > 1.0, k


def test_a_rest_not_found_is_said(monkeypatch):
    """Where the steps find no rest (forced here: no steps allowed), the run says so
    (start_not_at_rest), and the breaking-load check does not call it an unloaded start."""
    from chainmodel.models import modal
    monkeypatch.setattr(modal, "REST_ITERATIONS", 0)
    r = chainmodel.simulate("xu2010", fidelity=2, duration=0.02)
    found = {p.code: p.message for p in r.problems}
    assert "start_not_at_rest" in found and "level 2 found no rest" in found["start_not_at_rest"]
    assert "start_unloaded" not in found


def test_a_rest_beyond_the_string_model_is_refused():
    """xu2010 under 900 N m: the slack span's string would rest deeper than a tenth of the
    span, where the string model holds and the run's own check stops it; refused at the start
    naming the load, where before the run stopped at its first step blaming the meshing."""
    sc = chainmodel.Scene.from_preset("xu2010", fidelity=2, load_torque=900.0)
    m = sc.model()
    limit = 0.1 * min(m.reference["l_up"], m.reference["l_low"])
    with pytest.raises(ValueError, match=r"load.torque = 900 N.m.*beyond"):
        m.initial_state(Inputs(0.0, 0.0, 900.0))
    u = Inputs(0.0, 0.0, 600.0)
    x = m.initial_state(u)
    assert np.max(np.abs(x[m.n_sprocket_states:m.n_sprocket_states + 2 * m.n_modes])) < limit
