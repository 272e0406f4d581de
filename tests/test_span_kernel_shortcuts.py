"""The span kernel's shortcuts (issue 20, item 7) must not change a bit:

* spans._mod_two_pi replaces Python's float ``v % (2 pi)`` without a call to fmod: bitwise the
  same value (sign of zero included) as Python's operator;
* spans.evaluate_rate (the RK4 stages' evaluation, without the seat-event sines, midspan
  deflections and span roles nobody reads there) gives bitwise the derivative of
  spans.evaluate, and the auxiliary quantities it does write are evaluate's."""

import math

import numpy as np
import pytest

import chainmodel
from chainmodel.kernels import spans as S
from chainmodel.kernels.spans import _mod_two_pi

EDGES = [0.0, -0.0, 2 * math.pi, 4 * math.pi, -2 * math.pi, math.pi, -math.pi,
         math.nextafter(2 * math.pi, 0.0), math.nextafter(4 * math.pi, 0.0),
         math.nextafter(-2 * math.pi, 0.0), math.nextafter(-2 * math.pi, -10.0), 1e-300, -1e-300,
         5e-324, -5e-324, 1e6, -1e6, math.inf, -math.inf]


def _same(a, b):
    if math.isnan(a) or math.isnan(b):
        return math.isnan(a) and math.isnan(b)
    return a == b and math.copysign(1.0, a) == math.copysign(1.0, b)


def test_bitwise_python_modulo_on_edges_and_random_values():
    values = EDGES + [math.nan] + list(np.random.default_rng(20).uniform(-15.0, 20.0, 20000))
    for v in values:
        for f in (_mod_two_pi, _mod_two_pi.py_func):
            assert _same(f(float(v)), float(v) % (2 * math.pi)), v


@pytest.mark.parametrize("name,level", [("C1", 1), ("xu2010", 1), ("C1", 2), ("xu2010", 2)])
def test_rate_only_evaluation_gives_the_same_derivative(name, level):
    model = chainmodel.Scene.from_preset(name, fidelity=level, duration=0.1).model()
    rng = np.random.default_rng(7)
    n = model.n_states
    kept = [S.A_T_UP, S.A_T_LOW, S.A_TAU_IN, S.A_ACC1, S.A_ACC2, S.A_L_UP, S.A_L_LOW, S.A_G_UP,
            S.A_G_LOW, S.A_PHI1, S.A_W1, S.A_N_UP, S.A_N_LOW]
    for _ in range(200):
        x = np.zeros(n)
        x[:model.n_sprocket_states] = rng.uniform(-3.0, 3.0, model.n_sprocket_states)
        x[model.n_sprocket_states:] = rng.normal(0.0, 1e-4, n - model.n_sprocket_states)
        th, w, acc, load = rng.uniform(-3, 3), rng.uniform(-20, 20), rng.uniform(-50, 50), \
            rng.uniform(-100, 100)
        for ev, rate in ((S.evaluate, S.evaluate_rate),
                         (S.evaluate.py_func, S.evaluate_rate.py_func)):
            dx1, aux1 = np.empty(n), np.full(S.A_SIZE, np.nan)
            dx2, aux2 = np.empty(n), np.full(S.A_SIZE, np.nan)
            ev(x, th, w, acc, load, model.G, model.P, dx1, aux1)
            rate(x, th, w, acc, load, model.G, model.P, dx2, aux2)
            assert np.array_equal(dx1, dx2)
            assert np.array_equal(aux1[kept], aux2[kept])
