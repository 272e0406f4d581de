"""Modulation equations of seed 004, integrated numerically (scipy ``solve_ivp``), vectorised
over many detunings and initial conditions at once.

The polar forms of the paper are singular where an amplitude vanishes, so they are integrated
in the equivalent Cartesian form. With A = (a/2) e^{i phi}, V = (v/2) e^{i rho} (eqs 97, 99),
define b = a e^{-i psi2/2} and w = v e^{i(psi1 - psi2)} (psi1, psi2 of eqs 133-134). Eqs 126 and
128 become the autonomous system

    b' = -(mu_m + i sigma2/2) b + i (Lambda0 |b|^2 b + Lambda1 conj(b) w + f1 conj(b))
    w' = -(mu_theta + i (sigma2 - sigma_i)) w + i (Lambda2 b^2 + f2)

with Lambda0..2, f1, f2 of eq 135; |b| = a and |w| = v, and its polar form is exactly eqs
129-132 (:func:`combined_polar_rhs` gives them literally, for cross-checking). With w = 0 the
first line is eq 94 (section 5.10, eqs 100-101); with b = 0 the second is eq 117 (section 5.11,
eqs 119-120, with sigma_theta = -(sigma2 - sigma_i)). Detunings are physical (epsilon = 1, see
stationary.py).

How the combined case moves along sigma_i (eq 125) the paper does not say; the coefficients
Lambda2 = -eta_m/(4 omega_theta) and f2 = -omega_theta p2/2 depend on omega_theta. ``policy``:

* ``"inertia"`` (default): sigma_i is changed through the sprocket inertia J, so
  omega_theta = 2 omega_m + sigma_i and eta_m = alpha (m pi)^2/(4J) = omega_theta^2 (m pi)^2/8;
* ``"table"``: omega_theta = 2 omega_m + sigma_i in Lambda2 and f2, eta_m fixed at Table 2's J;
* ``"nominal"``: the coefficients are frozen at exact internal resonance omega_theta = 2 omega_m
  (J chosen for it); sigma_i enters only through the detuning (the usual first-order practice).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.integrate import solve_ivp

__all__ = ["POLICIES", "CombinedCoefficients", "combined_coefficients", "combined_rhs",
           "combined_polar_rhs", "combined_jacobian", "ModulationRun", "integrate_combined",
           "integrate_parametric", "integrate_sprocket", "polish_stationary", "SettledResponse",
           "settle_combined"]

POLICIES = ("inertia", "table", "nominal")


@dataclass(frozen=True)
class CombinedCoefficients:
    """Eq 135 (arrays broadcast against the sigma_i they were made for)."""

    mu_m: float
    mu_theta: float
    omega_m: float
    omega_theta: np.ndarray
    Lambda0: float          #: 3 kappa_m / (8 omega_m)
    Lambda1: float          #: -alpha_m / (4 omega_m)
    Lambda2: np.ndarray     #: -eta_m / (4 omega_theta)
    f1: float               #: alpha_m p2 / (4 omega_m)
    f2: np.ndarray          #: -omega_theta p2 / 2


def combined_coefficients(c, sigma_i, policy: str = "inertia",
                          epsilon: float = 1.0) -> CombinedCoefficients:
    """The coefficients of eqs 129-132 (eq 135) at internal detuning ``sigma_i`` (eq 125).

    ``epsilon`` is the bookkeeping parameter of eq 125 used where the coefficients need
    omega_theta = 2 omega_m + epsilon sigma_i (policies "inertia" and "table"); 1 is the
    physical system, a smaller value matches a direct integration of eqs 68-70 run at that
    epsilon (direct.py), and epsilon -> 0 is the "nominal" policy."""
    if not (np.isfinite(epsilon) and epsilon > 0):
        raise ValueError(f"epsilon must be a positive number, got {epsilon!r}")
    if policy not in POLICIES:
        raise ValueError(f"policy must be one of {', '.join(POLICIES)}, got {policy!r}")
    sigma_i = np.asarray(sigma_i, float)
    mpi2 = (c.mode * np.pi)**2
    if policy == "nominal":
        om_th = np.full_like(sigma_i, 2.0 * c.omega_m)
        eta = om_th**2 * mpi2 / 8.0
    else:
        om_th = 2.0 * c.omega_m + epsilon * sigma_i
        if np.any(om_th <= 0):
            raise ValueError(f"sigma_i must exceed -2 omega_m/epsilon = "
                             f"{-2 * c.omega_m / epsilon:.6g} (eq 125: omega_theta = 2 omega_m "
                             f"+ epsilon sigma_i > 0), got min {float(np.min(sigma_i)):.6g}")
        eta = om_th**2 * mpi2 / 8.0 if policy == "inertia" else np.full_like(sigma_i, c.eta_m)
    return CombinedCoefficients(
        mu_m=c.mu_m, mu_theta=c.mu_theta, omega_m=c.omega_m, omega_theta=om_th,
        Lambda0=3.0 * c.kappa_m / (8.0 * c.omega_m), Lambda1=-c.alpha_m / (4.0 * c.omega_m),
        Lambda2=-eta / (4.0 * om_th), f1=c.alpha_m * c.p2 / (4.0 * c.omega_m),
        f2=-0.5 * om_th * c.p2)


def combined_rhs(y, k: CombinedCoefficients, sigma2, sigma_i, coupled: bool = True,
                 span: bool = True):
    """Right-hand side of the Cartesian modulation equations (see module docstring).

    ``y`` has shape (4, ...): Re b, Im b, Re w, Im w. ``coupled=False`` drops the span-sprocket
    coupling (Lambda1, Lambda2: section 5.10 and 5.11 decoupled); ``span=False`` freezes b."""
    b = y[0] + 1j * y[1]
    w = y[2] + 1j * y[3]
    bc = np.conj(b)
    lam1 = k.Lambda1 if coupled else 0.0
    lam2 = k.Lambda2 if coupled else 0.0
    db = -(k.mu_m + 0.5j * sigma2) * b + 1j * (k.Lambda0 * (b * bc) * b + lam1 * bc * w + k.f1 * bc)
    if not span:
        db = np.zeros_like(db)
    dw = -(k.mu_theta + 1j * (sigma2 - sigma_i)) * w + 1j * (lam2 * b * b + k.f2)
    return np.stack([db.real, db.imag, dw.real, dw.imag])


def combined_polar_rhs(state, k: CombinedCoefficients, sigma2, sigma_i):
    """Eqs 129-132 literally, state (a, v, psi1, psi2) with psi1' = sigma_i - 2 phi' + rho' and
    psi2' = sigma2 - 2 phi' (eqs 133-134). Singular at a = 0 or v = 0."""
    a, v, p1, p2 = state
    da = -k.mu_m * a - k.Lambda1 * a * v * np.sin(p1) - k.f1 * a * np.sin(p2)          # 129
    dv = -k.mu_theta * v + k.Lambda2 * a**2 * np.sin(p1) - k.f2 * np.sin(p2 - p1)       # 130
    dphi = k.Lambda0 * a**2 + k.Lambda1 * v * np.cos(p1) + k.f1 * np.cos(p2)            # 131 / a
    drho = (k.Lambda2 * a**2 * np.cos(p1) + k.f2 * np.cos(p2 - p1)) / v                  # 132 / v
    return np.stack([da, dv, sigma_i - 2 * dphi + drho, sigma2 - 2 * dphi])


def combined_jacobian(y, k: CombinedCoefficients, sigma2, sigma_i, coupled: bool = True):
    """Analytic Jacobian of :func:`combined_rhs`, shape (..., 4, 4), from the Wirtinger
    derivatives (dF/dx = F_z + F_zbar, dF/dy = i (F_z - F_zbar))."""
    b = y[0] + 1j * y[1]
    w = y[2] + 1j * y[3]
    bc = np.conj(b)
    lam1 = k.Lambda1 if coupled else 0.0
    lam2 = k.Lambda2 if coupled else 0.0
    shape = np.broadcast(b, w, sigma2, sigma_i, k.Lambda2).shape
    Fb_b = -(k.mu_m + 0.5j * sigma2) + 2j * k.Lambda0 * b * bc
    Fb_bc = 1j * (k.Lambda0 * b * b + lam1 * w + k.f1)
    Fb_w = 1j * lam1 * bc
    Fw_b = 2j * lam2 * b
    Fw_w = -(k.mu_theta + 1j * (sigma2 - sigma_i))
    jac = np.zeros(shape + (4, 4))

    def put(row, dz, dzc, col):
        dx = np.broadcast_to(dz + dzc, shape)
        dy = np.broadcast_to(1j * (dz - dzc), shape)
        jac[..., row, col], jac[..., row + 1, col] = dx.real, dx.imag
        jac[..., row, col + 1], jac[..., row + 1, col + 1] = dy.real, dy.imag

    zero = np.zeros(shape, complex)
    put(0, Fb_b, Fb_bc, 0)
    put(0, Fb_w, zero, 2)
    put(2, Fw_b, zero, 0)
    put(2, Fw_w, zero, 2)
    return jac


@dataclass(frozen=True)
class ModulationRun:
    """Result of integrating the modulation equations for a batch of cases (arrays of the
    batch shape). ``a_*``/``v_*`` are the span/sprocket amplitudes over the final window;
    ``stationary`` is True where they settled (spread < ``tol`` relative)."""

    a_end: np.ndarray
    v_end: np.ndarray
    a_min: np.ndarray
    a_max: np.ndarray
    v_min: np.ndarray
    v_max: np.ndarray
    stationary: np.ndarray
    y_end: np.ndarray          #: final Cartesian state, shape (4, ...)
    nfev: int


def _integrate(y0, rhs, T1, window, rtol, atol, shape=None, t0=0.0, progress=None):
    n = y0.shape[1]
    t_eval = np.linspace(T1 - window, T1, 41)

    def f(t, z):
        if progress is not None:
            progress(t)         # slow time reached (a CLI progress line; cheap, throttled there)
        return rhs(z.reshape(4, n)).ravel()

    sol = solve_ivp(f, (t0, T1), y0.ravel(), method="RK45", rtol=rtol, atol=atol,
                    t_eval=t_eval)
    if not sol.success:
        raise RuntimeError(f"modulation integration failed: {sol.message}")
    z = sol.y.reshape(4, n, -1)
    a = np.hypot(z[0], z[1])
    v = np.hypot(z[2], z[3])
    return z, a, v, sol.nfev


def integrate_combined(c, sigma2, sigma_i, a0=1e-3, v0=0.0, psi0=0.0, T1: float = 600.0,
                       window: float = 100.0, policy: str = "inertia", coupled: bool = True,
                       rtol: float = 1e-6, atol: float = 1e-10, tol: float = 1e-3,
                       y0=None, t0: float = 0.0, epsilon: float = 1.0,
                       progress=None) -> ModulationRun:
    """Integrate the combined modulation equations (129-132, Cartesian form) from slow time
    ``t0`` to ``T1`` for every broadcast combination of ``sigma2``, ``sigma_i``, initial
    amplitudes ``a0``, ``v0`` and initial phase ``psi0`` (of b; w starts real), or from the
    Cartesian states ``y0`` (shape (4, ...)). One ``solve_ivp`` call for the whole batch."""
    sigma2, sigma_i, a0, v0, psi0 = np.broadcast_arrays(*(np.asarray(x, float) for x in
                                                          (sigma2, sigma_i, a0, v0, psi0)))
    shape = sigma2.shape
    k = combined_coefficients(c, sigma_i.ravel(), policy, epsilon)
    s2, si = sigma2.ravel(), sigma_i.ravel()
    if y0 is None:
        y0 = np.stack([a0.ravel() * np.cos(psi0.ravel()), a0.ravel() * np.sin(psi0.ravel()),
                       v0.ravel(), np.zeros(s2.size)])
    else:
        y0 = np.asarray(y0, float).reshape(4, -1)
    # One call for the batch: solve_ivp's error norm is the RMS over all components, so a
    # hard case in a large batch is integrated less tightly than alone; the fixed points are
    # Newton-polished afterwards (settle_combined), which removes that error where it matters.
    z, a, v, nfev = _integrate(y0, lambda y: combined_rhs(y, k, s2, si, coupled), T1, window,
                               rtol, atol, shape, t0, progress)
    return _run(z, a, v, nfev, shape, tol)


@dataclass(frozen=True)
class SettledResponse:
    """Where the combined modulation equations end up from given initial conditions (arrays
    of the batch shape): ``a``, ``v`` are the stationary amplitudes where the trajectory
    reached a stable fixed point (Newton-polished), otherwise the mean over the final window
    of a modulated (non-stationary) response, whose range is ``a_min``..``a_max``."""

    a: np.ndarray
    v: np.ndarray
    a_min: np.ndarray
    a_max: np.ndarray
    v_min: np.ndarray
    v_max: np.ndarray
    stationary: np.ndarray
    y: np.ndarray


def settle_combined(c, sigma2, sigma_i, a0=1e-3, v0=0.0, psi0=0.0, policy: str = "inertia",
                    T1: float = 150.0, T1_max: float = 600.0, window: float = 100.0,
                    coupled: bool = True, rtol: float = 1e-5,
                    epsilon: float = 1.0, progress=None) -> SettledResponse:
    """Integrate eqs 129-132 (Cartesian form) for the batch to slow time ``T1``, accept the
    cases whose end state Newton-polishes to a nearby (within 5 %) stable fixed point of eqs
    136-139, and integrate the rest on to ``T1_max``; cases that still have not settled are
    reported as modulated (window mean, min and max)."""
    sigma2, sigma_i, a0, v0, psi0 = np.broadcast_arrays(*(np.asarray(x, float) for x in
                                                          (sigma2, sigma_i, a0, v0, psi0)))
    shape = sigma2.shape
    s2, si = sigma2.ravel(), sigma_i.ravel()
    run = integrate_combined(c, s2, si, a0.ravel(), v0.ravel(), psi0.ravel(), T1=T1,
                             window=min(window, T1 / 2), policy=policy, coupled=coupled, rtol=rtol,
                             epsilon=epsilon, progress=progress)
    y = run.y_end.reshape(4, -1)
    out = {k: np.array(getattr(run, k)).ravel() for k in ("a_min", "a_max", "v_min", "v_max")}
    ys, ok = _accept(c, y, s2, si, policy, coupled, epsilon)
    todo = ~ok
    if np.any(todo):
        run2 = integrate_combined(c, s2[todo], si[todo], y0=y[:, todo], t0=T1, T1=T1_max,
                                  window=window, policy=policy, coupled=coupled, rtol=rtol,
                                  epsilon=epsilon, progress=progress)
        y[:, todo] = run2.y_end
        for k in out:
            out[k][todo] = getattr(run2, k)
        ys2, ok2 = _accept(c, run2.y_end, s2[todo], si[todo], policy, coupled, epsilon)
        ys[:, todo] = ys2
        ok[todo] = ok2
    a = np.where(ok, np.hypot(ys[0], ys[1]), 0.5 * (out["a_min"] + out["a_max"]))
    v = np.where(ok, np.hypot(ys[2], ys[3]), 0.5 * (out["v_min"] + out["v_max"]))
    for k, val in (("a_min", a), ("a_max", a), ("v_min", v), ("v_max", v)):
        out[k] = np.where(ok, val, out[k])
    r = lambda x: x.reshape(shape)
    return SettledResponse(r(a), r(v), r(out["a_min"]), r(out["a_max"]), r(out["v_min"]),
                           r(out["v_max"]), r(ok), np.where(ok, ys, y).reshape((4,) + shape))


def _accept(c, y, s2, si, policy, coupled, epsilon, rel: float = 5e-2):
    # A trajectory within a few per cent of a stable fixed point is in its basin (unless a
    # basin boundary passes that close), so the polished point is where it ends.
    ys, conv, _, stable = polish_stationary(c, y, s2, si, policy, coupled, epsilon=epsilon)
    scale = np.maximum(np.hypot(ys[0], ys[1]), 1e-4) + np.maximum(np.hypot(ys[2], ys[3]), 1e-5)
    near = np.max(np.abs(ys - y), axis=0) <= rel * scale
    return ys, conv & stable & near


def _run(z, a, v, nfev, shape, tol):
    amin, amax, vmin, vmax = a.min(-1), a.max(-1), v.min(-1), v.max(-1)
    scale_a = np.maximum(amax, 1e-6)
    scale_v = np.maximum(vmax, 1e-9)
    stationary = ((amax - amin) <= tol * scale_a) & ((vmax - vmin) <= tol * scale_v)
    r = lambda x: x.reshape(shape)
    return ModulationRun(r(a[:, -1]), r(v[:, -1]), r(amin), r(amax), r(vmin), r(vmax),
                         r(stationary), z[:, :, -1].reshape((4,) + shape), nfev)


def integrate_parametric(c, sigma2, a0, psi0=0.0, T1: float = 600.0, window: float = 100.0,
                         rtol: float = 1e-7, atol: float = 1e-10, tol: float = 1e-3) -> ModulationRun:
    """Section 5.10: eqs 100-101 (decoupled span, w = 0) integrated from amplitude ``a0`` and
    phase ``psi0`` (of b = a e^{-i psi2/2}), vectorised over the broadcast inputs."""
    sigma2, a0, psi0 = np.broadcast_arrays(*(np.asarray(x, float) for x in (sigma2, a0, psi0)))
    shape = sigma2.shape
    k = combined_coefficients(c, np.zeros(sigma2.size), "table")
    k = CombinedCoefficients(k.mu_m, k.mu_theta, k.omega_m, k.omega_theta, k.Lambda0, 0.0,
                             np.zeros_like(k.Lambda2), k.f1, np.zeros_like(k.f2))
    s2 = sigma2.ravel()
    y0 = np.stack([a0.ravel() * np.cos(psi0.ravel()), a0.ravel() * np.sin(psi0.ravel()),
                   np.zeros(s2.size), np.zeros(s2.size)])
    z, a, v, nfev = _integrate(y0, lambda y: combined_rhs(y, k, s2, s2, coupled=False), T1,
                               window, rtol, atol, shape)
    return _run(z, a, v, nfev, shape, tol)


def integrate_sprocket(c, Omega2, v0=0.0, T1: float = 600.0, window: float = 100.0,
                       rtol: float = 1e-8, atol: float = 1e-12, tol: float = 1e-3) -> ModulationRun:
    """Section 5.11: eqs 119-120 (span at rest, b = 0) integrated from sprocket amplitude
    ``v0``, vectorised over ``Omega2`` (sigma_theta = omega_theta - Omega2, eq 114)."""
    Omega2, v0 = np.broadcast_arrays(np.asarray(Omega2, float), np.asarray(v0, float))
    shape = Omega2.shape
    n = Omega2.size
    om = np.full(n, c.omega_theta)
    k = CombinedCoefficients(c.mu_m, c.mu_theta, c.omega_m, om, 0.0, 0.0, np.zeros(n), 0.0,
                             -0.5 * om * c.p2)
    # sigma2 - sigma_i = Omega2 - omega_theta; only the difference enters w'
    diff = Omega2.ravel() - c.omega_theta
    y0 = np.stack([np.zeros(n), np.zeros(n), v0.ravel(), np.zeros(n)])
    z, a, v, nfev = _integrate(y0, lambda y: combined_rhs(y, k, diff, 0.0, coupled=False,
                                                          span=False), T1, window, rtol, atol,
                               shape)
    return _run(z, a, v, nfev, shape, tol)


def polish_stationary(c, y, sigma2, sigma_i, policy: str = "inertia", coupled: bool = True,
                      iterations: int = 30, tol: float = 1e-12, epsilon: float = 1.0):
    """Newton's method on the stationary equations 136-139 (Cartesian form), batched, started
    from ``y`` (shape (4, ...)), with the eigenvalues of the Jacobian at the result.

    Returns (y_star, converged, eigenvalues, stable): converged is False where Newton did not
    reach |F| < tol; stable means every eigenvalue has a negative real part."""
    y = np.array(y, float)
    shape = y.shape[1:]
    sigma2, sigma_i = (np.broadcast_to(np.asarray(x, float), shape).ravel() for x in (sigma2, sigma_i))
    k = combined_coefficients(c, sigma_i, policy, epsilon)
    z = y.reshape(4, -1).copy()
    for _ in range(iterations):
        F = combined_rhs(z, k, sigma2, sigma_i, coupled)
        jac = combined_jacobian(z, k, sigma2, sigma_i, coupled)
        ok = np.abs(np.linalg.det(jac)) > 1e-300
        step = np.zeros_like(z)
        if np.any(ok):
            step[:, ok] = np.linalg.solve(jac[ok], F.T[ok][..., None])[..., 0].T
        z = z - step
    F = combined_rhs(z, k, sigma2, sigma_i, coupled)
    converged = np.max(np.abs(F), axis=0) < tol
    eig = np.linalg.eigvals(combined_jacobian(z, k, sigma2, sigma_i, coupled))
    stable = np.max(eig.real, axis=-1) < 0
    return (z.reshape((4,) + shape), converged.reshape(shape), eig.reshape(shape + (4,)),
            stable.reshape(shape))
