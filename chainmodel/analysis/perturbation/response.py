"""Frequency-response sweeps after seed 004 Figs 6-9 (section 6), vectorised over the sweep.

Each function returns a plain dict of numpy arrays (the CLI prints it as JSON, plots.py draws
it). Frequencies and detunings are non-dimensional (time unit of eq 27) with epsilon = 1;
ratios to omega_m or omega_theta are given alongside, as the paper plots them.
"""

from __future__ import annotations

import numpy as np

from . import modulation, stationary

__all__ = ["parametric_response", "sprocket_response", "combined_response"]


def _grid(name, values, default, allow_empty=False):
    arr = np.asarray(default if values is None else values, float)
    if arr.ndim != 1 or (arr.size < 1 and not allow_empty) or not np.all(np.isfinite(arr)):
        raise ValueError(f"{name} must be a 1-D array of finite numbers")
    return arr


def parametric_response(c, ratio=None, numerical_ratio=None, initial_conditions: int = 4,
                        seed: int = 0, T1: float = 400.0) -> dict:
    """Fig 6: tight-span amplitude a against Omega2/omega_m at primary parametric resonance
    (section 5.10): both branches of eq 105 with their stability (Jacobian of 100-101), the
    stability of the trivial solution, and the end points of eqs 100-101 integrated from
    ``initial_conditions`` random starts (amplitude uniform in [0, 1.5 max a], phase uniform)
    at each ``numerical_ratio``."""
    ratio = _grid("ratio", ratio, np.linspace(1.5, 2.8, 521))
    numerical_ratio = _grid("numerical_ratio", numerical_ratio, np.linspace(1.55, 2.75, 25))
    sigma2 = (ratio - 2.0) * c.omega_m
    br = stationary.parametric_branches(c, sigma2)
    lo, hi = stationary.parametric_instability_band(c)
    out = {"omega_m": c.omega_m, "ratio": ratio, "sigma2": sigma2,
           "a_upper": br.a_upper, "a_lower": br.a_lower,
           "upper_stable": br.upper_stable, "lower_stable": br.lower_stable,
           "trivial_stable": br.trivial_stable,
           "band_ratio": np.array([2.0 + lo / c.omega_m, 2.0 + hi / c.omega_m])}
    if initial_conditions > 0:
        rng = np.random.default_rng(seed)
        s2n = (numerical_ratio - 2.0) * c.omega_m
        amax = np.nanmax(stationary.parametric_branches(c, s2n).a_upper)
        amax = 0.03 if not np.isfinite(amax) else amax
        a0 = rng.uniform(0.0, 1.5 * amax, (initial_conditions, s2n.size))
        psi0 = rng.uniform(0.0, 2 * np.pi, (initial_conditions, s2n.size))
        run = modulation.integrate_parametric(c, s2n[None, :], a0, psi0, T1=T1)
        out.update(numerical_ratio=numerical_ratio, numerical_a=run.a_end,
                   numerical_a0=a0, numerical_stationary=run.stationary)
    return out


def sprocket_response(c, ratio=None, numerical_ratio=None, T1: float = 400.0) -> dict:
    """Fig 7: driven-sprocket amplitude v against Omega2/omega_theta at primary external
    resonance (section 5.11): eq 121, and eqs 119-120 integrated from rest."""
    ratio = _grid("ratio", ratio, np.linspace(0.97, 1.03, 601))
    numerical_ratio = _grid("numerical_ratio", numerical_ratio, np.linspace(0.975, 1.025, 21),
                            allow_empty=True)
    out = {"omega_theta": c.omega_theta, "ratio": ratio,
           "v": stationary.sprocket_amplitude(c, ratio * c.omega_theta),
           "v_peak": 0.5 * c.p2 * c.omega_theta / c.mu_theta}
    if numerical_ratio.size:
        run = modulation.integrate_sprocket(c, numerical_ratio * c.omega_theta, T1=T1)
        out.update(numerical_ratio=numerical_ratio, numerical_v=run.v_end,
                   numerical_stationary=run.stationary)
    return out


def combined_response(c, sigma2_ratio=None, sigma_i_ratio=None, policy: str = "inertia",
                      a0=(1e-3, None), T1: float = 150.0, T1_max: float = 600.0,
                      progress=None) -> dict:
    """Figs 8-9: span amplitude a and sprocket amplitude v from the combined modulation
    equations 129-132 (section 5.12) on the grid sigma2/omega_m x sigma_i/omega_m.

    ``a0`` lists the initial span amplitudes (the sprocket starts at rest); ``None`` stands
    for the decoupled upper branch of eq 105 at that sigma2 with its phase (where it exists,
    else 0.03), so the large-amplitude attractor is found where it coexists with a small one.
    Arrays have shape (len(a0), len(sigma_i_ratio), len(sigma2_ratio)). ``progress(t)`` is
    called with the slow time reached (up to ``T1_max``), for a progress line."""
    s2r = _grid("sigma2_ratio", sigma2_ratio, np.linspace(-2.0, 1.5, 71))
    sir = _grid("sigma_i_ratio", sigma_i_ratio, np.linspace(-1.95, 1.0, 60))
    S2, SI = np.meshgrid(s2r * c.omega_m, sir * c.omega_m)
    starts_a, starts_psi = [], []
    br = stationary.parametric_branches(c, S2)
    for x in a0:
        if x is None:
            ok = np.isfinite(br.a_upper)
            starts_a.append(np.where(ok, br.a_upper, 0.03))
            # b = a e^{-i psi2/2}
            starts_psi.append(np.where(ok, -0.5 * np.nan_to_num(br.psi_upper), 0.0))
        else:
            starts_a.append(np.full(S2.shape, float(x)))
            starts_psi.append(np.zeros(S2.shape))
    A0, P0 = np.stack(starts_a), np.stack(starts_psi)
    res = modulation.settle_combined(c, S2[None], SI[None], a0=A0, psi0=P0, policy=policy,
                                     T1=T1, T1_max=T1_max, progress=progress)
    return {"omega_m": c.omega_m, "policy": policy, "sigma2_ratio": s2r, "sigma_i_ratio": sir,
            "a0": np.array([np.nan if x is None else x for x in a0]),
            "a": res.a, "v": res.v, "a_min": res.a_min, "a_max": res.a_max,
            "v_min": res.v_min, "v_max": res.v_max, "stationary": res.stationary,
            "sigma_i_table2_ratio": c.sigma_i / c.omega_m}
