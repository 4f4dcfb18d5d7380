"""`plausible check` on every registered model (defaults and declared extremes):
sampling and chi-square always pass; reciprocity and energy pass exactly when the
model claims them (registry flags).  A model added later is checked automatically."""

import pytest

import plausible
from conftest import model_cases


@pytest.mark.parametrize("name,kw", model_cases())
def test_check_agrees_with_the_models_claims(name, kw):
    m = plausible.make(name, **kw)
    rep = plausible.check(m, quick=True)
    assert rep["sampling"].passed, rep["sampling"].worst
    assert rep["chi2"].passed, rep["chi2"].worst
    if m.info.reciprocal:
        assert rep["reciprocity"].passed, rep["reciprocity"].worst
    if m.info.energy_conserving:
        assert rep["energy"].passed, rep["energy"].worst


@pytest.mark.slow
@pytest.mark.parametrize("name,kw", model_cases(max_variants=0))
def test_full_check_agrees_with_the_models_claims(name, kw):
    m = plausible.make(name, **kw)
    rep = plausible.check(m)
    assert rep["sampling"].passed and rep["chi2"].passed, rep
    if m.info.reciprocal:
        assert rep["reciprocity"].passed
    if m.info.energy_conserving:
        assert rep["energy"].passed
