"""Geometry of seed 000 section 2.3-2.4 / seed 004 eq 1, and the refusal of bad input."""

import math
import re

import pytest

import chainmodel
from chainmodel.geometry import Drive, Sprocket

INCH = 0.0254


# --- seed 000 eq (1) and eqs (2), (5) --------------------------------------------------------

@pytest.mark.parametrize("n", [3, 6, 12, 18, 63, 120])
def test_sprocket_radii_eq1(n):
    p = 0.015875
    s = Sprocket(n, p)
    alpha = math.pi / n
    assert s.pitch_angle == pytest.approx(alpha, rel=1e-15)
    assert s.pitch_radius == pytest.approx(p / (2 * math.sin(alpha)), rel=1e-15)
    assert s.inscribed_radius == pytest.approx(p / (2 * math.tan(alpha)), rel=1e-15)
    # the polygon side between two seats on the pitch circle is one pitch
    chord = 2 * s.pitch_radius * math.sin(alpha)
    assert chord == pytest.approx(p, rel=1e-14)
    # r is the distance from the centre to a side: R cos(alpha)
    assert s.inscribed_radius == pytest.approx(s.pitch_radius * math.cos(alpha), rel=1e-14)


def test_centre_position_eq5():
    d = Drive(12, 18, INCH, 11, 0.4302)
    assert d.x_c == pytest.approx((11 + 1 + 0.4302) * INCH, rel=1e-15)
    r_o = INCH / (2 * math.tan(math.pi / 18))
    r_c = INCH / (2 * math.tan(math.pi / 12))
    assert d.y_c == pytest.approx(r_o - r_c, rel=1e-14)
    assert d.centre_distance == pytest.approx(math.hypot(d.x_c, d.y_c), rel=1e-15)
    assert d.lower_span_length == pytest.approx(12 * INCH)
    assert d.tooth_ratio == pytest.approx(12 / 18)


@pytest.mark.parametrize("name", ["coarse", "medium", "fine", "A1", "B2", "C1", "D3"])
def test_from_centre_distance_inverts_eq5(name):
    d = chainmodel.preset(name)
    back = Drive.from_centre_distance(d.n_driver, d.n_driven, d.pitch, d.centre_distance)
    assert back.span_pitches == d.span_pitches
    assert back.pitch_fraction == pytest.approx(d.pitch_fraction, abs=1e-9)


def test_from_centre_distance_whole_pitches_round_off():
    # x_c an exact whole number of pitches must give f = 0, not f = 0.999999...
    d = Drive(12, 12, INCH, 16, 0.0)
    back = Drive.from_centre_distance(12, 12, INCH, d.centre_distance * (1 + 1e-15))
    assert (back.span_pitches, back.pitch_fraction) == (16, pytest.approx(0.0, abs=1e-9))


def test_from_links_wraps_tightly():
    """seed 004 section 2: at the returned centre distance the shortest wrap of the period
    equals M p (the C1 row of Table 1 has M = 40, L_min/p = 40.0040 at f = 0.4302, so the
    tight distance has f slightly below 0.4302)."""
    d = Drive.from_links(12, 18, INCH, 40)
    lmin, _, _ = chainmodel.kinematics.wrap_length_range(d)
    assert lmin / INCH == pytest.approx(40.0, abs=1e-6)
    assert d.span_pitches == 11 and 0.42 < d.pitch_fraction < 0.4302


# --- bad input: ValueError naming the parameter and its valid range -------------------------

def _raises(fn, *patterns):
    with pytest.raises(ValueError) as err:
        fn()
    msg = str(err.value)
    for pat in patterns:
        assert re.search(pat, msg), f"{pat!r} not in {msg!r}"
    assert "\n" not in msg
    return msg


@pytest.mark.parametrize("fn, who", [
    (lambda: Drive(2, 18, INCH, 11, 0.4), r"n_driver"),
    (lambda: Drive(12, 2, INCH, 11, 0.4), r"n_driven"),
    (lambda: Drive(0, 18, INCH, 11, 0.4), r"n_driver"),
    (lambda: Drive.from_centre_distance(2, 17, 0.015875, 0.2), r"n_driver"),
    (lambda: Drive.from_links(25, 1, 0.015875, 46), r"n_driven"),
    (lambda: Sprocket(2, INCH), r"teeth"),
])
def test_fewer_than_three_teeth(fn, who):
    _raises(fn, who, r"at least 3")


def test_fractional_teeth():
    _raises(lambda: Drive(12.5, 18, INCH, 11, 0.4), r"n_driver", r"whole number", r"at least 3")


