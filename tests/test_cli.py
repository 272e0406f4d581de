"""The ``chainmodel`` command: JSON against the library and the papers, files, errors.

Most tests run the CLI in-process through ``chainmodel.cli.main(argv)``; one runs the real
``python -m chainmodel`` in a subprocess. Numbers checked come from the papers (seed 004 Table 1,
seed 003's 50 Hz meshing frequency), from physics (tooth ratio, power balance, mean velocity
ratio) or from the library called directly — never from an earlier run of the CLI.
"""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest

import chainmodel
from chainmodel import cli, kinematics
from chainmodel.numba_cache import COMPILE_NOTICE
from chainmodel.presets import preset, preset_names, reference_table

ROOT = Path(__file__).resolve().parent.parent
DOCS = ROOT / "docs" / "cli.md"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"
RPM = 2 * math.pi / 60


def run_cli(capsys, *argv):
    code = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def run_json(capsys, *argv):
    code, out, err = run_cli(capsys, *argv, "--json")
    assert code == 0, err
    assert out.count("\n") == 1 and out.endswith("\n")      # one object, one line
    data = json.loads(out)
    # stderr holds the one-time compile notice (first use of a kernel per machine) and the
    # summary's warnings, one line each, and nothing else (levels 0-1 at xu2010's 120 rpm are
    # warned that the meshing reaches the span modes they do not have: chainmodel.validity)
    assert [line for line in err.splitlines()
            if not line.startswith(COMPILE_NOTICE[:40])] == [
        f"chainmodel: warning: {w}" for w in data.get("warnings", [])]
    return data


def assert_png(path: Path):
    data = Path(path).read_bytes()
    assert data[:8] == PNG_SIGNATURE
    assert len(data) > 10_000


def documented_keys() -> set[str]:
    """Every `key` written in backticks in docs/cli.md."""
    return set(re.findall(r"`([a-z_0-9]+)`", DOCS.read_text()))


# --- kinematics -------------------------------------------------------------------------------

KINEMATICS_KEYS = {"seating", "release", "theta4", "theta2", "theta3", "span_length",
                   "velocity_ratio", "driven_acceleration"}


@pytest.mark.parametrize("load", [10.0, -10.0])
def test_the_summary_says_when_the_load_drives_the_chain(capsys, load):
    """An overrunning load (the load torque with the rotation: here -10 N.m at +300 rpm) sends
    power back into the input shaft, -|load| z1/z2 omega_in by the torque balance; the summary
    gives that power and the run's table says so in words. Driving the load it says nothing."""
    args = ("run", "xu2010", "--fidelity", 0, "--duration", 0.32, "--speed-rpm", 300,
            "--load-torque", load, "--output-interval", 2e-4, "--set", "ramp_time=0.02")
    data = run_json(capsys, *args)
    balance = load * 25 / 17 * 300 * math.pi / 30           # W into the input shaft
    assert data["mean_input_power_w"] == pytest.approx(balance, rel=5e-3)
    code, out, err = run_cli(capsys, *args)
    assert code == 0
    assert ("power flows back into the input shaft" in out) == (load < 0)


def test_a_run_that_ends_inside_the_speed_ramp_says_so(capsys):
    """Durations shorter than the speed ramp (0.05 s by default) never reach the operating
    speed: the warnings say so and name the ramp, whatever the level."""
    data = run_json(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.03,
                    "--output-interval", 1e-4)
    assert any("inside the input's speed ramp of 0.05 s" in w for w in data["warnings"])
    data = run_json(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.3,
                    "--output-interval", 1e-4)
    assert not any("speed ramp" in w for w in data["warnings"])


