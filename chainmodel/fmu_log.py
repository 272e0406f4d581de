"""The fmpy logger callbacks of chainmodel's FMU runs (no physics here): one
:class:`FMULog` per instance keeps that instance's messages.

fmpy 0.3 formats a message in a C proxy (its ``logging.c``) that passes it on to ONE logger per
process: the one last given to ``addLoggerProxy``, for every instance made with the proxy,
fmpy's default callbacks included. A logger per instance would therefore receive the messages
of other instances, and once collected leave the proxy calling freed memory (a segfault at the
next message of any instance of the process). Every :class:`FMULog` hands the proxy the same
immortal :func:`_dispatch`, which tells the instances apart by the component environment.
"""

from __future__ import annotations

import itertools
import weakref
from typing import Callable

__all__ = ["FMULog"]


class FMULog:
    """fmpy logger callbacks (``.callbacks``, for ``instantiate``) that keep one instance's
    messages as (status, text) in ``.messages`` and optionally pass them on to ``echo``."""

    LABELS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")

    def __init__(self, echo: Callable[[str], None] | None = None):
        from ctypes import byref

        from fmpy.fmi1 import calloc, free
        from fmpy.fmi2 import (fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                               fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
        self.messages: list[tuple[int, str]] = []
        self.echo = echo
        cb = fmi2CallbackFunctions()
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
        try:  # formats the printf-style message the FMU passes
            from fmpy.logging import addLoggerProxy
        except Exception:  # pragma: no cover - fmpy without the proxy library
            cb.logger = fmi2CallbackLoggerTYPE(self._log)
        else:
            global _DISPATCH
            if _DISPATCH is None:
                _DISPATCH = fmi2CallbackLoggerTYPE(_dispatch)
            key = next(_KEYS)
            _LOGS[key] = self
            cb.componentEnvironment = key
            cb.logger = _DISPATCH
            addLoggerProxy(byref(cb))   # (again) makes _dispatch the proxy's one logger
        self.callbacks = cb

    def _log(self, env, instance, status, category, message):
        text = message.decode("utf-8", "replace") if isinstance(message, bytes) else str(message)
        self.messages.append((int(status), text))
        if self.echo:
            self.echo(f"[{self.LABELS[status] if 0 <= status < 6 else status}] {text}")

    def problems(self, since: int = 0) -> str:
        msgs = [m for s, m in self.messages[since:] if s >= 1]
        return "; ".join(msgs) if msgs else "the FMU logged no reason"


_LOGS: weakref.WeakValueDictionary[int, FMULog] = weakref.WeakValueDictionary()
_KEYS = itertools.count(1)
_DISPATCH = None   # the ctypes logger fmpy's proxy calls, made once and never released


def _dispatch(env, instance, status, category, message):
    """fmpy's proxy's one logger: the message to the ``FMULog`` whose component environment it
    carries, or printed as fmpy's default callbacks print it (another instance of the process)."""
    log = _LOGS.get(env or 0)
    if log is not None:
        log._log(env, instance, status, category, message)
    else:
        from fmpy.fmi2 import printLogMessage
        printLogMessage(env, instance, status, category, message)
