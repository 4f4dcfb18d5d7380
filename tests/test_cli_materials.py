"""`plausible materials` and material specs on the command line."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.integrals.albedo import direction
from plausible.cli import main


def run(*args):
    return CliRunner().invoke(main, list(args), terminal_width=300)


def test_materials_lists_fit_sets_and_every_material_with_its_fits():
    r = run("materials")
    assert r.exit_code == 0
    for word in ("ngan2005/ward-duer", "low2012/cook-torrance-e2", "ngan2005/he", "alum-bronze", "yellow-plastic"):
        assert word in r.output
    only = run("materials", "--fit", "ngan2005/ward")
    assert "(86) of ngan2005/ward" in only.output


def test_an_unknown_fit_is_a_usage_error_with_suggestions():
    r = run("materials", "--fit", "ngan2005/wrd")
    assert r.exit_code == 2 and "did you mean ngan2005/ward" in r.output


def test_eval_accepts_a_material_spec():
    r = run("eval", "material:alum-bronze@ngan2005/ward", "--wi", "30,0", "--wo", "30,180")
    assert r.exit_code == 0
    want = plausible.material("alum-bronze", "ngan2005/ward").eval(direction(math.radians(30), 0),
                                                                    direction(math.radians(30), math.pi))
    assert [float(x) for x in r.output.split()] == pytest.approx(np.asarray(want).tolist(), rel=1e-9)


def test_eval_of_an_unknown_material_suggests_names():
    r = run("eval", "material:alum-bronz", "--wi", "30,0", "--wo", "30,180")
    assert r.exit_code == 2 and "did you mean alum-bronze" in r.output


# -- plausible check --materials ---------------------------------------------------------

def _table_row(material, fit):
    """The row of docs/materials-table.md for ``material`` in ``fit`` (largest albedo,
    angle, gains energy), written by an earlier full run."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "materials-table.md").read_text()
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 8 and cells[0] == material and cells[1] == fit:
            return float(cells[3]), float(cells[4].rstrip("°")), cells[7] != "no"
    raise KeyError((material, fit))


def test_the_published_table_covers_every_fit_of_every_set():
    """docs/materials-table.csv has one row per material of every fit set (1202: the He and
    Löw ABC sets included), and the He fits printed with eta = 1.0 (Fresnel exactly 0, scales
    up to 1.96e9) have the largest albedo of their Lambertian term alone, at every angle."""
    import csv
    from pathlib import Path

    from plausible import catalogue

    with open(Path(__file__).resolve().parents[1] / "docs" / "materials-table.csv") as fh:
        rows = {(r["material"], r["fit"]): r for r in csv.DictReader(fh)}
    want = {(n, f.key) for f in catalogue.fits() for n in catalogue.materials(f.key)}
    assert set(rows) == want and len(want) == 1202
    he = catalogue.fit_data("ngan2005/he")
    zero = [n for n, terms in he.items() if terms[1].params["eta"] == 1.0]
    assert "black-obsidian" in zero and len(zero) == 4
    for n in zero:
        assert float(rows[(n, "ngan2005/he")]["max_albedo"]) == pytest.approx(
            max(he[n][0].params["albedo"]), abs=1e-6)


def test_check_materials_json_reports_the_published_table_numbers():
    """Two fits of ngan2005/ward-duer, quick: the JSON list has one report each,
    whose largest albedo and its angle are docs/materials-table.md's (full
    accuracy, to its 4 decimals); gold-metallic-paint gains energy, so the status is 1."""
    r = run("check", "--materials", "--fit", "ngan2005/ward-duer", "--material", "gold-metallic-paint",
            "--material", "alum-bronze", "--quick", "--json", "--jobs", "1")
    assert r.exit_code == 1, r.output
    import json

    reps = json.loads(r.output)
    assert [x["material"] for x in reps] == ["gold-metallic-paint", "alum-bronze"]   # the order asked
    for x in reps:
        want, theta, gains = _table_row(x["material"], "ngan2005/ward-duer")
        assert x["max_albedo"] == pytest.approx(want, abs=6e-5)
        assert x["theta_deg"] == theta and x["gains_energy"] == gains
        assert x["error"] <= 1e-5 * 1.01 and x["reciprocal"]


