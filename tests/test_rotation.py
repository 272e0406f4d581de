"""Continuous sprocket rotations (kinematics/rotation.py): forward-positive driver and driven
angles that do not jump at seating and release, and reverse rotation by mirror symmetry."""

import math

import numpy as np
import pytest

import chainmodel
from chainmodel import kinematics as K
from chainmodel.geometry import Drive

INCH = 0.0254
DRIVES = ("coarse", "medium", "fine", "A1", "B2", "C1", "D3", "xu2010")


def _drive(name, **kw):
    return chainmodel.preset(name, **kw)


def _extreme_f0():
    # f = 0 yet release before the next seating (see test_fourbar.py)
    return Drive(3, 12, INCH, 1, 0.0)


def _all_drives():
    return [_drive(n) for n in DRIVES] + [_drive("medium", pitch_fraction=0.0),
                                          _drive("coarse", pitch_fraction=0.0), _extreme_f0()]


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("d", _all_drives(), ids=lambda d: d.name or "extreme_f0")
def test_driven_turns_one_tooth_per_driver_tooth(d, reverse):
    """Over k driver tooth periods (2 pi / n_c each) the driven sprocket turns exactly
    k 2 pi / n_o, from any starting angle, forwards and (reverse=True) backwards; speed,
    velocity ratio and span length repeat."""
    P_c, P_o = 2 * math.pi / d.n_driver, 2 * math.pi / d.n_driven
    phi = np.random.default_rng(1).uniform(-3 * P_c, 3 * P_c, 200)
    phi = np.concatenate([phi, np.arange(-3, 4) * P_c])           # the event instants too
    r0 = K.driven_rotation(d, phi, 7.0, reverse=reverse)
    for k in (-5, -1, 1, 2, 13):
        r = K.driven_rotation(d, phi + k * P_c, 7.0, reverse=reverse)
        np.testing.assert_allclose(r.driven_angle - r0.driven_angle, k * P_o, rtol=0,
                                   atol=1e-10 * (1 + abs(k)))
        # fields that jump at the events: compare off the event instants (at an instant
        # itself round-off in phi + k P_c decides which side of the jump is reported)
        for field in ("driven_speed", "velocity_ratio", "span_length", "driven_acceleration"):
            np.testing.assert_allclose(getattr(r, field)[:200], getattr(r0, field)[:200],
                                       rtol=1e-9, atol=1e-9, err_msg=field)


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("d", _all_drives(), ids=lambda d: d.name or "extreme_f0")
def test_driven_angle_is_continuous(d, reverse):
    """The sprocket does not jump at seating or release, though theta2 does: successive
    samples differ by at most (largest velocity ratio) x (driver step)."""
    P_c = 2 * math.pi / d.n_driver
    phi = np.linspace(-2 * P_c, 2 * P_c, 8001)
    r = K.driven_rotation(d, phi, reverse=reverse)
    step = np.diff(r.driven_angle)
    assert np.all(step > 0)
    assert np.max(step) <= np.max(r.velocity_ratio) * (phi[1] - phi[0]) * 1.01
    # while the contact angle theta2 does jump (by 2 alpha_o at release), except at f = 0
    if d.pitch_fraction > 0:
        assert np.max(np.abs(np.diff(r.theta2))) > 1.5 * math.pi / d.n_driven


@pytest.mark.parametrize("reverse", [False, True])
@pytest.mark.parametrize("name, f", [("coarse", 0.75), ("medium", 0.43), ("fine", 0.5),
                                     ("xu2010", None), ("medium", 0.0)])
@pytest.mark.parametrize("w, a", [(12.0, 0.0), (12.0, 150.0), (-8.0, 40.0)])
def test_rotation_derivatives_match_central_differences(name, f, w, a, reverse):
    """driven_speed and driven_acceleration are the time derivatives of driven_angle for a
    driver phi1(t) = phi0 + w t + a t^2 / 2 (accelerating), to 1e-6 relative, away from
    the events (samples whose +-dt neighbours straddle an event are left out)."""
    d = _drive(name) if f is None else _drive(name, pitch_fraction=f)
    P_c = 2 * math.pi / d.n_driver
    t = np.linspace(0, 3 * P_c / abs(w), 600)
    dt = 1e-6 * P_c / abs(w) * d.n_driver / 12
    phi = lambda t: 0.1 + w * t + 0.5 * a * t**2
    rot = lambda t: K.driven_rotation(d, phi(t), w + a * t, a, reverse=reverse)
    r0, rp, rm = rot(t), rot(t + dt), rot(t - dt)
    same = (rp.h == rm.h) & (rp.periods == rm.periods) & (rp.h == r0.h) & (rp.periods == r0.periods)
    assert same.mean() > 0.9
    fd_w = (rp.driven_angle - rm.driven_angle) / (2 * dt)
    fd_a = (rp.driven_speed - rm.driven_speed) / (2 * dt)
    rel = lambda fd, x: np.max(np.abs(fd - x)[same]) / np.max(np.abs(x[same]))
    assert rel(fd_w, r0.driven_speed) < 1e-6
    assert rel(fd_a, r0.driven_acceleration) < 1e-6
    np.testing.assert_allclose(r0.driven_speed, r0.velocity_ratio * (w + a * t), rtol=1e-14)


