"""Figures for the ``chainmodel`` command (matplotlib is the optional ``plot`` extra).

Every function draws on a :class:`matplotlib.figure.Figure` with an Agg canvas and writes the
format of the file's extension (.png, .pdf or .svg; :func:`check_plot_path` refuses others);
pyplot and its global backend are never touched, so calling these from a notebook or a GUI
program leaves the host's matplotlib state alone.

* :func:`plot_run`: a simulated run, panels after seed 003 section 7 — span tensions over time
  (its Fig. 7), transmission error, torsional vibration of both sprockets (speed minus its
  mean) and their amplitude spectra with the meshing frequency marked (its Fig. 10); at the
  modal and multibody levels (2-3, which model the spans' transverse motion) the tight span's
  midspan deflection over time and its amplitude spectrum; when the model kept snapshots
  with roller positions (the multibody level), the chain's shape and the
  x/y motion of a roller crossing the tight span (its Fig. 8). Panels whose data are missing
  are left out.
* :func:`plot_kinematics`: driven-sprocket position, velocity ratio and acceleration over one
  tooth period from seating, seating (▽) and release (△) marked, exact solid and approximate
  dashed (seed 000 Fig. 4).
* :func:`plot_wrap`: wrapping-length variation (L - L_mean) / p over one tooth period (seed 004
  Fig. 2).

The kinematics and wrap figures take the same dict the CLI prints with ``--json``, so a figure
always shows the numbers the JSON reports.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Mapping

import numpy as np

__all__ = ["PlottingUnavailable", "require_matplotlib", "amplitude_spectrum", "plot_run",
           "plot_kinematics", "plot_wrap", "PLOT_FORMATS", "check_plot_path"]

#: file extensions a figure can be written as (matplotlib's Agg, PDF and SVG backends)
PLOT_FORMATS = (".png", ".pdf", ".svg")

INSTALL_HINT = "pip install 'chaindrive[plot]' (or pip install matplotlib)"


class PlottingUnavailable(ImportError):
    """matplotlib is not installed."""


def require_matplotlib() -> None:
    """Raise :class:`PlottingUnavailable` with an actionable message if matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
        from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: F401
        from matplotlib.figure import Figure  # noqa: F401
    except ImportError as exc:
        raise PlottingUnavailable(f"--plot needs matplotlib, which is not installed: "
                                  f"{INSTALL_HINT}") from exc


def check_plot_path(path: str | Path, flag: str = "--plot") -> str:
    """The format of a figure file from its extension ("png", "pdf" or "svg"); ValueError
    naming the allowed extensions for any other (called before the work, so a typo costs
    nothing)."""
    suffix = Path(path).suffix.lower()
    if suffix not in PLOT_FORMATS:
        raise ValueError(f"{flag} {path}: cannot write a figure as "
                         f"{repr(suffix) if suffix else 'a file without an extension'}; "
                         f"name the file with one of {', '.join(PLOT_FORMATS)}")
    return suffix[1:]


def _figure(figsize: tuple[float, float]):
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _save(fig, path: str | Path) -> Path:
    path = Path(path)
    fig.savefig(path, dpi=110, format=check_plot_path(path))
    return path


# --- signal helpers ---------------------------------------------------------------------------

