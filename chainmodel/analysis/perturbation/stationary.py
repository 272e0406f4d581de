"""Stationary solutions of the modulation equations of seed 004 and their stability.

* section 5.10, primary parametric resonance of the tight span: eqs 100-101, trivial solution
  (104), non-trivial branches (105) under the conditions (106);
* section 5.11, primary external resonance of the driven sprocket: eq 121;
* section 5.12, the trivial solution (140) of the combined case.

Detunings are physical (epsilon = 1): ``sigma2`` stands for epsilon*sigma2 = Omega2 - 2 omega_m
(eq 93) and ``sigma_theta`` for omega_theta - Omega2 (eq 114), in the non-dimensional time of
eq 27. The stationary amplitudes do not depend on epsilon: every term of the solvability
conditions is O(epsilon), so epsilon only rescales the slow time.

Two misprints of eq 101 are corrected here (the amplitudes of (105) are unaffected, the
stability is): the cubic term is a^2 (not a^3), and the sign of the cosine term follows from
eq 94 as in the paper's own eq 131,

    a'    = -mu_m a - f1 a sin psi2                                   (100)
    psi2' = sigma2 - 2 Lambda0 a^2 - 2 f1 cos psi2                     (101, corrected)

with f1 = alpha_m p2 / (4 omega_m) and Lambda0 = 3 kappa_m / (8 omega_m) (eq 135). The phase of
(105) is then tan psi2 = 2 mu_m / (sigma2 - 2 Lambda0 a^2) (the printed 4 omega_m a^2/(3 kappa_m)
is inverted), taken in the quadrant sin psi2 = -mu_m/f1, cos psi2 = (sigma2 - 2 Lambda0 a^2)/(2 f1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

__all__ = ["ParametricBranches", "parametric_branches", "parametric_polar_jacobian",
           "parametric_trivial_eigenvalues", "parametric_instability_band",
           "sprocket_amplitude", "sprocket_phase", "combined_trivial_amplitude",
           "parametric_forcing", "cubic_shift"]


def parametric_forcing(c) -> float:
    """f1 = alpha_m p2 / (4 omega_m) (eq 135); (100)-(101) use it as the effective parametric
    forcing."""
    return c.alpha_m * c.p2 / (4.0 * c.omega_m)


def cubic_shift(c) -> float:
    """Lambda0 = 3 kappa_m / (8 omega_m) (eq 135): the hardening of the span frequency,
    phi' = Lambda0 a^2 for the free undamped mode."""
    return 3.0 * c.kappa_m / (8.0 * c.omega_m)


def parametric_instability_band(c) -> tuple[float, float]:
    """(sigma_lo, sigma_hi) = -/+ sqrt((alpha_m p2/(2 omega_m))^2 - 4 mu_m^2) (eq 106): the
    detunings between which the trivial solution is unstable; (nan, nan) when damping closes
    the band."""
    r2 = (c.alpha_m * c.p2 / (2.0 * c.omega_m))**2 - 4.0 * c.mu_m**2
    if r2 < 0:
        return float("nan"), float("nan")
    r = float(np.sqrt(r2))
    return -r, r


@dataclass(frozen=True)
class ParametricBranches:
    """Eqs 104-106 on a grid of detunings sigma2 = Omega2 - 2 omega_m (arrays, nan where a branch
    does not exist)."""

    sigma2: np.ndarray
    a_upper: np.ndarray          #: '+' branch of (105)
    a_lower: np.ndarray          #: '-' branch of (105)
    psi_upper: np.ndarray        #: psi2 of the '+' branch
    psi_lower: np.ndarray
    upper_stable: np.ndarray     #: bool (from the Jacobian of 100-101)
    lower_stable: np.ndarray
    trivial_stable: np.ndarray   #: bool (eigenvalues -mu +/- sqrt(f1^2 - sigma2^2/4))


def parametric_branches(c, sigma2) -> ParametricBranches:
    """Stationary amplitudes of the tight span at primary parametric resonance, eq 105 under
    the conditions (106), with their stability (vectorised over ``sigma2``).

    ``c`` is a :class:`~.coefficients.Coefficients` (or anything with omega_m, alpha_m,
    kappa_m, mu_m, p2)."""
    sigma2 = np.asarray(sigma2, float)
    f1, lam0, mu = parametric_forcing(c), cubic_shift(c), c.mu_m
    r2 = (2.0 * f1)**2 - 4.0 * mu**2
    r = np.sqrt(r2) if r2 >= 0 else np.nan
    out = {}
    for name, sign in (("upper", 1.0), ("lower", -1.0)):
        a2 = (sigma2 + sign * r) / (2.0 * lam0)            # = 4 omega_m/(3 kappa_m)(sigma2 +/- R)
        a2 = np.where(a2 > 0, a2, np.nan) if r2 >= 0 else np.full_like(sigma2, np.nan)
        a = np.sqrt(a2)
        psi = np.arctan2(np.full_like(sigma2, -mu / f1) if f1 > 0 else np.nan,
                         (sigma2 - 2.0 * lam0 * a2) / (2.0 * f1))
        jac = parametric_polar_jacobian(c, a, psi, sigma2)
        out[name] = (a, psi, _stable_2x2(jac) & np.isfinite(a))
    trivial = np.max(parametric_trivial_eigenvalues(c, sigma2).real, axis=-1) < 0
    return ParametricBranches(sigma2, out["upper"][0], out["lower"][0], out["upper"][1],
                              out["lower"][1], out["upper"][2], out["lower"][2], trivial)


