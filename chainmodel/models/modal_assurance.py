"""The mass-weighted modal assurance criterion (Allemang & Brown 1982), written once for the two
places that pick the driven sprocket's mode among a linearisation's modes: level 3's
(:func:`~chainmodel.models.multibody_statics.linear_driven_modes`) and levels 1-2's
(:func:`~chainmodel.models.torsional_mode.driven_mode`)."""

from __future__ import annotations

import numpy as np

__all__ = ["closest_mode"]


def closest_mode(lam: np.ndarray, shapes: np.ndarray, mass: np.ndarray,
                 ref: np.ndarray) -> int:
    """Index of the mode (eigenvalue ``lam[i]`` > 0, shape ``shapes[:, i]``) with the largest
    mass-weighted MAC (phi^T M r)^2 / ((phi^T M phi)(r^T M r)) against ``ref``; ``mass`` a
    matrix or its diagonal. Raises ValueError where no mode has a positive eigenvalue."""
    m = np.diag(mass) if mass.ndim == 1 else mass
    norm = np.einsum("ij,ik,kj->j", shapes, m, shapes)
    mac = np.where(lam > 0.0, (shapes.T @ (m @ ref)) ** 2 / (norm * (ref @ m @ ref)), -1.0)
    i = int(np.argmax(mac))
    if mac[i] <= 0.0:
        raise ValueError("no linear mode with a positive stiffness")
    return i