@pytest.mark.parametrize("name", ["coarse", "medium", "fine", "C1"])
def test_kinematics_json_matches_the_library(capsys, name):
    k = 240
    data = run_json(capsys, "kinematics", "--preset", name, "--samples", k)
    assert KINEMATICS_KEYS <= set(data)          # DESIGN.md's contract
    drive = preset(name)
    for event, ref in (("seating", kinematics.seating(drive)), ("release", kinematics.release(drive))):
        for angle in ("theta2", "theta3", "theta4"):
            assert data[event][angle] == pytest.approx(getattr(ref, angle), abs=1e-12)
    # one tooth period from seating: theta4 runs down from theta4s by 2 pi / n_c
    period = 2 * math.pi / drive.n_driver
    theta4 = kinematics.seating(drive).theta4 - np.arange(k) * period / k
    np.testing.assert_allclose(data["theta4"], theta4, rtol=0, atol=1e-12)
    # the four-bar at 100 rpm (paper convention: theta4 decreases, so omega4 = -100 rpm)
    w = 100 * RPM
    ref = kinematics.exact(drive, theta4, omega4=-w, alpha4=0.0)
    np.testing.assert_allclose(data["theta2"], ref.theta2, atol=1e-12)
    np.testing.assert_allclose(data["theta3"], ref.theta3, atol=1e-12)
    np.testing.assert_allclose(data["span_length"], ref.span_length, atol=1e-15)
    np.testing.assert_allclose(data["velocity_ratio"], ref.velocity_ratio, rtol=1e-12)
    # forward-positive driven acceleration = -d2(theta2)/dt2
    np.testing.assert_allclose(data["driven_acceleration"], -ref.alpha2, rtol=1e-10, atol=1e-10)
    # physics: the driven sprocket turns 2 pi / n_o per driver tooth, so the mean velocity ratio
    # over a period is n_c / n_o (sampled mean of a piecewise-smooth curve: 1e-4)
    assert np.mean(data["velocity_ratio"]) == pytest.approx(drive.n_driver / drive.n_driven, rel=1e-4)
    assert data["velocity_ratio_mean"] == pytest.approx(np.mean(data["velocity_ratio"]), rel=1e-14)
    # the span holds N + 1 or N + 2 pitches (seed 000 eq 13)
    assert set(np.round(np.array(data["span_length"]) / drive.pitch).astype(int)) <= {
        drive.span_pitches + 1, drive.span_pitches + 2}


def test_kinematics_acceleration_is_the_derivative_of_the_speed(capsys):
    """Independent check of the acceleration: central differences of the driven speed,
    away from seating and release where it jumps."""
    k = 4000
    data = run_json(capsys, "kinematics", "--preset", "medium", "--samples", k, "--speed-rpm", 250)
    w = 250 * RPM
    dt = (2 * math.pi / 12) / k / w
    speed = np.array(data["driven_speed"])
    np.testing.assert_allclose(speed, w * np.array(data["velocity_ratio"]), rtol=1e-12)
    acc = np.array(data["driven_acceleration"])
    diff = (speed[2:] - speed[:-2]) / (2 * dt)
    x = np.array(data["tooth_period_fraction"])[1:-1]
    away = (np.abs(x - data["release_fraction"]) > 3 / k) & (x > 3 / k) & (x < 1 - 3 / k)
    np.testing.assert_allclose(diff[away], acc[1:-1][away], rtol=1e-4, atol=1e-6 * np.max(np.abs(acc)))


def test_kinematics_explicit_drive_equals_the_preset(capsys):
    explicit = run_json(capsys, "kinematics", "--driver-teeth", 12, "--driven-teeth", 18,
                        "--span-pitches", 11, "--pitch-fraction", 0.43, "--pitch", 0.0254)
    named = run_json(capsys, "kinematics", "--preset", "medium")
    assert explicit["seating"] == named["seating"]
    assert explicit["theta2"] == named["theta2"]
    assert explicit["drive"]["centre_distance_m"] == pytest.approx(preset("medium").centre_distance)


def test_kinematics_approximate_curves_when_the_library_has_them(capsys):
    data = run_json(capsys, "kinematics", "--preset", "medium", "--samples", 100)
    approx = getattr(kinematics, "approximate", None)
    if approx is None:
        try:
            from chainmodel.kinematics.approx import approximate as approx
        except ImportError:
            assert "approximate" not in data and data["approximate_note"]
            return
    ref = approx(preset("medium"), np.array(data["theta4"]), omega4=-100 * RPM, alpha4=0.0)
    np.testing.assert_allclose(data["approximate"]["theta2"], ref.theta2, atol=1e-12)
    np.testing.assert_allclose(data["approximate"]["velocity_ratio"], ref.velocity_ratio, atol=1e-12)
    # seed 000 section 4.4: medium drive, position and velocity within a few per mille
    assert np.max(np.abs(np.array(data["approximate"]["velocity_ratio"])
                         - data["velocity_ratio"])) < 0.01 * (12 / 18)