def parametric_polar_jacobian(c, a, psi2, sigma2) -> np.ndarray:
    """Jacobian d(a', psi2')/d(a, psi2) of eqs 100-101 (corrected, see module docstring),
    shape (..., 2, 2):

        [[-mu_m - f1 sin psi2,  -f1 a cos psi2],
         [-4 Lambda0 a,          2 f1 sin psi2]]

    At a stationary point the trace is -2 mu_m and the determinant is +/- 2 Lambda0 a^2 R
    (R the root of eq 105): the '+' branch is a stable node/focus, the '-' branch a saddle."""
    a, psi2, sigma2 = np.broadcast_arrays(*(np.asarray(x, float) for x in (a, psi2, sigma2)))
    f1, lam0, mu = parametric_forcing(c), cubic_shift(c), c.mu_m
    s, co = np.sin(psi2), np.cos(psi2)
    jac = np.empty(a.shape + (2, 2))
    jac[..., 0, 0] = -mu - f1 * s
    jac[..., 0, 1] = -f1 * a * co
    jac[..., 1, 0] = -4.0 * lam0 * a
    jac[..., 1, 1] = 2.0 * f1 * s
    return jac


def parametric_trivial_eigenvalues(c, sigma2) -> np.ndarray:
    """Eigenvalues of the trivial solution (104), from eq 94 linearised in Cartesian form
    (the polar form is singular at a = 0): -mu_m +/- sqrt(f1^2 - sigma2^2/4)."""
    sigma2 = np.asarray(sigma2, float)
    f1 = parametric_forcing(c)
    root = np.sqrt((f1**2 - sigma2**2 / 4.0).astype(complex))
    return np.stack([-c.mu_m + root, -c.mu_m - root], axis=-1)


def _stable_2x2(jac) -> np.ndarray:
    tr = jac[..., 0, 0] + jac[..., 1, 1]
    det = jac[..., 0, 0] * jac[..., 1, 1] - jac[..., 0, 1] * jac[..., 1, 0]
    with np.errstate(invalid="ignore"):
        return (tr < 0) & (det > 0)


def sprocket_amplitude(c, Omega2) -> np.ndarray:
    """Driven-sprocket stationary amplitude at primary external resonance, eq 121:

        v = omega_theta p2 / (2 sqrt(mu_theta^2 + (omega_theta - Omega2)^2)).

    Unique and stable for mu_theta > 0 (eqs 119-120 are linear in Cartesian form)."""
    Omega2 = np.asarray(Omega2, float)
    return 0.5 * c.omega_theta * c.p2 / np.sqrt(c.mu_theta**2 + (c.omega_theta - Omega2)**2)


def sprocket_phase(c, Omega2) -> np.ndarray:
    """psi_theta of eq 121, tan psi_theta = -mu_theta / (omega_theta - Omega2), in the quadrant
    that (119)-(120) fix: sin psi_theta = -2 mu_theta v/(omega_theta p2),
    cos psi_theta = 2 (omega_theta - Omega2) v/(omega_theta p2)."""
    Omega2 = np.asarray(Omega2, float)
    sig = c.omega_theta - Omega2
    return np.arctan2(-c.mu_theta, sig)


def combined_trivial_amplitude(c, sigma2, sigma_i, omega_theta=None) -> np.ndarray:
    """Eq 140: the sprocket amplitude with the span at rest in the combined case,
    v = |f2| / sqrt(mu_theta^2 + (sigma2 - sigma_i)^2), f2 = -omega_theta p2/2 (eq 135);
    ``omega_theta`` defaults to 2 omega_m + sigma_i (eq 125 with epsilon = 1)."""
    sigma2, sigma_i = np.broadcast_arrays(np.asarray(sigma2, float), np.asarray(sigma_i, float))
    om = 2.0 * c.omega_m + sigma_i if omega_theta is None else omega_theta
    f2 = 0.5 * om * c.p2
    return np.abs(f2) / np.sqrt(c.mu_theta**2 + (sigma2 - sigma_i)**2)
