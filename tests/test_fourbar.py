"""Exact four-bar kinematics of the tight span (seed 000 section 2).

Reference numbers come from the paper's geometry (the aligned configuration at f = 0, eq 8;
the span lengths of eq 7), from physics (closure, the chain wrapping convexly, the driven
sprocket turning 2 alpha_o per driver tooth) or from finite differences computed here.
"""

import math

import numpy as np
import pytest

import chainmodel
from chainmodel import kinematics as K
from chainmodel.geometry import Drive
from chainmodel.kinematics import fourbar as fb

INCH = 0.0254
PAPER = ("coarse", "medium", "fine")        # seed 000 Table 1
FRACTIONS = (0.0, 0.25, 0.5, 0.75, 0.95)    # the paper's 0, 0.5, 0.75 and two more


def _drive(name, f):
    return chainmodel.preset(name, pitch_fraction=f, links=None)


def _interior(drive, per_interval=40, margin=0.02):
    """theta4 samples inside the two constant-h intervals of a period, ``margin`` (fraction of
    the period) away from seating and release."""
    s, r = K.seating(drive), K.release(drive)
    two_a = 2 * math.pi / drive.n_driver
    m = margin * two_a
    parts = []
    if s.theta4 - r.theta4 > 2 * m:
        parts.append(np.linspace(r.theta4 + m, s.theta4 - m, per_interval))
    if r.theta4 - (s.theta4 - two_a) > 2 * m:
        parts.append(np.linspace(s.theta4 - two_a + m, r.theta4 - m, per_interval))
    return np.concatenate(parts)


# --- events -------------------------------------------------------------------------------

@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("f", FRACTIONS)
def test_events_close_the_linkage(name, f):
    """Seating and release satisfy the closure eqs (14)-(15) with r3 = L (eq 13, h = 0) and
    their event conditions, eq (16) theta3s = theta4s - (pi/2 + alpha_c) and eq (22)
    theta3r = theta2r + alpha_o - pi/2."""
    d = _drive(name, f)
    a_c, a_o = math.pi / d.n_driver, math.pi / d.n_driven
    R_c, R_o = d.driver.pitch_radius, d.driven.pitch_radius
    C = complex(d.x_c, d.y_c)
    L = (d.span_pitches + 1) * d.pitch
    for ev in (K.seating(d), K.release(d)):
        A = R_o * np.exp(1j * ev.theta2)
        B = C + R_c * np.exp(1j * ev.theta4)
        assert abs(B - A) == pytest.approx(L, rel=1e-12)
        assert np.angle(B - A) == pytest.approx(ev.theta3, abs=1e-12)
    s, r = K.seating(d), K.release(d)
    assert s.theta3 == pytest.approx(s.theta4 - (math.pi / 2 + a_c), abs=1e-12)
    assert r.theta3 == pytest.approx(r.theta2 + a_o - math.pi / 2, abs=1e-12)
    # same-direction branch (seed 000 section 2.8): contact angles near pi/2
    for ang, a in ((s.theta2, a_o), (r.theta2, a_o), (s.theta4, a_c), (r.theta4, a_c)):
        assert abs(ang - math.pi / 2) <= a + 0.05
    # eq (26) as corrected: release inside the period [theta4s - 2 alpha_c, theta4s]
    assert s.theta4 - 2 * a_c - 1e-12 <= r.theta4 <= s.theta4 + 1e-12


