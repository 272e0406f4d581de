"""Level 0, the kinematic model (models/kinematic.py): exact driven motion and quasi-static
(kinetostatic) span tensions and input torque.

What must hold (derived in docs/kinematics.md, "Level 0 forces"): with the driver rigid on the
input shaft (speed w1, acceleration a1), the driven motion (w2, a2) from the four-bar, span
tensions T_u, T_l acting through the moment arms of the span lines, the two torque balances

    driver:  tau_in = I1 a1 + T_u a_uC - T_l a_lC
    driven:  T_u a_uO - T_l a_lO = I2 a2 + d2 w2 + M_load

multiplied by w1 and w2 and subtracted give the power balance

    tau_in w1 = M_load w2 + d/dt (I1 w1^2 / 2 + I2 w2^2 / 2) + d2 w2^2
                + T_u dl_u/dt + T_l dl_l/dt,

because a span's length changes at dl/dt = w_end a_end - w_start a_start. The tight span is
rigid (dl/dt = 0, the four-bar), so only the slack span's stretching power remains. The test
checks it with finite differences of the kinetic energy and of the span lengths, none of which
the model uses.
"""

import math

import numpy as np
import pytest

import chainmodel
from chainmodel import kinematics as K
from chainmodel.geometry import Drive
from chainmodel.models import Inputs
from chainmodel.models.kinematic import KinematicModel, static_span_tension
from chainmodel.models.span_sag import hanging_tension
from chainmodel.parameters import defaults
from chainmodel.presets import reference_table

INCH = 0.0254


def _model(drive, **over):
    p = defaults()
    p.update(over)
    return KinematicModel(drive, p)


def _upper_lower(out, g, d, p):
    """(T_u, T_l) effective (elastic) tensions of the upper and lower span from the outputs:
    the tight span is the one whose length tight_span.length reports, and both spans carry
    the centrifugal tension rho A v^2 on top, v = n_c p w / 2 pi (docs/stability.md)."""
    upper = np.isclose(out["tight_span.length"], g.upper.length, rtol=1e-14, atol=0)
    rho_v2 = p["chain.link_mass"] / d.pitch * (d.n_driver * d.pitch * out["driver.speed"]
                                               / (2 * math.pi)) ** 2
    return (np.where(upper, out["tight_span.tension"], out["slack_span.tension"]) - rho_v2,
            np.where(upper, out["slack_span.tension"], out["tight_span.tension"]) - rho_v2)


# --- motion -----------------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["C1", "xu2010", "coarse", "A1"])
def test_driven_motion_is_driven_rotation(name):
    d = chainmodel.preset(name)
    m = _model(d)
    rng = np.random.default_rng(5)
    angle = rng.uniform(-4, 4, 300)
    speed = rng.uniform(-20, 20, 300)
    accel = rng.uniform(-100, 100, 300)
    out = m.evaluate(angle, speed, accel, 10.0)
    for rev in (False, True):
        sel = (speed < 0) == rev
        r = K.driven_rotation(d, angle[sel], speed[sel], accel[sel], reverse=rev)
        np.testing.assert_allclose(out["driven.angle"][sel], r.driven_angle, rtol=1e-14, atol=0)
        np.testing.assert_allclose(out["driven.speed"][sel], r.driven_speed, rtol=1e-14)
        np.testing.assert_allclose(out["driven.acceleration"][sel], r.driven_acceleration,
                                   rtol=1e-14)
        np.testing.assert_allclose(out["velocity_ratio"][sel], r.velocity_ratio, rtol=1e-14)
        # span roles by power flow (DESIGN.md): the upper span is tight where the torque
        # the chain must put on the driven sprocket at the mean motion, load + ratio (c2 w +
        # J2 a), is positive, the lower span where it is negative (the inertia torque of these
        # random accelerations overruns the load there)
        g = K.chain_geometry(d, angle[sel], r.driven_angle)
        winds = g.lower.length if rev else g.upper.length
        np.testing.assert_allclose(winds, r.span_length, rtol=1e-12)
        p = m.params
        moment = 10.0 + d.tooth_ratio * (p["driven.damping"] * speed[sel]
                                         + p["driven.inertia"] * accel[sel])
        want = np.where(moment > 0, g.upper.length, g.lower.length)
        np.testing.assert_allclose(out["tight_span.length"][sel], want, rtol=1e-14)
    np.testing.assert_array_equal(out["driver.angle"], angle)
    np.testing.assert_array_equal(out["driver.speed"], speed)
    np.testing.assert_allclose(out["transmission_error"],
                               out["driven.angle"] - d.tooth_ratio * angle, rtol=1e-14)


