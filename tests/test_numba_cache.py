"""The per-machine kernel cache (chainmodel.numba_cache, docs/numba_cache.md).

A toy package with a three-module dependency chain (a kernel calling a jitted helper that reads
a constant of a third module) is compiled in fresh processes against a temporary cache folder;
numba's dispatcher statistics (cache hits and misses) and the one-line compile notice say what
each process did. The expected kernel results are the toy's arithmetic, computed here."""

from __future__ import annotations

import ast
import json
import os
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

numba = pytest.importorskip("numba")

ROOT = Path(__file__).resolve().parents[1]
NOTICE = "chainmodel: compiling the numba kernels"

TOY = {
    "__init__.py": "",
    "consts.py": "SCALE = {scale}\n",
    "helper.py": """
        from .numba_cache import cached_njit
        from .consts import SCALE

        @cached_njit
        def helper(x):
            return x * SCALE
        """,
    "kern.py": """
        from .numba_cache import cached_njit
        from .helper import helper

        @cached_njit
        def kernel(x):
            return helper(x) + {offset}
        """,
}

RUN = """
import json, sys
from toy.kern import kernel
value = kernel(3.0)
st = kernel.stats
print(json.dumps({"value": value, "hits": sum(st.cache_hits.values()),
                  "misses": sum(st.cache_misses.values()), "path": st.cache_path}))
"""


def write_toy(where: Path, scale=2.0, offset=1.0) -> Path:
    pkg = where / "toy"
    pkg.mkdir(parents=True, exist_ok=True)
    for name, text in TOY.items():
        (pkg / name).write_text(textwrap.dedent(text).format(scale=scale, offset=offset))
    # the mechanism under test, as a module of the toy (importing chainmodel would cost seconds
    # per process)
    shutil.copy2(ROOT / "chainmodel" / "numba_cache.py", pkg / "numba_cache.py")
    return pkg


def run_toy(where: Path, cache: Path) -> tuple[dict, str]:
    env = dict(os.environ, CHAINMODEL_CACHE_DIR=str(cache), PYTHONPATH=str(where))
    env.pop("CHAINMODEL_NUMBA", None)
    proc = subprocess.run([sys.executable, "-c", RUN], capture_output=True, text=True, env=env,
                          cwd=where)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout), proc.stderr


def test_compile_once_load_later_recompile_on_any_source_change(tmp_path):
    write_toy(tmp_path / "a")
    cache = tmp_path / "cache"
    first, err = run_toy(tmp_path / "a", cache)
    assert first["value"] == 3.0 * 2.0 + 1.0
    assert (first["hits"], first["misses"]) == (0, 1)
    assert err.count(NOTICE) == 1, err             # one line, however many kernels compile
    assert Path(first["path"]).is_relative_to(cache)

    second, err = run_toy(tmp_path / "a", cache)   # a later process loads, silently
    assert (second["value"], second["hits"], second["misses"]) == (7.0, 1, 0)
    assert NOTICE not in err

    # what an FMU extracted to a fresh folder does: same module names and sources, new path
    shutil.copytree(tmp_path / "a", tmp_path / "elsewhere" / "b")
    copy, err = run_toy(tmp_path / "elsewhere" / "b", cache)
    assert (copy["value"], copy["hits"], copy["misses"]) == (7.0, 1, 0)
    assert NOTICE not in err

    # a constant two modules away (kern -> helper -> consts; numba's own index checks kern.py
    # only): recompiled, never loaded stale
    write_toy(tmp_path / "a", scale=4.0)
    changed, err = run_toy(tmp_path / "a", cache)
    assert (changed["value"], changed["hits"], changed["misses"]) == (3.0 * 4.0 + 1.0, 0, 1)
    assert NOTICE in err

    # the kernel's own source
    write_toy(tmp_path / "a", scale=4.0, offset=5.0)
    changed, _ = run_toy(tmp_path / "a", cache)
    assert (changed["value"], changed["hits"], changed["misses"]) == (3.0 * 4.0 + 5.0, 0, 1)
    again, _ = run_toy(tmp_path / "a", cache)      # and the new binary is the one cached
    assert (again["value"], again["hits"], again["misses"]) == (17.0, 1, 0)


def test_an_unusable_cache_folder_is_said_and_the_kernels_still_run(tmp_path):
    """CHAINMODEL_CACHE_DIR naming a file (a leftover, a typo): the kernels compile and give
    the toy's arithmetic, and the one line on stderr says the folder cannot be used and every
    process compiles, naming the variable; before, it said "later runs load them from" a folder
    that could not exist, and every process compiled in silence after that."""
    write_toy(tmp_path / "a")
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the cache folder should be\n")
    for _ in range(2):      # and so in every process
        got, err = run_toy(tmp_path / "a", blocker)
        assert got["value"] == 3.0 * 2.0 + 1.0 and got["misses"] == 1
        assert err.count(NOTICE) == 1, err
        assert "cannot be used" in err and "every process compiles" in err
        assert "CHAINMODEL_CACHE_DIR" in err and "later runs load them" not in err


