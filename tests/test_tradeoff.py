"""The trade-off study behind `chainmodel bench`: each level against a reference level."""

import json
import math

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


def _cheapest_meeting(rows, scene_name, figure, target, accepted_levels):
    """The selection rule computed directly on the table rows, independently of choose()."""
    ok = [r for r in rows if r["scene"] == scene_name and r["status"] == "ok"
          and r["level"] in accepted_levels and r[f"err_{figure}"] <= target]
    return min(ok, key=lambda r: r["wall_per_sim_s"]) if ok else None


@pytest.mark.parametrize("target", [0.05, 0.20])
def test_auto_low_speed_driven_speed_ripple_takes_the_cheapest_row_meeting_the_target(target):
    """Only the driven-speed ripple at 30 rpm: the choice is the cheapest configuration whose
    measured ripple error meets the target. The issue expected kinematic or torsional at 5 %;
    the measurements say levels 0-2 are 11-15 % off level 3 there (docs/tradeoff.md), so at 5 %
    the rule gives level 3, and at 20 % it gives level 0 or 1."""
    scene = load_scene("xu2010", input_speed_rpm=30)
    choice = auto.choose(scene, ["driven_speed_ripple"], target)
    assert choice.source_scene == "xu2010 30 rpm" and not choice.extrapolated
    best = _cheapest_meeting(auto.table(), "xu2010 30 rpm", "driven_speed_ripple", target,
                             (0, 1, 2, 3))
    assert best is not None and choice.config == best["config"]
    assert choice.expected_error == pytest.approx(best["err_driven_speed_ripple"])
    if target == 0.20:
        assert choice.level in (0, 1), choice.message


def test_auto_prediction_holds_on_a_scene_not_in_the_table():
    """xu2010 at 60 rpm (between the measured 30 and 120 rpm), tight-span tension at 5 %: the
    error of the chosen configuration against level 3 run in this test (its own step, which
    is within 0.03 % of the converged one, docs/multibody.md) is within 2x the predicted one."""
    sc = load_scene("xu2010", input_speed_rpm=60, duration=0.6)
    assert all(r["scene"] != "xu2010 60 rpm" for r in auto.table())
    choice = auto.choose(sc, ["tight_span.tension"], 0.05)
    assert choice.met and choice.level < 3
    chosen = study.metrics(run_scene(sc.with_overrides(**choice.overrides)))
    ref = study.metrics(run_scene(sc.with_overrides(fidelity=3)))
    err = study.relative_errors(chosen, ref)
    measured = max(err["mean_tight_tension"], err["peak_tight_tension"])
    assert measured <= 2.0 * choice.expected_error, (measured, choice.message)


def test_trade_table_reproduces_within_noise():
    """Two cheap scenes regenerated here (fresh level-3 references, no cache): the errors, not
    the timings, agree with the committed table."""
    names = ("xu2010 120 rpm", "coarse 6/9 300 rpm")
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
