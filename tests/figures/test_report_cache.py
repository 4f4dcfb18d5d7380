"""The figures runner's cache and exit paths, on small fake figures (no rendering):
an interrupted remake leaves the previous figure whole, an interrupted run still
writes index.html, and the CLI reports unknown names, repeats and red checks."""

from __future__ import annotations

import json
import os
import re
import time

import numpy as np
import pytest
from click.testing import CliRunner

import plausible.figures as F
from plausible.cli import main
from plausible.figures.report import _cached, input_key, run


def _stamp(ctx, interrupt_at=None):
    """Two data files holding the run's spp; Ctrl-C after the first when spp == interrupt_at."""
    ctx.steps(2)
    ctx.table("first", {"spp": np.array([ctx.base_spp])})
    ctx.tick()
    if ctx.base_spp == interrupt_at:
        raise KeyboardInterrupt
    ctx.table("second", {"spp": np.array([ctx.base_spp])})
    ctx.tick()
    ctx.measure("spp", ctx.base_spp, expected=16, tol=0.5)   # holds only at spp 16


@pytest.fixture
def fake(monkeypatch):
    F.names()   # load the real ones first, so that ours is not overwritten
    monkeypatch.setitem(F.FIGURES, "fake", F.Figure("fake", "Fake", "test", "caption", _stamp,
                                                    dict(interrupt_at=4096)))
    return "fake"


def _spp(path):
    return float(path.read_text().splitlines()[1])


def test_an_interrupted_remake_leaves_the_previous_figure_whole(tmp_path, fake):
    run(tmp_path, only=[fake], spp=16)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=4096)
    d = tmp_path / fake
    assert _spp(d / "first.csv") == 16 and _spp(d / "second.csv") == 16      # not the interrupted run's 4096
    assert json.loads((d / "figure.json").read_text())["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []   # no partial folder left
    again = run(tmp_path, only=[fake], spp=16)
    assert again[fake]["cached"] is True


def _wrapped_interrupt(ctx, interrupt_at=None):
    """As :func:`_stamp`, but the Ctrl-C arrives as Mitsuba's render op re-raises it: a RuntimeError from it."""
    if ctx.base_spp == interrupt_at:
        try:
            raise KeyboardInterrupt
        except KeyboardInterrupt as e:
            raise RuntimeError("drjit.custom(<mitsuba.python.util._RenderOp>): error while performing a custom "
                               "differentiable operation. (see above).") from e
    _stamp(ctx)


def test_an_interrupt_a_renderer_wraps_stops_the_run_and_keeps_the_previous_figure(tmp_path, monkeypatch, fake):
    # before: recorded as a failed figure, which replaced the previous one, and the run went on
    monkeypatch.setitem(F.FIGURES, fake, F.Figure(fake, "Fake", "test", "caption", _wrapped_interrupt,
                                                  dict(interrupt_at=4096)))
    run(tmp_path, only=[fake], spp=16)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=4096)
    m = json.loads((tmp_path / fake / "figure.json").read_text())
    assert m["status"] == "ok" and m["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_a_runtime_error_without_an_interrupt_is_still_a_failed_figure(tmp_path, monkeypatch, fake):
    def broken(ctx):
        raise RuntimeError("a renderer's own error")
    monkeypatch.setitem(F.FIGURES, fake, F.Figure(fake, "Fake", "test", "caption", broken, {}))
    assert run(tmp_path, only=[fake], spp=16)[fake]["status"] == "failed"


def test_an_interrupted_run_in_a_fresh_folder_writes_the_index_and_claims_nothing(tmp_path, fake):
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=4096)
    assert (tmp_path / "index.html").exists()
    assert not (tmp_path / fake).exists()
    key = input_key(F.FIGURES[fake], resolution=None, spp=4096, quick=False)
    assert _cached(tmp_path / fake, key) is None
    assert run(tmp_path, only=[fake], spp=16)[fake]["cached"] is False


