"""``chainmodel frequency-response``: the frequency-response sweeps of seed 004 section 6
(Figs 6-9) from the multiple-scales analysis (:mod:`chainmodel.analysis.perturbation`).

Registered in :data:`chainmodel.cli.SUBCOMMANDS` as
``("chainmodel.analysis.perturbation.cli", "register")``.
"""

from __future__ import annotations

import math
import time

__all__ = ["register"]

CASES = ("parametric", "sprocket", "combined")


def register(subparsers) -> None:
    from ...cli_support import add_drive_arguments, add_output_arguments
    p = subparsers.add_parser(
        "frequency-response",
        help="multiple-scales frequency response of seed 004 (Figs 6-9)",
        description="Stationary amplitudes of the reduced 3-DOF model of seed 004 (eqs 68-70) "
                    "from its multiple-scales analysis: 'parametric' = primary parametric "
                    "resonance of the tight span (eq 105, Fig 6), 'sprocket' = primary external "
                    "resonance of the driven sprocket (eq 121, Fig 7), 'combined' = parametric "
                    "+ 2:1 internal resonance (eqs 129-132 integrated, Figs 8-9). Drive default "
                    "C1, dynamic parameters default seed 004 Table 2. Amplitudes are in units "
                    "of the centre distance l, frequencies in the time unit sqrt(rhoA l^2/P_t).")
    p.add_argument("--case", required=True, choices=CASES, help="which resonance case")
    p.add_argument("--speed-rpm", type=float, default=400.0, metavar="R",
                   help="driver speed [rpm] (sets chain speed and span tensions; default 400)")
    p.add_argument("--reference-tension", default="pretension", metavar="P_T",
                   help="P_t of eq 27: pretension (P_tot/2, default), tight (P0), total (P_tot) "
                        "or a tension in N")
    p.add_argument("--mode", type=int, default=1, metavar="M", help="span mode m (default 1)")
    p.add_argument("--param", action="append", default=[], metavar="NAME=VALUE",
                   help="override a Table 2 value (P_tot, EA, rhoA, J1, f1, d1, theta2_star, "
                        "mu_theta, mu_m); repeatable")
    p.add_argument("--policy", default="inertia", choices=("inertia", "table", "nominal"),
                   help="combined case: how omega_theta follows sigma_i (docs/perturbation.md)")
    p.add_argument("--points", type=int, default=None, metavar="N",
                   help="sweep points: parametric 521, sprocket 601, combined 36 along "
                        "sigma2/omega_m in [-2, 1.5] (sigma_i/omega_m from -1.9 to 1 at the same "
                        "spacing; 71 gives the 0.05 grid of the docs, several minutes)")
    add_drive_arguments(p)
    add_output_arguments(p, csv_help="write the sweep as CSV columns",
                         plot_help="write the figure (combined: <stem>_span.png and "
                                   "<stem>_sprocket.png, or .pdf/.svg alike)")
    p.set_defaults(handler=run_frequency_response)


def _params(items) -> dict:
    out = {}
    for item in items:
        name, sep, text = item.partition("=")
        name, text = name.strip(), text.strip()
        if not sep or not name or not text:
            raise ValueError(f"--param expects NAME=VALUE, got {item!r}")
        try:
            out[name] = float(text)
        except ValueError:
            raise ValueError(f"--param {name}: {text!r} is not a number") from None
    return out


def _reference(text: str):
    try:
        return float(text)
    except ValueError:
        return text


class _SlowTimeProgress:
    """One updating stderr line while the modulation equations integrate (the combined case
    runs about a minute): slow time reached of the longest integration, elapsed seconds."""

    def __init__(self, label: str, t_end: float):
        import sys
        self.err, self.label, self.t_end = sys.stderr, label, t_end
        self.start = self.last = time.perf_counter()
        self.reached = 0.0

    def __call__(self, t: float) -> None:
        self.reached = max(self.reached, float(t))
        now = time.perf_counter()
        if now - self.last >= 0.5:
            self.last = now
            self.err.write(f"\r{self.label}: slow time {self.reached:.0f} of at most "
                           f"{self.t_end:g}, {now - self.start:.0f} s elapsed ")
            self.err.flush()

    def close(self) -> None:
        if self.last > self.start:          # a line was shown: end it
            self.err.write("\n")
            self.err.flush()


