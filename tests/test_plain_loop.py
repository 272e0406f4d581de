"""Issue 20, item 1: the fixed-step loop is written once. The loop on the model interface
(chainmodel.kernels.plain_loop: models without kernels, integrate.python_loop_model's twin)
runs rk4_loop's own functions - the same code objects - with only the names that touch the
model rebound; integrate.py keeps no copy of the step rule or the event crossing."""

from __future__ import annotations

import pytest

from chainmodel import integrate
from chainmodel.kernels import plain_loop
from chainmodel.kernels import rk4_loop

SHARED = ("_interval", "_cross", "_locate", "_secant", "_dense", "_changed", "_step_bound",
          "_rk4_from", "_verlet_from")
HOOKS = ("_rhs_at", "_switch", "_omega_at", "_event_step", "_after_step")


def _code(fn):
    return getattr(fn, "py_func", fn).__code__


@pytest.mark.parametrize("method, step", [("rk4", "_rk4_from"), ("verlet", "_verlet_from")])
def test_the_plain_loop_runs_rk4_loops_own_code(method, step):
    loop = plain_loop.LOOPS[method]
    assert loop.__code__ is _code(rk4_loop._interval)
    ns = loop.__globals__
    for name in SHARED:
        assert ns[name].__code__ is _code(getattr(rk4_loop, name)), name
    assert ns["_step_from"].__code__ is _code(getattr(rk4_loop, step))
    for name in HOOKS:      # bound to the model interface, not the levels 1-2 kernel
        assert ns[name] is getattr(plain_loop, name), name
    # the rebinding never leaks into the kernel module itself
    assert rk4_loop._step_from is rk4_loop._rk4_from


def test_integrate_keeps_no_copy_of_the_step_rule_or_the_crossing():
    for name in ("_cross", "_locate", "_step"):
        assert not hasattr(integrate.FixedStepper, name), name
    for name in ("_changed", "_dense", "_secant"):
        assert not hasattr(integrate, name), name


# --- one sampling loop and one step rule per method for every level (levels 1-2 and 3) --------

from chainmodel.kernels import multibody_loops, stepping  # noqa: E402

INSTANCES = [("_points", stepping.points, ("_advance", "_outputs")),
             ("_held", stepping.held, ("_points", "_begin")),
             ("_rk4_from", stepping.rk4, ("_rhs_at",)),
             ("_verlet_from", stepping.verlet, ("_rhs_at",))]


@pytest.mark.parametrize("module", [rk4_loop, multibody_loops], ids=["levels 1-2", "level 3"])
@pytest.mark.parametrize("name, source, kernels", INSTANCES, ids=[i[0] for i in INSTANCES])
def test_every_level_runs_the_one_loop_source(module, name, source, kernels):
    """Each level's sampling loop, held step and step rules are instances of the one source in
    chainmodel.kernels.stepping (the same bytecode), with the level's own kernels bound, under
    a name of their own in the level's module (the on-disk cache files them apart)."""
    fn = getattr(getattr(module, name), "py_func", getattr(module, name))
    assert fn.__code__.co_code == source.__code__.co_code
    assert fn.__code__.co_names == source.__code__.co_names
    assert (fn.__module__, fn.__qualname__) == (module.__name__, name)
    for kernel in kernels:
        bound = getattr(module, kernel)
        if (module, name) == (multibody_loops, "_verlet_from"):
            bound = multibody_loops._accel_at     # the accelerations alone: all Verlet reads
        assert fn.__globals__[kernel] is bound, kernel


def test_the_status_codes_are_defined_once():
    """Levels 1-3 report through the codes of chainmodel.kernels.stepping: no level module
    assigns a STATUS_* name of its own (level 3 used the same numbers as literals)."""
    import ast
    import inspect
    for module in (rk4_loop, multibody_loops):
        tree = ast.parse(inspect.getsource(module))
        assigned = {t.id for node in ast.walk(tree) if isinstance(node, ast.Assign)
                    for t in node.targets if isinstance(t, ast.Name)}
        assert not {n for n in assigned if n.startswith("STATUS_")}, module.__name__
    for name in ("STATUS_OK", "STATUS_NONFINITE", "STATUS_UNSTABLE", "STATUS_AMPLITUDE",
                 "STATUS_OUTPUTS"):
        assert getattr(rk4_loop, name) == getattr(stepping, name), name
