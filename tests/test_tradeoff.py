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