def test_negative_speed_runs_the_reverse_branch():
    """Level 0 uses the mirror-symmetric reverse kinematics when the input runs backwards: the
    driven speed follows the reversed (lower-span) four-bar, not the forward one."""
    d = chainmodel.preset("C1")
    m = _model(d)
    angle = np.linspace(0.01, 1.0, 50)
    out = m.evaluate(angle, -10.0, 0.0, 0.0)
    rev = K.driven_rotation(d, angle, -10.0, reverse=True)
    fwd = K.driven_rotation(d, angle, -10.0, reverse=False)
    np.testing.assert_allclose(out["velocity_ratio"], rev.velocity_ratio, rtol=1e-14)
    assert np.max(np.abs(rev.velocity_ratio - fwd.velocity_ratio)) > 1e-3
    assert np.all(out["driven.speed"] < 0)
    # the step interface (outputs) takes the same branch
    o = m.outputs(0.0, np.empty(0), Inputs(angle=0.5, speed=-10.0))
    assert o["velocity_ratio"] == pytest.approx(
        float(K.driven_rotation(d, 0.5, -10.0, reverse=True).velocity_ratio), rel=1e-14)


# --- power balance ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["C1", "xu2010", "A1", "coarse"])
@pytest.mark.parametrize("w, a, load", [(12.0, 0.0, 40.0), (12.0, 80.0, 40.0),
                                        (8.0, -30.0, -15.0), (-10.0, 25.0, 30.0),
                                        (-6.0, -40.0, -20.0)])
def test_power_balance(name, w, a, load):
    d = chainmodel.preset(name)
    pre = 300.0
    if d.links is None:
        # a loose chain (no pretension: every level refuses a pre-strain on a slack chain)
        d = d.with_links(math.ceil(K.wrap_length_range(d)[2] / d.pitch))
        pre = 0.0
    m = _model(d, **{"driven.damping": 0.4, "chain.pretension": pre})
    p = m.params
    I1, I2, d2 = p["driver.inertia"], p["driven.inertia"], p["driven.damping"]
    P_c = 2 * math.pi / d.n_driver
    t_end = 3 * P_c / abs(w)
    if a * w < 0:               # decelerating: stop before the speed changes sign
        t_end = min(t_end, 0.5 * abs(w / a))
    t = np.linspace(0, t_end, 301) + 1e-4
    dt = 1e-6 * P_c / abs(w)

    def state(t):
        angle = 0.3 + w * t + 0.5 * a * t**2
        out = m.evaluate(angle, w + a * t, a, load)
        g = K.chain_geometry(d, angle, out["driven.angle"])
        return out, g

    (o, g0), (op, gp), (om, gm) = state(t), state(t + dt), state(t - dt)
    same = np.ones(t.shape, bool)
    for span in ("upper", "lower"):
        for field in ("seat_start", "seat_end"):
            for gg in (gp, gm):
                same &= getattr(getattr(gg, span), field) == getattr(getattr(g0, span), field)
    assert same.mean() > 0.9
    ke = lambda o: 0.5 * I1 * o["driver.speed"] ** 2 + 0.5 * I2 * o["driven.speed"] ** 2
    d_ke = (ke(op) - ke(om)) / (2 * dt)
    dl_u = (gp.upper.length - gm.upper.length) / (2 * dt)
    dl_l = (gp.lower.length - gm.lower.length) / (2 * dt)
    # which output is which span: the tight span is the one with the larger tension, its
    # length the output tight_span.length; the centrifugal tension rho A v^2 both carry on
    # top acts on no sprocket (docs/stability.md), so the balance takes it off
    T_u, T_l = _upper_lower(o, g0, d, p)
    w1, w2 = o["driver.speed"], o["driven.speed"]
    lhs = o["input_shaft.torque"] * w1
    rhs = load * w2 + d_ke + d2 * w2**2 + T_u * dl_u + T_l * dl_l
    scale = np.max(np.abs(load * w2)) + np.max(np.abs(d_ke)) + np.max(np.abs(T_l * dl_l))
    assert np.max(np.abs(lhs - rhs)[same]) < 1e-6 * scale
    # the tight span is rigid between events: no power goes into it
    # (the span of the four-bar: the one the driver winds on, lower in reverse)
    dl_four_bar = dl_l if w < 0 else dl_u
    assert np.max(np.abs(dl_four_bar[same])) < 1e-6 * d.pitch * abs(w)