def test_kinematics_table_csv_and_plot(capsys, tmp_path):
    code, out, err = run_cli(capsys, "kinematics", "--preset", "coarse", "--samples", 200,
                             "--csv", tmp_path / "k.csv", "--plot", tmp_path / "k.png")
    assert code == 0 and err == ""
    assert "seating" in out and "release" in out and "velocity ratio" in out
    with open(tmp_path / "k.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, units, values = rows[0], rows[1], rows[2:]
    assert {"theta4", "theta2", "velocity_ratio", "driven_acceleration"} <= set(header)
    assert units[header.index("theta4")] == "rad" and len(values) == 200
    col = np.array([[float(v) for v in row] for row in values])
    assert col[0, header.index("theta4")] == pytest.approx(kinematics.seating(preset("coarse")).theta4)
    assert_png(tmp_path / "k.png")


# --- wrap -------------------------------------------------------------------------------------

@pytest.mark.parametrize("row", [r for r in reference_table("wrap_length_jsv2016_table1.csv")
                                 if r["id"] in ("A1", "C1", "D3")], ids=lambda r: r["id"])
def test_wrap_json_matches_table1_and_the_library(capsys, row):
    data = run_json(capsys, "wrap", "--preset", row["id"], "--samples", 100)
    # seed 004 Table 1 (4 decimals; f given to 4 decimals supports about 2e-4)
    for key, col in (("l_min_over_p", "L_min_over_p"), ("l_mean_over_p", "L_mean_over_p"),
                     ("l_max_over_p", "L_max_over_p")):
        assert data[key] == pytest.approx(float(row[col]), abs=2e-4)
    drive = preset(row["id"])
    lmin, lmean, lmax = kinematics.wrap_length_range(drive, samples=100)
    p = drive.pitch
    assert (data["l_min_over_p"], data["l_mean_over_p"], data["l_max_over_p"]) == pytest.approx(
        (lmin / p, lmean / p, lmax / p), rel=1e-14)
    L = np.array(data["wrap_length"])
    assert len(L) == 100 and len(data["theta4"]) == 100
    assert np.mean(L) / p == pytest.approx(data["l_mean_over_p"], rel=1e-14)
    assert data["l_min_over_p"] <= np.min(L) / p + 1e-12 and np.max(L) / p <= data["l_max_over_p"] + 1e-12


def test_wrap_from_links_only_and_files(capsys, tmp_path):
    """--links alone places the sprockets where the chain wraps tightly: L_min = M p."""
    data = run_json(capsys, "wrap", "--driver-teeth", 25, "--driven-teeth", 17,
                    "--pitch", 0.015875, "--links", 46)
    assert data["l_min_over_p"] == pytest.approx(46, abs=1e-6)
    code, out, err = run_cli(capsys, "wrap", "--preset", "B1", "--csv", tmp_path / "w.csv",
                             "--plot", tmp_path / "w.png")
    assert code == 0 and "L_mean / p" in out
    with open(tmp_path / "w.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["tooth_period_fraction", "driver_angle", "theta4", "wrap_length"]
    assert len(rows) == 2 + 200
    assert_png(tmp_path / "w.png")


def test_presets_json_lists_every_preset(capsys):
    data = run_json(capsys, "presets")
    assert [d["name"] for d in data["presets"]] == preset_names()
    for d in data["presets"]:
        drive = preset(d["name"])
        assert (d["n_driver"], d["n_driven"], d["links"]) == (drive.n_driver, drive.n_driven, drive.links)
        assert d["centre_distance_m"] == pytest.approx(drive.centre_distance)
    code, out, _ = run_cli(capsys, "presets")
    assert code == 0 and all(name in out for name in preset_names())


# --- run --------------------------------------------------------------------------------------

RUN_KEYS = {"scene", "fidelity", "mean_tight_tension_n", "peak_tight_tension_n",
            "min_tight_tension_n", "min_slack_tension_n", "min_link_tension_n",
            "slack_link_time_fraction",
            "mean_slack_tension_n", "peak_slack_tension_n", "tooth_ratio",
            "dominant_frequency_hz", "meshing_frequency_hz", "mean_input_torque_nm",
            "wall_time_s", "real_time_factor", "static_span_tension_n", "notes", "drive"}


def test_run_json_level0_physics(capsys):
    data = run_json(capsys, "run", "xu2010", "--fidelity", "kinematic", "--duration", 0.2)
    assert RUN_KEYS <= set(data)
    assert data["fidelity"] == "kinematic" and data["fidelity_level"] == 0
    assert data["via_fmu"] is False
    # rigid chain: the driven sprocket turns exactly n1/n2 per driver turn
    assert data["tooth_ratio"] == pytest.approx(25 / 17, abs=1e-9)
    # seed 003 section 7: meshing frequency 25 teeth x 2 rev/s = 50 Hz, the fundamental
    assert data["meshing_frequency_hz"] == pytest.approx(50.0, rel=1e-9)
    assert abs(data["dominant_frequency_hz"] - 50.0) <= data["frequency_resolution_hz"]
    # lossless rigid drive at constant speed over whole tooth periods: mean input power equals
    # mean output power, tau_in = M_load * n1 / n2 (seed 003: 43.2 N.m)
    assert data["mean_input_torque_nm"] == pytest.approx(43.2 * 25 / 17, rel=1e-3)
    assert data["peak_tight_tension_n"] >= data["mean_tight_tension_n"] > data["mean_slack_tension_n"]
    assert data["samples"] == 2001 and data["output_interval_s"] == pytest.approx(1e-4)
    assert set(data) <= documented_keys()


def test_run_overrides_reach_the_scene(capsys):
    # 0.32 s: the steady half (from 0.16 s) is 20 whole tooth periods of 8 ms at 300 rpm, so
    # the inertia torques average out of the power balance
    data = run_json(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.32,
                    "--speed-rpm", 300, "--load-torque", 10, "--output-interval", 2e-4,
                    "--set", "ramp_time=0.02", "--set", "driven.inertia=2e-3")
    assert data["input_speed_rpm"] == pytest.approx(300)
    assert data["load_torque_nm"] == pytest.approx(10)
    assert data["meshing_frequency_hz"] == pytest.approx(300 / 60 * 25, rel=1e-9)
    assert data["mean_input_torque_nm"] == pytest.approx(10 * 25 / 17, rel=2e-3)
    ref = chainmodel.simulate("xu2010", fidelity=0, duration=0.32, input_speed_rpm=300,
                              load_torque=10, output_interval=2e-4, ramp_time=0.02,
                              parameters={"driven.inertia": 2e-3})
    assert data["peak_tight_tension_n"] == pytest.approx(float(np.max(
        ref["tight_span.tension"][ref.time >= 0.16 - 1e-12])), rel=1e-12)


def test_run_table_csv_and_plot(capsys, tmp_path):
    code, out, err = run_cli(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.2,
                             "--csv", tmp_path / "r.csv", "--plot", tmp_path / "r.png")
    assert code == 0, err
    for label in ("scene", "tight span", "tooth ratio", "meshing", "wall time", "real-time factor",
                  "static tension", "notes"):
        assert label in out
    ref = chainmodel.simulate("xu2010", fidelity=0, duration=0.2)
    with open(tmp_path / "r.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header, units, values = rows[0], rows[1], np.array([[float(v) for v in r] for r in rows[2:]])
    assert header[0] == "time" and set(ref.names) <= set(header)
    assert units[header.index("tight_span.tension")] == "N"
    np.testing.assert_array_equal(values[:, 0], ref.time)
    for name in ("driven.speed", "tight_span.tension", "input_shaft.torque"):
        np.testing.assert_array_equal(values[:, header.index(name)], ref[name])
    assert_png(tmp_path / "r.png")


def test_run_quiet_prints_nothing(capsys, tmp_path):
    code, out, err = run_cli(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.1,
                             "--quiet", "--csv", tmp_path / "q.csv")
    # nothing (0.1 s is too short for levels 0-1's span-modes check, which judges once the
    # driver has turned 4 tooth periods: chainmodel.validity.SPAN_JUDGE_PERIODS)
    assert (code, out, err) == (0, "", "")
    assert (tmp_path / "q.csv").stat().st_size > 1000


def test_run_scene_file(capsys, tmp_path):
    scene = tmp_path / "slow.toml"
    # 0.24 s: the steady half is 3 whole tooth periods (25 Hz) for the power balance
    scene.write_text('name = "slow"\npreset = "xu2010"\nfidelity = 0\nduration = 0.24\n'
                     '[operating]\ninput_speed_rpm = 60\nload_torque = 20\n')
    data = run_json(capsys, "run", scene)
    assert data["scene"] == "slow"
    assert data["meshing_frequency_hz"] == pytest.approx(25.0, rel=1e-9)
    assert data["mean_input_torque_nm"] == pytest.approx(20 * 25 / 17, rel=1e-3)


def test_level0_driven_angle_has_no_tooth_jumps(capsys, tmp_path):
    """Bug fixed in kinematics/rotation.py: where phi1 / (2 pi / n1) rounds to a whole number
    from below, the driven angle jumped by a whole driven tooth at that one sample (it did at
    t = 0.305 s in this run). Physics: with a positive velocity ratio the driven angle rises
    monotonically and stays within half a driven tooth of the mean-ratio angle."""
    code, _, err = run_cli(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.6,
                           "--quiet", "--csv", tmp_path / "r.csv")
    assert code == 0, err
    with open(tmp_path / "r.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    values = np.array([[float(v) for v in r] for r in rows[2:]])
    phi2 = values[:, rows[0].index("driven.angle")]
    te = values[:, rows[0].index("transmission_error")]
    assert np.all(np.diff(phi2[1:]) > 0)
    assert np.max(np.abs(te)) < math.pi / 17
    for name in preset_names():
        drive = preset(name)
        period = 2 * math.pi / drive.n_driver
        k = np.arange(-30, 120) * period
        phi1 = np.concatenate([k, np.nextafter(k, np.inf), np.nextafter(k, -np.inf)])
        te = kinematics.driven_rotation(drive, phi1).driven_angle - drive.tooth_ratio * phi1
        assert np.max(np.abs(te)) < math.pi / drive.n_driven, name


# --- multibody-style snapshots (the plot degrades gracefully) ---------------------------------

def _result_with_snapshots(wobble: float, freq: float, every: int = 6):
    from chainmodel.kinematics import roller_positions
    r = chainmodel.simulate("xu2010", fidelity=0, duration=0.32)
    drive = r.scene.drive
    snaps = []
    for i in range(0, len(r.time), every):
        t = float(r.time[i])
        pos = roller_positions(drive, r["driver.angle"][i], r["driven.angle"][i])
        pos = pos + wobble * np.sin(2 * np.pi * freq * t)
        snaps.append((t, {"roller_positions": pos}))
    r.snapshots = snaps
    return r


def test_plot_run_tracks_a_tight_span_roller(tmp_path):
    """A known wobble added to every roller of the rigid layout comes back out of the tracked
    roller's deviation from the rigid chain, and the roller crosses the tight span."""
    from chainmodel.plots import _snapshot_rollers, _tight_span_track, plot_run
    r = _result_with_snapshots(1e-4, 300.0)
    snaps = _snapshot_rollers(r)
    index, t, xy, rigid = _tight_span_track(r.scene.drive, snaps, r, 0.05)
    assert rigid is not None
    wobble = np.broadcast_to(1e-4 * np.sin(2 * np.pi * 300 * t)[:, None], xy.shape)
    np.testing.assert_allclose(xy - rigid, wobble, atol=1e-12)
    # from the driven sprocket (x near 0) to the driver (x near x_c) along the top
    drive = r.scene.drive
    assert abs(xy[0, 0]) < drive.pitch and abs(xy[-1, 0] - drive.x_c) < drive.pitch
    plot_run(r, tmp_path / "mb.png")
    assert_png(tmp_path / "mb.png")


def test_multibody_run_plots_snapshots(capsys, tmp_path):
    """The multibody level's snapshots reach the figure: the CLI asks for them with --plot, the
    tracked roller starts at the tight span's driven endpoint and the model numbers rollers like
    the rigid layout (so the panel can show the deviation from it)."""
    from chainmodel.models import MODEL_CLASSES
    from chainmodel.plots import _snapshot_rollers, _tight_span_track
    if 3 not in MODEL_CLASSES:
        pytest.skip("the multibody level is not in this tree yet")
    code, out, err = run_cli(capsys, "run", "xu2010", "--fidelity", "multibody", "--duration",
                             0.08, "--quiet", "--plot", tmp_path / "mb.png")
    assert code == 0, err
    assert_png(tmp_path / "mb.png")
    r = chainmodel.simulate("xu2010", fidelity=3, duration=0.08, snapshot_every=10)
    snaps = _snapshot_rollers(r)
    assert len(snaps) == len(r.snapshots) > 3
    assert snaps[0][1].shape == (46, 2)
    track = _tight_span_track(r.scene.drive, snaps, r, 0.05)
    assert track is not None and track[3] is not None


def test_plot_run_without_usable_snapshots(tmp_path):
    """Snapshots without an (M, 2) roller_positions array leave the snapshot panels out (no
    snapshots at all is the level-0 figure of test_run_table_csv_and_plot)."""
    from chainmodel.plots import _snapshot_rollers, plot_run
    r = chainmodel.simulate("xu2010", fidelity=0, duration=0.1)
    r.snapshots = [(0.0, {}), (0.01, {"roller_positions": None}),
                   (0.02, {"roller_positions": np.zeros(3)}), (0.03, "not a dict")]
    assert _snapshot_rollers(r) == []
    plot_run(r, tmp_path / "p.png")
    assert_png(tmp_path / "p.png")


# --- errors -----------------------------------------------------------------------------------

ERRORS = [
    (["run", "nosuch"], "unknown scene or preset"),
    (["run", "xu2010", "--fidelity", "7"], "fidelity"),
    (["run", "xu2010", "--set", "chain.link_damping=abc"], "not a number"),
    (["run", "xu2010", "--set", "nonsense=1"], "unknown scene setting or parameter"),
    (["run", "xu2010", "--set", "chain.link_damping=-1"], "chain.link_damping"),
    (["run", "xu2010", "--set", "novalue"], "NAME=VALUE"),
    (["run", "xu2010", "--solver", "euler"], "solver.method"),
    (["run", "xu2010", "--duration", "0.1", "--output-interval", "1"], "output_interval"),
    (["run", "xu2010", "--duration", "x"], "invalid float"),
    (["run", "/nonexistent/scene.toml"], "does not exist"),
    (["run", "xu2010", "--via-fmu", "/nonexistent/ChainDrive.fmu"], "build_fmu.py"),
    (["run"], "give a scene"),
    (["kinematics"], "--preset"),
    (["kinematics", "--preset", "bogus"], "unknown preset"),
    (["kinematics", "--driver-teeth", "2", "--driven-teeth", "18", "--span-pitches", "11",
      "--pitch-fraction", "0.4"], "at least 3 teeth"),
    (["kinematics", "--driver-teeth", "12", "--driven-teeth", "18", "--span-pitches", "11",
      "--pitch-fraction", "1.5"], "[0, 1)"),
    (["kinematics", "--driver-teeth", "12", "--driven-teeth", "18", "--span-pitches", "11"],
     "--pitch-fraction"),
    (["kinematics", "--preset", "medium", "--pitch", "-1"], "pitch"),
    (["kinematics", "--preset", "medium", "--samples", "1"], "samples"),
    (["kinematics", "--preset", "medium", "--speed-rpm", "0"], "speed-rpm"),
    (["kinematics", "--driver-teeth", "12.5", "--driven-teeth", "18"], "invalid int"),
    (["kinematics", "--preset", "medium", "--csv", "/nonexistent/dir/k.csv"], "does not exist"),
    (["wrap", "--driver-teeth", "12", "--driven-teeth", "18", "--span-pitches", "11",
      "--pitch-fraction", "0.4", "--links", "10"], "too short"),
    (["wrap", "--driver-teeth", "40", "--driven-teeth", "40", "--span-pitches", "1",
      "--pitch-fraction", "0.0"], "overlap"),
    (["frobnicate"], "invalid choice"),
    ([], "required"),
]


@pytest.mark.parametrize("argv,fragment", ERRORS, ids=[" ".join(a) or "(none)" for a, _ in ERRORS])
def test_user_mistakes_print_one_line_and_exit_2(capsys, tmp_path, argv, fragment):
    code, out, err = run_cli(capsys, *argv)
    assert code == 2
    assert out == ""
    assert err.count("\n") == 1 and err.startswith("chainmodel: error: "), err
    assert fragment in err
    assert "Traceback" not in err


def test_bad_scene_files(capsys, tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("duration = [\n")
    unknown = tmp_path / "unknown.toml"
    unknown.write_text("speed = 3\n")
    for path, fragment in ((bad, "not valid TOML"), (unknown, "unknown keys")):
        code, out, err = run_cli(capsys, "run", path, "--json")
        assert (code, out) == (2, "")
        assert err.count("\n") == 1 and fragment in err and "Traceback" not in err


def test_missing_matplotlib_is_one_line(capsys, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)     # import matplotlib -> ImportError
    for argv in (["kinematics", "--preset", "medium"], ["wrap", "--preset", "C1"],
                 ["run", "xu2010", "--fidelity", "0", "--duration", "0.1"]):
        code, out, err = run_cli(capsys, *argv, "--plot", tmp_path / "x.png")
        assert (code, out) == (2, "")
        assert err.count("\n") == 1 and "matplotlib" in err and "pip install" in err
        assert not (tmp_path / "x.png").exists()


def test_diverged_simulation_exits_3(capsys, monkeypatch):
    import chainmodel.simulation
    from chainmodel.models import SimulationDiverged

    def diverge(*args, **kwargs):
        raise SimulationDiverged("multibody model diverged at t = 0.0123 s: non-finite state x_3; "
                                 "try a smaller step or an implicit solver (solver.method = radau)")

    monkeypatch.setattr(chainmodel.simulation, "simulate", diverge)
    code, out, err = run_cli(capsys, "run", "xu2010", "--duration", "0.1", "--json")
    assert (code, out) == (3, "")
    assert err == ("chainmodel: error: multibody model diverged at t = 0.0123 s: non-finite state "
                   "x_3; try a smaller step or an implicit solver (solver.method = radau)\n")


def test_help_exits_0(capsys):
    code, out, _ = run_cli(capsys, "--help")
    assert code == 0 and "run" in out and "kinematics" in out and "wrap" in out
    code, out, _ = run_cli(capsys, "run", "--help")
    assert code == 0 and "--via-fmu" in out


# --- registry ---------------------------------------------------------------------------------

def test_registry_adds_subcommands_and_skips_missing_modules(capsys, monkeypatch):
    plugin = types.ModuleType("chainmodel_test_plugin")

    def register(subparsers):
        p = subparsers.add_parser("hello", help="test subcommand")
        p.add_argument("--times", type=int, default=1)
        p.set_defaults(handler=lambda args: print("hello " * args.times) or 5)

    plugin.register = register
    monkeypatch.setitem(sys.modules, "chainmodel_test_plugin", plugin)
    monkeypatch.setattr(cli, "SUBCOMMANDS", cli.SUBCOMMANDS + [
        ("chainmodel_test_plugin", "register"), ("chainmodel_no_such_module_xyz", "register")])
    code, out, _ = run_cli(capsys, "hello", "--times", 2)
    assert code == 5 and out.strip() == "hello hello"
    assert run_cli(capsys, "presets")[0] == 0


# --- library bug found through the CLI --------------------------------------------------------

def test_preset_with_only_span_pitches_overridden(capsys):
    """Bug fixed in presets.py: a preset given by its centre distance (xu2010) with only N or
    only f overridden raised KeyError / a misleading 'got None'."""
    data = run_json(capsys, "kinematics", "--preset", "xu2010", "--span-pitches", 10)
    base = preset("xu2010")
    assert data["drive"]["span_pitches"] == 10
    assert data["drive"]["pitch_fraction"] == pytest.approx(base.pitch_fraction, abs=1e-15)
    data = run_json(capsys, "wrap", "--preset", "xu2010", "--pitch-fraction", 0.2)
    assert data["drive"]["span_pitches"] == base.span_pitches
    assert data["drive"]["pitch_fraction"] == 0.2


# --- documentation and the real entry point ---------------------------------------------------

def test_every_json_key_is_documented(capsys):
    keys = documented_keys()
    outputs = [run_json(capsys, "kinematics", "--preset", "coarse", "--samples", 10),
               run_json(capsys, "wrap", "--preset", "A1", "--samples", 10),
               run_json(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.1),
               run_json(capsys, "presets")]
    for data in outputs:
        for key, value in data.items():
            assert key in keys, f"{key} is not documented in docs/cli.md"
            if isinstance(value, dict):
                assert set(value) <= keys, set(value) - keys
    assert {"drive", "seating", "release", "approximate"} <= keys


def test_python_dash_m_entry_point(tmp_path):
    env = dict(os.environ)
    env["PYTHONPATH"] = os.pathsep.join([str(ROOT)] + [p for p in [env.get("PYTHONPATH")] if p])
    ok = subprocess.run([sys.executable, "-m", "chainmodel", "kinematics", "--preset", "medium",
                         "--samples", "50", "--json"], cwd=tmp_path, env=env, capture_output=True,
                        text=True, timeout=60)
    assert ok.returncode == 0, ok.stderr
    data = json.loads(ok.stdout)
    assert data["seating"]["theta4"] == pytest.approx(kinematics.seating(preset("medium")).theta4,
                                                      abs=1e-12)
    bad = subprocess.run([sys.executable, "-m", "chainmodel", "run", "nosuch"], cwd=tmp_path,
                         env=env, capture_output=True, text=True, timeout=60)
    assert bad.returncode == 2 and bad.stdout == ""
    assert bad.stderr.count("\n") == 1 and "Traceback" not in bad.stderr


# --- through the FMU (only where it has been built) -------------------------------------------

@pytest.mark.fmu
def test_run_via_fmu_warns_when_the_fmu_is_another_version(capsys, chaindrive_fmu, tmp_path):
    """An FMU built from this tree runs without the warning; the same FMU with one file of its
    embedded chainmodel changed (as an FMU built from another version) gets it, naming the
    file and the rebuild."""
    import zipfile
    argv = ["run", "xu2010", "--fidelity", 0, "--duration", 0.2, "--output-interval", 1e-3]
    fresh = run_json(capsys, *argv, "--via-fmu", chaindrive_fmu)     # stderr silent
    assert not any("not built from this chainmodel" in w for w in fresh["warnings"])
    old = tmp_path / "ChainDrive.fmu"
    with zipfile.ZipFile(chaindrive_fmu) as src, zipfile.ZipFile(old, "w") as dst:
        for item in src.infolist():
            data = src.read(item.filename)
            if item.filename == "resources/_vendor/chainmodel/units.py":
                data += b"\n# another version\n"
            dst.writestr(item, data)
    code, out, err = run_cli(capsys, *argv, "--via-fmu", old, "--json")
    stale = json.loads(out)
    assert code == 0 and "chainmodel: warning: the FMU" in err
    (text,) = [w for w in stale["warnings"] if "not built from this chainmodel" in w]
    assert "1 of its package files differ (chainmodel/units.py)" in text
    assert "python build_fmu.py" in text


@pytest.mark.fmu
def test_run_via_fmu_matches_the_library(capsys, request):
    try:
        import chainmodel.fmu  # noqa: F401
    except ImportError:
        pytest.skip("chainmodel.fmu is not in this tree yet")
    try:
        fmu = request.getfixturevalue("chaindrive_fmu")     # built once per session (conftest)
    except pytest.FixtureLookupError:
        fmu = ROOT / "dist" / "ChainDrive.fmu"
        if not fmu.is_file():
            pytest.skip("dist/ChainDrive.fmu not built (python build_fmu.py)")
    argv = ["run", "xu2010", "--fidelity", 0, "--duration", 0.2, "--output-interval", 1e-3]
    data = run_json(capsys, *argv, "--via-fmu", fmu)
    lib = run_json(capsys, *argv)
    assert data["via_fmu"] is True and lib["via_fmu"] is False
    # the FMU's start-up is a part of its wall time; the library has none to report
    assert 0 < data["startup_time_s"] < data["wall_time_s"] and lib["startup_time_s"] is None
    assert data["tooth_ratio"] == pytest.approx(25 / 17, abs=1e-9)
    assert data["meshing_frequency_hz"] == pytest.approx(50.0, rel=1e-9)
    # same scene, same level-0 physics; the FMU's inputs differ only during the ramp
    # (backward-difference acceleration), which the steady half excludes
    for key in ("mean_tight_tension_n", "peak_tight_tension_n", "mean_slack_tension_n",
                "mean_input_torque_nm", "static_span_tension_n"):
        assert data[key] == pytest.approx(lib[key], rel=1e-9), key


@pytest.mark.parametrize("text, value", [("-1e3", -1e3), ("-2.5E1", -25.0), ("-.5e1", -5.0),
                                         ("-5", -5.0)])
def test_negative_numbers_in_exponent_form_are_values_not_options(capsys, text, value):
    """`--load-torque -1e3` (argparse before Python 3.13 took it for an option)."""
    code, out, err = run_cli(capsys, "run", "xu2010", "--fidelity", 0, "--duration", 0.2,
                             "--output-interval", 1e-3, "--load-torque", text, "--json")
    assert code == 0, err
    assert json.loads(out)["load_torque_nm"] == value
