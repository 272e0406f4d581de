"""The stepping loop written once for every level (issue 20, item 1; scipy's ``OdeSolver``
shape: status handling and output sampling once, a small step per method).

This module holds *sources*, never called as they are: each level builds its own compiled
instance of them with :func:`instance`, binding the names the source leaves free to the level's
kernels (numba resolves a function's globals when it compiles it, so an instance runs its
level's kernels with no call through a function pointer: as fast as a loop written by hand
for the level; benchmarks/loop_factory.py measures it).

==============  =====================================  ===========================================
source          free names (the level's kernels)       instances
==============  =====================================  ===========================================
:func:`rk4`     ``_rhs_at`` (right-hand side)          ``rk4_loop._rk4_from`` (levels 1-2),
                                                       ``multibody_loops._rk4_from`` (level 3)
:func:`verlet`  ``_rhs_at``                            ``rk4_loop._verlet_from``,
                                                       ``multibody_loops._verlet_from``
:func:`points`  ``_begin`` (work arrays), ``_advance`` ``rk4_loop._points``,
                (one communication step: step rule,    ``multibody_loops._points``
                guard, events, checks), ``_outputs``
:func:`held`    ``_points``, ``_begin``                ``rk4_loop._held``, ``multibody_loops._held``
==============  =====================================  ===========================================

Levels 1-2's ``_advance`` is ``rk4_loop._interval`` (the stable-step guard at every step, the
switching functions' events); level 3's is ``multibody_loops.fixed_steps`` behind its guard
at each communication point (no switching functions). Both take their steps with the
instances of :func:`rk4` and :func:`verlet` above.

An instance is a new function object on the source's code, under a name of its own
(``co_name``/``__qualname__``) and in the level's module (``__module__``): chainmodel's
on-disk cache (chainmodel.numba_cache) files a kernel under its module and qualified name
and keys it on its bytecode, so two instances of one source must differ by name, and the
level module's source stamp covers this module (it imports it) and the kernels bound.
With ``CHAINMODEL_NUMBA=0`` an instance is the plain function (its ``py_func``), the same
source run as Python.
"""

from __future__ import annotations

import math
import types

import numpy as np

from .._numba import jit, jit_inline, jit_noalloc

__all__ = ["instance", "rk4", "verlet", "points", "held", "finite", "STATUS_OK",
           "STATUS_NONFINITE", "STATUS_UNSTABLE", "STATUS_AMPLITUDE", "STATUS_OUTPUTS"]

#: the status of a loop, every level: fine; a state became non-finite (level 3: a link left
#: [l_min, l_max]); the explicit step is above the stable limit of the current state; a span
#: mode's amplitude left the string model's range (level 2); an output is not finite
STATUS_OK = 0
STATUS_NONFINITE = 1
STATUS_UNSTABLE = 2
STATUS_AMPLITUDE = 3
STATUS_OUTPUTS = 4       # an output is not finite (its row is filled, for the message)


def instance(source, name: str, module: str, noalloc: bool = True, inline: bool = False,
             **kernels):
    """``source`` compiled (chainmodel._numba.jit_noalloc; jit when ``noalloc`` is False,
    jit_inline when ``inline``) as the function ``name`` of ``module``, its free names bound
    to ``kernels``."""
    code = source.__code__.replace(co_name=name, co_qualname=name)
    namespace = dict(globals())
    namespace.update(kernels)
    fn = types.FunctionType(code, namespace, name, source.__defaults__)
    fn.__qualname__ = name
    fn.__module__ = module
    fn.__doc__ = source.__doc__
    return (jit_inline if inline else jit_noalloc if noalloc else jit)(fn)


@jit_noalloc
def finite(v):
    """True when every element of the vector v is finite."""
    for k in range(v.size):
        if not math.isfinite(v[k]):
            return False
    return True


