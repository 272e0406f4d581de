"""Level 2's spans against level 3's on drives nobody tuned for: what its span warnings say
where its span tensions are off (docs/reduced_models.md, "Level 2's spans locked on the
meshing", the twenty-eighth session's survey).

Six chains (08A, 08B, 10B, 12B, 12A, 16B) x five tooth pairs (8/16 of 32 links, 9/10 of 25,
11/33 of 44, 13/26 of 40, 17/34 of 48, each wrapping tightly) x 200, 600 and 1200 rpm, no load,
sprockets as steel discs (`chainmodel new-scene`'s), 1 s runs with its 0.05 s ramp; without
pretension (``none``, the default) or at `new-scene`'s 2 % of the breaking load
(``pretension``). Per drive: the spans' mean tension sum over 0.6-1 s at levels 2 and 3, each
against a rigid chain's (``Monitor.rigid_sum``: twice the static tension or the driven
sprocket's tension difference, plus the centrifugal tension), and level 2's span warnings
(``span_vibration``, ``span_modes_beyond``), with the meshing frequency over the slack
span's first string mode at level 2's mean slack tension (fm/f1; seed 004 eq 61). The summary
counts the drives where level 2's sum is off level 3's by more than a factor 1.5 either way,
and which of them are warned.

    python docs/scripts/level2_span_survey.py              # about 30 s with warm kernels
    python docs/scripts/level2_span_survey.py pretension
    python docs/scripts/level2_span_survey.py pretension --spans
    python docs/scripts/level2_span_survey.py pretension --spans --level 1
    python docs/scripts/level2_span_survey.py pretension --spans --loaded

``--loaded`` loads each drive to its static tension (load torque T0 r_o, T0 level 0's static
tension, as docs/scripts/auto_audit.py ``--new-drives`` does; twenty-ninth session).

``--spans`` prints instead each span's error of level 2 against level 3 (tight / slack, means
over 0.6-1 s), the rows sorted by fm/f1, each marked where it fails the criterion the span-modes
lines were drawn on (more than 3 % off on the tight span or 6 % on the slack span): the
evidence for `span_modes_beyond`'s line at 1.5 f_1 (docs/reduced_models.md, "Level 2 beyond
its modes"), and a count of the failing drives no span warning covers. ``--level 0`` or ``1``
compares that level instead of level 2 (its span warnings: ``span_modes_missing``,
``slack_span_hanging``, ``hanging_spans``; level 0 refuses the faster drives).

It reads the public API and chainmodel.validity.Monitor, so it runs on an older checkout too.
"""

from __future__ import annotations

import os
import sys
import tempfile
import time

import numpy as np

import chainmodel
from chainmodel.new_scene import scene_text
from chainmodel.models.limits import drive_string_frequency
from chainmodel.scene import load_scene
from chainmodel.validity import Monitor

CHAINS = ("08A", "08B", "10B", "12B", "12A", "16B")
TEETH = ((8, 16, 32), (9, 10, 25), (11, 33, 44), (13, 26, 40), (17, 34, 48))
SPEEDS = (200.0, 600.0, 1200.0)
SPAN_CODES = ("span_vibration", "span_modes_beyond", "span_modes_missing", "slack_span_hanging",
              "hanging_spans")
#: level 2's span sum is called off where it is more than this factor from level 3's
OFF = 1.5


def run(path, level, spans=None):
    """(span sum, rigid chain's sum) over 0.6-1 s, the run's problem codes and the meshing
    frequency over the slack span's first string mode at the run's mean slack tension;
    ``spans``, a dict, gets the (tight, slack) means."""
    r = chainmodel.simulate(path, fidelity=level)
    m = r.time >= 0.6
    total = float(np.mean(r["tight_span.tension"][m] + r["slack_span.tension"][m]))
    if spans is not None:
        spans[level] = (float(np.mean(r["tight_span.tension"][m])),
                        float(np.mean(r["slack_span.tension"][m])))
    sc = r.scene
    rigid = Monitor(sc.drive, sc.parameters, level).rigid_sum(
        r["driver.speed"][m], r["driven.speed"][m], sc.operating.load_torque)
    speed = float(np.mean(np.abs(r["driver.speed"][m])))
    f_1 = drive_string_frequency(sc.drive, sc.parameters,
                                 float(np.mean(r["slack_span.tension"][m])), speed)
    f_m = speed * sc.drive.n_driver / (2.0 * np.pi)
    return total, float(np.mean(rigid)), [p.code for p in r.problems], f_m / f_1


