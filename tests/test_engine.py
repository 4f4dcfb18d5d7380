"""The batch engine (`plausible.engine`): a claim names a live owner that is really the
run's (host, PID, start time, boot), and an empty, dead, reused-PID or ended claim is
taken over while a live owner's is left to it; rows are appended whole; a scheduler that
cannot be reached is a clear error; tasks run in spawned processes whose dead workers
are replaced."""

import errno
import json
import os
import socket
import subprocess
import sys

import pytest

from plausible import engine


def _write_claim(claims, key, **who):
    p = claims.path(key)
    p.parent.mkdir(parents=True, exist_ok=True)
    p.write_text(json.dumps(who) if who else "")
    return p


def test_an_empty_claim_is_taken_over(tmp_path):
    claims = engine.Claims(tmp_path, "t")
    p = _write_claim(claims, "a")                              # what a full disk left (was: blocks forever)
    assert p.read_text() == "" and claims.take("a")
    who = json.loads(p.read_text())
    assert (who["pid"], who["host"], who["start"]) == (os.getpid(), socket.gethostname(),
                                                       engine._start_time(os.getpid()))
    assert claims.taken_over == ["a: empty or unreadable"]
    assert not engine.Claims(tmp_path, "t").take("a")          # now held by this live run
    claims.release("a")
    assert not p.exists()


def test_a_claim_naming_a_live_process_of_another_start_is_taken_over(tmp_path):
    claims = engine.Claims(tmp_path, "t")
    parent = os.getppid()                                       # alive, and no run of this batch
    _write_claim(claims, "a", host=socket.gethostname(), pid=parent, start=engine._start_time(parent) + 1,
                 boot=engine._boot_id())
    assert claims.take("a") and "not the one that claimed it" in claims.taken_over[0]
    claims.release("a")
    _write_claim(claims, "b", host=socket.gethostname(), pid=parent)   # no start time: not this batch's
    assert claims.take("b")
    claims.release("b")


def test_a_claim_of_a_live_owner_is_left_to_it_until_it_ends(tmp_path):
    claims = engine.Claims(tmp_path, "t")
    owner = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        _write_claim(claims, "a", host=socket.gethostname(), pid=owner.pid, start=engine._start_time(owner.pid),
                     boot=engine._boot_id(), time=0)
        assert not claims.take("a") and claims.left_to["a"].startswith(f"PID {owner.pid} on {socket.gethostname()}")
    finally:
        owner.kill()
        owner.wait()
    assert claims.take("a") and f"process {owner.pid} is gone" in claims.taken_over[0]
    claims.release("a")


def test_claims_of_another_host_or_boot(tmp_path):
    claims = engine.Claims(tmp_path, "t")
    _write_claim(claims, "a", host="elsewhere.example", pid=os.getpid(), start=1)
    assert not claims.take("a") and "elsewhere.example" in claims.left_to["a"]   # not judged from here
    if engine._boot_id():
        _write_claim(claims, "b", host=socket.gethostname(), pid=os.getpid(), start=engine._start_time(os.getpid()),
                     boot="another-boot")
        assert claims.take("b") and "restarted" in claims.taken_over[-1]
        claims.release("b")


def test_a_claim_of_this_process_whose_run_ended_is_taken_over(tmp_path):
    claims = engine.Claims(tmp_path, "t")
    _write_claim(claims, "a", **engine.me())          # this process, but no run of it holds the claim
    assert claims.take("a") and claims.taken_over == ["a: left by an ended run of this process"]
    claims.release("a")


def test_a_claim_on_a_full_disk_is_a_clear_error_and_leaves_no_claim(full_disk):
    claims = engine.Claims(full_disk.path / "claims", "t")
    claims.folder.mkdir()
    full_disk.fill()
    with pytest.raises(engine.BatchWriteError, match="cannot write a claim in .*No space left on device.*resume"):
        claims.take("a")
    assert list(claims.folder.iterdir()) == []
    full_disk.free()
    assert claims.take("a")
    claims.release("a")


def test_append_line_puts_a_cut_line_on_its_own_and_writes_the_header_once(tmp_path):
    p = tmp_path / "t.csv"
    engine.append_line(p, "1,2", header="a,b")
    with open(p, "a") as fh:
        fh.write("3,")                                  # a crash mid-write
    engine.append_line(p, "5,6", header="a,b")
    assert p.read_text() == "a,b\n1,2\n3,\n5,6\n"


def test_append_line_on_a_full_disk_leaves_the_file_as_it_was(full_disk):
    p = full_disk.path / "t.csv"
    engine.append_line(p, "1,2", header="a,b")
    full_disk.fill()
    with pytest.raises(OSError) as e:
        engine.append_line(p, "x" * 100_000)
    assert e.value.errno == errno.ENOSPC and p.read_text() == "a,b\n1,2\n"


def test_an_unreachable_scheduler_is_named_quickly():
    with pytest.raises(engine.SchedulerError, match=r"scheduler: cannot reach the Dask scheduler at "
                                                    r"'tcp://127.0.0.1:1' within 2 s"):
        engine.connect("tcp://127.0.0.1:1", timeout=2)


def _square(x):
    return x * x


def _boom(x):
    raise ValueError(f"no {x}")


def test_tasks_in_processes_give_what_this_process_gives_and_a_raising_task_is_failed():
    got = {}
    s = engine.run(range(7), _square, lambda t, r: got.__setitem__(t, r), workers=2)
    assert got == {x: x * x for x in range(7)} and (s.done, s.workers) == (7, 2)
    bad = {}
    engine.run([1, 2], _boom, lambda t, r: bad.__setitem__(t, r), workers=2, failed=lambda t, e: str(e))
    assert bad == {1: "no 1", 2: "no 2"}
    with pytest.raises(ValueError, match="no 3"):        # no failed(): the error is raised
        engine.run([3], _boom, lambda t, r: None)


def test_without_a_worker_process_the_tasks_run_here(monkeypatch):
    monkeypatch.setattr(engine, "_start_worker", lambda ctx, work: None)     # at the limit of processes
    got = {}
    s = engine.run(range(4), _square, lambda t, r: got.__setitem__(t, r), workers=2)
    assert got == {x: x * x for x in range(4)} and (s.done, s.workers) == (4, 0)


def test_an_interrupt_keeps_what_was_recorded_and_releases_every_claim(tmp_path):
    claims, got = engine.Claims(tmp_path / "c", "t"), []

    def work(x):
        if x == 2:
            raise KeyboardInterrupt
        return x

    with pytest.raises(KeyboardInterrupt):
        engine.run(range(5), work, lambda t, r: got.append(r), key=str, claims=claims)
    assert got == [0, 1] and list(claims.folder.iterdir()) == []
    s = engine.run([t for t in range(5) if t not in got], _square, lambda t, r: got.append(r), key=str, claims=claims)
    assert got == [0, 1, 4, 9, 16] and s.done == 3
