"""Levels 0-2 on level 3's statics (``torsional.wrap_statics``; issue 21 items 3-4,
docs/reduced_models.md "One wrap and one static tension from level 3's statics").

* item 4: the 08B fan drive with no pretension near and away from its tight wrap (its spans
  sag; tests/test_span_sag.py for the pretension taking it up): levels 0, 1 and 2 report the static tension level 3's dynamic model holds at rest when
  started from the static equilibrium (0.1 s at rest, its own force law deciding), within 5 %;
  level 1 run at rest holds it too;
* item 3: the wrap's stiffness K_m puts levels 1-2's two-inertia system on level 3's linear
  driven-sprocket mode (checked against tests/linearised.py's own linearisation); C1's and
  xu2010's ring-downs at levels 1 and 2 after a sudden start to 1 and 5 rpm within 3 % of
  level 3's from the same start and of the two-inertia estimate on K_m; each level's own linear mode at rest, from the test's own linearisation, on level 3's;
  xu2010's loaded split, turned quasi-statically, against level 3's statics; level 2's floor
  fitted with its strings' sag (its loaded split is level 1's); the option's fallbacks warn.
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
from linearised import Linearised
from ringdown_check import ring, seat_ladder_spans, two_inertia_frequency

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


@pytest.mark.parametrize("options", [{"torsional_wrap_statics": False}, ON],
                         ids=["seat_ladder", "wrap_statics"])
@pytest.mark.parametrize("dc", [0.0, -0.5e-3, -2e-3, -5e-3])
def test_fan_without_pretension_static_tension_agrees_at_every_level(dc, options):
    """On the seat ladder too (torsional.wrap_statics off): a chain with no pretension that
    the seat ladder leaves slack hangs on its sag, and levels 0-2 carry that tension (wrap_statics.weighted_static_tension: the
    elastic catenary, its sag term from level 3's statics where the weight carries the
    tension); level 2 refuses a chain longer than its wrap (dc < 0) unless the option holds
    its ends, and says so."""
    t3 = _level3_at_rest(dc)
    assert t3 > 1.0                     # the sag tension, not a slack 0
    for level in (0, 1, 2):
        if level == 2 and dc < 0 and options != ON:
            # longer than its wrap: level 2's strings refuse it unless the option holds it
            with pytest.raises(ValueError, match="torsional.wrap_statics"):
                _fan_scene(dc, level, **options).model()
            continue
        t = _fan_scene(dc, level, **options).model().static_tension()
        assert t == pytest.approx(t3, rel=0.05), level
    if options != ON:
        return
    # level 1 with the option turned at 1 rpm through one tooth period from rest: its mean
    # span tension over the tooth holds level 3's (its span law and polygon, not a number; at
    # one driver angle its stiff ends - the mode's stiffness, not the sag's secant - put it a
    # few newtons off the mean, as the seat ladder's do)
    sc = _fan_scene(dc, 1, **options)
    r = chainmodel.simulate(sc, input_speed_rpm=1.0, load_torque=0.0, ramp_time=0.5,
                            duration=1.5 + 60.0 / sc.drive.n_driver, output_interval=1e-3)
    m = r.time >= 1.5
    mean = 0.5 * (r["tight_span.tension"][m].mean() + r["slack_span.tension"][m].mean())
    assert mean == pytest.approx(t3, rel=0.05)


def _estimate(name, **kw):
    """Two-inertia estimate [Hz] on the wrap levels 1-2 take: the spans' stiffness K_m / R_o^2
    on the sprockets' pitch radii (ringdown_check, written apart from wrap_statics'
    closed form)."""
    sc = load_scene(name, fidelity=1, **kw)
    return two_inertia_frequency(sc, wrap_fit(sc.drive, sc.parameters).modal_stiffness
                                 / sc.drive.driven.pitch_radius ** 2)


#: driver positions over a tooth period at which the tests take a tooth-period mean (not
#: wrap_statics.ANGLES: the fit's four positions should give the tooth's mean)
POSITIONS = 8


def _tooth_mean(name, frequency, positions=POSITIONS):
    """The mean of ``frequency(driver_angle)`` over ``positions`` driver positions in a tooth."""
    step = 2.0 * math.pi / load_scene(name).drive.n_driver / positions
    return float(np.mean([frequency(j * step) for j in range(positions)]))


@pytest.mark.parametrize("name", ["C1", "xu2010"])
def test_the_wrap_is_level3s_linear_mode(name):
    """wrap_fit's mode is level 3's linearised driven-sprocket mode of tests/linearised.py
    (another linearisation: MultibodyModel.rhs, not the compiled accelerations, every roller's
    inertia kept where wrap_fit condenses the seated ones), its mean over eight driver positions
    in a tooth period (wrap_fit takes four), within 1 %; and its modal stiffness puts the tests'
    own two-inertia system on it within 0.5 % (the closed form's root checked by an eigenvalue
    solve). Level 3's mode moves over a tooth (C1 24.5-25.3 Hz, its static tension 364-551 N), so
    the mean is a different number from angle 0's there."""
    sc = load_scene(name, fidelity=1, **ON)
    fit = wrap_fit(sc.drive, sc.parameters)
    assert fit.mode == pytest.approx(
        _tooth_mean(name, lambda angle: Linearised(name, angle).driven_mode()), rel=0.01)
    assert _estimate(name, **ON) == pytest.approx(fit.mode, rel=0.005)
    # the static condensation is softer: the spans' own dynamics stiffen the mode
    assert fit.stiffness < fit.modal_stiffness


