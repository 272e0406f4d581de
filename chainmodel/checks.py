"""Validation of input values, one sentence per refusal naming the value and what is valid
(used by the geometry and the kinematics; :mod:`chainmodel.geometry` re-exports every name)."""

from __future__ import annotations

import math
import numbers

__all__ = ["check_positive", "check_teeth", "check_whole", "check_fraction",
           "split_tangent_length"]


def _is_real(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def check_positive(name: str, value, *, allow_zero: bool = False) -> float:
    """Return ``value`` as float, or raise ValueError naming ``name`` if it is not a finite
    positive number (non-negative with ``allow_zero``)."""
    if not _is_real(value) or not math.isfinite(value):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    if value < 0 or (value == 0 and not allow_zero):
        bound = "non-negative" if allow_zero else "positive"
        raise ValueError(f"{name} must be {bound}, got {value!r}")
    return float(value)


def check_teeth(name: str, value) -> int:
    """A sprocket needs a whole number of teeth, at least 3 (a polygon)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        if _is_real(value) and float(value).is_integer():
            value = int(value)
        else:
            raise ValueError(f"{name} must be a whole number of teeth (at least 3), got {value!r}")
    if value < 3:
        raise ValueError(f"{name} needs at least 3 teeth, got {value}")
    return int(value)


def check_whole(name: str, value, minimum: int) -> int:
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        if _is_real(value) and float(value).is_integer():
            value = int(value)
        else:
            raise ValueError(f"{name} must be a whole number >= {minimum}, got {value!r}")
    if value < minimum:
        raise ValueError(f"{name} must be a whole number >= {minimum}, got {value}")
    return int(value)


def check_fraction(name: str, value) -> float:
    if not _is_real(value) or not math.isfinite(value) or not (0.0 <= value < 1.0):
        raise ValueError(f"{name} must lie in [0, 1), got {value!r}")
    return float(value)


def split_tangent_length(x_c: float, pitch: float) -> tuple[int, float]:
    """N and f such that x_c = (N + 1 + f) p (seed 000 eq 5), robust to round-off at whole pitches."""
    q = x_c / pitch - 1.0
    span = math.floor(q + 1e-12)
    frac = q - span
    if frac < 0.0:
        frac = 0.0
    if frac >= 1.0:
        span, frac = span + 1, 0.0
    return int(span), float(frac)