def run_frequency_response(args) -> int:
    import numpy as np
    from ...cli_support import drive_dict, drive_from_args, print_json, write_csv_columns
    from . import coefficients, response

    drive_flags = ("preset", "driver_teeth", "driven_teeth", "span_pitches", "pitch_fraction",
                   "centre_distance", "links")
    if all(getattr(args, f, None) is None for f in drive_flags):
        args.preset = "C1"
    drive = drive_from_args(args)
    if args.points is not None and args.points < 3:
        raise ValueError(f"--points must be at least 3, got {args.points}")
    c = coefficients(drive, _params(args.param), args.speed_rpm,
                     P_t=_reference(args.reference_tension), mode=args.mode)
    if args.plot:
        from ...plots import check_plot_path
        from .plots import _plt
        check_plot_path(args.plot)          # before the sweep: .png, .pdf or .svg
        _plt()                              # fail before the sweep if matplotlib is missing
    t0 = time.perf_counter()
    n = args.points
    if args.case == "parametric":
        data = response.parametric_response(
            c, None if n is None else np.linspace(1.5, 2.8, n))
        summary = _parametric_summary(c, data)
        columns = {"omega2_over_omega_m": data["ratio"], "a_upper": data["a_upper"],
                   "a_lower": data["a_lower"], "upper_stable": data["upper_stable"],
                   "lower_stable": data["lower_stable"], "trivial_stable": data["trivial_stable"]}
    elif args.case == "sprocket":
        data = response.sprocket_response(
            c, None if n is None else np.linspace(0.97, 1.03, n))
        summary = _sprocket_summary(c, data)
        columns = {"omega2_over_omega_theta": data["ratio"], "v": data["v"]}
    else:
        k = 36 if n is None else n
        step = 3.5 / (k - 1)
        bar = None if args.json else _SlowTimeProgress(
            f"frequency-response combined ({k} x {len(np.arange(-1.9, 1.0 + 1e-9, step))} "
            "points)", 600.0)
        try:
            data = response.combined_response(c, np.linspace(-2.0, 1.5, k),
                                              np.arange(-1.9, 1.0 + 1e-9, step),
                                              policy=args.policy, progress=bar)
        finally:
            if bar is not None:
                bar.close()
        summary = _combined_summary(c, data)
        S2, SI = np.meshgrid(data["sigma2_ratio"], data["sigma_i_ratio"])
        columns = {"sigma2_over_omega_m": S2.ravel(), "sigma_i_over_omega_m": SI.ravel()}
        for r, a0 in enumerate(data["a0"]):
            tag = "small_start" if math.isfinite(a0) else "large_start"
            columns[f"a_{tag}"] = data["a"][r].ravel()
            columns[f"v_{tag}"] = data["v"][r].ravel()
            columns[f"stationary_{tag}"] = data["stationary"][r].ravel()
    summary["wall_time_s"] = time.perf_counter() - t0
    written = []
    if args.csv:
        written.append(write_csv_columns(args.csv, {k: np.asarray(v, float) for k, v in
                                                    columns.items()}, {}))
    if args.plot:
        from .plots import plot_case
        written.extend(plot_case(args.case, data, args.plot, _variants(args, drive, c)))
    if args.json:
        print_json({"case": args.case, "drive": drive_dict(drive),
                    "speed_rpm": args.speed_rpm, "coefficients": _coef_dict(c),
                    "summary": summary, "response": data,
                    "files": [str(w) for w in written]})
        return 0
    print(f"frequency response, case {args.case}: drive {drive.name or 'custom'}, "
          f"{args.speed_rpm:g} rpm, P_t = {c.P_t:g} N, mode {c.mode}")
    width = max(len(k) for k in summary)
    for key, value in summary.items():
        print(f"  {key:<{width}}  {_fmt(value)}")
    for w in written:
        print(f"wrote {w}")
    return 0


