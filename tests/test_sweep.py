"""Parameter sweeps (issue 12): studies checked before any case runs, metrics from physics,
Dask runs equal to serial ones, failing cases recorded, kill-and-resume, the CLI.

Cases are tiny (levels 0-1, 0.1 s, 1 ms outputs). Expected numbers come from physics written
in the test (a synthetic sine's amplitude, the taut-string frequency, seed 000 eq 5) or from
the library computed independently in the test - never from an earlier sweep. Equality between
serial and Dask runs is exact: the same code on the same machine gives the same bits.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import chainmodel
from chainmodel import cli
from chainmodel.analysis.sweep import load_study, run_case, sweep
from chainmodel.analysis.sweep.metrics import (amplitude_spectrum, resonances, spectral_peaks,
                                               span_mode_frequency)
from chainmodel.analysis.sweep.runner import Journal, chunks_for
from chainmodel.analysis.sweep.table import read_table

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "studies" / "speed_pretension.toml"
QUICK = {"duration": 0.1, "output_interval": 1e-3}


def small_study(**vary):
    return {"name": "small", "scene": "xu2010", "fixed": {"fidelity": 1, **QUICK},
            "vary": vary or {"input_speed_rpm": [60, 120, 180, 240],
                             "static_tension": [650, 900, 1200]}}


def same(a, b) -> bool:
    """Exact equality of two table columns (nan equals nan)."""
    return len(a) == len(b) and all(
        x == y or (isinstance(x, float) and isinstance(y, float) and math.isnan(x)
                   and math.isnan(y)) for x, y in zip(a, b))


@pytest.fixture(scope="module")
def cluster():
    """One 2-worker LocalCluster for this module's Dask tests (started once: ~5-10 s)."""
    distributed = pytest.importorskip("distributed")
    import logging
    c = distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                 dashboard_address=None, silence_logs=logging.ERROR)
    yield c
    c.close()


# --- the study is checked before any case runs ------------------------------------------------

@pytest.mark.parametrize("vary, fragment", [
    ({"input_speed_rmp": [60]}, "input_speed_rmp'; did you mean input_speed_rpm"),
    ({"chain.link_stifness": [1e7]}, "did you mean chain.link_stiffness"),
    ({"input_speed_rpm": []}, "input_speed_rpm: the grid is empty"),
    ({"static_tension": [700, -5]}, "static_tension"),
    ({"chain.link_stiffness": [5e7, 0.0]}, "chain.link_stiffness"),
    ({"drive.pitch_fraction": [0.2, 1.5]}, "pitch_fraction"),
    ({"input_speed_rpm": {"start": 60, "stop": 10, "step": 10}}, "input_speed_rpm"),
    ({}, "varies nothing"),
])
def test_bad_studies_are_refused_before_any_case_runs(tmp_path, vary, fragment):
    study = {"name": "bad", "fixed": {"fidelity": 0, **QUICK}, "vary": vary}
    with pytest.raises(ValueError, match=fragment.replace("(", r"\(").replace("[", r"\[")):
        sweep(study, tmp_path / "out", serial=True)
    assert not (tmp_path / "out").exists()          # nothing ran, nothing was written


