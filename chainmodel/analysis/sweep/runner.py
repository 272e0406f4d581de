"""Running a study's cases: one case, a chunk of cases on one worker, and the whole sweep -
serially in this process or on Dask (a LocalCluster on this machine's cores, or an existing
cluster) - with a journal that makes an interrupted sweep resume where it stopped.

How the work is cut, after FMPy's parameter-variation example (a Dask bag in chunks, one FMU
instance per chunk): the cases still to run are dealt round-robin into chunks (so each chunk
mixes cheap and dear cases and the chunks cost about the same), one task per chunk. A chunk
runs its cases one after the other in one worker process: through the library, or through one
FMU instance reused between cases with fmi2Reset (re-instantiated where a reset is refused),
the FMU extracted once per machine (keyed by its hash, so workers share one copy). Kernels, the
library's and the FMU's, come from the per-machine numba cache (chainmodel.numba_cache,
docs/numba_cache.md): compiled once per machine, loaded once per worker process, never per case.

Results stream back as cases finish: a worker publishes each finished case as a Dask event
(``log_event``) and the client appends it to ``cases.jsonl`` at once; the chunk's return value
carries the same records, so nothing is lost if an event is. A case that raises is recorded with
its error and the chunk goes on; a chunk whose worker died has its unrecorded cases recorded as
failed. On the next run with the same output directory every case whose key (its settings, the
study's fingerprint, the library version) is in the journal is reused, not run.
"""

from __future__ import annotations

import json
import math
import os
import queue
import socket
import sys
import tempfile
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from .metrics import case_metrics, failed_metrics
from .study import FMUBlob, Study

__all__ = ["run_case", "run_chunk", "run_cases", "Journal", "SweepRun", "chunks_for",
           "JOURNAL_NAME"]

JOURNAL_NAME = "cases.jsonl"


# --- one case and one chunk (what a worker runs) ---------------------------------------------

def _fmu_dir(blob: FMUBlob) -> tuple[Path, Path]:
    """(fmu file, extracted directory) of ``blob`` on this machine: written and extracted once
    per machine under the temporary directory, keyed by the FMU's SHA-256, so every worker
    process (and every later sweep) on the machine shares one copy - and the numba cache the
    FMU's vendored package writes next to its sources."""
    root = Path(tempfile.gettempdir()) / "chainmodel-fmu" / blob.sha256[:32]
    fmu, unzipped = root / blob.name, root / "unzipped"
    if not (unzipped / "modelDescription.xml").is_file():
        from fmpy import extract
        root.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(prefix=f"{blob.sha256[:12]}-", dir=root.parent))
        (tmp / blob.name).write_bytes(blob.data)
        extract(str(tmp / blob.name), str(tmp / "unzipped"))
        try:
            os.rename(tmp, root)             # atomic; another process may have won the race
        except OSError:
            import shutil
            shutil.rmtree(tmp, ignore_errors=True)
    return fmu, unzipped


class _FMUCases:
    """One FMU session (one instance) for a chunk of cases."""

    def __init__(self, blob: FMUBlob):
        from ...fmu import FMUSession
        path, unzipped = _fmu_dir(blob)
        self.session = FMUSession(path, unzipdir=unzipped)

    def run(self, scene):
        return self.session.run(scene)

    def close(self):
        self.session.close()


def _error_text(exc: BaseException) -> str:
    return f"{type(exc).__name__}: {' '.join(str(exc).split())}"


def run_case(study: Study, index: int, fmu: "_FMUCases | None" = None) -> dict:
    """Run case ``index`` of ``study`` and reduce it: a record ``{"case", "row", "spectrum",
    "wall_time_s", "worker"}``. ``row`` holds the case's settings, ``status`` ("ok",
    "diverged" or "failed"), ``error`` ("" or the exception's type and message) and every
    metric (nan where the case failed). Never raises for a failing case."""
    from ...models import SimulationDiverged
    from ...simulation import run_scene
    start = time.perf_counter()
    row: dict[str, Any] = {"case": index, **study.cases[index]}
    spectrum: list[float] = []
    try:
        scene = study.scene(index)
        result = fmu.run(scene) if fmu is not None else run_scene(scene)
        metrics, spec = case_metrics(result, study.resonance_band, study.spectrum_max_hz)
        row.update(status="ok", error="", **metrics)
        spectrum = spec.tolist()
    except Exception as exc:            # noqa: BLE001 - a failing case is data, not a crash
        status = "diverged" if isinstance(exc, SimulationDiverged) else "failed"
        row.update(status=status, error=_error_text(exc),
                   **failed_metrics())
    return {"case": index, "row": row, "spectrum": spectrum,
            "wall_time_s": time.perf_counter() - start,
            "worker": f"{socket.gethostname()}:{os.getpid()}"}


