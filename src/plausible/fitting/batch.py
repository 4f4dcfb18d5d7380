"""Fitting a material database: many independent fits, on local worker processes
or on a Dask cluster, written as they finish, resumable.

One *task* is one ``(target, model, metric)`` fit (:func:`plausible.fitting.fit`
with the batch's seed, starts and time limit).  Ngan, Durand & Matusik (EGSR 2005)
fitted 7 models to 100 materials; with three metrics that is 2,100 fits of
seconds to minutes each, which outgrows one laptop.  The work is mapped with
Dask's ``distributed`` (the same code runs on local processes or on a cluster);
this module only decides *what* to run and *where the answers go*, and the batch
engine :mod:`plausible.engine` (shared with ``convert-table`` and ``check --materials``)
claims, runs and records:

1. :func:`plan` expands targets x models x metrics into :class:`FitTask` objects
   and drops those already in the results folder (resume).
2. :func:`fit_batch` runs the rest (local worker processes, one per usable core by
   default, or ``scheduler=`` the address of a running Dask scheduler) and appends
   one row per finished fit to the folder's table.  A fit that raises is recorded
   with its error and does not stop the batch; a worker that dies has its fit tried
   once more (Dask: rerun by Dask), then recorded as failed.
3. :func:`load_results` reads the table back (parameters and errors as Python
   values), for :func:`plausible.fitting.batch_report.write_report` or your own use.

The table, ``OUT/fits/<model>.csv`` (one file per model, so that every fitted
parameter is a column), is append-only: each row is written with one ``write``
on a file opened for appending, then flushed to disk.  An interrupted run
(Ctrl-C, a killed process) loses at most the fits in flight; a row cut short
by a crash mid-write is removed (:func:`repair`; a whole last row lacking only its
newline is kept) before anything else is appended, and a second row of a fit is
reported and dropped.  Columns: ``target, model, metric, status`` (``ok`` or ``failed``),
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
import platform
import re
import time
from dataclasses import asdict, dataclass, field
from pathlib import Path

import numpy as np

from .. import engine, registry
from ..engine import BatchWriteError

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
    """Remove a last row cut short by a crash mid-write (no final newline); a last row
    that is whole and lacks only its newline (:func:`whole_last_row`) gets it instead.
    Returns the number of bytes removed."""
    path = Path(path)
    if not path.exists():
        return 0
    data = path.read_bytes()
    if not data or data.endswith(b"\n"):
        return 0
    keep = data.rfind(b"\n") + 1
    if whole_last_row(path, data[keep:]):
        with open(path, "ab") as fh:
            fh.write(b"\n")
        return 0
    with open(path, "r+b") as fh:
        fh.truncate(keep)
    return len(data) - keep


#: A whole Python version (the last column): a row cut inside it does not end so.
_VERSION = re.compile(r"\d+\.\d+\.\d+\w*")


def whole_last_row(path, line: bytes) -> bool:
    """Is ``line``, the last line of the table ``path`` without its newline, a whole row?
    Yes when it reads as a row of the file's model (:func:`_read_table`'s tests) and
    ends with a whole Python version (the last column; a row cut inside it ends with
    ``3.11.`` or ``3.1``, and a row cut earlier lacks fields)."""
    try:
        header = list(columns(Path(path).stem))
    except ValueError:
        return False
    text = line.decode("utf-8", errors="replace")
    row, _ = _parse_line(text, header, Path(path).stem, "")
    return row is not None and bool(_VERSION.fullmatch(row["python_version"] or ""))


def append_row(path, header, row: dict) -> None:
    """Append ``row`` (a dict over ``header``) to the CSV ``path`` with one write,
    then flush it to disk; a new or empty file gets the header first
    (:func:`plausible.engine.append_line`)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(header)
    w.writerow([_cell(row.get(c)) for c in header])
    head, line = buf.getvalue().split("\n")[:2]
    engine.append_line(path, line, header=head)


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
    a status other than ok/failed, a cell that does not parse, a second row of a
    fit whose first row is ``ok`` (a later row replaces a ``failed`` one: a retry).
    A header that is not the model's columns is reported and the rows are read by
    the columns (the model is the file's name).  One row is one line
    (:func:`append_row` writes no newline inside a cell); a last line without its
    newline is read only when whole (:func:`whole_last_row`)."""
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
    elif lines and not whole_last_row(path, lines[-1].encode()):
        lines.pop()                     # a last row cut short by a crash (no newline)
    out, first = {}, {}
    for ln, line in enumerate(lines, 1):
        if ln == 1 and line.split(",", 1)[0] == "target":
            if next(csv.reader([line]), None) != header:
                problems.append(f"{path}:{ln}: header is not the columns of {model!r}; rows read by those columns")
            continue
        row, problem = _parse_line(line, header, model, f"{path}:{ln}")
        if row is None:
            problems.append(problem)
            continue
        key = (row["target"], row["model"], row["metric"])
        if key in out and out[key]["status"] == "ok":
            problems.append(f"{path}:{ln}: a second row of {key[0]} / {key[2]} (the first at line {first[key]}); "
                            "dropped")
            continue
        out.pop(key, None)              # a retry replaces the failed row
        out[key], first[key] = row, ln
    return list(out.values())


def _parse_line(line: str, header: list, model: str, where: str):
    """``(row, None)`` for a line that is a whole row of ``model``, else ``(None, reason)``."""
    try:
        cells = next(csv.reader([line], strict=True))
    except (csv.Error, StopIteration) as e:
        return None, f"{where}: not a CSV row ({e}); skipped"
    if len(cells) != len(header):
        return None, f"{where}: {len(cells)} fields where {model!r} has {len(header)}; skipped"
    r = dict(zip(header, cells))
    if r["status"] not in ("ok", "failed") or r["model"] != model or not r["target"] or not r["metric"]:
        return None, f"{where}: not a fit of {model!r} (status {r['status'][:20]!r}); skipped"
    try:
        return {k: (v if k in HEAD or k.endswith("_version") or k == "error" else _parse(v))
                for k, v in r.items()}, None
    except ValueError as e:
        return None, f"{where}: a cell does not parse ({e}); skipped"


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

    t0 = time.monotonic()
    try:
        res = fit(task.model, task.target, task.metric, seed=task.seed, starts=task.starts,
                  time_limit=task.time_limit)
    except Exception as e:  # noqa: BLE001 - recorded in the table, the batch goes on
        return failed_row(task, e, time.monotonic() - t0)
    row = dict(asdict(task))
    row.update(_versions())
    row.update(status="ok", seconds=res.seconds, evaluations=res.evaluations, timed_out=res.timed_out)
    for k, v in res.params.items():
        row[k] = v.tolist() if isinstance(v, np.ndarray) else (v if isinstance(v, (int, float, str)) else str(v))
    for k in ERROR_KEYS:
        v = res.errors.get(k)
        row[f"err_{k}"] = None if v is None or not math.isfinite(v) else float(v)
    return row


def failed_row(task: FitTask, exc, seconds=None) -> dict:
    """The row of a fit that raised ``exc`` (or whose worker died: :class:`plausible.engine.WorkerDied`)."""
    row = dict(asdict(task))
    row.update(_versions())
    row.update(status="failed", error=f"{type(exc).__name__}: {exc}", seconds=seconds)
    return row


def record(out, row: dict) -> None:
    """Append a finished task's row to ``OUT/fits/<model>.csv``."""
    append_row(table_path(out, row["model"]), columns(row["model"]), row)


# -- sharing a folder between runs --------------------------------------------------------

def _claims(out) -> engine.Claims:
    return engine.Claims(Path(out) / "fits" / ".claims", "fit")


def _key(task: FitTask) -> str:
    return json.dumps(list(task.key))


def _claim_path(out, task: FitTask) -> Path:
    return _claims(out).path(_key(task))


def claim(out, task: FitTask) -> bool:
    """Claim ``task`` for this process (:class:`plausible.engine.Claims`: atomically, in
    ``OUT/fits/.claims``); False when another live run holds it.  A stale claim (empty,
    of a dead process or of a PID now another process's) is taken over."""
    return _claims(out).take(_key(task))


def release(out, task: FitTask) -> None:
    """Give up the claim of ``task`` (after its row is written)."""
    _claims(out).release(_key(task))


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
    #: ``{claim key: owner}`` of the fits left to another live run (:func:`plausible.engine.describe`).
    left_to: dict = field(default_factory=dict)
    #: Stale claims taken over (``key: reason``).
    taken_over: list = field(default_factory=list)


def fit_batch(targets, models, metrics, out, *, scheduler: str | None = None, workers: int | None = None,
              seed: int = 0, starts: int = 4, time_limit: float | None = None, retry_failed: bool = False,
              progress=None, on_result=None) -> BatchSummary:
    """Fit every model to every target under every metric; write the rows to
    ``out`` as they finish (see the module docstring).

    The batch engine (:func:`plausible.engine.run`) runs them: ``scheduler``, the
    address of a running Dask scheduler (``tcp://host:8786``); without it ``workers``
    spawned local processes (default: the usable cores; a dead one is replaced and its
    fit tried once more, then recorded as failed), ``workers=0`` one fit after another
    in this process.  Each fit is claimed (``OUT/fits/.claims``) just before it starts,
    so that runs sharing the folder share the work.  ``progress``: a :mod:`plausible.progress` factory (ticked
    once per finished fit); ``on_result(row)`` is called in this
    process after each row is written.  Fits already in ``out`` are skipped
    (failed ones too, unless ``retry_failed``).  On ``KeyboardInterrupt`` the
    fits in flight are cancelled, what finished is kept, and the interrupt is
    re-raised after the workers are closed.  :class:`BatchWriteError` when the folder
    (table or claims) cannot be written; :class:`plausible.engine.SchedulerError` when
    the scheduler cannot be reached.
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

    def write(task, row):
        try:
            record(out, row)
        except OSError as e:
            raise BatchWriteError(
                f"fit_batch: cannot write {str(table_path(out, row['model']))!r} ({e.strerror or e}): "
                f"{summary.done} fits of this run are stored, none was lost in the table; free space or "
                f"fix the folder's permissions and run the same command again to resume") from None
        summary.done += 1
        summary.failed += row["status"] != "ok"
        if on_result:
            on_result(row)

    if workers is None:
        from ..analysis.suite import usable_cores

        workers = usable_cores()
    claims = _claims(out)
    try:
        s = engine.run(tasks, run_task, write, key=_key, claims=claims, done=lambda t: _in_table(out, t, retry_failed),
                       failed=failed_row, scheduler=scheduler, workers=workers, progress=progress, label="fits")
    finally:
        summary.left_to, summary.taken_over = dict(claims.left_to), list(claims.taken_over)
    summary.shared, summary.seconds, summary.workers, summary.dashboard = s.shared, s.seconds, s.workers, s.dashboard
    return summary


def scaling(per_fit_seconds: float, fits: int, workers: int, overhead: float = 0.0) -> float:
    """Expected wall time of ``fits`` independent fits of ``per_fit_seconds`` each on
    ``workers`` workers: ``ceil(fits / workers) * per_fit_seconds + overhead``
    (the fits are independent; a batch ends with its slowest wave)."""
    if workers < 1:
        raise ValueError(f"workers must be >= 1, got {workers}")
    return math.ceil(fits / workers) * per_fit_seconds + overhead


__all__ = ["BatchSummary", "BatchWriteError", "FitTask", "append_row", "claim", "columns", "done_keys", "failed_row",
           "fit_batch", "load_results", "plan", "record", "release", "repair", "run_task", "scaling", "table_path",
           "whole_last_row"]