def main(which, per_span=False, level=2, loaded=False):
    static = 0.0 if which == "none" else None
    folder = tempfile.mkdtemp()
    rows = []
    print(f"{'drive':>22s} {'rpm':>5s} {'level 2 [N] (x rigid)':>22s} "
          f"{'level 3 [N] (x rigid)':>22s} {'2 / 3':>6s} {'fm/f1':>6s}  level 2's span warnings")
    off = warned_off = warned_fine = fine = 0
    silent = []
    for chain in CHAINS:
        for z1, z2, links in TEETH:
            for rpm in SPEEDS:
                path = os.path.join(folder, f"{chain}_{z1}_{z2}_{rpm:g}.toml")
                with open(path, "w") as f:
                    f.write(scene_text(z1, z2, rpm, 0.0, chain=chain, links=links,
                                       static_tension=static, duration=1.0))
                if loaded:
                    sc0 = load_scene(path, fidelity=0)
                    load = sc0.model().static_tension() * sc0.drive.driven.pitch_radius
                    with open(path, "w") as f:
                        f.write(scene_text(z1, z2, rpm, round(load, 3), chain=chain,
                                           links=links, static_tension=static, duration=1.0))
                means = {}
                try:
                    s2, g2, codes, share = run(path, level, means)
                except ValueError as exc:      # level 0 above its speed limit
                    print(f"{chain} {z1}/{z2} at {rpm:g} rpm refused: {str(exc)[:80]}")
                    continue
                s3, g3, _, _ = run(path, 3, means)
                if per_span:
                    (t2, l2), (t3, l3) = means[level], means[3]
                    rows.append((share, f"{chain} {z1}/{z2}, {links} links", rpm,
                                 100 * (t2 / t3 - 1), 100 * (l2 / l3 - 1), codes))
                    continue
                said = [c for c in codes if c in SPAN_CODES]
                ratio = s2 / s3
                bad = ratio > OFF or ratio < 1.0 / OFF
                off += bad
                warned_off += bad and bool(said)
                warned_fine += (not bad) and bool(said)
                fine += not bad
                label = f"{chain} {z1}/{z2}, {links} links"
                if bad and not said:
                    silent.append(f"{label} at {rpm:g} rpm ({ratio:.2f} x)")
                print(f"{label:>22s} {rpm:5g} {s2:10.1f} ({s2 / g2:5.2f} x) "
                      f"{s3:10.1f} ({s3 / g3:5.2f} x) {ratio:6.2f} {share:6.2f}  "
                      f"{', '.join(said) or '-'}{'   <- off, silent' if bad and not said else ''}",
                      flush=True)
    if per_span:
        print(f"{'fm/f1':>6s} {'drive':>22s} {'rpm':>5s}  level {level} tight / slack   "
              f"level {level}'s span warnings")
        silent = 0
        for share, label, rpm, tight, slack, codes in sorted(rows):
            fails = abs(tight) > 3.0 or abs(slack) > 6.0
            said = [c for c in codes if c in SPAN_CODES]
            silent += fails and not said
            print(f"{share:6.2f} {label:>22s} {rpm:5g}  {tight:+6.1f} / {slack:+6.1f} %"
                  f"{'  fails' if fails else '       '}   {', '.join(said) or '-'}", flush=True)
        print(f"\n{len(rows)} drives; {sum(abs(r[3]) > 3.0 or abs(r[4]) > 6.0 for r in rows)} "
              f"fail 3 % / 6 %, {silent} of them with no span warning")
        return
    print(f"\n{off + fine} drives; level 2's span sum off level 3's by more than {OFF:g} x "
          f"on {off}, of which {warned_off} carry a span warning; {warned_fine} of the other "
          f"{fine} carry one too")
    print("off and silent: " + ("; ".join(silent) or "none"))


if __name__ == "__main__":
    start = time.perf_counter()
    argv = sys.argv[1:]
    level = 2
    if "--level" in argv:
        i = argv.index("--level")
        level = int(argv[i + 1])
        del argv[i:i + 2]
        if level not in (0, 1, 2):
            sys.exit(f"--level must be 0, 1 or 2 (compared with level 3), got {level}")
    args = [a for a in argv if a not in ("--spans", "--loaded")] or ["none"]
    if args[0] not in ("none", "pretension"):
        sys.exit(f"unknown case {args[0]!r}; choose none or pretension")
    if level != 2 and "--spans" not in argv:
        sys.exit("--level 0 or 1 goes with --spans (the span-sum table is level 2's)")
    main(args[0], "--spans" in argv, level, "--loaded" in argv)
    print(f"wall {time.perf_counter() - start:.0f} s")
