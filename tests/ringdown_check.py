"""The driven sprocket's torsional mode, measured and estimated independently of the models
(issue 21 items 3 and 6; shared by tests/test_top_rung.py and tests/test_wrap_statics.py).

* :func:`ring`: the driven speed's ring-down after a sudden start (5 rpm unless told) without load, its
  spectral peak (Hann window, 16x zero padding, linear trend removed) inside a band;
* :func:`two_inertia_frequency`: the two-inertia system written here - level 1's mass matrix,
  both spans as one spring of stiffness ``k_spans`` [N/m] acting on the sprockets' pitch radii,
  the input shaft's spring - and its mode with the largest share of kinetic energy in the driven
  sprocket;
* :func:`seat_ladder_spans`: that spring from the chain's values - each span's links in series
  with the seat ladder at both ends (K_seat = k_c + k_l K_seat / (k_l + K_seat)), softened by its
  sag under gravity with Ernst's equivalent modulus, k / (1 + (w_n l)^2 k l / (12 T^3)) (H.-J.
  Ernst, Der E-Modul von Seilen unter Beruecksichtigung des Durchhanges, Der Bauingenieur 40,
  1965; the tangent of the elastic catenary), the two spans in parallel.
"""

from __future__ import annotations

import math

import numpy as np

import chainmodel


def ring(name, level, band, rpm=5.0, **kw) -> float:
    """Frequency [Hz] of the driven speed's ring-down (module docstring) within ``band``, after
    a sudden start to ``rpm``."""
    return peak_frequency(ring_run(name, level, rpm, **kw), band)


def ring_run(name, level, rpm=5.0, **kw):
    """The run :func:`ring` reads: a sudden start to ``rpm`` without load, 0.5 s."""
    return chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, ramp_time=0.0,
                               load_torque=0.0, duration=0.5, output_interval=5e-5, **kw)


def spectrum(result) -> tuple[np.ndarray, np.ndarray]:
    """(f [Hz], |X|) of the driven speed after 0.02 s (module docstring)."""
    m = result.time >= 0.02
    t, w = result.time[m], result["driven.speed"][m]
    x = (w - np.polyval(np.polyfit(t, w, 1), t)) * np.hanning(m.sum())
    n = 16 * x.size
    return np.fft.rfftfreq(n, t[1] - t[0]), np.abs(np.fft.rfft(x, n))


def peak_frequency(result, band) -> float:
    """The driven speed's spectral peak [Hz] within ``band`` after 0.02 s."""
    f, spec = spectrum(result)
    spec[(f < band[0]) | (f > band[1])] = 0.0
    return float(f[np.argmax(spec)])


def seat_ladder_spans(scene) -> float:
    """The two spans' stiffness [N/m] from the chain's values (module docstring)."""
    p, d = scene.parameters, scene.drive
    model = scene.model()
    r, t0 = model.reference, model.static_tension()
    kl, kc = p["chain.link_stiffness"], p["contact.stiffness"]
    k_seat = 0.5 * (kc + math.sqrt(kc * kc + 4.0 * kc * kl))
    w = p["gravity"] * p["chain.link_mass"] / d.pitch
    up = 1j * np.exp(1j * (d.centre_angle - p["drive.inclination"]))   # drive.inclination
    total = 0.0
    for s in ("up", "low"):
        k = 1.0 / (r["n_" + s] / kl + 2.0 / k_seat)
        wn = abs(w * float((np.conj(1j * np.exp(1j * r["dir_" + s])) * up).real))
        total += k / (1.0 + (wn * r["l_" + s]) ** 2 * k * r["l_" + s] / (12.0 * t0 ** 3))
    return total


def two_inertia_frequency(scene, k_spans: float) -> float:
    """Driven-sprocket mode [Hz] of the two-inertia system (module docstring)."""
    p, d = scene.parameters, scene.drive
    M = scene.model().mass_matrix()
    rc, ro = d.driver.pitch_radius, d.driven.pitch_radius
    if p["input_shaft.rigid"]:
        return math.sqrt(ro * ro * k_spans / M[1, 1]) / (2 * math.pi)
    K = k_spans * np.array([[rc * rc, -rc * ro], [-rc * ro, ro * ro]])
    K[0, 0] += p["input_shaft.stiffness"]
    lam, vec = np.linalg.eig(np.linalg.solve(M, K))
    share = [M[1, 1] * v[1] ** 2 / (v @ M @ v) for v in np.real(vec).T]
    return math.sqrt(abs(lam[int(np.argmax(share))].real)) / (2 * math.pi)
