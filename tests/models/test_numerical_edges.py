"""Numerical edges found by the held-out probes (issue 27): subnormal sums,
subnormal lobes, tiny exponents; each against a limit the formulas must keep."""

import math

import numpy as np
import pytest

import plausible


def test_as_pdf_with_subnormal_diffuse_albedo_is_the_limit_not_nan():
    # rs = 0, rd = 1e-310: Fs + Ad is subnormal and 1/(Fs + Ad) overflowed (pdf NaN, weights 0);
    # at normal incidence Fs = 0, so the diffuse lobe is sampled alone whatever rd > 0
    wi = np.array([0.0, 0.0, 1.0])
    wo = np.array([0.3, 0.1, 0.9]) / np.linalg.norm([0.3, 0.1, 0.9])
    tiny = plausible.make("ashikhmin-shirley", rs=0, rd=1e-310, nu=10, nv=10)
    ref = plausible.make("ashikhmin-shirley", rs=0, rd=0.5, nu=10, nv=10)
    assert tiny.pdf(wi, wo) == pytest.approx(float(ref.pdf(wi, wo)), rel=1e-12)
    s = tiny.sample(wi, np.random.default_rng(0).random((1000, 3)))
    f = tiny.eval(wi, s.wo)
    assert np.all(np.isfinite(s.pdf)) and np.all((s.weight > 0) == (f > 0))


def test_pumped_up_tables_of_nearby_exponents_are_not_shared():
    # the cache key was repr(model), 6 significant digits: n=20 and n=20.00004 read one table
    from plausible.models.pumped_up import spec_of

    a = plausible.make("reciprocal-phong", n=20.0)
    b = plausible.make("reciprocal-phong", n=20.00004)
    assert repr(a) == repr(b) and spec_of(a) != spec_of(b)
    assert spec_of(plausible.make("pumped-up", base=a)) != spec_of(plausible.make("pumped-up", base=b))