def run_chunk(study: Study, indices: Sequence[int],
              publish: Callable[[dict], None] | None = None) -> list[dict]:
    """Run the cases ``indices`` one after the other (one FMU instance for all of them when
    the study runs through an FMU) and return their records; ``publish(record)`` is called as
    each finishes."""
    fmu = None
    records = []
    try:
        for i in indices:
            if study.fmu is not None and fmu is None:
                try:
                    fmu = _FMUCases(study.fmu)
                except Exception as exc:    # noqa: BLE001 - every case of the chunk fails alike
                    fmu = exc
            if isinstance(fmu, Exception):
                rec = {"case": i, "row": {"case": i, **study.cases[i], "status": "failed",
                                          "error": _error_text(fmu),
                                          **failed_metrics()},
                       "spectrum": [], "wall_time_s": 0.0,
                       "worker": f"{socket.gethostname()}:{os.getpid()}"}
            else:
                rec = run_case(study, i, fmu)
            records.append(rec)
            if publish is not None:
                publish(rec)
    finally:
        if fmu is not None and not isinstance(fmu, Exception):
            fmu.close()
    return records


def _dask_chunk(study: Study, indices: Sequence[int], topic: str) -> list[dict]:
    """run_chunk inside a Dask worker, publishing each finished case on ``topic``."""
    from distributed import get_worker
    worker = get_worker()
    return run_chunk(study, indices, lambda rec: worker.log_event(topic, rec))


def _warm_worker(study: Study) -> float:
    """Load this process's compiled kernels (numba's on-disk cache) for the study's levels by
    running its first case for a few output intervals; returns the seconds it took."""
    start = time.perf_counter()
    firsts: dict = {}                   # the first case of each fidelity the study names
    for i, case in enumerate(study.cases):
        firsts.setdefault(repr(case.get("fidelity")), i)
    for i in firsts.values():
        try:
            sc = study.scene(i)
        except ValueError:
            continue
        short = sc.with_overrides(duration=min(sc.duration, 3 * sc.output_interval))
        try:
            if study.fmu is not None:
                f = _FMUCases(study.fmu)
                try:
                    f.run(short)
                finally:
                    f.close()
            else:
                from ...simulation import run_scene
                run_scene(short)
        except Exception:           # noqa: BLE001 - the real case will report it
            pass
    return time.perf_counter() - start


# --- the journal ----------------------------------------------------------------------------

class Journal:
    """``cases.jsonl`` in the output directory: one JSON line per finished case (its key and
    record), appended and flushed as each case finishes. A line cut short by a kill is
    ignored on reading."""

    def __init__(self, directory: str | Path):
        self.path = Path(directory) / JOURNAL_NAME

    def load(self) -> dict[str, dict]:
        """Finished records by case key."""
        out: dict[str, dict] = {}
        if not self.path.is_file():
            return out
        with self.path.open() as fh:
            for line in fh:
                try:
                    rec = json.loads(line)
                except json.JSONDecodeError:
                    continue            # a line cut short by a kill
                if isinstance(rec, dict) and "key" in rec and "row" in rec:
                    out[rec["key"]] = rec
        return out

    def open(self):
        self.path.parent.mkdir(parents=True, exist_ok=True)
        if self.path.is_file() and self.path.stat().st_size:
            with self.path.open("rb+") as fh:     # end a line a kill cut short
                fh.seek(-1, os.SEEK_END)
                if fh.read(1) != b"\n":
                    fh.write(b"\n")
        self._fh = self.path.open("a")
        return self

    def append(self, key: str, record: dict) -> None:
        self._fh.write(json.dumps({"key": key, **record}) + "\n")
        self._fh.flush()

    def close(self) -> None:
        fh = getattr(self, "_fh", None)
        if fh is not None:
            fh.close()
            self._fh = None


