"""The batch engine: many independent tasks, claimed, run here, in local worker
processes or on a Dask cluster, and recorded by the calling process as they finish.

One engine serves ``plausible fit-batch`` (:mod:`plausible.fitting.batch`),
``plausible convert-table`` (:mod:`plausible.conversion.table`), ``plausible check
--materials`` (:mod:`plausible.analysis.materials`) and ``check --all --jobs``
(:mod:`plausible.analysis.suite`).  Each caller says *what* a task is (a picklable
value), *how* it is run (``work(task)``, a module-level function, so that a spawned
process or a Dask worker imports it), *where its result goes* (``record(task,
result)``, in the calling process only) and *whether it is done already*; the
engine does the rest, in these stages:

1. **claim** (:class:`Claims`): just before a task is started, a claim file is
   made for it in the folder's claims directory, naming its owner (host, PID,
   the process's start time from ``/proc/PID/stat`` and the boot id); then the
   caller's ``done(task)`` is asked again (another run may have written it
   meanwhile).  A task held by another live run is left to it.
2. **run** (:func:`run`): ``workers=0``, one task after another in this process;
   ``workers=n``, ``n`` spawned processes fed one task at a time, a dead worker
   (killed, out of memory) replaced and its task tried once more
   (:class:`WorkerDied` after a second death); ``scheduler=ADDRESS``, a running
   Dask scheduler (``distributed``), about two tasks per worker in flight.
3. **record**: ``record(task, result)`` as each finishes, then the claim is
   released.  Ctrl-C cancels what is in flight, releases its claims and is raised
   again; what was recorded stays (a rerun skips it: resume).

The takeover rule (issue 45): a claim is *live* when it names this host, this boot,
a running PID whose start time is the one written, and (for this very process) a
run still holding it.  A claim that is empty or unreadable as JSON (a full disk, a
crash between create and write), names a dead PID, a PID now used by another process
(its start time differs), another boot, or a run of this process that ended, is
*stale* and taken over.  A claim of another host cannot be judged from here: it is
left to that run and reported (remove the claims folder to release it).  Claims are
written whole (a temporary file linked into place), and judged and replaced under an
exclusive ``flock`` of the claims folder, so two runs never both take one task.

:func:`append_line` is the one way rows reach a results file: one ``write`` under an
exclusive ``flock``, after the header for a new file and after a newline when the last
line was left without one, then ``fsync``.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import os
import socket
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path

from .progress import start

__all__ = ["BatchWriteError", "Claims", "RunSummary", "SchedulerError", "WorkerDied", "append_line", "connect",
           "exit_text", "me", "run"]

#: Seconds to reach a Dask scheduler before giving up (Dask's own default waits 30 s).
CONNECT_TIMEOUT = 10.0


class BatchWriteError(ValueError):
    """A results folder cannot be written (read-only, disk full): the message says
    what is stored and how to resume."""


class SchedulerError(ValueError):
    """The Dask scheduler named by ``scheduler`` cannot be reached."""


class WorkerDied(RuntimeError):
    """The worker processes running a task died, each time it was tried."""

    def __init__(self, task, exitcodes, what: str = "running"):
        codes = ", ".join(exit_text(c) for c in exitcodes)
        super().__init__(f"the worker process {what} {task!r} died, {len(exitcodes)} times ({codes}); "
                         "its error, if any, is printed above")
        self.model = self.task = task
        self.exitcodes = list(exitcodes)


def exit_text(code) -> str:
    """A process's exit code in words: ``-9`` -> ``killed by SIGKILL``; ``3`` -> ``exit code 3``."""
    import signal

    if code is not None and code < 0:
        try:
            return f"killed by {signal.Signals(-code).name}"
        except ValueError:
            pass
    return f"exit code {code}"


# -- who owns a claim ------------------------------------------------------------------------

