"""Compile once per machine: the on-disk cache of chainmodel's numba kernels.

numba's own ``cache=True`` keys a kernel by the folder its source file sits in and checks only
the content of that one file. Both fail us: the FMU extracts its copy of the package to a new
folder in every process (so the cache never hit: every process recompiled, 10-40 s), and a
kernel calling a jitted function or reading a constant of another module would load a stale
binary after that other module changed. :func:`cached_njit` attaches a cache of its own to each
dispatcher instead (nothing in numba's global configuration changes, so numba code of other
packages in the same process - the FMU lives in someone else's Python - is untouched):

Where
    ``$CHAINMODEL_CACHE_DIR/numba`` if that variable is set, else the per-user cache folder
    (Linux ``$XDG_CACHE_HOME`` or ``~/.cache``, macOS ``~/Library/Caches``, Windows
    ``%LOCALAPPDATA%``) ``/chaindrive/numba``; one subfolder per module, named by the module's
    full name (``chainmodel.kernels.spans``, or ``_chaindrive_<build id>.kernels.spans`` inside
    a build of the FMU), so the library and every FMU build have their own entries but every
    extraction of one FMU build shares them.
Key
    numba's index key (the function's bytecode, its argument types, the CPU and its features)
    plus a source stamp that replaces numba's: a SHA-256 over the source of the defining
    module and of every module of the package it imports, transitively (any import statement,
    at any depth, in any of them), and the versions of Python, numba, llvmlite and numpy. A
    change to a kernel, to a kernel it calls or to a constant it reads makes the stamp differ,
    and a differing stamp discards the whole index: the kernel is recompiled, never loaded stale.
Concurrency
    Each compiled binary is written to a file of its own (unique name, written to a temporary
    file and renamed) *before* the index points to it; index updates are serialised by a lock
    file. A process reading at any moment sees either no entry (and compiles) or a complete
    binary. Two processes compiling at once both compile and both write; the last index
    update wins and both binaries are valid.
Clearing
    ``chainmodel cache --clear`` (or ``python -m chainmodel.cache --clear``) removes the
    folder; ``chainmodel cache`` prints where it is and what it holds.

The first compile in a process prints one line on stderr; a process that loads everything
from the cache prints nothing.
"""

from __future__ import annotations

import ast
import contextlib
import hashlib
import os
import shutil
import sys
import time
import uuid
from pathlib import Path

__all__ = ["ENV_VAR", "cache_root", "cached_njit", "source_stamp", "info", "clear",
           "COMPILE_NOTICE", "UNCACHED_NOTICE"]

ENV_VAR = "CHAINMODEL_CACHE_DIR"

#: printed once per process, on stderr, before the first kernel is compiled
COMPILE_NOTICE = ("chainmodel: compiling the numba kernels for this machine, once (about "
                  "{seconds}); later runs load them from {where}")
#: printed instead when the cache folder cannot be written (its reason): every process compiles
UNCACHED_NOTICE = ("chainmodel: compiling the numba kernels (about {seconds}) in this process: "
                   "the kernel cache folder {where} cannot be used ({why}), so every process "
                   "compiles them; set {env} to a writable folder (docs/numba_cache.md)")
#: why the cache folder could not be used, when it could not (None: it can)
_cache_problem: str | None = None
#: measured first-use compile times (docs/numba_cache.md): levels 1-2 about 15 s, level 3 about
#: 25 s, all levels about 60 s on a 2-core machine
_COMPILE_ESTIMATE = "10-60 s, depending on the fidelity level"


def cache_root() -> Path:
    """The folder holding the compiled kernels (see the module docstring)."""
    base = os.environ.get(ENV_VAR, "").strip()
    if base:
        return Path(base).expanduser() / "numba"
    if sys.platform == "win32":
        user = Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local")
        return user / "chaindrive" / "Cache" / "numba"
    if sys.platform == "darwin":
        return Path.home() / "Library" / "Caches" / "chaindrive" / "numba"
    user = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return user / "chaindrive" / "numba"


# --- source stamp ------------------------------------------------------------------------------

def _module_file(root: Path, parts: list[str]) -> Path | None:
    """File of module ``parts`` (relative to the package root), or None if not in the package."""
    path = root.joinpath(*parts)
    if (path / "__init__.py").is_file():
        return path / "__init__.py"
    file = path.with_suffix(".py")
    return file if parts and file.is_file() else None


_IMPORTS: dict[tuple, frozenset[Path]] = {}


