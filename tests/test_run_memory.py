"""Issue 19 item 2: a run whose time series would not fit in memory is refused at once, with
the estimate (samples x outputs x 8 bytes, computed here independently) and what would fit."""

from __future__ import annotations

import os
import re
import subprocess
import sys
import time

import pytest

import chainmodel
from chainmodel import cli, run_memory
from chainmodel.run_memory import RunTooLarge

#: this project's machine: 24.7 GB available (MemAvailable); the tests pin it so the verdicts
#: do not depend on the machine running them
AVAILABLE = 24.7e9


@pytest.fixture
def machine(monkeypatch):
    monkeypatch.delenv(run_memory.ENV_VAR, raising=False)
    monkeypatch.setattr(run_memory, "available_memory", lambda: int(AVAILABLE))


def outputs_per_sample() -> int:
    """The outputs a run keeps, counted on a real (short) run."""
    return len(chainmodel.simulate("xu2010", fidelity=0, duration=0.01).names)


def expected_samples(duration: float, interval: float = 1e-4) -> int:
    return round(duration / interval) + 1            # both ends of [0, duration]


@pytest.mark.parametrize("duration", [1e6, 1e4])
def test_cli_refuses_at_once_with_the_estimate(capsys, machine, duration):
    start = time.perf_counter()
    code = cli.main(["run", "xu2010", "--duration", str(duration)])
    elapsed = time.perf_counter() - start
    out, err = capsys.readouterr()
    assert code == 2 and out == ""
    assert err.count("\n") == 1 and err.startswith("chainmodel: error: ") and "Traceback" not in err
    assert elapsed < 5.0                    # nothing allocated, nothing simulated
    samples, outputs = expected_samples(duration), outputs_per_sample()
    m = re.search(r"(\d+) samples x (\d+) outputs x 8 bytes = ([\d.e+]+) ([kMGT]B)", err)
    assert m, err
    assert (int(m[1]), int(m[2])) == (samples, outputs)
    scale = {"kB": 1e3, "MB": 1e6, "GB": 1e9, "TB": 1e12}[m[4]]
    assert float(m[3]) * scale == pytest.approx(samples * outputs * 8, rel=5e-3)   # 3 digits
    for option in ("output_interval", "shorter duration", run_memory.ENV_VAR):
        assert option in err


def test_library_raises_value_error_with_the_bytes(machine):
    samples, outputs = expected_samples(1e4), outputs_per_sample()
    with pytest.raises(ValueError, match="samples x") as info:
        chainmodel.simulate("xu2010", duration=1e4)
    exc = info.value
    assert isinstance(exc, RunTooLarge)
    assert exc.samples == samples and exc.output_bytes == samples * outputs * 8
    assert exc.total_bytes > exc.output_bytes and exc.limit_bytes == int(0.5 * AVAILABLE)


def test_the_suggested_settings_fit(machine):
    """What the message proposes is accepted by the same check (it would run)."""
    with pytest.raises(RunTooLarge) as info:
        run_memory.check_run_memory(1e4, 1e-4, 1)
    text = str(info.value)
    interval = float(re.search(r"output_interval \(>= ([\d.e+-]+) s fits\)", text)[1])
    duration = float(re.search(r"shorter duration \(<= ([\d.e+-]+) s fits\)", text)[1])
    run_memory.check_run_memory(1e4, interval * 1.001, 1)       # no exception
    run_memory.check_run_memory(duration, 1e-4, 1)


def test_limit_override_and_small_runs(monkeypatch):
    monkeypatch.setenv(run_memory.ENV_VAR, "1M")
    # 1 s at 0.1 ms: 10001 samples x (15 + 7) arrays x 8 bytes = 1.76 MB > 1 MB
    with pytest.raises(RunTooLarge, match=r"1 MB allowed \(CHAINMODEL_MEMORY_LIMIT=1M\)"):
        run_memory.check_run_memory(1.0, 1e-4, 1, outputs=15)
    run_memory.check_run_memory(0.5, 1e-4, 1, outputs=15)        # 5001 x 22 x 8 = 0.88 MB
    monkeypatch.setenv(run_memory.ENV_VAR, "none")
    run_memory.check_run_memory(1e6, 1e-4, 1)                    # check turned off
    monkeypatch.setenv(run_memory.ENV_VAR, "lots")
    with pytest.raises(ValueError, match="CHAINMODEL_MEMORY_LIMIT='lots' is not a size"):
        run_memory.check_run_memory(1.0, 1e-4, 1)


def test_available_memory_is_read_from_the_system():
    avail = run_memory.available_memory()
    assert avail is None or avail > 0
    if sys.platform.startswith("linux"):
        with open("/proc/meminfo") as fh:
            kb = next(int(line.split()[1]) for line in fh if line.startswith("MemAvailable:"))
        assert abs(avail - kb * 1024) < 0.2 * kb * 1024       # it moves while we read it


def test_real_command_answers_in_one_line(tmp_path):
    """The installed entry point, as the issue ran it: one line, exit 2, at once."""
    start = time.perf_counter()
    env = {k: v for k, v in os.environ.items() if k != run_memory.ENV_VAR}    # the default limit
    proc = subprocess.run([sys.executable, "-m", "chainmodel", "run", "xu2010", "--duration",
                           "1e6"], capture_output=True, text=True, cwd=tmp_path, timeout=60,
                          env=env)
    assert proc.returncode == 2 and proc.stdout == ""
    assert proc.stderr.count("\n") == 1 and "1.2 TB of outputs" in proc.stderr
    assert time.perf_counter() - start < 30     # imports only (numba's); nothing allocated


@pytest.mark.fmu
def test_fmu_run_is_refused_before_it_starts(chaindrive_fmu, machine):
    """simulate_fmu keeps the same time series: the same refusal, before the first step."""
    from chainmodel.fmu import simulate_fmu
    from chainmodel.scene import load_scene
    scene = load_scene("xu2010").with_overrides(duration=1e4)
    start = time.perf_counter()
    with pytest.raises(RunTooLarge) as info:
        simulate_fmu(chaindrive_fmu, scene)
    assert time.perf_counter() - start < 30          # extraction only, no step
    assert info.value.output_bytes == expected_samples(1e4) * outputs_per_sample() * 8
