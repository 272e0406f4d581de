"""Static tension of a chain with little or no pretension at every level (issue 21 item 4;
docs/reduced_models.md, "One static tension, gravity included").

The 08B fan drive of examples/scenes/08b_fan_1500rpm.toml without its static tension.

Table 1, no pretension, the centre distance moved from the tight-wrap one: the elastic
catenary's parabola on the seat ladder alone (chainmodel.models.span_sag, Irvine's cable:
T^3 - T_raw T^2 - S / D = 0; ``exact=False``); the seat ladder without weight (levels 0-2 before
issue 21: 0 N on a slack chain); levels 0, 1, 2 by default (level 2 refuses a chain longer than
its wrap: nan) (wrap_statics.weighted_static_tension:
where the weight carries most of the tension its sag term is level 3's); level 1 with
torsional.wrap_statics; level 3's static equilibrium (multibody_statics: Newton steps, wall
time); level 3's dynamic model over 0.1 s at rest started from it (mean of its span outputs).

Table 2, the tight wrap, chain.pretension swept: the same columns where they apply, to show the
static tension is continuous in the pretension and where levels 0-2 and level 3 part.

Table 3, the same sweep on drives written by `chainmodel new-scene` (tight wrap, 40 pitches):
level 1 against level 3's statics, and each with gravity off.

    python docs/scripts/static_sag.py        # about 20 s
"""

from __future__ import annotations

import math

import numpy as np

from chainmodel.integrate import Verlet
from chainmodel.models import Inputs
from chainmodel.models.multibody_statics import static_state
from chainmodel.models import span_sag
from chainmodel.models.static_tension import static_numerator
from chainmodel.models.static_tension import static_span_tension as ladder
from chainmodel.scene import load_scene

PATH = "examples/scenes/08b_fan_1500rpm.toml"


def at_rest(model, x):
    u = Inputs(0.0, 0.0, 0.0)
    st = Verlet(model, 0.0, x.copy(), u)
    rows = [st.advance(i * 1e-3, u) for i in range(1, 101)]
    return float(np.mean([0.5 * (r["tight_span.tension"] + r["slack_span.tension"])
                          for r in rows]))


def parabola(d, p):
    """The elastic catenary's shallow parabola on the seat ladder, at any sag."""
    x, dd = static_numerator(d, p)
    return span_sag.tension(x / dd, span_sag.sag_term(d, p) / dd)


def _levels(**kw):
    out = []
    for lv in (0, 1, 2):
        try:
            out.append(load_scene(PATH, fidelity=lv, static_tension=None, **kw).model()
                       .static_tension())
        except ValueError:   # level 2 refuses a chain longer than its wrap (modal.py)
            out.append(math.nan)
    return out


def main():
    d0 = load_scene(PATH, fidelity=1, static_tension=None).drive
    print(f"{'dc [mm]':>8s} {'parabola':>9s} {'ladder':>7s} {'L0':>8s} {'L1':>8s} {'L2':>8s} "
          f"{'L1 wrap':>8s} {'L3 statics':>10s} {'steps':>5s} {'solve':>7s} {'L3 at rest':>10s}")
    for dc in (0.0, -0.5e-3, -2e-3, -5e-3, -10e-3, -20e-3):
        a = d0.centre_distance + dc
        m = load_scene(PATH, fidelity=1, static_tension=None, drive_centre_distance=a).model()
        d, p = m.drive, m.params
        levels = _levels(drive_centre_distance=a)
        try:
            wrap = load_scene(PATH, fidelity=1, static_tension=None, drive_centre_distance=a,
                              torsional_wrap_statics=True).model().static_tension()
        except ValueError:
            wrap = math.nan
        m3 = load_scene(PATH, fidelity=3, static_tension=None, drive_centre_distance=a).model()
        sol = static_state(m3)
        print(f"{1e3 * dc:8.1f} {parabola(d, p):9.2f} "
              f"{ladder(d, p):7.1f} {levels[0]:8.2f} {levels[1]:8.2f} {levels[2]:8.2f} "
              f"{wrap:8.2f} {sol.mean_tension:10.2f} {sol.iterations:5d} "
              f"{1e3 * sol.wall:5.0f}ms {at_rest(m3, sol.state):10.2f}", flush=True)
    print()
    print(f"{'pretension':>10s} {'parabola':>9s} {'ladder':>7s} {'L0':>8s} {'L1':>8s} {'L2':>8s} "
          f"{'L3 statics':>10s} {'L1 vs L3':>8s}")
    for pre in (0.0, 1.0, 10.0, 50.0, 100.0, 200.0, 400.0, 800.0):
        kw = {"chain_pretension": pre}
        m = load_scene(PATH, fidelity=1, static_tension=None, **kw).model()
        levels = _levels(**kw)
        t3 = static_state(load_scene(PATH, fidelity=3, static_tension=None, **kw).model()
                          ).mean_tension
        print(f"{pre:10.1f} {parabola(m.drive, m.params):9.2f} "
              f"{ladder(m.drive, m.params):7.1f} {levels[0]:8.2f} {levels[1]:8.2f} "
              f"{levels[2]:8.2f} {t3:10.2f} {100 * (levels[1] / t3 - 1):+7.1f}%", flush=True)


UNSEEN = [(21, 42, "12A"), (17, 51, "08A"), (19, 38, "10A"), (13, 39, "08B")]


def unseen():
    import tempfile
    from pathlib import Path

    from chainmodel.new_scene import scene_text
    print()
    print(f"{'drive':>12s} " + " ".join(f"{p:>26g}" for p in (0, 10, 50, 100, 200)))
    with tempfile.TemporaryDirectory() as tmp:
        for z1, z2, chain in UNSEEN:
            path = Path(tmp) / f"{chain}.toml"
            path.write_text(scene_text(z1, z2, 300.0, 10.0, chain=chain, static_tension=0.0))
            cells = []
            for pre in (0.0, 10.0, 50.0, 100.0, 200.0):
                t = {}
                for g in (None, 0.0):
                    kw = {"chain_pretension": pre} | ({} if g is None else {"gravity": g})
                    t1 = load_scene(path, fidelity=1, **kw).model().static_tension()
                    t3 = static_state(load_scene(path, fidelity=3, **kw).model()).mean_tension
                    t[g] = (t1, t3)
                (a, b), (c, d) = t[None], t[0.0]
                cells.append(f"{a:6.1f}/{b:6.1f} {100 * (a / b - 1):+5.1f}% ({c:3.0f}/{d:3.0f})")
            print(f"{chain + f' {z1}/{z2}':>12s} " + " ".join(f"{c:>26s}" for c in cells),
                  flush=True)


if __name__ == "__main__":
    main()
    unseen()
