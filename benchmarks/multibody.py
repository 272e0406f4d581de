"""Cost and accuracy of the multibody model (level 3) per stepper, and how cost grows with links.

    python benchmarks/multibody.py                 # the table for docs/performance.md
    python benchmarks/multibody.py --compare       # + model variants (Q forces, damping, seat)
    python benchmarks/multibody.py --figures docs/figures   # + the figures of docs/multibody.md
    python benchmarks/multibody.py --adaptive 0.02 # adaptive steppers timed over 0.02 s
    python benchmarks/multibody.py --overhead      # compiled loop alone vs full runs

xu2010 (seed 003 section 7) at 120 rpm for 1 s simulated, outputs every 1e-4 s. Error figures
are against a reference run (compiled RK4 at a quarter of its automatic step, itself checked
against an eighth): the mean tight-span tension and the RMS ripple of the driven speed, both
over the steady part (t >= 0.5 s). Wall and CPU seconds per simulated second are measured side
by side in one process; the machine is shared, so CPU time is the steadier figure.
"""

from __future__ import annotations

import argparse
import math
import os
import platform
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import chainmodel  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from chainmodel.simulation import run_scene  # noqa: E402

STEADY = 0.5


def metrics(result):
    m = result.time >= STEADY
    return (float(np.mean(result["tight_span.tension"][m])),
            float(np.std(result["driven.speed"][m])))


def timed(scene, snapshot_every=0):
    c0, w0 = time.process_time(), time.perf_counter()
    r = run_scene(scene, snapshot_every=snapshot_every)
    return r, time.perf_counter() - w0, time.process_time() - c0


def scene_for(links=46, duration=1.0, **params):
    base = load_scene("xu2010", fidelity="multibody", duration=duration)
    extra = dict(params)
    if links != 46:
        # same sprockets, the same 0.29 mm over the tight distance as 197.7 mm is for 46 links
        tight46 = chainmodel.Drive.from_links(25, 17, 0.015875, 46).centre_distance
        tight = chainmodel.Drive.from_links(25, 17, 0.015875, links).centre_distance
        extra.update({"drive.links": links,
                      "drive.centre_distance": tight + (0.1977 - tight46)})
    return base.with_overrides(parameters=extra)


def machine():
    try:
        name = [ln.split(":", 1)[1].strip() for ln in
                subprocess.run(["lscpu"], capture_output=True, text=True).stdout.splitlines()
                if ln.startswith("Model name")][0]
    except Exception:  # pragma: no cover
        name = platform.processor()
    return f"{name}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f}"


def stepper_table(joint_damping=0.0, links_list=(46, 100, 200)):
    extra = {"chain.joint_damping": joint_damping}
    print()
    print(f"machine: {machine()}; python {platform.python_version()}; "
          f"numba {'on' if chainmodel._numba.enabled() else 'off'}; "
          f"chain.joint_damping = {joint_damping:g} N.m.s/rad")
    model = scene_for(**extra).model()
    x0 = model.initial_state(scene_for().inputs(0))
    h_rk4 = 0.9 * 2 * math.sqrt(2) * model.stable_step(x0)
    ref, w, c = timed(scene_for(**extra, **{"solver.method": "rk4", "solver.step": h_rk4 / 4}))
    ref8, _, _ = timed(scene_for(**extra, **{"solver.method": "rk4", "solver.step": h_rk4 / 8}))
    T_ref, rip_ref = metrics(ref)
    T8, rip8 = metrics(ref8)
    print(f"reference rk4 h/4: mean tight {T_ref:.3f} N, driven-speed ripple {rip_ref:.5f} rad/s "
          f"(vs h/8: {abs(T_ref - T8) / T8:.1e}, {abs(rip_ref - rip8) / rip8:.1e} relative)")
    print()
    print("| chain | stepper | step [s] | wall s / sim s | CPU s / sim s | mean tight T [N] | "
          "err | driven ripple [rad/s] | err |")
    print("|---|---|---|---|---|---|---|---|---|")
    rows = []
    for links in links_list:
        for method in ("verlet", "rk4"):
            sc = scene_for(links, **extra, **{"solver.method": method})
            r, w, c = timed(sc)
            T, rip = metrics(r)
            step = sc.duration / r.stats["steps"] if r.stats.get("steps") else math.nan
            if links == 46:
                eT, eR = f"{abs(T - T_ref) / T_ref:.2%}", f"{abs(rip - rip_ref) / rip_ref:.2%}"
            else:
                eT = eR = "-"
            print(f"| {links} links | {method} | {step:.3g} | {w:.2f} | {c:.2f} | {T:.2f} | {eT} | "
                  f"{rip:.4f} | {eR} |", flush=True)
            rows.append((links, method, w, c))
    return rows


