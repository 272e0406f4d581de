"""``python -m chainmodel.analysis.perturbation``: the coefficient table of eqs 68-71 for a drive
(default C1) and seed 004 Table 2, as Markdown, with the internal-resonance check.

    python -m chainmodel.analysis.perturbation [--preset C1] [--speed-rpm 400]
        [--reference-tension pretension|tight|total|N] [--mode 1] [--param NAME=VALUE ...]
"""

from __future__ import annotations

import argparse
import sys


def main(argv=None) -> int:
    from ...presets import preset
    from .cli import _params, _reference
    from .coefficients import coefficients, internal_resonance_check

    ap = argparse.ArgumentParser(prog="python -m chainmodel.analysis.perturbation",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--preset", default="C1")
    ap.add_argument("--speed-rpm", type=float, default=400.0)
    ap.add_argument("--reference-tension", default="pretension")
    ap.add_argument("--mode", type=int, default=1)
    ap.add_argument("--param", action="append", default=[])
    args = ap.parse_args(argv)
    try:
        drive = preset(args.preset)
        params = _params(args.param)
        c = coefficients(drive, params, args.speed_rpm, P_t=_reference(args.reference_tension),
                         mode=args.mode)
        check = internal_resonance_check(drive, params, args.speed_rpm, mode=args.mode)
    except ValueError as exc:
        sys.stderr.write(f"error: {exc}\n")
        return 2
    print(f"Drive {drive.name}: {drive.n_driver}/{drive.n_driven} teeth, p = {drive.pitch} m, "
          f"N = {drive.span_pitches}, f = {drive.pitch_fraction}; {args.speed_rpm:g} rpm, "
          f"P_t = {c.P_t:g} N, mode {c.mode}\n")
    print("| symbol | value | unit | eq. | meaning |")
    print("|---|---|---|---|---|")
    for sym, val, unit, eq, meaning in c.table():
        print(f"| {sym} | {val:.6g} | {unit} | {eq} | {meaning} |")
    print()
    print(f"omega_theta/omega_m (tight) = {check['tight']:.4f}, "
          f"omega_theta/omega~_n (slack) = {check['slack']:.4f} at {args.speed_rpm:g} rpm")
    for span in ("tight", "slack"):
        rpm = check[f"{span}_speed_rpm_at_ratio"]
        print(f"omega_theta = 2 omega ({span} span) at: "
              + ("no speed (spans taut)" if rpm is None else f"{rpm:.1f} rpm"))
    return 0


if __name__ == "__main__":
    sys.exit(main())
