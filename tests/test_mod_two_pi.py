"""spans._mod_two_pi replaces Python's float ``v % (2 pi)`` in the span kernel without a call
to fmod; it must give bitwise the same value (sign of zero included) as Python's operator."""

import math

import numpy as np

from chainmodel.models.spans import _mod_two_pi

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
