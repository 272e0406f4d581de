"""Mean span tensions of levels 1, 2 and 3 on xu2010 at several speeds, and level 3 loaded at rest
(docs/reduced_models.md, "Level 1 versus level 3"). About 5 minutes with numba.

Run: python docs/scripts/mean_tensions.py

Every run is seed 003's scene (0.05 s ramp, 43.2 N m) for 0.6 s; means over 0.3-0.6 s. Level 2 runs
with its default modal damping and with level 3's span damping (level3_span_damping_ratio). For
level 3 it also prints the mean geometric excess of each span: the length of the polyline through
its rollers minus the distance between its endpoint rollers, the extra length that transverse
motion (and sag) takes out of the span's stretch.
"""
import math

import numpy as np

import chainmodel
from chainmodel.integrate import Verlet
from chainmodel.models import Inputs
from chainmodel.scene import load_scene


def span_excess(snapshot):
    """(tight, slack) polyline-minus-chord length of the two free runs of rollers [m]."""
    z = snapshot["roller_positions"]
    free = ~(snapshot["engaged_driver"] | snapshot["engaged_driven"])
    tight_ends = set(int(i) for i in snapshot["tight_span_rollers"])
    m = len(z)
    out = {}
    for i0 in (i for i in range(m) if free[i] and not free[i - 1]):
        j = i0
        while free[j % m]:
            j += 1
        ids = [(i0 - 1 + k) % m for k in range(j - i0 + 2)]
        pts = z[ids]
        excess = np.sum(np.hypot(*np.diff(pts, axis=0).T)) - np.hypot(*(pts[-1] - pts[0]))
        out["tight" if {ids[0], ids[-1]} & tight_ends else "slack"] = excess
    return out.get("tight", np.nan), out.get("slack", np.nan)


def running(level, **kw):
    snap = 5 if level == 3 else 0
    r = chainmodel.simulate("xu2010", fidelity=level, duration=0.6, output_interval=2e-4,
                            snapshot_every=snap, **kw)
    m = r.time >= 0.3
    row = [r["tight_span.tension"][m].mean(), r["slack_span.tension"][m].mean()]
    if level == 3:
        ex = np.array([span_excess(s) for t, s in r.snapshots if t >= 0.3])
        row += list(1e6 * np.nanmean(ex, axis=0))
    return row


def level3_span_damping_ratio():
    """modal.damping_ratio that gives level 2's first span modes the decay rate level 3's joint
    dampers give them: sigma = c_j p (pi / l)^4 / (2 rho) (docs/multibody.md, "Convergence and
    default damping"), divided by level 2's own omega_1 at the static tension (its damping term
    is 2 zeta m omega_1 q_m'); the mean over both spans."""
    model = load_scene("xu2010", fidelity=2).model()
    p = model.params
    rho = p["chain.link_mass"] / model.drive.pitch
    t0 = model.static_tension()
    zetas = []
    for span, key in (("upper", "l_up"), ("lower", "l_low")):
        lbar = model.reference[key]
        sigma = p["chain.joint_damping"] * model.drive.pitch * (math.pi / lbar) ** 4 / (2 * rho)
        zetas.append(sigma / float(model.modal_frequencies(t0, 0.0, span)[0]))
    return float(np.mean(zetas))


def loaded_at_rest(angle, load=43.2):
    """Level 3 relaxed with the driver held at ``angle`` and the load ramped on over 0.2 s."""
    sc = load_scene("xu2010", fidelity=3)
    relax = dict(sc.parameters)
    relax["chain.link_damping"] = 0.25 * math.sqrt(relax["chain.link_stiffness"]
                                                   * relax["chain.link_mass"])
    relax["driven.damping"] = 0.05
    relax["chain.joint_damping"] = 0.05
    st = Verlet(type(sc.model())(sc.drive, relax), 0.0, None, Inputs(angle, 0.0, 0.0))
    for i in range(1, 601):
        st.advance(i * 1e-3, Inputs(angle, 0.0, load * min(1.0, max(0.0, (i - 200) / 200))))
    o = st.outputs()
    return o["tight_span.tension"], o["slack_span.tension"]


if __name__ == "__main__":
    tooth = 2 * math.pi / 25
    for a in (0.0, 0.25 * tooth, 0.5 * tooth):
        t, s = loaded_at_rest(a)
        print(f"level 3 loaded at rest, driver at {a / tooth:.2f} tooth: "
              f"tight {t:7.1f} N  slack {s:6.1f} N")
    zeta = level3_span_damping_ratio()
    print(f"level 3's span damping as a modal damping ratio of level 2: {zeta:.4g}")
    for rpm in (30, 60, 120):
        for label, level, kw in (("level 1", 1, {}), ("level 2", 2, {}),
                                 ("level 2, level 3's span damping", 2,
                                  {"modal_damping_ratio": zeta}),
                                 ("level 3", 3, {})):
            row = running(level, input_speed_rpm=rpm, **kw)
            extra = (f"  span excess tight {row[2]:5.1f} um  slack {row[3]:5.1f} um"
                     if len(row) > 2 else "")
            print(f"{rpm:4d} rpm  {label:32s} tight {row[0]:7.1f} N  slack {row[1]:6.1f} N{extra}")
    for label, kw in (("level 3, gravity 0", {"gravity": 0.0}),
                      ("level 3, chain.joint_damping 0.02", {"chain_joint_damping": 0.02})):
        row = running(3, **kw)
        print(f" 120 rpm  {label:32s} tight {row[0]:7.1f} N  slack {row[1]:6.1f} N"
              f"  span excess tight {row[2]:5.1f} um  slack {row[3]:5.1f} um")
