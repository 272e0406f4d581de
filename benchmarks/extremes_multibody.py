"""Level 3 (multibody) across issue 10's stress matrix: what each case does.

    python benchmarks/extremes_multibody.py            # the table of docs/multibody.md
    python benchmarks/extremes_multibody.py --duration 0.6

Every case is xu2010 (seed 003 section 7: 25/17 teeth, 46 links, 197.7 mm, 0.05 s ramp to
120 rpm, 43.2 N m) with the overrides shown, run for --duration seconds (shorter for the costly
stiff cases); figures over the second half: finite, the relative error of the mean tooth ratio
(a skipped tooth shows as percent), the span tensions' minima, the smallest link tension
(0: a slack link; negative: plates bearing), the time fraction with a slack link, CPU seconds.
A refused case prints the first line of its message. The fast subset is
tests/test_extremes_multibody.py.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

import chainmodel  # noqa: E402
from chainmodel.analysis.summary import tooth_ratio  # noqa: E402

CASES = (
    ("xu2010 as given", {}),
    ("teeth 6/9, tight distance", dict(drive_driver_teeth=6, drive_driven_teeth=9, drive_centre_distance=0)),
    ("teeth 9/6, tight distance", dict(drive_driver_teeth=9, drive_driven_teeth=6, drive_centre_distance=0)),
    ("teeth 9/9, tight distance", dict(drive_driver_teeth=9, drive_driven_teeth=9, drive_centre_distance=0)),
    ("teeth 17/25, tight distance", dict(drive_driver_teeth=17, drive_driven_teeth=25, drive_centre_distance=0)),
    ("teeth 120/25, 200 links", dict(drive_driver_teeth=120, drive_driven_teeth=25, drive_links=200, drive_centre_distance=0)),
    ("3 links", dict(drive_links=3)),
    ("200 links, tight distance", dict(drive_links=200, drive_centre_distance=0)),
    ("0 rpm", dict(input_speed_rpm=0)),
    ("-120 rpm (reversed)", dict(input_speed_rpm=-120)),
    ("1000 rpm", dict(input_speed_rpm=1000)),
    ("3000 rpm", dict(input_speed_rpm=3000)),
    ("10000 rpm", dict(input_speed_rpm=10000)),
    ("no load", dict(load_torque=0)),
    ("10x load (432 N m)", dict(load_torque=432)),
    ("no damping at all", dict(chain_link_damping=0, contact_damping=0, input_shaft_damping=0, chain_joint_damping=0)),
    ("link stiffness x0.001", dict(chain_link_stiffness=5.1e4)),
    ("link stiffness x0.01", dict(chain_link_stiffness=5.1e5)),
    ("link stiffness x100", dict(chain_link_stiffness=5.1e9, duration=0.1)),
    ("contact stiffness x0.01", dict(contact_stiffness=8.46e4)),
    ("contact stiffness x100", dict(contact_stiffness=8.46e8, duration=0.15)),
    ("solver radau", dict(solver_method="radau")),
)


def run_case(kw, duration):
    kw = dict(kw)
    duration = min(duration, kw.pop("duration", duration))
    c0 = time.process_time()
    try:
        r = chainmodel.simulate("xu2010", fidelity=3, duration=duration, output_interval=2e-4, **kw)
    except Exception as e:  # noqa: BLE001 - the table reports every refusal
        return f"refused ({type(e).__name__}): {str(e).splitlines()[0][:160]}", time.process_time() - c0
    cpu = time.process_time() - c0
    m = r.time >= duration / 2
    d = r.scene.drive
    finite = all(np.all(np.isfinite(r[n])) for n in r.names)
    if abs(r.scene.operating.speed) > 0:
        # against the input-shaft angle (prescribed, monotonic), not the driver sprocket's
        # (a state, which in a rattling drive does not turn monotonically)
        phi_in = r.scene.input_arrays(r.time[m])[0]
        ratio = tooth_ratio(phi_in, r["driven.angle"][m], d.n_driver)
        err = f"{ratio / (d.n_driver / d.n_driven) - 1:+.1e}"
    else:
        err = "(at rest)"
    low = r["chain.min_link_tension"][m]
    return (f"{'yes' if finite else 'NO'} | {err} | {r['tight_span.tension'][m].min():.0f} | "
            f"{r['slack_span.tension'][m].min():.0f} | {low.min():.0f} | {np.mean(low <= 0):.2f}"), cpu


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--duration", type=float, default=0.3)
    args = ap.parse_args(argv)
    print(f"level 3, {args.duration:g} s per case (stiff cases shorter); load average "
          f"{os.getloadavg()[0]:.2f}")
    print("| case | finite | tooth-ratio error | min tight [N] | min slack [N] | min link [N] | "
          "slack-link time | CPU s |")
    print("|---|---|---|---|---|---|---|---|")
    for name, kw in CASES:
        row, cpu = run_case(kw, args.duration)
        if row.startswith("refused"):
            print(f"| {name} | {row} | | | | | | {cpu:.1f} |")
        else:
            print(f"| {name} | {row} | {cpu:.1f} |")


if __name__ == "__main__":
    main()
