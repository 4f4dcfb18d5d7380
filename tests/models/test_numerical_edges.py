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
    from plausible.integrals.cache import spec_of

    a = plausible.make("reciprocal-phong", n=20.0)
    b = plausible.make("reciprocal-phong", n=20.00004)
    assert repr(a) == repr(b) and spec_of(a) != spec_of(b)
    assert spec_of(plausible.make("pumped-up", base=a)) != spec_of(plausible.make("pumped-up", base=b))


def test_tables_of_unregistered_subclasses_are_not_shared_between_nearby_parameters():
    # CookTorranceWide (the published Cook-Torrance fits) inherits cook-torrance's registry entry but
    # is not its class: its spec() is its repr, 6 digits, so m=0.1234567 and 0.1234568 read one table
    from plausible.integrals.cache import spec_of
    from plausible.models.published import CookTorranceWide

    a, b = CookTorranceWide(m=0.1234567), CookTorranceWide(m=0.1234568)
    assert repr(a) == repr(b) and spec_of(a) != spec_of(b)
    assert spec_of(a) == spec_of(CookTorranceWide(m=0.1234567))          # a key, not a fresh name per object
    assert "0.1234567" in spec_of(a) and "CookTorranceWide" in spec_of(a)   # not cook-torrance's own key
    assert spec_of(a) != spec_of(plausible.make("cook-torrance", m=0.1234567))


def test_lafortune_pdf_of_a_subnormal_lobe_is_the_same_on_both_backends():
    # rho |C wi|^n = 1e-10 * 0.1^300 = 1e-310, a float64 subnormal: Dr.Jit flushed it to zero
    # (pdf 0, every sample lost) while NumPy kept it; the mixture is normalised by its largest weight
    from plausible.arrays.backend import drjit_available

    m = plausible.make("lafortune", lobes=[(-1.0, -1.0, 0.1, 300.0, 1e-10)], rd=0.0)
    wi = np.array([0.0, 0.0, 1.0])
    d = np.array([0.0, 0.0, 1.0])                                 # the lobe's axis C wi / |C wi|
    wo = np.array([[0.0, 0.0, 1.0], [0.1, 0.0, 0.995]])
    expect = 301 / (2 * math.pi) * np.maximum(wo @ d / np.linalg.norm(wo, axis=1), 0) ** 300
    assert m.pdf(wi, wo, backend="numpy") == pytest.approx(expect, rel=1e-9)
    if drjit_available():
        assert m.pdf(wi, wo, backend="drjit") == pytest.approx(expect, rel=1e-9)
        s = m.sample(wi, np.random.default_rng(1).random((64, 3)), backend="drjit")
        assert np.all(s.pdf > 0)


def test_lafortune_lobe_rim_samples_keep_their_weight():
    # n -> 0 is the uniform lobe rho over the half space C wi . wo > 0 (pdf 1/(2 pi)): weight 2 pi rho cos.
    # At u = 0 the warp lands on the rim, where f and the pdf rounded to opposite sides: 1e58 with rd = 1e-60
    rho = 0.1
    m = plausible.make("lafortune", lobes=[(-1.0, -1.0, 1.0, 1e-9, rho)], rd=1e-60)
    rng = np.random.default_rng(0)
    wi = rng.normal(size=(4000, 3))
    wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    u = np.column_stack([np.full(4000, 0.5), np.zeros(4000), rng.random(4000)])
    s = m.sample(wi, u, backend="numpy")
    assert np.max(s.weight) <= 2 * math.pi * rho
    lobe = m.eval(wi, s.wo) > 0.5 * rho          # where f has the lobe (the rim's side as f rounds it)
    assert np.count_nonzero(lobe) > 1000
    assert s.weight[lobe] == pytest.approx(2 * math.pi * rho * s.wo[lobe, 2], rel=1e-6)
