"""Both spans, total wrapping length and roller layout (seed 004 sections 2-3).

Independent reference used here: with both spans straight, each span is a *bridge* of the
convex hull of all seat centres of both sprockets (its line supports both pitch polygons),
the chain's seated links are the hull edges on each sprocket, and so the total wrapping
length of seed 004 eq (13) is the hull's perimeter. scipy's ConvexHull gives that without
any of the seating/release bookkeeping of eqs (2)-(12).
"""

import math

import numpy as np
import pytest
from scipy.spatial import ConvexHull

import chainmodel
from chainmodel import kinematics as K
from chainmodel.geometry import Drive
from chainmodel.presets import reference_table

INCH = 0.0254
TABLE1 = reference_table("wrap_length_jsv2016_table1.csv")


def _seats(d, phi1, phi2):
    s = K.seating(d)
    jc, jo = np.arange(d.n_driver), np.arange(d.n_driven)
    c = complex(d.x_c, d.y_c) + d.driver.pitch_radius * np.exp(
        1j * (s.theta4 - phi1 + 2 * math.pi / d.n_driver * jc))
    o = d.driven.pitch_radius * np.exp(1j * (s.theta2 - phi2 + 2 * math.pi / d.n_driven * jo))
    return c, o


def hull_reference(d, phi1, phi2):
    """(perimeter, (A_upper, B_upper), (start_lower, end_lower)) of the convex hull of all
    seat centres for one pair of rotations; upper runs driven -> driver, lower driver -> driven."""
    c, o = _seats(d, phi1, phi2)
    pts = np.concatenate([o, c])
    on_driver = np.r_[np.zeros(o.size, bool), np.ones(c.size, bool)]
    v = ConvexHull(np.column_stack([pts.real, pts.imag])).vertices     # counter-clockwise
    z, side = pts[v], on_driver[v]
    nxt = np.roll(np.arange(v.size), -1)
    upper = lower = None
    for i, j in zip(range(v.size), nxt):
        if side[i] and not side[j]:        # across the top, right to left
            upper = (z[j], z[i])
        elif not side[i] and side[j]:      # across the bottom, left to right
            lower = (z[j], z[i])
    return float(np.sum(np.abs(z[nxt] - z))), upper, lower


# --- seed 004 Table 1 -------------------------------------------------------------------------

@pytest.mark.parametrize("row", TABLE1, ids=[r["id"] for r in TABLE1])
def test_table1_wrap_length(row):
    """L_min/p, L_mean/p, L_max/p of seed 004 Table 1 within 2e-4 (the table gives f to four
    decimals and dL/df ~ 2p); the mean over 100 samples per tooth period (seeds README)."""
    d = Drive(int(row["n_c"]), int(row["n_o"]), INCH, int(row["N"]), float(row["f"]),
              links=int(row["M"]))
    lmin, lmean, lmax = K.wrap_length_range(d, samples=100)
    p = d.pitch
    assert lmin / p == pytest.approx(float(row["L_min_over_p"]), abs=2e-4)
    assert lmean / p == pytest.approx(float(row["L_mean_over_p"]), abs=2e-4)
    assert lmax / p == pytest.approx(float(row["L_max_over_p"]), abs=2e-4)


def test_table1_b2_length_constant():
    """Seed 004 section 3: for B2 (n_c = n_o, f ~ 0) the wrapping length does not vary."""
    d = chainmodel.preset("B2")
    L = K.wrap_length(d, driver_angle=np.linspace(0, 2 * math.pi / d.n_driver, 300))
    assert np.ptp(L) / d.pitch < 1e-6


# --- independent geometry: convex hull -------------------------------------------------------

HULL_DRIVES = [r["id"] for r in TABLE1] + ["coarse", "medium", "fine", "xu2010"]


@pytest.mark.parametrize("name", HULL_DRIVES)
def test_wrap_length_is_the_hull_perimeter(name):
    """Seed 004 eq (13) with the README corrections (beta = 2 theta1, counts on the driven
    sprocket over 2 alpha_o, the released roller counted once) equals the perimeter of the
    convex hull of the seats, over random driver angles (forward kinematics)."""
    d = chainmodel.preset(name)
    phi = np.random.default_rng(3).uniform(-1.0, 7.0, 25)
    phi2 = K.driven_rotation(d, phi).driven_angle
    L = K.wrap_length(d, driver_angle=phi)
    ref = np.array([hull_reference(d, a, b)[0] for a, b in zip(phi, phi2)])
    np.testing.assert_allclose(L, ref, rtol=1e-13)


