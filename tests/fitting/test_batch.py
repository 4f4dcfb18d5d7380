"""Batch fitting (`plausible.fitting.batch`, `plausible fit-batch`): 2 local worker processes
of the batch engine give the same rows as the sequential `fit`; a killed batch resumes
without losing or repeating a fit; a corrupt target is a failed row; a row cut
short by a crash is repaired; the report names the model with the smallest error."""

import csv
import math
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.cli import main
from plausible.fitting import batch, sample_pairs, save_table
from plausible.fitting.batch_report import LIGHT, best_models, render_sphere, write_report

MODELS = ["lambertian", "modified-phong"]
METRICS = ["l2-cos", "log"]


def _targets(tmp_path):
    m = plausible.make("modified-phong", kd=0.2, ks=0.5, n=15.0)
    wi, wo = sample_pairs(m.peak_directions, thetas_deg=(0.0, 30.0, 60.0))
    table = save_table(tmp_path / "mp.csv", wi, wo, m.eval(wi, wo))
    corrupt = tmp_path / "corrupt.csv"
    corrupt.write_text("wi_x,wi_y\n0.1,0.2\n0.3,0.4\n")   # two columns: not a BRDF table
    return ["lambertian:rd=0.6", "modified-phong:kd=0.3:ks=0.4:n=30", str(table), str(corrupt)]


def test_local_cluster_equals_sequential_fit(tmp_path):
    targets = _targets(tmp_path)
    s = batch.fit_batch(targets, MODELS, METRICS, tmp_path / "res", workers=2, starts=1, seed=3)
    assert (s.planned, s.done, s.skipped, s.workers) == (16, 16, 0, 2)
    rows = batch.load_results(tmp_path / "res")
    assert len(rows) == 16 and len({(r["target"], r["model"], r["metric"]) for r in rows}) == 16
    failed = [r for r in rows if r["status"] == "failed"]
    assert {r["target"] for r in failed} == {targets[3]} and s.failed == 4
    assert all("corrupt.csv" in r["error"] for r in failed)
    for r in rows:
        if r["status"] != "ok":
            continue
        ref = plausible.fit(r["model"], r["target"], r["metric"], starts=1, seed=3)
        for k, v in ref.params.items():       # same seed, same start points: the same optimum
            assert r["params"][k] == pytest.approx(float(v), rel=1e-9, abs=1e-12), (r["target"], k)
        assert r["errors"][r["metric"]] == pytest.approx(ref.errors[r["metric"]], rel=1e-6, abs=1e-12)