TWO = [("alum-bronze", "ngan2005/ward"), ("beige-fabric", "ngan2005/ward")]


@pytest.fixture
def two_fits(monkeypatch):
    """Every published fit is these two (so that a whole run takes seconds)."""
    from plausible.analysis import materials as M

    monkeypatch.setattr(M, "work_list", lambda fits=None, names=None: [
        w for w in TWO if (fits is None or w[1] in fits) and (names is None or w[0] in names)])
    return TWO


def test_check_materials_table_of_a_plausible_fit_exits_zero_and_writes_the_tables(tmp_path, monkeypatch):
    from plausible.analysis import materials as M

    monkeypatch.setattr(M, "work_list", lambda fits=None, names=None: [("alum-bronze", "ngan2005/ward")])
    r = run("check", "--materials", "--quick", "--out", str(tmp_path), "--jobs", "1")
    assert r.exit_code == 0, r.output
    assert "1 fits of 1 fit sets checked (quick): 1 plausible, 0 not" in r.output
    md = (tmp_path / "materials-table.md").read_text()
    assert "| alum-bronze | ngan2005/ward |" in md
    csv = (tmp_path / "materials-table.csv").read_text().splitlines()
    assert csv[0].startswith("material,fit,") and csv[1].startswith("alum-bronze,ngan2005/ward,")


def test_check_materials_in_two_processes_gives_the_rows_of_one():
    from plausible.analysis.materials import check_fits

    one = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True, jobs=1)
    two = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True, jobs=2)
    assert [r.material for r in two] == ["alum-bronze", "beige-fabric"]
    for a, b in zip(one, two):
        assert b.max_albedo == pytest.approx(a.max_albedo, rel=1e-12) and b.theta_deg == a.theta_deg


@pytest.mark.parametrize("args,words", [
    (("--fit", "ngan2005/ward"), "go with --materials"),
    (("--materials", "lambertian"), "takes no MODEL"),
    (("--materials", "--fit", "ngan2005/wrd"), "did you mean ngan2005/ward"),
    (("--materials", "--material", "alum-bronz"), "did you mean alum-bronze"),
])
def test_check_materials_usage_errors(args, words):
    r = run("check", *args)
    assert r.exit_code == 2 and words in r.output, r.output


# -- one batch engine under check --materials (issue 41 item 3, issue 45 items 4-5) ---------------

def test_a_filtered_run_does_not_replace_the_full_table(tmp_path):
    full = "material,fit\n" + "".join(f"m{i},f\n" for i in range(1202))
    (tmp_path / "materials-table.csv").write_text(full)
    (tmp_path / "materials.md").write_text("<!-- table:begin -->\nsummary of 1202\n<!-- table:end -->\n")
    r = run("check", "--materials", "--fit", "ngan2005/ward", "--material", "alum-bronze", "--quick",
            "--out", str(tmp_path), "--jobs", "1")
    assert r.exit_code == 2 and "a run filtered by --fit/--material would replace it" in r.output, r.output
    assert (tmp_path / "materials-table.csv").read_text() == full       # (was: 1 row)
    assert "summary of 1202" in (tmp_path / "materials.md").read_text()


def test_check_materials_refuses_out_dash(tmp_path, monkeypatch, two_fits):
    monkeypatch.chdir(tmp_path)
    r = run("check", "--materials", "--quick", "--out", "-")
    assert r.exit_code == 2 and "--out -: check --materials --out writes" in r.output
    assert not (tmp_path / "-").exists()