@pytest.mark.parametrize("name", PAPER)
def test_f0_events_are_the_aligned_configuration(name):
    """Seed 000 section 2.5: at f = 0 seating and release happen together at the instant the
    rollers A_m A_1 B_m B_1 lie on the points z1 z2 z3 z4 of the common tangent, i.e.
    theta4s = pi/2 + alpha_c, theta2s = pi/2 + alpha_o, theta3 = 0 and one period later
    theta4r = pi/2 - alpha_c, theta2r = pi/2 - alpha_o. The span length stays (N + 1) p (eq 8)."""
    d = _drive(name, 0.0)
    a_c, a_o = math.pi / d.n_driver, math.pi / d.n_driven
    s, r = K.seating(d), K.release(d)
    assert (s.theta2, s.theta3, s.theta4) == pytest.approx(
        (math.pi / 2 + a_o, 0.0, math.pi / 2 + a_c), abs=1e-9)
    assert (r.theta2, r.theta3, r.theta4) == pytest.approx(
        (math.pi / 2 - a_o, 0.0, math.pi / 2 - a_c), abs=1e-9)
    # simultaneous: release coincides with the next seating
    assert s.theta4 - r.theta4 == pytest.approx(2 * a_c, abs=1e-9)
    # over whole periods, including the event instants themselves (theta4s - k 2 alpha_c),
    # where round-off used to leave h = 1, a spurious (N + 2) p span
    t4 = s.theta4 - np.linspace(-6 * a_c, 6 * a_c, 6001)
    k = K.exact(d, t4, -10.47)
    np.testing.assert_allclose(k.span_length, (d.span_pitches + 1) * d.pitch, rtol=1e-14)
    assert not np.any(k.h)


# Where "f = 0 makes seating and release simultaneous" stops holding is a finding documented in
# docs/kinematics.md (scan command there): only one sprocket of <= 10 teeth against a much larger
# one on the shortest spans. The test asserts what must hold on either side of that boundary,
# not the scan's verdicts: at f = 0 the span is (N + 1) p for the whole period when the events
# coincide, and otherwise it is (N + 1) p and (N + 2) p with every rigid-chain state holding
# whole pitches between the endpoints the window condition picks.
def _buildable(n_c, n_o, N):
    try:
        Drive(n_c, n_o, INCH, N, 0.0)
    except ValueError:       # sprockets overlap at this span: geometry that cannot exist
        return False
    return True


F0_GRID = [(n_c, n_o, N) for n_c in (3, 4, 6, 12) for n_o in (9, 10, 13, 29, 93, 40)
           for N in (1, 2, 3, 7, 8) if _buildable(n_c, n_o, N)]


@pytest.mark.parametrize("n_c, n_o, N", F0_GRID)
def test_f0_events_coincide_or_the_chain_stays_rigid(n_c, n_o, N):
    d = Drive(n_c, n_o, INCH, N, 0.0)
    a_c = math.pi / n_c
    s, r = K.seating(d), K.release(d)
    phase = (s.theta4 - r.theta4) / (2 * a_c)
    t4 = s.theta4 - np.linspace(0, 2 * a_c, 2001)[:-1]
    lengths = np.unique(np.round(K.exact(d, t4).span_length / INCH, 9))
    if abs(phase - 1.0) < 1e-7:
        assert lengths.tolist() == [N + 1]          # eq (8)
    else:
        assert phase < 1.0                          # release before the next seating
        assert lengths.tolist() == [N + 1, N + 2]
        psi = s.theta4 - r.theta4
        phi = np.concatenate([np.linspace(0, 2 * a_c, 501),
                              psi + np.linspace(0, 2 * a_c - psi, 50, endpoint=False)[1:]])
        g = K.chain_geometry(d, phi, K.driven_rotation(d, phi).driven_angle)
        np.testing.assert_allclose(g.upper.length, g.upper_links * INCH, rtol=1e-12)
        assert set(np.unique(g.upper_links)) == {N + 1, N + 2}


def test_seeds_readme_extreme_example_cannot_be_built():
    """The seeds README's n_c = 6, n_o = 90, N = 5: its pitch circles overlap
    (|OC| = 14.73 p < R_c + R_o = 15.33 p), so Drive refuses it; the bare four-bar is
    non-simultaneous there, and the first buildable span (N = 7) is simultaneous."""
    R = lambda n: 1 / (2 * math.sin(math.pi / n))
    r = lambda n: 1 / (2 * math.tan(math.pi / n))
    assert math.hypot(6, r(90) - r(6)) < R(6) + R(90)
    with pytest.raises(ValueError, match="overlap"):
        Drive(6, 90, INCH, 5, 0.0)
    four, s, rel = fb._fourbar_cached(90, 6, 1.0, 6.0, 5)   # the bare linkage, pitch 1
    assert (s.theta4 - rel.theta4) / (2 * math.pi / 6) < 0.9
    d = Drive(6, 90, INCH, 7, 0.0)
    assert K.seating(d).theta4 - K.release(d).theta4 == pytest.approx(2 * math.pi / 6, abs=1e-9)