def test_figures_cli_unknown_name_creates_nothing(tmp_path):
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", "nonexistent"])
    assert r.exit_code == 2 and "unknown figure 'nonexistent'" in r.output and "as-furnace" in r.output
    assert not out.exists()


def test_figures_cli_repeated_name_made_once_and_red_check_fails(tmp_path, fake):
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", fake, "--only", fake, "--spp", "16"])
    assert r.exit_code == 0, r.output
    assert "1 figures (0 cached, 0 failed)" in r.output and "1/1 measured checks hold" in r.output
    r = CliRunner().invoke(main, ["figures", "--out", str(out), "--only", fake, "--spp", "8"])
    assert r.exit_code == 1
    assert "measured checks that do not hold (1): fake: spp" in r.output


def test_figures_cli_unwritable_folder(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = CliRunner().invoke(main, ["figures", "--out", str(blocker / "out"), "--only", "checks"])
    assert r.exit_code == 2 and "--out: cannot write into" in r.output and "Traceback" not in r.output


# -- worker processes (jobs > 1) ------------------------------------------------------------

def _crash(ctx):
    """A figure whose process dies mid-way, as a crash inside a renderer would."""
    ctx.steps(2)
    ctx.tick()
    os._exit(3)


def _sleep(ctx):
    from pathlib import Path

    ctx.steps(1)
    Path(os.environ["PLAUSIBLE_TEST_SLEEPING"]).touch()    # tells the test the worker is inside
    time.sleep(120)


def _strip(m):
    return {k: v for k, v in m.items() if k not in ("seconds", "cpu_seconds", "cached", "measurements")}


def _numbers(text):
    return np.array([float(x) for x in re.findall(r"-?\d+\.?\d*(?:e[-+]?\d+)?", text)])


def test_parallel_run_makes_the_same_report_as_one_process(tmp_path):
    """Two real figures made by two worker processes: the same figure.json (but the
    seconds), the same data files and the same index as in one process.  The numbers
    agree to rounding (1e-12 relative), not to the last bit: which backend ``auto``
    picks for a call depends on what the process compiled before (backend.choose)."""
    from plausible.progress import Counter

    figs = ["lobe-lambertian", "lobe-blinn"]
    one = run(tmp_path / "one", only=figs, quick=True, jobs=1)
    c = Counter()
    two = run(tmp_path / "two", only=figs, quick=True, jobs=2, progress=c)
    assert list(two) == figs                        # report order, whatever the finishing order
    for n in figs:
        assert two[n]["status"] == "ok" and _strip(two[n]) == _strip(one[n])
        for a, b in zip(one[n]["measurements"], two[n]["measurements"], strict=True):
            assert {**a, "measured": 0} == {**b, "measured": 0}
            assert np.isclose(a["measured"], b["measured"], rtol=1e-12, atol=1e-15), a["quantity"]
        files = sorted((tmp_path / "one" / n).glob("*.csv"))
        assert files
        for f in files:
            x, y = _numbers(f.read_text()), _numbers((tmp_path / "two" / n / f.name).read_text())
            assert x.shape == y.shape and np.allclose(x, y, rtol=1e-7, atol=1e-12), f   # %.8g; error bounds of 1e-11 are rounding
        assert c.counts[n][1] == c.counts[n][0] > 0    # the workers' progress reached the parent
    strip = lambda p: re.sub(r"made in [0-9.]+ s", "", p.read_text())   # noqa: E731
    assert strip(tmp_path / "two" / "index.html") == strip(tmp_path / "one" / "index.html")


def test_a_worker_that_dies_fails_its_figure_and_the_others_are_made(tmp_path, monkeypatch, fake):
    monkeypatch.setitem(F.FIGURES, "crash", F.Figure("crash", "Crash", "test", "caption", _crash, {}))
    res = run(tmp_path, only=["crash", fake, "lobe-lambertian"], spp=16, jobs=2)
    assert res["crash"]["status"] == "failed" and "died (exit code 3" in res["crash"]["error"]
    assert res[fake]["status"] == "ok" and res["lobe-lambertian"]["status"] == "ok"
    assert not (tmp_path / "crash").exists()
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []   # no partial folder left
    assert json.loads((tmp_path / fake / "figure.json").read_text())["spp"] == 16


def _running(pid: int) -> bool:
    """Whether the operating system still runs process ``pid`` (a zombie has ended).

    ``multiprocessing``'s own view can be stale: a Ctrl-C landing in ``os.waitpid``
    after the worker was reaped but before ``Process.join`` stored its exit code
    leaves a dead worker listed as "started" in ``active_children()`` for good."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except FileNotFoundError:
        return False


def test_running_tells_a_live_process_from_an_ended_one():
    import subprocess

    child = subprocess.Popen(["sleep", "30"])
    try:
        assert _running(child.pid) and _running(os.getpid())
    finally:
        child.kill()
    deadline = time.monotonic() + 30
    while _running(child.pid) and time.monotonic() < deadline:
        time.sleep(0.01)
    assert not _running(child.pid)             # killed, not yet reaped: a zombie
    child.wait()
    assert not _running(child.pid)             # reaped: gone


def test_an_interrupted_parallel_run_ends_its_workers_and_leaves_no_partial_folder(tmp_path, monkeypatch, fake):
    import _thread
    import multiprocessing
    import threading

    monkeypatch.setitem(F.FIGURES, "sleep", F.Figure("sleep", "Sleep", "test", "caption", _sleep, {}))
    mark = tmp_path.parent / f"{tmp_path.name}.sleeping"
    monkeypatch.setenv("PLAUSIBLE_TEST_SLEEPING", str(mark))
    run(tmp_path, only=[fake], spp=16)
    before = set(multiprocessing.active_children())         # children of earlier tests are not this run's
    done = threading.Event()

    def ctrl_c_while_sleeping():                            # Ctrl-C once "sleep" runs, however slow the spawn
        while not done.is_set():
            if mark.exists():
                _thread.interrupt_main()
                return
            time.sleep(0.05)

    watcher = threading.Thread(target=ctrl_c_while_sleeping, daemon=True)
    watcher.start()
    try:
        with pytest.raises(KeyboardInterrupt):
            run(tmp_path, only=["sleep", fake], spp=32, jobs=2, force=True)
    finally:
        done.set()
        watcher.join()
    assert [p for p in multiprocessing.active_children() if p not in before and _running(p.pid)] == []
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    assert not (tmp_path / "sleep").exists() and (tmp_path / "index.html").exists()
    assert json.loads((tmp_path / fake / "figure.json").read_text())["spp"] in (16, 32)   # whole, of one run


def test_a_remake_stopped_between_its_two_renames_keeps_the_previous_figure(tmp_path, fake, monkeypatch):
    """The window a Ctrl-C or a killed worker can hit: the finished figure moved aside,
    the new one not yet in its place.  Interrupted there, the old folder goes back at
    once; killed there (nothing runs after), the next run, or the parent of the killed
    worker, puts it back instead of deleting it as a leftover."""
    from pathlib import Path

    from plausible.figures.report import _remove_partial

    run(tmp_path, only=[fake], spp=16)
    rename = Path.rename

    def stop_second(self, target):
        if ".partial-" in self.name:        # the second rename: the new folder into place
            raise KeyboardInterrupt
        return rename(self, target)

    monkeypatch.setattr(Path, "rename", stop_second)
    with pytest.raises(KeyboardInterrupt):
        run(tmp_path, only=[fake], spp=32, force=True)
    monkeypatch.setattr(Path, "rename", rename)
    assert json.loads((tmp_path / fake / "figure.json").read_text())["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []

    dead = 2 ** 31 - 1                                              # above any pid_max: no such process
    (tmp_path / fake).rename(tmp_path / f".{fake}.old-{dead}")     # as a worker killed there leaves it
    (tmp_path / f".{fake}.partial-abc").mkdir()
    _remove_partial(tmp_path, fake)
    assert json.loads((tmp_path / fake / "figure.json").read_text())["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []
    (tmp_path / f".{fake}.old-{dead}").mkdir()                      # moved aside after the new one took its place
    _remove_partial(tmp_path, fake)
    assert json.loads((tmp_path / fake / "figure.json").read_text())["spp"] == 16
    assert [p.name for p in tmp_path.iterdir() if p.name.startswith(".")] == []


def test_a_figure_a_killed_run_moved_aside_is_found_by_the_next_run_and_a_live_runs_is_left_to_it(tmp_path, fake):
    """The next run puts a killed run's ``.NAME.old-PID`` back before its cache check (the figure is
    cached, not remade, and in index.html); a ``.old-`` folder of a process that still runs is that
    process's (between its two renames now) and is neither put back nor removed."""
    from plausible.figures.report import _remove_partial

    run(tmp_path, only=[fake], spp=16)
    made = json.loads((tmp_path / fake / "figure.json").read_text())
    (tmp_path / fake).rename(tmp_path / f".{fake}.old-{2 ** 31 - 1}")
    res = run(tmp_path, only=[fake], spp=16)
    assert res[fake]["cached"] and res[fake]["seconds"] == made["seconds"]
    assert f'{fake}/' in (tmp_path / "index.html").read_text()
    live = tmp_path / f".{fake}.old-{os.getppid()}"
    (tmp_path / fake).rename(live)
    _remove_partial(tmp_path, fake)
    assert live.exists() and not (tmp_path / fake).exists()


