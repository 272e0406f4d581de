"""Where torsional.wrap_statics refuses its fit (docs/reduced_models.md, "Where the fit is
refused"): per drive, the fitted end compliance c, the span's elastic compliance (mean link
count / k plus the loaded seats' ladder), their ratio against wrap_statics.END_RATIO, level 3's
static tension and mode at rest, and the spans' first string mode (1 / 2L) sqrt(T_0 / rho).

    python docs/scripts/wrap_refusals.py        # about 30 s
    python docs/scripts/wrap_refusals.py tight  # xu2010 at its tight distance, 380-470 N

``tight`` scans the pretension of xu2010 at its tight centre distance (0 mm), where its two
alike spans have near-degenerate string modes ("Two alike spans"): the fitted mode and K_m, or
why the fit is refused, per pretension.

The ratio is printed for refused drives too: the gate is lifted for this table (END_RATIO set
to infinity in this process only); a negative c prints as refused.
"""
import math
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "tests"))

import chainmodel.models.wrap_statics as W  # noqa: E402
from chainmodel.models.span_sag import normal_weights  # noqa: E402
from chainmodel.scene import load_scene  # noqa: E402
from test_extremes import drive_overrides  # noqa: E402

FAN = str(ROOT / "examples/scenes/08b_fan_1500rpm.toml")
limit, W.END_RATIO = W.END_RATIO, math.inf


def cases():
    a0 = load_scene(FAN, fidelity=1, static_tension=None).drive.centre_distance
    yield "xu2010", "xu2010", {}
    for name in ("C1", "C2", "C3", "fine"):
        yield name, name, {}
    yield "08B fan", FAN, {}
    yield "08B fan, no pretension", FAN, dict(static_tension=None)
    for dc in (0.5, 2.0, 5.0):
        yield (f"08B fan, no pretension, {dc:g} mm nearer", FAN,
               dict(static_tension=None, drive_centre_distance=a0 - dc * 1e-3))
    yield "6/9 teeth, 600 N", "xu2010", dict(drive_overrides(6, 9, links=16), static_tension=600)
    yield "9/6 teeth, 600 N", "xu2010", dict(drive_overrides(9, 6, links=16), static_tension=600)
    yield "120/12 teeth, 400 N", "xu2010", dict(drive_overrides(120, 12, links=130),
                                                static_tension=400)
    yield "N 200, 500 N", "xu2010", dict(drive_overrides(25, 17, links=424), static_tension=500)
    yield "loose, f 0", "xu2010", drive_overrides(25, 17, span=11, f=0.0)
    yield "loose, f 0.999", "xu2010", drive_overrides(25, 17, span=11, f=0.999)
    yield "xu2010, links x0.01", "xu2010", dict(chain_link_stiffness=5.1e5)


def tight_scan():
    sc = load_scene("xu2010", fidelity=1, drive_centre_distance=0.0, static_tension=None)
    print("| pretension [N] | T_0 [N] | mode [Hz] | K_m [N m/rad] |")
    print("|---|---|---|---|")
    for pre in [380.0 + 5.0 * i for i in range(19)] + [450.7, 451.0, 451.3, 451.7]:
        p = dict(sc.parameters, **{"chain.pretension": pre})
        try:
            f = W.wrap_fit(sc.drive, p)
        except ValueError as exc:
            print(f"| {pre:.1f} | - | - | refused: {str(exc)[:70]}... |")
            continue
        print(f"| {pre:.1f} | {f.static_tension:.1f} | {f.mode:.1f} | {f.modal_stiffness:.0f} |")


if sys.argv[1:] == ["tight"]:
    W.END_RATIO = limit
    tight_scan()
    sys.exit(0)
print(f"END_RATIO = {limit:g}\n")
print("| drive | c [m/N] | elastic [m/N] | ratio | T_0 [N] | mode [Hz] | string [Hz] | fit |")
print("|---|---|---|---|---|---|---|---|")
for label, name, kw in cases():
    sc = load_scene(name, fidelity=1, torsional_wrap_statics=True, **kw)
    d, p = sc.drive, sc.parameters
    elastic = W.span_elastic_compliance(d, p)
    try:
        f = W.wrap_fit(d, p)
    except ValueError as exc:
        text = str(exc)
        c = re.search(r"negative end compliance \((\S+) m/N\)", text)
        slope = re.search(r"slope at rest to (\S+) ", text)
        why = (f"a negative end compliance ({c.group(1)} m/N)"
               + (f", at the floor's slope {slope.group(1)}" if slope else "")
               if c else text[:60] + "...")
        print(f"| {label} | - | {elastic:.3g} | - | - | - | - | refused: {why} |")
        continue
    rho = p["chain.link_mass"] / d.pitch
    span = normal_weights(d, p)[0][1]
    string = math.sqrt(f.static_tension / rho) / (2.0 * span)
    ratio = f.compliance / elastic
    verdict = "refused" if ratio > limit or ratio < 0 else "kept"
    print(f"| {label} | {f.compliance:.3g} | {elastic:.3g} | {ratio:.3g} | "
          f"{f.static_tension:.1f} | {f.mode:.2f} | {string:.2f} | {verdict} |")