def _own_driven_frequency(model, angle: float = 0.0) -> float:
    """The model's undamped driven-sprocket mode at rest [Hz], the input shaft held at
    ``angle``, written here apart from chainmodel.models.torsional_mode: central differences
    of ``model.rhs`` over every position state (sprocket angles, string amplitudes q), the rows
    of their accelerations (sprocket speeds, the strings' v: dq/dt = v at rest); the mode with
    the largest share of its kinetic energy in the driven sprocket (the sprockets' mass matrix,
    each string mode's modal mass rho L / 2 of a sine)."""
    u = Inputs(angle, 0.0, 0.0)
    x0 = model.initial_state(u)
    names = model.state_names
    pos = [i for i, n in enumerate(names) if n.endswith(".angle") or ".q" in n]
    acc = [i for i, n in enumerate(names) if n.endswith(".speed") or ".v" in n]
    a = np.empty((len(pos), len(pos)))
    for j, i in enumerate(pos):
        h = 1e-9 if names[i].endswith(".angle") else 1e-10
        up, down = x0.copy(), x0.copy()
        up[i] += h
        down[i] -= h
        a[:, j] = (model.rhs(0.0, up, u)[acc] - model.rhs(0.0, down, u)[acc]) / (2.0 * h)
    angles = [names[i] for i in pos if names[i].endswith(".angle")]
    rho = model.params["chain.link_mass"] / model.drive.pitch
    mass = np.zeros((len(pos), len(pos)))
    mass[:len(angles), :len(angles)] = model.mass_matrix()[-len(angles):, -len(angles):]
    for j, i in enumerate(pos[len(angles):], start=len(angles)):
        span = "up" if "up" in names[i] else "low"
        mass[j, j] = 0.5 * rho * model.reference["l_" + span]
    lam, vec = np.linalg.eig(-a)
    lam, vec = lam.real, vec.real
    driven = angles.index("driven.angle")
    share = [(mass[driven] @ v) * v[driven] / (v @ mass @ v) if w > 0 else -1.0
             for w, v in zip(lam, vec.T)]
    return math.sqrt(lam[int(np.argmax(share))]) / (2.0 * math.pi)


@pytest.mark.parametrize("level", [1, 2])
@pytest.mark.parametrize("name", ["C1", "xu2010"])
def test_each_level_is_fitted_on_its_own_linear_mode(name, level):
    """Item 3: levels 1 and 2 with the option have a linear driven-sprocket mode at rest whose
    mean over the fit's four driver positions in a tooth is level 3's (wrap_fit.mode, itself
    checked against tests/linearised.py above) within 0.1 %, from this test's own
    linearisation of the level. The two-inertia fit K_m alone misses it (measured on these
    scenes: level 2 +3.1 % on C1, its string modes at 17-19 Hz pushing the mode up; -0.44 % on
    xu2010 at both levels; level 1 on C1 -0.19 %), so within 0.1 % is the levels' own fit
    (chainmodel.models.torsional_mode, tolerance 1e-5)."""
    sc = load_scene(name, fidelity=level, **ON)
    target = wrap_fit(sc.drive, sc.parameters).mode
    model = sc.model()
    f = _tooth_mean(name, lambda angle: _own_driven_frequency(model, angle), positions=4)
    assert f == pytest.approx(target, rel=0.001)


TIGHT = {"drive_centre_distance": 0.0, "static_tension": None}


def test_the_fitted_mode_is_continuous_where_two_alike_spans_split_their_string_modes():
    """xu2010 at its tight centre distance (the seat ladder's, 0 mm) with 450-452 N of
    pretension: its two spans are alike, their string modes lie 0.06-0.35 % apart near 170 Hz and
    their shapes turn within their plane from one pretension or driver position to the next.
    One newton of pretension moves a linear mode by a few tenths of a per cent at most; the
    picker that took each of the pair on its own took 535 Hz at 451 N (one of the pair fell
    below the share gate) and refused the fit at 450.7-451.7 N."""
    modes = []
    for pretension in (450.0, 451.0, 452.0):
        sc = load_scene("xu2010", fidelity=1, chain_pretension=pretension, **TIGHT)
        modes.append(wrap_fit(sc.drive, sc.parameters).mode)
    assert max(modes) / min(modes) < 1.005, modes


def test_level2_is_fitted_where_its_mode_barely_moves_with_the_wrap_stiffness():
    """The tight xu2010 drive at 150 N static tension (pretension 452 N): level 2's span ends
    are already stiff next to its links, so its mode moves as K^0.07, not K^0.5, and the
    square-root update did not converge in its 12 passes (the fit fell back to K_m). With the
    secant update level 2's own mode, from this test's linearisation over the fit's four driver
    positions, is level 3's within 0.1 %, and nothing is reported."""
    from chainmodel.models.wrap_statics import fallbacks, tooth_positions
    sc = load_scene("xu2010", fidelity=2, static_tension=150.0,
                    drive_centre_distance=0.0)
    model = sc.model()
    assert fallbacks(sc.drive, sc.parameters, 2) == []
    f = float(np.mean([_own_driven_frequency(model, a) for a in tooth_positions(sc.drive)]))
    assert f == pytest.approx(wrap_fit(sc.drive, sc.parameters).mode, rel=0.001)


@pytest.mark.parametrize("rpm", [1.0, 5.0])
@pytest.mark.parametrize("name,level", [("C1", 1), ("C1", 2), ("xu2010", 1), ("xu2010", 2)])
def test_torsional_mode_levels_1_2_on_level3s_wrap(name, level, rpm):
    """Item 3: the driven sprocket's ring-down of levels 1-2 with the option within 3 % of the
    two-inertia estimate on their wrap and of level 3's ring-down from the same start; 1 rpm
    (small amplitude: the mode) and the issue's 5 rpm. The estimate is linear: at 5 rpm the
    ring softens with its amplitude (level 3 on C1: -2.9 % from it; level 1 -2.4 % since its
    spans carry their lagged sag, -4.0 % before)."""
    est = _estimate(name, **ON)
    band = (0.85 * est, 1.15 * est)
    f = ring(name, level, band, rpm, **ON)
    f3 = ring(name, 3, band, rpm)
    # levels 1-2 are the two-inertia system on K_m (their own dynamics hold what they are given)
    assert f == pytest.approx(est, rel=0.03)
    # and that is level 3's mode
    assert f == pytest.approx(f3, rel=0.03)