def test_two_processes_compiling_at_once_are_safe(tmp_path):
    write_toy(tmp_path / "a")
    cache = tmp_path / "cache"
    env = dict(os.environ, CHAINMODEL_CACHE_DIR=str(cache), PYTHONPATH=str(tmp_path / "a"))
    procs = [subprocess.Popen([sys.executable, "-c", RUN], stdout=subprocess.PIPE,
                              stderr=subprocess.PIPE, text=True, env=env) for _ in range(3)]
    results = []
    for p in procs:
        out, err = p.communicate(timeout=300)
        assert p.returncode == 0, err
        results.append(json.loads(out))
    assert all(r["value"] == 7.0 for r in results)
    later, err = run_toy(tmp_path / "a", cache)
    assert (later["value"], later["hits"], later["misses"]) == (7.0, 1, 0)
    assert NOTICE not in err
    # every index entry names a complete binary; replaced ones were pruned or are recent
    index = list((cache / "numba" / "toy.kern").glob("kernel-*.nbi"))
    assert len(index) == 1


LEVELS = """
from chainmodel._numba import jit_noalloc
from chainmodel.kernels.stepping import instance


@jit_noalloc
def double(x):
    return 2.0 * x


@jit_noalloc
def square(x):
    return x * x


def source(x):
    return _kernel(x) + 1.0


one = instance(source, "one", __name__, _kernel=double)
two = instance(source, "two", __name__, _kernel=square)
"""

RUN_LEVELS = """
import json
from toy.levels import one, two
print(json.dumps({"values": [one(3.0), two(3.0)],
                  "hits": [sum(k.stats.cache_hits.values()) for k in (one, two)],
                  "misses": [sum(k.stats.cache_misses.values()) for k in (one, two)]}))
"""


def test_instances_of_one_loop_source_are_cached_apart(tmp_path):
    """chainmodel.kernels.stepping.instance builds each level's loop from one source with the
    level's kernels bound (same bytecode, other globals): each instance has its own cache
    entry, a later process loads both without compiling, and neither loads the other's."""
    pkg = write_toy(tmp_path / "a")
    (pkg / "levels.py").write_text(LEVELS)
    cache = tmp_path / "cache"
    env = dict(os.environ, CHAINMODEL_CACHE_DIR=str(cache),
               PYTHONPATH=os.pathsep.join([str(tmp_path / "a"), str(ROOT)]))
    env.pop("CHAINMODEL_NUMBA", None)
    runs = []
    for _ in range(2):
        proc = subprocess.run([sys.executable, "-c", RUN_LEVELS], capture_output=True,
                              text=True, env=env, cwd=tmp_path / "a")
        assert proc.returncode == 0, proc.stderr
        runs.append((json.loads(proc.stdout), proc.stderr))
    (first, err1), (second, err2) = runs
    assert first["values"] == second["values"] == [2.0 * 3.0 + 1.0, 3.0 * 3.0 + 1.0]
    assert (first["hits"], first["misses"]) == ([0, 0], [1, 1]) and NOTICE in err1
    assert (second["hits"], second["misses"]) == ([1, 1], [0, 0]) and NOTICE not in err2
    names = sorted(p.name.split("-")[0] for p in (cache / "numba" / "toy.levels").glob("*.nbi"))
    assert {"one", "two"} <= set(names)


def test_numba_global_configuration_is_untouched(tmp_path):
    """The FMU lives in someone else's Python: their numba caching must behave as before."""
    script = textwrap.dedent("""
        import json
        from numba.core import caching, config
        before = ([c.__name__ for c in caching.CacheImpl._locator_classes], config.CACHE_DIR)
        import chainmodel
        from chainmodel.kernels import spans
        from chainmodel.numba_cache import cached_njit
        f = cached_njit(lambda x: x + 1)
        f(1)
        after = ([c.__name__ for c in caching.CacheImpl._locator_classes], config.CACHE_DIR)
        print(json.dumps([before, after]))
    """)
    env = dict(os.environ, CHAINMODEL_CACHE_DIR=str(tmp_path))
    proc = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                          env=env, cwd=ROOT)
    assert proc.returncode == 0, proc.stderr
    before, after = json.loads(proc.stdout)
    assert before == after


def test_every_kernel_goes_through_the_cache():
    """A kernel compiled with numba.njit(cache=True) or bare numba.njit would compile in
    every FMU process again: all of them must use chainmodel._numba.njit."""
    offenders = []
    for path in sorted((ROOT / "chainmodel").rglob("*.py")):
        if path.name == "numba_cache.py":
            continue
        for node in ast.walk(ast.parse(path.read_text(), str(path))):
            if isinstance(node, ast.Attribute) and node.attr in ("njit", "jit", "generated_jit"):
                base = node.value
                name = getattr(base, "id", getattr(base, "attr", ""))
                if name in ("numba", "_numba", "nb"):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
            elif isinstance(node, ast.ImportFrom) and node.module == "numba":
                if any(a.name in ("njit", "jit") for a in node.names):
                    offenders.append(f"{path.relative_to(ROOT)}:{node.lineno}")
    assert not offenders, "compile with chainmodel._numba.njit instead: " + ", ".join(offenders)


def test_cache_command_info_and_clear(tmp_path, monkeypatch, capsys):
    from chainmodel.cache import main
    write_toy(tmp_path / "a")
    run_toy(tmp_path / "a", tmp_path / "c")
    monkeypatch.setenv("CHAINMODEL_CACHE_DIR", str(tmp_path / "c"))

    def cli(*args):
        assert main(list(args)) == 0
        return capsys.readouterr().out

    data = json.loads(cli("--json"))
    assert data["path"] == str(tmp_path / "c" / "numba")
    assert "toy.kern" in data["modules"] and data["files"] >= 2
    assert "toy.kern" in cli()
    cleared = json.loads(cli("--clear", "--json"))
    assert cleared["removed_files"] == data["files"] and cleared["files"] == 0
    assert not (tmp_path / "c" / "numba").exists()