# --- tension closure --------------------------------------------------------------------------

def test_symmetric_drive_unloaded_tensions_equal_static_tension():
    """n_c = n_o, f = 0: the chain of M = 46 links fits exactly (L = 2 x_c + 12 p = 46 p, seed
    004 Table 1 row B2 with f -> 0) and the two spans are mirror images with equal moment arms.
    With no load, no inertia and no damping both spans carry the static tension, which is the
    pretension alone (without gravity: the spans' weight adds its sag term, tests/test_span_sag.py).
    These are the seat ladder's closed forms, so the wrap fit (torsional.wrap_statics, level 3's
    statics: tests/test_wrap_statics.py) is off."""
    d = Drive(12, 12, INCH, 16, 0.0, links=46)
    ladder = {"torsional.wrap_statics": False}
    m = _model(d, **{"driver.inertia": 0.0, "driven.inertia": 0.0, "driven.damping": 0.0,
                     "chain.pretension": 800.0, "torsional.seat_compliance": False,
                     "gravity": 0.0}, **ladder)
    assert m.static_tension() == pytest.approx(800.0, rel=1e-9)
    # with the seats' ladder compliance and clearance in series (docs/reduced_models.md):
    # the pre-strain stretch X = 800 n / k_l is shared with two seat compliances 2/K per span
    # and reduced by two clearances per span; n = 2 (N + 1) = 34 span links here
    p = defaults()
    k_l, k_c = p["chain.link_stiffness"], p["contact.stiffness"]
    k_seat = (k_c + math.sqrt(k_c**2 + 4 * k_c * k_l)) / 2
    gap = p["contact.seat_radius"] - p["chain.roller_radius"]
    flex = 34 / k_l
    # the wrapped links carry their pre-strain less what sinking to the seat bottom (the
    # clearance, and the contact spring under 2 T sin(alpha)) takes off; the ladder at each
    # span end gives way to the span's tension minus theirs
    sa = math.sin(math.pi / 12)
    wrapped = max(0.0, (800.0 - 2 * k_l * gap * sa) / (1 + 4 * k_l * sa * sa / k_c))
    assert wrapped == 0.0     # here the clearance alone takes the pre-strain: loose in the seats
    wrapped_3k = (3000.0 - 2 * k_l * gap * sa) / (1 + 4 * k_l * sa * sa / k_c)
    stiff = _model(d, **{"chain.pretension": 3000.0, "torsional.seat_compliance": True,
                         "gravity": 0.0}, **ladder)
    assert stiff.static_tension() == pytest.approx(
        (3000.0 * flex - 2 * (2 * gap - 2 * wrapped_3k / k_seat)) / (flex + 4 / k_seat),
        rel=1e-9)
    expected = ((800.0 * flex - 2 * (2 * gap - 2 * wrapped / k_seat))
                / (flex + 2 * 2 / k_seat))
    soft = _model(d, **{"chain.pretension": 800.0, "torsional.seat_compliance": True,
                        "gravity": 0.0}, **ladder)
    assert soft.static_tension() == pytest.approx(expected, rel=1e-9)
    angle = np.linspace(-1, 1, 101)
    for speed, accel in ((10.0, 0.0), (10.0, 50.0), (-10.0, -50.0)):
        out = m.evaluate(angle, speed, accel, 0.0)
        v = 12 * INCH * speed / (2 * math.pi)          # chain speed; rho A v^2 on both spans
        centrifugal = p["chain.link_mass"] / INCH * v * v
        np.testing.assert_allclose(out["tight_span.tension"], 800.0 + centrifugal, rtol=1e-9)
        np.testing.assert_allclose(out["slack_span.tension"], 800.0 + centrifugal, rtol=1e-9)
        np.testing.assert_allclose(out["input_shaft.torque"], 0.0, atol=1e-9)


