"""Figures after seed 004 Figs 6-9 (matplotlib, imported lazily, Agg backend)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

__all__ = ["plot_parametric", "plot_sprocket", "plot_combined_span", "plot_combined_sprocket",
           "plot_case"]


def _plt():
    try:
        import matplotlib
    except ImportError as exc:          # pragma: no cover - depends on the installation
        raise ValueError("plotting needs matplotlib: pip install matplotlib") from exc
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def _segments(x, y, mask):
    """Runs of consecutive True in mask, as (x, y) pieces (so stable/unstable parts are drawn
    without joining across gaps)."""
    pieces, start = [], None
    for i, m in enumerate(np.append(mask & np.isfinite(y), False)):
        if m and start is None:
            start = i
        elif not m and start is not None:
            pieces.append((x[start:i], y[start:i]))
            start = None
    return pieces


def _branch(ax, x, y, stable, color, label=None):
    first = True
    for xs, ys in _segments(x, y, stable):
        ax.plot(xs, ys, "-", color=color, lw=1.6, label=label if first else None)
        first = False
    for xs, ys in _segments(x, y, ~stable):
        ax.plot(xs, ys, "--", color=color, lw=1.2)


def plot_parametric(data: dict, path, extra: list[tuple[str, dict]] = ()) -> Path:
    """Fig 6: a against Omega2/omega_m (stable solid, unstable dashed, circles from eqs
    100-101 integrated from random starts)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    curves = [("eq 105 (solid stable, dashed unstable)", data)] + list(extra)
    colors = ["k", "tab:blue", "tab:red", "tab:green"]
    for k, ((label, d), col) in enumerate(zip(curves, colors)):
        x = d["ratio"]
        _branch(ax, x, d["a_upper"], d["upper_stable"], col, label)
        _branch(ax, x, d["a_lower"], d["lower_stable"], col)
        if k == 0:                      # the trivial solution a = 0 (eq 104) of the main case
            _branch(ax, x, np.zeros_like(x), d["trivial_stable"], col)
    if "numerical_a" in data:
        xr = np.broadcast_to(data["numerical_ratio"], data["numerical_a"].shape)
        ax.plot(xr.ravel(), data["numerical_a"].ravel(), "o", mfc="none", color="k", ms=5,
                label="eqs 100-101 integrated (random starts)")
    ax.set_xlabel(r"$\Omega_2/\omega_m$ [-]")
    ax.set_ylabel(r"span amplitude $a$ of $\xi_m$ [units of $l$]")
    ax.set_title("Primary parametric resonance of the tight span (eq 105)")
    ax.legend(fontsize=8, loc="upper left")
    ax.grid(alpha=0.3)
    return _save(fig, path)