_SAGGING_08B = """
name = "08B 13/39, no pretension"
chain = "08B"
fidelity = "torsional"
duration = 0.5
[operating]
input_speed_rpm = 300.0
load_torque = 8.0
[parameters]
"drive.driver_teeth" = 13
"drive.driven_teeth" = 39
"drive.pitch" = 0.0127
"drive.links" = 108
"drive.centre_distance" = 0.0
"""


def test_sagging_drive_mode_is_level3s_ring_down(tmp_path):
    """A drive the presets do not hold (08B 13/39, tight wrap, no pretension: its spans carry
    their sag tension, about 50 N): level 3's ring-down (sudden start to 5 rpm) is the linear
    mode linear_driven_modes picks within 3 % - the mode choice checked by level 3's own
    dynamics, not by the linearisation - and level 1 on the wrap within 3 % of it. The statics'
    secant is its sag's, about a fifth of the stiffness the mode needs: level 1 on it, or on
    the seat ladder with the quasi-static sag (torsional.wrap_statics off), rings 30-40 % low."""
    path = tmp_path / "sagging.toml"
    path.write_text(_SAGGING_08B)
    sc = load_scene(str(path), fidelity=1, **ON)
    fit = wrap_fit(sc.drive, sc.parameters)
    assert fit.modal_stiffness > 2.0 * fit.stiffness
    band = (0.7 * fit.mode, 1.3 * fit.mode)
    f3 = ring(str(path), 3, band)
    assert f3 == pytest.approx(fit.mode, rel=0.03)
    assert ring(str(path), 1, band, **ON) == pytest.approx(f3, rel=0.03)


_ROLLER_MODE_16A = """
name = "16A 13/13"
chain = "16A"
fidelity = "torsional"
duration = 0.5
[operating]
input_speed_rpm = 200.0
load_torque = 300.0
static_tension = 1112.0
[parameters]
"drive.driver_teeth" = 13
"drive.driven_teeth" = 13
"drive.pitch" = 0.0254
"drive.links" = 94
"drive.centre_distance" = 0.0
"""


def test_a_kilohertz_roller_mode_with_the_largest_share_is_not_the_driven_sprockets(tmp_path):
    """A drive the presets do not hold (16A 13/13 written by ``chainmodel new-scene``, 2 % of
    the breaking load as pretension): level 3 linearised at rest puts the largest share of
    kinetic energy in the driven sprocket into a kHz mode of the span rollers beside it, whose
    shape has nothing of the static wrap's (MAC below 0.05), and the torsional mode has a
    quarter of that share. A gate on the share refused the fit (the thirteenth session); the
    gate on the response (multibody_statics.mode_measures: the driven sprocket's speed in each
    mode when the drive is set moving in the wrap's shape) keeps the torsional mode. Checked by
    level 3's own dynamics over a wide band: the strongest peak of its ring-down (sudden
    start to 5 rpm) in 10 Hz-5 kHz is the fitted mode within 3 %, and levels 1-2 on the fit ring
    within 3 % of it."""
    from chainmodel.models.multibody_statics import linearised_modes, mode_measures
    path = tmp_path / "roller_mode.toml"
    path.write_text(_ROLLER_MODE_16A)
    sc = load_scene(str(path), fidelity=1, **ON)
    fit = wrap_fit(sc.drive, sc.parameters)
    m3 = load_scene(str(path), fidelity=3).model()
    lam, phi, mass, driven, ref, _ = linearised_modes(m3, static_state(m3))
    share, mac, _ = mode_measures(lam, phi, mass, driven, ref)
    top = int(np.argmax(share))
    assert mac[top] < 0.05
    assert math.sqrt(lam[top]) / (2.0 * math.pi) > 5.0 * fit.mode
    f3 = ring(str(path), 3, (10.0, 5000.0))
    assert f3 == pytest.approx(fit.mode, rel=0.03)
    for level in (1, 2):
        assert ring(str(path), level, (10.0, 5000.0), **ON) == pytest.approx(f3, rel=0.03)


def test_the_mode_is_continued_where_the_static_shape_turns_into_the_shafts():
    """xu2010 with half its contact stiffness (the trade study's band): at the driver's third
    position of four the static condensation's driven-sprocket mode is the flexible input
    shaft's (174 Hz) rather than the wrap's (517-539 Hz at the other three), so against its
    shape the wrap's mode has no response; the continuation (``near``) counts a mode that turns
    the driven sprocket by its share too. The fit's tooth-period mean is level 3's ring-down
    (sudden start to 5 rpm) within 3 %, read above the driver's own frequency on its shaft,
    1.1 sqrt(k_s / J_1) (the shaft mode, 175 Hz, rings 26 times stronger there; levels 1-2 carry
    their own). A gate on the response alone at every position took the shaft mode at that
    position and fitted 464 Hz, -16 %."""
    over, fit, shaft = _xu2010_band("contact.stiffness", 0.5)
    f3 = ring("xu2010", 3, (1.1 * shaft, 5000.0), parameters=over)
    assert fit.mode == pytest.approx(f3, rel=0.03)


def test_on_a_shaft_stiffer_than_the_chain_the_wrap_is_the_lower_mode():
    """xu2010 on a 120 kN.m/rad input shaft (an independent audit): the static mode whose pitch
    circles move against each other is now the driver rattling on its shaft (about 0.73 of its
    strain energy in the shaft), and the chain's mode is the lower one. The fit takes the
    chain's (the anti-phase mode is taken only where it keeps less of its strain in the shaft
    than the other): the fit's mode and level 1's ring within 3 % of level 3's strongest peak
    below 0.9 sqrt(k_s / J_1)."""
    from ringdown_check import peak_frequency, ring_run
    over = {"input_shaft.stiffness": 120e3}
    sc = load_scene("xu2010", fidelity=1, **over)
    fit = wrap_fit(sc.drive, sc.parameters)
    own = math.sqrt(120e3 / sc.parameters["driver.inertia"]) / (2.0 * math.pi)
    band = (50.0, 0.9 * own)
    f3 = peak_frequency(ring_run("xu2010", 3, parameters=over), band)
    assert fit.mode == pytest.approx(f3, rel=0.03)
    assert peak_frequency(ring_run("xu2010", 1, parameters=over, **ON), band) == pytest.approx(
        f3, rel=0.03)


