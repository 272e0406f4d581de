"""Where level 1's running slack span falls short: the meshing harmonics on the slack span's
string modes (docs/reduced_models.md, "Level 1's running slack span: the meshing on the slack
span's string modes").

Level 1 has no span modes; level 3's spans bow under the polygonal action, and a bowed span is
longer than its chord, which lifts both spans' tension. Per scene this prints:

* the meshing frequency f_m = z1 n / 60 and the slack span's first string frequency
  f_1 = (1 / 2 lbar) sqrt(T_e / rho) (seed 004 eq 61; ``ModalModel.modal_frequencies``) at
  level 1's and at level 3's running slack-span tension;
* the nearest match k f_m = n f_1 (k = 1, 2 meshing harmonics, n = 1-3 string modes) as the
  detuning k f_m / (n f_1) - 1 at level 3's tension;
* an estimate of the bowing's lift that was tried as a level-1 term and not built: the linear
  steady state of level 2's Galerkin strings (seed 004 eq 58, one mode per span up to
  ``MODES``) under the kinematic endpoint motion of a tooth period (its first ``HARMONICS``
  harmonics), at level 1's running tensions and level 2's modal damping; its mean stretch
  sum (m pi)^2 <q_m^2> / (4 lbar) per span, times the two spans' stiffness in series, is the
  lift of both spans' tension;
* level 3's slack span, its rise over its value at 5 rpm (xu2010 only), and level 1's error.

    python docs/scripts/span_bowing.py            # xu2010 5-120 rpm and the trade study's
                                                  # scenes (about 40 s with warm kernels)
    python docs/scripts/span_bowing.py xu2010     # xu2010 only
    python docs/scripts/span_bowing.py xu2010 --zeta 0.0026 --at-level3 --modes 12
        # the estimate with level 3's span damping, at level 3's slack tension, 12 modes
    python docs/scripts/span_bowing.py --campbell docs/figures/span_campbell_xu2010.png
        # the figure: xu2010's slack span at levels 1-3 over 5-150 rpm above its Campbell
        # diagram (the spans' modes at level 3's tensions, the meshing harmonics); about 30 s
    python docs/scripts/span_bowing.py --campbell docs/figures/span_campbell_16b_mixer.png \
        --scene examples/scenes/16b_mixer.toml --speeds 20:330:10
        # the same for the 16B mixer example over 20-320 rpm; about 20 s

The estimate is linear: it leaves out the tension its own stretch adds, which tunes a string
towards a meshing harmonic above it (the hardening that makes level 3's rise at 60 rpm), and
the parametric terms. The table shows where that matters.
"""

from __future__ import annotations

import csv
import math
import sys
import time
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.analysis.trade_study import SCENES
from chainmodel.kernels import spans as S
from chainmodel.kernels.kinematic import driven_rotation, fourbar_constants
from chainmodel.kernels.span_roles import lower_tight
from chainmodel.models.modal import galerkin_coefficients
from chainmodel.scene import load_scene

MODES = 3
HARMONICS = 12
SAMPLES = 256          # per tooth period
XU_SPEEDS = (5, 15, 30, 45, 60, 90, 120)


def endpoint_velocities(model, rpm: float) -> np.ndarray:
    """dY/dt of the four span ends (upper start, upper end, lower start, lower end) across
    their span's reference line over one driver tooth period at constant driver speed, the
    driven sprocket on the exact kinematics (the kinematic motion of kernels/spans.py)."""
    d, P, G = model.drive, model.P, model.G
    K = fourbar_constants(d)
    w1 = rpm * 2.0 * math.pi / 60.0
    r_c, r_o = G[4], G[5]
    Y = np.empty((4, SAMPLES))
    for i, phi1 in enumerate(np.arange(SAMPLES) * 2.0 * math.pi / d.n_driver / SAMPLES):
        phi2, w2 = driven_rotation(phi1, w1, 0.0, False, K)[:2]
        g = S.span_geometry(phi1, phi2, G)
        Y[0, i] = -w2 * r_o * math.cos(g[6] - P[S.P_REF_U])
        Y[1, i] = -w1 * r_c * math.cos(g[7] - P[S.P_REF_U])
        Y[2, i] = -w1 * r_c * math.cos(g[15] - P[S.P_REF_L])
        Y[3, i] = -w2 * r_o * math.cos(g[16] - P[S.P_REF_L])
    return Y


