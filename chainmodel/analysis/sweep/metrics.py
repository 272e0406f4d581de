"""A case's run reduced to scalar metrics, its tension spectrum, and whether it hit a resonance.

Every figure is taken over the steady part of the run (:func:`..summary.steady_window`, the
window ``chainmodel run`` reports), so a sweep and a single run agree on it.

Resonance, from the physics of seed 004 (section 5.8, eq 90; section 5.11):
the polygonal action excites the drive at the meshing frequency f_mesh = n_driver f_driver and
its harmonics; it also modulates the span stiffness and tension at f_mesh, which excites a
mode of frequency f parametrically, most strongly near f_mesh = 2 f (primary parametric
resonance, eq 93). A case **hit a resonance** when any of the modes below lies within the band
``|f_exc / f_mode - 1| <= band`` (default 5 %) of f_exc = f_mesh (external resonance, eq 90 with
j = 1; eq 121 for the sprocket) or f_exc = f_mesh / 2 (primary parametric resonance):

* the first transverse mode of each span as an axially moving string (seed 004 eq 61 in
  dimensional form): f_1 = sqrt(T / rho - S^2) / (2 l), with T the span's mean tension in the
  run, rho = link mass / pitch, S = n_driver p f_driver the chain speed, l the mean tight-span
  length (both spans of a two-sprocket drive are equally long); none (nan) where T / rho <= S^2,
  above the span's critical speed;
* the sprocket torsional modes of the linearised level-1 equations, both spans taut
  (:meth:`chainmodel.models.torsional.TorsionalModel.sprocket_frequencies`): the driven sprocket
  on the spans' axial stiffness, and with a flexible input shaft the driver on the shaft
  (seed 004 eq 71 is the first with a rigid driver).

The spectrum is the single-sided amplitude spectrum of the tight-span tension (mean removed,
Hann window, amplitude-corrected: a sine of amplitude A at a bin frequency reads A).
"""

from __future__ import annotations

import math

import numpy as np

from ..summary import steady_window

__all__ = ["amplitude_spectrum", "spectral_peaks", "span_mode_frequency", "case_metrics",
           "resonances", "METRIC_UNITS", "N_PEAKS", "failed_metrics"]

#: peaks of the tension spectrum reported per case
N_PEAKS = 3

#: every metric column with its unit (the table's columns after the case's settings)
METRIC_UNITS = {
    "mean_tight_tension_n": "N", "peak_tight_tension_n": "N", "min_tight_tension_n": "N",
    "tight_tension_ripple_rms_n": "N",
    "mean_slack_tension_n": "N", "peak_slack_tension_n": "N", "min_slack_tension_n": "N",
    "mean_driver_speed_rad_s": "rad/s", "mean_driven_speed_rad_s": "rad/s",
    "driven_speed_ripple_rms_rad_s": "rad/s",
    "meshing_frequency_hz": "Hz",
    **{f"tension_peak_{k}_hz": "Hz" for k in range(1, N_PEAKS + 1)},
    **{f"tension_peak_{k}_n": "N" for k in range(1, N_PEAKS + 1)},
    "tension_amplitude_at_mesh_n": "N",
    "speed_peak_hz": "Hz", "speed_peak_rad_s": "rad/s",
    "max_midspan_deflection_m": "m", "midspan_deflection_amplitude_m": "m",
    "tight_span_mode_hz": "Hz", "slack_span_mode_hz": "Hz",
    "sprocket_mode_1_hz": "Hz", "sprocket_mode_2_hz": "Hz",
    "resonance": "", "resonance_with": "", "resonance_detuning": "",
}


def failed_metrics() -> dict:
    """The metrics of a case that failed: nan numbers, no resonance verdict (None), no text."""
    out = {k: math.nan for k in METRIC_UNITS}
    out.update(resonance=None, resonance_with="")
    return out


