"""The fixed-step loop of :mod:`chainmodel.kernels.rk4_loop` run as plain Python on any
:class:`~chainmodel.models.base.Model` (issue 20, item 1: the stepping algorithm written once).

The step rule, the stable-step guard, the event location (:func:`rk4_loop._locate`) and the
crossing (:func:`rk4_loop._cross`) exist only in ``rk4_loop``. Levels 1-2 run them compiled
(or as plain Python with ``CHAINMODEL_NUMBA=0``) on their kernel. Every other model - a model
without kernels, and ``chainmodel.integrate.python_loop_model`` (the twin the tests and
benchmarks compare) - runs the *same functions' source* (``py_func``), rebuilt here with
the few names that touch the model bound to the model interface instead of the kernel:

==============  ==================================  ============================================
name            in rk4_loop (levels 1-2 kernel)     here (any Model)
==============  ==================================  ============================================
``_rhs_at``     ``spans.evaluate`` at the inputs    ``model.rhs(t, x, source(t))``
``_switch``     the kernel's six span functions     ``model.rhs`` and ``model.switching_functions``
``_omega_at``   ``omega_estimate``                  ``model.omega_at``
``_event_step`` a quarter tooth period              ``model.event_step``
``_after_step`` finite check                        ``model.check`` (raises the model's sentence)
``_step_kept``  ``spans.lag_step_kept``             ``model.step_kept``
``_step_from``  ``_rk4_from``                       ``_rk4_from`` or ``_verlet_from`` (method)
==============  ==================================  ============================================

The argument ``c`` (the communication step's inputs in the kernel) carries the model, the
input source and the larger speed of the step's ends here; ``G``, ``P``, ``Q`` and ``aux``
are not used.
"""

from __future__ import annotations

import types

import numpy as np

from . import rk4_loop

__all__ = ["LoopContext", "LOOPS", "run_interval"]

#: the loop's functions, run from their one source
_SHARED = ("_interval", "_cross", "_locate", "_secant", "_dense", "_changed", "_step_bound",
           "_rk4_from", "_verlet_from")


class LoopContext:
    """What the rebound names need: the model, the inputs ``source(t)`` and the speed for the
    event step (the larger of the communication step's two ends)."""

    __slots__ = ("model", "source", "speed")

    def __init__(self, model, source, speed: float):
        self.model, self.source, self.speed = model, source, float(speed)


def _rhs_at(t, x, c, G, P, dx, aux):
    dx[:] = c.model.rhs(t, x, c.source(t))


def _switch(t, x, c, G, P, dx, aux, g):
    u = c.source(t)
    dx[:] = c.model.rhs(t, x, u)
    if g.size:
        g[:] = c.model.switching_functions(t, x, u)


def _omega_at(t, x, aux, c, G, P, Q):
    return c.model.omega_at(t, x, c.source(t))


def _event_step(c, Q):
    return c.model.event_step(c.speed)


def _after_step(t, x, c, P, Q):
    # every step, as the compiled loop checks finiteness: a diverging state is caught at its
    # first unphysical step, where its cause can still be told apart
    c.model.check(t, x)
    return rk4_loop.STATUS_OK if np.all(np.isfinite(x)) else rk4_loop.STATUS_NONFINITE


def _step_kept(x, xn, c, P):
    return c.model.step_kept(x, xn)


def _plain(fn):
    return getattr(fn, "py_func", fn)


def _build(method: str):
    """rk4_loop._interval for ``method``, its callees rebuilt from their source with the
    model's names bound (module docstring)."""
    namespace = dict(vars(rk4_loop))
    for name in _SHARED:
        f = _plain(getattr(rk4_loop, name))
        namespace[name] = types.FunctionType(f.__code__, namespace, name, f.__defaults__,
                                             f.__closure__)
    namespace.update(_rhs_at=_rhs_at, _switch=_switch, _omega_at=_omega_at,
                     _event_step=_event_step, _after_step=_after_step, _step_kept=_step_kept)
    namespace["_step_from"] = namespace["_rk4_from" if method == "rk4" else "_verlet_from"]
    return namespace["_interval"]


#: method -> rk4_loop._interval on the model interface
LOOPS = {method: _build(method) for method in ("rk4", "verlet")}


def run_interval(method, model, source, x, t0, t1, cfg, n_switch, log, log_cap):
    """:func:`rk4_loop._interval` from (t0, x) to t1 in place on ``x``, ``cfg`` the step rule
    (``FixedStepper.cfg``), ``n_switch`` the number of the model's switching functions; the
    first ``log_cap`` event times go to the ring buffer ``log``. Returns (status, steps,
    events, evaluations, t, omega) as the compiled loop does."""
    speed = max(abs(source(t0).speed), abs(source(t1).speed))
    ctx = LoopContext(model, source, speed)
    n = x.size
    W = np.empty((rk4_loop.W_ROWS, n))
    V = np.empty((rk4_loop.V_ROWS, n_switch))
    return LOOPS[method](x, t0, t1, ctx, None, None, None, cfg, W, V, np.empty(0), log, 0,
                         log_cap, False)
