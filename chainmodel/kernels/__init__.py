"""The compiled kernels of every level (issue 20, item 2), decorated through
:mod:`chainmodel._numba` (the one switch: compiled with numba, their plain Python source with
``CHAINMODEL_NUMBA=0``). Kernels import nothing from ``models``, ``scene``, ``cli``, ``fmu`` or
``analysis`` (tests/test_imports.py).

=====================  ==========================================================================
module                 holds
=====================  ==========================================================================
``span_roles``         which physical span is tight (levels 0-3), by power flow
``spans``              levels 1-2: both spans' polygon geometry, tensions, sprocket equations, modes
``kinematic``          level 0: the four-bar rotation and the outputs
``equilibrium``        levels 1-2: the static equilibrium at rest (initial state)
``stepping``           the loop written once for every level: the output sampling and status
                       loop, the held step, the RK4 and Verlet steps (sources; each level
                       compiles its own instance with its kernels bound)
``rk4_loop``           levels 1-2: the communication step (guard, events) and outputs
``plain_loop``         rk4_loop's loop as plain Python on any Model's rhs
``multibody_layout``   level 3: parameter vector, scratch rows, step-rule vector, Workspace
``multibody_forces``   level 3: the force law (positions' pass, velocities' pass), frequency bound
``multibody_outputs``  level 3: seated rollers, span ends, the output row
``multibody_loops``    level 3: the communication step (guard, Verlet / RK4 steps) and outputs
=====================  ==========================================================================

:data:`TWINS` lists, once, every compiled kernel that Python code calls; its plain twin is the
dispatcher's ``py_func`` (the same source, run as Python), which :func:`plain` returns.
tests/test_twins.py checks every pair.
"""

from __future__ import annotations

import importlib

__all__ = ["TWINS", "kernel", "plain"]

#: every (compiled, plain) pair, once: "module.function" of the kernels that Python code calls
#: (the others are called only from inside these); the plain twin is ``py_func``
TWINS = (
    "spans.evaluate",
    "rk4_loop.advance_points",
    "rk4_loop.advance_held",
    "rk4_loop.outputs_into",
    "rk4_loop.outputs_many",
    "rk4_loop.omega_estimate",
    "kinematic.driven_rotation",
    "kinematic.level0_outputs",
    "kinematic.split",
    "equilibrium.static_state",
    "multibody_forces.accelerations",
    "multibody_outputs.span_ends",
    "multibody_outputs.outputs_row",
    "multibody_loops.points_loop",
    "multibody_loops.held_loop",
)


def _split(entry: str) -> tuple[str, str]:
    if entry not in TWINS:
        raise ValueError(f"{entry!r} is not in chainmodel.kernels.TWINS; listed: "
                         + ", ".join(TWINS))
    module, name = entry.split(".")
    return f"{__name__}.{module}", name


def kernel(entry: str):
    """The kernel of a :data:`TWINS` entry ("module.function"): the numba dispatcher when the
    switch is on, else the plain function."""
    module, name = _split(entry)
    return getattr(importlib.import_module(module), name)


def plain(entry: str):
    """The plain twin of a :data:`TWINS` entry: the kernel's Python source (``py_func``)."""
    return kernel(entry).py_func
