"""What passing over the levels above their span-modes line changes in ``fidelity="auto"``'s
choice (docs/tradeoff.md, "Auditing the promise", *Levels that hold the spans' modes*;
twenty-ninth session of issue 21).

On the drives of ``auto_audit.py`` (its 27 and its 60 ``--new-drives``), for the tight and the
slack span at 10, 20 and 50 %: :func:`chainmodel.fidelity_auto.choose` as it is, and as it was
before, when it took the cheapest configuration the table says meets the target whatever the
level's span-modes line (here: ``SPAN_LINES`` emptied for the call). Every case whose choice
differs is run both ways on the drive and measured as the audit measures (worst case over
level 3's band, and against its nominal run; level 3's runs cached as the audit caches them).

    python docs/scripts/auto_span_choice.py      # about 2 min with warm kernels and cache
"""

from __future__ import annotations

import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import auto_audit as A                                              # noqa: E402
import chainmodel.fidelity_auto as auto                             # noqa: E402
from chainmodel.analysis import trade_study as study                # noqa: E402
from chainmodel.simulation import run_scene                         # noqa: E402


def before(scene, output, accuracy):
    """The choice without the span-modes preference (nor, here, its promise rule)."""
    lines = dict(auto.SPAN_LINES)
    auto.SPAN_LINES.clear()
    try:
        return auto.choose(scene, [output], accuracy)
    finally:
        auto.SPAN_LINES.update(lines)


def main():
    start = time.perf_counter()
    cache = Path(tempfile.gettempdir()) / "chainmodel_auto_audit"
    drives = A.new_drives(Path(tempfile.mkdtemp())) + A.DRIVES
    print("| drive | output | accuracy | before: level, over the band (against the nominal) | "
          "now | now promised |\n|---|---|---|---|---|---|")
    cases = changed = 0
    for label, source, rpm, extra in drives:
        kw = dict(input_speed_rpm=rpm, duration=A.duration(source, rpm, extra, 1.0), **extra)
        spec = study.SceneSpec(label, str(source), kw)
        scene = spec.scene()
        band, figures = None, {}
        for output in ("tight_span.tension", "slack_span.tension"):
            for acc in A.ACCURACIES:
                cases += 1
                old, new = before(scene, output, acc), auto.choose(scene, [output], acc)
                if old.config == new.config:
                    continue
                changed += 1
                band = band or study.reference_band(spec, cache_dir=cache)
                cells = []
                for c in (old, new):
                    if c.config not in figures:
                        figures[c.config] = study.metrics(
                            run_scene(scene.with_overrides(**c.overrides)))
                    be = study.band_errors(figures[c.config], band["figures"], band["lo"],
                                           band["hi"])
                    figs = auto.OUTPUT_FIGURES[output]
                    cells.append(f"level {c.level}: {100 * max(be['err'][f] for f in figs):.1f}"
                                 f" ({100 * max(be['errnom'][f] for f in figs):.1f}) %")
                promise = (f"{100 * new.expected_error:.1f} %" if new.promised else
                           "no: " + new.why_not[:60] + "...")
                print(f"| {label} | {output} | {acc:g} | {cells[0]} | {cells[1]} | {promise} |",
                      flush=True)
    print(f"\n{changed} of {cases} cases changed; wall {time.perf_counter() - start:.0f} s")


if __name__ == "__main__":
    main()
