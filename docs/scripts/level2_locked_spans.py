"""Level 2's spans locked on the meshing: the spans' mean tension sum (tight + slack, second
half of a 0.6 s run) of levels 2 and 3 against a rigid chain's (twice the static tension, or
the driven sprocket's tension difference, load and driven damping, over a slack span at the
weight's floor, plus both spans' centrifugal tension: chainmodel.validity, "span vibration"), on the trade study's scenes and on
an independent audit's 08A 9/10 drive of 25 links (docs/reduced_models.md, "Level 2's spans
locked on the meshing"). A level-2 row marked * carries the span_vibration warning.

    python docs/scripts/level2_locked_spans.py          # about 60 s with warm kernels
"""

from __future__ import annotations

from pathlib import Path

import chainmodel
from chainmodel.models.kinematic import centrifugal_tension
from chainmodel.models.span_sag import hanging_tension

MIXER = str(Path(__file__).resolve().parents[2] / "examples" / "scenes" / "16b_mixer.toml")
SMALL = dict(chain="08A", drive_pitch=0.0127, drive_driver_teeth=9, drive_driven_teeth=10,
             drive_links=25, drive_centre_distance=0.0, load_torque=3.0,
             driver_inertia=1.465e-5, driven_inertia=2.199e-5)
CASES = ([("xu2010", "xu2010", dict(input_speed_rpm=v)) for v in (120, 600, 2000)]
         + [("C1", "C1", dict(input_speed_rpm=v)) for v in (100, 400)]
         + [("16B mixer", MIXER, dict(input_speed_rpm=v)) for v in (200, 500)]
         + [("08A 9/10 (audit)", "xu2010", dict(SMALL, input_speed_rpm=v))
            for v in (300, 450, 600, 900, 1200)])


def main():
    print(f"{'scene':18s} {'rpm':>5s}  {'rigid [N]':>9s}  {'level 2 [N]':>16s}  "
          f"{'level 3 [N]':>16s}  level 2 / 3")
    for label, scene, kw in CASES:
        sums = {}
        for level in (2, 3):
            r = chainmodel.simulate(scene, fidelity=level, duration=0.6, **kw)
            m = r.time >= 0.3
            sums[level] = float(r["tight_span.tension"][m].mean()
                                + r["slack_span.tension"][m].mean())
            warned = any(p.code == "span_vibration" for p in r.problems)
            sums[(level, "warned")] = warned
            sc = r.scene
        d, p = sc.drive, sc.parameters
        speed = sc.operating.speed
        torque = sc.operating.load_torque + p["driven.damping"] * speed * d.tooth_ratio
        rigid = (max(2.0 * r.static_tension, abs(torque) / d.driven.pitch_radius
                     + 2.0 * hanging_tension(d, p))
                 + 2.0 * float(centrifugal_tension(d, p, speed)))
        mark = "*" if sums[(2, "warned")] else " "
        print(f"{label:18s} {kw['input_speed_rpm']:5g}  {rigid:9.1f}  {sums[2]:8.1f} "
              f"({sums[2] / rigid:4.2f}x){mark} {sums[3]:8.1f} ({sums[3] / rigid:4.2f}x)  "
              f"{sums[2] / sums[3]:.2f}")


if __name__ == "__main__":
    main()