# --- input-output -------------------------------------------------------------------------

@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("f", FRACTIONS)
def test_exact_position_closes_and_chain_wraps_convexly(name, f):
    """Every sample satisfies the closure equation (10) with r3 = L + h p, the span holds
    N + 1 or N + 2 pitches (eq 7), and both endpoints lie in the window where the chain wraps
    onto the sprocket without bending backwards: pi/2 - alpha < theta - theta3 <= pi/2 + alpha
    (the seating and release conditions, eqs 16 and 22, are its edges)."""
    d = _drive(name, f)
    a_c, a_o = math.pi / d.n_driver, math.pi / d.n_driven
    s = K.seating(d)
    t4 = s.theta4 - np.linspace(0, 2 * a_c, 997, endpoint=False)
    k = K.exact(d, t4)
    A = d.driven.pitch_radius * np.exp(1j * k.theta2)
    B = complex(d.x_c, d.y_c) + d.driver.pitch_radius * np.exp(1j * k.theta4)
    np.testing.assert_allclose(np.abs(B - A), k.span_length, rtol=1e-12)
    np.testing.assert_allclose(np.angle(B - A), k.theta3, atol=1e-12)
    np.testing.assert_allclose(k.span_length / d.pitch, d.span_pitches + 1 + k.h, atol=1e-12)
    tol = 1e-9
    assert np.all(k.theta2 - k.theta3 > math.pi / 2 - a_o - tol)
    assert np.all(k.theta2 - k.theta3 <= math.pi / 2 + a_o + tol)
    assert np.all(k.theta4 - k.theta3 > math.pi / 2 - a_c - tol)
    assert np.all(k.theta4 - k.theta3 <= math.pi / 2 + a_c + tol)
    if f > 0:
        assert set(np.unique(k.h)) == {0, 1}


@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("f", (0.0, 0.5, 0.75))
def test_mean_velocity_ratio_is_tooth_ratio(name, f):
    """Integrating eq (30) over one driver tooth (2 alpha_c) turns the driven sprocket by one
    of its teeth (2 alpha_o): the mean velocity ratio is n_c / n_o."""
    d = _drive(name, f)
    a_c = math.pi / d.n_driver
    n = 20000
    t4 = K.seating(d).theta4 - (np.arange(n) + 0.5) * (2 * a_c / n)   # midpoint rule
    k = K.exact(d, t4)
    assert np.mean(k.velocity_ratio) == pytest.approx(d.n_driver / d.n_driven, rel=1e-7)


def _central_difference_errors(d, t4, w4, a4, dt=1e-5):
    """Max relative deviation of (omega2, alpha2, omega3) from central differences of
    (theta2, omega2, theta3) in time, for the driver motion theta4(t) with d theta4/dt = w4
    and d^2 theta4/dt^2 = a4 at t = 0."""
    k0 = K.exact(d, t4, w4, a4)
    kp = K.exact(d, t4 + w4 * dt + 0.5 * a4 * dt**2, w4 + a4 * dt, a4)
    km = K.exact(d, t4 - w4 * dt + 0.5 * a4 * dt**2, w4 - a4 * dt, a4)
    rel = lambda fd, x: np.max(np.abs(fd - x)) / np.max(np.abs(x))
    return (rel((kp.theta2 - km.theta2) / (2 * dt), k0.omega2),
            rel((kp.omega2 - km.omega2) / (2 * dt), k0.alpha2),
            rel((kp.theta3 - km.theta3) / (2 * dt), k0.omega3))


