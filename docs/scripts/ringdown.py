"""Ring-down of the driven sprocket's torsional mode per fidelity level (issue 21 item 3).

A sudden start to 5 rpm (no ramp, no load torque) rings the driven sprocket on the chain; the
frequency is measured from the driven speed's oscillation about its mean over 0.02-0.5 s (mean
spacing of the zero crossings of the speed minus its running tooth-period mean, refined by the
peak of a Hann-windowed spectrum). The analytical estimate: the driven sprocket's inertia J_2
(plus the seated chain's m R^2 per seated roller) on the two spans in parallel, each of n
links in series with the wrap at both ends, k_span = 1 / (n / k_link + 2 / K_seat),
K_seat = (k_c + sqrt(k_c^2 + 4 k_c k_link)) / 2 (the seat ladder, docs/reduced_models.md),
softened by the span's sag with Ernst's modulus (tests/ringdown_check.py), and
f = sqrt(R_o^2 (k_up + k_low) / J_2) / 2 pi (rigid input shaft: the driver held by the input;
a flexible one: the two-inertia system with the shaft spring, the driven sprocket's mode).

    python docs/scripts/ringdown.py                # C1 and xu2010, levels 1-3
    python docs/scripts/ringdown.py C1 1,3         # one scene, some levels
    python docs/scripts/ringdown.py variants       # C1: level 3 vs the estimate, one value
                                                   # changed at a time (about 5 s)
    python docs/scripts/ringdown.py amplitude      # levels 1-3 against the start's speed,
                                                   # levels 1-2 on level 3's wrap (about 40 s)
    python docs/scripts/ringdown.py positions      # the linear modes at 8 driver positions in
                                                   # a tooth: level 3 (its static tension) and
                                                   # levels 1-2 on its wrap (a few seconds)
    python docs/scripts/ringdown.py modes          # which linear mode is the driven
                                                   # sprocket's: C1, C3, fine, xu2010 and
                                                   # a sagging 08B chain, each mode's share
                                                   # and MAC, level 3's ring (under a minute)
    python docs/scripts/ringdown.py loaded         # xu2010 under its 43.2 N m: level 3 and
                                                   # level 1 on the wrap and on the seat
                                                   # ladder (a few seconds)
    python docs/scripts/ringdown.py fan            # the 08B fan without pretension at its
                                                   # seat clearance x1 and x2: the fit's linear
                                                   # mode against levels 1-3's ring at 0.5, 1
                                                   # and 5 rpm (about 15 s)
    python docs/scripts/ringdown.py clearance      # xu2010 with its seat clearance x2: level
                                                   # 3's ring against its linear modes at rest
                                                   # (about 15 s)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

import chainmodel
from chainmodel.scene import load_scene

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))
from ringdown_check import peak_frequency, seat_ladder_spans, two_inertia_frequency  # noqa: E402

RPM = 5.0
DURATION = 0.5


def analytical(name, **kw):
    """Undamped two-inertia estimate [Hz]: the sprockets (mass matrix of level 1, chain
    inertia included) on the two spans in parallel, each span's n links in series with the
    seat ladder at both ends and softened by its sag (Ernst's modulus), and the input shaft's
    spring on the driver (none if rigid); the
    mode with the largest share of its kinetic energy in the driven sprocket (the tests' own
    two-inertia system, tests/ringdown_check.py)."""
    sc = load_scene(name, fidelity=1, **kw)
    return two_inertia_frequency(sc, seat_ladder_spans(sc))


def ring(name, level, band=None, rpm=RPM, **kw):
    """(frequency [Hz] of the driven speed's ring-down after a sudden start to ``rpm``: the
    strongest peak above 10 Hz, or within ``band``; wall time [s])."""
    t0 = time.time()
    r = chainmodel.simulate(name, fidelity=level, input_speed_rpm=rpm, ramp_time=0.0,
                            load_torque=0.0, duration=DURATION, output_interval=5e-5, **kw)
    # above 10 Hz without a band: below are the 5 rpm meshing (2-3 Hz) and the start's drift
    return peak_frequency(r, band or (10.0, np.inf)), time.time() - t0


C1_VARIANTS = (("defaults", {}),
               ("no seat clearance", {"contact_seat_radius": None}),
               ("chain.joint_clearance = 0", {"chain_joint_clearance": 0.0}),
               ("contact.stiffness x2", {"contact_stiffness": 2.0}),
               ("contact.stiffness x0.5", {"contact_stiffness": 0.5}),
               ("static tension 1000 N", {"static_tension": 1000.0}))


def variants():
    """C1's level 3 against the estimate with one value changed at a time, and level 1 with
    the seat ladder (torsional.seat_compliance) against it."""
    base = load_scene("C1").parameters
    print(f"{'C1 with':28s} {'estimate':>9s} {'level 3':>8s} {'vs est.':>8s}")
    for label, kw in C1_VARIANTS:
        kw = dict(kw)
        if "contact_seat_radius" in kw:
            kw["contact_seat_radius"] = base["chain.roller_radius"]
        if "contact_stiffness" in kw:
            kw["contact_stiffness"] *= base["contact.stiffness"]
        est = analytical("C1", **kw)
        f3 = ring("C1", 3, band=(0.6 * est, 1.4 * est), **kw)[0]
        print(f"{label:28s} {est:9.2f} {f3:8.2f} {100 * (f3 / est - 1):+7.1f}%", flush=True)
    est = analytical("C1")
    f1 = ring("C1", 1, band=(0.6 * est, 1.4 * est), torsional_seat_compliance=True)[0]
    print(f"{'level 1, seat_compliance':28s} {est:9.2f} {f1:8.2f} {100 * (f1 / est - 1):+7.1f}%"
          " (level 1)", flush=True)


AMPLITUDES = (1.0, 2.5, 5.0, 10.0)


def amplitude():
    """The ring-down against the start's speed (its amplitude): level 3 and levels 1-2 with
    ``torsional.wrap_statics`` (the wrap condensed from level 3 at its linear mode), each
    within 0.85-1.15 x level 3's linear mode (wrap_fit.mode), against level 3 at the same
    start."""
    from chainmodel.models.wrap_statics import wrap_fit
    print(f"{'scene':8s} {'start':>6s} {'level 3':>8s} {'level 1':>16s} {'level 2':>16s}"
          "   (levels 1-2 with torsional.wrap_statics; Hz, error against level 3)")
    for name in ("C1", "xu2010"):
        # with the option on: a static-tension target is then met on level 3's statics
        sc = load_scene(name, fidelity=1, torsional_wrap_statics=True)
        mode = wrap_fit(sc.drive, sc.parameters).mode
        band = (0.85 * mode, 1.15 * mode)
        for rpm in AMPLITUDES:
            f3 = ring(name, 3, band, rpm)[0]
            cells = []
            for level in (1, 2):
                f = ring(name, level, band, rpm, torsional_wrap_statics=True)[0]
                cells.append(f"{f:8.2f} ({100 * (f / f3 - 1):+5.1f}%)")
            print(f"{name:8s} {rpm:4.1f}rpm {f3:8.2f} " + " ".join(cells), flush=True)
        print(f"{name:8s} {'linear':>6s} {mode:8.2f}   (level 3 linearised at rest, "
              "multibody_statics.linear_driven_modes)", flush=True)


def positions(count=8):
    """Level 3's static span tensions and linear driven-sprocket mode, and levels 1-2's own
    linear mode with the option, at ``count`` driver positions over a tooth period (the fit
    takes the mean over wrap_statics.ANGLES of them: docs/reduced_models.md, "Over a tooth
    period, not at angle 0")."""
    import math
    from chainmodel.models import torsional_mode as TM
    from chainmodel.models.multibody_statics import linear_driven_modes, static_state
    from chainmodel.models.wrap_statics import wrap_fit
    for name in ("C1", "xu2010"):
        m3 = load_scene(name, fidelity=3).model()
        levels = {}
        for level in (1, 2):
            m = load_scene(name, fidelity=level, torsional_wrap_statics=True).model()
            fit = wrap_fit(m.drive, m.params)
            levels[level] = (m, TM._two_inertia_shape(m, fit.modal_stiffness,
                                                      2.0 * math.pi * fit.mode))
        print(f"{name}: driver position [tooth], level 3 static tension upper / lower [N], "
              f"linear mode [Hz] of level 3, of levels 1 and 2 with torsional.wrap_statics")
        near, ranks = None, {}
        for j in range(count):
            angle = 2.0 * math.pi / m3.drive.n_driver * j / count
            st = static_state(m3, angle)
            w3, ws = linear_driven_modes(m3, st, near=near)
            near = near or w3
            cells = []
            for level, (m, shape) in levels.items():
                w, ranks[level] = TM.driven_mode(m, shape, angle, ranks.get(level))
                cells.append(f"{w / (2 * math.pi):8.3f}")
            print(f"  {j}/{count}  {st.tension_upper:7.1f} / {st.tension_lower:7.1f}  "
                  f"{w3 / (2 * math.pi):8.3f}  " + "  ".join(cells), flush=True)


def clearance():
    """xu2010 with its seat clearance x1 and x2 (trade_study.band_overrides): level 3's ring in
    250-900 Hz against the start's speed, and its linearisation at rest at four driver positions
    in a tooth (wrap_statics.ANGLES): the static tensions, the static condensation's modes, the
    mode wrap_fit takes (its pick) and the continuation of the static condensation's other
    (chain) mode with the span rollers' inertia kept."""
    import math
    from chainmodel.analysis.trade_study import band_overrides
    from chainmodel.models import multibody_statics as MS
    from chainmodel.models.wrap_statics import tooth_positions
    base = load_scene("xu2010", fidelity=3)
    for factor in (1.0, 2.0):
        over = band_overrides(base, "seat_clearance", factor)
        rings = [ring("xu2010", 3, (250.0, 900.0), rpm, parameters=over)[0]
                 for rpm in (0.5, 1.0, 5.0)]
        print(f"xu2010, seat clearance x{factor:g}: level 3's ring-down in 250-900 Hz at 0.5 / 1 "
              f"/ 5 rpm: " + " / ".join(f"{f:.1f}" for f in rings) + " Hz", flush=True)
        model = base.with_overrides(over, fidelity=3).model()
        print("  position  tension up / low [N]  static condensation [Hz]  picked [Hz]  "
              "the other, continued [Hz]")
        for j, angle in enumerate(tooth_positions(model.drive)):
            st = MS.static_state(model, angle)
            captured = {}
            original = MS._condensed_modes

            def spy(k, mass, keep):
                lam, phi = original(k, mass, keep)
                if keep.size <= 2:
                    captured["static"] = np.sqrt(np.abs(lam))
                return lam, phi
            MS._condensed_modes = spy
            try:
                picked, ws = MS.linear_driven_modes(model, st)
            finally:
                MS._condensed_modes = original
            other = [w for w in captured["static"] if abs(w - ws) > 1e-9 * ws]
            cont = (MS.linear_driven_modes(model, st, near=other[0])[0] if other
                    else float("nan"))
            statics = " / ".join(f"{w / (2 * math.pi):.1f}" for w in captured["static"])
            print(f"  {j}/{len(tooth_positions(model.drive))}  {st.tension_upper:8.1f} / "
                  f"{st.tension_lower:6.1f}  {statics:>24s}  {picked / (2 * math.pi):11.1f}  "
                  f"{cont / (2 * math.pi):10.1f}", flush=True)


def modes():
    """Level 3 linearised at rest (multibody_statics.linearised_modes): every mode with at
    least 2 % of its kinetic energy in the driven sprocket's rotation or a MAC of 0.1 against
    the static wrap's shape, with its response (multibody_statics.mode_measures), the mode linear_driven_modes takes, the spans' first string mode
    (1 / 2L) sqrt(T_0 / rho), and level 3's ring-down after a sudden start to 1 and 5 rpm within
    0.6-1.4 x the mode taken (docs/reduced_models.md, "Which mode is the driven sprocket's")."""
    import math
    from chainmodel.models import multibody_statics as MS
    import tempfile
    from chainmodel.models.span_sag import normal_weights
    from test_wrap_statics import _SAGGING_08B    # the tests' sagging 08B 13/39 drive
    sagging = Path(tempfile.mkdtemp()) / "sagging_08b.toml"
    sagging.write_text(_SAGGING_08B)
    from chainmodel.analysis.trade_study import band_overrides
    xu = load_scene("xu2010", fidelity=3)
    cases = [(n, n, {}) for n in ("C1", "C3", "fine", "xu2010")] + [
        ("xu2010, seat clearance x2", "xu2010", band_overrides(xu, "seat_clearance", 2.0)),
        ("sagging 08B 13/39", str(sagging), {})]
    for label, name, over in cases:
        model = load_scene(name, fidelity=3).with_overrides(over, fidelity=3).model()
        rest = MS.static_state(model)
        lam, phi, mass, driven, ref, omega_s = MS.linearised_modes(model, rest)
        share, mac, response = MS.mode_measures(lam, phi, mass, driven, ref)
        taken = MS.linear_driven_modes(model, rest)[0]
        d, p = model.drive, model.params
        span = normal_weights(d, p)[0][1]
        string = math.sqrt(rest.mean_tension / (p["chain.link_mass"] / d.pitch)) / (2.0 * span)
        band = (0.6 * taken / (2 * math.pi), 1.4 * taken / (2 * math.pi))
        rings = " / ".join(f"{ring(name, 3, band, rpm, parameters=over)[0]:.2f}"
                           for rpm in (1.0, 5.0))
        print(f"{label}: spans {span:.3f} m, T_0 {rest.mean_tension:.1f} N, first string mode "
              f"{string:.2f} Hz, static condensation {omega_s / (2 * math.pi):.2f} Hz, level 3's "
              f"ring at 1 / 5 rpm {rings} Hz")
        for i in np.flatnonzero((share > 0.02) | (mac > 0.1)):
            tag = "  <- taken" if abs(math.sqrt(lam[i]) - taken) < 1e-9 * taken else ""
            print(f"  {math.sqrt(lam[i]) / (2 * math.pi):9.2f} Hz  share {share[i]:.3f}  "
                  f"MAC {mac[i]:.3f}  response^2 {response[i] ** 2:.3f}{tag}", flush=True)


def loaded(load=43.2):
    """xu2010 under its load: the driven sprocket's mode of level 3 and of level 1 on the wrap
    and on the seat ladder, rung by a sudden start to 5 rpm with the load applied from rest
    (band 350-800 Hz), against twice the meshing frequency at 600 rpm (500 Hz)."""
    print(f"xu2010, sudden start to {RPM:g} rpm with {load:g} N m from rest; strongest peak in "
          "350-800 Hz (twice the meshing frequency at 600 rpm: 500 Hz)")
    cases = [("level 3", dict(fidelity=3)),
             ("level 1, wrap (default)", dict(fidelity=1)),
             ("level 1, seat ladder", dict(fidelity=1, torsional_wrap_statics=False))]
    f3 = None
    for label, kw in cases:
        r = chainmodel.simulate("xu2010", input_speed_rpm=RPM, ramp_time=0.0, load_torque=load,
                                duration=0.5, output_interval=5e-5, **kw)
        f = peak_frequency(r, (350.0, 800.0))
        f3 = f if f3 is None else f3
        print(f"{label:26s} {f:8.1f} Hz {100 * (f / f3 - 1):+6.1f}%", flush=True)


def fan():
    """The 08B fan without pretension (examples/scenes/08b_fan_1500rpm.toml, static_tension
    None) at its seat clearance x1 and x2: wrap_fit's linear mode at rest against the strongest
    peak of each level's ring-down in 10 Hz-5 kHz after a sudden start to 0.5, 1 and 5 rpm."""
    from chainmodel.analysis.trade_study import band_overrides
    from chainmodel.models.wrap_statics import wrap_fit
    path = str(Path(__file__).resolve().parents[2] / "examples" / "scenes" /
               "08b_fan_1500rpm.toml")
    base = load_scene(path, fidelity=1, static_tension=None)
    print("08B fan without pretension: the fit's linear mode at rest and each level's ring-down "
          "[Hz] (strongest peak in 10 Hz-5 kHz) at 0.5 / 1 / 5 rpm")
    for factor in (1.0, 2.0):
        over = band_overrides(base, "seat_clearance", factor)
        sc = load_scene(path, fidelity=1, static_tension=None, **over)
        mode = wrap_fit(sc.drive, sc.parameters).mode
        cells = []
        for level in (3, 1, 2):
            rings = [ring(path, level, (10.0, 5000.0), rpm, static_tension=None,
                          parameters=over)[0] for rpm in (0.5, 1.0, 5.0)]
            cells.append(f"level {level} " + " / ".join(f"{f:.1f}" for f in rings))
        print(f"seat clearance x{factor:g}: fit {mode:.2f}; " + "; ".join(cells), flush=True)


def main(argv):
    if argv[1:2] == ["fan"]:
        return fan()
    if argv[1:2] == ["loaded"]:
        return loaded()
    if argv[1:2] == ["modes"]:
        return modes()
    if argv[1:2] == ["variants"]:
        return variants()
    if argv[1:2] == ["clearance"]:
        return clearance()
    if argv[1:2] == ["positions"]:
        return positions()
    if argv[1:2] == ["amplitude"]:
        return amplitude()
    names = argv[1].split(",") if len(argv) > 1 else ["C1", "xu2010"]
    levels = [int(v) for v in argv[2].split(",")] if len(argv) > 2 else [1, 2, 3]
    print("strongest peak of the driven speed above 10 Hz within 0.6-1.4 x the estimate of the "
          "driven sprocket's mode")
    print(f"{'scene':8s} {'level':>5s} {'f [Hz]':>8s} {'vs L3':>7s} {'vs est.':>8s} {'wall':>6s}")
    for name in names:
        est = analytical(name)
        f3 = None
        rows = []
        for level in sorted(levels, reverse=True):
            f, wall = ring(name, level, band=(0.6 * est, 1.4 * est))
            if level == 3:
                f3 = f
            rows.append((level, f, wall))
        for level, f, wall in sorted(rows):
            vs3 = f"{100 * (f / f3 - 1):+6.1f}%" if f3 else "   n/a"
            print(f"{name:8s} {level:5d} {f:8.2f} {vs3:>7s} {100 * (f / est - 1):+7.1f}% "
                  f"{wall:5.1f}s", flush=True)
        print(f"{name:8s} {'est.':>5s} {est:8.2f}", flush=True)


if __name__ == "__main__":
    main(sys.argv)
