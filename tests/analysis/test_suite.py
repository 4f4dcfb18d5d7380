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
