"""Parameter sets used by ``plausible check --all`` and the registry-wide tests:
each model's defaults plus variants at the extremes its parameters declare."""

from __future__ import annotations

import os

from .. import registry


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
    (spawned; each checks whole models, so every report is the one a single process
    gives, up to the rounding of the backend ``auto`` picks).  ``progress``: a
    :mod:`plausible.progress` factory, ticked after each model.

    A worker that dies (killed, out of memory, a crash in compiled code) is
    replaced, and the model it was checking is checked once more in a fresh worker;
    if that one dies too, the model's entry is a :class:`WorkerDied` naming it and
    the exit codes.  ``on_worker_death(model, exitcode, retried)`` is called at each
    death (``retried``: the model is checked again).  A worker that cannot be started
    leaves its models to the others, or to this process if none is running."""
    from ..progress import start

    models = list(models)
    tick = start(progress, len(models), "check")
    if jobs > 1 and len(models) > 1:
        return _check_in_workers(models, quick, jobs, tick, on_worker_death)
    out = []
    for m in models:
        out.append(_check_one(m, quick))
        tick()
    return out


def _check_in_workers(models, quick, jobs, tick, on_worker_death) -> list:
    """:func:`check_many` in ``jobs`` spawned worker processes fed one model at a time
    over pipes; a dead worker is replaced and its model checked once more."""
    import multiprocessing as mp
    from collections import deque
    from multiprocessing.connection import wait

    ctx = mp.get_context("spawn")
    out = [None] * len(models)
    todo = deque(range(len(models)))
    deaths = [[] for _ in models]     # exit codes of the workers that died checking each model
    workers = {}                      # connection -> [process, index of the model it checks or None]

    def spawn():
        mine, theirs = ctx.Pipe()
        p = ctx.Process(target=_worker, args=(theirs, quick), daemon=True)
        try:
            p.start()
        except OSError:               # no process to be had (at the limit of processes or memory)
            mine.close()
            return False
        finally:
            theirs.close()
        workers[mine] = [p, None]
        feed(mine)
        return True

    def feed(conn):
        w = workers[conn]
        w[1] = todo.popleft() if todo else None
        try:
            conn.send(None if w[1] is None else (w[1], models[w[1]]))
        except OSError:               # it died already: seen as its end of file below
            pass

    try:
        for _ in range(min(jobs, len(todo))):
            spawn()
        while workers:
            for conn in wait(list(workers)):
                p, k = workers[conn]
                try:
                    k, rep = conn.recv()
                except (EOFError, OSError):         # the worker is gone
                    p.join()
                    del workers[conn]
                    conn.close()
                    if k is None:                   # it was told to stop
                        continue
                    deaths[k].append(p.exitcode)
                    retried = len(deaths[k]) < 2
                    if on_worker_death:
                        on_worker_death(models[k], p.exitcode, retried)
                    if retried:
                        todo.appendleft(k)          # once more, in a fresh worker
                    else:
                        out[k] = WorkerDied(models[k], deaths[k])
                        tick()
                    if todo:
                        spawn()
                    continue
                out[k] = rep
                tick()
                feed(conn)
        while todo:                                 # no worker could be started: this process
            k = todo.popleft()
            out[k] = _check_one(models[k], quick)
            tick()
    finally:
        for conn, (p, _) in workers.items():
            if p.is_alive():
                p.terminate()
            p.join(timeout=10)
            conn.close()
    return out


class WorkerDied(RuntimeError):
    """The worker processes checking a model died, each time it was tried."""

    def __init__(self, model, exitcodes):
        codes = ", ".join(exit_text(c) for c in exitcodes)
        super().__init__(f"the worker process checking {model!r} died, {len(exitcodes)} times ({codes}); "
                         "its error, if any, is printed above")
        self.model, self.exitcodes = model, list(exitcodes)


def exit_text(code) -> str:
    """A process's exit code in words: ``-9`` -> ``killed by SIGKILL``; ``3`` -> ``exit code 3``."""
    import signal

    if code is not None and code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            pass
    return f"exit code {code}"


def _worker(conn, quick):
    """A process of :func:`check_many`: checks the models it is sent (``(index,
    model)``, ``None`` to stop) and sends back ``(index, report or exception)``."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)    # the parent handles Ctrl-C (and ends us)
    for k, model in iter(conn.recv, None):
        rep = _check_one(model, quick)
        try:
            conn.send((k, rep))
        except Exception as e:  # noqa: BLE001 - an exception that does not pickle: its text
            conn.send((k, RuntimeError(f"{type(rep).__name__}: {rep} (and it could not be sent: {e})")))


def _check_one(model, quick):
    from .report import check

    try:
        return check(model, quick=quick)
    except Exception as e:  # noqa: BLE001 - one model's failure is reported, the others still run
        return e

