"""Figure for docs/multibody.md, "Teeth the chain can wrap over": level 3's tooth as a roller
centre meets it, against the path of a roller turning about its seated neighbour.

    python docs/scripts/articulation_figure.py     # writes docs/figures/articulation_cut.png, ~10 s

Each panel is one seat of an 08A sprocket, in the seat's frame (u along the pitch circle, s
outward along the seat's radial, roller-centre coordinates). Shaded: where the kernel's
penetration (kernels.multibody_forces.geometry_pass, probed as tests/articulation_check.py
does) is positive, i.e. the tooth grown by the roller radius. Dashed: the straight flank's edge
written independently in tests/articulation_check.py. Solid: the circles of radius p about
the two seated neighbours, the paths a roller centre takes leaving or entering this seat.
On 9 teeth the straight flank reaches into those paths and the kernel's tooth is cut back to
them; on 17 teeth the flank clears them and nothing is cut.
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
from articulation_check import kernel_penetration, model_of, straight_flank_penetration  # noqa: E402


def panel(ax, z: int) -> None:
    model = model_of("08A", z)
    p = model.drive.pitch
    dR = model.flank["clearance"]
    R = p / (2 * math.sin(math.pi / z))
    ta = 2 * math.pi / z
    h = 2.5e-3 * p
    s, u = np.meshgrid(np.arange(-0.25 * p, 0.75 * p, h), np.arange(-0.6 * p, 0.6 * p, h),
                       indexing="ij")
    pts = np.stack([s.ravel(), u.ravel()], axis=1)
    pen, _ = kernel_penetration(model, pts)
    mm = 1e3
    ax.contourf(u * mm, s * mm, pen.reshape(s.shape), levels=[0.0, np.inf], colors=["0.75"])
    ax.contour(u * mm, s * mm, pen.reshape(s.shape), levels=[0.0], colors="k", linewidths=1.0)
    # this seat's straight flank only, below its tip (masked elsewhere: no edge drawn there)
    straight = straight_flank_penetration(pts[:, 0], pts[:, 1], z, p, dR)
    straight = np.ma.masked_where((np.abs(pts[:, 1]) >= p / 2) | ~np.isfinite(straight),
                                  straight)
    ax.contour(u * mm, s * mm, straight.reshape(s.shape), levels=[0.0], colors="tab:red",
               linewidths=1.2, linestyles="--")
    psi = np.linspace(0.0, 2 * math.pi, 721)
    for sign in (+1, -1):
        a = np.array([-R * (1 - math.cos(ta)), sign * R * math.sin(ta)])
        arc_s, arc_u = a[0] + p * np.cos(psi), a[1] + p * np.sin(psi)
        out = arc_s >= 0.0                   # outward of the seat centre: the roller's side
        ax.plot(np.where(out, arc_u, np.nan) * mm, np.where(out, arc_s, np.nan) * mm,
                color="tab:blue", linewidth=1.2)
        ax.plot(a[1] * mm, a[0] * mm, "o", color="tab:blue", markersize=4)
    ax.plot(0.0, 0.0, "o", color="k", markersize=4)
    cut = "cut" if model.flank["cut_driver"] else "not cut"
    ax.set_title(f"08A, {z} teeth ({cut})")
    ax.set_xlim(-0.6 * p * mm, 0.6 * p * mm)
    ax.set_ylim(-0.25 * p * mm, 0.75 * p * mm)
    ax.set_aspect("equal")
    ax.set_xlabel("u along the pitch circle [mm]")


def main() -> None:
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    fig, axes = plt.subplots(1, 2, figsize=(10, 5.6), sharey=True)
    for ax, z in zip(axes, (9, 17)):
        panel(ax, z)
    axes[0].set_ylabel("s outward from the seat centre [mm]")
    fig.legend(handles=[Patch(color="0.75", label="level 3's tooth (roller-centre space)"),
                        Line2D([], [], color="tab:red", ls="--",
                               label="straight flank (independent)"),
                        Line2D([], [], color="tab:blue",
                               label="path about a seated neighbour (radius p)")],
               loc="lower center", ncol=3, frameon=False)
    fig.suptitle("Roller-centre space of one seat: the tooth the chain can wrap over")
    fig.tight_layout(rect=(0, 0.1, 1, 0.95))
    out = ROOT / "docs" / "figures" / "articulation_cut.png"
    fig.savefig(out, dpi=110)
    print(f"wrote {out.relative_to(ROOT)}")


if __name__ == "__main__":
    main()
