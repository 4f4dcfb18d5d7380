"""Fitting a material database: many independent fits, on local worker processes
or on a Dask cluster, written as they finish, resumable.

One *task* is one ``(target, model, metric)`` fit (:func:`plausible.fitting.fit`
with the batch's seed, starts and time limit).  Ngan, Durand & Matusik (EGSR 2005)
fitted 7 models to 100 materials; with three metrics that is 2,100 fits of
seconds to minutes each, which outgrows one laptop.  The work is mapped with
Dask's ``distributed`` (the same code runs on local processes or on a cluster);
this module only decides *what* to run and *where the answers go*:

1. :func:`plan` expands targets x models x metrics into :class:`FitTask` objects
   and drops those already in the results folder (resume).
2. :func:`fit_batch` submits the rest to a Dask client (a ``LocalCluster`` of
   one single-threaded worker process per core by default, or ``scheduler=``
   the address of a running scheduler) and appends one row per finished fit to
   the folder's table.  A fit that raises is recorded with its error and does
   not stop the batch; a worker that dies has its tasks rerun by Dask.
3. :func:`load_results` reads the table back (parameters and errors as Python
   values), for :func:`plausible.fitting.batch_report.write_report` or your own use.

The table, ``OUT/fits/<model>.csv`` (one file per model, so that every fitted
parameter is a column), is append-only: each row is written with one ``write``
on a file opened for appending, then flushed to disk.  An interrupted run
(Ctrl-C, a killed process) loses at most the fits in flight; a row cut short
by a crash mid-write is removed (:func:`repair`) before anything else is
appended.  Columns: ``target, model, metric, status`` (``ok`` or ``failed``),
one column per parameter of the model (colours as JSON lists), one per error
figure of :func:`plausible.fitting.metrics.errors` (``err_l2-cos`` ...),
``seconds, evaluations, timed_out, seed, starts, time_limit, error`` (the
exception, for a failed fit) and the versions of ``plausible``, NumPy, SciPy
and Python that computed the row.
"""

from __future__ import annotations

import csv
import io
import json
import math
import os
import platform
import time
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .. import registry
from ..progress import start

#: The error figures of every fit, in column order (``metrics.errors`` keys).
ERROR_KEYS = ("l2-cos", "log", "fcos_max", "albedo_max", "perceptual")

#: Columns before the model's parameters, and after them.
HEAD = ("target", "model", "metric", "status")
TAIL = tuple(f"err_{k}" for k in ERROR_KEYS) + (
    "seconds", "evaluations", "timed_out", "seed", "starts", "time_limit", "error",
    "plausible_version", "numpy_version", "scipy_version", "python_version")


@dataclass(frozen=True)
class FitTask:
    """One fit of a batch: ``fit(model, target, metric, seed=, starts=, time_limit=)``."""

    target: str
    model: str
    metric: str
    seed: int = 0
    starts: int = 4
    time_limit: float | None = None

    @property
    def key(self) -> tuple:
        """What identifies a fit in the results (a rerun skips keys already there)."""
        return (self.target, self.model, self.metric)


# -- the table ------------------------------------------------------------------------

def columns(model: str) -> tuple:
    """The header of ``fits/<model>.csv``."""
    params = tuple(p.name for p in registry.info(model).params)
    return HEAD + params + TAIL


def table_path(out, model: str) -> Path:
    return Path(out) / "fits" / f"{model}.csv"


def repair(path) -> int:
    """Remove a last row cut short by a crash mid-write (no final newline).
    Returns the number of bytes removed."""
    path = Path(path)
    if not path.exists():
        return 0
    data = path.read_bytes()
    if not data or data.endswith(b"\n"):
        return 0
    keep = data.rfind(b"\n") + 1
    with open(path, "r+b") as fh:
        fh.truncate(keep)
    return len(data) - keep


