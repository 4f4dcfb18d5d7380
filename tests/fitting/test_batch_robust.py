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
