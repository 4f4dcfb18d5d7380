"""The figures report: run every figure (progress bar, cache) and write ``index.html``.

Cache: each figure's directory ``OUT/NAME/`` holds ``figure.json`` with the hash
of its inputs (figure name, parameters, resolution, spp, quick mode, and the
source of the plausible package except the CLI and this runner).  A figure
whose hash and files are unchanged is not made again.

A figure is made in a temporary folder ``OUT/.NAME.partial-*`` and put in place
of ``OUT/NAME/`` by renaming it only when it is complete, so ``OUT/NAME/`` always
holds the files of one run, the run its ``figure.json`` describes: a run
interrupted (Ctrl-C) or killed while it remakes a figure leaves the previous
one as it was, and the cache never claims files of another run.  On any exit,
Ctrl-C included, ``index.html`` is written for the figures made so far.
"""

from __future__ import annotations

import hashlib
import html
import json
import os
import resource
import shutil
import tempfile
import time
import traceback
from contextlib import contextmanager
from pathlib import Path

from rich.console import Console
from rich.markup import escape

from ..analysis.suite import usable_cores
from ..engine import process_alive
from ..integrals.albedo import remembering
from ..progress import start
from ..text import fmt
from .core import FIGURES, Context, get, names

_PKG = Path(__file__).resolve().parent.parent


