"""Level 3's free spans read from its rollers' positions, written here independently of the
library's span bookkeeping (shared by tests/test_top_rung.py and docs/scripts/span_vibration.py).

* :func:`free_spans`: per snapshot, each run of free rollers between the last rollers seated on
  either sprocket, named upper / lower by the side of the line of centres its middle roller
  lies on;
* :func:`span_shape`: a span's excess length over its chord (the polyline of its rollers minus
  the chord) and its midspan displacement from the chord.
"""

from __future__ import annotations

import numpy as np


def free_spans(snap, centres) -> dict[str, np.ndarray]:
    """{'upper' / 'lower': the roller indices of the span, from the last seated roller on one
    sprocket to the first on the other} for one snapshot of MultibodyModel.snapshot; centres:
    the (driver, driven) sprocket centres."""
    engaged = snap["engaged_driver"] | snap["engaged_driven"]
    m = engaged.size
    start = int(np.argmax(engaged))                 # a seated roller: runs do not wrap around
    order = [(start + j) % m for j in range(m)]
    axis = centres[1] - centres[0]
    out = {}
    j = 0
    while j < m:
        if engaged[order[j]]:
            j += 1
            continue
        a = j
        while j < m and not engaged[order[j]]:
            j += 1
        idx = np.array([order[a - 1]] + order[a:j] + [order[j % m]])
        mid = snap["roller_positions"][idx[idx.size // 2]] - centres[0]
        out["upper" if axis[0] * mid[1] - axis[1] * mid[0] > 0 else "lower"] = idx
    return out


def span_shape(z: np.ndarray) -> tuple[float, float]:
    """(excess length over the chord [m], displacement from the chord at its middle [m]) of the
    polyline z (k, 2)."""
    chord = z[-1] - z[0]
    length = float(np.hypot(*chord))
    along = (z - z[0]) @ (chord / length)
    across = (z - z[0]) @ (np.array([-chord[1], chord[0]]) / length)
    excess = float(np.sum(np.hypot(*np.diff(z, axis=0).T))) - length
    return excess, float(np.interp(0.5 * length, along, across))
