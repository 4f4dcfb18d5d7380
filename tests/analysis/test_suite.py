"""``check_many``: many checks in worker processes give the reports of one process."""

from __future__ import annotations

import numpy as np

import plausible
from plausible.analysis import check
from plausible.analysis.suite import check_many


def test_check_many_in_two_processes_equals_check_in_this_one_and_reports_an_error(monkeypatch):
    # one backend for the workers and this process: ``auto`` picks by what a process has
    # compiled already (fresh workers: NumPy for a check's 60,000 samples; this process after
    # other tests: Dr.Jit), and the two differ by rounding (2e-15 in the sampling figure)
    from plausible.arrays import backend

    monkeypatch.setenv(backend.ENV, "drjit" if backend.drjit_available() else "numpy")
    models = [plausible.make("lambertian", rd=0.8), "no-such-model", plausible.make("reciprocal-blinn", n=20)]
    got = check_many(models, quick=True, jobs=2)
    assert isinstance(got[1], ValueError) and "no-such-model" in str(got[1])
    for m, rep in zip((models[0], models[2]), (got[0], got[2])):
        ref = check(m, quick=True)
        assert [r.name for r in rep.results] == [r.name for r in ref.results]
        for a, b in zip(rep.results, ref.results):
            assert a.passed == b.passed and np.isclose(a.figure, b.figure, rtol=1e-12, atol=1e-15), a.name


# -- a worker that dies ----------------------------------------------------------------------

Lambertian = type(plausible.make("lambertian"))


class KillsItsWorker(Lambertian):
    """A Lambertian whose arrival in a worker process kills that process with SIGKILL
    (as the kernel's out-of-memory killer would), the first ``times`` times; then it
    arrives as the plain Lambertian of the same parameters."""

    def __init__(self, mark, times, **params):
        super().__init__(**params)
        self.mark, self.times = str(mark), times

    def __reduce__(self):
        return _arrive, (self.mark, self.times, dict(self.params))


def _arrive(mark, times, params):
    import os
    import signal
    from pathlib import Path

    p = Path(mark)
    n = int(p.read_text()) if p.exists() else 0
    if n < times:
        p.write_text(str(n + 1))
        os.kill(os.getpid(), signal.SIGKILL)
    return plausible.make("lambertian", **params)


def test_a_killed_worker_is_replaced_its_model_checked_again_and_a_second_death_reported(tmp_path, monkeypatch):
    from plausible.arrays import backend
    from plausible.analysis.suite import WorkerDied

    monkeypatch.setenv(backend.ENV, "drjit" if backend.drjit_available() else "numpy")
    once, twice = tmp_path / "once", tmp_path / "twice"
    models = [plausible.make("lambertian", rd=0.8), KillsItsWorker(once, 1, rd=0.5),
              KillsItsWorker(twice, 5, rd=0.3), plausible.make("reciprocal-blinn", n=20)]
    deaths = []
    got = check_many(models, quick=True, jobs=2, on_worker_death=lambda m, c, r: deaths.append((m.params, c, r)))
    assert once.read_text() == "1" and twice.read_text() == "2"      # killed once / twice, no third try
    assert sorted(deaths, key=str) == sorted([({"rd": 0.5}, -9, True), ({"rd": 0.3}, -9, True),
                                              ({"rd": 0.3}, -9, False)], key=str)
    assert isinstance(got[2], WorkerDied) and got[2].exitcodes == [-9, -9]
    assert "KillsItsWorker(rd=0.3)" in str(got[2]) and "2 times (killed by SIGKILL, killed by SIGKILL)" in str(got[2])
    for m, rep in ((models[0], got[0]), (plausible.make("lambertian", rd=0.5), got[1]), (models[3], got[3])):
        ref = check(m, quick=True)                  # the retried model's report is the plain one
        assert rep.params == ref.params and [r.name for r in rep.results] == [r.name for r in ref.results]
        for a, b in zip(rep.results, ref.results):
            assert a.passed == b.passed and np.isclose(a.figure, b.figure, rtol=1e-12, atol=1e-15), a.name


def test_check_all_names_the_set_whose_worker_died_and_gives_every_other_verdict(tmp_path, monkeypatch):
    import json

    from click.testing import CliRunner

    from plausible.analysis import suite
    from plausible.cli import main

    sets = {"lambertian": [plausible.make("lambertian"), KillsItsWorker(tmp_path / "k", 5, rd=0.3)],
            "reciprocal-blinn": [plausible.make("reciprocal-blinn", n=20)]}
    monkeypatch.setattr(suite, "model_variants", lambda name: sets.get(name, []))
    r = CliRunner().invoke(main, ["check", "--all", "--quick", "--json", "--jobs", "2"])
    assert r.exit_code == 1, r.output
    assert "check KillsItsWorker(rd=0.3): its worker process died (killed by SIGKILL); checking it again" in r.stderr
    assert "not tried again" in r.stderr
    reports = json.loads(r.stdout)
    assert [(x["model"], x["params"]) for x in reports] == [(m.name, dict(m.params))
                                                            for m in sets["lambertian"] + sets["reciprocal-blinn"]]
    assert "WorkerDied: the worker process checking KillsItsWorker(rd=0.3) died, 2 times" in reports[1]["error"]
    assert not reports[1]["passed"]
    for x, m in ((reports[0], sets["lambertian"][0]), (reports[2], sets["reciprocal-blinn"][0])):
        assert "error" not in x and x["passed"] == check(m, quick=True).passed   # the others' verdicts