@pytest.mark.parametrize("pitch", [0.0, -0.0254, float("nan"), float("inf")])
def test_non_positive_pitch(pitch):
    _raises(lambda: Drive(12, 18, pitch, 11, 0.4), r"^pitch", r"positive|finite")
    _raises(lambda: Drive.from_centre_distance(12, 18, pitch, 0.3), r"^pitch", r"positive|finite")


@pytest.mark.parametrize("f", [-0.1, 1.0, 1.5, float("nan")])
def test_pitch_fraction_outside_unit_interval(f):
    _raises(lambda: Drive(12, 18, INCH, 11, f), r"pitch_fraction", r"\[0, 1\)")


@pytest.mark.parametrize("n_span", [0, -3])
def test_span_pitches_below_one(n_span):
    _raises(lambda: Drive(12, 18, INCH, n_span, 0.4), r"span_pitches", r">= 1")


def test_overlapping_sprockets_from_pitches():
    # 25/17 teeth: pitch radii 2.0 + 2.7 inch > x_c = 2.4 inch
    msg = _raises(lambda: Drive(25, 17, INCH, 1, 0.4), r"overlap", r"span_pitches")
    # the bound quoted is the sum of the pitch radii
    bound = Sprocket(25, INCH).pitch_radius + Sprocket(17, INCH).pitch_radius
    assert f"{bound:.6g}" in msg


@pytest.mark.parametrize("cd", [0.001, 0.03, 0.09, 0.1065])
def test_overlapping_sprockets_from_centre_distance(cd):
    """xu2010 sprockets (25/17 teeth, p = 15.875 mm): pitch circles touch at 106.53 mm.
    The message must name centre_distance and a lower bound that really works."""
    p = 0.015875
    need = Sprocket(25, p).pitch_radius + Sprocket(17, p).pitch_radius
    msg = _raises(lambda: Drive.from_centre_distance(25, 17, p, cd), r"centre_distance")
    bounds = [float(v) for v in re.findall(r"(\d+\.\d+(?:e-?\d+)?) m", msg)]
    assert any(abs(b - need) < 1e-6 for b in bounds), msg
    # and just above the quoted bound the drive exists
    Drive.from_centre_distance(25, 17, p, need * (1 + 1e-6))


def test_chain_too_short_to_wrap():
    # C1 needs L_min = 40.0040 p (seed 004 Table 1): 39 links cannot wrap it
    _raises(lambda: Drive(12, 18, INCH, 11, 0.4302, links=39), r"39 links", r"too short",
            r"at least 40\.00\d pitches")
    _raises(lambda: chainmodel.preset("C1", links=30), r"30 links", r"too short")
    _raises(lambda: Drive.from_links(25, 17, 0.015875, 20), r"20 links", r"too short")
    _raises(lambda: Drive(12, 18, INCH, 11, 0.4302, links=3), r"links", r">= 4")


def test_good_input_is_accepted():
    d = Drive(12, 18, INCH, 11, 0.4302, links=40)
    assert d.links == 40
    # a chain of M links at the C1 geometry (needs 40.004 pitches: 0.01 % stretch) is accepted
    Drive(12, 18, INCH, 11, 0.4302, links=40)


def test_centre_distance_below_one_whole_span_pitch():
    """Small sprockets: the pitch circles clear each other before the tight span holds one
    whole pitch (N >= 1 needs x_c >= 2 p); the quoted bound must be that one."""
    p = INCH
    msg = _raises(lambda: Drive.from_centre_distance(3, 3, p, 0.04), r"centre_distance",
                  r"one whole pitch")
    assert f"{2 * p:.6g} m" in msg
    d = Drive.from_centre_distance(3, 3, p, 2 * p * (1 + 1e-9))
    assert d.span_pitches == 1


def test_too_few_links_names_the_least_that_wraps():
    """A 20/40 drive of 14 links: the message names the least link count that wraps the
    sprockets at all, and that count does (one fewer does not)."""
    with pytest.raises(ValueError, match=r"14 links.*too short") as err:
        Drive.from_links(n_driver=20, n_driven=40, pitch=0.0127, links=14)
    least = int(re.search(r"at least (\d+) links", str(err.value)).group(1))
    assert Drive.from_links(n_driver=20, n_driven=40, pitch=0.0127, links=least).links == least
    with pytest.raises(ValueError, match=rf"at least {least} links"):
        Drive.from_links(n_driver=20, n_driven=40, pitch=0.0127, links=least - 1)
