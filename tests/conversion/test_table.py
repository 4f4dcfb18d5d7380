"""The error table's run (issue 32): resumable (rows appended as they finish, a cut last
line ignored, done rows skipped), round robin over the fit sets, and its summary's counts."""

import json

import numpy as np
import pytest

from plausible.conversion import table


def _fake_row(job):
    to, fit, name = job
    return dict(to=to, fit=fit, material=name, target=f"{to}:x", perceptual=1.0, l2=0.5, log=0.2,
                albedo_diff=[0.01, 0.02, 0.07 if name.startswith("a") else 0.03], source_albedo_max=0.5,
                conserving=True, params={}, seconds=1.0)


def test_jobs_go_round_robin_over_the_fit_sets_and_every_target():
    j = table.jobs(("mitsuba", "gltf"), per_set=2, fits=["ngan2005/ward", "low2012/smooth-e2"])
    assert len(j) == 2 * 2 * 2
    assert [(f, t) for t, f, _ in j[:4]] == [("ngan2005/ward", "mitsuba"), ("ngan2005/ward", "gltf"),
                                             ("low2012/smooth-e2", "mitsuba"), ("low2012/smooth-e2", "gltf")]
    assert j[0][2] < j[4][2]          # the first material of each set, then the second
    with pytest.raises(ValueError, match="no loadable fit set nope"):
        table.jobs(fits=["nope"])


