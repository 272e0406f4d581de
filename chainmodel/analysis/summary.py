"""Summary figures of a simulated run (what ``chainmodel run`` prints)."""

from __future__ import annotations

import math

import numpy as np

from ..models.limits import drive_string_frequency, nearest_span_resonance

__all__ = ["steady_window", "dominant_frequency", "tooth_ratio", "span_modes", "summarise"]


def steady_window(time: np.ndarray, ramp_time: float, duration: float) -> np.ndarray:
    """Mask of the samples treated as steady state: after the ramp and after the first half of
    the run (start-up transients of the dynamic levels have decayed by then for the presets).

    Never a sample before that start (a coarse output interval used to pull in the start-up,
    t = 0 included): with fewer than two samples there, the samples after the ramp; with fewer
    than two of those, the last sample alone. :func:`summarise` warns when the window is
    short."""
    time = np.asarray(time, float)
    start = max(ramp_time, 0.5 * duration)
    mask = time >= start - 1e-12
    if mask.sum() < 2:
        mask = time >= ramp_time - 1e-12
    if mask.sum() < 2:
        mask = np.zeros_like(time, bool)
        mask[-1] = True
    return mask


#: fewer steady samples than this and the summary warns
STEADY_SAMPLES = 8


def dominant_frequency(time: np.ndarray, signal: np.ndarray) -> tuple[float, float]:
    """Frequency [Hz] of the largest spectral peak of ``signal`` (mean removed, Hann window) and
    the FFT bin width [Hz]. Returns (nan, bin) for a constant signal."""
    n = len(signal)
    if n < 4:
        return math.nan, math.nan
    dt = float(np.mean(np.diff(time)))
    x = (signal - np.mean(signal)) * np.hanning(n)
    spec = np.abs(np.fft.rfft(x))
    freqs = np.fft.rfftfreq(n, dt)
    spec[0] = 0.0
    if not np.any(spec > 1e-12 * max(1.0, float(np.max(np.abs(signal))))):
        return math.nan, 1.0 / (n * dt)
    return float(freqs[int(np.argmax(spec))]), 1.0 / (n * dt)


def tooth_ratio(driver_angle: np.ndarray, driven_angle: np.ndarray, n_driver: int) -> float:
    """Driven / driver rotation over the largest whole number of driver tooth periods in the
    samples (so the tooth-periodic transmission error cancels); nan if less than one period
    or if the driver does not turn monotonically."""
    period = 2 * math.pi / n_driver
    span = driver_angle[-1] - driver_angle[0]
    k = math.floor(abs(span) / period + 1e-9)
    if k < 1 or not (np.all(np.diff(driver_angle) > 0) or np.all(np.diff(driver_angle) < 0)):
        return math.nan
    sign = 1.0 if span > 0 else -1.0
    order = np.argsort(driver_angle)
    end = driver_angle[0] + sign * k * period
    phi2_end = float(np.interp(end, driver_angle[order], driven_angle[order]))
    return (phi2_end - float(driven_angle[0])) / (sign * k * period)


def span_modes(drive, params, mean_speed: float, tight: float, slack: float) -> dict:
    """The spans' first string modes at their mean tensions and the meshing harmonic nearest one
    of their first three modes (:func:`chainmodel.models.limits.nearest_span_resonance`): the
    summary's ``tight_span_mode_hz``, ``slack_span_mode_hz``, ``span_resonance`` (in words)
    and ``span_resonance_detuning``. Both spans of a two-sprocket drive have the same mean
    length (the two tangents), taken over a tooth period."""
    modes = {name: drive_string_frequency(drive, params, tension, mean_speed)
             for name, tension in (("tight", tight), ("slack", slack))}
    mesh = abs(mean_speed) * drive.n_driver / (2 * math.pi)
    span, k, n, detuning = nearest_span_resonance(mesh, modes)
    words = (f"{'meshing' if k == 1 else f'{k} x meshing'} on the {span} span's mode {n}"
             if span else "none (at rest, or no span in tension)")
    if span and detuning > 0.5 and n == 3:
        # the meshing above every span's third mode: among the dense higher modes (spaced by
        # f_1, the polygon's forcing falling as 1 / m) some mode is always near it, so the
        # row names none rather than mode 3 at +80 % (an audit read "+489 %" as clear)
        ratios = {name: mesh / f for name, f in modes.items() if f > 0.0}
        text = ", ".join(f"{r:.3g} x the {name} span's" for name, r in ratios.items())
        words = (f"none of modes 1-3: the meshing is {text} first mode, among their dense "
                 f"higher modes (level 3 holds them; level 2 with modal.modes)")
        detuning = math.nan
    return {"tight_span_mode_hz": modes["tight"], "slack_span_mode_hz": modes["slack"],
            "span_resonance": words, "span_resonance_detuning": detuning}


