"""The one switch for numba in chainmodel, and the decorator every compiled kernel uses.

numba is a core dependency. Every compiled kernel has a plain numpy/Python twin that computes
the same thing (tests compare them); ``CHAINMODEL_NUMBA=0`` (or false/no/off) in the
environment selects the plain paths even where numba is installed. That is the one switch,
read once when this module is imported (the kernels are decorated then: compiled or plain) and
reported by :func:`enabled`; no model, stepper or kernel module has a switch of its own. The
plain twin of a compiled kernel is its ``py_func`` (the same source run as Python), and the
pairs are listed once, in :data:`chainmodel.kernels.TWINS`.

Kernels are compiled with :func:`njit` (never ``numba.njit(cache=True)``): it attaches the
per-machine cache of :mod:`chainmodel.numba_cache`, which survives the FMU's fresh extraction
folders and never loads a kernel compiled from other sources (docs/numba_cache.md).
"""

from __future__ import annotations

import os

__all__ = ["numba_requested", "import_numba", "njit", "jit", "jit_noalloc", "jit_inline",
           "enabled", "quiet_when_plain"]


def numba_requested() -> bool:
    """False when CHAINMODEL_NUMBA is 0/false/no/off."""
    return os.environ.get("CHAINMODEL_NUMBA", "1").strip().lower() not in ("0", "false", "no", "off")


def import_numba():
    """The numba module, or None when it is missing or switched off."""
    if not numba_requested():
        return None
    try:
        import numba
    except Exception:  # pragma: no cover - depends on the environment
        return None
    return numba


#: the switch, read at import: numba importable and not switched off by CHAINMODEL_NUMBA
_ENABLED: bool = import_numba() is not None


def enabled() -> bool:
    """The one numba switch: True when the kernels of this process are compiled (numba
    importable and CHAINMODEL_NUMBA not 0/false/no/off when chainmodel was imported), False
    when they run as their plain Python source."""
    return _ENABLED


def njit(fn=None, **options):
    """Compile ``fn`` with numba in nopython mode, cached once per machine
    (:func:`chainmodel.numba_cache.cached_njit`). Needs numba importable; callers keep their
    plain twin for ``CHAINMODEL_NUMBA=0``."""
    from .numba_cache import cached_njit
    return cached_njit(fn, **options)


def jit(fn):
    """The kernel decorator: compiled (:func:`njit`) when :func:`enabled`, else the function
    itself; either way the plain function is at ``.py_func`` (the twin tests call)."""
    if _ENABLED:
        return njit(fn, fastmath=False)
    fn.py_func = fn
    return fn


def jit_noalloc(fn):
    """:func:`jit` for a kernel that allocates no array and returns none (it only reads and
    writes the arrays it is given, and makes views of them): compiled without numba's
    reference counting (``_nrt=False``). Its callers hold every array it touches for the
    whole call, so the counting is pure cost - on the level 1-2 stepping loop, where small
    kernels pass the same arrays and row views down many calls per evaluation, its atomic
    increments and decrements took half the time (docs/performance.md, issue 20 third pass).
    The arithmetic is the same: results are bitwise those of :func:`jit`."""
    if _ENABLED:
        return njit(fn, fastmath=False, _nrt=False)
    fn.py_func = fn
    return fn


def jit_inline(fn):
    """:func:`jit_noalloc` for a small kernel that numba inlines into each caller (its IR,
    ``inline="always"``) instead of calling it: level 3's step rules and force-law wrapper
    (chainmodel.kernels.multibody_loops), where a call passing a dozen arrays cost 5% of a
    step (docs/performance.md, issue 20 item 1). The arithmetic is the same."""
    if _ENABLED:
        return njit(fn, fastmath=False, _nrt=False, inline="always")
    fn.py_func = fn
    return fn


def quiet_when_plain(fn):
    """For a Python function that calls kernels: returned as it is when the kernels are
    compiled. Run as plain Python, the kernels' arithmetic on array elements is numpy's, which
    warns (RuntimeWarning) on the overflow and nan of a diverging state where the compiled code
    computes the same inf and nan silently and the callers' checks report the divergence
    (SimulationDiverged); the plain call is made under ``np.errstate(all="ignore")`` so both
    paths say the same."""
    if _ENABLED:
        return fn
    import functools

    import numpy as np

    @functools.wraps(fn)
    def quiet(*args, **kwargs):
        with np.errstate(all="ignore"):
            return fn(*args, **kwargs)
    return quiet