def test_an_interrupted_run_resumes_without_repeating_a_row(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(table, "convert_row", lambda job: calls.append(job) or _fake_row(job))
    path = tmp_path / "t.jsonl"
    kw = dict(per_set=2, fits=["ngan2005/ward", "low2012/smooth-e2"])
    table.run_table(path, ("mitsuba",), limit=3, **kw)
    assert len(calls) == 3 and len(path.read_text().splitlines()) == 3
    with open(path, "a") as f:        # an interrupt in the middle of a line
        f.write('{"to": "mitsuba", "fit": ')
    rows = table.run_table(path, ("mitsuba",), **kw)
    assert len(calls) == 4 and len(set(calls)) == 4 and len(rows) == 4
    assert table.run_table(path, ("mitsuba",), **kw) == rows and len(calls) == 4


def test_a_failing_conversion_is_recorded_and_the_run_goes_on(tmp_path, monkeypatch):
    def convert_row(job):
        if "oxide" in job[2]:
            raise ValueError("boom")
        return _fake_row(job)

    monkeypatch.setattr(table, "convert_row", convert_row)
    rows = table.run_table(tmp_path / "t.jsonl", ("gltf",), per_set=2, fits=["ngan2005/ward"])
    assert sorted("error" in r for r in rows.values()) == [False, True]
    assert "ValueError: boom" in table.markdown(rows)


def test_the_summary_counts_the_rows_within_the_band(tmp_path):
    rows = {table.key(r): r for r in (_fake_row(("mitsuba", "s", n)) for n in ("alpha", "beta", "gamma"))}
    rows[table.key(_fake_row(("mitsuba", "s", "delta")))] = {**_fake_row(("mitsuba", "s", "delta")),
                                                             "conserving": False, "albedo_diff": [0.2, 0, 0]}
    (s,) = table.summary(list(rows.values()), 0.05)
    assert (s["n"], s["within"], s["conserving"], s["worst"]) == (4, 2, 3, 0.2)
    md = table.markdown(rows)
    assert "| s | 4 | 2 / 3 |" in md and "no (source not conserving)" in md
    # a blendbsdf whose bsdf_0 is a roughplastic is the coat's blend; one of a diffuse is not
    coat = {**_fake_row(("mitsuba", "s", "coat")), "target": "mitsuba:blendbsdf",
            "params": {"type": "blendbsdf", "bsdf_0": {"type": "roughplastic"}}}
    plain = {**coat, "material": "plain", "params": {"type": "blendbsdf", "bsdf_0": {"type": "diffuse"}}}
    md = table.markdown({table.key(coat): coat, table.key(plain): plain})
    assert "| s | coat | blendbsdf-tir |" in md and "| s | plain | blendbsdf |" in md
    assert json.loads(json.dumps(rows)) == rows


def test_the_command_writes_the_markdown_of_the_rows_and_refuses_a_bad_target(tmp_path):
    from click.testing import CliRunner

    from plausible.cli import main

    path, md = tmp_path / "t.jsonl", tmp_path / "t.md"
    path.write_text("\n".join(json.dumps(_fake_row(("mitsuba", "ngan2005/ward", n))) for n in ("alum-bronze", "beige"))
                    + "\n")
    r = CliRunner().invoke(main, ["convert-table", "--out", str(path), "--to", "mitsuba", "--fits", "ngan2005/ward",
                                  "--limit", "0", "--markdown", str(md)])
    assert r.exit_code == 0, r.output
    assert "1 of 86 conversions" in r.output        # beige is no material of the set
    assert "| ngan2005/ward | 2 | 1 / 2 |" in md.read_text()
    r = CliRunner().invoke(main, ["convert-table", "--out", str(path), "--to", "blender"])
    assert r.exit_code == 2 and "--to: the table's targets are mitsuba, gltf" in r.output


def test_worker_processes_write_every_row_once(tmp_path):
    path = tmp_path / "t.jsonl"
    rows = table.run_table(path, ("mitsuba", "gltf"), per_set=2, fits=["ngan2005/ward"], workers=2, row=_fake_row)
    assert len(rows) == 4 and len(path.read_text().splitlines()) == 4
    assert set(rows) == {table.key(j) for j in table.jobs(("mitsuba", "gltf"), 2, ["ngan2005/ward"])}


def test_rows_of_a_redone_target_made_by_other_code_are_converted_again_first(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(table, "convert_row", lambda job: calls.append(job) or {**_fake_row(job), "code": "new"})
    monkeypatch.setattr(table, "code_version", lambda: "new")
    path = tmp_path / "t.jsonl"
    old = [_fake_row(j) for j in table.jobs(("mitsuba",), 2, ["ngan2005/ward"])]
    old[1]["target"] = "mitsuba:diffuse"
    path.write_text("".join(json.dumps(r) + "\n" for r in old))
    rows = table.run_table(path, ("mitsuba",), per_set=3, fits=["ngan2005/ward"], redo=["mitsuba:diffuse"])
    # first the redone row, then the one new job (the third material)
    assert calls == [table.jobs(("mitsuba",), 2, ["ngan2005/ward"])[1], table.jobs(("mitsuba",), 3, ["ngan2005/ward"])[2]]
    assert rows[table.key(old[1])]["code"] == "new" and len(rows) == 3
    table.run_table(path, ("mitsuba",), per_set=3, fits=["ngan2005/ward"], redo=["mitsuba:diffuse"])
    assert len(calls) == 2        # the redone row is this code's: not again


def test_rows_of_a_redone_fit_set_or_material_are_converted_again_in_job_order(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(table, "convert_row", lambda job: calls.append(job) or {**_fake_row(job), "code": "new"})
    monkeypatch.setattr(table, "code_version", lambda: "new")
    path = tmp_path / "t.jsonl"
    js = table.jobs(("mitsuba",), 2, ["ngan2005/ward", "ngan2005/blinn-phong"])
    path.write_text("".join(json.dumps(_fake_row(j)) + "\n" for j in js))
    # a fit set: both of its rows; a material of another set: that row alone
    one = table.key(js[2]).split(" ", 1)[1]        # material:alumina-oxide@ngan2005/blinn-phong
    table.run_table(path, ("mitsuba",), per_set=2, fits=["ngan2005/ward", "ngan2005/blinn-phong"],
                    redo=["ngan2005/ward", one])
    assert calls == [js[1], js[2], js[3]]
    # a redo that names nothing in the table converts nothing, and says so (it was silent)
    with pytest.raises(ValueError, match="redo: 'x/y' names no target"):
        table.run_table(path, ("mitsuba",), per_set=2, fits=["ngan2005/ward", "ngan2005/blinn-phong"], redo=["x/y"])
    assert len(calls) == 3


# -- one batch engine (issue 41 item 3, issue 45 item 5) ------------------------------------------

KW = dict(per_set=3, fits=["ngan2005/ward", "ngan2005/blinn-phong"])


def _slow_row(job):
    import time

    time.sleep(0.05)
    return _fake_row(job)


def test_two_concurrent_runs_write_each_row_once(tmp_path, monkeypatch):
    import threading

    monkeypatch.setattr(table, "convert_row", _slow_row)
    path = tmp_path / "t.jsonl"
    threads = [threading.Thread(target=table.run_table, args=(path, ("mitsuba", "gltf")), kwargs=KW)
               for _ in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    lines = path.read_text().splitlines()
    assert len(lines) == len(set(lines)) == 12          # (was: up to 24 lines, each row twice)
    assert {table.key(json.loads(x)) for x in lines} == {table.key(j) for j in table.jobs(("mitsuba", "gltf"), **KW)}
    assert list((tmp_path / ".t.jsonl.claims").iterdir()) == []


def _kills_its_worker_once(job):
    import os
    import signal
    from pathlib import Path

    mark = Path(os.environ["PLAUSIBLE_TEST_MARK"])
    if job[2] == "alum-bronze" and job[0] == "gltf" and not mark.exists():
        mark.touch()
        os.kill(os.getpid(), signal.SIGKILL)          # as the kernel's out-of-memory killer would
    return _fake_row(job)


def test_a_killed_worker_is_replaced_and_every_row_written(tmp_path, monkeypatch):
    monkeypatch.setenv("PLAUSIBLE_TEST_MARK", str(tmp_path / "killed"))
    path, runs = tmp_path / "t.jsonl", []
    rows = table.run_table(path, ("mitsuba", "gltf"), workers=2, row=_kills_its_worker_once, summary=runs, **KW)
    assert (tmp_path / "killed").exists()               # (was: BrokenProcessPool, 0 rows saved)
    assert len(rows) == 12 and not any("error" in r for r in rows.values()) and runs[0].done == 12
    assert len(path.read_text().splitlines()) == 12


def test_a_duplicated_row_is_reported_and_dropped(tmp_path):
    path = tmp_path / "t.jsonl"
    a, b = (json.dumps(_fake_row(("mitsuba", "ngan2005/ward", n))) for n in ("alum-bronze", "alumina-oxide"))
    path.write_text("\n".join([a, b, a]) + "\n")
    problems = []
    rows = table.read_rows(path, problems)
    assert len(rows) == 2
    assert problems == [f"{path}:3: a second row of mitsuba material:alum-bronze@ngan2005/ward (the first at line 1); "
                        "dropped"]
    redone = json.dumps({**_fake_row(("mitsuba", "ngan2005/ward", "alum-bronze")), "code": "new"})
    path.write_text("\n".join([a, b, redone]) + "\n")    # a row of other code replaces it (--redo)
    problems = []
    assert table.read_rows(path, problems)[table.key(json.loads(a))]["code"] == "new" and problems == []


def test_a_whole_last_row_lacking_its_newline_is_kept(tmp_path, monkeypatch):
    monkeypatch.setattr(table, "convert_row", _fake_row)
    path = tmp_path / "t.jsonl"
    path.write_text(json.dumps(_fake_row(table.jobs(("mitsuba",), 1, ["ngan2005/ward"])[0])))
    rows = table.run_table(path, ("mitsuba",), per_set=2, fits=["ngan2005/ward"])
    lines = path.read_text().splitlines()
    assert len(rows) == 2 and len(lines) == 2 and all(json.loads(x) for x in lines)


def test_on_a_dask_scheduler_the_rows_of_one_process(tmp_path):
    distributed = pytest.importorskip("distributed")
    one = table.run_table(tmp_path / "one.jsonl", ("mitsuba",), row=_fake_row, **KW)
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False, dashboard_address=None) as c:
        runs = []
        got = table.run_table(tmp_path / "dask.jsonl", ("mitsuba",), row=_fake_row, scheduler=c.scheduler_address,
                              summary=runs, **KW)
    assert got == one and runs[0].workers == 2 and runs[0].done == 6


def test_the_command_refuses_out_dash_and_names_a_scheduler_it_cannot_reach(tmp_path, monkeypatch):
    from click.testing import CliRunner

    from plausible import engine
    from plausible.cli import main

    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["convert-table", "--out", "-", "--limit", "0"])
    assert r.exit_code == 2 and "--out -: convert-table appends its rows to a file" in r.output
    assert not (tmp_path / "-").exists()
    monkeypatch.setattr(engine, "CONNECT_TIMEOUT", 2.0)
    r = CliRunner().invoke(main, ["convert-table", "--out", "t.jsonl", "--fits", "ngan2005/ward", "--per-set", "1",
                                  "--scheduler", "tcp://127.0.0.1:1"])
    assert r.exit_code == 2 and "--scheduler: cannot reach the Dask scheduler" in r.output, r.output


def _looked(name, ratios, warned=True):
    from plausible.mitsuba.looks import HIGHLIGHT_BAND, LIGHT_ANGLES, _warnings

    words = _warnings(ratios, LIGHT_ANGLES, *HIGHLIGHT_BAND) if warned else []
    worst = max(ratios, key=lambda r: abs(np.log(r)))
    return {**_fake_row(("gltf", "s", name)), "flip": 0.2, "highlight_ratio": worst,
            "highlight_ratios": list(ratios), "looks_warnings": words}


def test_every_row_outside_the_highlight_band_shows_its_warning_in_the_table():
    """Issue 40: a conversion whose highlight is lost (0.364x at 0 deg) or invented (25.9x at 150 deg)
    carries the warning compare_looks wrote, in its row of the table; one inside the band shows none."""
    rows = [_looked("bronze", [0.364, 0.8, 1.2, 25.9]), _looked("fine", [1.0, 0.9, 1.1, 1.3])]
    md = table.markdown({table.key(r): r for r in rows})
    line = next(x for x in md.splitlines() if "| bronze |" in x)
    assert "lost 0.364x at 0 deg" in line and "invented 25.9x at 150 deg" in line
    assert "| x1.3 | - |" in next(x for x in md.splitlines() if "| fine |" in x)
    assert table.unwarned(rows) == [] and "without their warning" not in md


def test_a_row_outside_the_band_without_its_warning_is_caught():
    """The check fails a row whose ratio is out of the band and whose warnings do not say so."""
    silent = _looked("bronze", [0.364, 0.8, 1.2, 1.0], warned=False)
    wrong = {**_looked("nickel", [2.0, 1.0, 1.0, 1.0]), "looks_warnings": ["highlight lost: 0.5x"]}
    assert [k for k, _ in table.unwarned([silent, wrong])] == [table.key(silent), table.key(wrong)]
    assert "without their warning" in table.markdown({table.key(silent): silent})


def test_an_unknown_fit_set_is_refused_with_the_loadable_ones_listed():
    from plausible import catalogue
    from plausible.conversion.table import jobs

    with pytest.raises(ValueError) as e:
        jobs(fits=["nope"])
    listed = str(e.value).split("the loadable ones are ")[1].split(", ")
    assert listed == [fs.key for fs in catalogue.fits() if fs.built] and len(listed) > 1   # was empty


def test_a_redo_that_names_nothing_of_the_table_is_refused(tmp_path):
    # an outside audit: --redo nope was ignored (nothing redone, no word of it)
    with pytest.raises(ValueError, match="redo: 'nope' names no target, fit set or material"):
        table.run_table(tmp_path / "t.jsonl", ("mitsuba",), per_set=1, fits=["ngan2005/ward"], redo=["nope"],
                        row=lambda job: _fake_row(job))
    assert not (tmp_path / "t.jsonl").exists()


def test_a_damaged_line_is_reported_and_its_conversion_made_again(tmp_path, monkeypatch):
    path = tmp_path / "t.jsonl"
    a = json.dumps(_fake_row(("mitsuba", "ngan2005/ward", "alum-bronze")))
    path.write_text("\n".join([a, '{"to": "mitsuba", "fit": "ngan2005/wa', a[:20] + "}"]) + "\n")
    problems = []
    rows = table.read_rows(path, problems)
    assert len(rows) == 1 and len(problems) == 2                     # were skipped without a word
    assert problems[0].startswith(f"{path}:2: not a row of this table") and problems[1].startswith(f"{path}:3:")


def test_a_redo_of_a_whole_target_converts_its_rows_again(tmp_path):
    # a second reader: "mitsuba" passed the name check but matched no row (rows hold the chosen family)
    calls = []
    path = tmp_path / "t.jsonl"
    job = ("mitsuba", "ngan2005/ward", "alum-bronze")
    path.write_text(json.dumps({**_fake_row(job), "target": "mitsuba:diffuse", "code": "old"}) + "\n")
    table.run_table(path, todo_jobs=[job], redo=["mitsuba"], row=lambda j: calls.append(j) or _fake_row(j))
    assert calls == [job]