@pytest.mark.parametrize("name", PAPER)
@pytest.mark.parametrize("f", (0.0, 0.5, 0.75))
@pytest.mark.parametrize("w4, a4", [(-10.47, 0.0),      # 100 rpm clockwise (paper section 4.1)
                                    (-10.47, -40.0),    # accelerating forward
                                    (6.0, 25.0)])       # running backwards, accelerating
def test_exact_derivatives_match_central_differences(name, f, w4, a4):
    """Eqs (30)-(32) are the time derivatives of eqs (27)-(29), also for a driver that
    accelerates; checked to 1e-6 relative away from seating and release."""
    d = _drive(name, f)
    errs = _central_difference_errors(d, _interior(d), w4, a4)
    assert max(errs) < 1e-6, errs


def test_exact_accepts_array_speeds_and_keeps_shape():
    d = _drive("medium", 0.43)
    t4 = _interior(d).reshape(2, -1)
    w4 = np.linspace(-12, -8, t4.size).reshape(t4.shape)
    k = K.exact(d, t4, w4, 3.0)
    assert k.theta2.shape == t4.shape and k.alpha2.shape == t4.shape
    np.testing.assert_allclose(k.omega2, k.velocity_ratio * w4, rtol=1e-15)
    assert np.all(k.alpha4 == 3.0)


@pytest.mark.parametrize("name", PAPER)
def test_exact_is_tooth_periodic(name):
    d = _drive(name, 0.75)
    t4 = _interior(d, 25)
    k0 = K.exact(d, t4, -10.0)
    for shift in (-3, -1, 1, 7):
        k = K.exact(d, t4 + shift * 2 * math.pi / d.n_driver, -10.0)
        for field in ("theta2", "theta3", "span_length", "velocity_ratio", "alpha2"):
            np.testing.assert_allclose(getattr(k, field), getattr(k0, field), rtol=1e-9,
                                       atol=1e-12, err_msg=field)


@pytest.mark.parametrize("n, N", [(6, 4), (6, 30), (12, 4), (12, 11), (12, 40), (24, 8),
                                  (40, 12), (40, 30)])
def test_equal_sprockets_f0_constant_ratio_one(n, N):
    """Seed 000 section 4.2: only for n_c = n_o and f = 0 is the velocity ratio constant, 1,
    and the driven acceleration equals the driver's."""
    d = Drive(n, n, INCH, N, 0.0)
    t4 = K.seating(d).theta4 - np.linspace(-2 * math.pi / n, 4 * math.pi / n, 1501)
    k = K.exact(d, t4, -10.47, -5.0)
    np.testing.assert_allclose(k.velocity_ratio, 1.0, atol=1e-12)
    np.testing.assert_allclose(k.alpha2, -5.0, atol=1e-9)
    # and not for f != 0
    d = Drive(n, n, INCH, N, 0.5)
    k = K.exact(d, t4, -10.47)
    assert np.ptp(k.velocity_ratio) > 1e-6


def test_velocity_ratio_ripple_decimal_per_drive():
    """Seed 000 section 4.2 (Fig. 4 d-f): "For the coarse, medium and fine configurations the
    variation of the velocity ratio is seen to be on the first, second and third decimal
    point, respectively" (largest peak-to-peak over f = 0, 0.5, 0.75); and f = 0 varies less
    than f = 0.5 (Bartlett, Morrison: minimum and maximum variation)."""
    for name, decimal in (("coarse", 1), ("medium", 2), ("fine", 3)):
        ripple = {}
        for f in (0.0, 0.5, 0.75):
            d = _drive(name, f)
            t4 = K.seating(d).theta4 - np.linspace(0, 2 * math.pi / d.n_driver, 2000)
            ripple[f] = np.ptp(K.exact(d, t4).velocity_ratio)
        assert 10.0 ** -decimal <= max(ripple.values()) < 10.0 ** (1 - decimal), (name, ripple)
        assert ripple[0.0] < ripple[0.5]