def test_a_follower_is_made_by_the_worker_that_made_its_leader(monkeypatch):
    """figures.report._next: a figure whose albedo curves another one computes first
    (FOLLOWS) waits for it and goes to the worker that made it, which remembers them."""
    from plausible.figures import report

    monkeypatch.setattr(report, "FOLLOWS", {"b": "a"})
    todo = [("b", 1), ("a", 2), ("c", 3)]           # longest first: b before its leader
    assert report._next(todo, busy=set()) == 1      # a fresh worker takes the leader, not b
    todo.pop(1)
    assert report._next(todo, busy={"a"}) == 1      # another worker: c, while a is being made
    assert report._next(todo, busy=set(), done="a") == 0    # the worker that made a: b
    assert report._next([("b", 1)], busy={"a"}) == 0        # nothing else left: b anyway
    assert report._next([], busy=set()) is None
    monkeypatch.setattr(report, "FOLLOWS", {})
    assert report._next([("b", 1), ("a", 2)], busy=set()) == 0   # no leaders: the order as given


def _blas_env(ctx):
    ctx.steps(1)
    ctx.json("env", {"OPENBLAS_NUM_THREADS": os.environ.get("OPENBLAS_NUM_THREADS")})
    ctx.tick()


def test_workers_get_one_blas_thread_unless_the_caller_set_it(tmp_path, monkeypatch):
    """The worker processes share the cores: each gets OPENBLAS_NUM_THREADS = 1 (report.WORKER_ENV),
    a value the caller set wins, and the parent's environment is left as it was."""
    monkeypatch.setitem(F.FIGURES, "blas", F.Figure("blas", "Blas", "test", "caption", _blas_env, {}))
    monkeypatch.setitem(F.FIGURES, "blas2", F.Figure("blas2", "Blas", "test", "caption", _blas_env, {}))
    monkeypatch.delenv("OPENBLAS_NUM_THREADS", raising=False)
    seen = lambda d, n: json.loads((d / n / "env.json").read_text())["OPENBLAS_NUM_THREADS"]   # noqa: E731
    run(tmp_path / "a", only=["blas", "blas2"], jobs=2)
    assert seen(tmp_path / "a", "blas") == seen(tmp_path / "a", "blas2") == "1"
    assert "OPENBLAS_NUM_THREADS" not in os.environ
    monkeypatch.setenv("OPENBLAS_NUM_THREADS", "2")
    run(tmp_path / "b", only=["blas", "blas2"], jobs=2)
    assert seen(tmp_path / "b", "blas") == "2" and os.environ["OPENBLAS_NUM_THREADS"] == "2"


