"""Issue 9, first hour: every file a command writes is named, long commands show progress, and
sweeps without Dask say which extra to install."""

from __future__ import annotations

import json
import sys

import pytest

from chainmodel import cli


def test_json_output_lists_the_files_written(tmp_path, capsys):
    csv = tmp_path / "k.csv"
    assert cli.main(["kinematics", "--preset", "medium", "--samples", "8", "--json",
                     "--csv", str(csv)]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["files"] == [str(csv)] and csv.is_file()
    assert cli.main(["run", "xu2010", "--fidelity", "0", "--duration", "0.05", "--json",
                     "--csv", str(tmp_path / "r.csv")]) == 0
    assert json.loads(capsys.readouterr().out)["files"] == [str(tmp_path / "r.csv")]


def test_combined_response_reports_its_progress():
    """The progress hook sees the slow time rise to the end of the first integration (T1)."""
    import numpy as np
    from chainmodel import preset
    from chainmodel.analysis.perturbation import coefficients, response
    seen = []
    response.combined_response(coefficients(preset("C1")), np.array([-1.0, 0.5]),
                               np.array([-1.0]), progress=seen.append)
    assert seen and max(seen) >= 150.0 and min(seen) >= 0.0      # T1 = 150 by default


def test_bench_says_it_is_warming_up(capsys):
    assert cli.main(["bench", "xu2010", "--levels", "0,1", "--reference", "1",
                     "--duration", "0.05", "--output-interval", "1e-3"]) == 0
    err = capsys.readouterr().err
    assert "warming up" in err and "kinematic" in err and "torsional" in err


def test_parallel_sweep_without_dask_names_the_extra(tmp_path, monkeypatch):
    from chainmodel.analysis.sweep import sweep
    monkeypatch.setitem(sys.modules, "distributed", None)      # import distributed fails
    study = {"fixed": {"fidelity": 0, "duration": 0.05, "output_interval": 1e-3},
             "vary": {"load_torque": [10.0]}}
    with pytest.raises(ValueError, match=r"chaindrive\[sweep\].*--serial"):
        sweep(study, tmp_path / "o", workers=2)
    assert sweep(study, tmp_path / "o", serial=True, plots=False).run.computed == 1