@pytest.mark.parametrize("name", ["C1", "A1", "coarse", "xu2010", "D2"])
def test_span_endpoints_are_hull_bridges_for_any_rotations(name):
    """The window condition of wrapping.py picks the same span endpoints as the convex hull,
    for arbitrary pairs of rotations (stretched or slack spans, as the dynamic levels use)."""
    d = chainmodel.preset(name)
    rng = np.random.default_rng(4)
    phi1 = rng.uniform(-5, 5, 40)
    phi2 = phi1 * d.tooth_ratio + rng.uniform(-0.5, 0.5, 40) * 2 * math.pi / d.n_driven
    g = K.chain_geometry(d, phi1, phi2)
    for i in range(phi1.size):
        per, up, low = hull_reference(d, phi1[i], phi2[i])
        assert abs(g.upper.start[i] - up[0]) < 1e-12 and abs(g.upper.end[i] - up[1]) < 1e-12
        assert abs(g.lower.start[i] - low[0]) < 1e-12 and abs(g.lower.end[i] - low[1]) < 1e-12
        assert g.wrap_length[i] == pytest.approx(per, abs=1e-12)
    # the moment arms are the distances from the centres to the span lines
    C = complex(d.x_c, d.y_c)
    for span, c_from, c_to in ((g.upper, 0j, C), (g.lower, C, 0j)):
        e = (span.end - span.start) / np.abs(span.end - span.start)
        dist = lambda c: np.abs(np.imag(np.conj(e) * (c - span.start)))
        np.testing.assert_allclose(span.arm_start, dist(c_from), atol=1e-12)
        np.testing.assert_allclose(span.arm_end, dist(c_to), atol=1e-12)


# --- the window condition and the four-bar events ---------------------------------------------

@pytest.mark.parametrize("name, f", [("coarse", 0.75), ("medium", 0.43), ("fine", 0.5),
                                     ("C1", None), ("A1", None), ("xu2010", None)])
def test_window_condition_switches_at_the_fourbar_events(name, f):
    """Along the forward motion, the upper span's driver endpoint moves to the next seat
    exactly at seating (driver angle 0 mod 2 alpha_c) and its driven endpoint exactly at
    release (theta4s - theta4r mod 2 alpha_c), and at no other angle."""
    d = chainmodel.preset(name) if f is None else chainmodel.preset(name, pitch_fraction=f)
    P = 2 * math.pi / d.n_driver
    psi = K.seating(d).theta4 - K.release(d).theta4
    phi = np.linspace(-0.5 * P, 2.5 * P, 6001)
    g = K.chain_geometry(d, phi, K.driven_rotation(d, phi).driven_angle)
    seat = phi[1:][np.diff(g.upper.seat_end) != 0]
    rel = phi[1:][np.diff(g.upper.seat_start) != 0]
    step = phi[1] - phi[0]
    k = np.arange(-1, 3)
    in_range = lambda x: x[(x > phi[0]) & (x < phi[-1])]
    np.testing.assert_allclose(seat, in_range(k * P), atol=1.01 * step)
    np.testing.assert_allclose(rel, in_range(psi + k * P), atol=1.01 * step)
    # and sharply: 1e-9 rad either side of each event
    for event, field in ((P, "seat_end"), (psi + P, "seat_start")):
        both = np.array([event - 1e-9, event + 1e-9])
        gg = K.chain_geometry(d, both, K.driven_rotation(d, both).driven_angle)
        assert np.diff(getattr(gg.upper, field))[0] == 1
    # between events the upper span holds a whole number of pitches
    np.testing.assert_allclose(g.upper.length, g.upper_links * d.pitch, rtol=1e-12)


@pytest.mark.parametrize("name", ["coarse", "A1", "C1", "D1", "xu2010"])
def test_wrap_length_continuous_across_events(name):
    """Only the count of seated links and the span lengths change at an event, and they change
    together: the total wrapping length has no jump there (eq 13)."""
    d = chainmodel.preset(name)
    P = 2 * math.pi / d.n_driver
    psi = K.seating(d).theta4 - K.release(d).theta4
    for event in (P, psi + P):
        for eps in (1e-6, 1e-9, 1e-12):
            L = K.wrap_length(d, driver_angle=np.array([event - eps, event + eps]))
            assert abs(L[1] - L[0]) < 10 * eps * d.driver.pitch_radius
    # nor anywhere else: steps bounded by the largest sprocket radius times the driver step
    phi = np.linspace(0, 3 * P, 3001)
    L = K.wrap_length(d, driver_angle=phi)
    assert np.max(np.abs(np.diff(L))) < 2 * max(d.driver.pitch_radius, d.driven.pitch_radius) \
        * (phi[1] - phi[0])


@pytest.mark.parametrize("name", ["A1", "coarse", "C1", "xu2010"])
def test_geometry_just_before_an_event(name):
    """Driver angles a hair before seating or release (1e-15 .. 1e-6 rad, as an event-locating
    stepper produces) are valid states: chain_geometry must settle there, scalar or array,
    and keep the rigid upper span a whole number of pitches. (The tolerant window used to
    flip between the two candidate endpoints about 1e-9 rad before seating and raise.)"""
    d = chainmodel.preset(name)
    P = 2 * math.pi / d.n_driver
    psi = K.seating(d).theta4 - K.release(d).theta4
    eps = np.logspace(-15, -6, 46)
    for event in (P, psi + P):
        phi = event - eps
        g = K.chain_geometry(d, phi, K.driven_rotation(d, phi).driven_angle)
        np.testing.assert_allclose(g.upper.length, g.upper_links * d.pitch, rtol=1e-12)
        for x in phi[::9]:
            K.chain_geometry(d, x, K.driven_rotation(d, x).driven_angle)