def _threads(ctx):
    import drjit

    ctx.steps(1)
    ctx.json("threads", {"drjit": drjit.thread_count()})
    ctx.tick()


def test_workers_share_the_cores_among_their_drjit_threads(tmp_path, monkeypatch):
    """Each worker process gets the cores divided by the workers (at least one) as Dr.Jit threads:
    a thread per core in each would oversubscribe them, and idle Dr.Jit threads spin."""
    import importlib

    pytest.importorskip("drjit")
    report = importlib.import_module("plausible.figures.report")
    for n in ("t1", "t2"):
        monkeypatch.setitem(F.FIGURES, n, F.Figure(n, "Threads", "test", "caption", _threads, {}))
    run(tmp_path, only=["t1", "t2"], jobs=2)
    got = [json.loads((tmp_path / n / "threads.json").read_text())["drjit"] for n in ("t1", "t2")]
    assert got == [report.worker_threads(2)] * 2
    monkeypatch.setattr(report, "usable_cores", lambda: 16)
    assert (report.worker_threads(2), report.worker_threads(1), report.worker_threads(32)) == (8, 16, 1)
    monkeypatch.setattr(report, "usable_cores", lambda: 2)
    assert report.worker_threads(2) == 1


def test_an_exr_is_written_with_one_drjit_thread(tmp_path):
    """Mitsuba 3.9's OpenEXR writer waits forever with one Dr.Jit thread; write_image lends it two
    and gives the pool back its size (run in a child process, so a hang fails by its timeout)."""
    import subprocess
    import sys
    from pathlib import Path

    import plausible

    pytest.importorskip("mitsuba")
    code = ("import drjit as dr, numpy as np\n"
            "from plausible.figures import scenes as S\n"
            "S.mitsuba(); dr.set_thread_count(1)\n"
            f"S.write_image({str(tmp_path / 'img')!r}, np.full((4, 5, 3), 0.5))\n"
            "print(dr.thread_count())\n")
    env = dict(os.environ, PYTHONPATH=str(Path(plausible.__file__).resolve().parents[1]))   # this tree's plausible
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120, env=env)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split()[-1] == "1"
    assert (tmp_path / "img.exr").exists() and (tmp_path / "img.png").exists()


