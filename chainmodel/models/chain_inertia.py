"""The sprockets' two-inertia system of levels 1-2: their mass matrix with the chain's inertia
(docs/reduced_models.md, "chain inertia") and their stiffness matrix on the spans, shared by
:class:`~chainmodel.models.torsional.TorsionalModel` and the wrap's modal stiffness
(:mod:`.wrap_statics`)."""

from __future__ import annotations

from functools import lru_cache
from typing import Any, Mapping

import numpy as np

from ..geometry import Drive
from ..kinematics.wrapping import tooth_period_geometry

__all__ = ["reference_geometry", "sprocket_mass_matrix", "two_inertia_stiffness"]


def reference_geometry(drive: Drive) -> dict[str, float]:
    """Tooth-period means of the level-0 configuration: link counts, span lengths and
    directions (the constant chain-inertia matrix and the modal basis use them)."""
    g = tooth_period_geometry(drive, 100)
    return {"n_up": float(np.mean(g.upper_links)), "n_low": float(np.mean(g.lower_links)),
            "n_up_min": float(np.min(g.upper_links)),
            "n_low_min": float(np.min(g.lower_links)),
            "wrapped_driver": float(np.mean(g.wrapped_driver)),
            "wrapped_driven": float(np.mean(g.wrapped_driven)),
            "l_up": float(np.mean(g.upper.length)), "l_low": float(np.mean(g.lower.length)),
            "dir_up": float(np.mean(g.upper.direction)),
            "dir_low": float(np.mean(g.lower.direction))}


@lru_cache(maxsize=64)
def mean_span_length(drive: Drive) -> float:
    """The spans' tooth-period-mean length [m] (the two tangents' mean, equal on a
    two-sprocket drive): the length of :func:`chainmodel.models.limits.drive_string_frequency`."""
    ref = reference_geometry(drive)
    return 0.5 * (ref["l_up"] + ref["l_low"])


def sprocket_mass_matrix(drive: Drive, params: Mapping[str, Any],
                         reference: Mapping[str, float] | None = None) -> np.ndarray:
    """[[J11, J12], [J12, J22]] of the sprocket rotations [kg m^2].

    Chain inertia (option ``torsional.chain_inertia``): the m_link of each roller seated on
    a sprocket at its pitch radius; a span of n pitches has n - 1 inner rollers at k/n along
    it, moving axially with the linear interpolation of its endpoints' chain speeds R w, so
    sum (1 - k/n)^2 = (n - 1)(2n - 1) / (6n) to each end and sum k/n (1 - k/n)
    = (n^2 - 1) / (6n) coupling the two (the lumped form of a bar's m/3, m/6 matrix). Link
    counts are tooth-period means (``reference``, :func:`reference_geometry`) so the matrix is
    constant (no momentum jumps at events)."""
    p = params
    j11, j22, j12 = p["driver.inertia"], p["driven.inertia"], 0.0
    if p["torsional.chain_inertia"]:
        r = reference_geometry(drive) if reference is None else reference
        m = p["chain.link_mass"]
        rc, ro = drive.driver.pitch_radius, drive.driven.pitch_radius
        ends = sum((n - 1) * (2 * n - 1) / (6 * n) for n in (r["n_up"], r["n_low"]))
        cross = sum((n * n - 1) / (6 * n) for n in (r["n_up"], r["n_low"]))
        j11 += m * rc * rc * (r["wrapped_driver"] + 1 + ends)
        j22 += m * ro * ro * (r["wrapped_driven"] + 1 + ends)
        j12 += m * rc * ro * cross
    return np.array([[j11, j12], [j12, j22]])


def two_inertia_stiffness(drive: Drive, params: Mapping[str, Any], k: float) -> np.ndarray:
    """Stiffness matrix [N m/rad] of the sprocket rotations on spans of total stiffness ``k``
    [N/m] pulling at the pitch radii, the input shaft's spring on the driver."""
    rc, ro = drive.driver.pitch_radius, drive.driven.pitch_radius
    K = k * np.array([[rc * rc, -rc * ro], [-rc * ro, ro * ro]])
    K[0, 0] += params["input_shaft.stiffness"]
    return K
