"""Issue 4's proof grid: `plausible check ashikhmin-shirley` on every pair of
exponents in {0, 1, 10, 100, 1000, 10000} (strongly anisotropic lobes too), for
rs in {0, 0.05, 0.5, 1} and rd in {0, 1}, incidence up to 89.9 degrees and
several azimuths (marker `slow`: run by `make test-all`)."""

import itertools

import pytest

import plausible

EXP = (0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0)
MATERIALS = [(rs, rd) for rs in (0.0, 0.05, 0.5, 1.0) for rd in (0.0, 1.0)]


@pytest.mark.slow
@pytest.mark.parametrize("rs,rd", MATERIALS)
@pytest.mark.parametrize("nu,nv", list(itertools.product(EXP, EXP)))
def test_check_passes_on_the_grid(nu, nv, rs, rd):
    rep = plausible.check(plausible.make("ashikhmin-shirley", nu=nu, nv=nv, rs=rs, rd=rd), quick=True)
    assert rep.passed, str(rep)