def _xu2010_band(what, factor):
    """(overrides, wrap fit, the driver's own frequency on its shaft sqrt(k_s / J_1) [Hz]) of
    xu2010 with the trade study's uncertain value ``what`` scaled by ``factor``."""
    from chainmodel.analysis.trade_study import band_overrides
    over = band_overrides(load_scene("xu2010", fidelity=1), what, factor)
    sc = load_scene("xu2010", fidelity=1, **over)
    p = sc.parameters
    own = math.sqrt(p["input_shaft.stiffness"] / p["driver.inertia"]) / (2.0 * math.pi)
    return over, wrap_fit(sc.drive, p), own


@pytest.mark.parametrize("clearance, shaft", [(2.0, 12e3), (2.0, 16e3), (1.0, 32e3)],
                         ids=["clearance x2", "clearance x2, shaft 16 kN.m/rad",
                              "shaft 32 kN.m/rad"])
def test_on_a_flexible_shaft_the_wrap_is_fitted_on_the_chains_mode_not_the_shafts(clearance,
                                                                                 shaft):
    """xu2010 on its flexible input shaft has two static modes: the shaft's (both pitch circles
    moving one way, the chain carried along) and the chain's. With twice its seat clearance the
    chain sits deeper in its seats, its static tension falls to about 226 N, and the largest
    share of the driven sprocket moves to the shaft's mode (about 172 Hz), which the wrap's
    stiffness hardly moves; fitted on it, levels 1-2 rang at 476 Hz where level 3 rings at 547 Hz
    (-13 %). A stiffer shaft (an independent audit: 16 kN.m/rad at twice the clearance, 32 at the
    nominal one) brings the two closer and mixes them; a bound on the chain's mode's shaft share
    (0.25) then fell back to the largest share, -10.4 / -6.4 %. The anti-phase mode is taken
    where it keeps less of its strain energy in the shaft than the other at every position the
    fit reads (multibody_statics.WRAP_SHARE, wrap_statics._tooth_modes), and levels 1-2 ring
    with level 3 in both modes: the chain's, read above the driver's own frequency on its shaft,
    1.1 sqrt(k_s / J_1), within 3 % of level 3's and of the fit's mode; the shaft's, in
    0.3-0.9 of it, within 4 % (measured +2.5 to +2.9 %). One run per level gives both peaks."""
    from ringdown_check import peak_frequency, ring_run
    from chainmodel.analysis.trade_study import band_overrides
    over = dict(band_overrides(load_scene("xu2010", fidelity=1), "seat_clearance", clearance),
                **{"input_shaft.stiffness": shaft})
    sc = load_scene("xu2010", fidelity=1, **over)
    fit = wrap_fit(sc.drive, sc.parameters)
    own = math.sqrt(shaft / sc.parameters["driver.inertia"]) / (2.0 * math.pi)
    chain_band, shaft_band = (1.1 * own, 5000.0), (0.3 * own, 0.9 * own)
    r3 = ring_run("xu2010", 3, parameters=over)
    chain3, shaft3 = peak_frequency(r3, chain_band), peak_frequency(r3, shaft_band)
    assert fit.mode == pytest.approx(chain3, rel=0.03)
    for level in (1, 2):
        r = ring_run("xu2010", level, parameters=over, **ON)
        assert peak_frequency(r, chain_band) == pytest.approx(chain3, rel=0.03)
        assert peak_frequency(r, shaft_band) == pytest.approx(shaft3, rel=0.04)


def test_where_the_modes_swap_over_a_tooth_the_coarse_drive_keeps_the_larger_share():
    """The trade study's 6/9-tooth drive at xu2010's pitch (16 links at the tight distance,
    400 N, 5 N m at 300 rpm): the wrap's static mode (pitch circles against each other) exists
    at two of the fit's four driver positions only, so the fit follows the larger share at all
    four (wrap_statics._tooth_modes) and says so. Taken where it exists, the wrap's stiffer fit
    could not hold level 3's tooth-period-mean static tension (about 207 N against 400 N at
    angle 0) and levels 1-2 ran about 30 % high on the mean tight span. Checked against level
    3: the spans hold the mean of its statics at the four positions (solved here), the one
    note is the modes' swap, and levels 1-2's mean tight span over the study's steady half is
    within 5 % of level 3's."""
    from chainmodel.analysis.trade_study import SCENES
    from chainmodel.models.wrap_statics import fallbacks, tooth_positions
    spec = next(s for s in SCENES if s.name.startswith("coarse"))
    sc = spec.scene()
    fit = wrap_fit(sc.drive, sc.parameters)
    m3 = sc.with_overrides(fidelity=3).model()
    held = np.mean([static_state(m3, a).mean_tension for a in tooth_positions(sc.drive)])
    assert fit.held_tension == pytest.approx(held, rel=1e-3)
    tights = {}
    for level in (1, 2, 3):
        r = chainmodel.simulate(sc.with_overrides(fidelity=level))
        steady = r.time >= 0.5 * r.time[-1]
        tights[level] = r["tight_span.tension"][steady].mean()
        if level < 3:
            notes = fallbacks(sc.drive, sc.with_overrides(fidelity=level).parameters, level)
            assert len(notes) == 1 and "swap roles" in notes[0], notes
    for level in (1, 2):
        assert tights[level] == pytest.approx(tights[3], rel=0.05), level


