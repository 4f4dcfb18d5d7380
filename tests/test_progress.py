"""The progress protocol (plausible.progress) and the command line's bar.

The counts are checked against what the work did (the nodes of a table, the
angles of a curve); the bar is checked in a pseudo-terminal, where a Rich bar
hides the cursor (ESC [?25l) and must show it again (ESC [?25h) on every exit.
"""

from __future__ import annotations

import io
import os
import pty
import select
import signal
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner
from rich.console import Console

import plausible
import plausible.integrals.cache
import plausible.models.pumped_up as pu
from plausible import cli, make, registry
from plausible.analysis import albedo_curve, albedo_table, check
from plausible.progress import Counter, reporting, start, within

HIDE, SHOW = b"\x1b[?25l", b"\x1b[?25h"
SRC = str(Path(plausible.__file__).resolve().parent.parent)


def _complete(counts):
    return all(total == ticks for total, ticks in counts.values())


class TestProtocol:
    def test_albedo_curve_ticks_once_per_angle(self):
        c = Counter()
        albedo_curve(make("lambertian"), np.linspace(0, 1.5, 5), progress=c)
        assert c.counts == {"albedo lambertian": [5, 5]}

    def test_albedo_table_announces_every_node_it_evaluates(self):
        c = Counter()
        table = albedo_table(make("lambertian"), n_theta=7, max_theta=13, progress=c)
        assert _complete(c.counts)
        assert sum(total for total, _ in c.counts.values()) == len(table.values)   # each node once

    def test_a_large_albedo_table_ticks_as_it_goes(self):
        """144 albedos (9 polar angles x 16 azimuths) tick in batches of 64, not once at the end."""
        ticks = []

        def factory(total, label=""):
            return lambda n=1: ticks.append(n)

        albedo_table(make("ward", alpha_x=0.1, alpha_y=0.3), n_phi=16, n_theta=9, max_theta=9, progress=factory)
        assert ticks == [64, 64, 16]

    def test_check_counts_every_step_in_one_total(self):
        c = Counter()
        check(make("lambertian"), quick=True, progress=c)
        assert list(c.counts) == ["check lambertian"] and _complete(c.counts)

    def test_within_sends_the_ticks_to_the_callers_count(self):
        c = Counter()
        tick = c(10, "outer")
        albedo_curve(make("lambertian"), [0.0, 0.5, 1.0], progress=within(tick))
        assert c.counts == {"outer": [10, 3]}

    def test_pumped_up_reports_the_tables_it_builds(self, tmp_path, monkeypatch):
        monkeypatch.setenv("PLAUSIBLE_CACHE_DIR", str(tmp_path))
        monkeypatch.setattr(plausible.integrals.cache, "_TABLES", {})
        c = Counter()
        with reporting(c):      # as the command line does: reaches a model built from a spec
            registry.make_from_spec("pumped-up:base=[lambertian:rd=0.7]")
        assert c.counts and _complete(c.counts)
        c2 = Counter()
        pu.PumpedUp(base="lambertian:rd=0.7", progress=c2)   # cached now: nothing to report
        assert c2.counts == {}

    def test_pumped_up_given_a_counter_completes_every_task_it_announces(self, tmp_path, monkeypatch):
        """Its horizon probe took the factory for a tick: it announced a task of 1 step that never ticked."""
        monkeypatch.setenv("PLAUSIBLE_CACHE_DIR", str(tmp_path))
        monkeypatch.setattr(plausible.integrals.cache, "_TABLES", {})
        c = Counter()
        pu.PumpedUp(base="lambertian:rd=0.6", progress=c)
        assert c.counts and _complete(c.counts), c.counts

    def test_the_ambient_reporter_ends_with_its_block(self):
        c = Counter()
        with reporting(c):
            start(None, 2, "in")()
        start(None, 2, "out")()
        assert c.counts == {"in": [2, 1]}


class TestBar:
    def test_stops_and_shows_the_cursor_when_the_work_raises(self, monkeypatch):
        buf = io.StringIO()
        monkeypatch.setattr(cli, "console", Console(file=buf, force_terminal=True))
        with pytest.raises(RuntimeError), cli._Bar() as bar:
            tick = bar(5, "work")
            tick()
            raise RuntimeError("boom")
        out = buf.getvalue().encode()
        assert out.count(HIDE) == 1 and out.rfind(SHOW) > out.rfind(HIDE)
        assert bar.prog is None

    def test_prints_nothing_on_a_pipe(self):
        r = CliRunner().invoke(cli.main, ["albedo", "lambertian", "-n", "3"])
        assert r.exit_code == 0 and "\x1b[" not in r.output and "0.800000" in r.output


def _run_in_pty(args, interrupt=False, timeout=60.0):
    """Run the CLI in a pseudo-terminal; with ``interrupt``, send SIGINT once the
    bar is up.  Returns everything the command wrote and its wait status."""
    pid, fd = pty.fork()
    if pid == 0:   # pragma: no cover (the child)
        os.environ["PYTHONPATH"] = SRC
        os.environ["COLUMNS"] = "100"
        os.execv(sys.executable, [sys.executable, "-m", "plausible.cli", *args])
    out, sent, t0 = b"", False, time.monotonic()
    while time.monotonic() - t0 < timeout:
        if interrupt and HIDE in out and time.monotonic() - (sent or 0) > 1.0:
            # Ctrl-C once the bar is up, again each second (as a user would): a
            # SIGINT that lands while LLVM compiles a Dr.Jit kernel can be lost
            # (seen on the first run of a new process, an upstream behaviour)
            time.sleep(0.3)
            os.kill(pid, signal.SIGINT)
            sent = time.monotonic()
        if select.select([fd], [], [], 0.1)[0]:
            try:
                chunk = os.read(fd, 65536)
            except OSError:      # the child closed the terminal
                break
            if not chunk:
                break
            out += chunk
    else:   # pragma: no cover
        os.kill(pid, signal.SIGKILL)
    _, status = os.waitpid(pid, 0)
    os.close(fd)
    return out, status


@pytest.mark.skipif(sys.platform == "win32", reason="needs a POSIX pseudo-terminal")
class TestTerminal:
    def test_a_time_limited_fit_restores_the_cursor(self):
        out, status = _run_in_pty(["fit", "modified-phong", "--target", "modified-phong:n=50",
                                   "--time-limit", "0.2", "--starts", "5"])
        assert os.WEXITSTATUS(status) == 0 and b"time limit reached" in out
        assert HIDE in out and out.rfind(SHOW) > out.rfind(HIDE)

    def test_an_interrupted_check_restores_the_cursor(self):
        # long enough that Ctrl-C lands inside it (one model's check can end within the 0.3 s
        # _run_in_pty waits once the bar is up); ended by the signal (Python re-raises an
        # unhandled SIGINT at exit) or with a non-zero status, either way the cursor is back
        out, status = _run_in_pty(["check", "--all", "--jobs", "1"], interrupt=True)
        assert os.WIFSIGNALED(status) or os.WEXITSTATUS(status) != 0
        assert HIDE in out and out.rfind(SHOW) > out.rfind(HIDE)
