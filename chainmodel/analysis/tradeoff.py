"""The measured trade between the fidelity levels: cost against distance from the most detailed.

``tradeoff(scene)`` runs the same scene at every requested level with its default stepper, in
one process one after the other, and reports for each level the wall time per simulated second
and how far its steady-state figures are from the reference level (3, multibody, unless told
otherwise): mean span tensions, mean input torque, the driven sprocket's speed ripple and the
dominant frequency of that ripple. This is what ``chainmodel bench`` prints and what
docs/fidelity.md records.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from ..parameters import FIDELITY_NAMES
from ..scene import Scene, load_scene
from ..simulation import run_scene
from .summary import dominant_frequency, steady_window

__all__ = ["LevelFigures", "tradeoff", "format_table", "FIGURES"]

#: (key, label, unit) of the figures compared between levels
FIGURES = (("mean_tight_tension", "mean tight tension", "N"),
           ("mean_slack_tension", "mean slack tension", "N"),
           ("mean_input_torque", "mean input torque", "N.m"),
           ("driven_speed_ripple", "driven-speed ripple RMS", "rad/s"),
           ("dominant_frequency", "dominant ripple frequency", "Hz"))


@dataclass
class LevelFigures:
    level: int
    wall_per_simulated_second: float
    figures: dict
    deviation: dict          # relative deviation from the reference level, per figure

    @property
    def name(self) -> str:
        return FIDELITY_NAMES[self.level]


def _figures(result) -> dict:
    t = result.time
    mask = steady_window(t, result.scene.operating.ramp_time, float(t[-1]))
    w = result["driven.speed"][mask]
    freq, _ = dominant_frequency(t[mask], w)
    return {"mean_tight_tension": float(np.mean(result["tight_span.tension"][mask])),
            "mean_slack_tension": float(np.mean(result["slack_span.tension"][mask])),
            "mean_input_torque": float(np.mean(result["input_shaft.torque"][mask])),
            "driven_speed_ripple": float(np.std(w)),
            "dominant_frequency": freq}


def tradeoff(scene: "str | Scene" = "xu2010", levels=(0, 1, 2, 3), reference: int = 3,
             duration: float | None = None, warmup: bool = True, progress: bool = False,
             **overrides) -> list[LevelFigures]:
    """Figures of every level in ``levels`` and their deviation from ``reference``.

    ``warmup`` runs each level once for a few milliseconds first, so one-off costs (numba
    compilation, cached geometry) do not count as the level's running cost."""
    base = load_scene(scene, **overrides)
    if duration is not None:
        base = base.with_overrides(duration=duration)
    if reference not in levels:
        levels = tuple(levels) + (reference,)
    runs = {}
    for level in levels:
        sc = base.with_overrides(fidelity=level)
        if warmup:
            if progress:    # the first use of a level can compile its kernels for a minute
                import sys
                sys.stderr.write(f"{sc.name} ({FIDELITY_NAMES[level]}): warming up (a first "
                                 "use compiles the level's kernels)...\n")
                sys.stderr.flush()
            run_scene(sc.with_overrides(duration=10 * sc.output_interval))
        wall = time.perf_counter()
        result = run_scene(sc, progress=progress)
        wall = time.perf_counter() - wall
        runs[level] = (wall / float(result.time[-1]), _figures(result))
    ref = runs[reference][1]
    out = []
    for level in levels:
        cost, figs = runs[level]
        dev = {k: (figs[k] - ref[k]) / ref[k] if ref[k] not in (0.0,) and math.isfinite(ref[k])
               else math.nan for k in figs}
        out.append(LevelFigures(level, cost, figs, dev))
    return out


def format_table(rows: list[LevelFigures], reference: int = 3) -> str:
    """A Markdown table: cost and each figure with its deviation from the reference level."""
    head = "| level | wall s per simulated s | " + " | ".join(
        f"{label} [{unit}]" for _, label, unit in FIGURES) + " |"
    lines = [head, "|" + "---|" * (2 + len(FIGURES))]
    for r in rows:
        cells = [f"{r.level} {r.name}", f"{r.wall_per_simulated_second:.3g}"]
        for key, _, _ in FIGURES:
            v, d = r.figures[key], r.deviation[key]
            if r.level == reference or not math.isfinite(d):
                cells.append(f"{v:.4g}")
            else:
                cells.append(f"{v:.4g} ({100 * d:+.1f} %)")
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


# --- CLI: chainmodel bench ------------------------------------------------------------------

def register(subparsers) -> None:
    p = subparsers.add_parser(
        "bench", help="the fidelity ladder's measured trade: cost and distance from level 3",
        description="Run one scene at every fidelity level with its default stepper and print "
                    "wall seconds per simulated second and the steady-state figures of each "
                    "level with their deviation from the reference level (default 3, multibody).")
    p.add_argument("scene", nargs="?", default="xu2010",
                   help="preset name or scene .toml; 'tradeoff' runs the study of many scenes "
                        "and steppers (chainmodel.analysis.trade_study, docs/tradeoff.md)")
    p.add_argument("--levels", default="0,1,2,3", help="comma-separated levels (default 0,1,2,3)")
    p.add_argument("--reference", type=int, default=3, help="reference level (default 3)")
    p.add_argument("--duration", type=float, default=None, metavar="S",
                   help="simulated seconds (default: the scene's)")
    p.add_argument("--output-interval", type=float, default=None, metavar="S",
                   help="communication step (default: the scene's; Python overhead per output "
                        "point is a large part of levels 1-3's cost at 1e-4 s)")
    p.add_argument("--json", action="store_true", help="print one JSON object")
    from .trade_study import add_arguments
    add_arguments(p)
    p.set_defaults(handler=_run_bench)


def _run_bench(args) -> int:
    from ..cli_support import print_json
    if args.scene == "tradeoff":    # `chainmodel bench tradeoff`: the study of many scenes
        from .trade_study import run_cli
        return run_cli(args)
    try:
        levels = tuple(int(x) for x in args.levels.split(","))
    except ValueError:
        raise ValueError(f"--levels must be comma-separated integers 0-3, got {args.levels!r}") from None
    for lv in levels + (args.reference,):
        if lv not in (0, 1, 2, 3):
            raise ValueError(f"--levels/--reference take levels 0-3, got {lv}")
    extra = {} if args.output_interval is None else {"output_interval": args.output_interval}
    rows = tradeoff(args.scene, levels, args.reference, args.duration,
                    progress=not args.json, **extra)
    if args.json:
        print_json({"scene": str(args.scene), "reference_level": args.reference,
                    "levels": [{"level": r.level, "name": r.name,
                                "wall_s_per_simulated_s": r.wall_per_simulated_second,
                                "figures": r.figures, "relative_deviation": r.deviation}
                               for r in rows]})
    else:
        print(format_table(rows, args.reference), end="")
    return 0