def rk4(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, out):
    """One classic RK4 step from (t, x) with k1 = f(t, x) already in ``k1`` (three new
    evaluations ``_rhs_at(t, x, c, G, P, dx, aux)``), the new state into ``out`` (which may be
    ``x`` itself). Returns the number of new evaluations."""
    n = x.size
    for i in range(n):
        tmp[i] = x[i] + 0.5 * h * k1[i]
    _rhs_at(t + 0.5 * h, tmp, c, G, P, k2, aux)  # noqa: F821 - the level's, bound per instance
    for i in range(n):
        tmp[i] = x[i] + 0.5 * h * k2[i]
    _rhs_at(t + 0.5 * h, tmp, c, G, P, k3, aux)  # noqa: F821
    for i in range(n):
        tmp[i] = x[i] + h * k3[i]
    _rhs_at(t + h, tmp, c, G, P, k4, aux)  # noqa: F821
    for i in range(n):
        out[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
    return 3


def verlet(t, x, h, c, G, P, k1, k2, k3, k4, tmp, aux, out):
    """One velocity Verlet (kick-drift-kick) step of a second-order state [q, v] with
    k1 = f(t, x) already in ``k1`` (one new evaluation): v_half = v + h/2 a(t, x),
    q1 = q + h v_half, v1 = v_half + h/2 a(t + h, [q1, v_half]) (velocity-dependent forces
    see the half-step velocity), into ``out`` (which may be ``x``: the step is then made in
    place, the evaluation at [q1, v_half] in ``out`` itself). Same arguments as :func:`rk4`
    (k3, k4 and tmp unused; only the acceleration halves of k1 and k2 are read)."""
    n = x.size // 2
    for i in range(n):
        v_half = x[n + i] + 0.5 * h * k1[n + i]
        out[i] = x[i] + h * v_half
        out[n + i] = v_half
    _rhs_at(t + h, out, c, G, P, k2, aux)  # noqa: F821
    for i in range(n):
        out[n + i] = out[n + i] + 0.5 * h * k2[n + i]
    return 1


def points(x_in, x_out, times, angle, speed, acc, load, K, S, cfg, OUT, states, log, log_cap):
    """Integrate from (times[0], x_in) through the communication points ``times`` (inputs given
    there: angle, speed, acc, load), leaving ``x_in`` untouched and the state at the last point
    reached in ``x_out``. ``K``: the level's constant arrays (a tuple), ``S`` its work arrays
    (``_begin(K, n)``, made by the caller: this loop allocates nothing and runs without
    reference counting), ``cfg`` the step rule (``chainmodel.integrate.FixedStepper.cfg``).
    ``OUT[i]`` receives the outputs at times[i] for i >= 1 (OUT may have no rows: not wanted),
    ``states[i]`` the state (likewise; states[0] = x_in). At most ``log_cap`` event times per
    communication step go to the ring buffer ``log``, in order from index 0.

    Each communication step is the level's ``_advance`` (returning status, steps, events,
    evaluations, t_status, omega); the outputs at its end are the level's ``_outputs``
    (returning its evaluations); both are inlined here (chainmodel._numba.jit_inline: a call
    passing two dozen arrays cost 4% of levels 1-2's run at one step per point).

    Returns (reached, status, steps, events, rhs_evaluations, logged, t_status, omega):
    ``reached`` the index of the last communication point completed (len(times) - 1 on
    success), status STATUS_OK, the level's status of the step that failed, or STATUS_OUTPUTS
    (an output not finite, its row filled); t_status and omega where it happened."""
    n = x_in.size
    x = x_out
    for j in range(n):
        x[j] = x_in[j]
    want_out = OUT.shape[0] > 0
    want_states = states.shape[0] > 0
    if want_states:
        for j in range(n):
            states[0, j] = x[j]
    total = 0
    events = 0
    evals = 0
    logged = 0
    for i in range(1, times.size):
        status, m, e, v, t_st, w = _advance(i, x, times, angle, speed, acc, load, K,  # noqa: F821
                                            cfg, S, log, logged, log_cap)
        total += m
        events += e
        evals += v
        logged += min(e, log_cap)
        if status != STATUS_OK:
            return i - 1, status, total, events, evals, logged, t_st, w
        if want_states:
            for j in range(n):
                states[i, j] = x[j]
        if want_out:
            evals += _outputs(i, x, angle, speed, acc, load, K, S, OUT[i])  # noqa: F821
            if not finite(OUT[i]):
                return i - 1, STATUS_OUTPUTS, total, events, evals, logged, times[i], 0.0
    return times.size - 1, STATUS_OK, total, events, evals, logged, times[-1], 0.0


def held(x_in, x_out, t0, t1, a0, w0, acc, load, K, cfg, OUT, log):
    """One communication step [t0, t1] with the inputs held first-order (the FMU's hold: the
    angle advances at the held speed; speed, acceleration and load held): the level's
    :func:`points` with times (t0, t1), angle (a0, a0 + w0 (t1 - t0)) and the rest repeated,
    so the same arithmetic as the batched path; the outputs at t1 go to OUT[1] (OUT has two
    rows), at most ``log.size`` event times to ``log``."""
    times = np.empty(2)
    angle = np.empty(2)
    speed = np.empty(2)
    acc2 = np.empty(2)
    load2 = np.empty(2)
    times[0] = t0
    times[1] = t1
    angle[0] = a0
    angle[1] = a0 + w0 * (t1 - t0)
    speed[0] = w0
    speed[1] = w0
    acc2[0] = acc
    acc2[1] = acc
    load2[0] = load
    load2[1] = load
    states = np.empty((0, x_in.size))
    S = _begin(K, x_in.size)  # noqa: F821 - the level's work arrays
    return _points(x_in, x_out, times, angle, speed, acc2, load2, K, S, cfg, OUT,  # noqa: F821
                   states, log, log.size)
