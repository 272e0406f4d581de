"""The error study of seed 000 section 4.4: largest NRMSD (eq 54) of the closed-form
approximations over a grid of drives with n_c = n_o = n, span pitches N and pitch fraction f.

    python -m chainmodel.kinematics.errors                       # n, N in 13..40, f 0.1..0.9
    python -m chainmodel.kinematics.errors --teeth 10:40 --spans 10:40

prints the maxima of position, velocity (eq 51 printed and corrected) and acceleration, and
where they occur. The numbers are quoted in docs/kinematics.md; tests/test_approx.py checks the
paper's bounds on a subgrid. (A separate module from approx.py so that ``python -m`` does not
run a module the package has already imported.)
"""

from __future__ import annotations

import math

import numpy as np

from ..geometry import Drive
from . import fourbar as fb
from .approx import approximate, approximate_velocity_ratio, nrmsd

__all__ = ["nrmsd_table", "main"]


def nrmsd_table(teeth, spans, fractions, samples: int = 200, pitch: float = 0.0254,
                omega4: float = -100 * 2 * math.pi / 60, events: str = "exact") -> dict:
    """Largest NRMSD (eq 54) of position, velocity (both eq 51 forms) and acceleration over
    drives with n_c = n_o = n for n in ``teeth``, N in ``spans``, f in ``fractions`` (seed 000
    section 4.4), with ``samples`` driver angles per tooth period at constant driver speed
    ``omega4`` (paper: 100 rpm, clockwise). Returns {quantity: (max, (n, N, f))} and, under
    "skipped", the (n, N) pairs whose pitch circles overlap (Drive refuses them). ``events`` as
    in :func:`.approx.approximate` (h from the exact or the approximate events)."""
    worst = {key: (-1.0, None) for key in ("position", "velocity_printed", "velocity_corrected",
                                           "acceleration")}
    skipped = []
    for n in teeth:
        for N in spans:
            for f in fractions:
                try:
                    d = Drive(int(n), int(n), pitch, int(N), float(f))
                except ValueError:
                    if (int(n), int(N)) not in skipped:
                        skipped.append((int(n), int(N)))
                    continue
                s = fb.seating(d)
                t4 = s.theta4 - np.arange(samples) * (2 * math.pi / n / samples)
                ex = fb.exact(d, t4, omega4=omega4)
                ap = approximate(d, t4, omega4=omega4, form="corrected", events=events)
                ap_p = approximate_velocity_ratio(d, ap.theta2, ap.theta4, "printed") * omega4
                errs = {"position": nrmsd(ap.theta2, ex.theta2),
                        "velocity_printed": nrmsd(ap_p, ex.omega2),
                        "velocity_corrected": nrmsd(ap.omega2, ex.omega2),
                        "acceleration": nrmsd(ap.alpha2, ex.alpha2)}
                for key, e in errs.items():
                    if e > worst[key][0]:
                        worst[key] = (e, (int(n), int(N), float(f)))
    worst["skipped"] = skipped
    return worst


def main(argv=None) -> int:
    import argparse
    ap = argparse.ArgumentParser(
        prog="python -m chainmodel.kinematics.errors",
        description="Largest NRMSD (seed 000 eq 54) of the closed-form approximations over "
                    "n = n_c = n_o, N and f (seed 000 section 4.4).")
    ap.add_argument("--teeth", default="13:40", help="n range lo:hi inclusive (default 13:40)")
    ap.add_argument("--spans", default="13:40", help="N range lo:hi inclusive (default 13:40)")
    ap.add_argument("--fractions", default="0.1:0.9:0.1", help="f lo:hi:step (default 0.1:0.9:0.1)")
    ap.add_argument("--samples", type=int, default=200, help="driver angles per tooth period")
    ap.add_argument("--events", choices=("exact", "approximate"), default="exact",
                    help="seating/release angles for h: exact (as the paper's Fig. 4) or eqs 41, 46")
    args = ap.parse_args(argv)

    def irange(text):
        lo, hi = (int(v) for v in text.split(":"))
        return range(lo, hi + 1)

    lo, hi, step = (float(v) for v in args.fractions.split(":"))
    fr = np.round(np.arange(lo, hi + step / 2, step), 10)
    worst = nrmsd_table(irange(args.teeth), irange(args.spans), fr, samples=args.samples,
                        events=args.events)
    print(f"n = n_c = n_o in {args.teeth}, N in {args.spans}, f in {args.fractions}, "
          f"{args.samples} samples per tooth period, 100 rpm, {args.events} events")
    print(f"{'quantity':<22}{'max NRMSD':>12}   at (n, N, f)")
    skipped = worst.pop("skipped")
    for key, (e, where) in worst.items():
        print(f"{key:<22}{100 * e:>11.4f}%   {where}")
    if skipped:
        print(f"skipped {len(skipped)} (n, N) pairs whose pitch circles overlap: {skipped}")
    return 0


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
