"""What lifts level 3's running span tensions, measured on level 3's own rollers, and how much
of it its damping decides (docs/reduced_models.md, "The 16B mixer: level 3's slack span rings
on its own first mode").

Three tables per scene and speed, from level 3 runs (second half of the run, snapshots every
1 ms):

* ``spans``: each physical span (the free rollers between the last rollers seated on either
  sprocket; upper / lower by the side of the centre line its middle roller lies on), its mean
  tension, the RMS of its midspan displacement from its chord and the three strongest lines of
  that displacement's spectrum, next to the meshing frequency f_m = z1 n / 60;
* ``length``: each span's excess length over its chord (the polyline of its rollers minus the
  chord) and its rise over the slowest speed given, times the two spans' stiffness in series
  (level 1's k_eff of each span, chainmodel.kernels.spans) - the tension rise the bowing
  alone would give, against the rise of level 3's span means;
* ``damping``: level 3's mean tight / slack tension with ``chain.joint_damping`` scaled x0.5
  to x10 (the trade study's band is x0.5-x2), and the power its dampers dissipate against the
  pin-bushing friction they stand in for (chainmodel.loss_balance, mu = 0.1; the check
  ``damper_losses``).

    python docs/scripts/span_vibration.py examples/scenes/16b_mixer.toml 20,60,100,150,200,300
    python docs/scripts/span_vibration.py xu2010 5,45,60,120
    python docs/scripts/span_vibration.py examples/scenes/16b_mixer.toml 100,200,300 damping

(about 5 s per scene with warm kernels; the damping table 10 s).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.kernels import spans as S
from chainmodel.loss_balance import balance_duration, run_shares

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from level3_spans import free_spans, span_shape  # noqa: E402

DURATION = 1.0
SNAPSHOT_EVERY = 5            # output points (2e-4 s): every 1 ms
DAMPING_FACTORS = (0.5, 1.0, 2.0, 4.0, 10.0)


def measure(path: str, rpm: float) -> dict:
    """Level 3 at ``rpm``: per span its mean tension, excess length, midspan displacement series;
    the snapshot times."""
    sc = chainmodel.load_scene(path, input_speed_rpm=rpm, duration=DURATION, fidelity=3)
    centres = sc.model()._centres
    r = chainmodel.simulation.run_scene(sc.with_overrides(output_interval=2e-4),
                                        snapshot_every=SNAPSHOT_EVERY)
    data = {s: {"tension": [], "excess": [], "mid": []} for s in ("upper", "lower")}
    times = []
    for t, snap in r.snapshots:
        if t < 0.5 * DURATION:
            continue
        spans = free_spans(snap, centres)
        if len(spans) < 2:
            continue
        times.append(t)
        for side, idx in spans.items():
            excess, mid = span_shape(snap["roller_positions"][idx])
            data[side]["excess"].append(excess)
            data[side]["mid"].append(mid)
            data[side]["tension"].append(float(np.mean(snap["link_tension"][idx[:-1]])))
    return {"scene": sc, "t": np.array(times),
            **{s: {k: np.array(v) for k, v in d.items()} for s, d in data.items()}}


def lines(t, y, count=3, gap=3.0) -> list[tuple[float, float]]:
    """The ``count`` strongest spectral lines (f [Hz], amplitude) of y(t) above 3 Hz, at least
    ``gap`` Hz apart (Hann window, 8x zero padding)."""
    y = y - y.mean()
    n = 8 * y.size
    amp = np.abs(np.fft.rfft(y * np.hanning(y.size), n)) * 4.0 / y.size
    f = np.fft.rfftfreq(n, t[1] - t[0])
    keep = f > 3.0
    f, amp = f[keep], amp[keep]
    out = []
    for k in np.argsort(amp)[::-1]:
        if all(abs(f[k] - g) > gap for g, _ in out):
            out.append((float(f[k]), float(amp[k])))
        if len(out) == count:
            break
    return out


def spans_table(path: str, speeds) -> None:
    base = None
    sc1 = chainmodel.load_scene(path, fidelity=1).model()
    series = 1.0 / (1.0 / sc1.P[S.P_KEFF_U] + 1.0 / sc1.P[S.P_KEFF_L])
    print(f"{path}: spans of level 3 (upper / lower), second half of {DURATION:g} s runs; "
          f"the two spans' stiffness in series {series / 1e6:.3g} kN/mm")
    print(f"{'rpm':>5s} {'f_m':>6s} | span   {'T [N]':>6s} {'RMS mid':>8s} lines of the midspan "
          f"displacement [Hz mm] | excess [um] (rise) | rise x k_series [N] / level 3's rise")
    for rpm in speeds:
        m = measure(path, rpm)
        f_m = m["scene"].drive.n_driver * rpm / 60.0
        excess = {s: float(m[s]["excess"].mean()) for s in ("upper", "lower")}
        tension = {s: float(m[s]["tension"].mean()) for s in ("upper", "lower")}
        if base is None:
            base = (excess, tension)
        for s in ("upper", "lower"):
            peaks = ", ".join(f"{f:.1f} {1e3 * a:.2f}" for f, a in lines(m["t"], m[s]["mid"]))
            rise = 1e6 * (excess[s] - base[0][s])
            print(f"{rpm:5.0f} {f_m:6.1f} | {s:6s} {tension[s]:6.0f} "
                  f"{1e3 * m[s]['mid'].std():6.2f} mm {peaks:34s} | {1e6 * excess[s]:6.1f} "
                  f"({rise:+6.1f})")
        d_len = sum(excess.values()) - sum(base[0].values())
        d_t = {s: tension[s] - base[1][s] for s in tension}
        print(f"{'':5s} {'':6s} | both spans' excess rise {1e6 * d_len:+.1f} um x k_series = "
              f"{series * d_len:+.0f} N; level 3's spans rose {d_t['upper']:+.0f} / "
              f"{d_t['lower']:+.0f} N (upper / lower)", flush=True)


def damping_table(path: str, speeds) -> None:
    base = chainmodel.load_scene(path).parameters["chain.joint_damping"]
    print(f"{path}: level 3's mean tight / slack tension [N] against chain.joint_damping "
          f"(nominal {base:g}); 'loss / friction': its dampers' dissipation over the joint "
          "friction they stand in for, at the nominal value")
    print(f"{'rpm':>5s} " + " ".join(f"{'x' + format(f, 'g'):>11s}" for f in DAMPING_FACTORS)
          + "  loss / friction")
    for rpm in speeds:
        cells = []
        ratio = float("nan")
        for f in DAMPING_FACTORS:
            sc = chainmodel.load_scene(path, input_speed_rpm=rpm, fidelity=3)
            duration = balance_duration(sc, DURATION)
            sc = sc.with_overrides({"chain.joint_damping": f * base}, duration=duration)
            r = chainmodel.simulate(sc, output_interval=5e-4)
            w = r.time >= 0.5 * duration
            cells.append(f"{r['tight_span.tension'][w].mean():5.0f}/{r['slack_span.tension'][w].mean():5.0f}")
            if f == 1.0:
                shares = run_shares(r)
                if shares is not None:
                    ratio = shares[0] / shares[1]
        print(f"{rpm:5.0f} " + " ".join(f"{c:>11s}" for c in cells) + f"  {ratio:.2f}", flush=True)


def main(argv):
    if len(argv) < 2:
        print(__doc__)
        return 2
    speeds = [float(v) for v in argv[1].split(",")]
    if "damping" in argv[2:]:
        damping_table(argv[0], speeds)
    else:
        spans_table(argv[0], speeds)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