def test_an_interrupted_run_resumes_from_its_journal(tmp_path, monkeypatch, two_fits):
    from plausible.analysis import materials as M

    real, calls = M.check_fit, []

    def check_fit(name, fit, *a, **k):
        calls.append(name)
        if len(calls) == 2:
            raise KeyboardInterrupt
        return real(name, fit, *a, **k)

    monkeypatch.setattr(M, "check_fit", check_fit)
    args = ("check", "--materials", "--quick", "--out", str(tmp_path), "--jobs", "1")
    r = run(*args)
    assert r.exit_code == 130 and "run the same command again to resume" in r.output, r.output
    assert not (tmp_path / "materials-table.csv").exists()
    assert list(M.read_journal(tmp_path / ".materials-rows.jsonl")) == [TWO[0]]      # (was: nothing kept)
    r = run(*args)
    assert r.exit_code == 0, r.output
    assert calls == ["alum-bronze", "beige-fabric", "beige-fabric"]                  # the first not again
    rows = (tmp_path / "materials-table.csv").read_text().splitlines()
    assert [x.split(",")[0] for x in rows[1:]] == ["alum-bronze", "beige-fabric"]
    assert not (tmp_path / ".materials-rows.jsonl").exists()
    assert rows[1] == _csv_row(real(*TWO[0], quick=True))                           # the journaled row is the row


def _csv_row(r):
    return (f"{r.material},{r.fit},{r.asymmetry:.3e},{r.max_albedo:.6f},{r.theta_deg:g},{r.channel},"
            f"{r.albedo_normal:.6f},{r.error:.2e},{int(r.gains_energy)}")


def test_a_fit_held_by_another_live_run_is_left_to_it(tmp_path, two_fits):
    import json
    import subprocess
    import sys

    from plausible import engine
    from plausible.analysis import materials as M

    journal = tmp_path / ".materials-rows.jsonl"
    settings = M._settings(M.THETAS_DEG, True, None)
    claims = engine.Claims(tmp_path / ".materials-rows.jsonl.claims", "check")
    owner = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    try:
        p = claims.path(json.dumps([TWO[1], settings]))
        p.parent.mkdir()
        p.write_text(json.dumps(dict(engine.me(), pid=owner.pid, start=engine._start_time(owner.pid))))
        r = run("check", "--materials", "--quick", "--out", str(tmp_path), "--jobs", "1")
        assert r.exit_code == 0, r.output
        assert f"1 fits left to another run on {tmp_path} (claimed by PID {owner.pid}" in r.output
        assert "1 fits are another run's" in r.output and not (tmp_path / "materials-table.csv").exists()
        assert list(M.read_journal(journal)) == [TWO[0]]
    finally:
        owner.kill()
        owner.wait()
    r = run("check", "--materials", "--quick", "--out", str(tmp_path), "--jobs", "1")     # its owner is gone
    assert r.exit_code == 0 and "took over a stale claim" in r.output, r.output
    assert len((tmp_path / "materials-table.csv").read_text().splitlines()) == 3


def test_check_materials_on_a_dask_scheduler_gives_the_rows_of_one_process():
    distributed = pytest.importorskip("distributed")
    from plausible.analysis.materials import check_fits

    one = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True, jobs=1)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as c:
        got = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True,
                         scheduler=c.scheduler_address)
    assert [(r.material, r.fit) for r in got] == [(r.material, r.fit) for r in one]
    for a, b in zip(one, got):
        assert b.max_albedo == pytest.approx(a.max_albedo, rel=1e-12) and b.theta_deg == a.theta_deg


def test_check_materials_names_a_scheduler_it_cannot_reach(monkeypatch):
    from plausible import engine

    monkeypatch.setattr(engine, "CONNECT_TIMEOUT", 2.0)
    r = run("check", "--materials", "--fit", "ngan2005/ward", "--material", "alum-bronze", "--quick",
            "--scheduler", "tcp://127.0.0.1:1")
    assert r.exit_code == 2 and "--scheduler: cannot reach the Dask scheduler" in r.output, r.output