def amplitude_spectrum(time: np.ndarray, signal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Single-sided amplitude spectrum of ``signal`` (mean removed, Hann window, amplitude
    corrected so a sinusoid of amplitude A shows a peak of about A). Returns (f [Hz], amplitude
    in the signal's unit)."""
    n = len(signal)
    if n < 4:
        return np.zeros(0), np.zeros(0)
    dt = float(np.mean(np.diff(time)))
    w = np.hanning(n)
    spec = np.abs(np.fft.rfft((signal - np.mean(signal)) * w)) * 2.0 / np.sum(w)
    return np.fft.rfftfreq(n, dt), spec


def _mark_meshing(ax, f_mesh: float, f_max: float) -> None:
    if not (math.isfinite(f_mesh) and f_mesh > 0):
        return
    ax.axvline(f_mesh, color="k", ls="--", lw=0.8, label=f"meshing {f_mesh:.4g} Hz")
    k = 2
    while k * f_mesh < f_max and k <= 12:
        ax.axvline(k * f_mesh, color="0.6", ls=":", lw=0.7)
        k += 1


# --- run --------------------------------------------------------------------------------------

def _snapshot_rollers(result) -> list[tuple[float, np.ndarray]]:
    """(t, roller_positions) of the snapshots that carry an (M, 2) array of roller positions."""
    out = []
    for item in getattr(result, "snapshots", None) or []:
        try:
            t, snap = item
            pos = np.asarray(snap.get("roller_positions"), float)
        except (TypeError, ValueError, AttributeError):
            continue
        if pos.ndim == 2 and pos.shape[1] == 2 and len(pos) >= 3 and np.all(np.isfinite(pos)):
            out.append((float(t), pos))
    return out


def _rigid_layout(drive, result, t: float) -> np.ndarray | None:
    """Roller positions of the rigid chain at the run's sprocket angles at time ``t`` (None if
    the drive has no link count or the layout cannot be built)."""
    from .kinematics import roller_positions
    try:
        phi1 = float(np.interp(t, result.time, result["driver.angle"]))
        phi2 = float(np.interp(t, result.time, result["driven.angle"]))
        return roller_positions(drive, phi1, phi2)
    except (ValueError, KeyError, RuntimeError):
        return None


def _draw_geometry(ax, drive, snaps, result) -> None:
    t, pos = snaps[-1]
    rigid = _rigid_layout(drive, result, t)
    for centre, sprocket in (((0.0, 0.0), drive.driven), ((drive.x_c, drive.y_c), drive.driver)):
        phi = np.linspace(0, 2 * math.pi, 200)
        ax.plot(1e3 * (centre[0] + sprocket.pitch_radius * np.cos(phi)),
                1e3 * (centre[1] + sprocket.pitch_radius * np.sin(phi)), color="0.75", lw=0.8)
    if rigid is not None and rigid.shape == pos.shape:
        loop = np.vstack([rigid, rigid[:1]])
        ax.plot(1e3 * loop[:, 0], 1e3 * loop[:, 1], ls="--", color="0.5", lw=0.8,
                label="rigid chain (kinematics)")
    loop = np.vstack([pos, pos[:1]])
    ax.plot(1e3 * loop[:, 0], 1e3 * loop[:, 1], "o-", ms=2.5, lw=0.8, color="C0",
            label="model rollers")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [mm]")
    ax.set_ylabel("y [mm]")
    ax.set_title(f"chain at t = {t:.4g} s")
    ax.legend(fontsize="small", loc="upper right")


def _tight_span_track(drive, snaps, result, t_start: float):
    """Times and positions of the roller that enters the tight span first after ``t_start``,
    over its traverse of the span. Returns (index, t, xy, rigid_xy or None)
    or None when there is nothing to show."""
    from .kinematics import chain_geometry
    times = np.array([t for t, _ in snaps])
    first = int(np.searchsorted(times, t_start - 1e-12))
    if first >= len(snaps) - 2:
        first = 0
    t0, pos0 = snaps[first]
    try:
        phi1 = float(np.interp(t0, result.time, result["driver.angle"]))
        phi2 = float(np.interp(t0, result.time, result["driven.angle"]))
        start = chain_geometry(drive, np.array([phi1]), np.array([phi2])).upper.start[0]
    except (ValueError, KeyError, RuntimeError):
        return None
    # the roller nearest the tight span's driven endpoint: it is about to cross the span
    index = int(np.argmin(np.hypot(pos0[:, 0] - start.real, pos0[:, 1] - start.imag)))
    speed = abs(float(np.mean(result["driver.speed"][result.time >= t0])))
    if not speed > 0:
        return None
    chain_speed = speed * drive.n_driver * drive.pitch / (2 * math.pi)
    # from the driven endpoint to the seat on the driver: one span length at the chain speed
    traverse = float(np.mean(result["tight_span.length"])) / chain_speed
    sel = [k for k in range(first, len(snaps)) if snaps[k][0] <= t0 + traverse]
    if len(sel) < 3 or any(len(snaps[k][1]) <= index for k in sel):
        return None
    t = times[sel]
    xy = np.array([snaps[k][1][index] for k in sel])
    rigid = []
    for k in sel:
        r = _rigid_layout(drive, result, snaps[k][0])
        if r is None or len(r) <= index:
            rigid = None
            break
        rigid.append(r[index])
    if rigid is not None:
        rigid = np.array(rigid)
        # same roller numbering? (the rigid layout must start where the model's roller is)
        if np.hypot(*(rigid[0] - xy[0])) > 0.5 * drive.pitch:
            rigid = None
    return index, t, xy, rigid


def _draw_track(fig, cell, track) -> None:
    """x and y of the tracked roller: its deviation from the rigid chain's roller (the
    vibration) when the rigid layout numbers rollers the same way, else the raw coordinates."""
    index, t, xy, rigid = track
    sub = cell.subgridspec(2, 1, hspace=0.05)
    ax_x = fig.add_subplot(sub[0])
    ax_y = fig.add_subplot(sub[1], sharex=ax_x)
    for k, (ax, name) in enumerate(((ax_x, "x"), (ax_y, "y"))):
        if rigid is not None:
            ax.plot(t, 1e3 * (xy[:, k] - rigid[:, k]), color="C0", lw=1.0)
            ax.set_ylabel(f"Δ{name} [mm]")
        else:
            ax.plot(t, 1e3 * xy[:, k], color="C0", lw=1.0)
            ax.set_ylabel(f"{name} [mm]")
        ax.grid(alpha=0.3)
    what = "minus the rigid chain's" if rigid is not None else "position"
    ax_x.set_title(f"roller {index} crossing the tight span ({what})")
    ax_x.tick_params(labelbottom=False)
    ax_y.set_xlabel("time [s]")


def _draw_midspan(fig, grid, row: int, result, mask, f_mesh: float) -> None:
    """Tight span's midspan deflection over the run, and its amplitude spectrum over the
    steady part with the meshing frequency and its harmonics marked (a span excited
    parametrically answers near its own natural frequency, seed 004 section 5)."""
    t = np.asarray(result.time, float)
    w = 1e3 * np.asarray(result["tight_span.midspan_deflection"], float)
    ax = fig.add_subplot(grid[row, 0])
    ax.plot(t, w, lw=0.9, color="C4")
    ax.axhline(0.0, color="k", lw=0.5)
    ax.set_xlabel("time [s]")
    ax.set_ylabel("midspan deflection [mm]")
    ax.set_title("tight span: transverse deflection at midspan")
    ax.grid(alpha=0.3)
    ax = fig.add_subplot(grid[row, 1])
    f, amp = amplitude_spectrum(t[mask], w[mask])
    if len(f):
        ax.plot(f, amp, lw=0.9, color="C4", label="tight span, midspan")
        f_max = float(f[-1])
        if math.isfinite(f_mesh) and f_mesh > 0:
            f_peak = float(f[int(np.argmax(amp))]) if np.any(amp > 0) else 0.0
            f_max = min(f_max, max(6.5 * f_mesh, 1.25 * f_peak))
        _mark_meshing(ax, f_mesh, f_max)
        if f_max > 0:
            ax.set_xlim(0, f_max)
        ax.legend(fontsize="small")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [mm]")
    ax.set_title("amplitude spectrum of the midspan deflection (steady part)")
    ax.grid(alpha=0.3)


def plot_run(result, path: str | Path, summary: Mapping[str, Any] | None = None) -> Path:
    """Figure of a simulated run (module docstring) as the format of ``path``'s extension
    (:data:`PLOT_FORMATS`); returns the path written."""
    from .analysis.summary import steady_window
    summary = dict(summary or result.summary())
    scene, drive = result.scene, result.scene.drive
    t = np.asarray(result.time, float)
    mask = steady_window(t, scene.operating.ramp_time, t[-1])
    ts = t[mask]
    f_mesh = float(summary.get("meshing_frequency_hz", math.nan))
    snaps = _snapshot_rollers(result)
    track = _tight_span_track(drive, snaps, result, ts[0]) if snaps else None
    # levels 0-1 give only the static sag there (a constant): no panel for it
    span_row = 2 if result.fidelity >= 2 and "tight_span.midspan_deflection" in result else None
    snap_row = (3 if span_row else 2) if snaps else None
    rows = 2 + (span_row is not None) + (snap_row is not None)
    fig = _figure((12, 3.4 * rows))
    grid = fig.add_gridspec(rows, 2)
    fig.suptitle(f"{scene.name}: fidelity {result.fidelity} ({result.fidelity_name}), "
                 f"{summary.get('input_speed_rpm', math.nan):.4g} rpm, load "
                 f"{summary.get('load_torque_nm', math.nan):.4g} N.m")

    ax = fig.add_subplot(grid[0, 0])
    ax.plot(t, result["tight_span.tension"], lw=0.9, label="tight span")
    ax.plot(t, result["slack_span.tension"], lw=0.9, label="slack span")
    low = np.asarray(result["chain.min_link_tension"], float)
    ax.plot(t, low, lw=0.6, color="C3", alpha=0.8,
            label=f"weakest link (slack {100 * float(np.mean(low[mask] <= 0)):.2g} % of steady time)")
    ax.axhline(0.0, color="k", lw=0.5)
    if math.isfinite(result.static_tension):
        ax.axhline(result.static_tension, color="0.5", ls=":", lw=0.8, label="static tension")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("tension [N]")
    ax.set_title("span tensions")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(grid[0, 1])
    ax.plot(t, 1e3 * result["transmission_error"], lw=0.9, color="C2")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("transmission error [mrad]")
    ax.set_title("driven angle minus mean-ratio angle")
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(grid[1, 0])
    spectra = []
    for name, label, colour in (("driver.speed", "driver", "C0"), ("driven.speed", "driven", "C1")):
        w = np.asarray(result[name], float)[mask]
        ax.plot(ts, w - np.mean(w), lw=0.9, color=colour,
                label=f"{label} (mean {np.mean(w):.4g} rad/s)")
        spectra.append((label, colour, *amplitude_spectrum(ts, w)))
    ax.set_xlabel("time [s]")
    ax.set_ylabel("speed minus mean [rad/s]")
    ax.set_title("torsional vibration (steady part)")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)

    ax = fig.add_subplot(grid[1, 1])
    f_top = f_peak = 0.0
    for label, colour, f, amp in spectra:
        if len(f):
            ax.plot(f, amp, lw=0.9, color=colour, label=label)
            f_top = max(f_top, float(f[-1]))
            if np.any(amp > 0):
                f_peak = max(f_peak, float(f[int(np.argmax(amp))]))
    # the first harmonics of the meshing frequency, and the largest peak wherever it is
    # (a resonance above them, e.g. the driven sprocket's at level 1)
    f_max = f_top
    if math.isfinite(f_mesh) and f_mesh > 0:
        f_max = min(f_top, max(6.5 * f_mesh, 1.25 * f_peak))
    _mark_meshing(ax, f_mesh, f_max)
    if f_max > 0:
        ax.set_xlim(0, f_max)
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude [rad/s]")
    ax.set_title("amplitude spectra of the sprocket speeds")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)

    if span_row is not None:
        _draw_midspan(fig, grid, span_row, result, mask, f_mesh)
    if snaps:
        _draw_geometry(fig.add_subplot(grid[snap_row, 0]), drive, snaps, result)
        if track is not None:
            _draw_track(fig, grid[snap_row, 1], track)
        else:
            ax = fig.add_subplot(grid[snap_row, 1])
            ax.text(0.5, 0.5, "no roller crossed the tight span in the snapshots",
                    ha="center", va="center", transform=ax.transAxes)
            ax.set_axis_off()
    return _save(fig, path)