def amplitude_spectrum(time: np.ndarray, signal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(frequencies [Hz], single-sided amplitudes) of ``signal`` sampled evenly at ``time``:
    mean removed, Hann window, scaled by 2 / sum(window) so that a sine of amplitude A at a bin
    frequency reads A (the DC bin is 0)."""
    n = len(signal)
    if n < 4:
        return np.zeros(0), np.zeros(0)
    dt = float(time[-1] - time[0]) / (n - 1)
    w = np.hanning(n)
    amp = 2.0 * np.abs(np.fft.rfft((signal - np.mean(signal)) * w)) / np.sum(w)
    amp[0] = 0.0
    return np.fft.rfftfreq(n, dt), amp


def spectral_peaks(freqs: np.ndarray, amps: np.ndarray, n: int = N_PEAKS
                   ) -> list[tuple[float, float]]:
    """The ``n`` largest local maxima (frequency, amplitude), largest first, padded with nan."""
    peaks: list[tuple[float, float]] = []
    if len(amps) >= 3:
        inner = (amps[1:-1] > amps[:-2]) & (amps[1:-1] >= amps[2:]) & (amps[1:-1] > 0)
        idx = np.nonzero(inner)[0] + 1
        order = idx[np.argsort(-amps[idx], kind="stable")][:n]
        peaks = [(float(freqs[k]), float(amps[k])) for k in order]
    return peaks + [(math.nan, math.nan)] * (n - len(peaks))


def span_mode_frequency(tension: float, link_mass: float, pitch: float, chain_speed: float,
                        length: float) -> float:
    """First transverse mode [Hz] of a span as an axially moving string, seed 004 eq 61 in
    dimensional form: omega_1 = (pi / l) sqrt(T / rho - S^2), rho = link_mass / pitch; nan
    where the span has no transverse stiffness (T / rho <= S^2)."""
    rho = link_mass / pitch
    c2 = tension / rho - chain_speed ** 2
    if not (c2 > 0 and length > 0):
        return math.nan
    return math.sqrt(c2) / (2.0 * length)


def resonances(f_mesh: float, modes: dict[str, float], band: float
               ) -> tuple[bool, str, float]:
    """(hit, which, detuning) for the modes {name: Hz} against f_mesh and f_mesh / 2 (module
    docstring): ``which`` lists the hits as ``mode@mesh`` or ``mode@mesh/2`` (';'-separated),
    ``detuning`` is the signed f_exc / f_mode - 1 of the closest pair (nan if none)."""
    hits, best = [], math.nan
    for name, f in modes.items():
        if not (f > 0 and math.isfinite(f)) or not math.isfinite(f_mesh):
            continue
        for label, f_exc in (("mesh", f_mesh), ("mesh/2", 0.5 * f_mesh)):
            d = f_exc / f - 1.0
            if abs(d) <= band:
                hits.append(f"{name}@{label}")
            if not math.isfinite(best) or abs(d) < abs(best):
                best = d
    return bool(hits), ";".join(hits), best


def _sprocket_modes(scene) -> tuple[float, float]:
    from ...models.torsional import TorsionalModel
    w = TorsionalModel(scene.drive, scene.parameters).sprocket_frequencies() / (2 * math.pi)
    return (float(w[0]), float(w[1]) if len(w) > 1 else math.nan)


def case_metrics(result, band: float = 0.05, spectrum_max_hz: float = 1000.0
                 ) -> tuple[dict, np.ndarray]:
    """(metrics, spectrum) of a :class:`chainmodel.simulation.Result`: ``metrics`` has the keys
    of :data:`METRIC_UNITS`; ``spectrum`` is the tight-span tension's amplitude spectrum [N] on
    the bins k * df up to ``spectrum_max_hz`` (df = 1 / steady-window length), as
    ``np.array([df, a_0, a_1, ...])``."""
    scene = result.scene
    t = result.time
    mask = steady_window(t, scene.operating.ramp_time, float(t[-1]))
    ts = t[mask]
    tight, slack = result["tight_span.tension"][mask], result["slack_span.tension"][mask]
    w1, w2 = result["driver.speed"][mask], result["driven.speed"][mask]
    defl = result["tight_span.midspan_deflection"][mask]
    drive, p = scene.drive, scene.parameters
    f_driver = abs(float(np.mean(w1))) / (2 * math.pi)
    f_mesh = drive.n_driver * f_driver
    freqs, amps = amplitude_spectrum(ts, tight)
    sfreqs, samps = amplitude_spectrum(ts, w2)
    m: dict = {
        "mean_tight_tension_n": float(np.mean(tight)), "peak_tight_tension_n": float(np.max(tight)),
        "min_tight_tension_n": float(np.min(tight)),
        "tight_tension_ripple_rms_n": float(np.std(tight)),
        "mean_slack_tension_n": float(np.mean(slack)), "peak_slack_tension_n": float(np.max(slack)),
        "min_slack_tension_n": float(np.min(slack)),
        "mean_driver_speed_rad_s": float(np.mean(w1)), "mean_driven_speed_rad_s": float(np.mean(w2)),
        "driven_speed_ripple_rms_rad_s": float(np.std(w2)),
        "meshing_frequency_hz": f_mesh,
    }
    for k, (f, a) in enumerate(spectral_peaks(freqs, amps), start=1):
        m[f"tension_peak_{k}_hz"], m[f"tension_peak_{k}_n"] = f, a
    if len(freqs) and f_mesh > 0:
        k = int(np.argmin(np.abs(freqs - f_mesh)))
        m["tension_amplitude_at_mesh_n"] = float(np.max(amps[max(k - 1, 0):k + 2]))
    else:
        m["tension_amplitude_at_mesh_n"] = math.nan
    (m["speed_peak_hz"], m["speed_peak_rad_s"]), = spectral_peaks(sfreqs, samps, 1)
    m["max_midspan_deflection_m"] = float(np.max(np.abs(defl)))
    m["midspan_deflection_amplitude_m"] = 0.5 * float(np.max(defl) - np.min(defl))

    chain_speed = drive.n_driver * drive.pitch * f_driver
    length = float(np.mean(result["tight_span.length"][mask]))
    modes = {
        "tight_span": span_mode_frequency(m["mean_tight_tension_n"], p["chain.link_mass"],
                                          drive.pitch, chain_speed, length),
        "slack_span": span_mode_frequency(m["mean_slack_tension_n"], p["chain.link_mass"],
                                          drive.pitch, chain_speed, length),
    }
    modes["sprocket_1"], modes["sprocket_2"] = _sprocket_modes(scene)
    m["tight_span_mode_hz"], m["slack_span_mode_hz"] = modes["tight_span"], modes["slack_span"]
    m["sprocket_mode_1_hz"], m["sprocket_mode_2_hz"] = modes["sprocket_1"], modes["sprocket_2"]
    m["resonance"], m["resonance_with"], m["resonance_detuning"] = resonances(f_mesh, modes, band)

    keep = freqs <= spectrum_max_hz
    df = float(freqs[1]) if len(freqs) > 1 else math.nan
    spectrum = np.concatenate([[df], amps[keep]])
    return m, spectrum