# --- progress -------------------------------------------------------------------------------

class _Progress:
    """One updating line on stderr: cases done of total, failures, elapsed and left."""

    def __init__(self, enabled: bool, total: int, reused: int, label: str):
        self.enabled, self.total, self.done, self.failed = enabled, total, reused, 0
        self.first = reused
        self.label = label
        self.start = self.last = time.perf_counter()
        self.update(force=True)

    def restart(self) -> None:
        """Count elapsed time from now (the cluster is up, the cases start)."""
        self.start = time.perf_counter()
        self.update(force=True)

    def add(self, record: dict) -> None:
        self.done += 1
        self.failed += record["row"].get("status") != "ok"
        self.update()

    def update(self, force: bool = False) -> None:
        if not self.enabled:
            return
        now = time.perf_counter()
        if not force and now - self.last < 0.5 and self.done < self.total:
            return
        self.last = now
        elapsed = now - self.start
        ran = self.done - self.first
        left = self.total - self.done
        eta = f", ~{elapsed / ran * left:.0f} s left" if ran and left else ""
        failed = f", {self.failed} failed" if self.failed else ""
        sys.stderr.write(f"\r{self.label}: {self.done}/{self.total} cases "
                         f"({100 * self.done / max(self.total, 1):.0f} %){failed}, "
                         f"{elapsed:.1f} s{eta} ")
        sys.stderr.flush()

    def close(self) -> None:
        if self.enabled:
            self.update(force=True)
            sys.stderr.write("\n")
            sys.stderr.flush()


# --- the sweep -----------------------------------------------------------------------------

@dataclass
class SweepRun:
    """What :func:`run_cases` did: the records by case (all, reused ones included), how many
    ran now and how many were reused, and where."""

    records: list[dict] = field(repr=False)
    computed: int
    reused: int
    mode: str                           # "serial", "LocalCluster(N)" or the scheduler address
    workers: int
    startup_s: float                    # cluster start and worker warm-up
    wall_s: float                       # from the first task submitted to the last result
    case_seconds: float                 # sum of the run cases' own wall times
    chunks: int = 0
    failed: list[int] = field(default_factory=list)


def chunks_for(indices: Sequence[int], workers: int, chunk_size: int | None = None
               ) -> list[list[int]]:
    """Deal ``indices`` round-robin into chunks of about ``chunk_size`` cases (default: eight
    chunks per worker, the fewest that keep the workers evenly loaded to the end while each
    task holds many cases)."""
    n = len(indices)
    if n == 0:
        return []
    if chunk_size is None:
        n_chunks = min(n, 8 * max(1, workers))
    else:
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size < 1:
            raise ValueError(f"chunk_size must be a whole number >= 1, got {chunk_size!r}")
        n_chunks = math.ceil(n / chunk_size)
    return [list(indices[j::n_chunks]) for j in range(n_chunks)]


def _cluster(workers: int | None, scheduler: str | None):
    try:
        from distributed import Client, LocalCluster
    except ImportError:
        raise ValueError("parallel sweeps need dask.distributed: pip install 'chaindrive[sweep]' "
                         "(or run with --serial / serial=True)") from None
    if scheduler is not None:
        client = Client(scheduler, set_as_default=False)
        n = sum(client.nthreads().values())      # tasks the cluster runs at once
        return client, None, max(n, 1), str(scheduler)
    if workers is None:
        workers = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else \
            (os.cpu_count() or 1)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise ValueError(f"workers must be a whole number >= 1, got {workers!r}")
    import logging
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=logging.ERROR)
    client = Client(cluster, set_as_default=False)
    return client, cluster, workers, f"LocalCluster({workers})"


