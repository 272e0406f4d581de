"""The ChainDrive FMU's embedding: one build among others, in someone else's process.

Everything here works around the host and pythonfmu 0.7, not the FMI mapping (that is
fmu_src/ChainDrive.py) and not the physics (the chainmodel package):

* the import of this build's own copy of ``chainmodel`` under a private name
  (:func:`vendored_chainmodel`), repointed when a host extracts the FMU anew, and the
  resources folder taken off ``sys.path`` again (:func:`tidy_sys_path`);
* messages for a misconfigured embedding (:func:`embedding_error`: what a C/C++ host needs);
* pythonfmu 0.7's reference counting (:func:`balance_namespace_reference`, :func:`guard_entry_points`)
  and its exit-time double release (:func:`wrapper_hosts_us`);
* log messages hosts print unformatted (:func:`fmi_text`) and the strings pythonfmu keeps.

build_fmu.py ships it as ``resources/_vendor/embedding.py`` beside the adapter, which loads it
under its own module name + ``_embedding`` (so two builds in one process keep theirs apart).
"""

from __future__ import annotations

import ctypes
import hashlib
import importlib
import importlib.util
import json
import os
import re
import sys
from pathlib import Path

from pythonfmu.enums import Fmi2Status

# --- the embedding: one build among others, in someone else's process ------------------------

#: what a C/C++ host must provide (docs/fmu.md, "Hosts")
_HOST_RECIPE = ("the ChainDrive FMU runs in the Python its host embeds: it needs Python >= 3.11 "
                "with numpy and scipy importable (numba too, for speed); in a C/C++ host the "
                "FMU's launcher starts the Python that built it, or the one CHAINDRIVE_PYTHON "
                "names (a python executable or a libpython); an FMU built without the launcher "
                "needs LD_PRELOAD (libpython), PYTHONHOME (its prefix) and PYTHONPATH (a "
                "site-packages with numpy, scipy and numba): see the Hosts section of the FMU's "
                "documentation (docs/fmu.md)")


def embedding_error(problem: str) -> ImportError:
    """An ImportError for a misconfigured embedding, also written to stderr: pythonfmu passes
    it to the host's logger only when logging is on, and then as fmi2Fatal."""
    message = f"ChainDrive FMU: {problem}. {_HOST_RECIPE}"
    try:
        print(message, file=sys.stderr, flush=True)
    except Exception:  # pragma: no cover - no usable stderr in the host
        pass
    return ImportError(message)


if sys.version_info < (3, 11):
    raise embedding_error(f"the embedded Python is {sys.version.split()[0]} "
                           f"({sys.executable or 'no executable'})")


def balance_namespace_reference(namespace: dict) -> None:
    """Give the entry module's namespace the reference pythonfmu 0.7 releases without having
    taken it (findClass: Py_DECREF of PyModule_GetDict's borrowed result, once per
    fmi2Instantiate). Called by the entry module each time its code runs (build_fmu.SHIM);
    the first run, the import, adds one spare reference that is never needed."""
    try:
        ctypes.pythonapi.Py_IncRef(ctypes.py_object(namespace))
    except Exception:  # pragma: no cover - not CPython: no reference counts to balance
        pass


#: pythonfmu versions whose wrapper leaks the sys.path string it inserts per fmi2Instantiate
_PATH_LEAKING_WRAPPERS = ("0.6.5", "0.6.6", "0.6.7", "0.6.8", "0.6.9", "0.7.0")
_WRAPPER_LEAKS_PATH = False


_BUILD_INFO: dict = {}


def _build_info(resources: Path) -> dict:
    """``{"id", "pythonfmu"}`` written by build_fmu.py; for an adapter run from a bare folder
    (benchmarks load fmu_src/ChainDrive.py next to a symlinked package) a path hash as id."""
    key = str(resources)
    if key not in _BUILD_INFO:
        try:
            _BUILD_INFO[key] = json.loads((resources / "_vendor" / "build.json").read_text())
        except (OSError, ValueError):
            _BUILD_INFO[key] = {"id": "dev_" + hashlib.sha1(str(resources.resolve()).encode())
                                .hexdigest()[:16], "pythonfmu": None}
    return _BUILD_INFO[key]


def build_defaults(resources: Path) -> dict:
    """Parameter defaults this build replaces (``build_fmu.py --default``), else {}."""
    try:
        return json.loads((resources / "_vendor" / "defaults.json").read_text())
    except (OSError, ValueError):
        return {}


#: log messages already passed to pythonfmu, see ChainDrive.log
MESSAGES: dict = {}
MESSAGES_MAX = 4096