def _start_time(pid: int):
    """The start time of process ``pid`` (clock ticks after boot, field 22 of
    ``/proc/PID/stat``); None where there is no ``/proc`` or no such process."""
    try:
        stat = Path(f"/proc/{int(pid)}/stat").read_text()
    except (OSError, ValueError):
        return None
    fields = stat[stat.rfind(")") + 2:].split()     # the name (field 2) may hold spaces and ')'
    try:
        return int(fields[19])
    except (IndexError, ValueError):
        return None


def _boot_id():
    try:
        return Path("/proc/sys/kernel/random/boot_id").read_text().strip()
    except OSError:
        return None


def me() -> dict:
    """This process as a claim's owner: host, PID, start time, boot id."""
    return dict(host=socket.gethostname(), pid=os.getpid(), start=_start_time(os.getpid()), boot=_boot_id())


def process_alive(pid: int) -> bool:
    """Whether process ``pid`` exists on this host (signal 0 delivered, or refused for permission:
    alive, another user's); a number no process can have (beyond the platform's PID type) is not."""
    try:
        os.kill(pid, 0)
    except (ProcessLookupError, OverflowError):
        return False
    except PermissionError:          # alive, another user's
        return True
    return True


#: Claim files held by runs of this process (a claim naming this process and not
#: listed here was left by a run that ended: stale).
_HELD: set = set()


def judge(who) -> str | None:
    """Why the claim content ``who`` (the parsed JSON, or None when the file was empty or
    not JSON) is stale, or None when its owner is live or cannot be judged from here
    (another host).  The rule of the module docstring."""
    if not isinstance(who, dict) or not isinstance(who.get("pid"), int) or not who.get("host"):
        return "empty or unreadable"
    here = me()
    if who["host"] != here["host"]:
        return None
    if here["boot"] and who.get("boot") and who["boot"] != here["boot"]:
        return "written before this machine restarted"
    if who["pid"] <= 0 or not process_alive(who["pid"]):
        return f"process {who['pid']} is gone"
    if _start_time(who["pid"]) is not None and who.get("start") != _start_time(who["pid"]):
        return f"process {who['pid']} is not the one that claimed it (another start time)"
    return None


def describe(who) -> str:
    """A claim's owner in words: ``PID 123 on HOST since 18:02:11``."""
    if not isinstance(who, dict):
        return "an unknown run"
    since = time.strftime(" since %H:%M:%S", time.localtime(who["time"])) if isinstance(
        who.get("time"), (int, float)) else ""
    return f"PID {who.get('pid')} on {who.get('host')}{since}"


