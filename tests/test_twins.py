"""Every compiled kernel that Python code calls, against its plain twin, in one parametrised
test (issue 20, item 2).

The kernels of levels 0-3 are compiled by numba (chainmodel._numba) and each dispatcher keeps
its plain Python function at ``py_func``: the code that runs with CHAINMODEL_NUMBA=0. ENTRY
lists, once, the kernels that Python code calls (the rest are called only from inside these);
a short run of every level records the arguments of the first call of each, and the test calls
the compiled kernel and its plain twin on copies of them: the results and every array the
kernel writes must agree to round-off (1e-9 relative: numba may contract a*b+c into one
rounding where Python rounds twice). The plain twins of the inner kernels are checked end to
end by tests/test_torsional.py::test_kernel_plain_python_equals_compiled (a process with
CHAINMODEL_NUMBA=0) and level 3's numpy force law by tests/test_multibody.py."""

from __future__ import annotations

import copy
import importlib

import numpy as np
import pytest

import chainmodel
from chainmodel import _numba
from chainmodel.scene import load_scene

#: (module, dispatcher) of every compiled kernel that Python code calls
ENTRY = (
    ("chainmodel.kernels.spans", "evaluate"),
    ("chainmodel.kernels.rk4_loop", "advance_points"),
    ("chainmodel.kernels.rk4_loop", "advance_held"),
    ("chainmodel.kernels.rk4_loop", "outputs_into"),
    ("chainmodel.kernels.rk4_loop", "omega_estimate"),
    ("chainmodel.kernels.kinematic", "driven_rotation"),
    ("chainmodel.kernels.equilibrium", "static_state"),
    ("chainmodel.kernels.multibody", "_accel_jit"),
    ("chainmodel.kernels.multibody", "_outputs_jit"),
    ("chainmodel.kernels.multibody", "_POINTS"),
    ("chainmodel.kernels.multibody", "_HELD"),
)

needs_numba = pytest.mark.skipif(not _numba.enabled(),
                                 reason="CHAINMODEL_NUMBA=0: there is no compiled twin")


@pytest.fixture(scope="module")
def recorded():
    """The arguments of the first call of every ENTRY kernel during short runs of every level
    (simulate, the FMU's held step, the model interface)."""
    _runs()         # compiles every kernel first: a compiled caller resolves its callees then
    calls, saved = {}, []
    for module_name, name in ENTRY:
        module = importlib.import_module(module_name)
        kernel = getattr(module, name)
        saved.append((module, name, kernel))

        def recorder(*args, _kernel=kernel, _key=(module_name, name)):
            calls.setdefault(_key, copy.deepcopy(args))
            return _kernel(*args)
        setattr(module, name, recorder)
    try:
        _runs()
    finally:
        for module, name, kernel in saved:
            setattr(module, name, kernel)
    return calls


def _runs():
    for level in (0, 1, 2, 3):
        chainmodel.simulate("xu2010", fidelity=level, duration=0.002)
    for level in (1, 2, 3):
        scene = load_scene("xu2010", fidelity=level)
        stepper = scene.stepper()
        stepper.advance_held(1e-3, 0.0, 12.0, 0.0, 43.2)
        model, x, u = scene.model(), stepper.x, scene.inputs(1e-3)
        model.rhs(1e-3, x, u)
        model.outputs(1e-3, x, u)


def _same(a, b, what):
    if isinstance(a, tuple):
        assert isinstance(b, tuple) and len(a) == len(b), what
        for k, (x, y) in enumerate(zip(a, b)):
            _same(x, y, f"{what}[{k}]")
        return
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape, what
    scale = np.max(np.abs(a[np.isfinite(a)]), initial=1.0)
    assert np.array_equal(np.isfinite(a), np.isfinite(b)), what
    fin = np.isfinite(a)
    assert np.allclose(a[fin], b[fin], rtol=1e-9, atol=1e-12 * scale), what


@needs_numba
@pytest.mark.parametrize("module_name, name", ENTRY, ids=[f"{m.rsplit('.', 1)[1]}.{n}"
                                                           for m, n in ENTRY])
def test_compiled_kernel_equals_its_plain_twin(module_name, name, recorded):
    assert (module_name, name) in recorded, "the short runs no longer call this kernel"
    kernel = getattr(importlib.import_module(module_name), name)
    args = recorded[(module_name, name)]
    compiled_args, plain_args = copy.deepcopy(args), copy.deepcopy(args)
    got = kernel(*compiled_args)
    want = kernel.py_func(*plain_args)
    if got is not None or want is not None:
        _same(got, want, "result")
    for k, (a, b) in enumerate(zip(compiled_args, plain_args)):
        if isinstance(a, np.ndarray):
            _same(a, b, f"argument {k}")