@pytest.mark.parametrize("sag", [False, True], ids=["no_sag", "sag"])
@pytest.mark.parametrize("name", ["C1", "xu2010", "A1"])
def test_unloaded_tensions_share_the_static_sum(name, sag):
    """No load, no inertia: the driven sprocket is free, so T_u a_uO = T_l a_lO, and the
    closure (seed 004 eqs 15-16 generalised) keeps T_u + T_l = 2 T0. With the spans' sag
    (torsional.sag_lag, the default; the seat ladder's law here) the closure is on the raw
    tensions T - k_eff S / T^2 (the elastic catenary inverted): their sum is the one at rest,
    2 T0 - sum k_eff S / T0^2, and T_u + T_l stays within the sag's share of it."""
    d = chainmodel.preset(name)
    m = _model(d, **{"driver.inertia": 0.0, "driven.inertia": 0.0, "driven.damping": 0.0,
                     "torsional.sag_lag": sag})
    angle = np.linspace(0, 2 * math.pi / d.n_driver, 200)
    out = m.evaluate(angle, 10.0, 0.0, 0.0)
    g = K.chain_geometry(d, angle, out["driven.angle"])
    T_u, T_l = _upper_lower(out, g, d, m.params)
    t0 = m.static_tension()
    ks_u, ks_l = m._sag_ks
    assert (ks_u > 0 and ks_l > 0) == sag
    np.testing.assert_allclose(T_u - ks_u / T_u ** 2 + T_l - ks_l / T_l ** 2,
                               2 * t0 - (ks_u + ks_l) / t0 ** 2, rtol=1e-12)
    np.testing.assert_allclose(T_u + T_l, 2 * t0, rtol=1e-12 if not sag else
                               (ks_u + ks_l) / t0 ** 3)
    np.testing.assert_allclose(T_u * g.upper.arm_start, T_l * g.lower.arm_end, rtol=1e-12)


@pytest.mark.parametrize("wrap", [False, True], ids=["seat_ladder", "wrap_statics"])
@pytest.mark.parametrize("load", [-1e5, -300.0, -1.0, 0.0, 1.0, 300.0, 1e5])
@pytest.mark.parametrize("speed", [10.0, -10.0])
def test_spans_never_push(load, speed, wrap):
    _spans_never_push(load, speed, wrap, sag=False)


@pytest.mark.parametrize("load", [-1e5, -300.0, 0.0, 300.0, 1e5])
def test_spans_never_push_and_hang_on_their_sag(load):
    """With the spans' sag (torsional.sag_lag, the default) on the seat ladder: the torque
    balance as without it, and a span the load would take to zero hangs on its sag instead
    (above 0, below what it holds at rest)."""
    _spans_never_push(load, 10.0, False, sag=True)


def _spans_never_push(load, speed, wrap, sag):
    """Tensions are never negative, whatever the load torque's sign; when one span would have
    to push it goes slack (zero on the seat ladder's linear law; under the wrap fit's floor b
    it sits on the floor's knee, above 0 and below b) and the other takes the whole torque,
    and the driven sprocket's torque balance still holds. (xu2010: with these defaults its
    wrap fit has a floor; C1's, with no pretension, has none since the held tension.)"""
    d = chainmodel.preset("xu2010")
    m = _model(d, **{"driven.damping": 0.2, "torsional.wrap_statics": wrap,
                     "torsional.sag_lag": sag})
    if wrap:
        assert m._floor > 0.0
    p = m.params
    angle = np.linspace(0, 2 * math.pi / d.n_driver, 120)
    out = m.evaluate(angle, speed, 30.0, load)
    T_t, T_s = out["tight_span.tension"], out["slack_span.tension"]
    assert np.all(T_t >= 0) and np.all(T_s >= 0)
    g = K.chain_geometry(d, angle, out["driven.angle"])
    T_u, T_l = _upper_lower(out, g, d, p)
    # span roles by power flow: the upper span is the tight one where the mean transmitted
    # torque load + ratio (c2 w + J2 a) is positive (DESIGN.md)
    moment = load + d.tooth_ratio * (p["driven.damping"] * speed + p["driven.inertia"] * 30.0)
    assert np.all(np.isclose(out["tight_span.length"], g.upper.length, rtol=1e-14, atol=0)
                  == (moment > 0))
    assert np.all(T_u >= 0) and np.all(T_l >= 0)
    torque = (p["driven.inertia"] * out["driven.acceleration"]
              + p["driven.damping"] * out["driven.speed"] + load)
    np.testing.assert_allclose(T_u * g.upper.arm_start - T_l * g.lower.arm_end, torque,
                               rtol=1e-10, atol=1e-9)
    if abs(load) >= 300 and sag:          # beyond what 2 T0 can split: one span on its sag
        lesser = T_u if load < 0 else T_l
        assert np.all(lesser > 0) and np.all(lesser < m.static_tension())
    elif abs(load) >= 300 and not wrap:   # beyond what 2 T0 can split: one span slack
        # (zero up to the rounding of taking rho A v^2 off the outputs, and the weight along
        # it: span_sag.hanging_tension, about 0.1 N on xu2010's slightly rising spans)
        hang = hanging_tension(d, p)
        assert 0.0 < hang < 1.0
        slack_u, slack_l = np.abs(T_u - hang) < 1e-9, np.abs(T_l - hang) < 1e-9
        assert np.all(slack_u | slack_l)
        assert np.all(slack_u == (load < 0))
    elif abs(load) >= 300:
        lesser = T_u if load < 0 else T_l
        assert np.all(lesser > 0) and np.all(lesser < m._floor)