def _busy(ctx, seconds, spin):
    """Spend ``seconds``: of CPU time computing (``spin``; a loaded machine stretches its wall
    time, not its CPU time), or of wall time asleep."""
    clock = time.process_time if spin else time.perf_counter
    end = clock() + seconds
    while clock() < end:
        if not spin:
            time.sleep(0.01)


def test_each_figure_records_its_cpu_seconds_apart_from_its_wall_time(tmp_path, monkeypatch):
    """``cpu_seconds`` is the process's CPU time (getrusage), not the wall clock: a figure that
    sleeps 0.4 s records ~0 of it, one that computes 0.4 s records ~0.4 (a machine's load makes
    the wall time longer, not the CPU time)."""
    F.names()
    for name, spin in (("sleeper", False), ("spinner", True)):
        monkeypatch.setitem(F.FIGURES, name, F.Figure(name, name, "test", "caption", _busy,
                                                      dict(seconds=0.4, spin=spin)))
    res = run(tmp_path, only=["sleeper", "spinner"], jobs=1)
    assert res["sleeper"]["seconds"] >= 0.4 and res["sleeper"]["cpu_seconds"] <= 0.15
    assert res["spinner"]["cpu_seconds"] >= 0.3
    assert json.loads((tmp_path / "spinner" / "figure.json").read_text())["cpu_seconds"] == res["spinner"]["cpu_seconds"]