# --- kinematics -------------------------------------------------------------------------------

def _events(ax, release_fraction: float) -> None:
    tr = ax.get_xaxis_transform()
    for x in (0.0, 1.0):
        ax.plot([x], [1.0], marker="v", color="k", ms=8, transform=tr, clip_on=False, ls="")
    ax.plot([release_fraction], [0.0], marker="^", color="k", ms=8, transform=tr,
            clip_on=False, ls="")
    ax.axvline(release_fraction, color="0.6", lw=0.6, ls=":")


def _segments(x: np.ndarray, y: np.ndarray, cut: float):
    """Two pieces of a curve, before and after the release (where theta2 and the acceleration
    jump), so no vertical line is drawn across the jump."""
    before = x < cut
    return [(x[before], y[before]), (x[~before], y[~before])]


def plot_kinematics(data: Mapping[str, Any], path: str | Path) -> Path:
    """Figure like seed 000 Fig. 4 from the ``chainmodel kinematics --json`` dict (format
    from the extension of ``path``)."""
    x = np.asarray(data["tooth_period_fraction"], float)
    cut = float(data["release_fraction"])
    approx = data.get("approximate") or {}
    rows = (("theta2", "driven contact angle θ2 [rad]", "position"),
            ("velocity_ratio", "velocity ratio ω2/ω4 [-]", "velocity"),
            ("driven_acceleration", "driven acceleration [rad/s²]", "acceleration"))
    fig = _figure((7, 8.5))
    d = data["drive"]
    fig.suptitle(f"{d.get('name') or 'drive'}: {d['n_driver']}/{d['n_driven']} teeth, "
                 f"N = {d['span_pitches']}, f = {d['pitch_fraction']:.4g}, "
                 f"{data['driver_speed_rpm']:.4g} rpm  (▽ seating, △ release)")
    axes = fig.subplots(3, 1, sharex=True)
    for ax, (key, ylabel, title) in zip(axes, rows):
        for k, (xs, ys) in enumerate(_segments(x, np.asarray(data[key], float), cut)):
            ax.plot(xs, ys, color="C0", lw=1.3, label="exact" if k == 0 else None)
        if key in approx:
            for k, (xs, ys) in enumerate(_segments(x, np.asarray(approx[key], float), cut)):
                ax.plot(xs, ys, color="C1", lw=1.3, ls="--",
                        label="approximate" if k == 0 else None)
        _events(ax, cut)
        ax.set_ylabel(ylabel)
        ax.set_title(title, fontsize="medium")
        ax.grid(alpha=0.3)
        ax.set_xlim(0, 1)
    axes[0].legend(fontsize="small")
    axes[-1].set_xlabel("driver angle over one tooth period from seating [-]")
    return _save(fig, path)