class Claims:
    """Claim files of the tasks of one results folder, in ``folder`` (made on first use).

    ``take(key)``: True when this process now holds ``key``'s claim; False when a live
    run holds it (its owner then in :attr:`left_to`).  ``release(key)`` after its result
    is recorded.  A claim's file is named by a digest of ``key`` (``prefix-<sha1>``)
    and holds :func:`me` with the key and the time (JSON)."""

    def __init__(self, folder, prefix: str = "task"):
        self.folder, self.prefix = Path(os.path.abspath(folder)), prefix
        self.left_to: dict = {}     # key -> owner (described) of the claims left to others
        self.taken_over: list = []  # "key: reason" of the stale claims taken over

    @classmethod
    def beside(cls, path, prefix: str = "task") -> "Claims":
        """The claims of the results file ``path``: the hidden folder ``.NAME.claims`` beside it."""
        p = Path(path)
        return cls(p.parent / f".{p.name.lstrip('.')}.claims", prefix)

    def path(self, key: str) -> Path:
        digest = hashlib.sha1(str(key).encode()).hexdigest()[:20]
        return self.folder / f"{self.prefix}-{digest}"

    def _write_error(self, e) -> BatchWriteError:
        return BatchWriteError(f"cannot write a claim in {str(self.folder)!r} ({e.strerror or e}); "
                               "nothing of it was lost: free space or fix the folder's permissions and run "
                               "the same command again to resume")

    def take(self, key: str) -> bool:
        path = self.path(key)
        try:
            self.folder.mkdir(parents=True, exist_ok=True)
            lock = os.open(self.folder, os.O_RDONLY)       # the folder itself is the lock (flock)
        except OSError as e:
            raise self._write_error(e) from None
        try:
            fcntl.flock(lock, fcntl.LOCK_EX)
            if os.path.lexists(path):
                try:
                    who = json.loads(path.read_bytes() or b"null")
                except ValueError:
                    who = None
                except OSError:
                    self.left_to[key] = "an unreadable claim"
                    return False
                why = judge(who)
                if why is None and not (isinstance(who, dict) and who.get("pid") == os.getpid()
                                        and who.get("host") == socket.gethostname() and str(path) not in _HELD):
                    self.left_to[key] = describe(who)
                    return False
                self.taken_over.append(f"{key}: {why or 'left by an ended run of this process'}")
            self._write(path, key)
            _HELD.add(str(path))
            return True
        finally:
            os.close(lock)          # (releases the lock)

    def _write(self, path: Path, key: str) -> None:
        """The claim, whole: into a temporary file, then renamed over ``path``."""
        tmp = self.folder / f".{path.name}.{os.getpid()}.tmp"
        try:
            with open(tmp, "wb") as fh:
                fh.write(json.dumps(dict(me(), key=str(key), time=time.time())).encode())
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except OSError as e:
            tmp.unlink(missing_ok=True)
            raise self._write_error(e) from None

    def release(self, key: str) -> None:
        path = self.path(key)
        _HELD.discard(str(path))
        path.unlink(missing_ok=True)


# -- the results files -------------------------------------------------------------------------

