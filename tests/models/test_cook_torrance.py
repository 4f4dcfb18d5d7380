"""Cook-Torrance (Beckmann, V-groove): normalisation, grazing albedo, sampling, Dr.Jit.
"""

import math

import numpy as np
import pytest
from scipy import integrate

from reference import check_drjit, check_reciprocal, check_sampling, halfvector_albedo
from reference import mc_albedo_at as mc_albedo

import plausible
from plausible import warps
from plausible.models.cook_torrance import beckmann_d
from plausible.arrays.ops import NP


ANGLES = [0.0, 60.0, 80.0, 85.0, 89.0, 89.9, 89.99]


def ct(**kw):
    kw.setdefault("m", 0.1)
    kw.setdefault("fresnel", "none")
    return plausible.make("cook-torrance", **kw)


# -- the distribution ------------------------------------------------------------

@pytest.mark.parametrize("m", [0.05, 0.1, 0.5])
def test_beckmann_d_integrates_to_one_against_cos(m):
    val, _ = integrate.quad(lambda t: 2 * math.pi * math.sin(t) * math.cos(t) *
                            beckmann_d(NP, (math.sin(t), 0.0, math.cos(t)), m),
                            0, math.pi / 2, points=[math.atan(m)], limit=200, epsabs=1e-13)
    assert val == pytest.approx(1.0, abs=1e-9)


def test_vgroove_g_symmetric_bounded_and_one_near_normal():
    m = ct(geometry="vgroove")
    check_reciprocal(m)
    wi = np.array([0.1, 0.0, 1.0]); wo = np.array([-0.1, 0.05, 1.0])
    assert m.eval(wi, wo) == pytest.approx(ct(geometry="none").eval(wi, wo), rel=1e-14)


# -- the integrator is right (and catches a wrong model) ----------------------------

def test_halfvector_integrator_on_closed_forms():
    lam = plausible.make("lambertian", rd=0.7)
    for t in (0.0, 50.0, 85.0):
        assert halfvector_albedo(lam, math.radians(t), width=1e7, n=300) == pytest.approx(0.7, abs=1e-6)
    # Microfacet with G = F = 1 at normal incidence: int D cos d omega_h = 1.
    assert halfvector_albedo(ct(geometry="none"), 0.0, 0.1) == pytest.approx(1.0, abs=1e-12)


def test_halfvector_integrator_detects_a_broken_model():
    class Broken(type(ct())):
        def _f(self, ops, wi, wo, p):
            return 1.01 * super()._f(ops, wi, wo, p)
    b = Broken(m=0.1, fresnel="none", geometry="none")
    assert abs(halfvector_albedo(b, 0.0, 0.1) - 1.0) > 5e-3


# -- section 2.1 of the pumping-up paper: grazing albedo ----------------------------

def test_albedo_without_g_diverges_like_one_over_cos():
    m = ct(geometry="none")
    a = {t: halfvector_albedo(m, math.radians(t), 0.1) for t in ANGLES}
    assert a[0.0] == pytest.approx(1.0, abs=1e-12)
    # Derived: a(theta) cos(theta) = int P(p, q) (cos - p sin) over wo.z > 0 in slope space, with
    # Gaussian slopes of variance m^2/2, -> E[max(-p, 0)] = m / (2 sqrt(pi)) at grazing; the
    # remainder is at most cos(theta).
    lim = 0.1 / (2 * math.sqrt(math.pi))
    for t in (89.9, 89.99):
        c = math.cos(math.radians(t))
        assert abs(a[t] * c - lim) <= c
    assert a[89.99] / a[89.9] == pytest.approx(10.0, rel=0.03)
    assert a[89.99] > 100


def test_albedo_with_vgroove_stays_bounded():
    # Measured, against the paper's claim: the V-groove G (<= 2 (N.H)(N.L)/(V.H)) cancels the
    # 1/(N.L) of the denominator, and the albedo stays below 1 and returns to 1 at grazing.
    m = ct(geometry="vgroove")
    thetas = list(np.linspace(0.0, 89.0, 30)) + ANGLES + [89.999]
    a = np.array([halfvector_albedo(m, math.radians(t), 0.1) for t in thetas])
    assert a.max() <= 1.0 + 1e-9
    assert a.min() > 0.9
    assert halfvector_albedo(m, math.radians(89.99), 0.1) == pytest.approx(1.0, abs=1e-3)


@pytest.mark.parametrize("geometry", ["vgroove", "none"])
@pytest.mark.parametrize("deg", [30.0, 75.0, 88.0])
def test_monte_carlo_albedo_matches_quadrature(geometry, deg):
    m = ct(geometry=geometry)
    det = halfvector_albedo(m, math.radians(deg), 0.1)
    mean, err = mc_albedo(m, math.radians(deg))
    assert abs(mean - det) < 5 * err + 1e-12