# --- static tension ---------------------------------------------------------------------------

def test_static_tension_without_links_is_the_pretension():
    d = chainmodel.preset("medium", links=None)
    p = defaults()
    p["chain.pretension"] = 123.0
    assert static_span_tension(d, p) == 123.0


def test_static_tension_from_span_stretch():
    """Rigid seats, elastic span links: the excess wrapping length L - M p (seed 004 section
    2) stretches the n_u + n_l span links. For n_c = n_o = 12, N = 16, f = 0.001 and M = 46,
    L = 46 p + 2 f p (the B2 row of Table 1: 46.0048 at f = 0.0024) spread over 17 + 17
    links, so T0 = pretension + k 2 f p / 34."""
    d = Drive(12, 12, INCH, 16, 0.001, links=46)
    p = defaults()
    p["chain.pretension"] = 100.0
    p["torsional.seat_compliance"] = False       # rigid seats, as stated
    k = p["chain.link_stiffness"]
    assert static_span_tension(d, p) == pytest.approx(100.0 + k * 2 * 0.001 * INCH / 34,
                                                      rel=1e-6)


def test_static_tension_c1_within_table1_bounds():
    """C1 with M = 40 (seed 004 Table 1): the stretch lies between L_min - M p = 0.0040 p and
    L_max - M p = 0.0149 p, spread over the span links."""
    row = next(r for r in reference_table("wrap_length_jsv2016_table1.csv") if r["id"] == "C1")
    d = chainmodel.preset("C1")
    p = defaults()
    p["torsional.seat_compliance"] = False       # the rigid-seat bound
    k = p["chain.link_stiffness"]
    phi = np.linspace(0, 2 * math.pi / d.n_driver, 100, endpoint=False)
    g = K.chain_geometry(d, phi, K.driven_rotation(d, phi).driven_angle)
    n = g.upper_links + g.lower_links
    lo = k * (float(row["L_min_over_p"]) - 40) * INCH / n.max()
    hi = k * (float(row["L_max_over_p"]) - 40) * INCH / n.min()
    T0 = static_span_tension(d, p)
    assert lo < T0 < hi
    # and close to the mean stretch over the mean span-link count
    mean = k * (float(row["L_mean_over_p"]) - 40) * INCH / n.mean()
    assert T0 == pytest.approx(mean, rel=0.05)


# --- the scalar compiled evaluation (kernels/kinematic.py) --------------------------------

