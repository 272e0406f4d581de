"""The trade-off study behind `chainmodel bench`: each level against a reference level."""

import json
import math
from pathlib import Path

import numpy as np
import pytest

from chainmodel.analysis.tradeoff import FIGURES, format_table, tradeoff
from chainmodel.cli import main


def test_reference_level_has_no_deviation_and_power_balance_holds_at_every_level():
    rows = tradeoff("xu2010", levels=(0, 1), reference=1, duration=0.2, warmup=False,
                    output_interval=1e-3)
    by_level = {r.level: r for r in rows}
    assert set(by_level) == {0, 1}
    for key, _, _ in FIGURES:
        assert by_level[1].deviation[key] == 0.0
    for r in rows:
        assert r.wall_per_simulated_second > 0
        # steady state: the input shaft supplies the load's torque through the exact tooth ratio
        assert r.figures["mean_input_torque"] == pytest.approx(43.2 * 25 / 17, rel=2e-3)
        assert r.figures["dominant_frequency"] == pytest.approx(50.0, abs=10.0)  # one 10 Hz bin
    table = format_table(rows, reference=1)
    assert table.count("\n") == 2 + len(rows)


def test_bench_cli_json(capsys):
    assert main(["bench", "xu2010", "--levels", "0", "--reference", "0", "--duration", "0.1",
                 "--output-interval", "1e-3", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["reference_level"] == 0
    (row,) = data["levels"]
    assert row["name"] == "kinematic"
    assert all(math.isclose(v, 0.0) for v in row["relative_deviation"].values() if v is not None)


def test_bench_cli_refuses_bad_levels(capsys):
    assert main(["bench", "--levels", "0,7"]) == 2
    assert "levels 0-3" in capsys.readouterr().err


# --- issue 11: the measured trade over many scenes and fidelity="auto" -------------------------

import chainmodel  # noqa: E402
from chainmodel import fidelity_auto as auto  # noqa: E402
from chainmodel.analysis import trade_study as study  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from chainmodel.simulation import run_scene  # noqa: E402


@pytest.mark.parametrize("output", ["chain.max_link_tension", "contact.max_force",
                                    "chain.min_link_tension"])
def test_auto_picks_multibody_for_outputs_only_level3_computes(output):
    # below level 3 these are quasi-static estimates (output_descriptions): whatever the table
    # says about the other figures, only level 3 computes them
    for rpm in (30, 120):
        choice = auto.choose(load_scene("xu2010", input_speed_rpm=rpm),
                             ["driven.speed", output], 0.2)
        assert choice.level == 3 and choice.overrides["fidelity"] == 3
        assert "level 3 forced" in choice.message
    desc = load_scene("xu2010", fidelity=1).model().output_descriptions()[output]
    assert desc.startswith(chainmodel.models.base.QUASI_STATIC)


def test_auto_through_simulate_logs_its_choice_and_runs_that_level():
    r = chainmodel.simulate("xu2010", fidelity="auto", outputs=["contact.max_force"],
                            accuracy=0.05, duration=0.01, output_interval=1e-3)
    assert r.fidelity == 3 and r.auto_choice.level == 3
    assert any("fidelity auto" in w and "tradeoff.csv" in w for w in r.warnings)


def _log_features(r):
    """The groups fidelity_auto places scenes by, written here again: natural logs of the
    mesh/mode and mesh/span ratios, 1 + load/static, both tooth counts and the pitch."""
    return (math.log(r["mesh_over_mode"] + 1e-3), math.log(r["mesh_over_span"] + 1e-3),
            math.log(1.0 + r["load_over_static"]), math.log(r["z1"]), math.log(r["z2"]),
            math.log(r["pitch_mm"]))


def _rule(rows, features, figures, target, accepted_levels):
    """The selection rule of docs/tradeoff.md computed directly on the table rows: among the
    scenes with a valid reference inside validity, the neighbours within distance 1 (or the
    nearest); per configuration the worst error over them, over their bands and against their
    nominal references; a configuration meets the target only if measured on every neighbour;
    the cheapest meeting it, else the most accurate (those measured everywhere first). Returns
    (config, its error, met, promised): promised when met and at least half of the error is
    the level's own (against the nominal reference), or the drive is a measured scene itself;
    a ripple figure (speed and torque ripple, mesh amplitude, transmission error) only from
    two neighbours at least; a span tension of levels 0-2 only where the meshing lies below
    the level's span-modes warning line (chainmodel.validity: 0.4 of the first string mode at
    levels 0-1, 1.5 at level 2), that mode taken at the static tension (mesh_over_span). For a
    span tension, where a level 0-2 below its line meets the target, the configurations of
    levels above theirs are not chosen."""
    from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO, SPAN_MODE_SHARE
    line = {0: SPAN_MODE_SHARE, 1: SPAN_MODE_SHARE, 2: LEVEL2_SPAN_MODE_RATIO}
    sources = {}
    for r in rows:
        if r["status"] == "ok" and not r["reference_problems"]:
            sources.setdefault(r["scene"], []).append(r)
    here = _log_features(features)
    dist = {n: math.dist(here, _log_features(rs[0])) for n, rs in sources.items()}
    nearest = min(dist, key=dist.get)
    near = [n for n in dist if dist[n] <= 1.0] or [nearest]
    worst, nominal, seen = {}, {}, {}
    for n in near:
        for r in sources[n]:
            c = r["config"]
            worst[c] = max(worst.get(c, 0.0), max(r[f"err_{f}"] for f in figures))
            nominal[c] = max(nominal.get(c, 0.0), max(r[f"errnom_{f}"] for f in figures))
            seen[c] = seen.get(c, 0) + 1
    cands = [r for r in sources[nearest] if r["level"] in accepted_levels]
    ok = [r for r in cands if worst[r["config"]] <= target and seen[r["config"]] == len(near)]
    spans = any(f.endswith(("tight_tension", "slack_tension")) for f in figures)

    def bowing(r):
        return (spans and dist[nearest] > 1e-3 and r["level"] in line
                and features["mesh_over_span"] >= line[r["level"]])
    # where a level 0-2 meeting the target holds the spans' string modes, the ones that miss
    # them are passed over
    holding = [r for r in ok if r["level"] <= 2 and not bowing(r)]
    if holding:
        ok = [r for r in ok if not bowing(r)]
    if ok:
        best = min(ok, key=lambda r: r["wall_per_sim_s"])
        c = best["config"]
        # a measured scene itself (its band measured) needs no model-error share
        if dist[nearest] <= 1e-3:
            return c, worst[c], True, True
        ripple = any(f in ("driven_speed_ripple", "input_torque_ripple", "mesh_amplitude",
                           "transmission_error") for f in figures)
        return c, worst[c], True, (nominal[c] >= 0.5 * worst[c]
                                   and not (ripple and seen[c] < 2) and not bowing(best))
    best = min(cands, key=lambda r: (seen[r["config"]] < len(near), worst[r["config"]],
                                     r["wall_per_sim_s"]))
    return best["config"], worst[best["config"]], False, False


@pytest.mark.parametrize("target", [0.05, 0.20, 0.50])
def test_auto_low_speed_driven_speed_ripple_follows_the_rule_written_in_the_test(target):
    """Only the driven-speed ripple at 30 rpm: the choice is the cheapest configuration whose
    worst error (over the reference's band and the neighbouring measured scenes) meets the
    target, else the most accurate, with no promise. The issue expected kinematic or torsional
    at 5 %; counted against the band, levels 0-2 are far more than 5 % off level 3 there."""
    scene = load_scene("xu2010", input_speed_rpm=30)
    choice = auto.choose(scene, ["driven_speed_ripple"], target)
    assert choice.source_scene == "xu2010 30 rpm" and not choice.extrapolated
    config, err, met, promised = _rule(auto.table(), auto.scene_features(scene),
                                       ["driven_speed_ripple"], target, (0, 1, 2, 3))
    assert choice.config == config and choice.met == met
    assert choice.expected_error == pytest.approx(err)
    assert choice.promised == promised
    if not met:
        assert "cannot promise" in choice.message and f"meets {100 * target:g} %" in choice.message


def _band_worst(value: dict, runs: list[dict], figures) -> float:
    """Worst case over the band written here: max over figures of max(|v - lo|, |v - hi|) /
    scale, the band the min-max over the level-3 runs, the scale |nominal| (tensions at least
    2 % of the nominal mean tight tension)."""
    nominal = runs[0]
    out = 0.0
    for f in figures:
        lo, hi = min(r[f] for r in runs), max(r[f] for r in runs)
        scale = abs(nominal[f])
        if "tension" in f:
            scale = max(scale, 0.02 * abs(nominal["mean_tight_tension"]))
        out = max(out, max(abs(value[f] - lo), abs(value[f] - hi)) / scale)
    return out


def _level3_band(scene) -> list[dict]:
    """Level 3 at the study's reference step, nominal first, then every uncertain value at
    x0.5 and x2 and the joint damping at the joint friction's factor where the study adds it
    (study.band_variants; the runs whose result is valid)."""
    runs = []
    for sc in [scene.with_overrides(fidelity=3)] + [
            study.band_scene(scene, n, f)[0] for n, f in study.band_variants(scene)]:
        r = run_scene(sc.with_overrides(**study.REFERENCE.overrides(sc)))
        if r.valid:
            runs.append(study.metrics(r))
    assert len(runs) >= 5
    return runs


_EXAMPLES = Path(__file__).resolve().parents[1] / "examples" / "scenes"


_UNSEEN = Path(__file__).resolve().parents[1] / "docs" / "scripts" / "unseen_drives"


def _taut_string_mode(scene, tension: float) -> float:
    """The first mode [Hz] of a span as a taut string at ``tension`` [N], sqrt(T / rho) / 2l,
    l the common tangent of the two pitch circles (R = p / (2 sin(pi / z)))."""
    d = scene.drive
    rho = scene.parameters["chain.link_mass"] / d.pitch
    r1, r2 = (d.pitch / (2.0 * math.sin(math.pi / z)) for z in (d.n_driver, d.n_driven))
    return math.sqrt(tension / rho) / (2.0 * math.sqrt(d.centre_distance ** 2 - (r2 - r1) ** 2))


@pytest.mark.parametrize("scene_kw, outputs, accuracy", [
    # an unseen 16B 21/21 drive (a 1:1 ratio the table does not hold) at 150 rpm
    ((str(_UNSEEN / "16b_21_21.toml"), dict(input_speed_rpm=150, duration=0.6)),
     ["tight_span.tension"], 0.2),
    # a 12B chain (19.05 mm): a chain size the table does not hold, at 300 rpm
    ((str(_EXAMPLES / "12b_conveyor.toml"), dict(input_speed_rpm=300, duration=0.3)),
     ["tight_span.tension"], 0.5),
    # the 16B mixer at 150 rpm, between the speeds measured on it
    ((str(_EXAMPLES / "16b_mixer.toml"), dict(input_speed_rpm=150, duration=0.6)),
     ["slack_span.tension"], 0.5),
])
def test_auto_does_not_promise_span_tensions_where_its_level_warns_of_missing_span_modes(
        scene_kw, outputs, accuracy):
    """Three drives outside the table on which auto promised level 1's span tensions from the
    16B mixer at 200 rpm (held there, 0.4-0.8x the promise): their meshing is far above 0.4 of
    the spans' first string mode, where level 1 itself warns that its span tensions may be
    off. A wider audit found such promises 2-17x off on 37 of 61 new drives (the next test
    measures one): the choice stands, the promise is not made, and the message says why. The
    string mode is computed here from the taut string at the static tension."""
    name, kw = scene_kw
    sc = load_scene(name, **kw)
    assert all(math.dist(_log_features(auto.scene_features(sc)), _log_features(r)) > 1e-3
               for r in auto.table())
    choice = auto.choose(sc, outputs, accuracy)
    d = sc.drive
    f_1 = _taut_string_mode(sc, sc.with_overrides(fidelity=0).model().static_tension())
    f_m = d.n_driver * kw["input_speed_rpm"] / 60.0
    assert choice.level == 1 and choice.met and f_m > 2.0 * 0.4 * f_1, (f_m, f_1)
    assert not choice.promised and "miss string modes" in choice.why_not
    assert "cannot promise" in choice.message


def test_auto_would_have_broken_its_promise_where_span_modes_are_missing(tmp_path):
    """A `new-scene` 16B 11/33 drive of 44 links at 2 % pretension, 600 rpm, loaded to its
    static tension: before, auto promised level 1's 11.5 % on the tight span from the 16B
    mixer at 200 rpm (distance under 1). Measured here against level 3 and its band (run in
    the test), level 1 is more than twice that off, so the promise would have broken; it is
    not made now."""
    from chainmodel.new_scene import scene_text
    path = tmp_path / "16b.toml"
    path.write_text(scene_text(11, 33, 600.0, 0.0, chain="16B", links=44))
    sc0 = load_scene(str(path), fidelity=0)
    load = sc0.model().static_tension() * sc0.drive.driven.pitch_radius
    path.write_text(scene_text(11, 33, 600.0, round(load, 3), chain="16B", links=44,
                               duration=0.3))
    sc = load_scene(str(path))
    choice = auto.choose(sc, ["tight_span.tension"], 0.2)
    assert choice.level == 1 and choice.met and choice.distance <= 1.0
    assert not choice.promised and "miss string modes" in choice.why_not
    chosen = study.metrics(run_scene(sc.with_overrides(**choice.overrides)))
    measured = _band_worst(chosen, _level3_band(sc), auto.OUTPUT_FIGURES["tight_span.tension"])
    assert measured > 2.0 * choice.expected_error, (measured, choice.expected_error)


def test_auto_prefers_a_level_that_holds_the_spans_string_modes(tmp_path):
    """A `new-scene` 16B 11/33 drive of 44 links at 2 % pretension, 200 rpm, loaded to its
    static tension (the `--new-drives` audit's): the table's cheapest configuration meeting
    20 % on the tight span is level 0's, whose meshing lies above its 0.4 line (the string mode
    computed here), and level 2, below its 1.5 line, meets 20 % too. Auto takes level 2 (the rule
    written above agrees); run here against level 3 at its nominal values, level 2 is within
    20 % and level 0, which auto chose before, is not."""
    from chainmodel.new_scene import scene_text
    from chainmodel.validity import LEVEL2_SPAN_MODE_RATIO, SPAN_MODE_SHARE
    path = tmp_path / "16b.toml"
    path.write_text(scene_text(11, 33, 200.0, 0.0, chain="16B", links=44))
    sc0 = load_scene(str(path), fidelity=0)
    t0 = sc0.model().static_tension()
    path.write_text(scene_text(11, 33, 200.0, round(t0 * sc0.drive.driven.pitch_radius, 3),
                               chain="16B", links=44, duration=0.33))
    sc = load_scene(str(path))
    ratio = (sc.drive.n_driver * 200.0 / 60.0) / _taut_string_mode(sc, t0)
    assert SPAN_MODE_SHARE < ratio < LEVEL2_SPAN_MODE_RATIO, ratio
    figures = auto.OUTPUT_FIGURES["tight_span.tension"]
    choice = auto.choose(sc, ["tight_span.tension"], 0.2)
    config, err, met, _ = _rule(auto.table(), auto.scene_features(sc), figures, 0.2,
                                (0, 1, 2, 3))
    assert (choice.level, choice.config, choice.met) == (2, config, met) and met
    assert choice.expected_error == pytest.approx(err)
    # level 0 meets the target by the table too, and is cheaper there
    config0, _, met0, _ = _rule(auto.table(), auto.scene_features(sc), figures, 0.2, (0,))
    wall = {r["config"]: r["wall_per_sim_s"] for r in auto.table()
            if r["scene"] == choice.source_scene}
    assert met0 and wall[config0] < wall[choice.config]
    sc3 = sc.with_overrides(fidelity=3)
    reference = [study.metrics(run_scene(sc3.with_overrides(**study.REFERENCE.overrides(sc3))))]
    chosen = _band_worst(study.metrics(run_scene(sc.with_overrides(**choice.overrides))),
                         reference, figures)
    before = _band_worst(study.metrics(run_scene(sc.with_overrides(fidelity=0))), reference,
                         figures)
    assert chosen <= 0.2 < before, (chosen, before)


def test_auto_declines_to_promise_a_ripple_figure_measured_on_one_neighbour_only():
    """The 16B mixer at 100 rpm: its one neighbour in the table is the mixer at 200 rpm,
    where level 1's driven-speed ripple is within 50 %; the same figure is 58 % off at 500
    rpm, and was 4.5x the promise at 100 rpm when promised from 200 rpm. A ripple figure's
    error follows where the meshing sits against the drive's modes: one scene does not carry
    it, so auto says it cannot promise (nor, since the twenty-eighth session, the tension:
    level 1's span tensions above its span-modes line)."""
    sc = load_scene(str(_EXAMPLES / "16b_mixer.toml"), input_speed_rpm=100)
    ripple = auto.choose(sc, ["driven.speed"], 0.5)
    assert ripple.met and not ripple.promised and len(ripple.neighbours) == 1
    assert "ripple figure" in ripple.why_not and "cannot promise" in ripple.message
    tension = auto.choose(sc, ["tight_span.tension"], 0.5)
    assert tension.met and tension.neighbours == ripple.neighbours
    # nor the tension: level 1 far above its spans' first string mode warns of missing modes
    assert not tension.promised and "miss string modes" in tension.why_not


def test_auto_promises_on_a_measured_scene_itself_whose_band_was_measured():
    """The README's example, xu2010 at 120 rpm (a scene of the table): level 0's 12.6 % is mostly
    the band, but it is this drive's own measured band, so it is promised."""
    choice = auto.choose(load_scene("xu2010"), ["tight_span.tension"], 0.2)
    assert choice.source_scene == "xu2010 120 rpm" and choice.distance < 1e-3
    assert choice.nominal_error < 0.5 * choice.expected_error
    assert choice.promised and "promised: error <=" in choice.message


def test_auto_declines_to_promise_an_error_that_is_mostly_the_reference_band():
    """Level 3 at its own step has almost no error against the nominal reference; its table
    error is the neighbour's uncertainty band, which does not carry over: auto says it cannot
    promise. On this unseen 10B 11/33 drive (before the rule auto promised 7.8 % on the driven
    speed and the worst case was 312-348 %; docs/tradeoff.md, "Auditing the promise"), the
    level's own share of the error, measured here against the nominal reference of the
    neighbour, is below half."""
    path = Path(__file__).resolve().parents[1] / "docs/scripts/unseen_drives/10b_11_33.toml"
    sc = load_scene(str(path), input_speed_rpm=300, duration=0.3)
    choice = auto.choose(sc, ["tight_span.tension"], 0.05)   # level 1's 10 % does not meet it
    assert choice.level == 3 and choice.met and not choice.promised
    assert "uncertainty band" in choice.why_not and "cannot promise" in choice.message
    assert choice.nominal_error < 0.5 * choice.expected_error
    rows = [r for r in auto.table() if r["scene"] in choice.neighbours
            and r["config"] == choice.config]
    figures = auto.OUTPUT_FIGURES["tight_span.tension"]
    own = max(r[f"errnom_{f}"] for r in rows for f in figures)
    band = max(r[f"band_{f}"] for r in rows for f in figures)
    assert own < 0.5 * (own + band)


@pytest.mark.parametrize("preset, rpm", [
    (str(_EXAMPLES / "16b_mixer.toml"), 300.0),       # level 0 refused on 2 of 4 neighbours
    ("xu2010", 60.0),
    (str(Path(__file__).resolve().parents[1] / "docs/scripts/unseen_drives/10b_11_33.toml"),
     300.0),
])
@pytest.mark.parametrize("output", ["tight_span.tension", "slack_span.tension", "driven.speed"])
def test_auto_choice_and_promise_follow_the_rule_written_in_the_test(preset, rpm, output):
    """On drives outside the table, for every output: the configuration, its error, whether
    the target is met and whether it is promised are those of the rule written in the test
    (coverage of every neighbour, the model-error share)."""
    sc = load_scene(preset, input_speed_rpm=rpm)
    for target in (0.1, 0.5):
        choice = auto.choose(sc, [output], target)
        assert not choice.extrapolated          # all three lie within distance 1 of the table
        config, err, met, promised = _rule(auto.table(), auto.scene_features(sc),
                                           auto.OUTPUT_FIGURES[output], target, (0, 1, 2, 3))
        assert (choice.config, choice.met, choice.promised) == (config, met, promised)
        assert choice.expected_error == pytest.approx(err)


def test_auto_declines_to_promise_far_from_the_table_and_says_why():
    # 5 rpm: meshing frequency far below every measured scene's
    far = auto.choose(load_scene("xu2010", input_speed_rpm=5), ["tight_span.tension"], 0.2)
    assert not far.promised and far.extrapolated
    assert "cannot promise" in far.message and "meshing frequency" in far.why_not
    # (a scene whose reference is invalid is never a source: the synthetic table of
    # test_auto_never_uses_a_scene_whose_reference_is_invalid below)


def test_auto_never_uses_a_scene_whose_reference_is_invalid():
    """Synthetic table: the same rows under two names, one marked invalid; auto must take the
    other even though the marked one is nearer."""
    sc = load_scene("xu2010", input_speed_rpm=120)
    base = [dict(r) for r in auto.table() if r["scene"] == "xu2010 120 rpm"]
    far = [dict(r, scene="far", mesh_over_mode=r["mesh_over_mode"] * 1.5) for r in base]
    marked = [dict(r, status="reference invalid") for r in base]
    c = auto.choose(sc, ["tight_span.tension"], 0.2, rows=marked + far)
    assert c.source_scene == "far"
    warned = [dict(r, reference_problems=1.0) for r in base]
    assert auto.choose(sc, ["tight_span.tension"], 0.2, rows=warned + far).source_scene == "far"


@pytest.mark.parametrize("factor, added", [(4.53, True), (2.4, False), (0.45, False),
                                            (0.3, True), (None, False)])
def test_band_adds_the_joint_friction_factor_only_outside_the_fixed_runs(monkeypatch, factor,
                                                                         added):
    """The joint damping's x0.5 and x2 runs stay; its joint-friction factor is one more run
    when it lies more than 1.25x outside them (x0.4-x2.5), none when the balance gives none."""
    monkeypatch.setattr(study, "joint_friction_factor", lambda *a, **k: factor)
    variants = study.band_variants(load_scene("xu2010"))
    assert variants[:len(study.UNCERTAIN)] == list(study.UNCERTAIN)
    extra = variants[len(study.UNCERTAIN):]
    assert extra == ([("chain.joint_damping", factor)] if added else [])


def test_joint_friction_factor_is_friction_over_level3_losses():
    """xu2010 at 120 rpm: the factor is the friction share over the loss share of
    chainmodel.loss_balance on a level-3 run of three revolutions, written here again; level 3's
    dampers dissipate less than the friction there (docs/multibody.md), so it is above 1."""
    from chainmodel.loss_balance import OUTPUTS, LossBalance
    sc = load_scene("xu2010", input_speed_rpm=120, duration=0.4)
    factor = study.joint_friction_factor(sc)
    run = sc.with_overrides(fidelity=3, duration=3 * 0.5 + sc.operating.ramp_time)
    r = run_scene(run)
    balance = LossBalance(run.drive, run.parameters)
    balance.add(r.time, *(r[n] for n in OUTPUTS), run.input_arrays(r.time)[3])
    loss, friction = balance.shares()
    assert factor == pytest.approx(friction / loss, rel=1e-9) and factor > 1.0


def test_band_overrides_scale_the_values_no_source_gives():
    sc = load_scene("C1")
    p = sc.parameters
    gap = p["contact.seat_radius"] - p["chain.roller_radius"]
    for f in (0.5, 2.0):
        o = study.band_overrides(sc, "seat_clearance", f)
        assert o["contact.seat_radius"] - p["chain.roller_radius"] == pytest.approx(f * gap)
        o = study.band_overrides(sc, "contact.stiffness", f)
        assert o["contact.stiffness"] == pytest.approx(f * p["contact.stiffness"])
        # same fraction of critical damping c / (2 sqrt(k m)): c scales as sqrt(k)
        assert o["contact.damping"] / math.sqrt(o["contact.stiffness"]) == pytest.approx(
            p["contact.damping"] / math.sqrt(p["contact.stiffness"]))
        v, _ = study.band_scene(sc, "seat_clearance", f)
        assert v.parameters["contact.seat_radius"] == pytest.approx(
            p["chain.roller_radius"] + f * gap)
    with pytest.raises(ValueError, match="chain.nothing"):
        study.band_overrides(sc, "chain.nothing", 2.0)


def test_band_errors_worst_case_distance_and_half_width():
    keys = list(study.METRICS)
    ref = {k: 100.0 for k in keys}
    lo = {k: 90.0 for k in keys}
    hi = {k: 105.0 for k in keys}
    e = study.band_errors({k: 110.0 for k in keys}, ref, lo, hi)
    for k in keys:
        assert e["err"][k] == pytest.approx(0.20)     # |110 - 90| / 100
        assert e["errnom"][k] == pytest.approx(0.10)
        assert e["dist"][k] == pytest.approx(0.05)    # 110 - 105
        assert e["band"][k] == pytest.approx(0.075)
    # no band (lo = hi = the nominal run): the worst case is the plain error, the width 0
    flat = study.band_errors({k: 110.0 for k in keys}, ref, ref, ref)
    assert flat["err"] == flat["errnom"] and set(flat["band"].values()) == {0.0}
    inside = study.band_errors({k: 95.0 for k in keys}, ref, lo, hi)
    assert inside["dist"]["mesh_amplitude"] == 0.0
    assert inside["err"]["mesh_amplitude"] == pytest.approx(0.10)   # to the far edge, 105


@pytest.mark.parametrize("name, chain", [("08B fan 600 rpm", "08B"), ("16B mixer 200 rpm", "16B"),
                                         ("C1 100 rpm", "16B"), ("xu2010 120 rpm", "10B")])
def test_study_scenes_carry_their_own_chain_values(name, chain):
    """Each scene of the study runs on its chain's values (chainmodel.chains), not 10B's."""
    from chainmodel.chains import CHAIN_PARAMETERS, parameter_values
    p = next(s for s in study.SCENES if s.name == name).scene().parameters
    want = parameter_values(chain)
    assert p["drive.pitch"] == pytest.approx(want["drive.pitch"])
    # xu2010 keeps seed 003's own values and C1 seed 004 Table 2's link values (issue 21
    # item 1); the values the band varies come from the chain on C1 too
    if name.startswith("xu2010"):
        keys = ()
    elif name.startswith("C1"):
        keys = ("contact.stiffness", "contact.seat_radius", "chain.roller_radius",
                "chain.breaking_load")
    else:
        keys = CHAIN_PARAMETERS
    for k in keys:
        assert p[k] == pytest.approx(want[k]), k


class _Stub:
    def __init__(self, data):
        self._d = data

    @property
    def names(self):
        return list(self._d)

    def __getitem__(self, k):
        return self._d[k]


def test_span_tensions_reads_physical_spans_when_the_library_gives_them():
    t = np.linspace(0.0, 1.0, 101)
    upper = 1000.0 + 600.0 * np.sin(40 * t)        # swings through the lower one's level
    lower = 700.0 - 600.0 * np.sin(40 * t)
    roles = {"tight_span.tension": np.maximum(upper, lower),
             "slack_span.tension": np.minimum(upper, lower)}
    mask = np.ones_like(t, dtype=bool)
    tight, slack, src = study.span_tensions(_Stub(roles), mask)
    assert src == "roles" and np.mean(tight) > np.mean(upper)
    tight, slack, src = study.span_tensions(
        _Stub({**roles, "upper_span.tension": upper, "lower_span.tension": lower}), mask)
    assert src == "physical"
    assert np.mean(tight) == pytest.approx(np.mean(upper))
    assert np.mean(slack) == pytest.approx(np.mean(lower))


def test_update_doc_block_replaces_only_between_its_markers(tmp_path):
    doc = tmp_path / "d.md"
    doc.write_text("a\n<!-- study:x -->\nold\n<!-- /study:x -->\nb\n")
    assert study.update_doc_block(doc, "x", "new 1\nnew 2")
    assert doc.read_text() == "a\n<!-- study:x -->\nnew 1\nnew 2\n<!-- /study:x -->\nb\n"
    assert not study.update_doc_block(doc, "y", "z")


def test_study_marks_a_scene_whose_reference_is_invalid():
    """A slack chain under a heavy load skips teeth at level 3 (Result.valid False,
    tests/test_validity.py): the study keeps the scene, marked, with no errors, and the
    tables say so."""
    spec = study.SceneSpec("skipping", "xu2010", dict(drive_links=48, static_tension=None,
                                                      chain_pretension=0.0, load_torque=200.0,
                                                      duration=0.6))
    rows = study.run_study([spec], [study.CONFIGS[0]], repeats=1, cache_dir=None, uncertain=())
    (row,) = rows
    assert row["status"] == "reference invalid" and row["reference_valid"] == 0
    assert row["note"].startswith("the result is not valid")   # its cause first
    assert "Reference invalid" in study.markdown(rows)
    assert "reference invalid" in study.headline(rows)


def test_trade_table_reproduces_within_noise():
    """Two cheap scenes regenerated here (fresh level-3 references, no cache): the errors, not
    the timings, agree with the committed table."""
    names = ("xu2010 120 rpm", "xu2010 30 rpm")
    specs = [s for s in study.SCENES if s.name in names]
    configs = [study.CONFIGS[0], study.Config(1, "rk4", 5e-4)]
    rows = study.run_study(specs, configs, repeats=1, cache_dir=None)
    table = {(r["scene"], r["config"]): r for r in auto.table()}
    assert len(rows) == 4
    for r in rows:
        t = table[(r["scene"], r["config"])]
        assert r["status"] == t["status"] == "ok"
        for k in study.METRICS:
            assert r[f"err_{k}"] == pytest.approx(t[f"err_{k}"], rel=1e-3, abs=1e-4), (r["scene"], r["config"], k)


@pytest.mark.parametrize("kw, match", [
    (dict(fidelity="auto", accuracy=0.0), r"accuracy must be a relative error in \(0, 1\].*0\.0"),
    (dict(fidelity="auto", accuracy="x"), r"accuracy must be.*'x'"),
    (dict(fidelity="auto", outputs=["driven.sped"]), r"outputs \['driven\.sped'\].*valid:"),
    (dict(fidelity="auto", outputs=[]), r"outputs must name at least one"),
    (dict(fidelity=1, accuracy=0.05), r"outputs and accuracy are only used with fidelity='auto'"),
])
def test_auto_arguments_are_validated_at_the_boundary(kw, match):
    with pytest.raises(ValueError, match=match):
        chainmodel.simulate("xu2010", duration=0.01, **kw)


def test_cli_fidelity_auto(capsys):
    assert main(["run", "xu2010", "--fidelity", "auto", "--outputs", "chain.max_link_tension",
                 "--accuracy", "0.1", "--duration", "0.01", "--output-interval", "1e-3",
                 "--json"]) == 0
    cap = capsys.readouterr()
    data = json.loads(cap.out)
    assert data["fidelity_level"] == 3 and data["fidelity_auto"]["source_scene"]
    assert data["fidelity_auto"]["promised"] == (data["fidelity_auto"]["why_not"] == "")
    # against the nominal reference alone the error is never above the worst case over the band
    assert 0.0 <= data["fidelity_auto"]["nominal_error"] <= data["fidelity_auto"]["expected_error"]
    assert "fidelity auto" in cap.err
    assert main(["run", "xu2010", "--fidelity", "1", "--accuracy", "0.1"]) == 2
    assert "--fidelity auto" in capsys.readouterr().err
    assert main(["run", "xu2010", "--fidelity", "auto", "--accuracy", "2"]) == 2
    assert "accuracy" in capsys.readouterr().err


def test_nearest_scene_is_the_measured_scene_itself_and_far_scenes_are_extrapolated():
    for spec in study.SCENES[:2]:
        choice = auto.choose(spec.scene(), ["tight_span.tension"], 0.05)
        assert choice.source_scene == spec.name and choice.distance < 1e-4  # CSV: 6 digits
    far = auto.choose(load_scene("xu2010", input_speed_rpm=5), ["tight_span.tension"], 0.05)
    assert far.extrapolated and "extrapolated" in far.message


def test_bench_tradeoff_cli_refuses_unknown_scenes_and_repeats(capsys, tmp_path):
    assert main(["bench", "tradeoff", "--scenes", "xu2010 7 rpm", "--csv",
                 str(tmp_path / "t.csv")]) == 2
    err = capsys.readouterr().err
    assert "--scenes" in err and "xu2010 7 rpm" in err and "xu2010 120 rpm" in err
    assert main(["bench", "tradeoff", "--repeats", "0", "--csv", str(tmp_path / "t.csv")]) == 2
    assert "--repeats" in capsys.readouterr().err
    assert not (tmp_path / "t.csv").exists()