#: the window's mean span tension difference may miss the load's by this share of it before
#: the window is called not steady; judged only where the load's asks at least UNSTEADY_SUM of
#: the spans' mean sum (at no load the span roles' small differences on a sagging or inclined
#: chain, a newton on 30, are not the load's)
UNSTEADY_SHARE = 0.10
UNSTEADY_SUM = 0.05


def unsteady_window(scene, mask, result, tight, slack) -> str | None:
    """A warning where the steady window's means break the driven sprocket's torque balance:
    mean(tight - slack) against |load + driven.damping x mean driven speed| / (z2 p / 2 pi),
    the sprocket's mean lever arm over a tooth period (R sin(pi/z) / (pi/z) with R the pitch
    radius). In a steady state the two agree at every level (the span roles' own check; 0.5 %
    on an audit's 13 drives); what is left is the driven side's inertia times its mean
    acceleration over the window, a start still ringing down or spinning up (an audit's 12B
    drive with a 2 kg.m2 machine: -19 to -31 % in a 1 s run, within 7 % in 4 s)."""
    if scene.operating.speed == 0.0 or tight.size < 2:
        return None
    d, p = scene.drive, scene.parameters
    w2 = float(np.mean(result["driven.speed"][mask]))
    arm = d.n_driven * d.pitch / (2 * math.pi)
    need = abs(scene.operating.load_torque + p["driven.damping"] * w2) / arm
    got = float(np.mean(tight) - np.mean(slack))
    miss = got - need
    if (need < UNSTEADY_SUM * float(np.mean(tight) + np.mean(slack))
            or abs(miss) <= UNSTEADY_SHARE * need):
        return None
    start = float(result.time[mask][0])
    return (f"the steady window from {start:g} s is not steady: the spans' mean tension "
            f"difference there is {got:.4g} N where the load asks {need:.4g} N (its torque and "
            f"the driven damping over the driven sprocket's mean arm z2 p / 2 pi, "
            f"{arm * 1e3:.4g} mm), {100 * miss / need:+.3g} %: the "
            f"driven side is still ringing down or spinning up from the start (its inertia, "
            f"driven.inertia = {p['driven.inertia']:g} kg.m2, times its mean acceleration over "
            f"the window), so the means carry the start; run longer than {float(result.time[-1]):g} s")


