"""The sweep's figures (matplotlib, Agg canvas, never pyplot):

* :func:`plot_campbell`: waterfall / Campbell diagram - the tight-span tension spectrum of each
  case over the swept speed (colour: amplitude, log scale), with the meshing frequency, its
  half and harmonics, and the span and sprocket natural frequencies of each case drawn over it;
  cases that hit a resonance are marked. One panel per value of the other varied settings (a
  random design: the spectral peaks as points).
* :func:`plot_resonance_map`: a metric (default: the tight span's midspan deflection amplitude
  at the modal levels, its tension ripple otherwise) over the first two varied settings, with
  the curves on which the meshing frequency equals a span or sprocket mode or twice it (the
  lines of exact external and parametric resonance), in the spirit of seed 004 Fig. 8b.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Sequence

import numpy as np

from ...plots import require_matplotlib
from .table import as_float_array

__all__ = ["plot_campbell", "plot_resonance_map", "speed_axis", "default_map_metric",
           "axis_label"]

from ...units import RPM  # noqa: E402  (one definition: chainmodel.units)
_MAX_PANELS = 6


def _figure(figsize):
    """A Figure on an Agg canvas with fixed margins (matplotlib's constrained layout costs
    seconds on a multi-panel figure)."""
    require_matplotlib()
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    fig = Figure(figsize=figsize)
    FigureCanvasAgg(fig)
    return fig


#: units of the scene settings a study can vary (chainmodel.scene.SETTINGS)
SETTING_UNITS = {"input_speed_rpm": "rpm", "input_speed": "rad/s", "load_torque": "N.m",
                 "static_tension": "N", "ramp_time": "s", "duration": "s",
                 "output_interval": "s", "fidelity": "-"}


def axis_label(name: str) -> str:
    """``name [unit]`` for a varied setting, a parameter (its schema unit) or a metric column
    (:data:`~.metrics.METRIC_UNITS`); ``[-]`` for a dimensionless one."""
    from ...parameters import BY_NAME, canonical_name
    from .metrics import METRIC_UNITS
    if name in SETTING_UNITS:
        unit = SETTING_UNITS[name]
    elif name in METRIC_UNITS:
        unit = METRIC_UNITS[name]
    else:
        spec = BY_NAME.get(canonical_name(name) or "")
        unit = spec.unit if spec is not None else ""
    return f"{name} [{unit or '-'}]"


def speed_axis(varied: Sequence[str]) -> tuple[str, str, float]:
    """(column, axis label, factor to the plotted unit) of the x axis: the input speed in rpm
    where the study varies it, else the first varied setting."""
    if "input_speed_rpm" in varied:
        return "input_speed_rpm", "input speed [rpm]", 1.0
    if "input_speed" in varied:
        return "input_speed", "input speed [rpm]", 1.0 / RPM
    return varied[0], axis_label(varied[0]), 1.0


def default_map_metric(cols: dict) -> str:
    """The span amplitude (midspan deflection amplitude) where it moves, else the tension
    ripple."""
    a = as_float_array(cols["midspan_deflection_amplitude_m"])
    fid = [c for c in cols.get("fidelity", []) if c is not None]
    if np.nanmax(np.nan_to_num(a, nan=0.0)) > 0 and (not fid or all(
            str(f) in ("2", "3", "modal", "multibody") for f in fid)):
        return "midspan_deflection_amplitude_m"
    return "tight_tension_ripple_rms_n"


def _groups(cols: dict, varied: Sequence[str], x: str) -> list[tuple[str, np.ndarray]]:
    """(title, row indices) per combination of the varied settings other than ``x``."""
    others = [v for v in varied if v != x]
    n = len(cols["case"])
    keys: dict[tuple, list[int]] = {}
    for i in range(n):
        keys.setdefault(tuple(cols[o][i] for o in others), []).append(i)
    try:
        items = sorted(keys.items())
    except TypeError:                   # mixed types: order by their text
        items = sorted(keys.items(), key=lambda kv: tuple(str(k) for k in kv[0]))
    if len(items) > _MAX_PANELS:
        pick = np.linspace(0, len(items) - 1, _MAX_PANELS).round().astype(int)
        items = [items[k] for k in pick]
    return [(", ".join(f"{o} = {v:g}" if isinstance(v, (int, float)) else f"{o} = {v}"
                       for o, v in zip(others, key)) or "all cases", np.array(idx))
            for key, idx in items]


def _overlay(ax, xs, cols, idx, order):
    mesh = as_float_array(cols["meshing_frequency_hz"])[idx][order]
    for k, style in ((0.5, ":"), (1, "-"), (2, "--"), (3, "--")):
        ax.plot(xs, k * mesh, style, color="white", lw=0.9, alpha=0.8)
        if len(xs):
            ax.annotate(f"{k:g}x mesh" if k != 1 else "mesh", (xs[-1], k * mesh[-1]),
                        color="white", fontsize=7, ha="right", va="bottom")
    for name, colour in (("tight_span_mode_hz", "tab:cyan"), ("slack_span_mode_hz", "tab:olive"),
                         ("sprocket_mode_1_hz", "tab:orange"), ("sprocket_mode_2_hz", "tab:red")):
        f = as_float_array(cols[name])[idx][order]
        if np.any(np.isfinite(f)):
            ax.plot(xs, f, "-.", color=colour, lw=1.0, label=name.replace("_hz", ""))
    hit = np.array([bool(v) for v in np.array(cols["resonance"], dtype=object)[idx][order]])
    if hit.any():
        ax.plot(xs[hit], mesh[hit], "o", mfc="none", mec="red", ms=6, label="resonance hit")


def plot_campbell(cols: dict, spectra, varied: Sequence[str], path: str | Path,
                  design: str = "grid", title: str = "") -> Path:
    """Waterfall / Campbell diagram of the tight-span tension spectra (module docstring)."""
    from matplotlib.colors import LogNorm
    x_name, x_label, factor = speed_axis(varied)
    spec = {case: (f, a) for case, f, a in spectra}
    cases = np.array(cols["case"])
    xall = as_float_array(cols[x_name]) * factor
    groups = _groups(cols, varied, x_name) if design == "grid" else [("all cases",
                                                                     np.arange(len(cases)))]
    ncol = min(len(groups), 3)
    nrow = math.ceil(len(groups) / ncol)
    fig = _figure((5.0 * ncol + 1.2, 3.8 * nrow + 0.6))
    axes = np.atleast_1d(fig.subplots(nrow, ncol, squeeze=False)).ravel()
    fig.subplots_adjust(left=0.9 / fig.get_figwidth(), right=1 - 1.3 / fig.get_figwidth(),
                        bottom=0.6 / fig.get_figheight(), top=1 - 0.6 / fig.get_figheight(),
                        wspace=0.25, hspace=0.35)
    fmax = max((float(f[-1]) for f, _ in spec.values() if len(f)), default=1.0)
    amax = max((float(np.max(a)) for _, a in spec.values() if len(a)), default=1.0)
    norm = LogNorm(vmin=max(amax * 1e-3, 1e-12), vmax=max(amax, 1e-11))
    image = None
    for ax, (label, idx) in zip(axes, groups):
        idx = np.array([i for i in idx if cases[i] in spec], int)
        order = np.argsort(xall[idx], kind="stable")
        xs = xall[idx][order]
        if design == "grid" and len(idx) >= 2:
            df = min(float(spec[cases[i]][0][1]) for i in idx)
            grid = np.arange(0.0, fmax + df, df)
            z = np.array([np.interp(grid, *spec[cases[i]], right=np.nan) for i in idx[order]]).T
            edges = np.concatenate([[xs[0] - (xs[1] - xs[0]) / 2], (xs[1:] + xs[:-1]) / 2,
                                    [xs[-1] + (xs[-1] - xs[-2]) / 2]])
            fedges = np.concatenate([grid - df / 2, [grid[-1] + df / 2]])
            image = ax.pcolormesh(edges, fedges, np.clip(z, norm.vmin, None), norm=norm,
                                  cmap="viridis", shading="flat")
            ax.set_facecolor("black")
        else:
            for k in (1, 2, 3):
                f = as_float_array(cols[f"tension_peak_{k}_hz"])[idx][order]
                a = as_float_array(cols[f"tension_peak_{k}_n"])[idx][order]
                image = ax.scatter(xs, f, c=np.clip(a, norm.vmin, None), norm=norm, s=12,
                                   cmap="viridis")
            ax.set_facecolor("black")
        _overlay(ax, xs, cols, idx, order)
        ax.set_ylim(0, fmax)
        ax.set_xlabel(x_label)
        ax.set_ylabel("frequency [Hz]")
        ax.set_title(label, fontsize=9)
    for ax in axes[len(groups):]:
        ax.set_visible(False)
    if image is not None:
        w, h = fig.get_figwidth(), fig.get_figheight()
        cax = fig.add_axes([1 - 1.0 / w, 0.6 / h, 0.18 / w, 1 - 1.2 / h])
        fig.colorbar(image, cax=cax, label="tight-span tension amplitude [N]")
    if axes[0].get_legend_handles_labels()[0]:     # overlay lines drawn (else no legend)
        axes[0].legend(fontsize=7, loc="upper left")
    fig.suptitle(title or "Campbell diagram of the tight-span tension")
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path


def plot_resonance_map(cols: dict, varied: Sequence[str], path: str | Path,
                       metric: str | None = None, design: str = "grid", title: str = "") -> Path:
    """``metric`` over the first two varied settings (x: the speed where varied), with the
    lines of exact resonance (module docstring)."""
    metric = metric or default_map_metric(cols)
    if metric not in cols:
        raise ValueError(f"unknown metric {metric!r} for the resonance map; choose one of "
                         f"{', '.join(k for k in cols if k not in ('case', 'status', 'error'))}")
    x_name, x_label, factor = speed_axis(varied)
    others = [v for v in varied if v != x_name]
    fig = _figure((7.0, 5.0))
    ax = fig.subplots()
    fig.subplots_adjust(left=0.13, right=0.97, bottom=0.11, top=0.93)
    x = as_float_array(cols[x_name]) * factor
    z = as_float_array(cols[metric])
    sel = np.ones(len(x), bool)
    note = ""
    for o in others[1:]:             # more than two varied: the first value of the rest
        first = cols[o][0]
        sel &= np.array([v == first for v in cols[o]])
        note += f", {o} = {first}"
    if not others:
        ax.plot(x[sel], z[sel], "o-")
        ax.set_xlabel(x_label)
        ax.set_ylabel(axis_label(metric))
    else:
        y_name = others[0]
        y = as_float_array(cols[y_name])
        xs, ys, zs = x[sel], y[sel], z[sel]
        ux, uy = np.unique(xs), np.unique(ys)
        on_grid = design == "grid" and len(ux) >= 2 and len(uy) >= 2 and len(xs) == len(ux) * len(uy)
        if on_grid:
            Z = np.full((len(uy), len(ux)), np.nan)
            R = {k: np.full_like(Z, np.nan) for k in ("tight_span_mode_hz", "sprocket_mode_1_hz")}
            mesh = as_float_array(cols["meshing_frequency_hz"])[sel]
            for k in range(len(xs)):
                i, j = np.searchsorted(uy, ys[k]), np.searchsorted(ux, xs[k])
                Z[i, j] = zs[k]
                for name in R:
                    R[name][i, j] = mesh[k] / as_float_array(cols[name])[sel][k]
            image = ax.pcolormesh(ux, uy, Z, shading="nearest", cmap="magma")
            for name, colour in (("tight_span_mode_hz", "cyan"), ("sprocket_mode_1_hz", "lime")):
                if np.sum(np.isfinite(R[name])) >= 4:
                    cs = ax.contour(ux, uy, R[name], levels=[1.0, 2.0], colors=colour,
                                    linewidths=1.2, linestyles=["-", "--"])
                    ax.clabel(cs, fmt={1.0: f"mesh = {name[:-3]}", 2.0: f"mesh = 2 {name[:-3]}"},
                              fontsize=7)
        else:
            image = ax.scatter(xs, ys, c=zs, cmap="magma", s=30)
        hit = np.array([bool(v) for v in np.array(cols["resonance"], dtype=object)[sel]])
        if hit.any():
            ax.plot(xs[hit], ys[hit], "x", color="white", ms=4, label="resonance hit")
            ax.legend(fontsize=7, loc="upper left")
        fig.colorbar(image, ax=ax, label=axis_label(metric))
        ax.set_xlabel(x_label)
        ax.set_ylabel(axis_label(y_name))
    ax.set_title(title or f"resonance map: {metric}{note}", fontsize=9)
    path = Path(path)
    fig.savefig(path, dpi=110)
    return path
