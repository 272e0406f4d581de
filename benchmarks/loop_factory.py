"""Prototype for issue 20 item 1: one stepping loop, per-level instances of one code object
(design b), cached by chainmodel's on-disk numba cache across processes.

``points`` below is the loop written once (an RK4 step through communication points, outputs
at each point); :func:`instance` rebuilds it from its code object with the level's kernels
(``_rhs``, ``_outputs``) bound as globals, under a name of its own (numba's cache files are
named by qualname and keyed on bytecode: two instances with one name would share an entry).
Two toy levels: a linear oscillator and a Duffing oscillator. ``hand_*`` are the same loops
written by hand for each level (the reference for speed).

    python benchmarks/loop_factory.py        # fresh cache, two processes, speed
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
import tempfile
import time
import types

import numpy as np

from chainmodel._numba import jit, jit_noalloc


@jit_noalloc
def _osc_rhs(t, x, p, dx):
    dx[0] = x[1]
    dx[1] = -p[0] * x[0] - p[1] * x[1] + math.sin(t)


@jit_noalloc
def _osc_out(x, p, out):
    out[0] = x[0]
    out[1] = 0.5 * (x[1] * x[1] + p[0] * x[0] * x[0])


@jit_noalloc
def _duf_rhs(t, x, p, dx):
    dx[0] = x[1]
    dx[1] = -p[0] * x[0] - p[2] * x[0] ** 3 - p[1] * x[1] + math.cos(t)


@jit_noalloc
def _duf_out(x, p, out):
    out[0] = x[0]
    out[1] = x[1]


def points(x, times, h_max, p, k, OUT):
    """The loop written once: RK4 through ``times``, outputs at each point."""
    n = x.size
    k1, k2, k3, k4, tmp = k[0], k[1], k[2], k[3], k[4]
    steps = 0
    for i in range(1, times.size):
        t = times[i - 1]
        m = max(1, int(math.ceil((times[i] - t) / h_max - 1e-9)))
        h = (times[i] - t) / m
        for _s in range(m):
            _rhs(t, x, p, k1)  # noqa: F821 - bound per instance
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k1[j]
            _rhs(t + 0.5 * h, tmp, p, k2)  # noqa: F821
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k2[j]
            _rhs(t + 0.5 * h, tmp, p, k3)  # noqa: F821
            for j in range(n):
                tmp[j] = x[j] + h * k3[j]
            _rhs(t + h, tmp, p, k4)  # noqa: F821
            for j in range(n):
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            t += h
            steps += 1
        _outputs(x, p, OUT[i])  # noqa: F821
    return steps


def instance(name, **kernels):
    """``points`` with ``kernels`` bound, compiled under the name ``name`` (its own cache files)."""
    code = points.__code__.replace(co_name=name, co_qualname=name)
    namespace = dict(globals())
    namespace.update(kernels)
    fn = types.FunctionType(code, namespace, name)
    fn.__qualname__ = name
    fn.__module__ = __name__
    fn.__doc__ = points.__doc__
    namespace[name] = fn
    return jit(fn)


points_osc = instance("points_osc", _rhs=_osc_rhs, _outputs=_osc_out)
points_duf = instance("points_duf", _rhs=_duf_rhs, _outputs=_duf_out)


@jit
def hand_osc(x, times, h_max, p, k, OUT):
    n = x.size
    k1, k2, k3, k4, tmp = k[0], k[1], k[2], k[3], k[4]
    steps = 0
    for i in range(1, times.size):
        t = times[i - 1]
        m = max(1, int(math.ceil((times[i] - t) / h_max - 1e-9)))
        h = (times[i] - t) / m
        for _s in range(m):
            _osc_rhs(t, x, p, k1)
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k1[j]
            _osc_rhs(t + 0.5 * h, tmp, p, k2)
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k2[j]
            _osc_rhs(t + 0.5 * h, tmp, p, k3)
            for j in range(n):
                tmp[j] = x[j] + h * k3[j]
            _osc_rhs(t + h, tmp, p, k4)
            for j in range(n):
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            t += h
            steps += 1
        _osc_out(x, p, OUT[i])
    return steps


@jit
def hand_duf(x, times, h_max, p, k, OUT):
    n = x.size
    k1, k2, k3, k4, tmp = k[0], k[1], k[2], k[3], k[4]
    steps = 0
    for i in range(1, times.size):
        t = times[i - 1]
        m = max(1, int(math.ceil((times[i] - t) / h_max - 1e-9)))
        h = (times[i] - t) / m
        for _s in range(m):
            _duf_rhs(t, x, p, k1)
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k1[j]
            _duf_rhs(t + 0.5 * h, tmp, p, k2)
            for j in range(n):
                tmp[j] = x[j] + 0.5 * h * k2[j]
            _duf_rhs(t + 0.5 * h, tmp, p, k3)
            for j in range(n):
                tmp[j] = x[j] + h * k3[j]
            _duf_rhs(t + h, tmp, p, k4)
            for j in range(n):
                x[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
            t += h
            steps += 1
        _duf_out(x, p, OUT[i])
    return steps


def measure(repeat=5):
    """One process: first-call time of each loop (compile or cache load), then best-of-repeat
    run time and bit-identity of factory instance vs hand-written loop."""
    import chainmodel.numba_cache as nc
    times = np.linspace(0.0, 20.0, 20001)
    p = np.array([4.0e4, 0.3, 1.0e3])
    rows = []
    for name, fac, hand in (("osc", points_osc, hand_osc), ("duf", points_duf, hand_duf)):
        res = {}
        for label, fn in (("factory", fac), ("hand", hand)):
            x = np.array([1e-3, 0.0])
            k = np.zeros((5, 2))
            OUT = np.zeros((times.size, 2))
            t0 = time.perf_counter()
            fn(x, times, 1e-4, p, k, OUT)
            first = time.perf_counter() - t0
            best = math.inf
            for _ in range(repeat):
                x = np.array([1e-3, 0.0])
                t0 = time.perf_counter()
                fn(x, times, 1e-4, p, k, OUT)
                best = min(best, time.perf_counter() - t0)
            res[label] = (first, best, OUT.copy())
        same = np.array_equal(res["factory"][2], res["hand"][2])
        rows.append((name, res["factory"][0], res["hand"][0], res["factory"][1], res["hand"][1],
                     same))
    print(f"announced compile: {nc._announced}")
    print(f"{'level':6} {'1st call fac':>12} {'1st call hand':>13} {'run fac':>9} {'run hand':>9}"
          f" {'fac/hand':>8} bit-identical")
    for name, ff, fh, bf, bh, same in rows:
        print(f"{name:6} {ff:12.3f} {fh:13.3f} {bf:9.4f} {bh:9.4f} {bf / bh:8.3f} {same}")


def main():
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, CHAINMODEL_CACHE_DIR=cache,
                   PYTHONPATH=os.path.dirname(os.path.abspath(__file__)))
        for proc in (1, 2):
            print(f"--- fresh process {proc} (cache {cache})", flush=True)
            subprocess.run([sys.executable, "-c", "import loop_factory; loop_factory.measure()"],
                           env=env, check=True)
        files = sorted(os.listdir(os.path.join(cache, "numba", "loop_factory")))
        print("cache files:", ", ".join(f for f in files if f.endswith(".nbi")))


if __name__ == "__main__":
    main()