@pytest.mark.parametrize("wrap", [False, True], ids=["seat_ladder", "wrap_statics"])
@pytest.mark.parametrize("name", ["xu2010", "C1", "coarse", "fine"])
def test_scalar_kernel_equals_the_vectorised_library(name, wrap):
    """The FMU's one-sample evaluation (compiled, and its plain-Python twin ``.py_func``) gives
    the vectorised KinematicModel.evaluate's outputs to 1e-12 at many random angles, speeds of
    both signs (forward and reverse branches), accelerations and loads."""
    from chainmodel.models import ALL_OUTPUTS
    from chainmodel.kernels.kinematic import level0_outputs
    m = chainmodel.Scene.from_preset(name, fidelity=0, torsional_wrap_statics=wrap).model()
    # `coarse` holds level 3's tooth-period mean, 1286 N against 500 N at angle 0, under a
    # floor; `fine`'s wrap (refused until it was fitted with its spans' sag) too
    assert (m._floor > 0) == wrap
    rng = np.random.default_rng(7)
    n = 400
    angle = rng.uniform(-60, 60, n)
    speed = rng.uniform(-40, 40, n)
    speed[:4] = (0.0, -0.0, 1e-300, -1e-300)
    # loads up to three times what the static tension sum carries: one span goes slack
    acc = rng.uniform(-200, 200, n)
    load = rng.uniform(-3, 3, n) * 2 * m.static_tension() * m.drive.driven.pitch_radius
    ref = m.evaluate(angle, speed, acc, load)
    K_, G, C = m._kernel_constants
    out = np.empty(len(ALL_OUTPUTS))
    assert np.any(speed < 0)
    if m._floor > 0 or max(m._sag_ks) > 0:   # the floor's knee or the sag: never 0
        assert np.all(ref["slack_span.tension"] > 0.0)
    else:
        assert np.any(ref["slack_span.tension"] == 0.0)
    for fn in (level0_outputs, level0_outputs.py_func):
        for i in range(n):
            assert fn(angle[i], speed[i], acc[i], load[i], K_, G, C, out) is True
            for k, spec in enumerate(ALL_OUTPUTS):
                assert out[k] == pytest.approx(ref[spec.name][i], rel=1e-12, abs=1e-12), \
                    (spec.name, i)


def test_scalar_rotation_equals_driven_rotation_over_many_periods():
    """kernels.kinematic.driven_rotation against kinematics.driven_rotation, forward and reverse,
    on a fine grid over several tooth periods (seating and release inside) and at the event
    angles themselves."""
    from chainmodel.kernels.kinematic import driven_rotation, fourbar_constants
    drive = chainmodel.Scene.from_preset("xu2010").drive
    Kc = fourbar_constants(drive)
    period = 2 * math.pi / drive.n_driver
    phi = np.concatenate([np.linspace(-3 * period, 3 * period, 2001),
                          np.arange(-3, 4) * period])
    for reverse in (False, True):
        ref = K.driven_rotation(drive, phi, 11.0, -3.0, reverse=reverse)
        got = np.array([driven_rotation(p, 11.0, -3.0, reverse, Kc) for p in phi])
        for k, field in enumerate(("driven_angle", "driven_speed", "driven_acceleration",
                                   "velocity_ratio", "span_length")):
            np.testing.assert_allclose(got[:, k], getattr(ref, field), rtol=1e-12, atol=1e-12,
                                       err_msg=f"{field}, reverse={reverse}")


# --- the floored split (torsional.wrap_statics) -----------------------------------------------

def _floored(raw, b):
    return 0.5 * (raw + math.sqrt(raw * raw + 4 * b * b))


def _split_by_bisection(total, b, a_pull, a_back, load):
    """Written apart from kernels.kinematic.split: T_back such that the floored tensions of the
    raw pair (total - r, r) balance the load, by bisection on the raw tension r."""
    lo, hi = -1e7, 1e7
    for _ in range(200):
        r = 0.5 * (lo + hi)
        if _floored(total - r, b) * a_pull - _floored(r, b) * a_back > load:
            lo = r
        else:
            hi = r
    r = 0.5 * (lo + hi)
    return _floored(total - r, b), _floored(r, b)


@pytest.mark.parametrize("fn", ["compiled", "plain"])
def test_floored_split_balances_the_torque_and_keeps_the_raw_sum(fn):
    from chainmodel.kernels.kinematic import split
    f = split if fn == "compiled" else getattr(split, "py_func", split)
    rng = np.random.default_rng(3)
    for _ in range(300):
        total, b = rng.uniform(-500, 3000), rng.uniform(1.0, 400.0)
        a_pull, a_back = rng.uniform(0.03, 0.2, 2)
        load = rng.uniform(-300, 300)
        tp, tb = f(total, b, a_pull, a_back, load)
        assert tp > 0 and tb > 0                          # the floor: no span goes slack
        assert tp * a_pull - tb * a_back == pytest.approx(load, abs=1e-9 * (1 + abs(load)))
        assert (tp - b * b / tp) + (tb - b * b / tb) == pytest.approx(total, abs=1e-7 * (1 + abs(total)))
        ref = _split_by_bisection(total, b, a_pull, a_back, load)
        assert (tp, tb) == pytest.approx(ref, rel=1e-7, abs=1e-7)
        # no floor: seed 004 eqs 15-16, the sum kept and a span that would push at 0
        lp, lb = f(total, 0.0, a_pull, a_back, load)
        if lp > 0 and lb > 0:
            assert lp + lb == pytest.approx(total) and lp * a_pull - lb * a_back == pytest.approx(load)
        # a vanishing floor tends to it
        sp, sb = f(total, 1e-6, a_pull, a_back, load)
        assert (sp, sb) == pytest.approx((lp, lb), abs=1e-3)