def _repoint(alias: str, root: Path) -> None:
    """Point the loaded package ``alias`` and its subpackages at ``root``. Hosts such as
    fmpy.simulate_fmu delete their extraction folder after a run; the next instance of the same
    build comes from a fresh folder, and modules or data files the package loads lazily must be
    found there."""
    for name, module in list(sys.modules.items()):
        if module is None or not (name == alias or name.startswith(alias + ".")):
            continue
        rel = name.split(".")[1:]
        if hasattr(module, "__path__"):
            folder = root.joinpath(*rel)
            spec = importlib.util.spec_from_file_location(
                name, folder / "__init__.py", submodule_search_locations=[str(folder)])
            module.__path__ = [str(folder)]
        else:
            spec = importlib.util.spec_from_file_location(
                name, root.joinpath(*rel[:-1], rel[-1] + ".py"))
        module.__spec__, module.__loader__, module.__file__ = spec, spec.loader, spec.origin


def vendored_chainmodel(resources: str):
    """Import ``resources/_vendor/chainmodel`` as a private package and return its modules.

    The package is registered in ``sys.modules`` as ``_chaindrive_<build id>`` (needed for its
    relative imports), never as ``chainmodel``: a host process may have its own chainmodel
    imported or first on sys.path, and a different build of the FMU loaded in the same process
    must not share code with this one. Instances of one build share it, whichever folder each
    was extracted to."""
    resources = Path(resources)
    root = resources / "_vendor" / "chainmodel"
    init = root / "__init__.py"
    if not init.is_file():
        raise embedding_error(f"this FMU's copy of the chainmodel package is missing ({root}); "
                               "the resources folder the host passed is incomplete")
    global _WRAPPER_LEAKS_PATH
    info = _build_info(resources)
    _WRAPPER_LEAKS_PATH = info.get("pythonfmu") in _PATH_LEAKING_WRAPPERS
    alias = "_chaindrive_" + info["id"]
    if alias not in sys.modules:
        spec = importlib.util.spec_from_file_location(alias, init,
                                                      submodule_search_locations=[str(root)])
        package = importlib.util.module_from_spec(spec)
        sys.modules[alias] = package
        try:
            spec.loader.exec_module(package)
        except BaseException as exc:
            for name in [n for n in sys.modules if n == alias or n.startswith(alias + ".")]:
                del sys.modules[name]
            if isinstance(exc, ImportError) and exc.name and exc.name.split(".")[0] in (
                    "numpy", "scipy"):
                raise embedding_error(f"{exc.name} cannot be imported in the embedded Python "
                                       f"{sys.version.split()[0]} (sys.prefix {sys.prefix}): "
                                       f"{exc}") from exc
            raise
    elif not Path(sys.modules[alias].__path__[0]).is_dir():
        _repoint(alias, root)
    mod = {name: importlib.import_module(f"{alias}.{name}")
           for name in ("parameters", "models", "integrate", "scene", "fidelity_auto",
                        "validity", "cosim")}
    mod["package"] = sys.modules[alias]
    return mod


def tidy_sys_path(resources: str) -> None:
    """Take this FMU's resources folder off sys.path. pythonfmu 0.7 inserts it at sys.path[0]
    at every fmi2Instantiate (so the entry module and its pythonfmu copy import) and keeps one
    reference to each inserted string forever: a host's own imports would search our folder
    first, and a long-running host collected one entry per instance. Everything of ours is
    imported by then. The string's stray reference is released where the build shipped a
    wrapper known to leak it and the count proves it is that one: after the list lets go, the
    leaked reference + this loop's name + getrefcount's argument = 3 (the first inserted string
    is also a key of sys.path_importer_cache and is left alone)."""
    path = sys.path
    for index in range(len(path) - 1, -1, -1):
        item = path[index]
        if item != resources:
            continue
        del path[index]
        if (_WRAPPER_LEAKS_PATH and type(item) is str and sys.getrefcount(item) == 3
                and not any(key is item for key in sys.path_importer_cache)):
            try:
                ctypes.pythonapi.Py_DecRef(ctypes.py_object(item))
            except Exception:  # pragma: no cover - not CPython
                pass
        del item


_WRAPPERS: dict = {}