def overhead():
    """Where the time goes: the compiled Verlet loop alone over 1 s, and full runs with outputs
    every 1e-4 s and 1e-3 s (CPU seconds per simulated second)."""
    from chainmodel.kernels.multibody_loops import run_fixed
    sc = scene_for()
    run_scene(sc.with_overrides(duration=0.01))  # warm the compiled code
    print()
    print("| what (xu2010, verlet, 1 s) | CPU s / sim s | wall s / sim s |")
    print("|---|---|---|")
    for interval in (1e-4, 1e-3):
        r, w, c = timed(sc.with_overrides(output_interval=interval))
        print(f"| full run, outputs every {interval:g} s | {c:.2f} | {w:.2f} |", flush=True)
    m = sc.model()
    x = m.initial_state(sc.inputs(0.0))
    h = 0.9 * 2 * m.stable_step(x)
    n = int(1.0 / h)
    w_in = 120 * 2 * math.pi / 60
    c0, w0 = time.process_time(), time.perf_counter()
    run_fixed(0, x, 0.0, h, n, 0.0, 1.0, 0.0, w_in, w_in, w_in, 43.2, 43.2, m.P, m.ws)
    print(f"| compiled Verlet loop alone ({n} steps, constant speed) | "
          f"{time.process_time() - c0:.2f} | {time.perf_counter() - w0:.2f} |")


def adaptive_table(duration):
    print()
    print(f"adaptive steppers (xu2010, first {duration} s from rest, cost only):")
    print("| stepper | rtol | wall s / sim s | CPU s / sim s | steps | rhs evaluations |")
    print("|---|---|---|---|---|---|")
    for method, rtol in (("rk45", 1e-5), ("dop853", 1e-6), ("radau", 1e-5), ("bdf", 1e-5)):
        sc = scene_for(duration=duration, **{"solver.method": method, "solver.rtol": rtol})
        try:
            r, w, c = timed(sc)
        except Exception as exc:  # report, do not hide
            print(f"| {method} | {rtol:g} | failed: {exc} | | | |")
            continue
        print(f"| {method} | {rtol:g} | {w / duration:.1f} | {c / duration:.1f} | "
              f"{r.stats['steps']} | {r.stats['rhs_evaluations']} |", flush=True)


def compare():
    print()
    print("model variants (xu2010, 1 s, verlet; steady part t >= 0.5 s):")
    print("| variant | mean tight T [N] | mean slack T [N] | mean input torque [N.m] | "
          "driven ripple [rad/s] | peak contact force [N] | static T [N] |")
    print("|---|---|---|---|---|---|---|")
    variants = [
        ("default (axial dampers, ISO flanks, no Q)", {}, None),
        ("Q forces on (appendix eqs A4-A7)", {"multibody.rotating_frame_forces": True}, None),
        ("paper's isotropic dissipation S", {"multibody.paper_damping": True}, None),
        ("paper's bare circular seat (eq 9)", {"contact.seating_angle": math.pi}, None),
        ("tight centre distance (197.41 mm)", {"drive.centre_distance": 0.0}, None),
        ("joint dampers 0.02 N.m.s/rad", {"chain.joint_damping": 0.02}, None),
        ("default at 600 rpm", {}, 600),
        ("Q forces on at 600 rpm", {"multibody.rotating_frame_forces": True}, 600),
        # with the span modes damped the runs converge, so small differences can be read
        ("joint dampers 0.02, Q forces on", {"chain.joint_damping": 0.02,
                                             "multibody.rotating_frame_forces": True}, None),
        ("joint dampers 0.02 at 600 rpm", {"chain.joint_damping": 0.02}, 600),
        ("joint dampers 0.02, Q forces on, 600 rpm", {"chain.joint_damping": 0.02,
                                                      "multibody.rotating_frame_forces": True},
         600),
    ]
    for label, params, rpm in variants:
        sc = scene_for(**params)
        if rpm:
            sc = sc.with_overrides(input_speed_rpm=rpm)
        try:
            r = run_scene(sc)
        except Exception as exc:
            print(f"| {label} | failed: {exc} | | | | | |")
            continue
        m = r.time >= STEADY
        print(f"| {label} | {np.mean(r['tight_span.tension'][m]):.1f} | "
              f"{np.mean(r['slack_span.tension'][m]):.1f} | "
              f"{np.mean(r['input_shaft.torque'][m]):.3f} | {np.std(r['driven.speed'][m]):.4f} | "
              f"{np.max(r['contact.max_force'][m]):.0f} | {r.static_tension:.0f} |", flush=True)


