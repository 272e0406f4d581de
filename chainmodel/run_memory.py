"""How much memory a run's time series take, and the refusal of a run that would not fit.

A run keeps every output at every communication point (``Result``), so its memory grows with
``duration / output_interval``: seed 003's drive for 1e4 s at the default 0.1 ms is 1e8 samples
x 15 outputs x 8 bytes = 12 GB of outputs alone. :func:`check_run_memory` refuses such a run
before anything is allocated, with the estimate and what to change.

The estimate (bytes) is::

    samples x (outputs + working arrays per sample) x 8

* ``samples = round(duration / output_interval) + 1`` (:meth:`chainmodel.scene.Scene.times`);
* ``outputs`` = the 15 outputs every level gives (``chainmodel.models.ALL_OUTPUTS``);
* working arrays per sample, measured with tracemalloc over ``simulate`` plus ``summary``
  (benchmarks/run_memory.py): :data:`WORKING_ARRAYS` - the time grid and the four sampled
  inputs the compiled loop of levels 1-3 takes, the level-0 model's intermediates (it evaluates
  every sample at once), and the summary's steady-window copies and spectrum.

The limit is :data:`MEMORY_FRACTION` of the memory the operating system reports available
(Linux ``MemAvailable`` of /proc/meminfo, elsewhere the physical memory from ``os.sysconf``),
or the number of bytes in the environment variable ``CHAINMODEL_MEMORY_LIMIT`` (suffixes K, M,
G, T: powers of 1000; ``0`` or ``none`` turns the check off).
"""

from __future__ import annotations

import math
import os

__all__ = ["ENV_VAR", "MEMORY_FRACTION", "WORKING_ARRAYS", "RunTooLarge", "run_samples",
           "output_bytes", "run_bytes", "available_memory", "memory_limit", "check_run_memory"]

ENV_VAR = "CHAINMODEL_MEMORY_LIMIT"
#: share of the available memory one run may take (the rest: the OS, other programs, and the
#: copies a caller makes of the result, e.g. ``--csv``)
MEMORY_FRACTION = 0.5
#: float64 arrays per sample besides the outputs, the peak measured per level rounded up
#: (benchmarks/run_memory.py, 50 000 and 200 000 samples, summary included: level 0 53.5,
#: levels 1-3 6.1-6.4)
WORKING_ARRAYS = {0: 55, 1: 7, 2: 7, 3: 7}

_SUFFIX = {"": 1, "K": 1e3, "M": 1e6, "G": 1e9, "T": 1e12}


class RunTooLarge(ValueError):
    """A run whose time series would not fit in memory (a ValueError: a user's setting)."""

    def __init__(self, message: str, samples: int, outputs: int, output_bytes: int,
                 total_bytes: int, limit_bytes: int):
        super().__init__(message)
        self.samples, self.outputs = samples, outputs
        self.output_bytes, self.total_bytes, self.limit_bytes = output_bytes, total_bytes, limit_bytes


def run_samples(duration: float, output_interval: float) -> int:
    """Samples of a run, as :meth:`Scene.times` makes them (without making them)."""
    return max(1, round(duration / output_interval)) + 1


def output_bytes(samples: int, outputs: int) -> int:
    """Bytes of the outputs' time series: samples x outputs x 8 (float64)."""
    return int(samples) * int(outputs) * 8


def run_bytes(samples: int, outputs: int, fidelity: int) -> int:
    """Estimated peak bytes of a run with its summary (module docstring)."""
    return int(samples) * (int(outputs) + WORKING_ARRAYS.get(int(fidelity), 55)) * 8


def available_memory() -> int | None:
    """Bytes of memory available to a new allocation, or None where it cannot be read."""
    try:
        with open("/proc/meminfo") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return int(os.sysconf("SC_PAGE_SIZE")) * int(os.sysconf("SC_PHYS_PAGES"))
    except (AttributeError, OSError, ValueError):
        return None


def _parse_limit(text: str) -> int | None:
    t = text.strip().upper().removesuffix("B")
    if t in ("0", "NONE", "OFF"):
        return None
    unit = t[-1:] if t[-1:] in _SUFFIX and not t[-1:].isdigit() else ""
    try:
        value = float(t[:len(t) - len(unit)]) * _SUFFIX[unit]
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise ValueError(f"{ENV_VAR}={text!r} is not a size: give bytes, e.g. 8G, 500M or "
                         "2000000000 (0 or none: no limit)")
    return int(value)


def memory_limit() -> tuple[int | None, str]:
    """(bytes one run may use, where that figure comes from); (None, ...) means no limit."""
    text = os.environ.get(ENV_VAR, "").strip()
    if text:
        return _parse_limit(text), f"{ENV_VAR}={text}"
    avail = available_memory()
    if avail is None:
        return None, "available memory unknown"
    return int(MEMORY_FRACTION * avail), (f"{MEMORY_FRACTION:.0%} of the {_gb(avail)} "
                                          "available")


def _gb(n: float) -> str:
    """Bytes as text in decimal units: 1.2e12 -> '1.2 TB'."""
    for unit, size in (("TB", 1e12), ("GB", 1e9), ("MB", 1e6), ("kB", 1e3)):
        if n >= size:
            return f"{n / size:.3g} {unit}"
    return f"{n:.0f} bytes"


def _sig3(x: float, up: bool) -> float:
    """``x`` to 3 significant digits, rounded up or down (a suggestion that surely fits)."""
    if x <= 0:
        return x
    scale = 10.0 ** (math.floor(math.log10(x)) - 2)
    return (math.ceil if up else math.floor)(x / scale * (1 - 1e-12 if up else 1 + 1e-12)) * scale


def check_run_memory(duration: float, output_interval: float, fidelity: int,
                     outputs: int | None = None) -> None:
    """Raise :class:`RunTooLarge` (a ValueError) if a run of ``duration`` s sampled every
    ``output_interval`` s would exceed :func:`memory_limit`, naming the estimate and what
    would fit."""
    if outputs is None:
        from .models import ALL_OUTPUTS
        outputs = len(ALL_OUTPUTS)
    samples = run_samples(duration, output_interval)
    total = run_bytes(samples, outputs, fidelity)
    limit, source = memory_limit()
    if limit is None or total <= limit:
        return
    out = output_bytes(samples, outputs)
    per_sample = total / samples
    fit = max(1, int(limit / per_sample) - 1)            # samples that would fit
    coarser = _sig3(duration / fit, up=True)
    shorter = _sig3(fit * output_interval, up=False)
    raise RunTooLarge(
        f"a run of duration {duration:g} s at output_interval {output_interval:g} s would keep "
        f"{samples if samples < 1e15 else f'{samples:.3g}'} samples x {outputs} outputs x 8 "
        f"bytes = {_gb(out)} of outputs (about "
        f"{_gb(total)} with the working arrays), more than the {_gb(limit)} allowed ({source}); "
        f"use a coarser output_interval (>= {coarser:g} s fits) or a shorter duration "
        f"(<= {shorter:g} s fits), or set {ENV_VAR} to allow more",
        samples, outputs, out, total, limit)