def run_cases(study: Study, out: str | Path, *, serial: bool = False, workers: int | None = None,
              scheduler: str | None = None, chunk_size: int | None = None,
              retry_failed: bool = False, progress: bool = False,
              on_record: Callable[[dict], None] | None = None) -> SweepRun:
    """Run every case of ``study`` not already in ``out``'s journal, appending each as it
    finishes; see the module docstring. ``retry_failed`` runs failed cases again."""
    keys = study.case_keys()
    journal = Journal(out)
    stored = journal.load()
    done: dict[int, dict] = {}
    for i, key in enumerate(keys):
        rec = stored.get(key)
        if rec is not None and not (retry_failed and rec["row"].get("status") != "ok"):
            done[i] = rec
    pending = [i for i in range(len(study)) if i not in done]
    reused = len(done)
    bar = _Progress(progress, len(study), reused, f"sweep {study.name}")
    case_seconds = 0.0
    journal.open()

    def record(rec: dict) -> None:
        nonlocal case_seconds
        i = rec["case"]
        if i in done and done[i].get("fresh"):
            return                      # already recorded from its event
        rec = {**rec, "fresh": True}
        done[i] = rec
        case_seconds += rec.get("wall_time_s", 0.0)
        journal.append(keys[i], {k: v for k, v in rec.items() if k != "fresh"})
        bar.add(rec)
        if on_record is not None:
            on_record(rec)

    startup = 0.0
    n_chunks = 0
    try:
        if serial or not pending:
            mode, n_workers = "serial", 1
            t0 = time.perf_counter()
            if pending:
                n_chunks = 1
                run_chunk(study, pending, record)
            wall = time.perf_counter() - t0
        else:
            t_start = time.perf_counter()
            client, cluster, n_workers, mode = _cluster(workers, scheduler)
            try:
                client.run(_warm_worker, study)
                startup = time.perf_counter() - t_start
                bar.restart()
                wall, n_chunks = _run_on_dask(client, study, pending, n_workers, chunk_size,
                                              record)
            finally:
                client.close()
                if cluster is not None:
                    cluster.close()
    finally:
        journal.close()
        bar.close()
    records = [{k: v for k, v in done[i].items() if k != "fresh"} for i in range(len(study))]
    failed = [i for i in range(len(study)) if records[i]["row"].get("status") != "ok"]
    return SweepRun(records, len(pending), reused, mode, n_workers, startup, wall, case_seconds,
                    n_chunks, failed)


def _run_on_dask(client, study: Study, pending: list[int], n_workers: int,
                 chunk_size: int | None, record: Callable[[dict], None]) -> tuple[float, int]:
    import threading
    events: "queue.Queue[dict]" = queue.Queue()
    wake = threading.Event()            # set by an event or a finished chunk: no busy polling

    def on_event(event):
        events.put(event[1])
        wake.set()
    topic = f"chainmodel-sweep-{uuid.uuid4().hex}"
    client.subscribe_topic(topic, on_event)
    chunks = chunks_for(pending, n_workers, chunk_size)
    t0 = time.perf_counter()
    [study_f] = client.scatter([study], broadcast=True, hash=False)
    futures = {client.submit(_dask_chunk, study_f, chunk, topic, pure=False): chunk
               for chunk in chunks}
    for fut in futures:
        fut.add_done_callback(lambda _: wake.set())
    remaining = set(futures)

    def drain():
        while True:
            try:
                record(events.get_nowait())
            except queue.Empty:
                return

    try:
        while remaining:
            wake.wait(timeout=1.0)
            wake.clear()
            finished = {f for f in remaining if f.done()}
            remaining -= finished
            drain()
            for fut in finished:
                try:
                    recs = fut.result()
                except Exception as exc:        # noqa: BLE001 - the worker died or the task broke
                    recs = [_lost(study, i, exc) for i in futures[fut]]
                for rec in recs:
                    record(rec)
        drain()
    finally:
        client.unsubscribe_topic(topic)
        for fut in remaining:
            fut.cancel()
    return time.perf_counter() - t0, len(chunks)


def _lost(study: Study, i: int, exc: BaseException) -> dict:
    """The record of a case whose chunk was lost with its worker (only used for cases no
    event reported; record() keeps the first record of each case)."""
    return {"case": i, "row": {"case": i, **study.cases[i], "status": "failed",
                               "error": f"the worker running it was lost: {_error_text(exc)}",
                               **failed_metrics()},
            "spectrum": [], "wall_time_s": 0.0, "worker": ""}


def records_to_spectra(records: list[dict]) -> list[tuple[int, np.ndarray, np.ndarray]]:
    """(case, frequencies, amplitudes) of each record with a spectrum."""
    out = []
    for rec in records:
        spec = rec.get("spectrum") or []
        if len(spec) > 1 and math.isfinite(spec[0]):
            amps = np.asarray(spec[1:], float)
            out.append((rec["case"], spec[0] * np.arange(len(amps)), amps))
    return out
