"""Levels 1-2's driven-sprocket mode linearised at rest, and the wrap stiffness fitted on it
(``torsional.wrap_statics``; issue 21 item 3, docs/reduced_models.md "Item 3, the torsional
mode: one wrap").

:func:`~chainmodel.models.wrap_statics.wrap_fit` finds K_m, the driven sprocket's stiffness at
which levels 1-2's two-inertia system (their sprocket mass matrix, the spans on the pitch radii,
the shaft's spring) rings at level 3's linear driven-sprocket mode omega_3. The levels are not
that two-inertia system:

* level 1's spans pull at the driver's angle 0 with their own lengths and moment arms (not the
  pitch radii), through the floor's slope;
* level 2's string modes couple to the rotation through their sag. Below the torsional mode
  (C1: 17.5 and 19 Hz against 25 Hz) they push it up: +4 % on K_m, measured.

Level 3's own linearisation holds its span rollers' transverse inertia, so a level with string
modes of its own counts them twice on K_m. Each level therefore fits the stiffness to its own
linearisation from K_0 = K_m until omega_j is omega_3 within ``TOLERANCE``: first K_1 = K_0
(omega_3 / omega_0)^2 (a two-inertia system's omega ~ sqrt K), then secant steps on ln omega(ln K)
(:func:`_next_stiffness`; where the ends are already stiff next to the links, omega moves far
slower than sqrt K: xu2010 at its tight distance, 150 N, d ln omega / d ln K = 0.07, and the
square-root step took 12 passes to close a 0.7 % gap by a sixth); omega_j the level's mode
at rest (input held, no load) from central differences of its own right-hand side, its mean
over the driver positions in a tooth period at which wrap_fit takes level 3's
(:func:`tooth_mean_mode`). The mode is the one with the largest mass-weighted MAC (Allemang &
Brown 1982) against the two-inertia system's mode at K_m, the string coordinates counted in the
norm with their modal mass rho L / 2 (a sine mode's), so a string mode never passes for the
rotation's.
"""

from __future__ import annotations

import math

import numpy as np

from .base import Inputs
from .modal_assurance import closest_mode

__all__ = ["position_states", "linear_positions", "driven_mode", "tooth_modes",
           "tooth_mean_mode", "fitted_ends", "TOLERANCE"]

#: the fitted mode's relative distance from level 3's at which the iteration stops
TOLERANCE = 1e-5
#: iterations before the fit keeps K_m (the two-inertia fit)
MAX_ITERATIONS = 12
#: the secant's least slope d ln omega / d ln K, and its largest step factor in K
SLOPE_MIN, MAX_STEP = 0.02, 4.0

_CACHE: dict = {}