def append_line(path, line: str, header: str | None = None) -> None:
    """Append ``line`` (one line, no newline of its own) to ``path`` with one ``write``
    under an exclusive ``flock``, then ``fsync``: after ``header`` when the file is new or
    empty, after a newline when its last line has none (a row cut by a crash stays a line
    of its own, read and reported as malformed).  An ``OSError`` (full disk, read-only)
    propagates; a partial write is cut back to the file's former length."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd = os.open(path, os.O_RDWR | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)      # another run appending to the same file waits
        size = os.fstat(fd).st_size
        text = line + "\n"
        if size == 0 and header is not None:
            text = header + "\n" + text
        elif size and os.pread(fd, 1, size - 1) != b"\n":
            text = "\n" + text
        data = text.encode()
        try:
            if os.write(fd, data) != len(data):
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
            os.fsync(fd)
        except OSError:
            os.ftruncate(fd, size)
            raise
    finally:
        os.close(fd)                        # (releases the lock)


# -- where tasks run -------------------------------------------------------------------------------

def connect(scheduler: str, timeout: float | None = None):
    """A Dask ``distributed.Client`` of the scheduler at ``scheduler`` (``tcp://host:8786``);
    :class:`SchedulerError` naming the address and the cause when it cannot be reached
    within ``timeout`` seconds (default :data:`CONNECT_TIMEOUT`)."""
    try:
        from distributed import Client
    except ImportError:
        raise SchedulerError("scheduler: a Dask scheduler needs the package distributed "
                             "(pip install 'plausible[batch]')") from None
    t = CONNECT_TIMEOUT if timeout is None else timeout
    try:
        return Client(scheduler, timeout=t)
    except (OSError, TimeoutError, ValueError, TypeError) as e:
        raise SchedulerError(f"scheduler: cannot reach the Dask scheduler at {scheduler!r} within {t:g} s "
                             f"({type(e).__name__}: {e}); start one (dask scheduler) or leave the scheduler "
                             "out to use local processes") from None


@dataclass
class RunSummary:
    """What :func:`run` did: tasks given, recorded, left to another run (claimed by it
    or recorded by it meanwhile, with their owners), workers, the wall time."""

    planned: int = 0
    done: int = 0
    shared: int = 0
    left_to: dict = field(default_factory=dict)
    taken_over: list = field(default_factory=list)
    workers: int = 0
    dashboard: str | None = None
    interrupted: bool = False
    seconds: float = 0.0


def run(tasks, work, record, *, key=None, claims: Claims | None = None, done=None, failed=None,
        scheduler: str | None = None, workers: int = 0, progress=None, label: str = "tasks",
        on_death=None) -> RunSummary:
    """Run ``work(task)`` for each of ``tasks`` and ``record(task, result)`` each result
    in this process as it arrives (module docstring).

    ``claims``, ``key(task) -> str``: claim each task just before it starts (None: no
    claims).  ``done(task) -> bool``: recorded already (asked after the claim; a task
    recorded meanwhile by another run is skipped).  ``failed(task, exc) -> result``: the
    result of a task whose ``work`` raised or whose worker died twice (default: the
    exception is raised).  ``scheduler``: a Dask scheduler's address; else ``workers``
    spawned processes (0: this process).  ``progress``: a :mod:`plausible.progress`
    factory, ticked once per task (recorded or left to another run).  ``on_death(task,
    exitcode, retried)``: a local worker died running ``task``."""
    tasks = list(tasks)
    s = RunSummary(planned=len(tasks))
    t0 = time.monotonic()
    tick = start(progress, len(tasks), label)
    held = set()
    client = connect(scheduler) if scheduler and tasks else None

    def take(t):
        k = key(t) if claims is not None else None
        if claims is not None and not claims.take(k):
            s.shared += 1
            tick()
            return False
        if done is not None and done(t):
            if claims is not None:
                claims.release(k)
            s.shared += 1
            tick()
            return False
        held.add(k)
        return True

    def finish(t, result):
        record(t, result)
        if claims is not None:
            claims.release(key(t))
        held.discard(key(t) if claims is not None else None)
        s.done += 1
        tick()

    def fail(t, exc):
        if failed is None:
            raise exc
        return failed(t, exc)

    pending = (t for t in tasks if take(t))
    try:
        if client is not None:
            _on_dask(client, pending, work, finish, fail, s, label)
        elif workers and len(tasks) > 1:
            _in_processes(pending, work, workers, finish, fail, s, on_death)
        else:
            s.workers = 1
            for t in pending:
                _run_here(t, work, finish, fail)
    except KeyboardInterrupt:
        s.interrupted = True
        raise
    finally:
        if claims is not None:
            for k in held:          # claims of tasks not finished (interrupted, failed to record)
                claims.release(k)
            s.left_to, s.taken_over = dict(claims.left_to), list(claims.taken_over)
        s.seconds = time.monotonic() - t0
    return s


def _on_dask(client, pending, work, finish, fail, s, label):
    """The tasks of ``pending`` on a Dask client, about two per worker in flight."""
    from distributed import as_completed

    try:
        s.workers = len(client.scheduler_info().get("workers", {}))
        s.dashboard = client.dashboard_link
        done, futures = as_completed(), {}
        tag = f"{label}-{os.getpid()}-{uuid.uuid4().hex[:8]}"

        def submit_next():
            t = next(pending, None)
            if t is None:
                return False
            fut = client.submit(work, t, pure=False, key=f"{tag}-{len(futures)}-{time.monotonic_ns()}")
            futures[fut] = t
            done.add(fut)
            return True

        for _ in range(max(2 * s.workers, 2)):
            if not submit_next():
                break
        try:
            for fut in done:
                t = futures.pop(fut)
                try:
                    result = fut.result()
                except Exception as e:  # noqa: BLE001 - a raising task, or KilledWorker
                    result = fail(t, e)
                finish(t, result)
                submit_next()
        except KeyboardInterrupt:
            client.cancel(list(futures))
            raise
    finally:
        client.close()


def _in_processes(pending, work, jobs, finish, fail, s, on_death):
    """The tasks of ``pending`` in ``jobs`` spawned processes fed one task at a time over
    pipes; a dead worker is replaced and its task tried once more; a worker that cannot
    be started leaves its tasks to the others, or to this process if none is running."""
    import multiprocessing as mp
    from collections import deque
    from multiprocessing.connection import wait

    ctx = mp.get_context("spawn")     # not fork: Dr.Jit's threads do not survive a fork
    retry, deaths, workers, tasks = deque(), {}, {}, {}
    numbered = enumerate(pending)

    def next_task():
        """The number of the next task (one to retry first), or None."""
        if retry:
            return retry.popleft()
        n, t = next(numbered, (None, None))
        if n is not None:
            tasks[n] = t
        return n

    def spawn():
        """A fresh worker for the next task; False when none is left or no process could be started."""
        n = next_task()
        if n is None:
            return False
        started = _start_worker(ctx, work)
        if started is None:
            retry.appendleft(n)
            return False
        mine, p = started
        workers[mine] = [p, None]
        s.workers = max(s.workers, len(workers))
        feed(mine, n)
        return True

    def feed(conn, n=None):
        w = workers[conn]
        w[1] = next_task() if n is None else n
        try:
            conn.send(None if w[1] is None else (w[1], tasks[w[1]]))
        except OSError:               # it died already: seen as its end of file below
            pass

    def died(conn):
        p, n = workers.pop(conn)
        p.join()
        conn.close()
        if n is None:                 # it was told to stop
            return
        deaths.setdefault(n, []).append(p.exitcode)
        again = len(deaths[n]) < 2
        if on_death:
            on_death(tasks[n], p.exitcode, again)
        if again:
            retry.appendleft(n)       # once more, in a fresh worker
        else:
            t = tasks.pop(n)
            finish(t, fail(t, WorkerDied(t, deaths[n])))
        spawn()

    try:
        for _ in range(jobs):
            if not spawn():
                break
        while workers:
            for conn in wait(list(workers)):
                try:
                    n, (ok, result) = conn.recv()
                except (EOFError, OSError):         # the worker is gone
                    died(conn)
                    continue
                t = tasks.pop(n)
                finish(t, result if ok else fail(t, result))
                feed(conn)
        while (n := next_task()) is not None:       # no worker could be started: this process
            _run_here(tasks.pop(n), work, finish, fail)
    finally:
        _stop(workers)


def _start_worker(ctx, work):
    """``(connection, process)`` of a fresh :func:`_worker`, or None when no process can be had
    (at the limit of processes or memory)."""
    mine, theirs = ctx.Pipe()
    p = ctx.Process(target=_worker, args=(theirs, work), daemon=True)
    try:
        p.start()
    except OSError:
        mine.close()
        return None
    finally:
        theirs.close()
    return mine, p


def _run_here(t, work, finish, fail):
    try:
        result = work(t)
    except Exception as e:  # noqa: BLE001 - the caller's failed() says what it becomes
        result = fail(t, e)
    finish(t, result)


def _stop(workers):
    """End the worker processes left (after Ctrl-C or an error)."""
    for conn, (p, _) in workers.items():
        if p.is_alive():
            p.terminate()
        p.join(timeout=10)
        conn.close()


def _worker(conn, work):
    """A process of :func:`_in_processes`: runs the tasks it is sent (``(n, task)``,
    ``None`` to stop) and sends back ``(n, (True, result))`` or ``(n, (False, exception))``."""
    import signal

    signal.signal(signal.SIGINT, signal.SIG_IGN)    # the parent handles Ctrl-C (and ends us)
    for n, task in iter(conn.recv, None):
        try:
            out = (True, work(task))
        except Exception as e:  # noqa: BLE001 - the parent's failed() says what it becomes
            out = (False, e)
        try:
            conn.send((n, out))
        except Exception as e:  # noqa: BLE001 - a result that does not pickle: its text
            conn.send((n, (False, RuntimeError(f"{type(out[1]).__name__}: {out[1]} (and it could not be "
                                               f"sent: {e})"))))