def append_row(path, header, row: dict) -> None:
    """Append ``row`` (a dict over ``header``) to the CSV ``path`` with one write,
    then flush it to disk; a new or empty file gets the header first."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        if os.fstat(fd).st_size == 0:
            w.writerow(header)
        w.writerow([_cell(row.get(c)) for c in header])
        os.write(fd, buf.getvalue().encode())
        os.fsync(fd)
    finally:
        os.close(fd)


def _cell(v) -> str:
    if v is None:
        return ""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (list, tuple, np.ndarray)):
        return json.dumps([float(x) for x in np.ravel(v)])
    if isinstance(v, float):
        return repr(v)
    return str(v)


def _parse(v: str):
    if v == "":
        return None
    if v in ("true", "false"):
        return v == "true"
    if v.startswith("["):
        return json.loads(v)
    try:
        return float(v)
    except ValueError:
        return v


def load_results(out) -> list[dict]:
    """Every row of ``OUT/fits/*.csv`` as a dict: parameters under ``"params"``,
    error figures under ``"errors"``, the other columns as they are (numbers as
    floats, colours as lists, empty cells as ``None``).  A row cut short by a
    crash is skipped."""
    rows = []
    for path in sorted((Path(out) / "fits").glob("*.csv")):
        with open(path, newline="") as fh:
            text = fh.read()
        if text and not text.endswith("\n"):
            text = text[: text.rfind("\n") + 1]
        reader = csv.DictReader(io.StringIO(text))
        fixed = set(HEAD) | set(TAIL)
        for r in reader:
            row = {k: (r[k] if k in HEAD or k.endswith("_version") or k == "error" else _parse(r[k]))
                   for k in r if k in fixed}
            row["params"] = {k: _parse(v) for k, v in r.items() if k not in fixed}
            row["errors"] = {k: _parse(r.get(f"err_{k}", "")) for k in ERROR_KEYS}
            rows.append(row)
    return rows


def done_keys(out, retry_failed: bool = False) -> set:
    """Keys of the fits already in ``out`` (failed ones too, unless ``retry_failed``)."""
    return {(r["target"], r["model"], r["metric"]) for r in load_results(out)
            if r["status"] == "ok" or not retry_failed}


# -- one task ----------------------------------------------------------------------------

def _versions() -> dict:
    import scipy

    from .. import __version__

    return {"plausible_version": __version__, "numpy_version": np.__version__,
            "scipy_version": scipy.__version__, "python_version": platform.python_version()}


def run_task(task: FitTask) -> dict:
    """Run one fit and return its table row (a failed fit returns a row with
    ``status = "failed"`` and the exception in ``error``; it never raises, so one
    bad target cannot stop a batch).  Runs on a worker."""
    from .fit import fit

    row = dict(asdict(task))
    row.update(_versions())
    t0 = time.monotonic()
    try:
        res = fit(task.model, task.target, task.metric, seed=task.seed, starts=task.starts,
                  time_limit=task.time_limit)
    except Exception as e:  # noqa: BLE001 - recorded in the table, the batch goes on
        row.update(status="failed", error=f"{type(e).__name__}: {e}", seconds=time.monotonic() - t0)
        return row
    row.update(status="ok", seconds=res.seconds, evaluations=res.evaluations, timed_out=res.timed_out)
    for k, v in res.params.items():
        row[k] = v.tolist() if isinstance(v, np.ndarray) else (v if isinstance(v, (int, float, str)) else str(v))
    for k in ERROR_KEYS:
        v = res.errors.get(k)
        row[f"err_{k}"] = None if v is None or not math.isfinite(v) else float(v)
    return row


def record(out, row: dict) -> None:
    """Append a finished task's row to ``OUT/fits/<model>.csv``."""
    append_row(table_path(out, row["model"]), columns(row["model"]), row)


# -- the batch --------------------------------------------------------------------------

def plan(targets, models, metrics, *, out=None, seed: int = 0, starts: int = 4,
         time_limit: float | None = None, retry_failed: bool = False) -> list[FitTask]:
    """Every ``(target, model, metric)`` task, minus those already in ``out``.

    ``models`` and ``metrics`` are checked here (unknown names raise
    :class:`ValueError` before any work starts); targets are checked by the fit
    itself, so that a corrupt file becomes a failed row, not a failed batch.
    """
    from .metrics import METRICS

    targets, models, metrics = [str(t) for t in targets], list(models), list(metrics)
    if not targets:
        raise ValueError("fit_batch: no targets given")
    if not models or not metrics:
        raise ValueError("fit_batch: give at least one model and one metric")
    for m in models:
        registry.info(m)
    for m in metrics:
        if m not in METRICS:
            raise ValueError(f"fit_batch: metric must be one of {', '.join(METRICS)}, got {m!r}")
    if starts < 1:
        raise ValueError(f"fit_batch: starts must be >= 1, got {starts}")
    skip = done_keys(out, retry_failed) if out is not None else set()
    tasks = [FitTask(t, m, k, seed, starts, time_limit)
             for t in dict.fromkeys(targets) for m in dict.fromkeys(models) for k in dict.fromkeys(metrics)]
    return [t for t in tasks if t.key not in skip]


@dataclass
class BatchSummary:
    """What :func:`fit_batch` did: counts, the wall time, and the dashboard link
    of the cluster (``None`` without one)."""

    planned: int
    skipped: int
    done: int
    failed: int
    seconds: float
    workers: int
    dashboard: str | None = None
    interrupted: bool = False


def _client(scheduler, workers):
    """A Dask client: to ``scheduler`` (an address) if given, else a LocalCluster of
    ``workers`` single-threaded processes (default: every core)."""
    from distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    n = workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=n, threads_per_worker=1, processes=True,
                           dashboard_address=None, silence_logs=40)
    return Client(cluster), cluster


def fit_batch(targets, models, metrics, out, *, scheduler: str | None = None, workers: int | None = None,
              seed: int = 0, starts: int = 4, time_limit: float | None = None, retry_failed: bool = False,
              progress=None, on_result=None) -> BatchSummary:
    """Fit every model to every target under every metric; write the rows to
    ``out`` as they finish (see the module docstring).

    ``scheduler``: address of a running Dask scheduler (``tcp://host:8786``);
    without it a ``LocalCluster`` of ``workers`` processes (default: all cores)
    is started and closed.  ``workers=0`` runs the fits one after another in this
    process (no Dask).  ``progress``: a :mod:`plausible.progress` factory (ticked
    once per finished fit); ``on_result(row)`` is called in this
    process after each row is written.  Fits already in ``out`` are skipped
    (failed ones too, unless ``retry_failed``).  On ``KeyboardInterrupt`` the
    fits in flight are cancelled, what finished is kept, and the interrupt is
    re-raised after the cluster is closed.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    for p in (out / "fits").glob("*.csv"):
        repair(p)
    all_tasks = plan(targets, models, metrics, seed=seed, starts=starts, time_limit=time_limit)
    tasks = plan(targets, models, metrics, out=out, seed=seed, starts=starts, time_limit=time_limit,
                 retry_failed=retry_failed)
    summary = BatchSummary(len(all_tasks), len(all_tasks) - len(tasks), 0, 0, 0.0, 0)
    t0 = time.monotonic()

    def finish(row, tick):
        record(out, row)
        summary.done += 1
        summary.failed += row["status"] != "ok"
        if on_result:
            on_result(row)
        tick()

    tick = start(progress, len(tasks), "fits")
    if tasks and workers == 0 and not scheduler:
        summary.workers = 1
        for t in tasks:
            finish(run_task(t), tick)
    elif tasks:
        _run_dask(tasks, scheduler, workers, summary, lambda row: finish(row, tick))
    summary.seconds = time.monotonic() - t0
    return summary


def _run_dask(tasks, scheduler, workers, summary, finish):
    from distributed import as_completed

    client, cluster = _client(scheduler, workers)
    try:
        summary.workers = len(client.scheduler_info().get("workers", {}))
        summary.dashboard = client.dashboard_link if scheduler else None
        futures = client.map(run_task, tasks, pure=False, key=[f"fit-{i}" for i in range(len(tasks))])
        try:
            for fut in as_completed(futures):
                finish(fut.result())
        except KeyboardInterrupt:
            summary.interrupted = True
            client.cancel(futures)
            raise
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def scaling(per_fit_seconds: float, fits: int, workers: int, overhead: float = 0.0) -> float:
    """Expected wall time of ``fits`` independent fits of ``per_fit_seconds`` each on
    ``workers`` workers: ``ceil(fits / workers) * per_fit_seconds + overhead``
    (the fits are independent; a batch ends with its slowest wave)."""
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return math.ceil(fits / workers) * per_fit_seconds + overhead


__all__ = ["BatchSummary", "FitTask", "append_row", "columns", "done_keys", "fit_batch", "load_results",
           "plan", "record", "repair", "run_task", "scaling", "table_path"]
