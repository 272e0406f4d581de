"""Levels 0-1 warn where the meshing reaches the spans' string modes, which they do not have
(chainmodel.validity, "span modes missing"; docs/reduced_models.md, "Running spans on seed
004's presets").

The string frequency is computed here from the drive's geometry (the span as the common
tangent of the two pitch circles, sqrt(a^2 - (R2 - R1)^2), R = p / (2 sin(pi / z))) and the
taut moving string (seed 004 eq 61 with the
gyroscopic factor of an axially moving string, (c^2 - v^2) / (2 l c), c^2 = T / rho), at the
run's own mean slack tension; the threshold's side is asserted only for points at least 15 %
away from it."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

import chainmodel
from chainmodel.scene import load_scene
from chainmodel.validity import SPAN_MODE_SHARE

CODE_TEXT = "has no span modes"


def _first_string_mode(scene, slack: float, rpm: float) -> float:
    """f_1 [Hz] of the slack span at tension ``slack`` (module docstring); ``scene`` a scene
    object, or a preset or scene file loaded here."""
    sc = load_scene(scene) if isinstance(scene, str) else scene
    d = sc.drive
    r1, r2 = (d.pitch / (2.0 * math.sin(math.pi / z)) for z in (d.n_driver, d.n_driven))
    length = math.sqrt(d.centre_distance ** 2 - (r2 - r1) ** 2)
    rho = sc.parameters["chain.link_mass"] / d.pitch
    c2 = slack / rho
    v = d.n_driver * d.pitch * rpm / 60.0
    return (c2 - v * v) / (2.0 * length * math.sqrt(c2))


def _run(name, level, rpm):
    return chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, duration=0.6,
                               output_interval=2e-4)


@pytest.mark.parametrize("name,rpm", [("xu2010", 15.0), ("xu2010", 30.0), ("C1", 30.0),
                                      ("C1", 45.0)])
def test_level1_warns_where_the_meshing_reaches_the_slack_spans_string_mode(name, rpm):
    r = _run(name, 1, rpm)
    d = load_scene(name).drive
    turned = np.abs(r["driver.angle"] - r["driver.angle"][0]) >= 2 * math.pi / d.n_driver
    slack = float(np.mean(r["slack_span.tension"][turned]))
    f_1 = _first_string_mode(name, slack, rpm)
    ratio = (d.n_driver * rpm / 60.0) / f_1
    assert abs(ratio / SPAN_MODE_SHARE - 1.0) > 0.15, ratio    # not on the edge
    warned = [w for w in r.warnings if CODE_TEXT in w]
    assert bool(warned) == (ratio >= SPAN_MODE_SHARE), (ratio, r.warnings)
    if warned:
        named = float(re.search(r"first string mode \(([\d.]+) Hz", warned[0]).group(1))
        assert named == pytest.approx(f_1, rel=0.03)
        assert "fidelity 2 or 3" in warned[0]


def test_level0_warns_as_level1():
    """Level 0 has no span modes either."""
    assert any(CODE_TEXT in w for w in _run("xu2010", 0, 120.0).warnings)


LEVEL2_TEXT = "string mode per span (modal.modes)"


@pytest.mark.parametrize("name,rpm", [("xu2010", 60.0), ("C1", 100.0), ("xu2010", 600.0),
                                      ("C1", 400.0)])
def test_level2_warns_where_the_meshing_reaches_the_second_string_mode(name, rpm):
    """Level 2 holds one string mode per span by default: it warns where the meshing reaches
    LEVEL2_SPAN_MODE_RATIO = 1.5 x the slack span's first string mode (its second harmonic on
    the third mode), f_1 computed here as above at level 2's own mean slack tension; points at
    least 15 % away from the line (xu2010 60 rpm and C1 100 rpm below it, xu2010 600 rpm and
    C1 400 rpm above). The check takes the lower of that tension and the one the spans hold
    where they do not vibrate (the test after the next); at these points both lie on the same
    side of the line."""
    from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO
    r = _run(name, 2, rpm)
    d = load_scene(name).drive
    turned = np.abs(r["driver.angle"] - r["driver.angle"][0]) >= 2 * math.pi / d.n_driver
    f_1 = _first_string_mode(name, float(np.mean(r["slack_span.tension"][turned])), rpm)
    ratio = (d.n_driver * rpm / 60.0) / f_1
    assert abs(ratio / LEVEL2_SPAN_MODE_RATIO - 1.0) > 0.15, ratio
    warned = [w for w in r.warnings if LEVEL2_TEXT in w]
    assert bool(warned) == (ratio >= LEVEL2_SPAN_MODE_RATIO), (ratio, r.warnings)
    assert not any(CODE_TEXT in w for w in r.warnings)      # level 1's sentence is not level 2's
    if warned:
        named = float(re.search(r"first string mode \(([\d.]+) Hz", warned[0]).group(1))
        assert named == pytest.approx(f_1, rel=0.03)
        assert "fidelity 3" in warned[0]


@pytest.mark.parametrize("name,rpm,level", [("xu2010", 120.0, 1), ("xu2010", 21.0, 1),
                                            ("C1", 45.0, 1), ("xu2010", 120.0, 2),
                                            ("xu2010", 60.0, 2)])
def test_the_fmu_path_says_what_the_whole_run_says(name, rpm, level):
    """Sample by sample (the FMU's Monitor.update) the check fires once where the whole run's
    check fires, and not where it does not: xu2010 at 21 rpm sits just below the threshold,
    where a judgement on the start-up's means alone had fired (an independent review). Level
    2's own check likewise, at 120 rpm (above its line) and 60 rpm (below)."""
    from chainmodel.models import ALL_OUTPUTS
    from chainmodel.validity import Monitor

    sc = load_scene(name, fidelity=level)
    r = _run(name, level, rpm)
    names = [o.name for o in ALL_OUTPUTS if o.name in r.names]
    rows = np.column_stack([r[n] for n in names])
    mon = Monitor(sc.drive, sc.parameters, level, names)
    said = []
    for t, row in zip(r.time, rows):
        said += mon.update(t, row, rpm * 2 * math.pi / 60.0, sc.operating.load_torque)
    code, text = (("span_modes_missing", CODE_TEXT) if level == 1 else
                  ("span_modes_beyond", LEVEL2_TEXT))
    whole = any(p.code == code for p in r.problems)
    assert sum(text in s for s in said) == int(whole)
    assert whole == (rpm not in (21.0, 60.0))


def test_a_slack_span_at_its_centrifugal_tension_is_warned():
    """A slack span carrying no more than rho v^2 has its string modes at 0 Hz: every meshing
    frequency is above them (here on made-up outputs: xu2010's geometry turning at 120 rpm,
    the slack span at 0 N)."""
    from chainmodel.validity import output_problems

    sc = load_scene("xu2010", fidelity=1)
    w1 = 4 * math.pi
    t = np.linspace(0.0, 0.3, 3001)
    out = {"driver.angle": w1 * t, "driver.speed": np.full_like(t, w1),
           "driven.speed": np.full_like(t, w1 * 25 / 17), "transmission_error": 0 * t,
           "contact.max_force": 0 * t, "chain.max_link_tension": np.full_like(t, 1100.0),
           "chain.min_link_tension": 0 * t, "slack_span.tension": 0 * t}
    found = [p for p in output_problems(sc.drive, sc.parameters, 1, t, out, w1)
             if p.code == "span_modes_missing"]
    assert len(found) == 1 and "centrifugal tension" in found[0].message


@pytest.mark.fmu
@pytest.mark.parametrize("level", [1, 2])
def test_the_fmu_logs_it_as_fmi2warning_once(chaindrive_fmu, level):
    """Through the built FMU (fmpy): logged once at 120 rpm, not at 15 rpm (f_m / f_1 = 2.2 and
    0.28 in the tests above' terms), at level 1 and, with its own sentence, at level 2."""
    from chainmodel.fmu import simulate_fmu
    text = CODE_TEXT if level == 1 else LEVEL2_TEXT
    for rpm, duration, expected in ((120.0, 0.2, 1), (15.0, 0.6, 0)):
        messages = []
        simulate_fmu(chaindrive_fmu, load_scene("xu2010", fidelity=level, duration=duration,
                                                input_speed_rpm=rpm), log=messages.append)
        warned = [m for m in messages if m.startswith("[WARNING]") and text in m]
        assert len(warned) == expected, (rpm, messages)


def _sample_path(scene, r, names, rows, rpm, force=None):
    """The FMU's path: each row through Monitor.update; per sample, whether the span-modes
    warning has been said by then."""
    from chainmodel.validity import Monitor

    mon = Monitor(scene.drive, scene.parameters, 1, names)
    said, so_far = [], False
    for i, (t, row) in enumerate(zip(r.time, rows)):
        if force is not None:
            row = row.copy()
            row[names.index("contact.max_force")] = force[i]
        so_far = so_far or any(CODE_TEXT in m for m in mon.update(t, row, rpm * math.pi / 30))
        said.append(so_far)
    return said


def test_both_paths_agree_at_every_length_of_a_run_on_the_line():
    """C1 at 36 rpm sits within 1 % of the line, where its slack span swings 205-472 N within a
    tooth period. The whole-run check (the library) and the sample-by-sample one (the FMU) read
    the same samples and judge at the same whole tooth periods, so they agree on every
    prefix of the run (an independent review found the whole-run path counting a partial last
    period and disagreeing on 74 % of run lengths here). A force alarm changing every sample
    (a rising contact force above the breaking load) does not make the sample path judge out
    of turn."""
    from chainmodel.models import ALL_OUTPUTS
    from chainmodel.validity import output_problems

    sc = load_scene("C1", fidelity=1)
    r = chainmodel.simulate("C1", fidelity=1, input_speed_rpm=36.0, duration=1.5,
                            output_interval=2e-4)
    names = [o.name for o in ALL_OUTPUTS]
    rows = np.column_stack([r[n] for n in names])
    said = _sample_path(sc, r, names, rows, 36.0)
    rising = np.linspace(0.0, 2.0 * sc.parameters["chain.breaking_load"], len(r.time))
    assert _sample_path(sc, r, names, rows, 36.0, force=rising) == said
    outputs = {n: r[n] for n in names}
    cuts = np.linspace(len(r.time) // 4, len(r.time), 25).astype(int)
    whole = [any(p.code == "span_modes_missing" for p in output_problems(
        sc.drive, sc.parameters, 1, r.time[:n], {k: v[:n] for k, v in outputs.items()},
        36.0 * math.pi / 30)) for n in cuts]
    assert whole == [said[n - 1] for n in cuts]


def test_level2_warns_where_it_reads_low_below_the_second_string_mode(tmp_path):
    """The gap the twenty-fifth session's line (2 f_1) left: a 12A 8/16 drive of 32 links at
    2 % pretension (`new-scene`'s) at 600 rpm lies at about 1.7 f_1, where level 2 reads both
    spans more than 3 % / 6 % low against level 3 (the criterion the line was drawn on,
    checked here from both runs); it is warned, and f_1 at level 2's mean slack tension, computed
    here, lies at least 10 % above the line (docs/reduced_models.md, "Level 2 beyond its
    modes")."""
    from chainmodel.new_scene import scene_text
    from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO

    path = tmp_path / "12a.toml"
    path.write_text(scene_text(8, 16, 600.0, 0.0, chain="12A", links=32, duration=1.0))
    runs = {level: chainmodel.simulate(str(path), fidelity=level) for level in (2, 3)}
    m = runs[2].time >= 0.6
    tight = {k: float(np.mean(r["tight_span.tension"][m])) for k, r in runs.items()}
    slack = {k: float(np.mean(r["slack_span.tension"][m])) for k, r in runs.items()}
    assert tight[2] < 0.97 * tight[3] and slack[2] < 0.94 * slack[3], (tight, slack)
    ratio = (8 * 600.0 / 60.0) / _first_string_mode(str(path), slack[2], 600.0)
    assert 1.1 * LEVEL2_SPAN_MODE_RATIO < ratio < 2.0, ratio
    assert "span_modes_beyond" in [q.code for q in runs[2].problems]


#: an independent audit's 08A 9/10 drive of 25 links without pretension, 3 N m on the driven
#: shaft (docs/reduced_models.md, "Level 2's spans locked on the meshing"; xu2010's scene with
#: these values)
AUDIT_08A = dict(chain="08A", drive_pitch=0.0127, drive_driver_teeth=9, drive_driven_teeth=10,
                 drive_links=25, drive_centre_distance=0.0, load_torque=3.0,
                 driver_inertia=1.465e-5, driven_inertia=2.199e-5, input_speed_rpm=450.0,
                 duration=1.0)


def test_level2_judges_its_line_where_its_spans_do_not_vibrate():
    """The audit's 08A drive at 450 rpm: level 2's spans lock on the meshing, and their stretch
    lifts its own slack span so far that the meshing at its own mean lies below the line
    (computed here), while at level 3's mean it lies above, and level 2 reads the spans more
    than 3 % / 6 % off level 3 (from both runs here); the old judgement, at level 2's own
    mean, was silent. It is judged now at the lower of that mean and the tension the spans
    hold where they do not vibrate (level 0's quasi-static split), and warned in both the
    library's path and the FMU's (Monitor.update, the load fed sample by sample); the tension
    it names puts the meshing above the line by the formula here."""
    from chainmodel.models import ALL_OUTPUTS
    from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO, Monitor

    runs = {k: chainmodel.simulate("xu2010", fidelity=k, **AUDIT_08A) for k in (2, 3)}
    m = runs[2].time >= 0.6
    tight = {k: float(np.mean(r["tight_span.tension"][m])) for k, r in runs.items()}
    slack = {k: float(np.mean(r["slack_span.tension"][m])) for k, r in runs.items()}
    assert tight[2] > 1.03 * tight[3] and slack[2] > 1.06 * slack[3], (tight, slack)
    sc = runs[2].scene
    f_m = sc.drive.n_driver * 450.0 / 60.0
    own = f_m / _first_string_mode(sc, slack[2], 450.0)
    assert own < LEVEL2_SPAN_MODE_RATIO / 1.1, own
    assert f_m / _first_string_mode(sc, slack[3], 450.0) > LEVEL2_SPAN_MODE_RATIO, slack
    warned = [p.message for p in runs[2].problems if p.code == "span_modes_beyond"]
    assert len(warned) == 1
    named = float(re.search(r"at the ([\d.]+) N its spans hold where they do not vibrate",
                            warned[0]).group(1))
    assert named < slack[3]
    assert f_m / _first_string_mode(sc, named, 450.0) >= LEVEL2_SPAN_MODE_RATIO
    r = runs[2]
    names = [o.name for o in ALL_OUTPUTS if o.name in r.names]
    mon = Monitor(sc.drive, sc.parameters, 2, names)
    said = []
    for t, row in zip(r.time, np.column_stack([r[n] for n in names])):
        said += mon.update(t, row, 450.0 * math.pi / 30.0, sc.operating.load_torque)
    assert sum(LEVEL2_TEXT in s for s in said) == 1