def wrapper_hosts_us(resources: str, model_identifier: str) -> bool:
    """True when this FMU's own pythonfmu wrapper library is loaded in the process, i.e. we
    were instantiated through FMI (not by pythonfmu's builder or a test calling the class).
    On Linux it also makes the process exit safe (below); elsewhere it only checks the file.

    Exit safety (Linux).

    pythonfmu 0.7's wrapper keeps its interpreter guard in a static ``std::shared_ptr pyState``
    and releases it in an ELF destructor (``onLibraryUnload`` -> ``finalizePythonInterpreter``).
    The library is never really unloaded (its C++ unique symbols make it NODELETE, whatever
    the host's dlclose), so that destructor runs at process exit, from ``_dl_fini`` - after the
    C++ static destructor of ``pyState`` itself ran from ``exit()``'s handler list and freed the
    guard. The destructor then releases the freed 128-byte block a second time; depending on
    the heap's state that is harmless or aborts the process ("corrupted double-linked list",
    PythonFMU issue #229 shows the same read in valgrind). Registering the library's own
    ``finalizePythonInterpreter`` with ``__cxa_atexit`` now - after the library's static
    constructors registered ``pyState``'s destructor - runs it first: it releases the guard
    once and leaves ``pyState`` empty, so both later destructors find nothing to release. The
    library is pinned (RTLD_NODELETE) so the registered address stays valid."""
    binaries = Path(resources).parent / "binaries"
    if not sys.platform.startswith("linux"):
        # Windows: DllMain finalizes before the DLL's static destructors run: nothing to do
        return any(binaries.glob(f"*/{model_identifier}.*"))
    lib = binaries / "linux64" / f"{model_identifier}.so"
    try:
        key = (lib.stat().st_dev, lib.stat().st_ino)
    except OSError:
        return False
    if key not in _WRAPPERS:
        try:   # a handle only if the host loaded this very file; pinned from now on
            wrapper = ctypes.CDLL(str(lib), mode=os.RTLD_NOW | os.RTLD_NOLOAD | os.RTLD_NODELETE)
        except OSError:
            return False   # not loaded: pythonfmu's builder, or a test using the class
        try:
            finalize = wrapper.finalizePythonInterpreter
            libc = ctypes.CDLL(None)
            libc.__cxa_atexit.argtypes = (ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p)
            libc.__cxa_atexit(ctypes.cast(finalize, ctypes.c_void_p), None, None)
        except AttributeError:   # the launcher (fmu_src/launcher) does it itself, or another
            pass                 # wrapper than pythonfmu 0.7's
        _WRAPPERS[key] = wrapper
    return True


def fmi_text(message: str) -> str:
    """FMI log messages are printf format strings, but not every host formats them (libcosim,
    some loggers print them as they are, so an escaped '%%' showed as "5 %%"): no '%' at all,
    the word instead."""
    return re.sub(r"\s*%", " percent", str(message))


def why(exc: BaseException) -> str:
    """The library's ValueError / SimulationDiverged messages are sentences for users; anything
    else is a defect and keeps its type name."""
    if isinstance(exc, ValueError) or any(c.__name__ == "SimulationDiverged" for c in type(exc).__mro__):
        return str(exc)
    return f"{type(exc).__name__}: {exc}"



# --- every call from pythonfmu's wrapper ------------------------------------------------------

#: the methods pythonfmu 0.7's wrapper calls on an instance (PySlaveInstance.cpp)
_ENTRY_POINTS = ("setup_experiment", "enter_initialization_mode", "exit_initialization_mode",
                 "do_step", "terminate", "set_real", "set_integer", "set_boolean", "set_string",
                 "get_real", "get_integer", "get_boolean", "get_string", "_get_fmu_state",
                 "_set_fmu_state")


def _guard(method):
    """Wrap an entry point so that an exception leaving it is survivable.

    pythonfmu 0.7 turns any exception into fmi2Fatal and, handling it, releases its references
    to the instance, the class and the log queue - and releases them again in
    fmi2FreeInstance. Without one extra reference each, the instance is freed while the wrapper
    still uses it and the host crashes later (at free, or at exit). An exception the adapter did
    not log itself is logged here first, as an error naming its type."""
    import functools

    @functools.wraps(method)
    def entry(self, *args):
        try:
            return method(self, *args)
        except BaseException as exc:
            if not getattr(exc, "chaindrive_logged", False):
                self.log(fmi_text(f"{method.__name__} failed: {type(exc).__name__}: {exc}"),
                         Fmi2Status.error)
            try:
                for obj in (self, type(self), self.log_queue):
                    ctypes.pythonapi.Py_IncRef(ctypes.py_object(obj))
            except Exception:  # pragma: no cover - not CPython
                pass
            # pythonfmu logs the exception's repr as the FMI logger's format string (its
            # handle_py_exception, passed on by fmi2.cpp's logger with no arguments): a '%' in
            # a sentence ("5 % or more") is a printf conversion reading an argument that is not
            # there
            try:
                exc.args = tuple(fmi_text(a) if isinstance(a, str) else a for a in exc.args)
            except Exception:  # an exception whose args cannot be set keeps them
                pass
            raise
    return entry


def _never_raise_bytes(method, fallback):
    """The (de)serialisation hooks are called on the class, with no instance whose references
    could be balanced: they return a value the next call refuses instead of raising."""
    import functools

    @functools.wraps(method)
    def hook(arg):
        try:
            return method(arg)
        except Exception as exc:
            return fallback(exc)
    return staticmethod(hook)


def guard_entry_points(cls):
    for name in _ENTRY_POINTS:
        setattr(cls, name, _guard(getattr(cls, name)))
    cls._fmu_state_to_bytes = _never_raise_bytes(
        cls._fmu_state_to_bytes,
        lambda exc: json.dumps({"format": "invalid", "reason": repr(exc)}).encode())
    cls._fmu_state_from_bytes = _never_raise_bytes(
        cls._fmu_state_from_bytes,
        lambda exc: {"format": "invalid", "reason": f"not a serialized ChainDrive state: {exc}"})
    return cls