# --- wrapping length --------------------------------------------------------------------------

def plot_wrap(data: Mapping[str, Any], path: str | Path) -> Path:
    """Figure like seed 004 Fig. 2 from the ``chainmodel wrap --json`` dict (format from the
    extension of ``path``)."""
    x = np.asarray(data["tooth_period_fraction"], float)
    d = data["drive"]
    p = float(d["pitch_m"])
    dl = np.asarray(data["wrap_length"], float) / p - float(data["l_mean_over_p"])
    fig = _figure((7, 4))
    ax = fig.add_subplot()
    ax.plot(x, dl, color="C0", lw=1.3,
            label=f"{d.get('name') or 'drive'}: {d['n_driver']}/{d['n_driven']}, "
                  f"N = {d['span_pitches']}, f = {d['pitch_fraction']:.4g}")
    for key, ls in (("l_min_over_p", ":"), ("l_max_over_p", ":")):
        ax.axhline(float(data[key]) - float(data["l_mean_over_p"]), color="0.5", ls=ls, lw=0.8)
    ax.axhline(0.0, color="0.3", lw=0.6)
    ax.set_xlim(0, 1)
    ax.set_xlabel("driver angle over one tooth period from seating [-]")
    ax.set_ylabel("(L - L_mean) / p [-]")
    ax.set_title(f"wrapping length: L_mean / p = {float(data['l_mean_over_p']):.4f}, range "
                 f"{float(data['l_max_over_p']) - float(data['l_min_over_p']):.3g}", fontsize="medium")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return _save(fig, path)
