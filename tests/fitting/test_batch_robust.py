"""Batch fitting on hostile folders (issue 27): malformed rows are skipped and
reported with file:line while the good rows stay; two runs on one folder share
the work without storing a fit twice; a folder that cannot be written says what
is kept and how to resume; a folder named like the target model is no target."""

import errno
import os
import threading

import pytest
from click.testing import CliRunner

from plausible.cli import main
from plausible.fitting import batch, load_table

TARGETS = [f"lambertian:rd={r}" for r in (0.2, 0.4, 0.6)]


def _three_rows(out):
    s = batch.fit_batch(TARGETS, ["lambertian"], ["l2-cos"], out, workers=0, starts=1)
    assert s.done == 3
    return batch.table_path(out, "lambertian")


def test_malformed_rows_are_skipped_and_named_and_the_good_rows_kept(tmp_path):
    path = _three_rows(tmp_path)
    lines = path.read_text().splitlines(keepends=True)
    good = lines[1]
    bad = ["garbage that is no row\n", good.rstrip("\n") + ",extra\n", good.split(",", 1)[1],
           'lambertian:rd=0.9,lambertian,l2-cos,ok,"0.5\n']
    path.write_text(lines[0] + lines[1] + "".join(bad) + "".join(lines[2:]))
    problems = []
    rows = batch.load_results(tmp_path, problems)
    assert sorted(r["target"] for r in rows) == TARGETS
    assert [p.split(": ")[0] for p in problems] == [f"{path}:{k}" for k in (3, 4, 5, 6)]
    s = batch.fit_batch(TARGETS, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    assert s.done == 0 and s.skipped == 3 and len(s.bad_rows) == 4


def test_a_cut_header_is_reported_and_the_rows_still_read(tmp_path):
    path = _three_rows(tmp_path)
    text = path.read_text()
    path.write_text("target,model,met\n" + text.split("\n", 1)[1])
    problems = []
    assert len(batch.load_results(tmp_path, problems)) == 3
    assert problems == [f"{path}:1: header is not the columns of 'lambertian'; rows read by those columns"]


def test_two_runs_on_one_folder_share_the_work_and_store_each_fit_once(tmp_path):
    targets = [f"lambertian:rd={r / 20}" for r in range(1, 13)]
    summaries = []

    def run():
        summaries.append(batch.fit_batch(targets, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1))

    threads = [threading.Thread(target=run) for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    keys = [r["target"] for r in batch.load_results(tmp_path)]
    assert sorted(keys) == sorted(targets)                     # every fit once (was: twice)
    assert sum(s.done for s in summaries) == len(targets)
    assert not list((tmp_path / "fits" / ".claims").iterdir())  # no claim left behind


def test_a_claim_of_a_dead_run_is_taken_over(tmp_path):
    task = batch.FitTask("lambertian:rd=0.5", "lambertian", "l2-cos")
    p = batch._claim_path(tmp_path, task)
    p.parent.mkdir(parents=True)
    import json
    import socket

    p.write_text(json.dumps(dict(host=socket.gethostname(), pid=2 ** 22 + 12345)))   # no such process
    assert batch.claim(tmp_path, task)
    assert not batch.claim(tmp_path, task)                      # now held by this (live) process


def test_a_full_disk_says_what_is_kept_and_how_to_resume(tmp_path, monkeypatch):
    real = batch.append_row
    calls = []

    def full(path, header, row):
        calls.append(row["target"])
        if len(calls) > 1:
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        real(path, header, row)

    monkeypatch.setattr(batch, "append_row", full)
    with pytest.raises(batch.BatchWriteError, match="No space left on device.*1 fits of this run are stored.*"
                                                    "run the same command again to resume"):
        batch.fit_batch(TARGETS, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    monkeypatch.setattr(batch, "append_row", real)
    s = batch.fit_batch(TARGETS, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    assert s.skipped == 1 and s.done == 2


def test_cli_fit_batch_into_an_unwritable_folder_is_a_clear_error(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = CliRunner().invoke(main, ["fit-batch", "lambertian:rd=0.5", "--models", "lambertian", "--out",
                                  str(blocker / "res"), "--workers", "0"])
    assert r.exit_code != 0 and "cannot write into the results folder" in r.output
    assert "Traceback" not in r.output


def test_cli_fit_out_folder_named_like_the_target_model(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["fit", "lambertian", "--target", "ward", "--out", "ward", "--starts", "1",
                                  "--metric", "l2-cos"])
    assert r.exit_code == 0, r.output
    assert (tmp_path / "ward" / "fit.json").exists()
    (tmp_path / "notamodel").mkdir()
    r = CliRunner().invoke(main, ["fit", "lambertian", "--target", "notamodel", "--starts", "1"])
    assert r.exit_code != 0 and "is a folder" in r.output and "Traceback" not in r.output


def test_a_byte_order_mark_does_not_drop_the_first_row(tmp_path):
    p = tmp_path / "t.csv"
    p.write_bytes("\ufeff0,0,1,0,0,1,0.5\n0,0,1,0.6,0,0.8,0.25\n".encode())
    wi, wo, f = load_table(p)
    assert list(f) == [0.5, 0.25]


def test_a_huge_brdf_value_is_named_with_its_line(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("0,0,1,0,0,1,0.5\n0,0,1,0.6,0,0.8,1e300\n")
    with pytest.raises(ValueError, match=r"t.csv:2: column f .* must lie in \[0, 1e\+150\].*got 1e\+300"):
        load_table(p)


# -- issue 45 items 3-5: claims that never block, a full disk, a scheduler that is not there ----

def test_an_empty_claim_left_by_a_full_disk_does_not_block_the_fit(tmp_path):
    task = batch.FitTask("lambertian:rd=0.5", "lambertian", "l2-cos")
    p = batch._claim_path(tmp_path, task)
    p.parent.mkdir(parents=True)
    p.write_text("")                                  # (was: "1 fits left to another run", exit 0, nothing run)
    r = CliRunner().invoke(main, ["fit-batch", task.target, "--models", "lambertian", "--metrics", "l2-cos",
                                  "--out", str(tmp_path), "--workers", "0", "--starts", "1"])
    assert r.exit_code == 0, r.output
    assert "1 fits done (0 failed)" in r.output and "took over a stale claim" in r.output
    assert [x["params"]["rd"] for x in batch.load_results(tmp_path)] == [pytest.approx(0.5, rel=1e-6)]
    assert not p.exists()


def test_a_claim_naming_a_live_unrelated_pid_does_not_block_the_fit(tmp_path):
    import json
    import socket

    task = batch.FitTask("lambertian:rd=0.5", "lambertian", "l2-cos")
    p = batch._claim_path(tmp_path, task)
    p.parent.mkdir(parents=True)
    p.write_text(json.dumps(dict(host=socket.gethostname(), pid=1)))   # init: alive, and no run of this batch
    s = batch.fit_batch([task.target], ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    assert (s.done, s.shared) == (1, 0) and "process 1 is not the one that claimed it" in s.taken_over[0]


def test_fit_batch_on_a_full_disk_is_exit_2_naming_the_cause_and_resumes_once_freed(full_disk):
    out = full_disk.path / "res"
    args = ["fit-batch", "lambertian:rd=0.5", "--models", "lambertian", "--metrics", "l2-cos", "--out", str(out),
            "--workers", "0", "--starts", "1"]
    (out / "fits").mkdir(parents=True)
    full_disk.fill()
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 2 and "No space left on device" in r.output, r.output     # (was: a bare OSError)
    assert r.exception is None or isinstance(r.exception, SystemExit)
    assert list((out / "fits" / ".claims").iterdir()) == []                         # no empty claim left
    full_disk.free()
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0 and "1 fits done" in r.output, r.output


def test_fit_batch_names_a_scheduler_it_cannot_reach(tmp_path, monkeypatch):
    from plausible import engine

    monkeypatch.setattr(engine, "CONNECT_TIMEOUT", 2.0)
    r = CliRunner().invoke(main, ["fit-batch", "lambertian:rd=0.5", "--models", "lambertian", "--out",
                                  str(tmp_path), "--scheduler", "tcp://127.0.0.1:1"])
    assert r.exit_code == 2, r.output
    assert "--scheduler: cannot reach the Dask scheduler at 'tcp://127.0.0.1:1' within 2 s" in r.output
    assert not list((tmp_path / "fits" / ".claims").glob("*")) if (tmp_path / "fits" / ".claims").exists() else True


def test_fit_batch_refuses_out_dash(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["fit-batch", "lambertian:rd=0.5", "--models", "lambertian", "--out", "-"])
    assert r.exit_code == 2 and "--out -: fit-batch writes a results folder" in r.output
    assert not (tmp_path / "-").exists()


def test_repair_keeps_a_whole_last_row_lacking_only_its_newline(tmp_path):
    path = _three_rows(tmp_path)
    text = path.read_text()
    path.write_text(text[:-1])                         # the newline of the last row lost (was: row deleted, refitted)
    assert len(batch.load_results(tmp_path)) == 3
    assert batch.repair(path) == 0 and path.read_text() == text
    path.write_text(text[:-3])                         # cut inside the last field (the Python version): removed
    assert batch.repair(path) == len(text.splitlines()[-1]) - 2 and path.read_text().count("\n") == 3
    s = batch.fit_batch(TARGETS, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    assert (s.skipped, s.done) == (2, 1)


def test_a_duplicated_row_is_reported_and_dropped(tmp_path):
    path = _three_rows(tmp_path)
    lines = path.read_text().splitlines(keepends=True)
    path.write_text("".join(lines) + lines[2])        # the second fit's row twice
    problems = []
    rows = batch.load_results(tmp_path, problems)
    assert sorted(r["target"] for r in rows) == TARGETS
    assert problems == [f"{path}:5: a second row of {TARGETS[1]} / l2-cos (the first at line 3); dropped"]


def test_a_retry_replaces_the_failed_row(tmp_path):
    args = (["/no/such/file.csv"], ["lambertian"], ["l2-cos"], tmp_path)
    batch.fit_batch(*args, workers=0)
    batch.fit_batch(*args, workers=0, retry_failed=True)
    problems = []
    assert len(batch.load_results(tmp_path, problems)) == 1 and problems == []


def test_fit_batch_on_a_dask_scheduler_gives_the_rows_of_one_process(tmp_path):
    distributed = pytest.importorskip("distributed")
    targets = ["lambertian:rd=0.6", "modified-phong:kd=0.3:ks=0.4:n=30"]
    ref = batch.fit_batch(targets, ["lambertian"], ["l2-cos"], tmp_path / "one", workers=0, starts=1, seed=2)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as c:
        s = batch.fit_batch(targets, ["lambertian"], ["l2-cos"], tmp_path / "dask", scheduler=c.scheduler_address,
                            starts=1, seed=2)
    assert (ref.done, s.done, s.workers) == (2, 2, 2)
    got = {r["target"]: r["params"]["rd"] for r in batch.load_results(tmp_path / "dask")}
    assert got == {r["target"]: r["params"]["rd"] for r in batch.load_results(tmp_path / "one")}


# -- an outside audit of bad input: a failed fit, a sphere that is no target, a report that cannot be written --

def test_a_batch_with_a_failed_fit_writes_its_row_and_exits_1(tmp_path):
    r = CliRunner().invoke(main, ["fit-batch", "nope-not-a-target", "lambertian:rd=0.5", "--models", "lambertian",
                                  "--metrics", "l2-cos", "--out", str(tmp_path), "--workers", "0", "--starts", "1"])
    assert r.exit_code == 1, r.output                         # was 0 with the failure in the log only
    rows = {x["target"]: x["status"] for x in batch.load_results(tmp_path)}
    assert rows["lambertian:rd=0.5"] == "ok" and rows["nope-not-a-target"] != "ok"


def test_spheres_that_are_no_target_and_an_unwritable_report_are_refused_before_any_fit(tmp_path):
    args = ["fit-batch", "lambertian:rd=0.5", "--models", "lambertian", "--metrics", "l2-cos", "--out",
            str(tmp_path / "res"), "--workers", "0", "--starts", "1"]
    r = CliRunner().invoke(main, args + ["--report", str(tmp_path / "rep"), "--spheres", "nope"])
    assert r.exit_code == 2 and "--spheres: 'nope' is not one of the TARGETS" in r.output, r.output
    (tmp_path / "file").write_text("x")
    r = CliRunner().invoke(main, args + ["--report", str(tmp_path / "file" / "rep")])
    assert r.exit_code == 2 and "cannot use" in r.output, r.output
    assert not (tmp_path / "res").exists() or not batch.load_results(tmp_path / "res")     # no fit ran
