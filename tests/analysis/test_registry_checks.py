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
    assert rep.as_claimed(m.info), str(rep)


@pytest.mark.slow
@pytest.mark.parametrize("name,kw", model_cases(max_variants=0))
def test_full_check_agrees_with_the_models_claims(name, kw):
    m = plausible.make(name, **kw)
    rep = plausible.check(m)
    assert rep.as_claimed(m.info), str(rep)
