"""The mass-weighted modal assurance criterion (Allemang & Brown 1982), written once for the two
places that pick the driven sprocket's mode among a linearisation's modes: level 3's
(:func:`~chainmodel.models.multibody_statics.mode_measures`) and levels 1-2's
(:func:`~chainmodel.models.torsional_mode.driven_mode`)."""

from __future__ import annotations

import numpy as np

__all__ = ["mac", "closest_mode"]


def mac(lam: np.ndarray, shapes: np.ndarray, mass: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Per mode (eigenvalue ``lam[i]``, shape ``shapes[:, i]``) the mass-weighted MAC
    (phi^T M r)^2 / ((phi^T M phi)(r^T M r)) against ``ref``, -1 where ``lam`` <= 0; ``mass`` a
    matrix or its diagonal."""
    if mass.ndim == 1:
        norm, m_ref = np.einsum("i,ij,ij->j", mass, shapes, shapes), mass * ref
    else:
        norm, m_ref = np.einsum("ij,ik,kj->j", shapes, mass, shapes), mass @ ref
    return np.where(lam > 0.0, (shapes.T @ m_ref) ** 2 / (norm * (ref @ m_ref)), -1.0)


def closest_mode(lam: np.ndarray, shapes: np.ndarray, mass: np.ndarray,
                 ref: np.ndarray) -> int:
    """Index of the mode with the largest :func:`mac` against ``ref``. Raises ValueError where
    no mode has a positive eigenvalue."""
    values = mac(lam, shapes, mass, ref)
    i = int(np.argmax(values))
    if values[i] <= 0.0:
        raise ValueError("no linear mode with a positive stiffness")
    return i
