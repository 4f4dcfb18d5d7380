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
import fcntl
import hashlib
import io
import json
import math
import os
import platform
import socket
import time
from dataclasses import asdict, dataclass, field
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
        fcntl.flock(fd, fcntl.LOCK_EX)      # another run appending to the same table waits
        if os.fstat(fd).st_size == 0:
            w.writerow(header)
        w.writerow([_cell(row.get(c)) for c in header])
        os.write(fd, buf.getvalue().encode())
        os.fsync(fd)
    finally:
        os.close(fd)                        # (releases the lock)


def _cell(v) -> str:
    """One cell's text, never with a line break (one row is one line of the file)."""
    if v is None:
        return ""
    if isinstance(v, str):
        return " | ".join(v.splitlines()) if ("\n" in v or "\r" in v) else v
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


def _read_table(path, problems: list):
    """The rows of one ``fits/<model>.csv`` as dicts over its columns, skipping
    (and listing in ``problems`` as ``file:line: reason``) every line that is not
    a whole row: a garbage line, extra or missing fields, an unterminated quote,
    a status other than ok/failed, a cell that does not parse.  A header that is
    not the model's columns is reported and the rows are read by the columns
    (the model is the file's name).  One row is one line (:func:`append_row`
    writes no newline inside a cell)."""
    model = path.stem
    try:
        header = list(columns(model))
    except ValueError:
        problems.append(f"{path}: not a results table of a registered model (file name {path.name!r}); skipped")
        return []
    with open(path, "rb") as fh:
        data = fh.read()
    lines = data.decode("utf-8", errors="replace").split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    elif lines:
        lines.pop()                     # a last row cut short by a crash (no newline)
    out = []
    for ln, line in enumerate(lines, 1):
        where = f"{path}:{ln}"
        try:
            cells = next(csv.reader([line], strict=True))
        except (csv.Error, StopIteration) as e:
            problems.append(f"{where}: not a CSV row ({e}); skipped")
            continue
        if ln == 1 and cells and cells[0] == "target":
            if cells != header:
                problems.append(f"{where}: header is not the columns of {model!r}; rows read by those columns")
            continue
        if len(cells) != len(header):
            problems.append(f"{where}: {len(cells)} fields where {model!r} has {len(header)}; skipped")
            continue
        r = dict(zip(header, cells))
        if r["status"] not in ("ok", "failed") or r["model"] != model or not r["target"] or not r["metric"]:
            problems.append(f"{where}: not a fit of {model!r} (status {r['status'][:20]!r}); skipped")
            continue
        try:
            parsed = {k: (v if k in HEAD or k.endswith("_version") or k == "error" else _parse(v))
                      for k, v in r.items()}
        except ValueError as e:
            problems.append(f"{where}: a cell does not parse ({e}); skipped")
            continue
        out.append(parsed)
    return out


def load_results(out, problems: list | None = None) -> list[dict]:
    """Every row of ``OUT/fits/*.csv`` as a dict: parameters under ``"params"``,
    error figures under ``"errors"``, the other columns as they are (numbers as
    floats, colours as lists, empty cells as ``None``).  A row cut short by a
    crash, and every malformed row, is skipped; each malformed one is appended
    to ``problems`` (if given) as ``file:line: reason``, and the good rows are
    kept (so a batch resumes and refits only what was lost)."""
    rows = []
    problems = [] if problems is None else problems
    fixed = set(HEAD) | set(TAIL)
    for path in sorted((Path(out) / "fits").glob("*.csv")):
        for r in _read_table(path, problems):
            row = {k: v for k, v in r.items() if k in fixed}
            row["params"] = {k: v for k, v in r.items() if k not in fixed}
            row["errors"] = {k: r.get(f"err_{k}") for k in ERROR_KEYS}
            rows.append(row)
    return rows