def test_rerun_skips_what_is_done(tmp_path):
    targets = ["lambertian:rd=0.6", "lambertian:rd=0.2"]
    first = batch.fit_batch(targets[:1], ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    second = batch.fit_batch(targets, ["lambertian"], ["l2-cos"], tmp_path, workers=0, starts=1)
    assert (first.done, second.skipped, second.done) == (1, 1, 1)
    rows = batch.load_results(tmp_path)
    assert sorted(r["params"]["rd"] for r in rows) == pytest.approx([0.2, 0.6], rel=1e-6)


def test_failed_fits_rerun_only_when_asked(tmp_path):
    args = (["/no/such/file.csv"], ["lambertian"], ["l2-cos"], tmp_path)
    assert batch.fit_batch(*args, workers=0).failed == 1
    assert batch.fit_batch(*args, workers=0).done == 0
    assert batch.fit_batch(*args, workers=0, retry_failed=True).done == 1


TEN = [f"lambertian:rd={x}" for x in (0.1, 0.3, 0.5, 0.7, 0.9)]     # x 2 models: ten fits

#: The batch's process: `plausible fit-batch` whose fit number ``PLAUSIBLE_TEST_STOP_AT``
#: (counted from 1) touches the file ``PLAUSIBLE_TEST_MARK`` and then takes ten minutes,
#: so the test signals it mid-fit with exactly STOP_AT - 1 rows written, however loaded
#: the machine (polling the tables instead let the whole batch finish between two
#: polls).  Ctrl-C is the terminal's, whatever the test inherited: a background job of
#: a non-interactive shell, and so its children, ignore SIGINT.
_CHILD = """
import os, signal, time
from pathlib import Path
signal.signal(signal.SIGINT, signal.default_int_handler)
from plausible.fitting import batch
real, calls = batch.run_task, []
def run_task(task):
    calls.append(task)
    if len(calls) == int(os.environ["PLAUSIBLE_TEST_STOP_AT"]):
        Path(os.environ["PLAUSIBLE_TEST_MARK"]).touch()
        time.sleep(600)
    return real(task)
batch.run_task = run_task
from plausible.cli import main
main()
"""


def _batch_stopped_in_fit(out, stop_at, **popen):
    """Start `plausible fit-batch` on :data:`TEN` in a subprocess (:data:`_CHILD`); return
    it once it is inside fit number ``stop_at``, the ``stop_at - 1`` before in the tables."""
    mark = out.parent / f"{out.name}.fitting"
    cmd = [sys.executable, "-c", _CHILD, "fit-batch", *TEN, "--models", "lambertian,modified-phong",
           "--metrics", "l2-cos", "--out", str(out), "--workers", "0", "--starts", "1"]
    env = dict(os.environ, PLAUSIBLE_TEST_STOP_AT=str(stop_at), PLAUSIBLE_TEST_MARK=str(mark))
    proc = subprocess.Popen(cmd, env=env, **popen)
    deadline = time.monotonic() + 600       # a bound for a stuck child, not a timing assumption
    while not mark.exists():
        if proc.poll() is not None or time.monotonic() > deadline:
            proc.kill()
            output = proc.communicate()[0]
            pytest.fail(f"the batch ended (status {proc.returncode}) before fit {stop_at} started: {output}")
        time.sleep(0.05)
    return proc, [out / "fits" / "lambertian.csv", out / "fits" / "modified-phong.csv"]


def test_killed_batch_resumes_without_loss_or_repeat(tmp_path):
    targets, out = TEN, tmp_path / "res"
    proc, files = _batch_stopped_in_fit(out, 3, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                                        start_new_session=True)
    os.killpg(proc.pid, signal.SIGKILL)
    proc.wait()
    with open(files[0], "a") as fh:           # a crash in the middle of a write
        fh.write("lambertian:rd=0.9,lambertian,l2-cos,o")
    kept = batch.load_results(out)
    assert len(kept) == 2                     # the two fits finished before the kill; the third's cut row is gone
    s = batch.fit_batch(targets, ["lambertian", "modified-phong"], ["l2-cos"], out, workers=0, starts=1)
    rows = batch.load_results(out)
    keys = [(r["target"], r["model"], r["metric"]) for r in rows]
    assert len(keys) == len(set(keys)) == 10 and s.skipped == len(kept) and s.done == 10 - len(kept)
    assert all(r["status"] == "ok" for r in rows)
    for f in files:
        text = f.read_text()
        assert text.endswith("\n") and ",o\n" not in text
        assert all(len(r) == len(batch.columns(f.stem)) for r in csv.reader(text.splitlines()))


def test_repair_removes_only_a_cut_row(tmp_path):
    p = tmp_path / "t.csv"
    p.write_text("a,b\n1,2\n3,")
    assert batch.repair(p) == 2 and p.read_text() == "a,b\n1,2\n"
    assert batch.repair(p) == 0 and p.read_text() == "a,b\n1,2\n"


def test_plan_names_bad_models_and_metrics(tmp_path):
    with pytest.raises(ValueError, match="unknown model 'nope'"):
        batch.plan(["lambertian"], ["nope"], ["l2-cos"])
    with pytest.raises(ValueError, match="metric must be one of .* got 'l3'"):
        batch.plan(["lambertian"], ["lambertian"], ["l3"])
    with pytest.raises(ValueError, match="no targets"):
        batch.plan([], ["lambertian"], ["l2-cos"])


def test_scaling_is_waves_of_workers():
    assert batch.scaling(10.0, 2100, 64) == math.ceil(2100 / 64) * 10.0
    assert batch.scaling(10.0, 3, 4, overhead=2.0) == 12.0
    with pytest.raises(ValueError, match="workers must be >= 1, got 0"):
        batch.scaling(1.0, 1, 0)


def test_sphere_of_lambert_is_cosine_over_pi():
    img = render_sphere(plausible.make("lambertian", rd=1.0), 48)
    c = (np.arange(48) + 0.5) / 48 * 2 - 1
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    n = np.stack([x, y, np.sqrt(np.clip(1 - r2, 0, None))], -1)
    expected = np.where(r2 < 1, np.clip(n @ LIGHT, 0, None) / math.pi, 0.0)
    assert np.max(np.abs(img - expected)) < 1e-12
    # rgb: each channel its own reflectance times the same cosine / pi; a grey model in all three
    rd = np.array([0.8, 0.3, 0.1])
    rgb = render_sphere(plausible.make("lambertian", rd=list(rd)), 48, rgb=True)
    assert rgb.shape == (48, 48, 3) and np.max(np.abs(rgb - expected[..., None] * rd)) < 1e-12
    grey = render_sphere(plausible.make("lambertian", rd=1.0), 48, rgb=True)
    assert np.array_equal(grey, np.repeat(img[..., None], 3, axis=-1))


def test_report_names_the_best_model(tmp_path):
    rows = [dict(target="t", model=m, metric="l2-cos", status="ok", params={}, error=None,
                 errors={"l2-cos": e}) for m, e in (("a", 0.3), ("b", 0.1), ("c", 0.2))]
    rows.append(dict(target="t", model="d", metric="l2-cos", status="failed", params={}, error="boom",
                     errors={"l2-cos": None}))
    assert best_models(rows)[("t", "l2-cos")]["model"] == "b"
    html = write_report(rows, tmp_path).read_text()
    assert "<td>b (0.1)</td>" in html and "d / l2-cos failed: boom" in html
    assert (tmp_path / "t-errors.png").read_bytes()[:4] == b"\x89PNG"


def test_cli_fit_batch_writes_table_report_and_resumes(tmp_path):
    out, rep = tmp_path / "res", tmp_path / "rep"
    args = ["fit-batch", "lambertian:rd=0.4", "modified-phong:kd=0.3:ks=0.4:n=30", "--models", "lambertian",
            "--metrics", "l2-cos,log", "--out", str(out), "--workers", "0", "--starts", "1",
            "--report", str(rep)]
    r = CliRunner().invoke(main, args)
    assert r.exit_code == 0, r.output
    assert "4 fits done (0 failed)" in r.output
    assert (rep / "index.html").exists() and (rep / "lambertian_rd_0.4-spheres.png").exists()
    again = CliRunner().invoke(main, args)
    assert again.exit_code == 0 and "0 fits to run" in again.output and "4 already in" in again.output


def test_cli_fit_batch_names_a_bad_model(tmp_path):
    r = CliRunner().invoke(main, ["fit-batch", "lambertian", "--models", "lambertian,nope", "--out",
                                  str(tmp_path)])
    assert r.exit_code == 2 and "unknown model 'nope'" in r.output
    assert not (tmp_path / "fits").exists()


def test_ctrl_c_keeps_finished_fits_and_says_how_to_resume(tmp_path):
    out = tmp_path / "res"
    proc, _ = _batch_stopped_in_fit(out, 2, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    proc.send_signal(signal.SIGINT)
    output, _ = proc.communicate(timeout=60)
    assert proc.returncode == 130, output
    assert "interrupted" in output and "run the same command again to resume" in output
    rows = batch.load_results(out)
    assert len(rows) == 1 and rows[0]["status"] == "ok"      # the fit before the Ctrl-C; the one in flight is not
    assert list((out / "fits" / ".claims").iterdir()) == []  # nor is it left claimed
