"""The one switch for the optional numba acceleration of levels 1-3.

numba is an optional extra (``pip install chaindrive[fast]``; the test extra includes it). Every
compiled kernel has a plain numpy/Python twin that computes the same thing (tests compare them).
The environment variable ``CHAINMODEL_NUMBA=0`` (or false/no/off) selects the plain paths even
where numba is installed - as inside the FMU's own environment, which has no numba.
"""

from __future__ import annotations

import os

__all__ = ["numba_requested", "import_numba"]


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