def done_keys(out, retry_failed: bool = False, problems: list | None = None) -> set:
    """Keys of the fits already in ``out`` (failed ones too, unless ``retry_failed``);
    malformed rows go to ``problems`` (:func:`load_results`)."""
    return {(r["target"], r["model"], r["metric"]) for r in load_results(out, problems)
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


# -- sharing a folder between runs --------------------------------------------------------

def _claim_path(out, task: FitTask) -> Path:
    digest = hashlib.sha1(json.dumps(list(task.key)).encode()).hexdigest()[:20]
    return Path(out) / "fits" / ".claims" / f"{task.model}-{digest}"


def _stale(path: Path) -> bool:
    """A claim left by a run that is gone (same machine, process not alive)."""
    try:
        who = json.loads(path.read_text())
    except (OSError, ValueError):
        return False                   # being written, or unreadable: not ours to judge
    if who.get("host") != socket.gethostname():
        return False
    try:
        os.kill(int(who.get("pid", -1)), 0)
    except ProcessLookupError:
        return True
    except (PermissionError, ValueError, OverflowError):
        return False
    return False


def claim(out, task: FitTask) -> bool:
    """Claim ``task`` for this process, atomically (a file created with ``O_EXCL``
    in ``OUT/fits/.claims``); False when another live run holds it.  A claim left
    by a run that died on this machine is taken over."""
    path = _claim_path(out, task)
    path.parent.mkdir(parents=True, exist_ok=True)
    for _ in range(2):
        try:
            fd = os.open(path, os.O_CREAT | os.O_EXCL | os.O_WRONLY, 0o644)
        except FileExistsError:
            if _stale(path):
                path.unlink(missing_ok=True)
                continue
            return False
        try:
            os.write(fd, json.dumps(dict(host=socket.gethostname(), pid=os.getpid(), key=list(task.key),
                                         time=time.time())).encode())
        finally:
            os.close(fd)
        return True
    return False


def release(out, task: FitTask) -> None:
    """Give up the claim of ``task`` (after its row is written)."""
    _claim_path(out, task).unlink(missing_ok=True)


def _in_table(out, task: FitTask, retry_failed: bool) -> bool:
    """Is ``task`` already in its model's table (written by another run meanwhile)?"""
    path = table_path(out, task.model)
    if not path.exists():
        return False
    return any((r["target"], r["model"], r["metric"]) == task.key and (r["status"] == "ok" or not retry_failed)
               for r in _read_table(path, []))


# -- the batch --------------------------------------------------------------------------

def plan(targets, models, metrics, *, out=None, seed: int = 0, starts: int = 4,
         time_limit: float | None = None, retry_failed: bool = False, problems: list | None = None) -> list[FitTask]:
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
    skip = done_keys(out, retry_failed, problems) if out is not None else set()
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
    #: Fits another run on the same folder was running or had written (left to it).
    shared: int = 0
    #: Malformed rows of the folder's tables (``file:line: reason``), skipped and refitted.
    bad_rows: list = field(default_factory=list)


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
    try:
        out.mkdir(parents=True, exist_ok=True)
        for p in (out / "fits").glob("*.csv"):
            repair(p)
    except OSError as e:
        raise BatchWriteError(f"fit_batch: cannot write into the results folder {str(out)!r} "
                              f"({e.strerror or e}); nothing was run") from None
    all_tasks = plan(targets, models, metrics, seed=seed, starts=starts, time_limit=time_limit)
    bad = []
    tasks = plan(targets, models, metrics, out=out, seed=seed, starts=starts, time_limit=time_limit,
                 retry_failed=retry_failed, problems=bad)
    summary = BatchSummary(len(all_tasks), len(all_tasks) - len(tasks), 0, 0, 0.0, 0, bad_rows=bad)
    t0 = time.monotonic()
    held = set()

    def take(task):
        """Claim ``task``, unless another run holds it or has written it meanwhile."""
        if not claim(out, task):
            summary.shared += 1
            tick()
            return False
        held.add(task)
        if _in_table(out, task, retry_failed):
            release(out, task)
            held.discard(task)
            summary.shared += 1
            tick()
            return False
        return True

    def finish(row):
        task = FitTask(row["target"], row["model"], row["metric"], row["seed"], row["starts"], row["time_limit"])
        try:
            record(out, row)
        except OSError as e:
            raise BatchWriteError(
                f"fit_batch: cannot write {str(table_path(out, row['model']))!r} ({e.strerror or e}): "
                f"{summary.done} fits of this run are stored, none was lost in the table; free space or "
                f"fix the folder's permissions and run the same command again to resume") from None
        release(out, task)
        held.discard(task)
        summary.done += 1
        summary.failed += row["status"] != "ok"
        if on_result:
            on_result(row)
        tick()

    tick = start(progress, len(tasks), "fits")
    try:
        if tasks and workers == 0 and not scheduler:
            summary.workers = 1
            for t in tasks:
                if take(t):
                    finish(run_task(t))
        elif tasks:
            _run_dask(tasks, scheduler, workers, summary, finish, take)
    finally:
        for t in list(held):        # claims of fits not finished (interrupted, failed to write)
            release(out, t)
    summary.seconds = time.monotonic() - t0
    return summary


class BatchWriteError(ValueError):
    """The results folder cannot be written (read-only, disk full): the message says
    what is stored and how to resume."""


def _run_dask(tasks, scheduler, workers, summary, finish, take):
    """Run ``tasks`` on Dask, claiming each (``take``) just before it is submitted and
    keeping about two per worker in flight, so that runs sharing a folder share
    the work."""
    from distributed import as_completed

    client, cluster = _client(scheduler, workers)
    try:
        summary.workers = len(client.scheduler_info().get("workers", {}))
        summary.dashboard = client.dashboard_link if scheduler else None
        queue = iter(tasks)
        done = as_completed()
        futures = []

        def submit_next():
            for t in queue:
                if take(t):
                    fut = client.submit(run_task, t, pure=False, key=f"fit-{os.getpid()}-{len(futures)}")
                    futures.append(fut)
                    done.add(fut)
                    return True
            return False

        for _ in range(max(2 * summary.workers, 2)):
            if not submit_next():
                break
        try:
            for fut in done:
                finish(fut.result())
                submit_next()
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


__all__ = ["BatchSummary", "BatchWriteError", "FitTask", "append_row", "claim", "columns", "done_keys", "fit_batch",
           "load_results", "plan", "record", "release", "repair", "run_task", "scaling", "table_path"]