def summarise(result) -> dict:
    """Key figures of a :class:`chainmodel.simulation.Result` (SI units, snake_case keys)."""
    t = result.time
    scene = result.scene
    mask = steady_window(t, scene.operating.ramp_time, t[-1])
    tight, slack = result["tight_span.tension"][mask], result["slack_span.tension"][mask]
    phi1, phi2 = result["driver.angle"][mask], result["driven.angle"][mask]
    drive = scene.drive
    freq, df = dominant_frequency(t[mask], result["driven.speed"][mask])
    mean_speed = float(np.mean(result["driver.speed"][mask]))
    warnings = []
    n_steady = int(mask.sum())
    if n_steady < STEADY_SAMPLES:
        warnings.append(f"the steady window from {float(t[mask][0]):g} s holds only {n_steady} "
                        f"sample(s): the means and peaks are rough; use a smaller output "
                        f"interval (now {scene.output_interval:g} s) or a longer run")
    mesh = abs(mean_speed) * drive.n_driver / (2 * math.pi)
    dt = float(np.mean(np.diff(t))) if len(t) > 1 else math.inf
    if mesh > 0 and mesh >= 0.5 / dt:
        warnings.append(f"the output interval {dt:g} s cannot resolve the meshing frequency "
                        f"{mesh:.4g} Hz (it needs less than {0.5 / mesh:.3g} s, two samples per "
                        "tooth period): the dominant frequency would be an alias and is not "
                        "reported, the peaks miss the tooth-periodic ripple, and the means are "
                        "taken at few phases of the tooth period (at one sample per period, at "
                        "one phase: biased by up to the ripple)")
        freq = math.nan
    turned = abs(float(phi1[-1] - phi1[0])) if phi1.size else 0.0
    if scene.operating.speed == 0.0:
        # held at rest: no tooth period to average over (the driver's residual speed, a
        # vibration about rest, is not a running speed: it asked for runs of 1e13 s)
        if phi1.size:
            warnings.append("the input shaft is held at rest: there is no tooth period, so "
                            "the tooth ratio is not defined (reported as n/a) and the means "
                            "are those of the drive at rest")
    elif mesh > 0 and turned < 2 * math.pi / drive.n_driver:
        need = (2 * math.pi / drive.n_driver) / abs(mean_speed)
        warnings.append(f"the steady window from {float(t[mask][0]):g} s holds less than one "
                        f"driver tooth period ({need:.3g} s at {abs(mean_speed):.4g} rad/s): the "
                        "tooth ratio is not defined (reported as n/a) and the ripples are partial; "
                        f"run for at least {scene.operating.ramp_time + 2 * need:.3g} s")
    elif phi1.size > 1 and not (np.all(np.diff(phi1) > 0) or np.all(np.diff(phi1) < 0)):
        # tooth_ratio's other n/a: a driver that turns back within the window (a soft input
        # shaft ringing, a driven inertia pulling the chain round)
        w1 = result["driver.speed"][mask]
        warnings.append(f"the driver sprocket stops or turns back within the steady window from "
                        f"{float(t[mask][0]):g} s (its speed between {float(np.min(w1)):.4g} "
                        f"and {float(np.max(w1)):.4g} rad/s about a mean of {mean_speed:.4g}): "
                        "the tooth ratio over whole driver tooth periods is not defined "
                        "(reported as n/a); the driver's vibration about its mean speed is "
                        "what to look at (input_shaft.stiffness, the driven inertia)")
    unsteady = unsteady_window(scene, mask, result, tight, slack)
    if unsteady:
        warnings.append(unsteady)
    ramp = scene.operating.ramp_time
    if scene.operating.speed != 0.0 and float(t[-1]) < ramp:
        warnings.append(f"the run ends at {float(t[-1]):g} s, inside the input's speed ramp of "
                        f"{ramp:g} s: the drive never reached its operating speed, and every "
                        f"figure is of the start; run for at least {ramp + 0.5:g} s (or set a "
                        "shorter ramp_time)")
    found = getattr(result, "problems", [])
    warnings += [p.text for p in found]
    # power into the input shaft: negative where the load drives the chain (an overrunning
    # load, or reverse drive with the load's sign)
    input_power = float(np.mean(result["input_shaft.torque"][mask] * result["driver.speed"][mask]))
    out = {
        "scene": scene.name,
        "fidelity": result.fidelity_name,
        "duration_s": float(t[-1]),
        "steady_from_s": float(t[mask][0]),
        "input_speed_rpm": scene.operating.speed * 60 / (2 * math.pi),
        "load_torque_nm": scene.operating.load_torque,
        "static_span_tension_n": result.static_tension,
        "mean_tight_tension_n": float(np.mean(tight)),
        "peak_tight_tension_n": float(np.max(tight)),
        "mean_slack_tension_n": float(np.mean(slack)),
        "peak_slack_tension_n": float(np.max(slack)),
        "min_tight_tension_n": float(np.min(tight)),
        "min_slack_tension_n": float(np.min(slack)),
        # a slack link (level 3) or span (levels 0-2) shows as a zero minimum link tension
        "min_link_tension_n": float(np.min(result["chain.min_link_tension"][mask])),
        "slack_link_time_fraction": float(np.mean(result["chain.min_link_tension"][mask] <= 0.0)),
        "mean_input_torque_nm": float(np.mean(result["input_shaft.torque"][mask])),
        "mean_input_power_w": input_power,
        "tooth_ratio": tooth_ratio(phi1, phi2, drive.n_driver),
        "exact_tooth_ratio": drive.n_driver / drive.n_driven,
        "mean_driven_speed_rad_s": float(np.mean(result["driven.speed"][mask])),
        "driven_speed_ripple_rms_rad_s": float(np.std(result["driven.speed"][mask])),
        "dominant_frequency_hz": freq,
        "frequency_resolution_hz": df,
        "meshing_frequency_hz": mesh,
        # a scene set to rest has no meshing (its mean speed is round-off, not a frequency)
        **span_modes(drive, scene.parameters, mean_speed if scene.operating.speed else 0.0,
                     float(np.mean(tight)), float(np.mean(slack))),
        "wall_time_s": result.wall_time,
        "real_time_factor": float(t[-1] / result.wall_time) if result.wall_time > 0 else math.inf,
        # through the FMU: the part of the wall time before the first step (instantiation with
        # its embedded import and cached-kernel load, parameters, initialization)
        "startup_time_s": (float(result.stats["startup_time"])
                           if "startup_time" in (result.stats or {}) else None),
        "warnings": warnings,
        # False when a validity problem makes the figures meaningless (chainmodel.validity)
        "valid": not any(p.invalid for p in found),
    }
    return out