def plot_sprocket(data: dict, path, extra: list[tuple[str, dict]] = ()) -> Path:
    """Fig 7: v against Omega2/omega_theta (eq 121 line, circles from eqs 119-120)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2))
    ax.plot(data["ratio"], data["v"], "k-", label=r"eq 121, Table 2 $\mu_\theta$")
    for (label, d), col in zip(extra, ["tab:blue", "tab:red", "tab:green"]):
        ax.plot(d["ratio"], d["v"], "-", color=col, lw=1.2, label=label)
    if "numerical_v" in data:
        ax.plot(data["numerical_ratio"], data["numerical_v"], "o", mfc="none", color="k", ms=5,
                label="eqs 119-120 integrated")
    ax.set_xlabel(r"$\Omega_2/\omega_\theta$ [-]")
    ax.set_ylabel(r"sprocket amplitude $v$ of $u_1$ [units of $l$]")
    ax.set_title("Primary external resonance of the driven sprocket (eq 121)")
    ax.legend(fontsize=8)
    ax.grid(alpha=0.3)
    return _save(fig, path)


def _nearest(values, targets):
    return [int(np.argmin(np.abs(values - t))) for t in targets]


def _combined(data: dict, path, key: str, sections_axis: str, sections, title: str,
              ylabel: str) -> Path:
    plt = _plt()
    s2, si = data["sigma2_ratio"], data["sigma_i_ratio"]
    Z = data[key]
    fig, (ax0, ax1) = plt.subplots(1, 2, figsize=(11, 4.4))
    styles = ["-", "--", "-."]
    if sections_axis == "sigma_i":
        idx = _nearest(si, sections)
        for j, st in zip(idx, styles):
            ax0.plot(s2, Z[0, j], st, color="k", lw=1.2,
                     label=rf"$\sigma_i/\omega_m$ = {si[j]:.2f}")
            for r in range(1, Z.shape[0]):
                diff = np.abs(Z[r, j] - Z[0, j]) > 1e-3 * np.nanmax(Z)
                ax0.plot(s2[diff], Z[r, j][diff], "o", mfc="none", ms=4, color="tab:red",
                         label="other start (coexisting)" if j == idx[0] and r == 1 else None)
        ax0.set_xlabel(r"$\sigma_2/\omega_m$ [-]")
    else:
        idx = _nearest(s2, sections)
        for j, st in zip(idx, styles):
            ax0.plot(si, Z[0, :, j], st, color="k", label=rf"$\sigma_2/\omega_m$ = {s2[j]:.2f}")
        ax0.set_xlabel(r"$\sigma_i/\omega_m$ [-]")
    ax0.set_ylabel(ylabel)
    ax0.legend(fontsize=8)
    ax0.grid(alpha=0.3)
    m = ax1.pcolormesh(s2, si, Z[0], shading="nearest", cmap="viridis")
    fig.colorbar(m, ax=ax1, label=ylabel)
    lim = [max(s2.min(), si.min()), min(s2.max(), si.max())]
    ax1.plot(lim, lim, "w:", lw=1, label=r"$\sigma_i = \sigma_2$")
    for j in idx:
        if sections_axis == "sigma_i":
            ax1.axhline(si[j], color="w", lw=0.8)
        else:
            ax1.axvline(s2[j], color="w", lw=0.8)
    t2 = data.get("sigma_i_table2_ratio")
    if t2 is not None and si.min() <= t2 <= si.max():
        ax1.axhline(t2, color="tab:orange", lw=1, ls="--", label="C1, Table 2, 400 rpm")
    ax1.set_xlabel(r"$\sigma_2/\omega_m$ [-]")
    ax1.set_ylabel(r"$\sigma_i/\omega_m$ [-]")
    ax1.legend(fontsize=7, loc="lower right")
    fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    return _save(fig, path)


def plot_combined_span(data: dict, path, sections=(-1.9, -1.1, -0.3)) -> Path:
    """Fig 8: span amplitude a in the combined case (eqs 129-132 integrated from a small
    start; circles where the large start ends elsewhere)."""
    return _combined(data, path, "a", "sigma_i", sections,
                     "Combined parametric + internal resonance: span amplitude a "
                     f"(eqs 129-132, policy '{data['policy']}')", r"span amplitude $a$ [units of $l$]")


def plot_combined_sprocket(data: dict, path, sections=(-0.9, -0.5, 0.0)) -> Path:
    """Fig 9: sprocket amplitude v in the combined case."""
    return _combined(data, path, "v", "sigma2", sections,
                     "Combined parametric + internal resonance: sprocket amplitude v "
                     f"(eqs 129-132, policy '{data['policy']}')", r"sprocket amplitude $v$ [units of $l$]")


def plot_case(case: str, data: dict, path, extra=()) -> list[Path]:
    """The figure(s) of one CLI case; the combined case writes <stem>_span and
    <stem>_sprocket next to ``path``. ``extra``: (label, data) of further curves."""
    path = Path(path)
    if case == "parametric":
        return [plot_parametric(data, path, list(extra))]
    if case == "sprocket":
        return [plot_sprocket(data, path, list(extra))]
    stem, suffix = path.with_suffix(""), path.suffix or ".png"
    return [plot_combined_span(data, f"{stem}_span{suffix}"),
            plot_combined_sprocket(data, f"{stem}_sprocket{suffix}")]


def _save(fig, path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=130)
    import matplotlib.pyplot as plt
    plt.close(fig)
    return path
