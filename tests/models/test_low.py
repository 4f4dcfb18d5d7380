"""Löw et al. 2012's microfacet and smooth-surface models against their formulas written
again here in angles (eqs. 8, 12, 14, 15), the closed forms of the sampling densities
against quadrature, and bbm's definitions (tests/models/bbm_reference.py)."""

import math

import numpy as np
import pytest
from scipy import integrate

import plausible
from plausible.models import low as L
from plausible.arrays.ops import NP

from bbm_reference import cook_fresnel, lowmicrofacetfit, lowsmooth


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


PAIRS = [(10, 0, 25, 180), (30, 0, 30, 180), (45, 20, 60, 170), (60, 0, 10, 90), (75, 0, 80, 180),
         (5, 0, 40, 0), (50, 0, 50, 200), (85, 10, 70, 150), (20, 0, 89, 180), (70, 30, 35, 260)]
SETS = [dict(A=100.0, B=1000.0, C=1.2, eta=1.5), dict(A=51.7, B=10482.1, C=0.8167, eta=2.2365),
        dict(A=0.146, B=3.44e6, C=0.0832, eta=10.4), dict(A=3.0, B=30.0, C=1.0, eta=1.05)]


def fresnel_angle(c, eta):
    """Snell and the two amplitude ratios, in angles (Born & Wolf)."""
    ti = math.acos(c)
    st = math.sin(ti) / eta
    if st >= 1:
        return 1.0
    tt = math.asin(st)
    if ti == 0:
        return ((eta - 1) / (eta + 1)) ** 2
    rs = math.sin(ti - tt) / math.sin(ti + tt)
    rp = math.tan(ti - tt) / math.tan(ti + tt)
    return 0.5 * (rs * rs + rp * rp)


def ref_microfacet(a, b, c, d, A, B, C, eta, norm=math.pi):
    """Eq. 15 in angles: theta_h, theta_d from the half vector, V-groove G in angles."""
    wi, wo = direction(a, b), direction(c, d)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    th = math.acos(min(h[2], 1.0))
    td = math.acos(min(float(np.dot(wi, h)), 1.0))
    D = (1 + B * (1 - math.cos(th))) ** (-C)
    G = min(1.0, 2 * math.cos(th) * wi[2] / math.cos(td), 2 * math.cos(th) * wo[2] / math.cos(td))
    return A * D * G * fresnel_angle(math.cos(td), eta) / (norm * wi[2] * wo[2])


def ref_smooth(a, b, c, d, A, B, C, eta):
    """Eqs. 10-14: D_p = mirror(I)_p - O_p, cos(theta_d) = sqrt(1 - |I_p - O_p|^2 / 4)."""
    ti, pi_, to, po = map(math.radians, (a, b, c, d))
    Ip = np.array([math.sin(ti) * math.cos(pi_), math.sin(ti) * math.sin(pi_)])
    Op = np.array([math.sin(to) * math.cos(po), math.sin(to) * math.sin(po)])
    Dp = -Ip - Op
    cd = math.sqrt(1 - np.dot(Ip - Op, Ip - Op) / 4)
    return A / (1 + B * np.dot(Dp, Dp)) ** C * fresnel_angle(cd, eta)


@pytest.mark.parametrize("kw", SETS)
def test_microfacet_matches_eq_15(kw):
    m = plausible.make("low-microfacet", **kw)
    for a, b, c, d in PAIRS:
        want = ref_microfacet(a, b, c, d, **kw)
        assert float(m.eval(direction(a, b), direction(c, d))) == pytest.approx(want, rel=1e-10)
    none = plausible.make("low-microfacet", normalization="none", **kw)
    a, b, c, d = PAIRS[2]
    assert float(none.eval(direction(a, b), direction(c, d))) == pytest.approx(math.pi * ref_microfacet(a, b, c, d, **kw), rel=1e-10)


@pytest.mark.parametrize("kw", SETS)
def test_smooth_matches_eqs_12_and_14(kw):
    m = plausible.make("low-smooth", **kw)
    for a, b, c, d in PAIRS:
        want = ref_smooth(a, b, c, d, **kw)
        assert float(m.eval(direction(a, b), direction(c, d))) == pytest.approx(want, rel=1e-10)


