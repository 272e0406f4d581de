"""Levels 0-2's span ends from level 3's statics (issue 21 items 3-4; docs/reduced_models.md,
"One wrap and one static tension from level 3's statics").

Levels 1-2 hold each span between its sprockets with the law T = (l - n p_free - f) / (n / k + c)
(spans.py ``_tension``): n links of stiffness k in series with an end compliance c, and a free
length f the ends give away. Here (c, f) are fitted to the static equilibrium of level 3's own
chain (:mod:`chainmodel.models.multibody_statics`: the same rollers, links, seats with their
clearance and flanks, gravity), condensed onto the driven sprocket's rotation (a Guyan
reduction of the chain's statics onto the sprocket coordinates, driver held at angle 0):

* the driven sprocket's torsional stiffness K_3 = 2 dM / |phi2(+dM) - phi2(-dM)|, the secant
  over a load step dM = ``LOAD_STEP`` T_0 R_o either way (tension steps of about a tenth of the
  static tension per span), and level 1's R_o^2 sum_spans 1 / (n_s / k + c) = K_3 gives c
  (n_s the tooth-period-mean link counts level 1 uses);
* the static span tension T_0 (mean of the two spans' middle links at rest, no load) and
  level 0-2's static law T_0 = (X - 2 f) / (D + 2 c) (static_tension._static_numerator's X, D
  without seats) give f.

So levels 0-2 have level 3's static tension by construction, sag, clearance and the flanks'
tension decay around the wrap included, and level 1's driven-sprocket mode the condensed
stiffness of level 3's chain. Computed once per (drive, parameters) (three static solves).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, Mapping

from ..geometry import Drive
from .multibody_statics import solve_statics, static_state

__all__ = ["WrapFit", "wrap_fit", "LOAD_STEP"]

#: the secant's load step dM / (T_0 R_o)
LOAD_STEP = 0.2

_CACHE: dict = {}


@dataclass(frozen=True)
class WrapFit:
    """Level 3's statics condensed for levels 0-2 (module docstring).

    compliance, free_length: per span end pair (c [m/N], f [m]) for spans.py's law;
    static_tension: T_0 [N]; stiffness: K_3 [N m/rad] (driven sprocket, driver held);
    upper, lower: the two span tensions at rest [N]; solves_wall: seconds spent."""
    compliance: float
    free_length: float
    static_tension: float
    stiffness: float
    upper: float
    lower: float
    solves_wall: float


def _key(drive: Drive, params: Mapping[str, Any]):
    return (drive, tuple(sorted((k, v) for k, v in params.items()
                                if not k.startswith(("solver.", "output", "torsional.",
                                                     "modal.")))))


def wrap_fit(drive: Drive, params: Mapping[str, Any]) -> WrapFit:
    """(c, f, T_0, K_3, ...) of this drive and parameters (module docstring); cached."""
    key = _key(drive, params)
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    from .multibody import MultibodyModel
    from .static_tension import _rest_geometry
    from ..kinematics.wrapping import tooth_period_geometry
    import numpy as np
    from .. import parameters as PRM
    p3 = {k: v for k, v in params.items() if k in PRM.BY_NAME}
    model = MultibodyModel(drive, p3)
    rest = static_state(model)
    t0 = rest.mean_tension
    ro = drive.driven.pitch_radius
    w = abs(p3["gravity"]) * p3["chain.link_mass"]
    for share in (LOAD_STEP, 0.25 * LOAD_STEP, 0.05 * LOAD_STEP):
        # a smaller step where a roller at a tooth tip (where its contact ends) stalls Newton
        dm = share * max(t0, w) * ro
        try:
            plus = _loaded(model, rest, dm)
            minus = _loaded(model, rest, -dm)
            break
        except ValueError:
            if share == 0.05 * LOAD_STEP:
                raise
    k3 = 2.0 * dm / abs(minus.driven_angle - plus.driven_angle)
    k = p3["chain.link_stiffness"]
    g = tooth_period_geometry(drive, 100)
    n_up, n_low = float(np.mean(g.upper_links)), float(np.mean(g.lower_links))
    target = k3 / (ro * ro)

    def span_stiffness(c):
        return 1.0 / (n_up / k + c) + 1.0 / (n_low / k + c)

    # span_stiffness falls with c; bracket from just above -min(n)/k
    lo = -0.999 * min(n_up, n_low) / k
    hi = max(n_up, n_low) / k
    while span_stiffness(hi) > target:
        hi *= 4.0
    from scipy.optimize import brentq
    c = float(brentq(lambda cc: span_stiffness(cc) - target, lo, hi, xtol=1e-18, rtol=1e-13))
    excess, links = _rest_geometry(drive)
    x = excess + links * p3["chain.pretension"] / k
    f = 0.5 * (x - t0 * (links / k + 2.0 * c))
    fit = WrapFit(c, f, t0, k3, rest.tension_upper, rest.tension_lower,
                  rest.wall + plus.wall + minus.wall)
    if len(_CACHE) > 256:
        _CACHE.clear()
    _CACHE[key] = fit
    return fit


def _loaded(model, rest, load):
    """The equilibrium under ``load``, Newton started from the unloaded one ``rest`` (a sagging
    span's load step is small next to its distance from the straight layout)."""
    try:
        return solve_statics(model, 0.0, load, start=rest.state)
    except ValueError:
        return static_state(model, 0.0, load)
