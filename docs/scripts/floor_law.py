"""Level 3's slack span at rest under load against levels 1-2's floored span law (issue 21 item
3, docs/reduced_models.md "The floor law across loads"): for a scene, level 3's statics at load
shares s (the load torque s 2 T_0 R_o) averaged over wrap_fit's driver positions, the law's slack
span with the fitted floor, and the law refitted at other shares.

    python docs/scripts/floor_law.py [xu2010|C1|scene]      # a few seconds
    python docs/scripts/floor_law.py running SHARE          # xu2010 running, about 10 s

``running SHARE``: xu2010 at 30 / 60 / 120 rpm (means over 0.3-0.6 s) at levels 1-2 with the floor
fitted where a linear law's slack span would carry SHARE T_0 (wrap_statics.SLACK_SHARE, 0.25 by
default; 0.0 fits it at the load share 1.0 above), set in this process only.
"""
import sys, numpy as np
from chainmodel.scene import load_scene
from chainmodel.models import wrap_statics as WS
from chainmodel.models.multibody import MultibodyModel
from chainmodel.models.multibody_statics import solve_statics, static_state
from chainmodel.kinematics.wrapping import tooth_period_geometry
from chainmodel import parameters as PRM

name = sys.argv[1] if len(sys.argv) > 1 else "xu2010"
if name == "running":
    import chainmodel
    WS.SLACK_SHARE = float(sys.argv[2])
    for rpm in (30, 60, 120):
        out = []
        for level in (1, 2):
            r = chainmodel.simulate("xu2010", fidelity=level, input_speed_rpm=rpm, duration=0.6,
                                    output_interval=2e-4)
            m = r.time >= 0.3
            out.append(f"level {level} {r['tight_span.tension'][m].mean():.1f} / "
                       f"{r['slack_span.tension'][m].mean():.1f} N")
        print(f"{rpm} rpm:", ", ".join(out), flush=True)
    sys.exit(0)
sc = load_scene(name, fidelity=1)
d, p = sc.drive, sc.parameters
fit = WS.wrap_fit(d, p)
p3 = {k: v for k, v in p.items() if k in PRM.BY_NAME}
m3 = MultibodyModel(d, p3)
t0, ro = fit.static_tension, d.driven.pitch_radius
g = tooth_period_geometry(d, 100)
nu, nl = float(np.mean(g.upper_links)), float(np.mean(g.lower_links))
k = p3["chain.link_stiffness"]
print(f"T0 {t0:.1f} b {fit.softness:.2f} c {fit.compliance:.3g} loaded_slack {fit.loaded_slack:.2f}")
shares = np.array([0.25, 0.5, 0.75, 0.9, 1.0, 1.1, 1.25, 1.5])
res = {s: [] for s in shares}
for angle in WS.tooth_positions(d):
    st = static_state(m3, angle); state = st.state
    for s in shares:
        sol = solve_statics(m3, angle, s * 2 * t0 * ro, start=state); state = sol.state
        res[s].append(min(sol.tension_upper, sol.tension_lower))
for s in shares:
    s3 = np.mean(res[s]); dt = s * 2 * t0
    s1 = WS._split_slack(t0, fit.softness, fit.compliance, (nu, nl, k, (0.0, 0.0)), dt)
    print(f"share {s:.2f} dt {dt:7.1f}  L3 slack {s3:7.2f}  law {s1:7.2f}  {100*(s1/s3-1):+6.1f}%")
print("refit at other loads")
for fs in (0.75, 0.9, 1.0, 1.1):
    WS.SLACK_SHARE = 1 - fs
    c, f, b = WS._ends(d, p3, t0, float(np.mean(res[fs])), fit.modal_stiffness)
    errs = []
    for s in shares:
        s1 = WS._split_slack(t0, b, c, (nu, nl, k, (0.0, 0.0)), s * 2 * t0)
        errs.append(100 * (s1 / np.mean(res[s]) - 1))
    print(f"fit at {fs:.2f}: b {b:.1f} c {c:.3g} ", " ".join(f"{e:+.1f}" for e in errs))
