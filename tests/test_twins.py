"""Every compiled kernel that Python code calls, against its plain twin, in one parametrised
test (issue 20, item 2).

The kernels of levels 0-3 are compiled by numba (chainmodel._numba) and each dispatcher keeps
its plain Python function at ``py_func``: the code that runs with CHAINMODEL_NUMBA=0.
chainmodel.kernels.TWINS lists, once, the kernels that Python code calls (the rest are called
only from inside these); a short run of every level records the arguments of the first call of
each, and the test calls the compiled kernel and its plain twin on copies of them: the results
and every array the kernel writes must agree to round-off (1e-9 relative: numba may contract
a*b+c into one rounding where Python rounds twice). The plain twins of the inner kernels are
checked end to end by tests/test_torsional.py::test_runs_without_numba (a process with
CHAINMODEL_NUMBA=0); level 3's kernels also against an independent numpy force law
(tests/multibody_oracle.py, tests/test_multibody.py)."""

from __future__ import annotations

import copy
import sys

import numpy as np
import pytest

import chainmodel
from chainmodel import _numba, kernels
from chainmodel.scene import load_scene

needs_numba = pytest.mark.skipif(not _numba.enabled(),
                                 reason="CHAINMODEL_NUMBA=0: there is no compiled twin")


@pytest.fixture(scope="module")
def recorded():
    """The arguments of the first call of every TWINS kernel during short runs of every level
    (simulate, the FMU's held step, the model interface). Every chainmodel module that holds
    the kernel under its name (the kernel's own module, a model importing it by name) gets the
    recorder for the second run."""
    _runs()         # compiles every kernel first: a compiled caller resolves its callees then
    calls, saved = {}, []
    for entry in kernels.TWINS:
        kernel = kernels.kernel(entry)
        name = entry.split(".")[1]

        def recorder(*args, _kernel=kernel, _key=entry):
            calls.setdefault(_key, copy.deepcopy(args))
            return _kernel(*args)
        for module in [m for n, m in list(sys.modules.items()) if n.startswith("chainmodel")]:
            if getattr(module, name, None) is kernel:
                saved.append((module, name, kernel))
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
    scene = load_scene("xu2010", fidelity=0)
    scene.model().outputs(1e-3, np.empty(0), scene.inputs(1e-3))
    scene.model().quasi_static_spans(43.2)     # level 2's span-modes check calls it
    for level in (1, 2, 3):
        scene = load_scene("xu2010", fidelity=level)
        stepper = scene.stepper()
        stepper.advance_held(1e-3, 0.0, 12.0, 0.0, 43.2)
        model, x, u = scene.model(), stepper.x, scene.inputs(1e-3)
        model.rhs(1e-3, x, u)
        model.outputs(1e-3, x, u)
        model.snapshot(1e-3, x, u)
        if level < 3:
            model.outputs_many(np.array([1e-3]), x[None, :], [0.0], [12.0], [0.0], [43.2])


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
@pytest.mark.parametrize("entry", kernels.TWINS)
def test_compiled_kernel_equals_its_plain_twin(entry, recorded):
    assert entry in recorded, "the short runs no longer call this kernel"
    kernel = kernels.kernel(entry)
    assert kernels.plain(entry) is kernel.py_func and kernel.py_func is not kernel
    args = recorded[entry]
    compiled_args, plain_args = copy.deepcopy(args), copy.deepcopy(args)
    got = kernel(*compiled_args)
    want = kernels.plain(entry)(*plain_args)
    if got is not None or want is not None:
        _same(got, want, "result")
    for k, (a, b) in enumerate(zip(compiled_args, plain_args)):
        if isinstance(a, np.ndarray):
            _same(a, b, f"argument {k}")


def test_the_registry_names_every_kernel_once():
    assert len(set(kernels.TWINS)) == len(kernels.TWINS)
    for entry in kernels.TWINS:
        assert callable(kernels.plain(entry)), entry
    with pytest.raises(ValueError, match="not in chainmodel.kernels.TWINS"):
        kernels.kernel("spans.no_such_kernel")