@pytest.mark.parametrize("shaft, swapped", [(16e3, False), (20e3, True)])
def test_where_the_modes_swap_over_a_tooth_levels_1_2_say_so(shaft, swapped):
    """xu2010 at twice its seat clearance: on a 16 kN.m/rad shaft the wrap's static mode is
    found at all four driver positions and followed; on a 20 kN.m/rad one it falls below the
    share floor at one, the fit follows the larger share, and levels 1-2 say so
    (wrap_statics_fallback, "swap roles"). The warning is checked against level 3's ring-down:
    where it is given, level 1's chain mode (above 1.1 sqrt(k_s / J_1)) is more than 3 % off
    level 3's (measured -8.8 %); where not, within 3 %."""
    from chainmodel.analysis.trade_study import band_overrides
    from chainmodel.models.wrap_statics import fallbacks
    from ringdown_check import peak_frequency, ring_run
    over = dict(band_overrides(load_scene("xu2010", fidelity=1), "seat_clearance", 2.0),
                **{"input_shaft.stiffness": shaft})
    sc = load_scene("xu2010", fidelity=1, **over)
    wrap_fit(sc.drive, sc.parameters)
    notes = fallbacks(sc.drive, sc.parameters, 1)
    assert any("swap roles" in n for n in notes) == swapped, notes
    own = math.sqrt(shaft / sc.parameters["driver.inertia"]) / (2.0 * math.pi)
    band = (1.1 * own, 5000.0)
    f3 = peak_frequency(ring_run("xu2010", 3, parameters=over), band)
    f1 = peak_frequency(ring_run("xu2010", 1, parameters=over, **ON), band)
    assert (abs(f1 / f3 - 1.0) > 0.03) == swapped, (f1, f3)


def test_where_the_modes_swap_over_a_tooth_a_short_chain_rings_with_level3():
    """A 9/9 drive of 20 links at xu2010's pitch and 500 N on its 12 kN.m/rad shaft: the two
    static modes mix the springs and swap roles over a tooth (the wrap's, 361-382 Hz, at three
    positions; at the fourth the other mode's continuation, 191 Hz). Fitted on the wrap's where
    it exists, the tooth's mean (326 Hz) was no mode of either and level 1 rang 12 % below
    level 3 in both of its modes. Followed on the larger share at all four: level 1's strongest
    peak after a sudden start to 5 rpm within 5 % of level 3's (measured -4.2 %)."""
    from ringdown_check import peak_frequency, ring_run
    kw = dict(drive_driver_teeth=9, drive_driven_teeth=9, drive_links=20,
              drive_centre_distance=0.0, static_tension=500.0)
    band = (50.0, 2000.0)
    f3 = peak_frequency(ring_run("xu2010", 3, **kw), band)
    assert peak_frequency(ring_run("xu2010", 1, **kw, **ON), band) == pytest.approx(f3, rel=0.05)


@pytest.mark.parametrize("name, tol", [("fine", 0.03), ("C3", 0.06)])
def test_on_long_sagging_spans_the_mode_is_the_driven_sprockets_not_a_string_mode(name, tol):
    """The 21/63-tooth 16B scene ``fine`` and C3 (0.895 / 0.876 m spans at 500 N): level 3
    linearised at rest takes the driven sprocket's mode, the one level 3's own ring-down shows
    (sudden start to 1 rpm, the strongest peak within 0.6-1.4 x the two-inertia estimate on
    the seat ladder), and not a mode near the spans' first string mode (1 / 2L) sqrt(T_0 /
    rho), whose shape is nearest the static wrap's (mostly the spans' sag) but which hardly
    turns the sprocket (the pick before the share gate: 7.7 Hz on both). C3 within 6 %:
    level 3's ring there moves with the amplitude (16.1 / 14.5 Hz at 1 / 5 rpm: docs/scripts/
    ringdown.py modes)."""
    from chainmodel.models.multibody_statics import linear_driven_modes
    m3 = load_scene(name, fidelity=3).model()
    rest = static_state(m3)
    mode = linear_driven_modes(m3, rest)[0] / (2.0 * math.pi)
    d, p = m3.drive, m3.params
    r1, r2 = d.driver.pitch_radius, d.driven.pitch_radius
    span = math.sqrt(d.centre_distance ** 2 - (r2 - r1) ** 2)
    string = math.sqrt(rest.mean_tension / (p["chain.link_mass"] / d.pitch)) / (2.0 * span)
    assert mode > 2.0 * string
    sc = load_scene(name, fidelity=1)
    est = two_inertia_frequency(sc, seat_ladder_spans(sc))
    assert ring(name, 3, (0.6 * est, 1.4 * est), rpm=1.0) == pytest.approx(mode, rel=tol)


@pytest.mark.parametrize("name", ["C3", "fine"])
def test_a_long_sagging_span_fits_with_its_sag(name):
    """C3 and the 21/63-tooth `fine` (long 16B spans at 500 N): level 3's slack span under the
    fit's load hangs on its sag. Fitted with a floor alone, that floor softened the spans at
    rest below their links and level 3's mode needed ends of negative compliance, so the fit
    was refused; with the spans' parabola sag in the law the floor holds only the rest
    (wrap_fit's ``_ends``), the ends are plausible and the model holds the scene's 500 N.
    Levels 1-2 ring with level 3 at a small start (1 rpm: its linear regime) within 3 %."""
    from chainmodel.models import wrap_statics as W
    sc = load_scene(name, fidelity=1, **ON)
    fit = W.wrap_fit(sc.drive, sc.parameters)
    assert fit.compliance > 0.0
    assert sc.model().static_tension() == pytest.approx(500.0, rel=2e-6)
    assert W.unavailable(sc.drive, sc.parameters) is None
    band = (0.7 * fit.mode, 1.3 * fit.mode)
    f3 = ring(name, 3, band, 1.0)
    for level in (1, 2):
        assert ring(name, level, band, 1.0, **ON) == pytest.approx(f3, rel=0.03), level


def _turning_mean(name, level, rpm):
    """The spans' mean tension [N] over one driver tooth period after 0.3 s, no load, the driver
    turning at ``rpm`` (quasi-static)."""
    period = 60.0 / (rpm * load_scene(name).drive.n_driver)
    r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, load_torque=0.0,
                            duration=0.3 + period, output_interval=1e-3)
    m = r.time >= 0.3
    return 0.5 * (r["tight_span.tension"][m].mean() + r["slack_span.tension"][m].mean())