def test_beckmann_sampler_slopes_are_gaussian():
    # Closed form: Beckmann slopes -hx/hz, -hy/hz are N(0, m^2/2) (independent truth).
    from scipy import stats
    m = 0.3
    u = np.random.default_rng(5).random((2, 20000))
    h = warps.beckmann_half_vector(NP, m, m, u[0], u[1])
    for s in (h[0] / h[2], h[1] / h[2]):
        assert stats.kstest(s, "norm", args=(0, m / math.sqrt(2))).pvalue > 1e-3
    # broken input: the wrong width is rejected
    assert stats.kstest(h[0] / h[2], "norm", args=(0, m)).pvalue < 1e-6


# -- contract ---------------------------------------------------------------------

@pytest.mark.parametrize("kw", [dict(), dict(geometry="none"), dict(fresnel="schlick", rs=[0.9, 0.6, 0.3]),
                                dict(fresnel="conductor", eta=[0.2, 0.9, 1.1], k=[3.5, 2.4, 2.3], m=0.4)])
def test_reciprocity_and_sampling_consistency(kw):
    m = ct(**kw)
    check_reciprocal(m)
    for wi in ([0.0, 0.0, 1.0], [0.6, 0.2, 0.5], [0.99, 0.0, 0.05]):
        check_sampling(m, wi)


def test_fresnel_choices():
    wi = np.array([math.sin(1.0), 0.0, math.cos(1.0)]); wo = np.array([-wi[0], 0.0, wi[2]])
    base = ct(geometry="none").eval(wi, wo)
    # Schlick at wi.h = cos(theta_i) at the mirror direction.
    sch = ct(geometry="none", fresnel="schlick", rs=0.04).eval(wi, wo)
    assert sch == pytest.approx(base * (0.04 + 0.96 * (1 - math.cos(1.0)) ** 5), rel=1e-12)
    g = ct(geometry="none", fresnel="conductor", eta=0.2, k=3.0).eval(wi, wo)
    assert g == pytest.approx(base * plausible.fresnel.conductor(NP, math.cos(1.0), 0.2, 3.0), rel=1e-12)


def test_bad_inputs():
    for kw, name in [(dict(m=0.0), "m"), (dict(m=-1), "m"), (dict(rs=1.5), "rs"),
                     (dict(geometry="smith"), "geometry"), (dict(fresnel="x"), "fresnel")]:
        with pytest.raises(ValueError, match=name):
            plausible.make("cook-torrance", **kw)


def test_registry_entry():
    info = plausible.info("cook-torrance")
    assert info.reciprocal and not info.energy_conserving


@pytest.mark.parametrize("kw", [dict(), dict(geometry="none", fresnel="schlick", rs=0.5)])
def test_numpy_and_drjit_agree(kw):
    check_drjit(ct(**kw))


# -- the Blinn distribution (the reading of Wavefront MTL's highlight) ------------------

@pytest.mark.parametrize("m", [0.05, 0.3, 1.0])
def test_blinn_d_integrates_to_one_against_cos_and_is_the_power_of_n_dot_h(m):
    from plausible.models.cook_torrance import blinn_d, blinn_exponent

    n = blinn_exponent(m)
    d = lambda t: blinn_d(NP, (math.sin(t), 0.0, math.cos(t)), m)  # noqa: E731
    val, _ = integrate.quad(lambda t: 2 * math.pi * math.sin(t) * math.cos(t) * d(t), 0, math.pi / 2,
                            points=[min(m, 1.0)], limit=200, epsabs=1e-13)
    assert val == pytest.approx(1.0, abs=1e-9)
    # closed form: (n + 2) / (2 pi) cos^n
    for t in (0.0, 0.3 * m, m, 1.2):
        assert d(t) == pytest.approx((n + 2) / (2 * math.pi) * math.cos(t) ** n, rel=1e-10)


@pytest.mark.parametrize("kw", [dict(m=0.3), dict(m=0.05, geometry="none"), dict(m=0.7)])
def test_blinn_reciprocity_sampling_and_drjit(kw):
    m = ct(distribution="blinn", **kw)
    check_reciprocal(m)
    for wi in ([0.0, 0.0, 1.0], [0.6, 0.2, 0.5], [0.99, 0.0, 0.05]):
        check_sampling(m, wi)
    check_drjit(m)


@pytest.mark.parametrize("deg", [0.0, 60.0, 85.0])
def test_blinn_monte_carlo_albedo_matches_quadrature_and_differs_from_beckmann(deg):
    m = ct(distribution="blinn", m=0.6, geometry="vgroove")
    det = halfvector_albedo(m, math.radians(deg), 0.6)
    mean, err = mc_albedo(m, math.radians(deg))
    assert abs(mean - det) < 5 * err + 1e-12
    # the broken input: Beckmann's D of the same slope is another surface at m = 0.6
    beck = ct(m=0.6, geometry="vgroove")
    assert abs(mc_albedo(beck, 0.0)[0] - halfvector_albedo(m, 0.0, 0.6)) > 0.02