def test_the_references_tell_the_models_apart():
    """A check that can fail: the smooth model is not the microfacet one, and pi matters."""
    kw = SETS[0]
    a, b, c, d = PAIRS[2]
    wi, wo = direction(a, b), direction(c, d)
    assert abs(float(plausible.make("low-smooth", **kw).eval(wi, wo)) - ref_microfacet(a, b, c, d, **kw)) > 1e-3
    assert abs(float(plausible.make("low-microfacet", **kw).eval(wi, wo))
               - ref_microfacet(a, b, c, d, norm=1.0, **kw)) > 1e-3


@pytest.mark.parametrize("kw", SETS)
def test_models_equal_bbms_definitions(kw):
    rng = np.random.default_rng(5)
    for _ in range(40):
        v = rng.normal(size=(2, 3))
        v[:, 2] = np.abs(v[:, 2])
        wi, wo = v / np.linalg.norm(v, axis=-1, keepdims=True)
        assert float(plausible.make("low-microfacet", **kw).eval(wi, wo)) == pytest.approx(
            float(np.ravel(lowmicrofacetfit(wi, wo, **kw))[0]), rel=1e-9)
        assert float(plausible.make("low-smooth", **kw).eval(wi, wo)) == pytest.approx(
            float(np.ravel(lowsmooth(wi, wo, **kw))[0]), rel=1e-12)


def test_cook_fresnel_equals_the_exact_dielectric_and_is_zero_at_eta_one():
    from plausible import fresnel
    c = np.linspace(0, 1, 101)
    for eta in (1.0, 1.05, 1.5, 9.0):
        cc = c[1:] if eta == 1.0 else c      # bbm's form is 0/0 at eta = 1, c = 0
        np.testing.assert_allclose(fresnel.cook(NP, cc, eta), [cook_fresnel(eta, x) for x in cc], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(fresnel.cook(NP, c[1:], eta), fresnel.dielectric(NP, c[1:], eta), rtol=1e-10, atol=1e-15)
    assert np.all(fresnel.cook(NP, c, 1.0) == 0)


@pytest.mark.parametrize("B,C", [(30.0, 1.2), (1e4, 0.8), (500.0, 1.0), (50.0, 1.0 + 1e-8), (1e3, 0.0), (10.0, 3.0)])
def test_abc_ndf_integral_and_sampler(B, C):
    """int D domega_h (closed form, C = 1 limit included) against quadrature; the sampled
    cos(theta_h) follows the density D / int D (CDF at a few points)."""
    quad = 2 * math.pi * integrate.quad(lambda z: (1 + B * (1 - z)) ** (-C), 0, 1, points=[1 - 1 / B] if B > 1 else None,
                                        epsabs=0, epsrel=1e-12, limit=200)[0]
    assert float(L.abc_ndf_integral(NP, B, C)) == pytest.approx(quad, rel=1e-9)
    u = np.random.default_rng(1).random((200_000, 2))
    z = L.abc_half_vector(NP, B, C, u[:, 0], u[:, 1])[2]
    for z0 in (0.2, 0.9, 0.99, 1 - 1 / B):
        frac = 2 * math.pi * integrate.quad(lambda x: (1 + B * (1 - x)) ** (-C), z0, 1, epsrel=1e-12)[0] / quad
        assert np.mean(z > z0) == pytest.approx(frac, abs=5 * math.sqrt(frac * (1 - frac) / len(z)) + 1e-9)


def test_smooth_sampling_density_integrates_to_the_valid_fraction():
    m = plausible.make("low-smooth", B=200.0, C=0.7)
    wi = direction(50, 0)
    s = m.sample(wi, np.random.default_rng(3).random((100_000, 3)))
    valid = np.mean(s.pdf > 0)
    import importlib

    total = float(importlib.import_module("plausible.integrals.albedo").pdf_integrals(m, [wi])[0].value)
    assert total == pytest.approx(valid, abs=5 * math.sqrt(valid * (1 - valid) / 1e5) + 1e-4)