@pytest.mark.parametrize("name, rpm", [("xu2010", 1.0), ("C1", 2.0)])
def test_the_spans_at_rest_hold_level3s_tooth_period_mean(name, rpm):
    """Level 3's static tension moves over a tooth (C1 373-532 N, 500 N at angle 0, the scene's
    target), and levels 1-2's spans move about what their law holds by their own polygon: over
    one tooth period, turning slowly without load, they carry what level 3's chain carries -
    its own run, not the statics the fit read - within 1.5 % (measured xu2010 -0.1 %, C1
    +0.9 %; holding the angle-0 tension: -2.7 % and +11.7 %). Every level reports the scene's
    static tension, level 3's at angle 0."""
    sc = load_scene(name)
    mean3 = _turning_mean(name, 3, rpm)
    for level in (1, 2):
        model = sc.with_overrides(fidelity=level).model()
        assert model.static_tension() == pytest.approx(
            sc.with_overrides(fidelity=3).model().static_tension(), rel=1e-6)
        assert model.held_tension() == pytest.approx(wrap_fit(sc.drive, model.params)
                                                     .held_tension, rel=1e-9)
        assert _turning_mean(name, level, rpm) == pytest.approx(mean3, rel=0.015)


@pytest.mark.parametrize("load", [20.0, 43.2])
def test_xu2010_quasi_static_split_follows_level3s_statics(load):
    """Level 1 turned at 1 rpm under a load (driver held by a rigid shaft, the driven sprocket
    damped so that it follows quasi-statically; its damping torque taken off the load), mean
    over the last tooth period, against the mean of level 3's static equilibria under the same
    load at 8 driver positions over a tooth: the tight span within 1 %, the slack span within
    5 % (measured -0.2 / -0.3 % at 20 N m, -0.2 / -2.6 % at 43.2 N m; holding the angle-0
    tension instead of level 3's tooth-period mean: -1.5 / -3.6 and +0.8 / +11.3 %; the seat
    ladder: +20 % and +26 %). The floor is fitted at 35 N m (0.75 x 2 T_h R_o), neither of
    these loads, at the fit's 4 positions, not these 8."""
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
    assert r["tight_span.tension"][m].mean() == pytest.approx(t3, rel=0.01)
    assert r["slack_span.tension"][m].mean() == pytest.approx(s3, rel=0.05)


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


def test_a_weaker_fit_is_reported(monkeypatch):
    """The option's two fallbacks each give a warning naming what was used instead: level 3
    without a linear mode (the wrap takes its statics' secant K_3) and a level whose own mode
    cannot be fitted (its ends stay on K_m); level 0, which takes only T_0, does not warn, and
    neither does a fit that worked."""
    from chainmodel.models import multibody_statics as MS
    from chainmodel.models import torsional_mode as TM
    from chainmodel.models import wrap_statics as W

    def fresh_caches():
        for module, name in ((W, "_CACHE"), (W, "_FELL_BACK"), (TM, "_CACHE")):
            monkeypatch.setattr(module, name, {})

    def no_mode(model, rest, near=None, wrap_first=True, choice=None):
        raise ValueError("singular roller stiffness (forced by the test)")

    true_modes = MS.linear_driven_modes

    def only_at_angle_0(model, rest, near=None, wrap_first=True, choice=None):
        if rest.driver_angle != 0.0:
            no_mode(model, rest)
        return true_modes(model, rest, near)

    def notes(result, text):
        return [w for w in result.warnings if "torsional.wrap_statics" in w and text in w]

    fresh_caches()
    monkeypatch.setattr(MS, "linear_driven_modes", no_mode)
    sc = load_scene("xu2010", fidelity=1, **ON)
    r = chainmodel.simulate(sc, duration=0.05, output_interval=1e-3)
    fit = wrap_fit(sc.drive, sc.parameters)
    assert math.isnan(fit.mode) and fit.modal_stiffness == fit.stiffness
    found = notes(r, "secant K_3")
    assert len(found) == 1 and "forced by the test" in found[0]
    r0 = chainmodel.simulate(load_scene("xu2010", fidelity=0, **ON), duration=0.05,
                             output_interval=1e-3)
    assert not notes(r0, "")

    # a mode at angle 0 only: the mean is angle 0's, and the warning says over how many
    monkeypatch.undo()
    fresh_caches()
    monkeypatch.setattr(MS, "linear_driven_modes", only_at_angle_0)
    r = chainmodel.simulate(load_scene("xu2010", fidelity=1, **ON), duration=0.05,
                            output_interval=1e-3)
    fit = wrap_fit(sc.drive, sc.parameters)
    level3 = load_scene("xu2010", fidelity=3).model()
    assert 2.0 * math.pi * fit.mode == pytest.approx(
        true_modes(level3, static_state(level3))[0], rel=1e-9)
    found = notes(r, f"found at 1 of {W.ANGLES} driver positions")
    assert len(found) == 1

    monkeypatch.undo()
    fresh_caches()
    monkeypatch.setattr(TM, "MAX_ITERATIONS", 1)    # K_m alone is 3 % off on C1 at level 2
    sc = load_scene("C1", fidelity=2, **ON)
    r = chainmodel.simulate(sc, duration=0.05, output_interval=1e-3)
    found = notes(r, "could not be fitted")
    assert len(found) == 1 and "did not converge in 1 passes" in found[0]
    model = chainmodel.models.ModalModel(sc.drive, sc.parameters)
    assert model.series_compliance()[0] == wrap_fit(sc.drive, sc.parameters).compliance

    monkeypatch.undo()
    fresh_caches()
    r = chainmodel.simulate(load_scene("C1", fidelity=2, **ON), duration=0.05,
                            output_interval=1e-3)
    assert not notes(r, "")


