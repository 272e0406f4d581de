"""The measured speed-accuracy trade (issue 11): every level x stepper on twelve scenes against a
converged level-3 reference and its uncertainty band (issue 21); writes the CSV that
``fidelity="auto"`` reads, the docs' tables, the figures and docs/tradeoff.md's marked blocks.

    python benchmarks/tradeoff.py              # the study (same as `chainmodel bench tradeoff`)
    python benchmarks/tradeoff.py --fmu        # ... and the FMU cost per step at 1e-4 and 1e-3 s
    python benchmarks/tradeoff.py --scenes "xu2010 120 rpm" --repeats 1   # one scene, quick

Outputs: chainmodel/data/tradeoff.csv, docs/tradeoff_results.md, docs/figures/tradeoff_pareto.png,
docs/figures/tradeoff_map.png. Level-3 references are cached in ~/.cache/chainmodel/tradeoff
(keyed by a hash of the whole scene).
"""

from __future__ import annotations

import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from chainmodel.cli import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main(["bench", "tradeoff", *sys.argv[1:]]))