def bowing_stretch(model, rpm: float, t_upper: float, t_lower: float, modes: int = MODES,
                   zeta: float | None = None) -> tuple[float, float]:
    """Mean stretch [m] of each span's strings (upper, lower) in the linear steady state of
    seed 004 eq 58 under the endpoint motion, the mean (static sag) left out; ``modes`` per
    span, damping ratio ``zeta`` (default: the model's modal.damping_ratio)."""
    d, P = model.drive, model.P
    Y = endpoint_velocities(model, rpm)
    F = np.fft.rfft(Y, axis=1) / SAMPLES          # Y' = sum_k F_k e^{i k W t} + c.c.
    W = d.n_driver * rpm * 2.0 * math.pi / 60.0
    gc = galerkin_coefficients(modes)
    g, e, C = gc["G"], gc["E"], gc["C"]
    m = np.arange(1, modes + 1)
    rho = P[S.P_RHOA]
    zeta = P[S.P_ZETA] if zeta is None else zeta
    speed = d.n_driver * d.pitch * rpm / 60.0          # chain speed [m/s]
    out = []
    for (a, b), tension, lbar, w1 in (((0, 1), t_upper, P[S.P_LBAR_U], P[S.P_W1_U]),
                                      ((2, 3), t_lower, P[S.P_LBAR_L], P[S.P_W1_L])):
        stiff = np.diag(max(tension - rho * speed * speed, 0.0) / rho * (m * math.pi / lbar) ** 2)
        damp = 2.0 * speed / lbar * C + np.diag(2.0 * zeta * m * w1)
        stretch = 0.0
        for k in range(1, min(HARMONICS, SAMPLES // 2 - 1) + 1):
            om = k * W
            v1, v2 = F[a, k], F[b, k]
            rhs = (-(g - e) * 1j * om * v1 - e * 1j * om * v2
                   - 2.0 * speed / lbar * (v2 - v1) * g)
            q = np.linalg.solve(-om * om * np.eye(modes) + 1j * om * damp + stiff, rhs)
            stretch += float(np.sum((m * math.pi) ** 2 * 2.0 * np.abs(q) ** 2 / (4.0 * lbar)))
        out.append(stretch)
    return out[0], out[1]


def running(scene, level):
    """(tight, slack) means over the second half."""
    r = chainmodel.simulate(scene, fidelity=level, output_interval=2e-4)
    m = r.time >= 0.5 * r.time[-1]
    return float(r["tight_span.tension"][m].mean()), float(r["slack_span.tension"][m].mean())


def row(label, scene, slack3=None, rise3=None, modes=MODES, zeta=None, at_level3=False):
    sc = scene.with_overrides(fidelity=2)
    modal = sc.model()
    d, p = sc.drive, sc.parameters
    rpm = abs(sc.operating.speed) * 60.0 / (2.0 * math.pi)
    tight1, slack1 = running(scene, 1)
    if slack3 is None:
        slack3 = running(scene, 3)[1]
    f_m = d.n_driver * rpm / 60.0
    v = d.n_driver * d.pitch * rpm / 60.0
    lower = lower_tight(sc.operating.load_torque, p["driven.damping"],
                        modal.mass_matrix()[1, 1], d.tooth_ratio, sc.operating.speed, 0.0)
    span = "upper" if lower else "lower"           # the slack one
    f1 = [float(modal.modal_frequencies(t, v, span)[0]) / (2.0 * math.pi)
          for t in (slack1, slack3)]
    k, n = min(((k, n) for k in (1, 2) for n in (1, 2, 3)),
               key=lambda kn: abs(kn[0] * f_m / (kn[1] * f1[1]) - 1.0))
    detune = k * f_m / (n * f1[1]) - 1.0
    slack = slack3 if at_level3 else slack1
    t_up, t_low = (slack, tight1) if lower else (tight1, slack)
    s_up, s_low = bowing_stretch(modal, rpm, t_up, t_low, modes, zeta)
    m1 = scene.with_overrides(fidelity=1).model()
    series = 1.0 / (1.0 / m1.P[S.P_KEFF_U] + 1.0 / m1.P[S.P_KEFF_L])
    lift = series * (s_up + s_low)
    rise = f"{rise3:+6.1f}" if rise3 is not None else "     -"
    print(f"{label:26s} {f_m:6.1f} {f1[0]:6.1f} {f1[1]:6.1f}  {k}x/{n}  {100 * detune:+6.1f}% "
          f"{lift:7.2f} N ({100 * lift / slack:5.1f} %) {slack3:7.1f} {rise} "
          f"{100 * (slack1 / slack3 - 1):+6.1f} %", flush=True)


def main(argv):
    start = time.perf_counter()
    if "--campbell" in argv:
        speeds = _option(argv, "--speeds", None)
        campbell(_option(argv, "--campbell", None), _option(argv, "--scene", "xu2010"),
                 tuple(range(5, 155, 5)) if speeds is None
                 else tuple(range(*(int(v) for v in speeds.split(":")))))
        print(f"wall {time.perf_counter() - start:.0f} s")
        return
    zeta = _option(argv, "--zeta", None)
    opts = dict(modes=int(_option(argv, "--modes", MODES)),
                zeta=None if zeta is None else float(zeta), at_level3="--at-level3" in argv)
    print(f"{'scene':26s} {'f_m':>6s} {'f_1(1)':>6s} {'f_1(3)':>6s}  k/n  detuning "
          f"{'linear estimate of the lift':>22s} {'slack3':>7s} {'rise3':>6s} level 1")
    base = load_scene("xu2010")
    rest = running(base.with_overrides(input_speed_rpm=5.0, duration=0.6), 3)[1]
    for rpm in XU_SPEEDS:
        sc = base.with_overrides(input_speed_rpm=float(rpm), duration=0.6)
        slack3 = running(sc, 3)[1] if rpm != 5 else rest
        row(f"xu2010 {rpm} rpm (0.6 s)", sc, slack3, slack3 - rest, **opts)
    if "xu2010" not in argv:
        dropped = _dropped()
        for spec in SCENES:
            if spec.name in dropped:
                print(f"{spec.name:26s} not run: the trade study's reference is invalid (dropped)")
                continue
            sc = load_scene(spec.preset, **spec.overrides)
            try:
                sc.with_overrides(fidelity=1).model().speed_limit()
                row(spec.name, sc, **opts)
            except ValueError as err:
                print(f"{spec.name:26s} not run: {str(err)[:90]}")
    print(f"f in Hz; detuning at level 3's slack tension; estimate with {opts['modes']} modes per "
          f"span, zeta {'modal.damping_ratio' if opts['zeta'] is None else opts['zeta']}, at level "
          f"{3 if opts['at_level3'] else 1}'s slack tension; wall {time.perf_counter() - start:.0f} s")


def campbell(path: str, scene_name: str = "xu2010", speeds=tuple(range(5, 155, 5))) -> None:
    """Two panels over a scene's input speed: the mean slack-span tension of levels 1, 2 and 3
    (0.6 s runs, second half), and below it a Campbell diagram, the slack span's first three
    string modes and the tight span's first two at level 3's running tensions with the meshing
    frequency and twice it: where a ray crosses a mode, level 3's spans rise and level 1's do
    not."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    base = load_scene(scene_name)
    modal = base.with_overrides(fidelity=2).model()
    d = modal.drive
    slack = {level: [] for level in (1, 2, 3)}
    tight3 = []
    for k, rpm in enumerate(speeds):
        sc = base.with_overrides(input_speed_rpm=float(rpm), duration=0.6)
        for level in slack:
            tight, s = running(sc, level)
            slack[level].append(s)
            if level == 3:
                tight3.append(tight)
        print(f"\r{k + 1}/{len(speeds)} speeds", end="", file=sys.stderr, flush=True)
    print(file=sys.stderr)
    rpm = np.asarray(speeds, float)
    lower = lower_tight(base.operating.load_torque, base.parameters["driven.damping"],
                        modal.mass_matrix()[1, 1], d.tooth_ratio, base.operating.speed, 0.0)
    spans = ("upper", "lower") if lower else ("lower", "upper")      # (slack, tight)

    def first_mode(tensions, span):
        return np.array([float(modal.modal_frequencies(t, d.n_driver * d.pitch * n / 60.0,
                                                       span)[0]) / (2.0 * math.pi)
                         for t, n in zip(tensions, rpm)])

    f_slack, f_tight = first_mode(slack[3], spans[0]), first_mode(tight3, spans[1])
    fig, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(7.5, 6.5))
    for level, style in ((3, "k-o"), (2, "C0-s"), (1, "C3-^")):
        top.plot(rpm, slack[level], style, ms=3, label=f"level {level}")
    top.set_ylabel("mean slack-span tension [N]")
    top.legend(loc="upper left")
    top.set_title(f"{base.name}, {base.operating.load_torque:g} N m: the spans against the "
                  "meshing's harmonics", fontsize=10)
    for n in (1, 2, 3):
        bottom.plot(rpm, n * f_slack, "k-", lw=1.2)
        bottom.annotate(f"slack mode {n}", (rpm[-1], n * f_slack[-1]), fontsize=8,
                        xytext=(-60, 4), textcoords="offset points")
    for n in (1, 2):
        bottom.plot(rpm, n * f_tight, "-", color="0.55", lw=1.0)
        mid = rpm.size // 2
        bottom.annotate(f"tight mode {n}", (rpm[mid], n * f_tight[mid]), fontsize=8,
                        color="0.4", xytext=(2, 4), textcoords="offset points")
    f_m = d.n_driver * rpm / 60.0
    bottom.plot(rpm, f_m, "C1--", label="meshing f_m")
    bottom.plot(rpm, 2 * f_m, "C2--", label="2 f_m")
    bottom.set_ylim(0, 4 * float(np.max(f_slack)))
    bottom.set_xlabel("input speed [rpm]")
    bottom.set_ylabel("frequency [Hz]")
    bottom.legend(loc="upper left")
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    print(f"wrote {path}")


def _dropped() -> set[str]:
    """The scenes the committed trade study dropped (its level-3 reference invalid)."""
    path = Path(chainmodel.__file__).parent / "data" / "tradeoff.csv"
    with open(path, newline="") as f:
        rows = csv.DictReader(line for line in f if not line.startswith("#"))
        return {r["scene"] for r in rows if r["status"] == "reference invalid"}


def _option(argv, name, default):
    return argv[argv.index(name) + 1] if name in argv else default


if __name__ == "__main__":
    main(sys.argv[1:])