def figures(outdir: Path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from chainmodel.analysis.summary import steady_window
    from chainmodel.kinematics.wrapping import chain_geometry, roller_positions
    from chainmodel.plots import amplitude_spectrum

    outdir.mkdir(parents=True, exist_ok=True)
    sc = scene_for(duration=1.0)
    r = run_scene(sc, snapshot_every=1)
    d = sc.drive
    t = r.time
    m = steady_window(t, 0.05, 1.0)
    # seating instants on the driver (a roller leaves the tight span): geometric, for marks
    g = chain_geometry(d, r["driver.angle"], r["driven.angle"])
    seat_events = t[1:][np.diff(g.upper.seat_end) != 0]

    # Fig 7: span tensions
    fig, ax = plt.subplots(2, 1, figsize=(9, 6.5), layout="constrained")
    ax[0].plot(t, r["tight_span.tension"], lw=0.7, label="tight span")
    ax[0].plot(t, r["slack_span.tension"], lw=0.7, label="slack span")
    ax[0].axhline(r.static_tension, color="0.5", ls=":", label="static tension")
    ax[0].set(xlabel="time [s]", ylabel="tension [N]",
              title="span tensions (link nearest each span's middle), xu2010, 120 rpm")
    ax[0].legend(fontsize="small")
    z = (t >= 0.80) & (t <= 0.86)
    ax[1].plot(t[z], r["tight_span.tension"][z], lw=0.9, label="tight span (middle link)")
    ax[1].plot(t[z], r["chain.max_link_tension"][z], lw=0.7, label="largest link tension")
    for e in seat_events[(seat_events >= 0.80) & (seat_events <= 0.86)]:
        ax[1].axvline(e, color="k", lw=0.6, ls="--")
    ax[1].set(xlabel="time [s]", ylabel="tension [N]",
              title="zoom: dashed = a roller seats on the driver (rigid-chain instant)")
    ax[1].legend(fontsize="small")
    fig.savefig(outdir / "multibody_tensions.png", dpi=100)
    plt.close(fig)

    # Fig 8: a roller crossing the tight span, deviation from the rigid chain
    pos = np.array([s["roller_positions"] for _, s in r.snapshots])
    ts = np.array([tt for tt, _ in r.snapshots])
    rigid = np.array([roller_positions(d, a, b) for a, b in
                      zip(r["driver.angle"][::1], r["driven.angle"][::1])])
    # the roller that is in the middle of the tight span at t = 0.8 s
    i0 = int(np.searchsorted(ts, 0.8))
    snap = r.snapshots[i0][1]
    a, b = snap["tight_span_rollers"]
    k = int((a + ((b - a) % d.links) // 2) % d.links)
    win = (ts >= 0.8 - 0.12) & (ts <= 0.8 + 0.12)
    fig, ax = plt.subplots(2, 1, figsize=(9, 5.5), sharex=True, layout="constrained")
    dx = (pos[win, k, 0] - rigid[win, k, 0]) * 1e3
    dy = (pos[win, k, 1] - rigid[win, k, 1]) * 1e3
    ax[0].plot(ts[win], dx, lw=0.8)
    ax[1].plot(ts[win], dy, lw=0.8)
    for e in seat_events[(seat_events >= ts[win][0]) & (seat_events <= ts[win][-1])]:
        ax[0].axvline(e, color="0.6", lw=0.5, ls=":")
        ax[1].axvline(e, color="0.6", lw=0.5, ls=":")
    ax[0].set(ylabel="x - x_rigid [mm]", title=f"roller {k}: leaves the driven sprocket, crosses "
              "the tight span, seats on the driver (deviation from the rigid chain)")
    ax[1].set(xlabel="time [s]", ylabel="y - y_rigid [mm]")
    fig.savefig(outdir / "multibody_roller.png", dpi=100)
    plt.close(fig)

    # Fig 10: torsional vibration and spectra
    fig, ax = plt.subplots(2, 2, figsize=(11, 6.5), layout="constrained")
    for j, (name, label) in enumerate((("driver.speed", "driver"), ("driven.speed", "driven"))):
        w = r[name][m]
        ax[0, j].plot(t[m], w - np.mean(w), lw=0.6)
        ax[0, j].set(xlabel="time [s]", ylabel="speed - mean [rad/s]",
                     title=f"{label} sprocket torsional vibration (mean {np.mean(w):.3f} rad/s)")
        f, amp = amplitude_spectrum(t[m], w)
        ax[1, j].plot(f, amp, lw=0.8)
        for h in range(1, 13):
            ax[1, j].axvline(50 * h, color="0.7", lw=0.5, ls=":")
        ax[1, j].set(xlim=(0, 700), xlabel="frequency [Hz]", ylabel="amplitude [rad/s]",
                     title=f"{label}: spectrum (dotted: multiples of 50 Hz)")
    fig.savefig(outdir / "multibody_torsional.png", dpi=100)
    plt.close(fig)

    # one link's tension as it travels round the loop (seed 003's reading of Fig. 7)
    tens = np.array([s["link_tension"] for _, s in r.snapshots])
    spans_ = np.array([s["tight_span_rollers"] for _, s in r.snapshots])
    win2 = (ts >= 0.5) & (ts <= 1.0)
    in_tight = ((k - spans_[:, 0]) % d.links) < ((spans_[:, 1] - spans_[:, 0]) % d.links)
    fig, ax = plt.subplots(figsize=(9, 3.8), layout="constrained")
    ax.plot(ts[win2], tens[win2, k], lw=0.7, label=f"link {k} (roller {k} to {k + 1})")
    yl = ax.get_ylim()
    ax.fill_between(ts[win2], yl[0], yl[1], where=in_tight[win2], color="C1", alpha=0.15,
                    label="link in the tight span")
    ax.set_ylim(yl)
    ax.set(xlabel="time [s]", ylabel="tension [N]",
           title="one link's tension on its way round the chain")
    ax.legend(fontsize="small", loc="upper right")
    fig.savefig(outdir / "multibody_link_tension.png", dpi=100)
    plt.close(fig)

    # chain snapshot with contact forces
    snap = r.snapshots[i0][1]
    fig, ax = plt.subplots(figsize=(9, 5), layout="constrained")
    zr = snap["roller_positions"] * 1e3
    ax.plot(np.append(zr[:, 0], zr[0, 0]), np.append(zr[:, 1], zr[0, 1]), "-", color="0.6", lw=0.8)
    f = snap["contact_force"]
    sc_ = ax.scatter(zr[:, 0], zr[:, 1], c=f, s=18 + 60 * f / max(f.max(), 1), cmap="viridis")
    fig.colorbar(sc_, ax=ax, label="contact force [N]")
    for key in ("seat_positions_driver", "seat_positions_driven"):
        sp = snap[key] * 1e3
        ax.plot(sp[:, 0], sp[:, 1], "x", color="C3", ms=3)
    ax.set_aspect("equal")
    ax.set(xlabel="X [mm]", ylabel="Y [mm]", title=f"chain at t = {ts[i0]:.3f} s: rollers coloured "
           "by contact force, seats x (driver right)")
    fig.savefig(outdir / "multibody_chain.png", dpi=100)
    plt.close(fig)
    print(f"figures written to {outdir}")
    return r


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--compare", action="store_true")
    ap.add_argument("--figures", type=Path)
    ap.add_argument("--adaptive", type=float, default=0.0,
                    help="also time the adaptive steppers over this many simulated seconds")
    ap.add_argument("--skip-table", action="store_true")
    ap.add_argument("--overhead", action="store_true",
                    help="also split the cost into the compiled loop and the per-output Python")
    args = ap.parse_args(argv)
    print(time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()))
    if not args.skip_table:
        stepper_table()
        stepper_table(0.02, (46,))
    if args.overhead:
        overhead()
    if args.adaptive > 0:
        adaptive_table(args.adaptive)
    if args.compare:
        compare()
    if args.figures:
        figures(args.figures)


if __name__ == "__main__":
    main()
