"""Unit conversions used across chainmodel, defined once (the modules that used to define their
own keep the names importable)."""

from __future__ import annotations

import math

__all__ = ["RPM"]

#: rad/s per rpm
RPM = 2.0 * math.pi / 60.0
