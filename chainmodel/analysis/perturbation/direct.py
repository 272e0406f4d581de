"""Direct numerical integration of the non-dimensional 3-DOF model itself, seed 004 eqs 68-70
(not the modulation equations), used to validate the multiple-scales results:

    xi''  + 2 eps mu_m xi'  + omega_m^2 xi  + eps alpha_m (u2* - u1 + po*) xi  + eps kappa_m xi^3  = 0    (68)
    xi~'' + 2 eps mu~ xi~'  + omega~^2 xi~  + eps alpha~_n (u1 - u2* + po*) xi~ + eps kappa~ xi~^3   = 0    (69)
    u1''  + 2 eps mu_theta u1' + omega_theta^2 u1 + eps eta~ xi~^2 - eps eta_m xi^2
                                             = eps omega_theta^2 u2* + eps M1*/J                      (70)

with u2* = p2 cos(Omega2 t) (eq 86), po* = p0 cos(Omega0 t) (eq 84) and M1*/J = p1 cos(Omega1 t)
(eq 85). The transverse impulse forcing k_m of eqs 63-67 is left out (none of the paper's three
resonance cases uses it), so xi = 0 and xi~ = 0 are invariant: a span that starts exactly at
rest stays at rest.

``epsilon`` is the paper's bookkeeping parameter, kept explicit: epsilon = 1 is the physical
system of the coefficients; a small epsilon scales damping, parametric excitation, nonlinearity,
coupling and the sprocket forcing down together, which is the limit in which the expansion is
asymptotically exact. The multiple-scales amplitudes do not depend on epsilon when the
detunings are scaled with it (Omega2 = 2 omega_m + epsilon sigma2), so the same prediction is
compared at every epsilon.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["DirectRun", "integrate_direct", "harmonic_amplitude", "parametric_initial_state",
           "combined_initial_state"]


def parametric_initial_state(a, psi2, Omega2):
    """(xi(0), xi'(0)) of the first-order solution xi = a cos(Omega2 t/2 - psi2/2) (back
    substitution of eqs 97, 102 into 81; eq 103 prints +psi2/2, the section 5.12
    back-substitution has the sign used here)."""
    a, psi2, Omega2 = np.broadcast_arrays(*(np.asarray(x, float) for x in (a, psi2, Omega2)))
    return a * np.cos(0.5 * psi2), a * 0.5 * Omega2 * np.sin(0.5 * psi2)


def combined_initial_state(y, Omega2):
    """(xi, xi', u1, u1') at t = 0 of the first-order solution of section 5.12 for a Cartesian
    modulation state y = (Re b, Im b, Re w, Im w) (modulation.py): xi = Re(b e^{i Omega2 t/2}),
    u1 = Re(w e^{i Omega2 t}), i.e. q0 = a cos(Omega2 T0/2 - psi2/2) and
    nu0 = v cos(Omega2 T0 + psi1 - psi2) (the paper prints psi2 - psi1)."""
    y = np.asarray(y, float)
    Omega2 = np.asarray(Omega2, float)
    return y[0], -0.5 * Omega2 * y[1], y[2], -Omega2 * y[3]


@dataclass(frozen=True)
class DirectRun:
    """Steady-state amplitudes of a batch of direct integrations (arrays of the batch shape).

    ``a_span`` is the amplitude of xi at Omega2/2 (the parametric response, eq 103),
    ``v_sprocket`` the amplitude of u1 at Omega2 (eq 124); ``*_peak`` are half the peak-to-peak
    values over the same final window; ``drift`` the relative change of a_span's peak value
    between the two halves of the window (small when the response has settled)."""

    a_span: np.ndarray
    v_sprocket: np.ndarray
    a_peak: np.ndarray
    v_peak: np.ndarray
    a_slack_peak: np.ndarray
    drift: np.ndarray
    t: np.ndarray              #: sample times of the final window
    y: np.ndarray              #: samples, shape (6, batch..., len(t)): xi, xi', xi~, xi~', u1, u1'
    nfev: int


def harmonic_amplitude(t, x, omega):
    """Amplitude of the component of x(t) at angular frequency omega, by projection over the
    samples (uniform, spanning a whole number of periods)."""
    return 2.0 * np.abs(np.mean(x * np.exp(-1j * omega * t), axis=-1))


def integrate_direct(c, Omega2, t_end: float, epsilon: float = 1.0, xi0=0.0, xi_slack0=0.0,
                     u10=0.0, dxi0=0.0, du10=0.0, omega_theta=None, eta_scale: float = 1.0,
                     p0: float = 0.0, Omega0: float = 0.0, p1: float = 0.0, Omega1: float = 0.0,
                     window_periods: int = 40, samples_per_period: int = 32,
                     rtol: float = 1e-7, atol: float = 1e-11, method: str = "DOP853") -> DirectRun:
    """Integrate eqs 68-70 from rest (plus the given initial displacements) to ``t_end`` for
    every broadcast combination of ``Omega2`` and the initial values, in one ``solve_ivp``
    call, and extract the steady amplitudes over the last ``window_periods`` periods of the
    span response (period 4 pi / Omega2).

    ``omega_theta`` replaces the sprocket frequency (for the combined case, eq 125); when it
    does, eta_m and eta~_n follow the sprocket inertia J = 2 alpha/omega_theta^2 (the
    "inertia" policy of modulation.py) times ``eta_scale``."""
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise ValueError(f"epsilon must be a positive number, got {epsilon!r}")
    Omega2, xi0, xi_slack0, u10, dxi0, du10, om_th = np.broadcast_arrays(
        *(np.asarray(x, float) for x in (Omega2, xi0, xi_slack0, u10, dxi0, du10,
                                          c.omega_theta if omega_theta is None else omega_theta)))
    shape = Omega2.shape
    n = Omega2.size
    W2, om_th = Omega2.ravel(), om_th.ravel()
    if np.any(W2 <= 0):
        raise ValueError("Omega2 must be positive")
    if omega_theta is None:
        eta, eta_s = np.full(n, c.eta_m), np.full(n, c.eta_n_slack)
    else:
        J = 2.0 * c.alpha / om_th**2
        eta = eta_scale * c.alpha * (c.mode * np.pi)**2 / (4.0 * J)
        eta_s = eta_scale * c.alpha * (c.slack_mode * np.pi)**2 / (4.0 * J)
    e = float(epsilon)
    wm2, wn2, wt2 = c.omega_m**2, c.omega_n_slack**2, om_th**2

    def rhs(t, z):
        xi, dxi, xs, dxs, u1, du1 = z.reshape(6, n)
        u2 = c.p2 * np.cos(W2 * t)
        po = p0 * np.cos(Omega0 * t)
        ddxi = -(2 * e * c.mu_m * dxi + wm2 * xi + e * c.alpha_m * (u2 - u1 + po) * xi
                 + e * c.kappa_m * xi**3)
        ddxs = -(2 * e * c.mu_n_slack * dxs + wn2 * xs
                 + e * c.alpha_n_slack * (u1 - u2 + po) * xs + e * c.kappa_n_slack * xs**3)
        ddu1 = (-2 * e * c.mu_theta * du1 - wt2 * u1 - e * eta_s * xs**2 + e * eta * xi**2
                + e * wt2 * u2 + e * p1 * np.cos(Omega1 * t))
        return np.concatenate([dxi, ddxi, dxs, ddxs, du1, ddu1])

    z0 = np.concatenate([xi0.ravel(), dxi0.ravel(), xi_slack0.ravel(), np.zeros(n),
                         u10.ravel(), du10.ravel()])
    period = 4.0 * np.pi / W2                       # span period at Omega2/2
    t_win = t_end - window_periods * float(period.max())
    if t_win <= 0:
        raise ValueError(f"t_end = {t_end!r} is shorter than the sampling window "
                         f"({window_periods} span periods)")
    # transient without dense output, then the final window with it
    sol = solve_ivp(rhs, (0.0, t_win), z0, method=method, rtol=rtol, atol=atol)
    if not sol.success:
        raise RuntimeError(f"direct integration failed: {sol.message}")
    nfev = sol.nfev
    sol = solve_ivp(rhs, (t_win, t_end), sol.y[:, -1], method=method, rtol=rtol, atol=atol,
                    dense_output=True)
    if not sol.success:
        raise RuntimeError(f"direct integration failed: {sol.message}")
    nfev += sol.nfev
    # per-case window: a whole number of span periods 4 pi/Omega2 ending at t_end
    m = window_periods * samples_per_period
    frac = (np.arange(m) + 0.5) / m
    tw = t_end - window_periods * period[:, None] * (1.0 - frac[None, :])      # (n, m)
    zs = np.empty((6, n, m))
    for i in range(n):
        zs[:, i, :] = sol.sol(tw[i]).reshape(6, n, m)[:, i, :]
    a = harmonic_amplitude(tw, zs[0], 0.5 * W2[:, None])
    v = harmonic_amplitude(tw, zs[4], W2[:, None])
    a_peak = 0.5 * (zs[0].max(-1) - zs[0].min(-1))
    v_peak = 0.5 * (zs[4].max(-1) - zs[4].min(-1))
    as_peak = 0.5 * (zs[2].max(-1) - zs[2].min(-1))
    h = m // 2
    first = 0.5 * (zs[0, :, :h].max(-1) - zs[0, :, :h].min(-1))
    second = 0.5 * (zs[0, :, h:].max(-1) - zs[0, :, h:].min(-1))
    drift = np.abs(second - first) / np.maximum(second, 1e-12)
    r = lambda x: x.reshape(shape)
    return DirectRun(r(a), r(v), r(a_peak), r(v_peak), r(as_peak), r(drift), tw.reshape(shape + (m,)),
                     zs.reshape((6,) + shape + (m,)), nfev)
