"""Design studies at scale: parameter sweeps of scenes, serially or on Dask.

    import chainmodel
    res = chainmodel.sweep("examples/studies/speed_pretension.toml", out="sweep_out", workers=2)
    res.table["tight_tension_ripple_rms_n"], res.files

A study (:mod:`.study`) is a base scene, settings fixed for every case and a grid or random
design over any scene setting; each case runs through the library or the FMU
(:mod:`.runner`), reduces to scalar metrics and a tension spectrum (:mod:`.metrics`, which also
defines a resonance hit from the physics), and lands in a journal as it finishes, so a sweep
that is interrupted resumes without running a finished case again. At the end the tidy tables
(:mod:`.table`) and the figures (:mod:`.plots`) are written. docs/sweep.md has the details,
including running a study on a multi-node cluster.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping

from .metrics import METRIC_UNITS, case_metrics
from .runner import SweepRun, run_case, run_cases
from .study import DRIVE_SETTINGS, FMUBlob, Study, load_study

__all__ = ["sweep", "SweepResult", "Study", "load_study", "run_case", "case_metrics",
           "METRIC_UNITS", "DRIVE_SETTINGS", "FMUBlob", "write_outputs"]


@dataclass
class SweepResult:
    """A finished sweep: ``table`` (columns by name, one entry per case, in case order),
    ``spectra`` (case, frequencies [Hz], amplitudes [N]), ``files`` written (what -> path),
    and ``run`` (how it ran: computed/reused counts, workers, timings)."""

    study: Study
    table: dict[str, list]
    spectra: list
    run: SweepRun
    files: dict[str, Path] = field(default_factory=dict)

    @property
    def failed(self) -> list[int]:
        return self.run.failed

    def to_pandas(self):
        """The case table as a pandas DataFrame (needs pandas)."""
        import pandas as pd
        return pd.DataFrame(self.table)


def write_outputs(study: Study, records: list[dict], out: str | Path, *, plots: bool = True,
                  table_format: str = "auto", map_metric: str | None = None
                  ) -> tuple[dict[str, list], list, dict[str, Path]]:
    """Write the case table, the spectra table, study.json and (``plots``, where matplotlib
    is installed) the Campbell diagram and the resonance map into ``out``."""
    from .runner import records_to_spectra
    from .table import columns, spectra_columns, write_table
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    cols = columns(records, study.varied)
    spectra = records_to_spectra(records)
    files: dict[str, Path] = {}
    files["table"] = write_table(cols, out / "results", fmt=table_format)
    files["spectra"] = write_table(spectra_columns(spectra), out / "spectra",
                                   {"frequency_hz": "Hz", "amplitude_n": "N"}, fmt=table_format)
    meta = {"name": study.name, "scene": study.base.name, "design": study.design,
            "cases": len(study), "varied": list(study.varied), "fixed": study.fixed,
            "resonance_band": study.resonance_band, "spectrum_max_hz": study.spectrum_max_hz,
            "fmu_sha256": study.fmu.sha256 if study.fmu else None,
            "fingerprint": study.fingerprint()}
    (out / "study.json").write_text(json.dumps(meta, indent=1, default=repr) + "\n")
    files["study"] = out / "study.json"
    if plots and any(s == "ok" for s in cols["status"]):
        try:
            from ...plots import require_matplotlib
            require_matplotlib()
        except ImportError:
            return cols, spectra, files
        from .plots import plot_campbell, plot_resonance_map
        ok = [i for i, s in enumerate(cols["status"]) if s == "ok"]
        ok_cols = {k: [v[i] for i in ok] for k, v in cols.items()}
        files["campbell"] = plot_campbell(ok_cols, spectra, study.varied, out / "campbell.png",
                                          study.design, f"{study.name}: tight-span tension "
                                          "spectrum (Campbell diagram)")
        files["resonance_map"] = plot_resonance_map(ok_cols, study.varied,
                                                    out / "resonance_map.png", map_metric,
                                                    study.design)
    return cols, spectra, files


def sweep(study: "str | Path | Mapping[str, Any] | Study", out: str | Path | None = None, *,
          serial: bool = False, workers: int | None = None, scheduler: str | None = None,
          via_fmu: str | Path | None = None, chunk_size: int | None = None,
          retry_failed: bool = False, plots: bool = True, table_format: str = "auto",
          map_metric: str | None = None, progress: bool = False,
          on_record: Callable[[dict], None] | None = None, **fixed) -> SweepResult:
    """Run a study's cases and write its tables and figures into ``out``.

    ``study``: a study .toml, a dict of the same layout, or a :class:`Study`; ``fixed``
    keyword settings are added to its [fixed] table (e.g. ``duration=0.2`` for a quick try).
    Where: ``serial=True`` in this process; ``scheduler="tcp://host:8786"`` on an existing Dask
    cluster; otherwise a LocalCluster of ``workers`` processes (default: this machine's cores).
    ``via_fmu``: run each case through this FMU with fmpy instead of the library.
    ``out`` (default ``<study name>_sweep``) keeps the journal: cases already in it are reused,
    failed ones too unless ``retry_failed``. The study is checked before any case runs."""
    st = load_study(study, **fixed)
    if via_fmu is not None:
        st = st.with_fmu(via_fmu)
    if sum(bool(x) for x in (serial, workers is not None, scheduler is not None)) > 1:
        raise ValueError("choose one of serial, workers and scheduler")
    out = Path(out) if out is not None else Path(f"{st.name}_sweep")
    run = run_cases(st, out, serial=serial, workers=workers, scheduler=scheduler,
                    chunk_size=chunk_size, retry_failed=retry_failed, progress=progress,
                    on_record=on_record)
    cols, spectra, files = write_outputs(st, run.records, out, plots=plots,
                                         table_format=table_format, map_metric=map_metric)
    files = {"journal": out / "cases.jsonl", **files}
    return SweepResult(st, cols, spectra, run, files)
