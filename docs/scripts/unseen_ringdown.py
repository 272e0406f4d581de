"""The driven sprocket's mode on drives the presets do not hold (issue 21 item 3,
docs/reduced_models.md "Item 3, the torsional mode: one wrap"): the three example scenes and
eight drives written by ``chainmodel new-scene`` (docs/scripts/unseen_drives/, some with no
pretension, where the spans carry only their sag tension).

Per drive: level 3 linearised at rest (wrap_fit.mode, multibody_statics.linear_driven_modes),
the ring-down after a sudden start to 5 rpm (tests/ringdown_check.py's ``ring``, band
0.6-1.4 x that mode) at level 3, at levels 1 and 2 with ``torsional.wrap_statics`` (the
default since the twelfth session) and at level 1 on the seat ladder (``torsional.wrap_statics =
false``; band 0.3-1.4 x: on a hanging chain it rings 40 % low), and K_m / K_3 (the wrap's modal
stiffness over its statics' secant). "L3 wide" is level 3's strongest peak in 10 Hz-5 kHz with
its size against the peak inside the band: a check of the mode picked that does not start from
it (on a hanging chain the spans' sag modes ring too, below the band). A drive whose scene or
fit is refused prints why.

    python docs/scripts/unseen_ringdown.py                   # about 11 s with warm kernels
    python docs/scripts/unseen_ringdown.py --disc-inertias   # the unseen drives' sprockets as
                                                             # steel discs (new-scene's now)

The unseen drives were written when `new-scene` left the sprocket inertias at xu2010's
(4.0108e-3 / 9.33e-4 kg m2); ``--disc-inertias`` runs copies whose sprockets are solid steel
discs (chainmodel.chains.sprocket_disc_inertia, what `new-scene` writes since the twenty-fifth
session; the example scenes have them already).
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from chainmodel.models.wrap_statics import wrap_fit
from chainmodel.scene import load_scene

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "tests"))
from ringdown_check import peak_frequency, ring, ring_run, spectrum  # noqa: E402

EXAMPLES = [ROOT / "examples" / "scenes" / n for n in
            ("12b_conveyor.toml", "16b_mixer.toml", "08b_fan_1500rpm.toml")]
UNSEEN = sorted((Path(__file__).resolve().parent / "unseen_drives").glob("*.toml"))
ON = {"torsional_wrap_statics": True}
WIDE = (10.0, 5000.0)


def with_disc_inertias(paths):
    """Copies of the scene files ``paths`` whose sprocket inertias are steel discs."""
    from chainmodel.chains import sprocket_disc_inertia
    folder = Path(tempfile.mkdtemp())
    out = []
    for path in paths:
        sc = load_scene(str(path))
        discs = (f'"driver.inertia" = {sprocket_disc_inertia(sc.chain, sc.drive.n_driver):.4g}\n'
                 f'"driven.inertia" = {sprocket_disc_inertia(sc.chain, sc.drive.n_driven):.4g}\n')
        text = path.read_text()
        tables = [ln for ln in text.splitlines() if ln.startswith("[")]
        assert tables[-1].startswith("[parameters]"), path   # the lines go to its last table
        (folder / path.name).write_text(text.rstrip("\n") + "\n" + discs)
        out.append(folder / path.name)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--disc-inertias", action="store_true",
                    help="the unseen drives' sprockets as steel discs")
    args = ap.parse_args(argv)
    drives = EXAMPLES + (with_disc_inertias(UNSEEN) if args.disc_inertias else UNSEEN)
    print(f"{'drive':22s} {'T0 [N]':>7s} {'Km/K3':>6s} {'L3 lin.':>8s} {'L3 ring':>8s} "
          f"{'L3 wide':>13s} {'L1 wrap':>16s} {'L2 wrap':>16s} {'L1 ladder':>16s}")
    for path in drives:
        try:
            sc = load_scene(str(path), fidelity=1, **ON)
            fit = wrap_fit(sc.drive, sc.parameters)
        except ValueError as exc:
            print(f"{path.stem:22s} refused: {exc}", flush=True)
            continue
        band = (0.6 * fit.mode, 1.4 * fit.mode)
        r3 = ring_run(str(path), 3)
        f3 = peak_frequency(r3, band)
        wide = peak_frequency(r3, WIDE)
        f, amp = spectrum(r3)
        size = amp[f == wide][0] / amp[f == f3][0]
        cells = []
        for level, kw in ((1, ON), (2, ON), (1, {"torsional_wrap_statics": False})):
            f = ring(str(path), level, band if kw is ON else (0.3 * fit.mode, band[1]),
                     **kw)
            cells.append(f"{f:8.2f} ({100 * (f / f3 - 1):+5.1f}%)")
        print(f"{path.stem:22s} {fit.static_tension:7.1f} {fit.modal_stiffness / fit.stiffness:6.2f} "
              f"{fit.mode:8.2f} {f3:8.2f} {wide:8.2f} x{size:3.1f} " + " ".join(cells), flush=True)


if __name__ == "__main__":
    main()