def _imports(root: Path, top: str, file: Path) -> frozenset[Path]:
    """Files of the package that ``file`` imports anywhere (relative imports and absolute ones
    naming the package ``top``); a submodule named in ``from X import name`` counts too.
    Memoised per file version (path, mtime, size): every kernel module walks the same files,
    and parsing them once per kernel cost ~0.9 s per process (an FMU instantiation pays it)."""
    st = file.stat()
    key = (root, top, file, st.st_mtime_ns, st.st_size)
    found = _IMPORTS.get(key)
    if found is None:
        found = _IMPORTS[key] = frozenset(_parse_imports(root, top, file))
    return found


def _parse_imports(root: Path, top: str, file: Path) -> set[Path]:
    """:func:`_imports` without the memo."""
    # the package a relative import starts from: the containing package of a module, the
    # package itself for an __init__.py - both are the parts before the last one
    here = list(file.relative_to(root).with_suffix("").parts[:-1])
    found: set[Path] = set()
    for node in ast.walk(ast.parse(file.read_bytes(), str(file))):
        if isinstance(node, ast.ImportFrom):
            if node.level:
                if node.level - 1 > len(here):
                    continue
                base = here[:len(here) - (node.level - 1)]
            elif node.module and node.module.split(".")[0] == top:
                base = []
            else:
                continue
            mod = base + (node.module.split(".") if node.module else [])
            if node.level == 0:
                mod = mod[1:]   # drop the package's own name
            target = _module_file(root, mod) if mod else root / "__init__.py"
            if target is not None:
                found.add(target)
            for alias in node.names:
                sub = _module_file(root, mod + [alias.name])
                if sub is not None:
                    found.add(sub)
        elif isinstance(node, ast.Import):
            for alias in node.names:
                parts = alias.name.split(".")
                if parts[0] == top:
                    for k in range(1, len(parts) + 1):
                        target = _module_file(root, parts[1:k]) if k > 1 else root / "__init__.py"
                        if target is not None:
                            found.add(target)
    return found


_STAMPS: dict[str, str] = {}


def _versions() -> str:
    import llvmlite
    import numba
    import numpy
    return (f"python {sys.version_info[:3]} {sys.implementation.name}; numba {numba.__version__}; "
            f"llvmlite {llvmlite.__version__}; numpy {numpy.__version__}")


def source_stamp(module_name: str) -> str:
    """SHA-256 of the sources a kernel of ``module_name`` can depend on (module docstring).

    ``module_name`` must be imported (its package's location comes from ``sys.modules``)."""
    if module_name in _STAMPS:
        return _STAMPS[module_name]
    top = module_name.split(".")[0]
    package_file = getattr(sys.modules.get(top), "__file__", None)
    module_file = getattr(sys.modules.get(module_name), "__file__", None)
    if not (package_file and module_file):
        raise ValueError(f"module {module_name!r} has no source file: nothing to key a cache by")
    root = Path(package_file).resolve().parent
    start = Path(module_file).resolve()
    todo, seen = [start], {start}
    while todo:
        for dep in _imports(root, top, todo.pop()):
            if dep not in seen:
                seen.add(dep)
                todo.append(dep)
    h = hashlib.sha256(_versions().encode())
    for path in sorted(seen):
        h.update(b"\0" + path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes())
    _STAMPS[module_name] = stamp = h.hexdigest()
    return stamp


# --- the cache numba uses ----------------------------------------------------------------------

_announced = False
#: seconds after which an unreferenced binary is surely not a concurrent writer's fresh one
_PRUNE_AGE = 600.0


def _announce() -> None:
    global _announced
    if not _announced:
        _announced = True
        text = (COMPILE_NOTICE.format(seconds=_COMPILE_ESTIMATE, where=cache_root())
                if _cache_problem is None else
                UNCACHED_NOTICE.format(seconds=_COMPILE_ESTIMATE, where=cache_root(),
                                       why=_cache_problem, env=ENV_VAR))
        print(text, file=sys.stderr, flush=True)


@contextlib.contextmanager
def _locked(path: str):
    """Exclusive lock on ``path`` (created if needed); no lock where the platform has none."""
    with open(path, "a+b") as handle:
        try:
            if os.name == "nt":
                import msvcrt
                handle.seek(0)
                msvcrt.locking(handle.fileno(), msvcrt.LK_LOCK, 1)
            else:
                import fcntl
                fcntl.flock(handle.fileno(), fcntl.LOCK_EX)
        except (ImportError, OSError):   # pragma: no cover - exotic file systems
            pass
        yield