def source_hash() -> str:
    """SHA-1 over the package's sources that figures depend on."""
    h = hashlib.sha1()
    for p in sorted(_PKG.rglob("*")):
        if p.suffix not in (".py", ".csv") or p.name in ("cli.py", "report.py") or "__pycache__" in p.parts:
            continue
        h.update(str(p.relative_to(_PKG)).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def input_key(fig, *, resolution, spp, quick, src=None) -> str:
    from importlib.metadata import PackageNotFoundError, version

    try:
        ver = version("plausible")
    except PackageNotFoundError:   # pragma: no cover
        ver = "0"
    blob = json.dumps(dict(name=fig.name, params=fig.params, resolution=resolution, spp=spp, quick=quick,
                           version=ver, source=src or source_hash(), variant=render_variant(fig)),
                      sort_keys=True, default=str)
    return hashlib.sha1(blob.encode()).hexdigest()


def render_variant(fig):
    """The Mitsuba RGB variant a rendering figure runs on (:func:`plausible.mitsuba.variant.preferred`:
    CUDA where a GPU is found, ``plausible figures --variant``); None for a figure that renders
    nothing, or where Mitsuba cannot render (the figure then fails and says why)."""
    if not fig.renders:
        return None
    try:
        from ..mitsuba.variant import preferred

        return preferred("rgb")
    except ValueError:
        return None


def _cached(d: Path, key: str):
    meta = d / "figure.json"
    if not meta.exists():
        return None
    try:
        m = json.loads(meta.read_text())
    except ValueError:
        return None
    if m.get("key") != key or m.get("status") != "ok":
        return None
    files = [it.get("png") or it.get("file") for it in m.get("items", [])]
    files += [it["exr"] for it in m.get("items", []) if it.get("exr")]
    return m if all((d / f).exists() for f in files) else None


def _remove_partial(out: Path, name: str):
    """Tidy what a killed or interrupted run left of figure ``name``: its unfinished
    ``.NAME.partial-*`` folders are removed, and its previous figure put back
    (:func:`_restore_old`)."""
    for p in out.glob(f".{name}.partial-*"):
        shutil.rmtree(p, ignore_errors=True)
    _restore_old(out, name)


def _restore_old(out: Path, name: str):
    """A ``.NAME.old-PID`` folder is a finished figure that :func:`_replace` of process PID moved
    aside and did not replace (it was killed between its two renames): put it back where ``NAME``
    is missing, else remove it.  One whose process still runs (another run on the same folder, in
    that window now) is left to it."""
    for p in sorted(out.glob(f".{name}.old-*")):
        pid = p.name.rsplit("-", 1)[1]
        if pid.isdigit() and int(pid) != os.getpid() and process_alive(int(pid)):
            continue
        if not (out / name).exists():
            try:
                p.rename(out / name)
                continue
            except OSError:         # NAME appeared meanwhile: this one is the older
                pass
        shutil.rmtree(p, ignore_errors=True)


def _replace(tmp: Path, d: Path):
    """Put the finished figure folder ``tmp`` in place of ``d`` (renames only; the
    old folder is moved aside first, since a rename cannot replace a non-empty one).
    Interrupted between the two renames, the old folder goes back; killed there, the
    next run (or the parent of a killed worker) puts it back (:func:`_remove_partial`)."""
    old = None
    if d.exists():
        old = d.with_name(f".{d.name}.old-{os.getpid()}")
        d.rename(old)
    try:
        tmp.rename(d)
    except BaseException:
        if old is not None and not d.exists():
            old.rename(d)
        raise
    if old is not None:
        shutil.rmtree(old, ignore_errors=True)


def _index_all(out: Path, results: dict) -> Path:
    """``index.html`` of every figure present in ``out``, not only this run's."""
    allm = {}
    for n in names():
        if n in results:
            allm[n] = results[n]
        elif (out / n / "figure.json").exists():
            try:
                allm[n] = json.loads((out / n / "figure.json").read_text())
            except ValueError:
                pass
    return write_index(out, allm)


def _dir_mode() -> int:
    """The mode ``mkdir`` gives a new folder under the current umask (0755 under 022)."""
    mask = os.umask(0)
    os.umask(mask)
    return 0o777 & ~mask


def cpu_seconds() -> float:
    """User + system CPU seconds of this process (all its threads: Dr.Jit's pool included) and of its
    children that have ended, from ``getrusage``: what a figure costs on a machine whose cores are
    shared, where its wall time depends on the load."""
    return sum(u.ru_utime + u.ru_stime for u in (resource.getrusage(resource.RUSAGE_SELF),
                                                 resource.getrusage(resource.RUSAGE_CHILDREN)))


def _make(fig, key: str, out: Path, *, resolution, spp, quick, progress) -> dict:
    """Make the :class:`~plausible.figures.Figure` ``fig`` into ``out/NAME`` (through a
    partial folder, see the module docstring) and return its ``figure.json``
    contents.  A figure that raises is recorded as failed with its traceback; the
    others are unaffected."""
    name = fig.name
    d = out / name
    _remove_partial(out, name)      # left by a run that was killed
    tmp = Path(tempfile.mkdtemp(prefix=f".{name}.partial-", dir=out))
    try:
        os.chmod(tmp, _dir_mode())      # mkdtemp makes 0700: the figure folder follows the umask
        ctx = Context(tmp, resolution=resolution, spp=spp, quick=quick,
                      progress=lambda total, label="", _n=name: start(progress, total, _n))
        t0, c0 = time.time(), cpu_seconds()
        m = dict(name=name, title=fig.title, source=fig.source, caption=fig.caption, params=fig.params,
                 key=key, resolution=ctx.base_res, spp=ctx.base_spp, quick=quick, renders=fig.renders,
                 variant=render_variant(fig))
        try:
            fig.fn(ctx, **fig.params)
            m["status"] = "ok"
        except Exception as e:   # a failing figure is reported, the others still run
            if _interrupted(e):     # Ctrl-C inside a render: Mitsuba's render op re-raises it as a RuntimeError
                raise KeyboardInterrupt from e
            m["status"] = "failed"
            m["error"] = traceback.format_exc()
        ctx.finish()
        m.update(items=ctx.items, measurements=ctx.measurements, notes=ctx.notes,
                 seconds=round(time.time() - t0, 1), cpu_seconds=round(cpu_seconds() - c0, 1), cached=False)
        (tmp / "figure.json").write_text(json.dumps(m, indent=1))
        _replace(tmp, d)
        tmp = None
        return m
    finally:    # interrupted (Ctrl-C): drop the unfinished figure
        if tmp is not None:
            shutil.rmtree(tmp, ignore_errors=True)


def _interrupted(e) -> bool:
    """``e`` is an interrupt a library turned into another exception: a ``KeyboardInterrupt`` in its chain
    of causes (``drjit.custom``, around every ``mitsuba.render``, raises a RuntimeError from it; recorded as
    a failed figure, it replaced the previous one and the run went on to the next)."""
    seen = set()
    while e is not None and id(e) not in seen:
        if isinstance(e, KeyboardInterrupt):
            return True
        seen.add(id(e))
        e = e.__cause__ or e.__context__
    return False


def _report(console, name, m):
    if m["status"] != "ok":
        console.print(f"[red]figure {escape(name)} failed:[/red]\n{escape(m.get('error', ''))}")
    cpu = f" ({m['cpu_seconds']} CPU-s)" if "cpu_seconds" in m else ""
    console.print(f"{escape(name):<22} {m['status']} {m['seconds']} s{cpu}")


def run(out, *, only=None, spp=None, resolution=None, quick=False, force=False, console=None,
        progress=None, jobs: int = 1) -> dict:
    """Make the figures (all, or the names in ``only``) into ``out`` and write
    ``out/index.html``.  Returns ``{name: figure.json contents}`` in report order;
    each has ``status`` ("ok" or "failed"), ``cached``, ``seconds`` and (made in this run or one since
    CPU time was recorded) ``cpu_seconds`` (:func:`cpu_seconds`).

    ``spp`` / ``resolution`` override the samples per pixel / base image size
    (defaults :data:`plausible.figures.DEFAULT_SPP` / ``DEFAULT_RESOLUTION``);
    ``quick`` uses small ones (the CI mode).  Deterministic: fixed seeds.
    ``progress``: a :mod:`plausible.progress` factory, announced once per figure
    (labelled with its name); a line per figure says how it went.

    ``jobs`` > 1: the figures to make run in that many worker processes
    (:func:`_run_parallel`, the longest first); each figure is made exactly as in
    one process (its own seeds, its own folder), so the report is the same, and a
    line per figure still says how it went as each one finishes.
    """
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    console = console or Console()
    todo = names() if not only else list(dict.fromkeys(get(n).name for n in only))
    src = source_hash()
    results = {}
    t_all = time.time()
    name = ""
    with remembering():     # an albedo asked again by another figure of this process is not recomputed
        try:
            make = []
            for name in todo:
                key = input_key(FIGURES[name], resolution=resolution, spp=spp, quick=quick, src=src)
                _restore_old(out, name)         # a figure a killed run moved aside is still this folder's
                m = None if force else _cached(out / name, key)
                if m is not None:
                    m["cached"] = True
                    console.print(f"{escape(name):<22} cached")
                    results[name] = m
                else:
                    make.append((name, key))
            if jobs > 1 and len(make) > 1:
                _run_parallel(out, make, results, jobs=jobs, resolution=resolution, spp=spp, quick=quick,
                              console=console, progress=progress)
            else:
                for name, key in make:
                    m = _make(FIGURES[name], key, out, resolution=resolution, spp=spp, quick=quick,
                              progress=progress)
                    _report(console, name, m)
                    results[name] = m
        except KeyboardInterrupt:
            busy = name if jobs <= 1 else ", ".join(n for n, _ in make if n not in results)
            left = "it is left as it was" if "," not in busy else "they are left as they were"
            console.print(f"[yellow]interrupted while making {escape(busy)}: {left} before this run; "
                          f"{len(results)} figures done -> {escape(str(out / 'index.html'))}[/yellow]")
            raise
        finally:    # on any exit: index what is done
            _index_all(out, results)
    results = {n: results[n] for n in todo if n in results}
    total = round(time.time() - t_all, 1)
    failed = [n for n, m in results.items() if m["status"] != "ok"]
    checks = [x for m in results.values() for x in m.get("measurements", []) if "ok" in x]
    bad = [x for x in checks if not x["ok"]]
    unmeasured = sum(1 for m in results.values() for x in m.get("measurements", []) if x.get("unmeasured"))
    console.print(f"{len(results)} figures ({sum(m.get('cached', False) for m in results.values())} cached, "
                  f"{len(failed)} failed) in {total} s ({_cpu_made(results)} CPU-s making them);")
    console.print(f"{len(checks) - len(bad)}/{len(checks)} measured "
                  f"checks hold" + (f", {unmeasured} not measured at this quality" if unmeasured else "")
                  + f" -> {escape(str(out / 'index.html'))}")
    return results


def _cpu_made(results) -> float:
    """CPU seconds of the figures made (not cached) in this run, summed."""
    return round(sum(m.get("cpu_seconds", 0.0) for m in results.values() if not m.get("cached")), 1)


# -- worker processes -----------------------------------------------------------------

#: Seconds each figure takes in a default run (2-core machine: its CPU seconds, one Dr.Jit thread as in a
#: worker of ``make demo``, empty kernel cache, all figures in one process, 2 December 07:10 UTC), for the
#: order in which worker processes take them: the longest first, so that no long figure starts last (before
#: ``convert-legacy`` was listed it was made last, 5 s with the other worker idle).  Only the order depends
#: on these; a figure not listed (the lobe figures: 0.2-0.9 s) counts as 1 s, and the ``seconds`` of a
#: previous run in the output folder take precedence.
EXPECTED_SECONDS = {"checks": 19.1, "materials-check": 14.3, "compensation": 13.4, "notes-cornell": 11.9,
                    "materials-atlas": 11.6, "neumann-fig8": 11.2, "as-red-spheres": 9, "as-gold": 8.6,
                    "as-three-views": 8.5, "convert-looks": 30.0, "convert-legacy": 5.8, "as-lambert-vs-as": 5.5, "as-cylinder": 5.5,
                    "neumann-fig1": 4.5, "mitsuba-builtins": 4.4, "as-furnace": 4.1, "neumann-fig5": 4,
                    "as-half-sphere": 3.2, "as-convergence": 3.1, "neumann-fig6": 2.7, "neumann-fig4": 2.5,
                    "neumann-fig3": 2.3, "neumann-perceptual": 1.8, "lobe-kulla-conty": 1.5}


#: Figures made right after another one by the same worker process: follower -> leader.  The leader
#: integrates albedo curves that the follower shows too (fig. 5 holds fig. 3's max pumping once and three
#: times, fig. 6 fig. 4's), and a process remembers them (:func:`plausible.integrals.albedo.remembering`).
FOLLOWS = {"neumann-fig3": "neumann-fig5", "neumann-fig4": "neumann-fig6"}


def _next(todo, busy, done=None):
    """Index in ``todo`` (``(name, key)`` pairs, in order) of the figure a worker that has just
    made ``done`` (or nothing) takes next: a follower of ``done`` (:data:`FOLLOWS`), else the first
    figure whose leader is neither waiting nor being made (``busy``: the names in progress), else
    the first.  None when ``todo`` is empty."""
    if not todo:
        return None
    names = [n for n, _ in todo]
    for i, n in enumerate(names):
        if done is not None and FOLLOWS.get(n) == done:
            return i
    for i, n in enumerate(names):
        lead = FOLLOWS.get(n)
        if lead is None or (lead not in names and lead not in busy):
            return i
    return 0


def _expected_seconds(out: Path, name: str) -> float:
    try:
        return float(json.loads((out / name / "figure.json").read_text())["seconds"])
    except (OSError, ValueError, KeyError, TypeError):
        return float(EXPECTED_SECONDS.get(name, 1.0))


#: Environment variables of the worker processes, where not set already: one BLAS thread
#: each.  The workers share the cores, and OpenBLAS's threads wait for work by spinning:
#: ``numpy.polynomial.legendre.leggauss(256)`` (one small eigenvalue problem) took 0.50
#: CPU-s with two threads and 0.009 with one.
WORKER_ENV = {"OPENBLAS_NUM_THREADS": "1"}


@contextmanager
def _environment(values: dict):
    """``os.environ`` with ``values`` added where unset, within the block."""
    added = [k for k in values if k not in os.environ]
    os.environ.update({k: values[k] for k in added})
    try:
        yield
    finally:
        for k in added:
            os.environ.pop(k, None)


def worker_threads(jobs: int) -> int:
    """Dr.Jit worker threads of each of ``jobs`` figure processes: the cores shared out, at least
    one.  Dr.Jit's default, a thread per core in every process, oversubscribes the cores, and its
    idle threads wait for the next launch by spinning: the ``checks`` figure alone (warm kernel
    cache, 2 cores) took 17.1 CPU-s in 8.8 s with two threads and 12.0 CPU-s in 11.7 s with one, and
    in ``make demo`` the other process needs those CPU seconds."""
    return max(1, usable_cores() // max(1, jobs))


def _set_threads(n):
    """Dr.Jit's thread pool of this process to ``n`` threads (nothing without Dr.Jit)."""
    if not n:
        return
    try:
        import drjit
    except ImportError:     # pragma: no cover - the NumPy-only install
        return
    if drjit.thread_count() != n:
        drjit.set_thread_count(n)


def _worker(conn, out, resolution, spp, quick, threads=0):
    """A worker process: make each figure ``(Figure, key)`` the parent sends on the
    pipe ``conn`` until it sends None.  Progress and results go back on the same
    pipe (synchronously, so nothing is lost if the process dies afterwards):
    ``("start", id, total, label)``, ``("tick", id, n)``, ``("done", figure.json)``."""
    import itertools
    import signal

    from ..progress import reporting

    signal.signal(signal.SIGINT, signal.SIG_IGN)    # the parent handles Ctrl-C (and ends us)
    _set_threads(threads)
    ids = itertools.count()

    def forward(total, label=""):
        i = next(ids)
        conn.send(("start", i, int(total), label))

        def tick(n=1):
            conn.send(("tick", i, int(n)))

        return tick

    with reporting(forward), remembering():
        for fig, key in iter(conn.recv, None):
            conn.send(("done", _make(fig, key, Path(out), resolution=resolution, spp=spp, quick=quick,
                                     progress=forward)))


def _failed(name, key, error) -> dict:
    return dict(name=name, key=key, status="failed", error=error, cached=False, seconds=0.0, items=[],
                measurements=[], notes=[])


def _run_parallel(out, make, results, *, jobs, resolution, spp, quick, console, progress):
    """Make the figures ``make`` (``(name, key)`` pairs) in ``jobs`` worker processes
    (spawned: a fresh interpreter each, no Dr.Jit state shared), the longest first
    (:data:`EXPECTED_SECONDS`), each worker given the next figure when it finishes
    one (a follower of the one it finished first, :data:`FOLLOWS`); fill ``results`` as they finish.  A worker that dies fails the figure it
    was making (its exit code in the error) and is replaced; on any exit the workers
    are ended and the partial folders of unfinished figures removed."""
    import multiprocessing as mp
    from multiprocessing.connection import wait

    ctx = mp.get_context("spawn")
    todo = sorted(make, key=lambda nk: -_expected_seconds(out, nk[0]))
    threads = worker_threads(min(jobs, len(todo)))
    workers = {}    # connection -> [process, figure name or None, {progress id: tick}]

    def spawn():
        mine, theirs = ctx.Pipe()
        p = ctx.Process(target=_worker, args=(theirs, str(out), resolution, spp, quick, threads), daemon=True)
        try:
            with _environment(WORKER_ENV):     # a spawned interpreter reads it when NumPy loads
                p.start()
        finally:                               # a Ctrl-C right after the start still ends it below
            theirs.close()
            if p.pid is not None:
                workers[mine] = [p, None, {}]
        feed(mine)

    def feed(conn):
        w = workers[conn]
        i = _next(todo, {v[1] for c, v in workers.items() if c is not conn and v[1] is not None}, done=w[1])
        if i is not None:
            name, key = todo.pop(i)
            w[1] = name
            conn.send((FIGURES[name], key))     # the Figure itself: its function pickles by name
        else:
            w[1] = None
            conn.send(None)

    def finish(name, m):
        _report(console, name, m)
        results[name] = m

    try:
        for _ in range(min(jobs, len(todo))):
            spawn()
        while workers:
            for conn in wait(list(workers), timeout=1.0):
                p, name, ticks = workers[conn]
                try:
                    msg = conn.recv()
                except (EOFError, OSError):     # the worker is gone
                    p.join()
                    del workers[conn]
                    conn.close()
                    if name is not None:
                        _remove_partial(out, name)
                        finish(name, _failed(name, dict(make)[name], "the worker process making this figure "
                                             f"died (exit code {p.exitcode}; its error, if any, is printed above)"))
                        if todo:
                            spawn()
                    continue
                if msg[0] == "start":
                    ticks[msg[1]] = start(progress, msg[2], msg[3])
                elif msg[0] == "tick":
                    ticks.get(msg[1], lambda n=1: None)(msg[2])
                else:
                    finish(name, msg[1])
                    ticks.clear()
                    feed(conn)
    finally:
        for conn, (p, name, _) in workers.items():
            if p.is_alive():
                p.terminate()
            p.join(timeout=10)
            conn.close()
            if name is not None:
                _remove_partial(out, name)


# -- index.html ---------------------------------------------------------------------

_CSS = """body{font-family:system-ui,sans-serif;max-width:1100px;margin:2em auto;padding:0 1em;color:#222}
h2{border-top:1px solid #ccc;padding-top:1em}figure{display:inline-block;margin:.5em;vertical-align:top}
figure img{max-width:520px;image-rendering:pixelated;border:1px solid #ddd}figcaption{font-size:.85em;max-width:520px}
blockquote{color:#444;border-left:3px solid #aaa;margin:.5em 0;padding-left:1em}table{border-collapse:collapse;font-size:.9em}
td,th{border:1px solid #ccc;padding:2px 6px;text-align:left}.ok{color:#080}.bad{color:#b00;font-weight:bold}
.failed{background:#fee;padding:1em}nav a{margin-right:.8em}code{font-size:.9em}"""

#: Sets ``data-images`` on <body> to "LOADED/TOTAL" once every image has loaded or
#: failed (the headless-browser test reads it); broken images get a red border.
_JS = """<script>
(function(){
  function done(){
    var imgs=document.images, ok=0, n=imgs.length, pending=0;
    for(var i=0;i<n;i++){ if(!imgs[i].complete){pending++;} else if(imgs[i].naturalWidth>0){ok++;}
      else {imgs[i].style.border='3px solid red';} }
    if(pending>0){ setTimeout(done, 50); return; }
    document.body.setAttribute('data-images', ok+'/'+n);
  }
  window.addEventListener('load', done);
})();
</script>"""


def _joined(*parts) -> str:
    return "; ".join(p for p in parts if p)


def _cell(x):
    """A measurement's number (a boolean as yes / no) in a table cell."""
    if isinstance(x, bool):
        return "yes" if x else "no"
    return "" if x is None else html.escape(fmt(x, ".6g"))


def _expected(x) -> str:
    """The "expected" cell: the value, or the bounds ``>= a`` / ``<= b``."""
    bounds = [f"&ge; {_cell(x['at_least'])}" if x.get("at_least") is not None else "",
              f"&le; {_cell(x['at_most'])}" if x.get("at_most") is not None else ""]
    bounds = [b for b in bounds if b]
    if bounds:
        return ", ".join(bounds)
    return _cell(x.get("expected"))


def write_index(out: Path, figs: dict) -> Path:
    """Write ``out/index.html`` showing every figure in ``figs`` (``figure.json`` contents)."""
    e = html.escape
    parts = ["<!DOCTYPE html><html><head><meta charset='utf-8'><title>plausible: the papers' figures</title>",
             f"<style>{_CSS}</style>{_JS}</head><body>",
             "<h1>plausible: the papers' figures, reproduced</h1>",
             "<p>Each section shows a figure of Ashikhmin &amp; Shirley (2000), Neumann, Neumann &amp; "
             "Szirmay-Kalos (1999) or the Modified Phong notes, with the paper's caption, the parameters used, "
             "and the numbers measured on it (checks in <span class='ok'>green</span> hold, "
             "<span class='bad'>red</span> do not). Renders: PNG for viewing (sRGB, clipped at 1), EXR for "
             "the linear radiance. Made by <code>plausible figures</code>.</p><nav>"]
    parts += [f"<a href='#{e(n)}'>{e(n)}</a>" for n in figs]
    parts.append("</nav>")
    for n, m in figs.items():
        parts.append(f"<h2 id='{e(n)}'>{e(m.get('title', n))}</h2>")
        parts.append(f"<p><b>{e(m.get('source', ''))}</b></p><blockquote>{e(m.get('caption', ''))}</blockquote>")
        params = dict(m.get("params", {}))
        if m.get("renders", True):   # image size, samples and Mitsuba variant only where the section renders
            params.update(resolution=m.get("resolution"), spp=m.get("spp"))
            if m.get("variant"):
                params.update(variant=m["variant"])
        parts.append("<p>Parameters: " + ", ".join(f"<code>{e(k)} = {e(str(v))}</code>" for k, v in params.items())
                     + f" &middot; made in {m.get('seconds', '?')} s</p>")
        if m.get("status") != "ok":
            parts.append(f"<pre class='failed'>{e(m.get('error', 'failed'))}</pre>")
        for it in m.get("items", []):
            if it["kind"] in ("image", "plot"):
                link = f" &middot; <a href='{e(n)}/{e(it['exr'])}'>EXR</a>" if it.get("exr") else ""
                parts.append(f"<figure><a href='{e(n)}/{e(it['png'])}'><img src='{e(n)}/{e(it['png'])}' "
                             f"alt='{e(it['png'])}'></a><figcaption>{e(it.get('caption', ''))}{link}"
                             "</figcaption></figure>")
        data = [it for it in m.get("items", []) if it["kind"] == "data"]
        if data:
            parts.append("<p>Data: " + ", ".join(f"<a href='{e(n)}/{e(it['file'])}'>{e(it['file'])}</a>"
                                                 + (f" ({e(it['caption'])})" if it.get("caption") else "")
                                                 for it in data) + "</p>")
        meas = m.get("measurements", [])
        if meas:
            parts.append("<table><tr><th>measured</th><th>value</th><th>expected</th><th>tolerance</th>"
                         "<th></th><th>note</th></tr>")
            for x in meas:
                ok = x.get("ok")
                cls = "" if ok is None else ("ok" if ok else "bad")
                verdict = "" if ok is None else ("holds" if ok else "DOES NOT HOLD")
                if x.get("unmeasured"):
                    verdict = "not measured at this quality"
                parts.append(f"<tr><td>{e(x['quantity'])}</td><td>{_cell(x['measured'])}</td>"
                             f"<td>{_expected(x)}</td><td>{_cell(x['tol'])}</td>"
                             f"<td class='{cls}'>{verdict}</td>"
                             f"<td>{e(_joined(x.get('note', ''), x.get('unmeasured', '')))}</td></tr>")
            parts.append("</table>")
        for t in m.get("notes", []):
            parts.append(f"<p>{e(t)}</p>")
    parts.append("</body></html>")
    path = out / "index.html"
    path.write_text("\n".join(parts))
    return path
