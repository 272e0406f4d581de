"""Issue 19 item 4: a figure is written in the format of its file's extension (.png, .pdf,
.svg; anything else refused before any work), the level-2 run figure shows the midspan
deflection, and every axis of every figure carries its unit."""

from __future__ import annotations

import re

import numpy as np
import pytest

import chainmodel
from chainmodel import cli

pytest.importorskip("matplotlib")

#: file signatures: PNG (RFC 2083), PDF (ISO 32000 header), SVG (XML declaration, svg root)
MAGIC = {".png": b"\x89PNG\r\n\x1a\n", ".pdf": b"%PDF-", ".svg": b"<?xml"}
UNIT = re.compile(r"\[[^\]]+\]")


@pytest.fixture
def figures(monkeypatch):
    """Every matplotlib Figure saved while the test runs (pyplot's and the Agg canvases')."""
    from matplotlib.figure import Figure
    saved = []
    original = Figure.savefig

    def savefig(self, *args, **kwargs):
        saved.append(self)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(Figure, "savefig", savefig)
    return saved


def label_problems(fig) -> list[str]:
    """Axis labels without a unit: every non-empty label must hold one in brackets; every
    drawn axes needs a y label, and an x label unless it shares its x axis with one that has
    it (stacked panels) - a colorbar needs its one label."""
    problems = []
    for ax in fig.axes:
        if not ax.get_visible() or not ax.axison:
            continue
        colorbar = getattr(ax, "_colorbar", None) is not None
        xl, yl = ax.get_xlabel(), ax.get_ylabel()
        for label in (xl, yl):
            if label and not UNIT.search(label):
                problems.append(f"{ax.get_title()!r}: label {label!r} has no [unit]")
        if colorbar:
            if not (xl or yl):
                problems.append("colorbar without a label")
            continue
        if not yl:
            problems.append(f"{ax.get_title()!r}: no y label")
        shared = ax.get_shared_x_axes().get_siblings(ax)
        if not xl and not any(other.get_xlabel() for other in shared):
            problems.append(f"{ax.get_title()!r}: no x label")
    return problems


@pytest.mark.parametrize("suffix", [".png", ".pdf", ".svg"])
def test_the_extension_chooses_the_format(capsys, tmp_path, suffix):
    for argv in (["kinematics", "--preset", "medium", "--samples", "40"],
                 ["wrap", "--preset", "C1", "--samples", "40"],
                 ["run", "xu2010", "--fidelity", "0", "--duration", "0.1", "--quiet"]):
        path = tmp_path / f"{argv[0]}{suffix}"
        assert cli.main(argv + ["--plot", str(path)]) == 0, capsys.readouterr().err
        head = path.read_bytes()[:400]
        assert head.startswith(MAGIC[suffix]), (argv[0], head[:20])
        if suffix == ".svg":
            assert b"<svg" in head
    capsys.readouterr()


@pytest.mark.parametrize("argv", [
    ["run", "xu2010", "--fidelity", "0", "--duration", "0.1"],
    ["kinematics", "--preset", "medium"],
    ["wrap", "--preset", "C1"],
    ["frequency-response", "--case", "sprocket", "--points", "11"],
])
@pytest.mark.parametrize("name", ["out.jpg", "out"])
def test_other_extensions_are_refused_before_any_work(capsys, tmp_path, monkeypatch, argv, name):
    import chainmodel.kinematics
    import chainmodel.simulation

    def no_work(*args, **kwargs):
        raise AssertionError("the work started before the file name was checked")

    monkeypatch.setattr(chainmodel.simulation, "simulate", no_work)
    monkeypatch.setattr(chainmodel.kinematics, "driven_rotation", no_work)
    monkeypatch.setattr(chainmodel.kinematics, "wrap_length_range", no_work)
    from chainmodel.analysis.perturbation import response
    monkeypatch.setattr(response, "sprocket_response", no_work)
    code = cli.main(argv + ["--plot", str(tmp_path / name)])
    out, err = capsys.readouterr()
    assert (code, out) == (2, "")
    assert err.count("\n") == 1 and err.startswith("chainmodel: error: --plot ")
    assert ".png, .pdf, .svg" in err and "Traceback" not in err
    assert not (tmp_path / name).exists()


