"""Level 1's lagged sag (torsional.sag_lag; kernels/spans.py ``_lagged``, docs/reduced_models.md
"Level 1's lagged sag"), against computations written here:

* the law's root (the wrap's floor and the elastic catenary in one equation) against a
  bracketing root finder, and the change of variables the state uses (T_q and the lagged
  elastic tension r = T_q - b^2 / T_q - k S / T_q^2) both ways;
* at rest, slowly, a span is the elastic catenary: its stiffness against the driven
  sprocket's rotation is the elastic one over 1 + 2 k S / T^3 (Ernst's equivalent modulus,
  the tangent of T^3 - T_raw T^2 - k S = 0), while with the sag frozen (faster than it
  follows) it is the elastic one: the mode sees the links, the mean sees the sag;
* the sag's state relaxes at the span's first string frequency pi / L sqrt(T / rho) (a taut
  string's, seed 004 eq 61 at rest), and after a load step a slack span hangs on its new sag
  within a few tenths of a second, as level 3's does, not seconds;
* plain and compiled kernels agree on it (tests/test_twins.py runs the levels both ways).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from chainmodel.kernels import spans as S
from chainmodel.models import Inputs
from chainmodel.scene import load_scene

SAGGING_08B = """
name = "08B 13/39, no pretension"
chain = "08B"
fidelity = "torsional"
[operating]
input_speed_rpm = 300.0
load_torque = 8.0
[parameters]
"chain.pretension" = 0.0
"drive.driver_teeth" = 13
"drive.driven_teeth" = 39
"drive.links" = 108
"drive.centre_distance" = 0.0
"""


def _root(raw, floor, ks):
    """T > 0 with T - floor^2 / T - ks / T^2 = raw, by brentq on a bracket written here."""
    def g(t):
        return t - floor * floor / t - ks / (t * t) - raw
    hi = abs(raw) + floor + ks ** (1.0 / 3.0) + 1.0
    lo = 1e-12
    while g(lo) > 0:
        lo *= 0.1
    return brentq(g, lo, hi, xtol=1e-15, rtol=1e-15)


@pytest.mark.parametrize("fn", [S._floored_sag, S._floored_sag.py_func],
                         ids=["compiled", "plain"])
def test_the_laws_root_against_a_bracketing_solver(fn):
    rng = np.random.default_rng(3)
    for _ in range(400):
        raw = rng.uniform(-2000.0, 3000.0)
        floor = rng.choice([0.0, rng.uniform(0.1, 300.0)])
        ks = rng.choice([0.0, 10 ** rng.uniform(2.0, 9.0)])
        if floor == 0.0 and ks == 0.0:
            assert fn(raw, floor, ks) == max(raw, 0.0)
            continue
        # (without a floor: the elastic catenary's own loop-free root, within 3e-10)
        assert fn(raw, floor, ks) == pytest.approx(_root(raw, floor, ks), rel=1e-9)


def test_the_laws_root_is_its_inverse():
    """The state r is a lagged elastic tension; the quasi-static law at r = T - b^2 / T -
    k S / T^2 gives T back, over tensions from 1 N to 3 kN."""
    rng = np.random.default_rng(5)
    for _ in range(200):
        tq = 10 ** rng.uniform(0.0, 3.5)
        floor = rng.choice([0.0, rng.uniform(1.0, 200.0)])
        ks = 10 ** rng.uniform(3.0, 9.0)
        r = tq - floor * floor / tq - ks / tq ** 2
        assert S._floored_sag(r, floor, ks) == pytest.approx(tq, rel=1e-9)


def _sagging_model(tmp_path, **kw):
    path = tmp_path / "sagging.toml"
    path.write_text(SAGGING_08B)
    return load_scene(str(path), fidelity=1, **kw).model()


@pytest.mark.parametrize("wrap", [False, True], ids=["seat_ladder", "wrap_statics"])
def test_slow_stiffness_is_ernsts_and_fast_the_elastic(tmp_path, wrap):
    """At rest, the driven sprocket turned by a small angle: with the sags re-settled (the
    quasi-static law) the upper span's tension moves by the elastic change over
    1 + 2 k S / T^3 (+ the floor's slope on the wrap), with the sags frozen by the elastic
    change through the floor alone - Ernst's modulus written here from the span's own S and
    k_eff."""
    m = _sagging_model(tmp_path, torsional_wrap_statics=wrap)
    assert m.lag
    u = Inputs(0.0, 0.0, 0.0)
    x0 = m.initial_state(u)
    P = m.P
    ks = P[S.P_SAG_U] * P[S.P_KEFF_U]
    b = P[S.P_SOFT]

    def upper(x, params):
        dx, aux = np.empty(m.n_states), np.empty(S.A_SIZE)
        S.evaluate(x, 0.0, 0.0, 0.0, 0.0, m.G, params, dx, aux)
        return aux[S.A_T_UP], aux

    t0, aux0 = upper(x0, P)
    assert x0[-2] == pytest.approx(aux0[S.A_LAG_UP], rel=1e-12)   # the state at rest
    h = 1e-6
    x_plus, x_minus = x0.copy(), x0.copy()
    x_plus[1] += h
    x_minus[1] -= h
    quasi = P.copy()
    quasi[S.P_LAG_QS] = 1.0
    fast = (upper(x_plus, P)[0] - upper(x_minus, P)[0]) / (2 * h)
    slow = (upper(x_plus, quasi)[0] - upper(x_minus, quasi)[0]) / (2 * h)
    # elastic change of the raw tension per radian, from the floor's slope s at t0:
    # dT = s d(raw + sag offset), with the sag offset frozen (fast) or following (slow)
    r_sum = t0 - b * b / t0              # raw + offset at rest, through the floor's inverse
    s = 1.0 if b == 0 else 0.5 * (1.0 + r_sum / math.sqrt(r_sum ** 2 + 4 * b * b))
    d_raw = fast / s
    ernst = 1.0 + 2.0 * ks / t0 ** 3 + (b * b / t0 ** 2 if b > 0 else 0.0)
    assert 2.0 * ks / t0 ** 3 > 0.5          # a span that hangs on its sag: a real effect
    assert slow == pytest.approx(d_raw / ernst, rel=1e-5)
    assert abs(fast) > 1.5 * abs(slow)


def test_the_sag_relaxes_at_the_first_string_frequency(tmp_path):
    """d(dT_q/dt)/dT_q at rest is -pi / L sqrt(T / rho): the sag follows the span at its first
    string frequency (the span's tooth-period-mean length L, its tension at rest, rho its mass
    per length, written here; spans.LAG_RATE); at rest the sag has followed and is still."""
    m = _sagging_model(tmp_path)
    u = Inputs(0.0, 0.0, 0.0)
    x0 = m.initial_state(u)
    rho = m.params["chain.link_mass"] / m.drive.pitch
    dx, aux = np.empty(m.n_states), np.empty(S.A_SIZE)
    S.evaluate(x0, 0.0, 0.0, 0.0, 0.0, m.G, m.P, dx, aux)
    for k, length, t in ((-2, m.reference["l_up"], aux[S.A_T_UP]),
                         (-1, m.reference["l_low"], aux[S.A_T_LOW])):
        h = 1e-6 * max(abs(x0[k]), 1.0)
        xp, xm = x0.copy(), x0.copy()
        xp[k] += h
        xm[k] -= h
        rate = (m.rhs(0.0, xp, u)[k] - m.rhs(0.0, xm, u)[k]) / (2 * h)
        assert rate == pytest.approx(-math.pi / length * math.sqrt(t / rho), rel=1e-5)
        assert abs(m.rhs(0.0, x0, u)[k]) < 1e-9 * t      # at rest it has followed


def test_a_span_that_suddenly_goes_slack_stays_finite(tmp_path):
    """A span whose ends jump together faster than its sag follows goes slack and picks up
    again as the sag deepens, without a tension spike: the state (a lagged elastic tension)
    may overshoot its target inside a step, the sag's tension stays positive and bounded.
    (With the sag's tension itself as the state, a stage below zero made an unbounded sag: C1
    at a sudden 400 rpm diverged to 1e26 N.)"""
    import chainmodel
    r = chainmodel.simulate("C1", fidelity=1, input_speed_rpm=400.0, ramp_time=0.0,
                            duration=0.3, output_interval=1e-3)
    for name in ("tight_span.tension", "slack_span.tension"):
        assert np.all(np.isfinite(r[name])) and np.all(r[name] >= 0.0)
    assert float(np.max(r["tight_span.tension"])) < 0.5 * r.scene.parameters["chain.breaking_load"]


def test_without_gravity_or_with_the_option_off_there_is_no_lag_state(tmp_path):
    assert not _sagging_model(tmp_path, gravity=0.0).lag
    m = _sagging_model(tmp_path, torsional_sag_lag=False)
    assert not m.lag and m.n_states == 4 and m.second_order
    assert _sagging_model(tmp_path).n_states == 6


def test_a_load_step_is_followed_within_tenths_of_a_second(tmp_path):
    """An independent audit's 10B 17/34 drive with no pretension at 400 rpm, its load stepped
    from 30 to 90 N m at 1 s through the stepper: level 3's slack span carries 34-40 N within
    0.1 s. Level 1's sag follows at the spans' string frequency: over 0.2-0.5 s after the step
    its slack span is within 20 % of its own constant-90-N m run (at an eighth of that
    frequency it stayed at 3.6 N for half a second and took seconds), and it never drops to
    zero while it does."""
    import chainmodel
    from chainmodel.new_scene import scene_text
    text = scene_text(driver_teeth=17, driven_teeth=34, chain="10B", speed_rpm=400.0,
                      load_torque=30.0, static_tension=0.0)
    path = tmp_path / "step.toml"
    path.write_text(text)
    sc = load_scene(str(path), fidelity=1)
    st = sc.stepper()
    dt, rows = 1e-4, []
    for i in range(1, 15001):
        t = i * dt
        u = sc.inputs(t - dt)
        out = st.advance(t, Inputs(u.angle, u.speed, 30.0 if t - dt < 1.0 else 90.0,
                                   u.acceleration))
        rows.append((t, out["slack_span.tension"]))
    rows = np.array(rows)
    const = chainmodel.simulate(str(path), fidelity=1, duration=1.5, load_torque=90.0)
    target = float(np.mean(const["slack_span.tension"][const.time >= 1.0]))
    after = rows[(rows[:, 0] >= 1.2) & (rows[:, 0] < 1.5), 1]
    assert float(np.mean(after)) == pytest.approx(target, rel=0.2)
    assert float(np.min(rows[rows[:, 0] >= 1.0, 1])) > 0.0



def test_a_sag_tension_through_zero_is_reported_not_returned(tmp_path):
    """T_q <= 0 has no meaning (the sag term k S / T_q^2 is unbounded there): the model's check
    refuses the state, naming the span and the option, where before a step that outran the
    lag's rate returned tensions of 1e24 N (C1 at a sudden 400 rpm through 10 ms
    communication steps; tests/test_step_independence.py now runs it)."""
    from chainmodel.models.base import SimulationDiverged
    m = _sagging_model(tmp_path)
    x = m.initial_state(Inputs(0.0, 0.0, 0.0)).copy()
    k = m.n_states - 2
    m.check(0.0, x)
    x[k + 1] = -3.0
    with pytest.raises(SimulationDiverged, match="lower span's sag tension.*sag_lag"):
        m.check(0.1, x)
    with pytest.raises(SimulationDiverged, match="lower span"):
        m.check_states(np.array([0.0, 0.1]), np.vstack([x, x]))
