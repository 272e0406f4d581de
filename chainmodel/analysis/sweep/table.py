"""The sweep's tidy tables: one row per case (its settings, status, error and metrics) and one
row per case and frequency of its tension spectrum - Parquet where pyarrow is installed, else
CSV (first row the names, second their units, as every chainmodel CSV).

Timings are not in the tables (they are in the journal), so the same study writes the same
tables however it ran - serially, on two workers or on a cluster.
"""

from __future__ import annotations

import csv
import math
import numbers
from pathlib import Path
from typing import Any, Sequence

import numpy as np

from .metrics import METRIC_UNITS

__all__ = ["columns", "write_table", "read_table", "pyarrow_available", "spectra_columns"]

_FIRST = ("case",)
_TEXT = ("status", "error", "resonance_with")


def pyarrow_available() -> bool:
    try:
        import pyarrow  # noqa: F401
        import pyarrow.parquet  # noqa: F401
    except ImportError:
        return False
    return True


def columns(records: Sequence[dict], varied: Sequence[str]) -> dict[str, list]:
    """The case table as columns, in the order case, the varied settings, status, error, then
    the metrics (:data:`~.metrics.METRIC_UNITS`); rows sorted by case."""
    rows = sorted((r["row"] for r in records), key=lambda r: r["case"])
    names = list(_FIRST) + list(varied) + ["status", "error"] + list(METRIC_UNITS)
    return {n: [r.get(n) for r in rows] for n in names}


def spectra_columns(spectra) -> dict[str, list]:
    """Long form of the spectra: case, frequency_hz, amplitude_n."""
    case, freq, amp = [], [], []
    for i, f, a in sorted(spectra, key=lambda s: s[0]):
        case += [i] * len(f)
        freq += f.tolist()
        amp += a.tolist()
    return {"case": case, "frequency_hz": freq, "amplitude_n": amp}


def _kind(name: str, values: list) -> str:
    present = [v for v in values if v is not None]
    if name in _TEXT or any(isinstance(v, str) for v in present):
        return "string"
    if present and all(isinstance(v, bool) for v in present):
        return "bool"
    if present and all(isinstance(v, numbers.Integral) and not isinstance(v, bool)
                       for v in present):
        return "int"
    return "float"


def _units(name: str) -> str:
    return METRIC_UNITS.get(name, "")


def write_table(cols: dict[str, list], path_stem: str | Path, units: dict[str, str] | None = None,
                fmt: str = "auto") -> Path:
    """Write ``cols`` to ``<stem>.parquet`` (pyarrow; ``fmt="auto"`` picks it when installed)
    or ``<stem>.csv``; returns the path written."""
    units = units or {}
    stem = Path(path_stem)
    if fmt not in ("auto", "parquet", "csv"):
        raise ValueError(f"table format must be auto, parquet or csv, got {fmt!r}")
    if fmt == "parquet" and not pyarrow_available():
        raise ValueError("Parquet output needs pyarrow: pip install pyarrow (or use csv)")
    if fmt == "parquet" or (fmt == "auto" and pyarrow_available()):
        return _write_parquet(cols, stem.with_suffix(".parquet"), units)
    return _write_csv(cols, stem.with_suffix(".csv"), units)


def _write_parquet(cols, path: Path, units) -> Path:
    import pyarrow as pa
    import pyarrow.parquet as pq
    fields, arrays = [], []
    for name, values in cols.items():
        kind = _kind(name, values)
        typ = {"string": pa.string(), "bool": pa.bool_(), "int": pa.int64(),
               "float": pa.float64()}[kind]
        if kind == "float":
            values = [math.nan if v is None else float(v) for v in values]
        elif kind == "string":
            values = [None if v is None else str(v) for v in values]
        unit = units.get(name, _units(name))
        fields.append(pa.field(name, typ, metadata={"unit": unit} if unit else None))
        arrays.append(pa.array(values, type=typ))
    table = pa.Table.from_arrays(arrays, schema=pa.schema(fields))
    pq.write_table(table, path)
    return path


def _cell(v: Any) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _write_csv(cols, path: Path, units) -> Path:
    names = list(cols)
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        w.writerow([units.get(n, _units(n)) for n in names])
        for row in zip(*(cols[n] for n in names)):
            w.writerow([_cell(v) for v in row])
    return path


def read_table(path: str | Path) -> dict[str, list]:
    """A table written by :func:`write_table`, as columns (CSV cells parsed back: numbers,
    true/false, empty = None)."""
    path = Path(path)
    if path.suffix == ".parquet":
        import pyarrow.parquet as pq
        return pq.read_table(path).to_pydict()
    with path.open(newline="") as fh:
        rows = list(csv.reader(fh))
    names, data = rows[0], rows[2:]

    def parse(text: str):
        if text == "":
            return None
        if text in ("true", "false"):
            return text == "true"
        for conv in (int, float):
            try:
                return conv(text)
            except ValueError:
                pass
        return text
    return {n: [r[k] if n in _TEXT else parse(r[k]) for r in data]
            for k, n in enumerate(names)}


def as_float_array(values: list) -> np.ndarray:
    return np.array([math.nan if v is None else float(v) for v in values])
