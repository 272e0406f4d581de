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


# --- the suite leaves nothing in the user's cache, home or working tree (issue 19 item 5) ----
#
# Every process of the session (this one, build_fmu.py, `python -m chainmodel`, Dask workers)
# compiles its numba kernels into a session folder instead of the user's cache: the session
# sets CHAINMODEL_CACHE_DIR before chainmodel is imported, and copies the user's compiled
# kernels in first so nothing is compiled that the user's cache already holds (a few MB).
# matplotlib's font cache goes there too (MPLCONFIGDIR). At the end the session folder is
# removed, and the run fails if the user's kernel cache, matplotlib's folders in the home
# directory or the repository's untracked files gained anything while it ran.
# CHAINMODEL_TEST_LEFTOVERS=warn reports instead of failing (e.g. while another process shares
# the cache).

import os
import shutil
import tempfile


def _user_kernel_cache() -> Path:
    """chainmodel.numba_cache.cache_root() as the user's environment sets it, read without
    importing the package (its import compiles or loads kernels, which must already see the
    session's folder)."""
    import importlib.util
    spec = importlib.util.spec_from_file_location("_chaindrive_cache_root_probe",
                                                  ROOT / "chainmodel" / "numba_cache.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)                     # standard library imports only
    return module.cache_root()


def _listing(folder: Path) -> set[str]:
    if not folder.is_dir():
        return set()
    return {str(p) for p in folder.rglob("*") if p.is_file()}


def _untracked() -> set[str]:
    proc = subprocess.run(["git", "ls-files", "--others", "--exclude-standard"], cwd=ROOT,
                          capture_output=True, text=True)
    return {str(ROOT / line) for line in proc.stdout.splitlines()} if proc.returncode == 0 else set()


def _watched() -> dict[str, set[str]]:
    home = Path.home()
    xdg_cache = Path(os.environ.get("XDG_CACHE_HOME") or home / ".cache")
    xdg_config = Path(os.environ.get("XDG_CONFIG_HOME") or home / ".config")
    return {"the user's numba kernel cache": _listing(_SESSION["user_cache"]),
            "matplotlib's cache": _listing(xdg_cache / "matplotlib"),
            "matplotlib's configuration": _listing(xdg_config / "matplotlib"),
            "the repository (untracked files)": _untracked()}


def _isolate() -> dict:
    """Point the session's caches at a temporary folder (see above); returns the state the
    session end needs."""
    state = {"user_cache": _user_kernel_cache()}
    session = Path(tempfile.mkdtemp(prefix="chaindrive-tests-"))
    state["session"] = session
    if state["user_cache"].is_dir():
        shutil.copytree(state["user_cache"], session / "numba", dirs_exist_ok=True,
                        ignore=shutil.ignore_patterns("*.lock"))
    mpl = session / "matplotlib"
    mpl.mkdir()
    user_mpl = Path(os.environ.get("MPLCONFIGDIR") or
                    Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "matplotlib")
    for font_cache in user_mpl.glob("fontlist-*.json"):     # saves rebuilding it (seconds)
        shutil.copy2(font_cache, mpl)
    os.environ["CHAINMODEL_CACHE_DIR"] = str(session)
    os.environ["MPLCONFIGDIR"] = str(mpl)
    return state


_SESSION = _isolate()
_SESSION["before"] = _watched()


def pytest_sessionfinish(session, exitstatus):
    added = {what: sorted(files - _SESSION["before"].get(what, set()))
             for what, files in _watched().items()}
    shutil.rmtree(_SESSION["session"], ignore_errors=True)
    added = {what: files for what, files in added.items() if files}
    if not added:
        return
    lines = [f"the test session left files behind in {what}: {len(files)}, e.g. "
             + ", ".join(files[:3]) for what, files in added.items()]
    lines.append("(or another process wrote there while the tests ran; "
                 "CHAINMODEL_TEST_LEFTOVERS=warn reports without failing)")
    reporter = session.config.pluginmanager.get_plugin("terminalreporter")
    if reporter is not None:
        reporter.write_line("")
        for line in lines:
            reporter.write_line(("WARNING: " if _warn_only() else "ERROR: ") + line)
    if not _warn_only() and session.exitstatus == 0:
        session.exitstatus = 1


def _warn_only() -> bool:
    return os.environ.get("CHAINMODEL_TEST_LEFTOVERS", "").strip().lower() == "warn"
