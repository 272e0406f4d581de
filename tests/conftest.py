"""Shared test fixtures. Others may add fixtures here; keep each one small and documented."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def chaindrive_fmu(tmp_path_factory) -> Path:
    """ChainDrive.fmu built ONCE per test session, with `python build_fmu.py` exactly as a user
    runs it (in a subprocess, so pythonfmu's builder leaves no modules in this process), into a
    temporary directory. The build itself fails if fmpy's validation finds a problem."""
    out = tmp_path_factory.mktemp("fmu") / "ChainDrive.fmu"
    proc = subprocess.run([sys.executable, str(ROOT / "build_fmu.py"), "--out", str(out), "-q"],
                          capture_output=True, text=True, cwd=ROOT)
    if proc.returncode != 0 or not out.is_file():
        pytest.fail(f"build_fmu.py failed (exit {proc.returncode}):\n{proc.stdout}\n{proc.stderr}")
    return out


@pytest.fixture(scope="session")
def chaindrive_fmu_dir(chaindrive_fmu, tmp_path_factory) -> Path:
    """The session's ChainDrive.fmu unzipped once (fmpy loads instances from here)."""
    from fmpy import extract
    return Path(extract(str(chaindrive_fmu), str(tmp_path_factory.mktemp("fmu_unzipped"))))
