"""Parameter sets used by ``plausible check --all`` and the registry-wide tests:
each model's defaults plus variants at the extremes its parameters declare."""

from __future__ import annotations

import os

from .. import registry
from ..engine import WorkerDied, exit_text

__all__ = ["WorkerDied", "check_many", "default_jobs", "exit_text", "model_variants", "usable_cores", "variants"]


def usable_cores() -> int:
    """The cores this process may run on (its CPU affinity; the machine's count elsewhere)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


def default_jobs() -> int:
    """Worker processes of the commands that spread work over processes (``check --all``,
    ``check --materials``, ``figures``): the usable cores, at most 2 (Dr.Jit's kernels use
    every core already; a second process keeps them busy while the other runs Python and
    NumPy)."""
    return max(1, min(2, usable_cores()))


def variants(name: str, max_variants: int = 4) -> list[dict]:
    """Parameter dicts: ``{}`` (defaults), then one parameter at a time set to
    each of its declared extremes (skipping combinations the model refuses)."""
    inf = registry.info(name)
    out = [{}]
    for p in inf.params:
        for v in p.extremes:
            if v != p.default:
                out.append({p.name: v})
    good = []
    for kw in out:
        try:
            inf.cls(**kw)
        except ValueError:
            continue
        good.append(kw)
    return good[:max_variants] if max_variants else good


def model_variants(name: str, max_variants: int = 4):
    inf = registry.info(name)
    return [inf.cls(**kw) for kw in variants(name, max_variants)]


def check_many(models, *, quick: bool = False, jobs: int = 1, progress=None, on_worker_death=None) -> list:
    """:func:`plausible.check` of each model of ``models``, in order: a list holding
    each :class:`~plausible.analysis.report.CheckReport`, or the exception its
    check raised (the others still run).  ``jobs`` > 1: that many worker processes
    of the batch engine (:func:`plausible.engine.run`: spawned; each checks whole
    models, so every report is the one a single process gives, up to the rounding
    of the backend ``auto`` picks).  ``progress``: a :mod:`plausible.progress`
    factory, ticked after each model.

    A worker that dies (killed, out of memory, a crash in compiled code) is
    replaced, and the model it was checking is checked once more in a fresh worker;
    if that one dies too, the model's entry is a :class:`WorkerDied` naming it and
    the exit codes.  ``on_worker_death(model, exitcode, retried)`` is called at each
    death (``retried``: the model is checked again).  A worker that cannot be started
    leaves its models to the others, or to this process if none is running."""
    from functools import partial

    from .. import engine

    models = list(models)
    out = [None] * len(models)

    def record(task, rep):
        out[task[0]] = rep

    def failed(task, exc):
        if isinstance(exc, WorkerDied):
            return WorkerDied(task[1], exc.exitcodes, "checking")
        return exc

    engine.run(list(enumerate(models)), partial(_check_numbered, quick=quick), record, failed=failed,
               workers=jobs if jobs > 1 else 0, progress=progress, label="check",
               on_death=None if on_worker_death is None else lambda t, c, r: on_worker_death(t[1], c, r))
    return out


def _check_numbered(task, quick):
    return _check_one(task[1], quick)


def _check_one(model, quick):
    from .report import check

    try:
        return check(model, quick=quick)
    except Exception as e:  # noqa: BLE001 - one model's failure is reported, the others still run
        return e