def test_fmu_test_refuses_a_bad_extension_before_running(capsys, tmp_path):
    fake = tmp_path / "ChainDrive.fmu"
    fake.write_bytes(b"not read: the name is checked first")
    code = cli.main(["fmu-test", str(fake), "--plot", str(tmp_path / "worst.gif")])
    _, err = capsys.readouterr()
    assert code == 2 and ".png, .pdf, .svg" in err and err.count("\n") == 1


def test_level2_figure_shows_the_midspan_deflection(tmp_path, figures):
    from chainmodel.plots import plot_run
    r = chainmodel.simulate("xu2010", fidelity="modal", duration=0.2)
    plot_run(r, tmp_path / "modal.png")
    axes = {ax.get_ylabel(): ax for ax in figures[-1].axes}
    assert "midspan deflection [mm]" in axes
    line = axes["midspan deflection [mm]"].get_lines()[0]
    np.testing.assert_array_equal(line.get_xdata(), r.time)
    np.testing.assert_allclose(line.get_ydata(), 1e3 * r["tight_span.midspan_deflection"],
                               rtol=1e-15, atol=0)
    assert "amplitude [mm]" in axes          # its spectrum
    # level 1 has no span motion (only the static sag): no such panel
    plot_run(chainmodel.simulate("xu2010", fidelity="torsional", duration=0.1),
             tmp_path / "torsional.png")
    assert "midspan deflection [mm]" not in {ax.get_ylabel() for ax in figures[-1].axes}


def test_every_axis_of_every_figure_has_its_unit(tmp_path, capsys, figures):
    from chainmodel.analysis.fmu_test import OutputCheck, plot_worst
    from chainmodel.analysis.perturbation.plots import plot_combined_span, plot_combined_sprocket
    from chainmodel.analysis.sweep import sweep
    from chainmodel.plots import plot_run
    from test_cli import _result_with_snapshots

    # run figures: level 0, level 2 (midspan row) and one with roller snapshots (level 3's rows)
    plot_run(chainmodel.simulate("xu2010", fidelity=0, duration=0.1), tmp_path / "r0.png")
    plot_run(chainmodel.simulate("xu2010", fidelity=2, duration=0.1), tmp_path / "r2.svg")
    plot_run(_result_with_snapshots(1e-4, 300.0), tmp_path / "r3.pdf")
    for argv in (["kinematics", "--preset", "medium", "--samples", "40"],
                 ["wrap", "--preset", "C1", "--samples", "40"],
                 ["frequency-response", "--case", "parametric", "--points", "9"],
                 ["frequency-response", "--case", "sprocket", "--points", "9"]):
        assert cli.main(argv + ["--plot", str(tmp_path / f"{argv[0]}_{len(figures)}.png")]) == 0
    # the combined case's figures from a small made-up grid (the equations take minutes)
    s2, si = np.linspace(-2, 1.5, 5), np.linspace(-1.9, 1.0, 4)
    grid = {"sigma2_ratio": s2, "sigma_i_ratio": si, "policy": "inertia",
            "a": np.random.default_rng(1).random((2, 4, 5)),
            "v": np.random.default_rng(2).random((2, 4, 5))}
    plot_combined_span(grid, tmp_path / "span.png")
    plot_combined_sprocket(grid, tmp_path / "sprocket.png")
    # a sweep over a parameter (not the speed): its resonance map and Campbell diagram
    study = {"fixed": {"fidelity": 0, "duration": 0.05, "output_interval": 1e-3},
             "vary": {"chain.link_damping": [20.0, 40.0], "static_tension": [700.0, 900.0]}}
    sweep(study, tmp_path / "sweep", serial=True)
    t = np.linspace(0, 1, 11)
    plot_worst([OutputCheck("L1", "tight_span.tension", True, 0.5, 0.5, 0, t, t, t - 1, t + 1,
                            t)], tmp_path / "worst.png")
    capsys.readouterr()
    assert len(figures) >= 12
    problems = [f"figure {k}: {p}" for k, fig in enumerate(figures) for p in label_problems(fig)]
    assert problems == []