def test_level2s_floor_holds_the_weight_once():
    """Levels 1 and 2 are fitted to the same level 3 statics; level 2's strings sag under
    gravity by themselves (S_N / T^2 in its span law), so its floor is fitted with that sag and
    its slack span under the fit's load M_a = 0.75 x 2 T_0 R_o, turned quasi-statically
    (1e-3 rpm), is level 1's (which has no sag term with the option) within 0.2 %. Fitted
    without it (the floor holding the weight a second time) level 2 carried 150.9 N against
    149.6 N, +0.9 %."""
    from chainmodel.models.wrap_statics import SLACK_SHARE
    sc = load_scene("xu2010", fidelity=1, **ON)
    fit = wrap_fit(sc.drive, sc.parameters)
    m_a = (1.0 - SLACK_SHARE) * 2.0 * fit.static_tension * sc.drive.driven.pitch_radius
    slack = []
    for level in (1, 2):
        r = chainmodel.simulate("xu2010", fidelity=level, input_speed_rpm=1e-3, load_torque=m_a,
                                ramp_time=0.3, duration=1.0, output_interval=1e-3, **ON)
        slack.append(r["slack_span.tension"][r.time > 0.8].mean())
    assert slack[1] == pytest.approx(slack[0], rel=2e-3)


def test_the_fit_reads_no_damper_and_holds_the_scenes_static_tension():
    """The fit is cached across the dampers and the fidelity (wrap_statics.STATIC_IGNORED):
    its statics are taken at zero velocity and its linear modes undamped, so a damper's force,
    c v, is zero in all of them. Computed afresh (caches cleared) with every damper x3 the
    fit is the same to rounding. And a scene's static_tension, searched on level 3's static
    tension alone (static_span_tension(fitted=False)), is what the fitted model holds at rest:
    the fit's free length is chosen to hold it (the law at rest, a hyperbola's root)."""
    from chainmodel.models import wrap_statics as W
    sc = load_scene("C1", fidelity=1, **ON)
    assert sc.static_tension is not None      # C1 names one

    def fresh(params):
        W._CACHE.clear()
        fit = wrap_fit(sc.drive, params)
        return np.hstack([v for k, v in vars(fit).items() if k != "solves_wall"])

    dampers = [n for n in W.STATIC_IGNORED if n.endswith("damping") and n in sc.parameters
               and isinstance(sc.parameters[n], float)]
    assert len(dampers) >= 5
    changed = dict(sc.parameters, **{n: 3.0 * sc.parameters[n] + 1e-3 for n in dampers})
    np.testing.assert_allclose(fresh(changed), fresh(sc.parameters), rtol=1e-9)
    # level 2's own fit (its linear mode at rest, the modal damping included in the change)
    from chainmodel.models import torsional_mode as TM
    own = []
    for extra in ({}, dict({n: changed[n] for n in dampers}, modal_damping_ratio=0.2)):
        W._CACHE.clear()
        TM._CACHE.clear()
        own.append(TM.fitted_ends(load_scene("C1", fidelity=2, **ON, **{
            k.replace(".", "_"): v for k, v in extra.items()}).model()))
    assert own[0] is not None
    np.testing.assert_allclose(own[1], own[0], rtol=1e-9)
    W._CACHE.clear()
    model = load_scene("C1", fidelity=1, **ON).model()
    assert model.static_tension() == pytest.approx(sc.static_tension, rel=1e-6)


# --- where the fit is refused (docs/reduced_models.md, "Where the fit is refused") ----------

def _loose_xu2010(f):
    """xu2010's 25/17 teeth at 11 span pitches and pitch fraction f, a chain one link longer
    than its longest wrapping length: nowhere stretched, it hangs on its sag at rest."""
    from chainmodel.geometry import Drive
    from chainmodel.kinematics import wrap_length_range
    p = 0.015875
    d = Drive(25, 17, p, 11, f)
    return dict(drive_driver_teeth=25, drive_driven_teeth=17,
                drive_links=math.ceil(wrap_length_range(d)[2] / p),
                drive_centre_distance=d.centre_distance)


@pytest.mark.parametrize("level", [0, 1])
def test_a_chain_hanging_at_rest_gets_no_wrap_fitted_at_rest(level):
    """A loose chain hangs at rest with a few newtons; level 3's mode there is its sag's. Ends
    linear from rest would have to be that soft and stretch the loaded span by metres (level 1
    found no equilibrium under the 43.2 N.m load within 20 teeth). The fit is refused, the
    seat ladder holds the ends, the result warns, and the loaded drive turns at the tooth ratio
    (a span end is a series of springs: it cannot be more compliant than END_RATIO times the
    span's links and seats and still carry the load in place)."""
    from chainmodel.models import wrap_statics as W
    r = chainmodel.simulate("xu2010", fidelity=level, duration=0.2, output_interval=2e-4,
                            ramp_time=0.05, **_loose_xu2010(0.0), **ON)
    found = [w for w in r.warnings if "torsional.wrap_statics = true was not honoured" in w]
    assert len(found) == 1 and "hangs on its sag" in found[0], r.warnings
    # the cause first: the chain is too long for its centre distance (chainmodel.validity);
    # besides it only that the meshing reaches the (slack) span's modes levels 0-1 do not have
    # and that the slack span, a newton under the load, hangs on its weight
    assert found[0].startswith("the chain is too long") and r.warnings[0] == found[0]
    assert all("has no span modes" in w or "hangs on its weight" in w
               for w in r.warnings[1:]), r.warnings
    sc = r.scene
    assert r.static_tension == pytest.approx(
        W.weighted_static_tension(sc.drive, sc.parameters), rel=1e-9)
    mask = r.time >= 0.1
    turns1 = r["driver.angle"][mask][-1] - r["driver.angle"][mask][0]
    turns2 = r["driven.angle"][mask][-1] - r["driven.angle"][mask][0]
    # whole tooth periods are not guaranteed here: the polygon's ripple, at most a driven
    # tooth's angle, bounds the error
    assert abs(turns2 - turns1 * 25 / 17) < 2 * math.pi / 17


def test_a_negative_end_compliance_is_refused():
    """Links at a hundredth of their stiffness: level 3's mode at rest is stiffer than level
    1's spans alone, so the fit would need ends of negative compliance (a spring in series
    cannot stiffen the span). It is refused with that reason, not run."""
    from chainmodel.models import wrap_statics as W
    sc = load_scene("xu2010", fidelity=1, chain_link_stiffness=5.1e5, **ON)
    with pytest.raises(ValueError, match="negative end compliance"):
        W.wrap_fit(sc.drive, sc.parameters)
    r = chainmodel.simulate(sc, load_torque=5.0, input_speed_rpm=40, duration=0.05,
                            output_interval=1e-3)
    assert any("negative end compliance" in w for w in r.warnings)