def test_forward_matches_the_papers_contact_angles():
    """driven_rotation is the exact four-bar of seed 000 in other coordinates:
    theta4 = theta4s - (phi1 mod 2 alpha_c), phi2 = theta2s - theta2 + 2 alpha_o (k + h)."""
    d = _drive("C1")
    s = K.seating(d)
    P_c, a_o = 2 * math.pi / d.n_driver, math.pi / d.n_driven
    phi = np.linspace(0.013, 5 * P_c, 777)
    r = K.driven_rotation(d, phi, 10.0, 3.0)
    k = np.floor(phi / P_c)
    ex = K.exact(d, s.theta4 - (phi - k * P_c), -10.0, -3.0)
    np.testing.assert_allclose(r.theta2, ex.theta2, atol=1e-12)
    np.testing.assert_allclose(r.driven_angle, s.theta2 - ex.theta2 + 2 * a_o * (k + ex.h),
                               atol=1e-12)
    np.testing.assert_allclose(r.driven_speed, -ex.omega2, rtol=1e-12)
    np.testing.assert_allclose(r.driven_acceleration, -ex.alpha2, rtol=1e-12)
    assert np.all(r.driven_angle[phi < 1e-9] == 0) or phi[0] > 0
    assert K.driven_rotation(d, 0.0).driven_angle == pytest.approx(0.0, abs=1e-15)


# --- reverse rotation: mirror symmetry --------------------------------------------------------

def _mirrored_ratio(d, phi):
    """Velocity ratio of the drive running backwards at driver rotation phi, computed here
    from scratch: reflect the drive about its line of centres OC (angle theta1). A driver seat
    at angle theta4s - phi + 2 alpha_c j maps to 2 theta1 - theta4s + phi - 2 alpha_c j; the
    mirror image is the same drive running forwards, its upper span the real lower span. So
    the ratio is that of the forward four-bar at the reflected seat angle, mapped into the
    tooth period (theta4s - 2 alpha_c, theta4s]."""
    s = K.seating(d)
    t1 = math.atan2(d.y_c, d.x_c)
    P_c = 2 * math.pi / d.n_driver
    reflected = 2 * t1 - s.theta4 + phi
    theta4 = s.theta4 - np.mod(s.theta4 - reflected, P_c)
    return K.exact(d, theta4).velocity_ratio


@pytest.mark.parametrize("d", _all_drives(), ids=lambda d: d.name or "extreme_f0")
def test_reverse_ratio_is_the_mirrored_forward_ratio(d):
    P_c = 2 * math.pi / d.n_driver
    phi = np.random.default_rng(2).uniform(-2 * P_c, 2 * P_c, 500)
    rev = K.driven_rotation(d, phi, -5.0, reverse=True)
    np.testing.assert_allclose(rev.velocity_ratio, _mirrored_ratio(d, phi), rtol=1e-10)
    np.testing.assert_allclose(rev.driven_speed, -5.0 * rev.velocity_ratio, rtol=1e-14)


@pytest.mark.parametrize("name", ["coarse", "C1", "A1", "xu2010"])
def test_reverse_keeps_the_lower_span_rigid(name):
    """Running backwards the driver pulls the lower span: it must keep a whole number of
    pitches between its endpoints (as the upper span does running forwards), with the
    endpoints found from the seats by the span-window geometry (wrapping.py, validated
    against a convex hull in test_wrapping.py)."""
    d = _drive(name)
    P_c = 2 * math.pi / d.n_driver
    phi = np.linspace(0, 2 * P_c, 997)
    for reverse, span in ((False, "upper"), (True, "lower")):
        r = K.driven_rotation(d, phi, reverse=reverse)
        g = K.chain_geometry(d, phi, r.driven_angle)
        length = getattr(g, span).length / d.pitch
        np.testing.assert_allclose(length, np.round(length), atol=1e-9)
        np.testing.assert_allclose(length, r.span_length / d.pitch, atol=1e-9)


@pytest.mark.parametrize("name", DRIVES)
def test_reverse_stays_within_half_a_tooth_of_forward(name):
    """The reverse branch is pinned to the forward one so that the chain's backlash is the
    least possible: their mean offset lies within half a driven tooth."""
    d = _drive(name)
    phi = np.linspace(0, 2 * math.pi / d.n_driver, 400, endpoint=False)
    diff = (K.driven_rotation(d, phi, reverse=True).driven_angle
            - K.driven_rotation(d, phi).driven_angle)
    assert abs(np.mean(diff)) <= math.pi / d.n_driven + 1e-12
