"""Issue 19 item 5: the test suite leaves nothing in the user's cache, home or working tree.

conftest.py points every process of the session at a session folder (CHAINMODEL_CACHE_DIR,
MPLCONFIGDIR) and fails the run when the watched folders gained files. Checked here on a
miniature copy of the suite run by a real pytest in a subprocess, with its own home folder."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def run_suite(tmp_path: Path, test_source: str, **env) -> subprocess.CompletedProcess:
    (tmp_path / "tests").mkdir()
    (tmp_path / "chainmodel").mkdir()
    shutil.copy2(ROOT / "tests" / "conftest.py", tmp_path / "tests")
    shutil.copy2(ROOT / "chainmodel" / "numba_cache.py", tmp_path / "chainmodel")
    (tmp_path / "tests" / "test_mini.py").write_text(test_source)
    home = tmp_path / "home"
    (home / ".cache" / "chaindrive" / "numba" / "chainmodel.kernels.spans").mkdir(parents=True)
    (home / ".cache" / "chaindrive" / "numba" / "chainmodel.kernels.spans" / "k.nbi").write_text("x")
    clean = {k: v for k, v in os.environ.items()
             if k not in ("CHAINMODEL_CACHE_DIR", "MPLCONFIGDIR", "XDG_CACHE_HOME",
                          "XDG_CONFIG_HOME", "CHAINMODEL_TEST_LEFTOVERS", "PYTEST_ADDOPTS")}
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider",
                           "tests/test_mini.py"], cwd=tmp_path, capture_output=True, text=True,
                          env={**clean, "HOME": str(home), **env}, timeout=120)


CLEAN = '''
import os
from pathlib import Path

def test_uses_the_session_folder():
    folder = Path(os.environ["CHAINMODEL_CACHE_DIR"])
    assert folder.name.startswith("chaindrive-tests-")
    # the user's compiled kernels were copied in, so nothing is compiled twice
    assert (folder / "numba" / "chainmodel.kernels.spans" / "k.nbi").read_text() == "x"
    (folder / "numba" / "new.nbi").write_text("compiled in the session")
    Path(os.environ["MPLCONFIGDIR"], "fontlist.json").write_text("{}")
    Path("session.txt").write_text(str(folder))     # (the miniature's cwd is no repository)
'''

LEAK = '''
from pathlib import Path

def test_writes_into_the_users_cache():
    # a process that ignores CHAINMODEL_CACHE_DIR (say, a build run with a cleaned environment)
    (Path.home() / ".cache" / "chaindrive" / "numba" / "leaked.nbi").write_text("left behind")
'''


def test_a_clean_session_passes_and_removes_its_folder(tmp_path):
    proc = run_suite(tmp_path, CLEAN)
    assert proc.returncode == 0, proc.stdout + proc.stderr
    assert "left files behind" not in proc.stdout
    # the user's cache is as it was, and the session folders are gone
    cache = tmp_path / "home" / ".cache" / "chaindrive" / "numba"
    assert sorted(p.name for p in cache.rglob("*") if p.is_file()) == ["k.nbi"]
    assert not (tmp_path / "home" / ".cache" / "matplotlib").exists()
    session = Path((tmp_path / "session.txt").read_text())
    assert session.name.startswith("chaindrive-tests-") and not session.exists()


def test_a_session_that_leaves_files_fails(tmp_path):
    proc = run_suite(tmp_path, LEAK)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "1 passed" in proc.stdout
    assert "ERROR: the test session left files behind in the user's numba kernel cache: 1" \
        in proc.stdout and "leaked.nbi" in proc.stdout


def test_leftovers_can_be_reported_without_failing(tmp_path):
    proc = run_suite(tmp_path, LEAK, CHAINMODEL_TEST_LEFTOVERS="warn")
    assert proc.returncode == 0 and "WARNING: the test session left files behind" in proc.stdout


def test_this_session_is_isolated():
    """The running suite itself compiles into its session folder, not the user's cache."""
    from chainmodel.numba_cache import cache_root
    assert Path(os.environ["CHAINMODEL_CACHE_DIR"]).name.startswith("chaindrive-tests-")
    assert cache_root() == Path(os.environ["CHAINMODEL_CACHE_DIR"]) / "numba"
    pytest.importorskip("matplotlib")
    import matplotlib
    assert Path(matplotlib.get_cachedir()) == Path(os.environ["MPLCONFIGDIR"])