def position_states(model) -> tuple[list[int], list[int]]:
    """(indices of the position states, indices of their accelerations) in levels 1-2's layout
    (:func:`linear_positions`)."""
    ns, nm = model.n_sprocket_states, model.n_modes
    return (list(range(ns // 2)) + list(range(ns, ns + 2 * nm)),
            list(range(ns // 2, ns)) + list(range(ns + 2 * nm, ns + 4 * nm)))


def linear_positions(model, x: np.ndarray, u: Inputs, h: float = 1e-6
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(indices of the position states, -d(accelerations)/d(positions) at ``x``): central
    differences of ``model.rhs``, each position stepped by ``h`` times its state scale. Levels
    1-2's layout: sprocket angles, sprocket speeds, then [q_up, q_low, v_up, v_low] of the
    string modes (at rest dq/dt = v, so dv/dt is the modal acceleration)."""
    pos, acc = position_states(model)
    scale = model.state_scale()
    a = np.empty((len(pos), len(pos)))
    for j, i in enumerate(pos):
        step = h * scale[i]
        up, down = x.copy(), x.copy()
        up[i] += step
        down[i] -= step
        a[:, j] = -(model.rhs(0.0, up, u)[acc] - model.rhs(0.0, down, u)[acc]) / (2.0 * step)
    return np.array(pos), a


def _position_mass(model) -> np.ndarray:
    """The positions' mass for the MAC: the sprocket mass matrix, each string mode rho L / 2."""
    m = model.mass_matrix()
    sprockets = m[1:, 1:] if model.rigid else m
    rho = model.params["chain.link_mass"] / model.drive.pitch
    strings = ([0.5 * rho * model.reference["l_up"]] * model.n_modes
               + [0.5 * rho * model.reference["l_low"]] * model.n_modes)
    n = sprockets.shape[0] + len(strings)
    full = np.zeros((n, n))
    full[:sprockets.shape[0], :sprockets.shape[0]] = sprockets
    full[sprockets.shape[0]:, sprockets.shape[0]:] = np.diag(strings)
    return full


def _two_inertia_shape(model, stiffness: float, omega: float) -> np.ndarray:
    """The sprocket rotations of the two-inertia system with the driven sprocket's stiffness
    ``stiffness`` in the mode nearest ``omega`` (wrap_statics.modal_stiffness's system)."""
    if model.rigid:
        return np.array([1.0])
    kk = model.two_inertia_stiffness(stiffness / model.drive.driven.pitch_radius ** 2)
    w2, v = np.linalg.eig(np.linalg.solve(model.mass_matrix(), kk))
    return v[:, int(np.argmin(np.abs(w2.real - omega * omega)))].real


def driven_mode(model, shape: np.ndarray, angle: float = 0.0, rank: int | None = None
                ) -> tuple[float, int]:
    """(omega [rad/s], its rank among the positive modes in frequency): the level's
    driven-sprocket mode at rest with the input shaft held at ``angle`` (module docstring), the
    linear mode with the largest mass-weighted MAC against the sprocket rotations ``shape``;
    with ``rank``, the mode of that rank instead (where the level has as many)."""
    u = Inputs(angle=angle)
    x = model.initial_state(u)
    if getattr(model, "start_fallback", None):      # level 2 without its strings' rest
        raise ValueError(f"no rest at driver angle {angle:.4g} rad ({model.start_fallback})")
    _, a = linear_positions(model, x, u)
    lam, vecs = np.linalg.eig(a)
    lam, vecs = lam.real, vecs.real
    positive = np.sort(lam[lam > 0.0])
    if rank is not None and rank < positive.size:
        return math.sqrt(positive[rank]), rank
    ref = np.zeros(len(a))
    ref[:len(shape)] = shape
    try:
        best = closest_mode(lam, vecs, _position_mass(model), ref)
    except ValueError:
        raise ValueError("no linear mode with a positive stiffness at rest") from None
    return math.sqrt(lam[best]), int(np.searchsorted(positive, lam[best]))


def tooth_modes(model, shape: np.ndarray) -> list[float]:
    """The level's driven-sprocket mode [rad/s] at each of wrap_statics' driver positions in a
    tooth period (:func:`~chainmodel.models.wrap_statics.tooth_positions`, where wrap_fit takes
    level 3's): the mode :func:`driven_mode` picks at angle 0 and, at the other positions, the
    mode of the same rank in frequency: where a string mode crosses the driven sprocket's
    (level 2 on C1: 22-23 Hz against 25 Hz), the two share the rotation and the larger MAC
    jumps between them, the branch does not."""
    from .wrap_statics import tooth_positions
    first, *others = tooth_positions(model.drive)
    omega, rank = driven_mode(model, shape, first)
    return [omega] + [driven_mode(model, shape, a, rank)[0] for a in others]


def tooth_mean_mode(model, shape: np.ndarray) -> float:
    """The mean [rad/s] of :func:`tooth_modes`, the mode :func:`fitted_ends` fits."""
    return float(np.mean(tooth_modes(model, shape)))


def _next_stiffness(stiffness: float, omega: float, omega3: float,
                    previous: tuple[float, float] | None) -> float:
    """The next trial stiffness of :func:`fitted_ends`: a secant step on ln omega(ln K) through
    this trial and the ``previous`` (K, omega), its slope kept within [SLOPE_MIN, 1] and the step
    within a factor MAX_STEP; the square-root law's step (slope 1/2) where there is no previous
    trial or the two coincide."""
    slope = 0.5
    if previous is not None:
        dk = math.log(stiffness / previous[0])
        if dk != 0.0:
            slope = min(max(math.log(omega / previous[1]) / dk, SLOPE_MIN), 1.0)
    step = math.log(omega3 / omega) / slope
    return stiffness * math.exp(min(max(step, -math.log(MAX_STEP)), math.log(MAX_STEP)))


def fitted_ends(model) -> tuple[float, float, float] | None:
    """The span ends (c, f, a) at which ``model``'s own driven-sprocket mode is level 3's
    (module docstring), written into ``model.P`` as it goes; cached per level, mode count,
    drive and parameters (the level's options included, unlike wrap_fit's). None where
    level 3 had no linear mode (wrap_fit then used the static secant) or the iteration does not
    converge: the model keeps :func:`~chainmodel.models.wrap_statics.wrap_fit`'s ends (the
    two-inertia fit), and :func:`~chainmodel.models.wrap_statics.fallbacks` says why."""
    from .wrap_statics import note_fallback, parameters_key, span_ends, wrap_fit
    key = (model.level, model.n_modes) + parameters_key(model.drive, model.params,
                                                        skip=("solver.", "output"))
    if key in _CACHE:
        return _CACHE[key]
    fit = wrap_fit(model.drive, model.params)
    result, why = None, None
    if math.isfinite(fit.mode):
        omega3 = 2.0 * math.pi * fit.mode
        shape = _two_inertia_shape(model, fit.modal_stiffness, omega3)
        stiffness = fit.modal_stiffness
        previous = None
        sags = model._sag_terms
        stretch = sum(sags)
        why = f"it did not converge in {MAX_ITERATIONS} passes"
        for _ in range(MAX_ITERATIONS):
            try:
                ends = span_ends(model.drive, model.params, stretch=stretch,
                                 stiffness=stiffness, sags=sags)
                model._write_span_ends(model.P, ends)
                omega = tooth_mean_mode(model, shape)
            except ValueError as exc:   # no end compliance or no mode for this stiffness
                why = f"at {stiffness:.4g} N m/rad: {exc}"
                break
            if abs(omega / omega3 - 1.0) < TOLERANCE:
                result, why = ends, None
                break
            stiffness, previous = _next_stiffness(stiffness, omega, omega3, previous), \
                (stiffness, omega)
        if why is not None:
            why = (f"level {model.level}'s own driven-sprocket mode at rest could not be fitted "
                   f"to level 3's {fit.mode:.4g} Hz ({why}), so its span ends stay on the "
                   f"two-inertia fit K_m = {fit.modal_stiffness:.4g} N m/rad (its torsional "
                   f"mode then off level 3's by the two-inertia system's error, +3 % on C1 at "
                   f"level 2; docs/reduced_models.md)")
    note_fallback(model.level, model.drive, model.params, why)
    if len(_CACHE) > 256:
        _CACHE.clear()
    _CACHE[key] = result
    return result