def test_a_chain_with_no_tension_and_no_weight_is_refused_by_the_ladder_not_a_crash():
    """No pretension and no gravity: the chain carries nothing at rest, so its wrap has no
    stiffness to fit (was a ZeroDivisionError); level 2 then refuses the slack span, as it does
    without the option."""
    loose = chainmodel.Drive.from_links(25, 17, 0.015875, 46, tight_at="max")
    with pytest.raises(ValueError, match="chain.pretension"):
        chainmodel.simulate("xu2010", fidelity=2, duration=0.01, gravity=0.0,
                            drive_centre_distance=loose.centre_distance, **ON)


_REFUSED_16A = """
name = "16A 15/38 at 45 degrees"
chain = "16A"
[operating]
input_speed_rpm = 150.0
load_torque = 200.0
static_tension = 400.0
[parameters]
"drive.driver_teeth" = 15
"drive.driven_teeth" = 38
"drive.links" = 108
"drive.centre_distance" = 0.0
"drive.inclination" = 0.7853981633974483
"""


def test_a_refused_fit_still_holds_the_scenes_static_tension(tmp_path):
    """A 16A 15/38 drive inclined at 45 degrees at 400 N (an audit's drive): the fit is refused
    there (its floor, over the spans' sag, would still need ends of negative compliance); the
    pretension search then solves on the seat ladder's tension, so the model holds the 400 N
    the scene names, within the search's tolerance (1e-6 relative)."""
    path = tmp_path / "refused16a.toml"
    path.write_text(_REFUSED_16A)
    sc = load_scene(str(path), fidelity=1, **ON)
    m = sc.model()
    assert m.static_tension() == pytest.approx(400.0, rel=2e-6)
    from chainmodel.models import wrap_statics as W
    assert "negative end compliance" in W.unavailable(sc.drive, sc.parameters)


@pytest.mark.parametrize("level", [0, 1, 2])
def test_the_speed_limits_read_the_loaded_seats_with_or_without_the_fit(level):
    """The levels' speed limits take the spans' axial mode on their links and loaded seats
    (clearance taken up), with the fit as without it: the fit's ends at rest are softer by the
    clearance the running load takes up (docs/stability.md, "Speed limits")."""
    off = load_scene("xu2010", fidelity=level).model().speed_limit()
    on = load_scene("xu2010", fidelity=level, **ON).model().speed_limit()
    assert on[0] == pytest.approx(off[0], rel=1e-12)


def test_a_chain_hanging_on_its_sag_carries_its_sag_at_levels_0_1(tmp_path):
    """The 08B 13/39 drive with no pretension (its spans hang on their sag, about 54 N): under
    its running load level 3's slack span keeps about 40 N. With the spans' sag in levels 0-1's
    law (torsional.sag_lag, the default: level 1's lagged, level 0's quasi-static) they keep
    it too, within 12 % of level 3's mean over the run's second half (measured -9 %), and do
    not warn. Without it (the law before the twentieth session) they let it fall more than
    ``SHORTFALL`` below level 3's, and say so (code slack_span_sag) - a claim true of their
    own runs; level 2, whose strings sag, never warns; xu2010 warns at no level."""
    from chainmodel.models.wrap_statics import SHORTFALL
    from chainmodel.validity import geometry_problems
    path = tmp_path / "sagging.toml"
    path.write_text(_SAGGING_08B)
    slack = {}
    for lag in (True, False):
        for level in (0, 1, 2, 3):
            if level in (2, 3) and not lag:
                continue
            r = chainmodel.simulate(str(path), fidelity=level, duration=0.5,
                                    torsional_sag_lag=lag)
            m = r.time >= 0.25
            slack[level, lag] = r["slack_span.tension"][m].mean()
            warned = [w for w in r.warnings if "falls short of level 3's" in w]
            assert len(warned) == (1 if level in (0, 1) and not lag else 0), (level, lag)
    for level in (0, 1):
        assert slack[level, True] == pytest.approx(slack[3, True], rel=0.12), level
        assert slack[level, False] < (1.0 - SHORTFALL) * slack[3, True]
        sc = load_scene(str(path), fidelity=level, torsional_sag_lag=False)
        sc.model()
        assert "slack_span_sag" in [p.code for p in geometry_problems(sc.drive, sc.parameters,
                                                                      level)]
    assert slack[2, True] > (1.0 - SHORTFALL) * slack[3, True]
    for level in (0, 1, 2):
        r = chainmodel.simulate("xu2010", fidelity=level, duration=0.02)
        assert not [w for w in r.warnings if "falls short of level 3's" in w]


def test_a_slack_chain_without_gravity_gives_no_raw_scipy_warning(tmp_path):
    """No pretension and no gravity on an 08B 19/38 drive whose 110 links wrap tightly (the
    fuzz's reproducer): level 3's rollers have no static stiffness (the condensed matrix is
    singular to rcond ~1e-25). The wrap fit is refused in Result.warnings, and scipy's
    LinAlgWarning does not leak past it."""
    import warnings
    import scipy.linalg
    import chainmodel
    path = tmp_path / "nogravity.toml"
    path.write_text('name = "08B 19/38 no gravity"\nchain = "08B"\n[operating]\n'
                    'input_speed_rpm = 300\nload_torque = 15\n[parameters]\n'
                    '"drive.driver_teeth" = 19\n"drive.driven_teeth" = 38\n'
                    '"drive.pitch" = 0.0127\n"drive.links" = 110\n"drive.centre_distance" = 0.0\n'
                    '"chain.pretension" = 0.0\n"gravity" = 0.0\n')
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = chainmodel.simulate(str(path), fidelity=0, duration=0.05, output_interval=1e-3)
    assert not [w for w in caught if issubclass(w.category, scipy.linalg.LinAlgWarning)]
    assert any("was not honoured" in w for w in r.warnings)