def test_bad_study_in_the_cli_is_one_line_and_exit_2(tmp_path, capsys):
    path = tmp_path / "bad.toml"
    path.write_text('[vary]\nstatic_tensoin = [600]\n')
    assert cli.main(["sweep", str(path), "--serial", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "static_tensoin" in err and "static_tension" in err


def test_grid_and_random_designs():
    st = load_study({"fixed": QUICK, "vary": {"input_speed_rpm": {"start": 60, "stop": 120,
                                                                   "step": 30},
                                               "drive.driver_teeth": [19, 25]}})
    assert [c["input_speed_rpm"] for c in st.cases] == [60, 60, 90, 90, 120, 120]
    assert len(st) == 3 * 2
    spec = {"design": "random", "samples": 7, "seed": 3, "fixed": QUICK,
            "vary": {"load_torque": {"min": 10.0, "max": 40.0}, "drive.links": {"min": 44,
                                                                              "max": 48},
                     "fidelity": [0, 1]}}
    a, b = load_study(dict(spec)), load_study(dict(spec))
    assert a.cases == b.cases and len(a) == 7                       # reproducible
    assert all(10.0 <= c["load_torque"] <= 40.0 for c in a.cases)
    assert all(isinstance(c["drive.links"], int) and 44 <= c["drive.links"] <= 48
               for c in a.cases)


def test_pitch_fraction_moves_the_centre_distance_by_seed_000_eq_5():
    st = load_study({"fixed": {"fidelity": 0, **QUICK},
                     "vary": {"drive.pitch_fraction": [0.1, 0.6], "drive.span_pitches": [10]}})
    for i, case in enumerate(st.cases):
        d = st.scene(i).drive
        p = d.pitch
        # x_c = (N + 1 + f) p, the tight span's tangent length (seed 000 eq 5)
        assert d.x_c == pytest.approx((10 + 1 + case["drive.pitch_fraction"]) * p, rel=1e-9)


# --- metrics --------------------------------------------------------------------------------

def test_spectrum_reads_the_amplitude_of_a_sine():
    fs, n = 2000.0, 4000                      # 2 s: bins every 0.5 Hz, 50 and 120 Hz on bins
    t = np.arange(n) / fs
    x = 7.0 + 3.0 * np.sin(2 * np.pi * 50 * t) + 0.5 * np.cos(2 * np.pi * 120 * t)
    f, a = amplitude_spectrum(t, x)
    (f1, a1), (f2, a2), _ = spectral_peaks(f, a)
    assert (f1, f2) == (50.0, 120.0)
    assert a1 == pytest.approx(3.0, rel=1e-3) and a2 == pytest.approx(0.5, rel=1e-3)


def test_span_mode_is_the_axially_moving_string():
    T, m, p, l = 1000.0, 0.0162, 0.015875, 0.19
    rho = m / p
    # at rest: a taut string, f1 = sqrt(T / rho) / 2l
    assert span_mode_frequency(T, m, p, 0.0, l) == pytest.approx(math.sqrt(T / rho) / (2 * l))
    # at the critical speed S^2 = T / rho the span has no transverse stiffness
    assert math.isnan(span_mode_frequency(T, m, p, math.sqrt(T / rho), l))
    # the library's level-2 model (seed 004 eq 61 in its own code) gives the same
    sc = chainmodel.load_scene("xu2010", fidelity=2)
    model = sc.model()
    S, lbar = 5.0, model.reference["l_up"]
    span = model.modal_frequencies(T, S, "upper")[0] / (2 * math.pi)
    ours = span_mode_frequency(T, sc.parameters["chain.link_mass"], sc.drive.pitch, S, lbar)
    assert ours == pytest.approx(span, rel=1e-12)


def test_resonance_band():
    hit, which, d = resonances(100.0, {"tight_span": 51.0, "sprocket_1": 300.0}, 0.05)
    assert hit and which == "tight_span@mesh/2" and d == pytest.approx(50.0 / 51.0 - 1)
    hit, which, _ = resonances(100.0, {"tight_span": 97.0}, 0.05)
    assert hit and which == "tight_span@mesh"
    assert not resonances(100.0, {"tight_span": 80.0, "sprocket_1": math.nan}, 0.05)[0]


def test_case_metrics_match_the_run_summary():
    """A sweep case reports what `chainmodel run` reports for the same scene."""
    st = load_study(small_study(input_speed_rpm=[150]))
    row = run_case(st, 0)["row"]
    s = chainmodel.simulate(st.scene(0)).summary()
    assert row["status"] == "ok"
    for k in ("mean_tight_tension_n", "peak_tight_tension_n", "mean_slack_tension_n",
              "driven_speed_ripple_rms_rad_s", "meshing_frequency_hz"):
        assert row[k] == pytest.approx(s[k], rel=1e-12), k


def test_no_compilation_per_case():
    """After one case, others with other parameters at the same level add no compiled
    specialisation: kernels compile (or load from numba's cache) once per process."""
    from chainmodel.kernels import rk4_loop
    kernel = rk4_loop.advance_points      # simulate()'s compiled loop at levels 1-2
    if not hasattr(kernel, "signatures"):
        pytest.skip("numba is switched off (CHAINMODEL_NUMBA=0): nothing is compiled")
    st = load_study(small_study(input_speed_rpm=[60, 200], chain_link_damping=[50.0, 150.0]))
    run_case(st, 0)
    before = len(kernel.signatures)
    for i in range(1, len(st)):
        assert run_case(st, i)["row"]["status"] == "ok"
    assert len(kernel.signatures) == before


def test_chunks_deal_every_case_once():
    chunks = chunks_for(list(range(23)), workers=2)
    assert sorted(i for c in chunks for i in c) == list(range(23)) and len(chunks) == 16
    assert [len(c) for c in chunks_for(list(range(10)), 2, chunk_size=4)] == [4, 3, 3]


# --- running: Dask equals serial, failures, resume ---------------------------------------------

def test_two_workers_equal_serial_exactly(tmp_path, cluster):
    serial = sweep(small_study(), tmp_path / "serial", serial=True, plots=False)
    dask = sweep(small_study(), tmp_path / "dask", scheduler=cluster.scheduler_address,
                 plots=False)
    assert len(serial.study) == 12 and dask.run.workers == 2 and dask.run.computed == 12
    assert set(r["worker"] for r in dask.run.records) != {serial.run.records[0]["worker"]}
    assert list(serial.table) == list(dask.table)
    for k in serial.table:
        assert same(serial.table[k], dask.table[k]), k
    assert all(s == "ok" for s in dask.table["status"])
    assert (serial.files["table"].read_bytes() == dask.files["table"].read_bytes())


def test_a_failing_case_is_recorded_and_the_others_run(tmp_path, cluster):
    study = {"fixed": {"fidelity": 1, "solver.method": "rk4", **QUICK},
             "vary": {"solver.step": [0.0, 5e-3], "input_speed_rpm": [60, 120]}}
    res = sweep(study, tmp_path / "o", scheduler=cluster.scheduler_address, plots=False)
    status, error = res.table["status"], res.table["error"]
    steps = res.table["solver.step"]
    for k in range(4):
        if steps[k] == 0.0:
            assert status[k] == "ok" and error[k] == ""
        else:       # above the stable limit of rk4 for the 615 Hz sprocket mode: refused
            assert status[k] == "failed" and "solver.step" in error[k] and "stable" in error[k]
            assert math.isnan(res.table["mean_tight_tension_n"][k])
    assert res.failed == [k for k in range(4) if steps[k] != 0.0]
    # the error survives the round trip through the written table
    assert read_table(res.files["table"])["error"] == error


def test_kill_and_resume_recomputes_nothing_that_finished(tmp_path, cluster):
    study = tmp_path / "study.toml"
    study.write_text('name = "resume"\n[fixed]\nfidelity = 1\nduration = 3.0\n'
                     'output_interval = 1e-4\n[vary]\ninput_speed_rpm = [60, 80, 100, 120, 140, '
                     '160, 180, 200, 220, 240]\n')
    out = tmp_path / "out"
    journal = out / "cases.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "chainmodel", "sweep", str(study), "--serial",
                             "--out", str(out), "--quiet", "--no-plots"],
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and proc.poll() is None:
        if journal.is_file() and journal.read_text().count("\n") >= 3:
            break
        time.sleep(0.05)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    assert proc.returncode == -signal.SIGKILL, proc.stderr.read().decode()
    before = journal.read_bytes()
    finished = Journal(out).load()
    assert 3 <= len(finished) < 10
    seen = []
    res = sweep(study, out, scheduler=cluster.scheduler_address, plots=False,
                on_record=lambda rec: seen.append(rec["case"]))
    assert res.run.reused == len(finished)
    assert res.run.computed == 10 - len(finished)
    done_before = {rec["case"] for rec in finished.values()}
    assert not done_before & set(seen)                       # nothing finished ran again
    assert sorted(done_before | set(seen)) == list(range(10))
    assert journal.read_bytes().startswith(before.rstrip(b"\n").rsplit(b"\n", 1)[0])
    assert all(s == "ok" for s in res.table["status"])
    # a third run finds everything in the journal and runs nothing
    again = sweep(study, out, serial=True, plots=False)
    assert again.run.computed == 0 and again.run.reused == 10
    for k in res.table:
        assert same(res.table[k], again.table[k]), k


def test_csv_table_when_asked(tmp_path):
    res = sweep(small_study(input_speed_rpm=[90, 150]), tmp_path / "o", serial=True,
                plots=False, table_format="csv")
    assert res.files["table"].suffix == ".csv"
    back = read_table(res.files["table"])
    for k in res.table:
        assert same(back[k], res.table[k]), k


# --- the CLI on the shipped example ---------------------------------------------------------

def test_cli_example_workers_and_serial_write_identical_tables(tmp_path):
    # level 1: the example reaches 600 rpm, beyond level 0's speed limit on xu2010 (552 rpm)
    quick = ["--set", "duration=0.1", "--set", "output_interval=1e-3", "--set", "fidelity=1"]
    outs = {}
    for mode in (["--workers", "2", "--no-plots"], ["--serial"]):
        out = tmp_path / mode[0].strip("-")
        proc = subprocess.run([sys.executable, "-m", "chainmodel", "sweep", str(EXAMPLE), *mode,
                               "--out", str(out), "--quiet", *quick],
                              capture_output=True, text=True, cwd=tmp_path, timeout=600)
        assert proc.returncode == 0, proc.stderr
        written = [line.split(" to ", 1)[1] for line in proc.stdout.splitlines()
                   if line.startswith("wrote ")]
        expected = {"cases.jsonl", "study.json"} | (
            set() if "--no-plots" in mode else {"campbell.png", "resonance_map.png"})
        assert {Path(w).name for w in written} >= expected
        assert all(Path(w).is_file() for w in written)      # every file it names exists
        outs[mode[0]] = out
    names = [p.name for p in outs["--workers"].iterdir() if p.name.startswith("results.")]
    assert len(names) == 1
    a = (outs["--workers"] / names[0]).read_bytes()
    b = (outs["--serial"] / names[0]).read_bytes()
    assert a == b
    table = read_table(outs["--serial"] / names[0])
    assert len(table["case"]) == 55 * 6 and set(table["status"]) == {"ok"}
    assert (outs["--serial"] / "campbell.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_cli_json(tmp_path, capsys):
    path = tmp_path / "s.toml"
    path.write_text('[fixed]\nfidelity = 0\nduration = 0.1\noutput_interval = 1e-3\n'
                    '[vary]\nload_torque = [10.0, 20.0]\n')
    assert cli.main(["sweep", str(path), "--serial", "--json", "--no-plots",
                     "--out", str(tmp_path / "o")]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["cases"] == 2 and data["computed"] == 2 and data["failed"] == 0
    assert Path(data["files"]["table"]).is_file()


# --- through the FMU --------------------------------------------------------------------------

@pytest.mark.fmu
def test_sweep_through_the_fmu_reuses_one_instance(tmp_path, chaindrive_fmu):
    """Each case through the FMU (one instance, fmi2Reset between cases) gives the metrics
    of a fresh chainmodel.fmu.simulate_fmu run of its scene."""
    from chainmodel.analysis.sweep.metrics import case_metrics
    from chainmodel.fmu import simulate_fmu
    study = small_study(input_speed_rpm=[90, 150], static_tension=[700])
    study["fixed"]["fidelity"] = 0
    res = sweep(study, tmp_path / "o", serial=True, plots=False, via_fmu=chaindrive_fmu)
    assert res.run.chunks == 1 and set(res.table["status"]) == {"ok"}
    for i in range(2):
        fresh, _ = case_metrics(simulate_fmu(chaindrive_fmu, res.study.scene(i)))
        for k, v in fresh.items():
            assert same([res.table[k][i]], [v]), k