def _variants(args, drive, c) -> list:
    """Closed-form curves drawn beside the main one, as the paper discusses them: a doubled
    driver amplitude (Fig 6: the peak widens) and doubled/quadrupled sprocket damping (Fig 7:
    the peak drops)."""
    from . import coefficients, response
    base = dict(c.params)

    def coef(**change):
        return coefficients(drive, {**base, **change}, args.speed_rpm, P_t=c.P_t, mode=c.mode)

    if args.case == "parametric":
        return [(r"$2\theta_2^*$", response.parametric_response(
            coef(theta2_star=2 * base["theta2_star"]), initial_conditions=0))]
    if args.case == "sprocket":
        return [(rf"$\mu_\theta$ = {k * base['mu_theta']:g}", response.sprocket_response(
            coef(mu_theta=k * base["mu_theta"]), numerical_ratio=[])) for k in (2, 4)]
    return []


def _coef_dict(c) -> dict:
    d = c.as_dict()
    d.pop("params", None)
    d["params"] = dict(c.params)
    return d


def _fmt(v) -> str:
    if isinstance(v, float):
        return "n/a" if not math.isfinite(v) else f"{v:.6g}"
    if isinstance(v, (list, tuple)):
        return ", ".join(_fmt(x) for x in v)
    return str(v)


def _parametric_summary(c, data) -> dict:
    import numpy as np
    from . import stationary
    lo, hi = data["band_ratio"]
    a = data["a_upper"]
    out = {"omega_m": c.omega_m, "omega_m_rad_s": c.omega_m_dim, "p2": c.p2,
           "trivial_unstable_band_omega2_over_omega_m": [float(lo), float(hi)],
           "a_upper_at_omega2_eq_2omega_m": float(
               stationary.parametric_branches(c, 0.0).a_upper),
           "a_upper_at_sweep_end": float(a[-1]) if np.isfinite(a[-1]) else float("nan")}
    coexist = data["upper_stable"] & data["trivial_stable"]
    out["coexistence_from_omega2_over_omega_m"] = (float(data["ratio"][coexist][0])
                                                   if coexist.any() else float("nan"))
    if "numerical_a" in data:
        upper = np.interp(data["numerical_ratio"], data["ratio"], np.nan_to_num(a))
        num = data["numerical_a"]
        on = num > 1e-4
        rel = np.abs(num[on] / np.broadcast_to(upper, num.shape)[on] - 1)
        out["numerical_max_rel_deviation_from_eq105"] = float(rel.max()) if rel.size else float("nan")
    return out


def _sprocket_summary(c, data) -> dict:
    import numpy as np
    out = {"omega_theta": c.omega_theta, "omega_theta_rad_s": c.omega_theta_dim,
           "mu_theta": c.mu_theta, "v_peak_eq121": data["v_peak"],
           "half_power_width_omega2_over_omega_theta": 2 * c.mu_theta / c.omega_theta}
    if "numerical_v" in data:
        ref = np.interp(data["numerical_ratio"], data["ratio"], data["v"])
        out["numerical_max_rel_deviation_from_eq121"] = float(np.max(np.abs(
            data["numerical_v"] / ref - 1)))
    return out


def _combined_summary(c, data) -> dict:
    import numpy as np
    a, v = data["a"][0], data["v"][0]
    ia = np.unravel_index(np.argmax(a), a.shape)
    iv = np.unravel_index(np.argmax(v), v.shape)
    s2, si = data["sigma2_ratio"], data["sigma_i_ratio"]
    return {"policy": data["policy"], "sigma_i_table2_over_omega_m": c.sigma_i / c.omega_m,
            "a_max": float(a[ia]), "a_max_at_sigma2_sigma_i_over_omega_m": [float(s2[ia[1]]),
                                                                           float(si[ia[0]])],
            "v_max": float(v[iv]), "v_max_at_sigma2_sigma_i_over_omega_m": [float(s2[iv[1]]),
                                                                           float(si[iv[0]])],
            "non_stationary_fraction": float(1 - data["stationary"].mean()),
            "coexisting_fraction": float(np.mean(np.abs(data["a"][1] - data["a"][0])
                                                 > 1e-3 * max(a.max(), 1e-12)))}