def _make_cache_class():
    """KernelCache and its parts, defined when numba is imported (this module is not)."""
    from numba.core import caching

    class _Locator(caching._CacheLocator):
        def __init__(self, py_func, module_name: str):
            self._py_file = py_func.__code__.co_filename
            self._lineno = py_func.__code__.co_firstlineno
            self._path = str(cache_root() / module_name)
            self._stamp = source_stamp(module_name)

        def get_cache_path(self):
            return self._path

        def get_source_stamp(self):
            return self._stamp

        def get_disambiguator(self):
            return str(self._lineno)

    class _Impl(caching.CompileResultCacheImpl):
        def __init__(self, py_func):   # no locator search: always ours
            self._lineno = py_func.__code__.co_firstlineno
            self._locator = _Locator(py_func, py_func.__module__)
            abiflags = getattr(sys, "abiflags", "")
            self._filename_base = self.get_filename_base(f"{py_func.__qualname__}", abiflags)

    class _Files(caching.IndexDataCacheFile):
        def save(self, key, data):
            # a fresh data file per save, written before the index points to it
            name = self._data_name_pattern.replace("{number:d}", uuid.uuid4().hex[:16])
            self._save_data(name, data)
            with _locked(self._index_path + ".lock"):
                overloads = self._load_index()
                overloads[key] = name
                self._save_index(overloads)
                self._prune(set(overloads.values()))

        def _prune(self, keep):
            """Remove this function's binaries no index entry names (replaced, or left by an
            older source stamp); recent ones may belong to a writer about to update the index."""
            prefix = self._index_name[:-len(".nbi")] + "."
            now = time.time()
            with contextlib.suppress(OSError):
                for entry in os.scandir(self._cache_path):
                    if (entry.name.startswith(prefix) and entry.name.endswith(".nbc")
                            and entry.name not in keep
                            and now - entry.stat().st_mtime > _PRUNE_AGE):
                        with contextlib.suppress(OSError):
                            os.unlink(entry.path)

    class KernelCache(caching.FunctionCache):
        _impl_class = _Impl

        def __init__(self, py_func):
            super().__init__(py_func)
            self._cache_file = _Files(cache_path=self._cache_path,
                                      filename_base=self._impl.filename_base,
                                      source_stamp=self._impl.locator.get_source_stamp())

        def load_overload(self, sig, target_context):
            data = super().load_overload(sig, target_context)
            if data is None:
                _announce()
            return data

    class UncachedKernel(caching.NullCache):
        """Used when the cache folder cannot be written: compiles in every process."""

        def load_overload(self, sig, target_context):
            _announce()

    return KernelCache, UncachedKernel


_CLASSES = None


def cached_njit(fn=None, **options):
    """``numba.njit(**options)(fn)`` with the per-machine cache of this module (also usable as
    ``@cached_njit`` or ``@cached_njit(fastmath=False)``). ``cache=`` is not accepted: use this
    instead of numba's own cache."""
    if fn is None:
        return lambda f: cached_njit(f, **options)
    if "cache" in options:
        raise ValueError("cached_njit: do not pass cache=; the dispatcher gets chainmodel's "
                         "per-machine cache (chainmodel.numba_cache)")
    import numba
    global _CLASSES
    if _CLASSES is None:
        _CLASSES = _make_cache_class()
    kernel_cache, uncached = _CLASSES
    dispatcher = numba.njit(**options)(fn)
    try:
        cache = kernel_cache(fn)
        cache._impl.locator.ensure_cache_path()
    except (OSError, ValueError) as exc:   # folder not writable, or no source file
        global _cache_problem
        if isinstance(exc, OSError) and _cache_problem is None:
            _cache_problem = f"{type(exc).__name__}: {exc}"
        cache = uncached()
    dispatcher._cache = cache
    return dispatcher


# --- housekeeping ------------------------------------------------------------------------------

def info() -> dict:
    """Where the cache is and what it holds: ``{"path", "exists", "modules", "files", "bytes"}``."""
    root = cache_root()
    files = [p for p in root.rglob("*") if p.is_file()] if root.is_dir() else []
    modules = sorted(p.name for p in root.iterdir() if p.is_dir()) if root.is_dir() else []
    return {"path": str(root), "exists": root.is_dir(), "modules": modules,
            "files": len(files), "bytes": sum(p.stat().st_size for p in files),
            "env_var": ENV_VAR}


def clear() -> int:
    """Remove the cache folder; return the number of files removed. Safe while other processes
    run: they recompile what they miss."""
    root = cache_root()
    if not root.is_dir():
        return 0
    count = sum(1 for p in root.rglob("*") if p.is_file())
    shutil.rmtree(root, ignore_errors=True)
    return count


def format_info(data: dict) -> str:
    lines = [f"numba kernel cache: {data['path']}"
             + ("" if data["exists"] else " (empty: nothing compiled yet)"),
             f"  {data['files']} files, {data['bytes'] / 1e6:.1f} MB, "
             f"{len(data['modules'])} module(s)"]
    lines += [f"  {m}" for m in data["modules"]]
    lines.append(f"  set {data['env_var']} to move it; clear it with `chainmodel cache --clear`")
    return "\n".join(lines)