def test_wrap_length_theta4_argument():
    d = chainmodel.preset("C1")
    s = K.seating(d)
    phi = np.linspace(0.01, 0.5, 7)
    np.testing.assert_allclose(K.wrap_length(d, theta4=s.theta4 - phi), K.wrap_length(d, driver_angle=phi),
                               rtol=1e-14)


# --- roller layout ----------------------------------------------------------------------------

@pytest.mark.parametrize("name", ["medium", "C1", "A1", "D3", "xu2010"])
def test_roller_positions(name):
    """M rollers; every link outside the lower span exactly one pitch; the lower span's links
    share its length equally; the closed chain's length is the wrapping length; seated rollers
    sit on their pitch circles."""
    d = chainmodel.preset(name)
    for phi1 in (0.0, 0.137, 1.0):
        phi2 = float(K.driven_rotation(d, phi1).driven_angle)
        pos = K.roller_positions(d, phi1, phi2)
        assert pos.shape == (d.links, 2)
        z = pos[:, 0] + 1j * pos[:, 1]
        link = np.abs(np.roll(z, -1) - z)
        g = K.chain_geometry(d, np.array([phi1]), np.array([phi2]))
        n_low = int(g.lower_links[0])
        long_links = np.abs(link - d.pitch) > 1e-12
        assert long_links.sum() in (0, n_low)
        if long_links.any():
            np.testing.assert_allclose(link[long_links], g.lower.length[0] / n_low, rtol=1e-12)
        assert np.sum(link) == pytest.approx(float(K.wrap_length(d, driver_angle=phi1)), rel=1e-13)
        on_c = np.abs(np.abs(z - complex(d.x_c, d.y_c)) - d.driver.pitch_radius) < 1e-12
        on_o = np.abs(np.abs(z) - d.driven.pitch_radius) < 1e-12
        assert on_c.sum() >= int(g.wrapped_driver[0]) + 1
        assert on_o.sum() >= int(g.wrapped_driven[0]) + 1
        # all distinct
        assert np.min(np.abs(z[:, None] - z[None, :]) + np.eye(z.size)) > 0.5 * d.pitch


def test_roller_positions_tight_chain_all_links_one_pitch():
    """At the centre distance of Drive.from_links the chain is unstretched at the shortest
    instant of the period: there every one of the M links is exactly one pitch."""
    d = Drive.from_links(12, 18, INCH, 40)
    P = 2 * math.pi / d.n_driver
    phi = np.linspace(0, P, 2001)
    i = int(np.argmin(K.wrap_length(d, driver_angle=phi)))
    from scipy.optimize import minimize_scalar
    res = minimize_scalar(lambda x: float(K.wrap_length(d, driver_angle=np.array([x]))[0]),
                          bounds=(phi[max(i - 1, 0)], phi[min(i + 1, phi.size - 1)]),
                          method="bounded", options={"xatol": 1e-12})
    phi1 = res.x
    pos = K.roller_positions(d, phi1, float(K.driven_rotation(d, phi1).driven_angle))
    z = pos[:, 0] + 1j * pos[:, 1]
    np.testing.assert_allclose(np.abs(np.roll(z, -1) - z), d.pitch, rtol=1e-8)


def test_from_links_tight_at_max():
    """tight_at="max": the chain is nowhere stretched, just tight at the longest instant."""
    d = Drive.from_links(12, 18, INCH, 40, tight_at="max")
    lmin, _, lmax = K.wrap_length_range(d)
    assert lmax / INCH == pytest.approx(40.0, abs=1e-6)
    assert lmin < lmax


def test_roller_positions_needs_links():
    with pytest.raises(ValueError, match="links"):
        K.roller_positions(chainmodel.preset("medium", links=None), 0.0, 0.0)


def test_design_positional_form_takes_theta4():
    """DESIGN.md's public interface: kinematics.wrap_length(drive, theta4) - the paper's
    contact angle, one tooth period from seating (theta4s) down; equal to the driver-rotation
    form at phi = theta4s - theta4."""
    d = chainmodel.preset("C1")
    s = K.seating(d)
    phi = np.linspace(0, 2 * math.pi / d.n_driver, 50, endpoint=False)
    np.testing.assert_allclose(K.wrap_length(d, s.theta4 - phi), K.wrap_length(d, driver_angle=phi),
                               rtol=1e-14)
    with pytest.raises(ValueError, match="not both"):
        K.wrap_length(d, s.theta4, driver_angle=0.0)
