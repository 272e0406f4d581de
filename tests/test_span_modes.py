"""The spans' string modes in the run summary (chainmodel.models.limits.span_string_frequency,
nearest_span_resonance; chainmodel.analysis.summary.span_modes).

Numbers from physics computed here: the first transverse mode of a taut string of length l and
mass rho per metre under tension T is (1 / 2 l) sqrt(T / rho); a string moving at v under the
material tension T carries rho v^2 of it as centrifugal tension (seed 004 eq 61 uses the rest)
and vibrates at (c^2 - v^2) / (2 l c), c^2 = T / rho (the travelling string, Wickert & Mote
1990); the two tangent spans of a two-sprocket drive are equally long.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.models.limits import nearest_span_resonance, span_string_frequency
from chainmodel.scene import load_scene


def test_a_string_at_rest_has_its_textbook_frequency_and_moving_loses_its_centrifugal_part():
    # 0.5 m of 10B chain (0.95 kg/m) at 400 N: (1 / 1 m) sqrt(400 / 0.95) = 20.52 Hz
    assert span_string_frequency(0.5, 400.0, 0.0, 0.95) == pytest.approx(math.sqrt(400 / 0.95))
    # at 10 m/s, 95 N of the 400 N is centrifugal
    assert span_string_frequency(0.5, 400.0, 10.0, 0.95) == pytest.approx(math.sqrt(305 / 0.95))
    # nothing beyond the centrifugal tension: no transverse stiffness
    assert span_string_frequency(0.5, 95.0, 10.0, 0.95) == 0.0
    # the travelling string's own frequency (c^2 - v^2) / (2 l c), c^2 = T / rho: lower by
    # sqrt(1 - rho v^2 / T)
    c = math.sqrt(400 / 0.95)
    assert span_string_frequency(0.5, 400.0, 10.0, 0.95, moving=True) == pytest.approx(
        (c * c - 100.0) / (2 * 0.5 * c))


def test_the_nearest_resonance_is_the_smallest_detuning_over_harmonics_modes_and_spans():
    # meshing 25 Hz; slack 23 Hz, tight 83 Hz: the candidates k 25 / (n f1) - 1 for k = 1, 2 and
    # n = 1-3; the nearest is the meshing on the slack mode 1 (+8.7 %), not twice it on the
    # tight span's mode 1 (50 / 83 - 1 = -40 %) or on the slack mode 2 (+8.7 % as well: the first
    # found, the lower harmonic, is kept)
    span, k, n, detuning = nearest_span_resonance(25.0, {"tight": 83.0, "slack": 23.0})
    assert (span, k, n) == ("slack", 1, 1)
    assert detuning == pytest.approx(25.0 / 23.0 - 1.0)
    # the tight span's mode 2 at exactly twice the meshing
    assert nearest_span_resonance(25.0, {"tight": 50.0, "slack": 7.1})[:3] == ("tight", 2, 1)
    # at rest there is no meshing, and a span without tension has no mode
    assert nearest_span_resonance(0.0, {"tight": 83.0, "slack": 23.0})[0] == ""
    assert nearest_span_resonance(25.0, {"tight": 0.0, "slack": 0.0})[0] == ""


@pytest.mark.parametrize("rpm,k,detuning_range", [(30.0, 2, (0.08, 0.13)),
                                                   (60.0, 1, (0.08, 0.14))])
def test_the_summary_reports_the_slack_span_on_xu2010s_meshing(rpm, k, detuning_range):
    """xu2010 under its 43.2 N m at level 1: the summary's span modes are the string formula at
    the run's own mean span tensions (computed here from the outputs, the span length from the
    tooth-period geometry), and the nearest match is the slack span's first mode, at k times
    the meshing (docs/reduced_models.md: +10.4 % and +11.3 % at level 1's tension)."""
    r = chainmodel.simulate("xu2010", fidelity=1, input_speed_rpm=rpm, duration=0.6,
                            output_interval=2e-4)
    s = r.summary()
    d, p = r.scene.drive, r.scene.parameters
    mask = r.time >= s["steady_from_s"]
    rho = p["chain.link_mass"] / d.pitch
    w = float(np.mean(r["driver.speed"][mask]))
    v = d.n_driver * d.pitch * w / (2 * math.pi)
    model = load_scene("xu2010", fidelity=1).model()
    length = model.reference["l_up"]
    assert model.reference["l_low"] == pytest.approx(length, rel=1e-3)
    for key, output in (("slack_span_mode_hz", "slack_span.tension"),
                        ("tight_span_mode_hz", "tight_span.tension")):
        tension = float(np.mean(r[output][mask]))
        c = math.sqrt(tension / rho)              # the travelling string: (c^2 - v^2) / (2 l c)
        expected = (c * c - v * v) / (2 * length * c)
        assert s[key] == pytest.approx(expected, rel=1e-3), key
    words = "meshing" if k == 1 else f"{k} x meshing"
    assert s["span_resonance"] == f"{words} on the slack span's mode 1"
    mesh = d.n_driver * rpm / 60.0
    assert s["span_resonance_detuning"] == pytest.approx(
        k * mesh / s["slack_span_mode_hz"] - 1.0, rel=1e-2)
    assert detuning_range[0] < s["span_resonance_detuning"] < detuning_range[1]


def test_level2_modal_frequencies_are_the_same_string():
    """Level 2's Galerkin frequencies (seed 004 eq 61) are m times the summary's first mode at
    the same tension and chain speed: one formula."""
    m = load_scene("xu2010", fidelity=2).model()
    rho = m.params["chain.link_mass"] / m.drive.pitch
    w = m.modal_frequencies(300.0, 5.0, "upper") / (2 * math.pi)
    f1 = math.sqrt((300.0 - rho * 25.0) / rho) / (2 * m.reference["l_up"])
    assert w == pytest.approx(f1 * np.arange(1, m.n_modes + 1), rel=1e-12)


def test_a_drive_at_rest_has_no_span_resonance():
    """At 0 rpm the meshing frequency is zero: the summary names no match (its mean speed is
    round-off, 1e-16 rad/s, which must not read as a meshing harmonic 100 % below a mode), and
    the spans still report their modes at the loaded tensions."""
    s = chainmodel.simulate("xu2010", fidelity=1, input_speed_rpm=0.0, duration=0.1).summary()
    assert s["span_resonance"].startswith("none")
    assert math.isnan(s["span_resonance_detuning"])
    assert s["slack_span_mode_hz"] > 0.0 and s["tight_span_mode_hz"] > s["slack_span_mode_hz"]


def test_a_meshing_above_the_third_modes_names_no_mode():
    """xu2010 at 2000 rpm (meshing 833 Hz; the spans' first modes at the running tensions are
    tens of Hz): the meshing lies far above both spans' third modes, among dense higher modes
    spaced by f_1, so the row names none of modes 1-3 (it printed "mode 3, +NNN %", which an
    audit read as clear of resonance) and gives the meshing over each first mode, checked here
    from the string frequencies the summary reports."""
    r = chainmodel.simulate("xu2010", fidelity=1, input_speed_rpm=2000.0, duration=0.1,
                            ramp_time=0.02)
    s = r.summary()
    mesh = 25 * 2000.0 / 60.0
    assert mesh > 4.5 * max(s["tight_span_mode_hz"], s["slack_span_mode_hz"])
    assert s["span_resonance"].startswith("none of modes 1-3")
    assert math.isnan(s["span_resonance_detuning"])
    assert f"{mesh / s['slack_span_mode_hz']:.3g} x the slack span's" in s["span_resonance"]