def test_level0_on_the_wrap_is_level1_running_slowly():
    """A limit case: at 120 rpm xu2010's meshing frequency (50 Hz) is a twelfth of its 600 Hz
    torsional mode, so level 1 runs quasi-statically on its span law; level 0 with the same
    static tension and floor (torsional.wrap_statics) gives the same mean span tensions
    (within 2 %), where the linear split left the slack span at a quarter of it."""
    means = []
    for level in (0, 1):
        r = chainmodel.simulate("xu2010", fidelity=level, duration=0.6, output_interval=2e-4)
        m = r.time >= 0.3
        means.append((r["tight_span.tension"][m].mean(), r["slack_span.tension"][m].mean()))
    assert means[0] == pytest.approx(means[1], rel=0.02)


@pytest.mark.parametrize("floor,ks", [(0.0, 0.0), (40.0, 0.0), (0.0, 5e4)])
def test_no_span_below_the_hanging_floor_and_the_torque_balance_kept(floor, ks):
    """Level 0's split with the weight along the spans (span_sag.hanging_tension) as a floor:
    over loads of both signs, from none to far beyond what the spans' sum can split, neither
    span is below the floor, the driven sprocket's balance T_pull a_pull - T_back a_back =
    load holds, and where both spans were above it the split is the one without it."""
    from chainmodel.models.kinematic import split_tensions
    total, hang, a_pull, a_back = 600.0, 25.0, 0.05, 0.04
    load = np.linspace(-200.0, 200.0, 801)
    free = split_tensions(total, a_pull, a_back, load, floor, ks, ks)
    t_pull, t_back = split_tensions(total, a_pull, a_back, load, floor, ks, ks, hang)
    assert np.all(t_pull >= hang * (1 - 1e-12)) and np.all(t_back >= hang * (1 - 1e-12))
    np.testing.assert_allclose(t_pull * a_pull - t_back * a_back, load, rtol=0, atol=1e-9)
    above = (free[0] >= hang) & (free[1] >= hang)
    assert above.any() and (~above).any()
    np.testing.assert_array_equal(t_pull[above], free[0][above])
    np.testing.assert_array_equal(t_back[above], free[1][above])


@pytest.mark.parametrize("name", ["xu2010", "C1"])
def test_quasi_static_spans_balance_the_torque_on_the_pitch_radius(name):
    """Level 0's spans where they do not vibrate (KinematicModel.quasi_static_spans, what
    level 2's span-modes line is judged at: chainmodel.validity): on the seat ladder's linear
    law without sag (seed 004 eqs 15-16) the spans share the static sum and the torque,
    T = T0 +- M / (2 R_o), written here; with the default law (wrap fit, sag) the torque
    balance holds exactly, no load leaves both spans at the held tension, the slack span falls
    as the load rises and never below the weight's floor (span_sag.hanging_tension)."""
    d = chainmodel.preset(name)
    r = d.driven.pitch_radius
    linear = _model(d, **{"torsional.wrap_statics": False, "torsional.sag_lag": False,
                          "gravity": 0.0})
    t0 = linear.static_tension()
    for load in (0.0, 0.25 * t0 * r, t0 * r):
        pull, back = linear.quasi_static_spans(load)
        assert pull == pytest.approx(t0 + load / (2 * r), rel=1e-12)
        assert back == pytest.approx(t0 - load / (2 * r), rel=1e-12, abs=1e-9 * t0)
    m = chainmodel.load_scene(name, fidelity=0).model()
    held = m.held_tension()
    pull, back = m.quasi_static_spans(0.0)
    assert pull == pytest.approx(held, rel=1e-9) and back == pytest.approx(held, rel=1e-9)
    floor = hanging_tension(d, m.params)
    backs = []
    for load in np.linspace(0.0, 4.0 * held * r, 9)[1:]:
        pull, back = m.quasi_static_spans(load)
        assert (pull - back) * r == pytest.approx(load, rel=1e-9)
        assert back >= floor * (1 - 1e-12)
        backs.append(back)
    assert np.all(np.diff(backs) <= 1e-9 * held) and backs[0] < held
