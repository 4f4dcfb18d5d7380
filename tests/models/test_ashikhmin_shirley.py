"""Tests of the Ashikhmin-Shirley models against independent truths.

Truths used: closed forms derived by hand (peak value, diffuse albedo, albedo at
normal incidence, half-maximum widths along the tangents), SciPy quadrature of
the model's ``eval`` or of the papers' ``p_h`` written out here, exact
symmetries (reciprocity), and Monte Carlo with fixed seeds and an n-sigma
tolerance from the sample variance.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from reference import hooks_agree, mc_albedos as mc_albedo
from scipy import integrate, optimize, special, stats

from plausible import registry, warps
from plausible.directions import as_directions
from plausible.models.ashikhmin_shirley import (
    AshikhminShirley,
    AshikhminShirleyDiffuse,
    AshikhminShirleySpecular,
    half_vector_density,
    half_vector_exponent,
)
from plausible.arrays.ops import NP

SQRT_HALF = math.sqrt(0.5)


# -- helpers --------------------------------------------------------------------------

def hemisphere(rng, n):
    """Uniformly random unit directions with z > 0."""
    a = rng.normal(size=(n, 3))
    a[:, 2] = np.abs(a[:, 2]) + 1e-12
    return a / np.linalg.norm(a, axis=1, keepdims=True)


def direction(theta_deg, phi_deg=0.0):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def normal_incidence_albedo_truth(nu, nv):
    """Albedo at ``wi = n`` of the specular term with ``rs = 1``, derived by hand.

    With ``k1 = n``: ``max(n.k1, n.k2) = 1``, ``F = 1`` and
    ``rho_s cos d omega_2 = p_h(h) (n.k2) d omega_h`` (the ``4 (k.h)`` of the
    change of measure cancels the one in the BRDF); ``n.k2 = 2 (n.h)^2 - 1`` is
    positive for ``n.h > 1/sqrt(2)``.  With ``x = n.h`` and
    ``e(phi) = nu cos^2 phi + nv sin^2 phi``:

    ``a = sqrt((nu+1)(nv+1))/(2 pi) int_0^{2 pi} int_{1/sqrt 2}^1 x^e (2x^2 - 1) dx dphi``

    and the inner integral is ``2 (1 - s^(e+3)) / (e+3) - (1 - s^(e+1)) / (e+1)``
    with ``s = 1/sqrt(2)``.  The outer integral by SciPy quad (isotropic: exact).
    """
    c = math.sqrt((nu + 1.0) * (nv + 1.0)) / (2.0 * math.pi)

    def inner(phi):
        e = nu * math.cos(phi) ** 2 + nv * math.sin(phi) ** 2
        return (2.0 * (1.0 - SQRT_HALF ** (e + 3.0)) / (e + 3.0)
                - (1.0 - SQRT_HALF ** (e + 1.0)) / (e + 1.0))

    if nu == nv:
        return 2.0 * math.pi * c * inner(0.0)
    # one quadrant times four (e is symmetric in each axis)
    val, _ = integrate.quad(inner, 0.0, 0.5 * math.pi, epsabs=0, epsrel=1e-12, limit=200)
    return 4.0 * c * val


def hemisphere_quadrature(fn, n):
    """``int_{H^2} fn(wo) d omega_o`` by a Gauss-Legendre product rule with ``n``
    nodes in theta_o on [0, pi/2] and ``2n`` in phi_o on [0, 2 pi]
    (vectorised; independent of the sampler).  The horizon is the edge of the
    domain, so an integrand that is cut off there stays smooth inside it."""
    x, w = special.roots_legendre(n)
    th, wt = 0.25 * math.pi * (x + 1), 0.25 * math.pi * w
    x2, w2 = special.roots_legendre(2 * n)
    ph, wp = math.pi * (x2 + 1), math.pi * w2
    T, P = np.meshgrid(th, ph, indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    return float(np.sum(fn(wo) * np.sin(T) * wt[:, None] * wp[None, :]))


def converged_quadrature(fn, n=250, tol=1e-5):
    """:func:`hemisphere_quadrature` at n and 2n nodes; asserts they agree to
    ``tol`` (the error estimate; the kink of max(n.k1, n.k2) inside the domain
    limits the rule to about 1e-6) and returns the finer one."""
    coarse, fine = hemisphere_quadrature(fn, n), hemisphere_quadrature(fn, 2 * n)
    assert abs(fine - coarse) < tol, (coarse, fine)
    return fine


def albedo_quadrature(model, wi):
    """Directional albedo ``int f(wi, wo) (n.wo) d omega_o`` by quadrature of
    the model's eval (moderate exponents)."""
    wi = np.asarray(wi, dtype=float)

    def fn(wo):
        f = model.eval(wi, wo)
        return (f.mean(axis=-1) if f.ndim == wo.ndim else f) * wo[..., 2]

    return converged_quadrature(fn)


# -- registry and parameters ---------------------------------------------------------

def test_registered_with_parameter_specs():
    assert registry.info("ashikhmin-shirley").cls is AshikhminShirley
    assert registry.info("ashikhmin-shirley-specular").cls is AshikhminShirleySpecular
    assert registry.info("ashikhmin-shirley-diffuse").cls is AshikhminShirleyDiffuse
    info = registry.info("ashikhmin-shirley")
    assert [p.name for p in info.params] == ["nu", "nv", "rs", "rd"]
    for name in ("nu", "nv"):
        p = info.param(name)
        assert (p.kind, p.lo, p.hi, p.extremes) == ("scalar", 0.0, 1e6, (0.0, 1.0, 1e4))
    for name in ("rs", "rd"):
        p = info.param(name)
        assert (p.kind, p.lo, p.hi, p.extremes) == ("color", 0.0, 1.0, (0.0, 1.0))
    assert [p.name for p in registry.info("ashikhmin-shirley-specular").params] == ["nu", "nv", "rs"]
    assert [p.name for p in registry.info("ashikhmin-shirley-diffuse").params] == ["rs", "rd"]


@pytest.mark.parametrize("cls, kwargs, name", [
    (AshikhminShirley, dict(nu=-1.0), "nu"),
    (AshikhminShirley, dict(nv=float("nan")), "nv"),
    (AshikhminShirley, dict(nu=2e6), "nu"),
    (AshikhminShirley, dict(rs=1.5), "rs"),
    (AshikhminShirley, dict(rs=[0.2, 1.01, 0.3]), "rs"),
    (AshikhminShirley, dict(rd=-0.1), "rd"),
    (AshikhminShirley, dict(rd=[0.1, float("nan"), 0.1]), "rd"),
    (AshikhminShirleySpecular, dict(nv=-1e-9), "nv"),
    (AshikhminShirleySpecular, dict(rs=2.0), "rs"),
    (AshikhminShirleyDiffuse, dict(rd=1.2), "rd"),
    (AshikhminShirleyDiffuse, dict(rs=float("inf")), "rs"),
])
def test_bad_parameters_raise_naming_the_parameter(cls, kwargs, name):
    with pytest.raises(ValueError, match=f"'{name}'"):
        cls(**kwargs)


# -- values -------------------------------------------------------------------------

@pytest.mark.parametrize("nu, nv", [(0.0, 0.0), (10.0, 10.0), (10.0, 100.0), (1e4, 1.0),
                                    (1.0, 1e4), (1e5, 1e5), (1e5, 3.0), (1e6, 1e6)])
@pytest.mark.parametrize("rs", [0.0, 0.05, 0.5, 1.0])
def test_peak_value_at_normal_incidence(nu, nv, rs):
    """At wi = wo = n the exponent is 0/0; the lobe's limit is its peak:
    ``sqrt((nu+1)(nv+1)) / (8 pi) rs`` (journal eq. 4 with n.h = k.h = 1, F = rs)."""
    n = np.array([0.0, 0.0, 1.0])
    expected = math.sqrt((nu + 1.0) * (nv + 1.0)) / (8.0 * math.pi) * rs
    spec = AshikhminShirleySpecular(nu=nu, nv=nv, rs=rs).eval(n, n)
    assert spec == expected
    full = AshikhminShirley(nu=nu, nv=nv, rs=rs, rd=0.0).eval(n, n)
    assert full == expected
    # and the limit is continuous: approaching the pole from an oblique azimuth
    eps = 1e-7
    wo = np.array([eps * 0.6, eps * 0.8, 1.0])
    near = AshikhminShirleySpecular(nu=nu, nv=nv, rs=rs).eval(n, wo)
    assert near == pytest.approx(expected, rel=1e-8, abs=1e-12)


def test_colour_channels_follow_the_per_channel_formula():
    """A colour evaluates each channel as the scalar model with that channel."""
    rng = np.random.default_rng(5)
    a, b = hemisphere(rng, 500), hemisphere(rng, 500)
    rs, rd = [0.9, 0.5, 0.02], [0.1, 0.7, 1.0]
    col = AshikhminShirley(nu=30, nv=300, rs=rs, rd=rd).eval(a, b)
    for k in range(3):
        scal = AshikhminShirley(nu=30, nv=300, rs=rs[k], rd=rd[k]).eval(a, b)
        np.testing.assert_array_equal(col[:, k], scal)


@pytest.mark.parametrize("nu, nv", [(1e4, 1.0), (1.0, 1e4), (10.0, 100.0), (50.0, 50.0),
                                    (0.0, 0.0), (1e5, 10.0)])
def test_reciprocity_on_random_pairs(nu, nv):
    """f(a, b) == f(b, a) exactly (the formulas are symmetric; the code keeps the
    symmetry bitwise), including strongly anisotropic and grazing pairs."""
    rng = np.random.default_rng(11)
    a, b = hemisphere(rng, 20000), hemisphere(rng, 20000)
    b[:100, 2] = 1e-6  # near-grazing
    m = AshikhminShirley(nu=nu, nv=nv, rs=[0.04, 0.5, 1.0], rd=[1.0, 0.3, 0.0])
    fab, fba = m.eval(a, b), m.eval(b, a)
    assert np.all(np.isfinite(fab)) and np.all(fab >= 0)
    np.testing.assert_array_equal(fab, fba)


@settings(max_examples=40, deadline=None)
@given(nu=st.floats(0.0, 1e5), nv=st.floats(0.0, 1e5), rs=st.floats(0.0, 1.0),
       rd=st.floats(0.0, 1.0), seed=st.integers(0, 2**32 - 1))
def test_reciprocity_and_positivity_property(nu, nv, rs, rd, seed):
    rng = np.random.default_rng(seed)
    a, b = hemisphere(rng, 64), hemisphere(rng, 64)
    m = AshikhminShirley(nu=nu, nv=nv, rs=rs, rd=rd)
    fab = m.eval(a, b)
    np.testing.assert_array_equal(fab, m.eval(b, a))
    assert np.all(np.isfinite(fab)) and np.all(fab >= 0)


def test_zero_below_the_horizon():
    rng = np.random.default_rng(2)
    a, b = hemisphere(rng, 1000), hemisphere(rng, 1000)
    below = b * np.array([1.0, 1.0, -1.0])
    m = AshikhminShirley(nu=10, nv=100, rs=0.3, rd=0.8)
    assert np.all(m.eval(a, below) == 0) and np.all(m.eval(below, a) == 0)
    assert np.all(m.pdf(a, below) == 0) and np.all(m.pdf(below, a) == 0)


def test_specular_matches_journal_eq4_written_out():
    """The implementation (p_h F / (4 (k.h) max)) against journal eq. 4 written
    out directly with NumPy, on random pairs, anisotropic exponents."""
    rng = np.random.default_rng(3)
    a, b = hemisphere(rng, 5000), hemisphere(rng, 5000)
    nu, nv, rs = 40.0, 700.0, 0.2
    h = a + b
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    kh = np.sum(a * h, axis=1)
    e = (nu * h[:, 0] ** 2 + nv * h[:, 1] ** 2) / (1.0 - h[:, 2] ** 2)
    fres = rs + (1 - rs) * (1 - kh) ** 5
    eq4 = (math.sqrt((nu + 1) * (nv + 1)) / (8 * math.pi) * h[:, 2] ** e
           / (kh * np.maximum(a[:, 2], b[:, 2])) * fres)
    got = AshikhminShirleySpecular(nu=nu, nv=nv, rs=rs).eval(a, b)
    np.testing.assert_allclose(got, eq4, rtol=1e-11, atol=1e-300)  # subnormal tail


def test_diffuse_matches_journal_eq5_written_out():
    rng = np.random.default_rng(4)
    a, b = hemisphere(rng, 5000), hemisphere(rng, 5000)
    a[:20, 2] = 1e-7  # near grazing, where 1 - (1 - z/2)^5 cancels in float64
    a /= np.linalg.norm(a, axis=1, keepdims=True)
    rs, rd = 0.3, 0.9
    # the factors written out in exact rational arithmetic, then rounded once
    g = np.vectorize(lambda z: float(1 - (1 - Fraction(float(z)) / 2) ** 5))
    eq5 = 28 * rd / (23 * math.pi) * (1 - rs) * g(a[:, 2]) * g(b[:, 2])
    np.testing.assert_allclose(AshikhminShirleyDiffuse(rs=rs, rd=rd).eval(a, b), eq5,
                               rtol=1e-14, atol=0)


def test_isotropic_fast_path_agrees_with_general_code():
    """nu == nv takes the exponent nu directly; it must agree with the general
    exponent (nu hx^2 + nv hy^2) / (1 - hz^2) and with nv = nu (1 + 1e-15)."""
    rng = np.random.default_rng(6)
    h = hemisphere(rng, 20000)
    h[:50] = np.array([1e-9, 2e-9, 1.0]) / np.linalg.norm([1e-9, 2e-9, 1.0])
    hc = (h[:, 0], h[:, 1], h[:, 2])
    for nu in (0.0, 1.0, 37.0, 1e4, 1e5):
        assert half_vector_exponent(NP, hc, nu, nu) is nu  # the fast path is taken
        fast = half_vector_density(NP, hc, nu, nu)
        general = warps.anisotropic_half_vector_pdf(NP, nu, nu, hc)
        np.testing.assert_allclose(fast, general, rtol=1e-12, atol=0)
        a, b = hemisphere(rng, 5000), hemisphere(rng, 5000)
        nv = nu * (1.0 + 1e-15) if nu else 1e-300
        f_iso = AshikhminShirley(nu=nu, nv=nu, rs=0.4, rd=0.5).eval(a, b)
        f_gen = AshikhminShirley(nu=nu, nv=nv, rs=0.4, rd=0.5).eval(a, b)
        np.testing.assert_allclose(f_iso, f_gen, rtol=1e-11, atol=0)


def test_anisotropy_goes_the_right_way():
    """Larger nu narrows the highlight along x (u).  At normal incidence with
    rs = 1 and wo in the xz plane, h = (sin(t/2), 0, cos(t/2)) and
    f = peak * cos(t/2)^(nu - 1), so the half maximum is at
    t = 2 acos(2^(-1/(nu - 1))) (along y the same with nv)."""
    n = np.array([0.0, 0.0, 1.0])

    def half_width(model, axis):
        peak = float(model.eval(n, n))

        def g(t):
            wo = np.array([0.0, 0.0, math.cos(t)])
            wo[axis] = math.sin(t)
            return float(model.eval(n, wo)) - 0.5 * peak

        return optimize.brentq(g, 1e-9, 0.5 * math.pi - 1e-9, xtol=1e-15, rtol=1e-14)

    for nu, nv in [(100.0, 10.0), (10.0, 100.0), (1e4, 50.0)]:
        m = AshikhminShirleySpecular(nu=nu, nv=nv, rs=1.0)
        wx, wy = half_width(m, 0), half_width(m, 1)
        assert wx == pytest.approx(2 * math.acos(2 ** (-1 / (nu - 1))), rel=1e-9)
        assert wy == pytest.approx(2 * math.acos(2 ** (-1 / (nv - 1))), rel=1e-9)
        assert (wx < wy) == (nu > nv)


# -- diffuse albedo --------------------------------------------------------------------

@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 85.0, 89.99])
@pytest.mark.parametrize("rs, rd", [(0.0, 1.0), (0.05, 0.8), (0.5, 0.3)])
def test_diffuse_directional_albedo_closed_form(theta, rs, rd):
    """a_d(theta) = rd (1 - rs) (1 - (1 - cos(theta)/2)^5), against SciPy quad of
    the model's eval over mu = cos(theta_o) (the term is isotropic in wo)."""
    m = AshikhminShirleyDiffuse(rs=rs, rd=rd)
    wi = direction(theta, 20.0)

    def integrand(mu):
        wo = np.array([math.sqrt(max(1 - mu * mu, 0.0)), 0.0, mu])
        return float(m.eval(wi, wo)) * mu

    quad, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0, epsrel=1e-13)
    closed = rd * (1 - rs) * (1 - (1 - math.cos(math.radians(theta)) / 2) ** 5)
    assert 2 * math.pi * quad == pytest.approx(closed, rel=1e-11, abs=1e-15)


def test_diffuse_hemispherical_albedo_is_23_over_28():
    """(1/pi) int a_d(theta) cos(theta) d omega = 23/28 rd (1 - rs): quad over mu
    of the model's eval (a double integral, since a_d itself is integrated)."""
    rs, rd = 0.2, 0.9
    m = AshikhminShirleyDiffuse(rs=rs, rd=rd)

    def f(mu_o, mu_i):
        wi = np.array([math.sqrt(1 - mu_i * mu_i), 0.0, mu_i])
        wo = np.array([0.0, math.sqrt(1 - mu_o * mu_o), mu_o])
        return float(m.eval(wi, wo)) * mu_o * mu_i

    val, _ = integrate.dblquad(f, 0.0, 1.0, 0.0, 1.0, epsabs=0, epsrel=1e-12)
    hemi = (2 * math.pi) ** 2 * val / math.pi
    assert hemi == pytest.approx(23 / 28 * rd * (1 - rs), rel=1e-10)


def test_diffuse_monte_carlo_albedo():
    m = AshikhminShirleyDiffuse(rs=0.05, rd=[1.0, 0.5, 0.2])
    th = np.radians([0.0, 50.0, 88.0])
    wi = np.stack([np.sin(th), 0 * th, np.cos(th)], -1)
    mean, se = mc_albedo(m, wi, 100000, seed=7)
    closed = np.mean([1.0, 0.5, 0.2]) * 0.95 * (1 - (1 - np.cos(th) / 2) ** 5)
    assert np.all(np.abs(mean - closed) <= 4 * se + 1e-12)


# -- energy -------------------------------------------------------------------------------

EXPONENTS = (0.0, 1.0, 10.0, 100.0, 1000.0, 10000.0)
INCIDENCES = np.radians([0.0, 60.0, 85.0, 89.9])


def _energy_cases():
    pairs = [(e, e) for e in EXPONENTS] + [(1e4, 1.0), (1.0, 1e4), (10.0, 1000.0), (1000.0, 0.0)]
    materials = [dict(rs=1.0, rd=0.0)] + [dict(rs=rs, rd=1.0) for rs in (0.0, 0.05, 0.5)]
    return [(pair, kw) for kw in materials for pair in pairs]


def test_energy_conservation_monte_carlo():
    """Albedo (model's own sampler, 2e5 samples per incidence, fixed seed)
    <= 1 + 4 sigma for rs = 1, rd = 0 and rs in {0, 0.05, 0.5}, rd = 1, over the
    isotropic exponents {0, 1, 10, ..., 1e4} and four anisotropic pairs, at
    incidences 0, 60, 85 and 89.9 degrees."""
    wi = np.stack([np.sin(INCIDENCES), 0 * INCIDENCES, np.cos(INCIDENCES)], -1)
    worst = -np.inf
    for k, ((nu, nv), kw) in enumerate(_energy_cases()):
        m = AshikhminShirley(nu=nu, nv=nv, **kw)
        mean, se = mc_albedo(m, wi, 200000, seed=1000 + k)
        assert np.all(mean <= 1.0 + 4 * se), (nu, nv, kw, mean, se)
        worst = max(worst, float(np.max(mean - 4 * se)))
    assert worst > 0.99  # the grid reaches near-lossless cases (sanity of the sweep)


@pytest.mark.parametrize("rs, rd", [(0.05, 0.0), (0.5, 0.5), (0.0, 0.3)])
def test_albedo_below_the_derived_bound(rs, rd):
    """Sharper than <= 1 (derivation in the docs): the specular albedo is at most
    F(k.h_min) <= F(cos(theta_i) / 2) since p_h integrates to one and
    k.h >= cos(theta_i)/2 for every wo above the horizon, so
    a(theta_i) <= 1 - (1 - rs)(1 - rd)(1 - (1 - cos(theta_i)/2)^5)."""
    wi = np.stack([np.sin(INCIDENCES), 0 * INCIDENCES, np.cos(INCIDENCES)], -1)
    bound = 1 - (1 - rs) * (1 - rd) * (1 - (1 - np.cos(INCIDENCES) / 2) ** 5)
    for k, n in enumerate((0.0, 10.0, 1000.0)):
        mean, se = mc_albedo(AshikhminShirley(nu=n, nv=n, rs=rs, rd=rd), wi, 100000, seed=50 + k)
        assert np.all(mean <= bound + 4 * se), (n, mean, bound)


def test_energy_checker_flags_a_model_that_creates_energy():
    """The same check must fail for a model scaled by 1.1 (broken on purpose)."""

    class Brighter(AshikhminShirley):
        def _f(self, ops, wi, wo, p):
            return 1.1 * super()._f(ops, wi, wo, p)

    m = Brighter(nu=1000.0, nv=1000.0, rs=1.0, rd=0.0)
    mean, se = mc_albedo(m, direction(0.0), 200000, seed=1)
    assert np.any(mean > 1.0 + 4 * se)


# -- albedo: closed forms and a second method -----------------------------------------

def test_furnace_sphere_centre_albedo():
    """Tech. report Fig. 2: rs = 1, rd = 0, nu = nv = 10 in a furnace; the sphere
    centre shows the albedo at normal incidence.  Closed form (see
    normal_incidence_albedo_truth) = 0.69571, against SciPy quad of the model's
    eval and Monte Carlo with its sampler.  The paper says "about 68%"."""
    truth = normal_incidence_albedo_truth(10.0, 10.0)
    s = SQRT_HALF
    assert truth == pytest.approx(11 * (2 * (1 - s ** 13) / 13 - (1 - s ** 11) / 11), rel=1e-14)
    m = AshikhminShirley(nu=10.0, nv=10.0, rs=1.0, rd=0.0)
    n = np.array([0.0, 0.0, 1.0])

    def integrand(mu):  # isotropic lobe at normal incidence: integrate over mu
        return float(m.eval(n, np.array([math.sqrt(max(1 - mu * mu, 0)), 0.0, mu]))) * mu

    quad, _ = integrate.quad(integrand, 0.0, 1.0, epsabs=0, epsrel=1e-13, limit=200)
    assert 2 * math.pi * quad == pytest.approx(truth, rel=1e-10)
    mean, se = mc_albedo(m, n, 400000, seed=3)
    assert abs(mean[0] - truth) <= 4 * se[0]
    assert truth == pytest.approx(0.6957072441, abs=1e-9)  # the number in the docs
    assert abs(truth - 0.68) < 0.02  # the paper's "about 68%" holds to 2 points


@pytest.mark.parametrize("nu, nv", [(10.0, 10.0), (10.0, 100.0), (1e4, 1.0),
                                    (1e5, 1e5), (1e5, 10.0), (1e6, 1e6)])
def test_normal_incidence_albedo_closed_form_vs_monte_carlo(nu, nv):
    """Large exponents (up to 1e6) work: the sampler's albedo matches the
    closed form (outer quad over phi for nu != nv) within 4 sigma."""
    truth = normal_incidence_albedo_truth(nu, nv)
    m = AshikhminShirleySpecular(nu=nu, nv=nv, rs=1.0)
    mean, se = mc_albedo(m, direction(0.0), 200000, seed=int(nu + 7 * nv) % 2**31)
    assert abs(mean[0] - truth) <= 4 * se[0] + 1e-13
    if nu == nv:
        # and the large-n limit of the closed form, 1 - 4 / (n + 3) + O(2^(-n/2))
        assert truth == pytest.approx(
            2 * (nu + 1) / (nu + 3) - 1 + (nu + 1) * (SQRT_HALF ** (nu + 1) / (nu + 1)
                                                     - 2 * SQRT_HALF ** (nu + 3) / (nu + 3)),
            rel=1e-12)


@pytest.mark.parametrize("nu, nv", [(10.0, 10.0), (1e5, 10.0)])
def test_cross_check_with_plausible_analysis(nu, nv):
    """The project's adaptive albedo integrator against the closed form."""
    analysis = pytest.importorskip("plausible.analysis")
    r = analysis.albedo(AshikhminShirleySpecular(nu=nu, nv=nv, rs=1.0), np.array([0.0, 0.0, 1.0]))
    truth = normal_incidence_albedo_truth(nu, nv)
    assert abs(float(r.value) - truth) <= max(float(r.error), 1e-12)


@pytest.mark.parametrize("model, theta, phi", [
    (AshikhminShirley(nu=10.0, nv=100.0, rs=0.05, rd=0.8), 60.0, 30.0),
    (AshikhminShirley(nu=5.0, nv=5.0, rs=0.5, rd=1.0), 80.0, 0.0),
    (AshikhminShirleySpecular(nu=100.0, nv=3.0, rs=[0.9, 0.6, 0.3]), 45.0, 70.0),
])
def test_albedo_monte_carlo_vs_quadrature(model, theta, phi):
    """Two methods: Gauss-Legendre quadrature of eval over the hemisphere
    (with its own error estimate) and the model's sampler (eval, pdf and
    sample together)."""
    wi = direction(theta, phi)
    quad = albedo_quadrature(model, wi)
    mean, se = mc_albedo(model, wi, 200000, seed=17)
    assert abs(mean[0] - quad) <= 4 * se[0] + 1e-5


# -- sampling -----------------------------------------------------------------------------

SAMPLING_MODELS = [
    AshikhminShirley(nu=10.0, nv=100.0, rs=0.05, rd=0.8),
    AshikhminShirley(nu=1e4, nv=1.0, rs=[0.9, 0.5, 0.1], rd=[0.0, 0.5, 1.0]),
    AshikhminShirley(nu=0.0, nv=0.0, rs=0.0, rd=0.0),
    AshikhminShirleySpecular(nu=1e5, nv=30.0, rs=0.7),
    AshikhminShirleyDiffuse(rs=0.1, rd=0.6),
]


@pytest.mark.parametrize("model", SAMPLING_MODELS, ids=repr)
def test_sample_consistent_with_pdf_and_eval(model):
    """(a) pdf(wi, sampled wo) equals the returned pdf; (b) weight equals
    eval * cos / pdf; below-horizon samples carry zero weight and pdf.

    Bitwise through the hooks on the directions the sampler used; through the
    public API to 1e-10, because ``pdf``/``eval`` re-normalise ``wo`` (one ulp),
    which a lobe with exponent 1e5 (or Schlick's ``(1 - k.h)^5`` near
    ``k.h = 1``) amplifies to ~1e-12 relative.
    """
    rng = np.random.default_rng(23)
    wi = hemisphere(rng, 50000)
    # NumPy, the backend of the hooks compared bitwise below (``auto`` may pick Dr.Jit)
    s = model.sample(wi, rng.random((50000, 3)), backend="numpy")
    ok = s.pdf > 0
    assert ok.mean() > 0.2
    assert np.all(s.weight[~ok] == 0)
    assert np.all(s.pdf[s.wo[:, 2] <= 0] == 0)
    # hooks, same directions: exact
    wn = as_directions("wi", wi)
    wi_c, wo_c = (wn[:, 0], wn[:, 1], wn[:, 2]), (s.wo[:, 0], s.wo[:, 1], s.wo[:, 2])
    pdf = model._pdf(NP, wi_c, wo_c, model.q)
    np.testing.assert_array_equal(np.broadcast_to(pdf, ok.shape)[ok], s.pdf[ok])
    col = (lambda c: tuple(x[:, None] for x in c)) if model.channels else (lambda c: c)
    f = np.broadcast_to(model._f(NP, col(wi_c), col(wo_c), model.p), s.weight.shape)
    ratio = s.wo[:, 2] / np.where(ok, s.pdf, 1.0)
    w = f * (ratio[:, None] if model.channels else ratio)
    np.testing.assert_array_equal(s.weight[ok], w[ok])
    # public API
    np.testing.assert_allclose(model.pdf(wi, s.wo)[ok], s.pdf[ok], rtol=1e-10, atol=0)
    fp = model.eval(wi, s.wo)
    w = fp * (ratio[:, None] if model.channels else ratio)
    np.testing.assert_allclose(s.weight[ok], w[ok], rtol=1e-10, atol=0)


def test_pdf_integrates_to_the_fraction_of_samples_above_the_horizon():
    """int_{H^2} pdf d omega (quadrature) == P(wo above) (MC)."""
    m = AshikhminShirley(nu=5.0, nv=40.0, rs=0.3, rd=0.5)
    wi = direction(75.0, 40.0)
    total = converged_quadrature(lambda wo: m.pdf(wi, wo))
    n = 200000
    s = m.sample(wi, np.random.default_rng(29).random((n, 3)))
    frac = np.mean(s.wo[:, 2] > 0)
    assert abs(frac - total) <= 4 * math.sqrt(total * (1 - total) / n) + 1e-9
    assert total < 1.0 - 1e-3  # part of the specular lobe is below the horizon here


def _cell_probabilities(nu, nv, c_edges, phi_edges):
    """Probability of each (cos theta_h, phi_h) cell under
    p_h = sqrt((nu+1)(nv+1))/(2 pi) cos^e(theta), e = nu cos^2 phi + nv sin^2 phi
    (journal eq. 6, written out here): the integral over cos(theta) is
    analytic, the one over phi by SciPy quad."""
    c = math.sqrt((nu + 1) * (nv + 1)) / (2 * math.pi)
    probs = np.empty((len(c_edges) - 1, len(phi_edges) - 1))
    for i in range(len(c_edges) - 1):
        c0, c1 = c_edges[i], c_edges[i + 1]

        def g(phi):
            e = nu * math.cos(phi) ** 2 + nv * math.sin(phi) ** 2
            return c * (c1 ** (e + 1) - c0 ** (e + 1)) / (e + 1)

        for j in range(len(phi_edges) - 1):
            probs[i, j] = integrate.quad(g, phi_edges[j], phi_edges[j + 1],
                                         epsabs=0, epsrel=1e-12)[0]
    return probs


def half_vector_chi2_pvalue(h, nu, nv, n_c=12, n_phi=16):
    """Chi-square test of sampled half vectors ``h`` (N, 3) against p_h."""
    c_edges = np.linspace(0.0, 1.0, n_c + 1) ** (1.0 / 31.0)
    c_edges[0], c_edges[-1] = 0.0, 1.0
    phi_edges = np.linspace(0.0, 2 * math.pi, n_phi + 1)
    probs = _cell_probabilities(nu, nv, c_edges, phi_edges)
    assert probs.sum() == pytest.approx(1.0, abs=1e-10)
    phi = np.mod(np.arctan2(h[:, 1], h[:, 0]), 2 * math.pi)
    counts, _, _ = np.histogram2d(h[:, 2], phi, bins=[c_edges, phi_edges])
    expected = probs * len(h)
    counts, expected = counts.ravel(), expected.ravel()
    small = expected < 5
    obs = np.append(counts[~small], counts[small].sum())
    exp = np.append(expected[~small], expected[small].sum())
    if exp[-1] == 0:
        obs, exp = obs[:-1], exp[:-1]
    chi2 = np.sum((obs - exp) ** 2 / exp)
    return stats.chi2.sf(chi2, len(obs) - 1)


def _model_half_vectors(model, n, seed):
    n_dir = np.array([0.0, 0.0, 1.0])
    s = model.sample(n_dir, np.random.default_rng(seed).random((n, 3)))
    h = s.wo + n_dir  # at normal incidence k1.h = h.z > 0, so h is recovered
    return h / np.linalg.norm(h, axis=1, keepdims=True)


@pytest.mark.parametrize("nu, nv", [(10.0, 100.0), (100.0, 10.0), (20.0, 20.0)])
def test_sampled_half_vectors_chi_square(nu, nv):
    h = _model_half_vectors(AshikhminShirleySpecular(nu=nu, nv=nv, rs=1.0), 200000, seed=31)
    assert half_vector_chi2_pvalue(h, nu, nv) > 1e-3


def test_chi_square_rejects_swapped_exponents():
    h = _model_half_vectors(AshikhminShirleySpecular(nu=100.0, nv=10.0, rs=1.0), 200000, seed=31)
    assert half_vector_chi2_pvalue(h, 10.0, 100.0) < 1e-12


def test_chi_square_rejects_a_dropped_quadrant():
    """A sampler that maps u1 into the first quadrant only (quadrant logic lost)."""
    u = np.random.default_rng(37).random((200000, 2))
    hx, hy, hz = warps.anisotropic_half_vector(NP, 10.0, 100.0, 0.25 * u[:, 0], u[:, 1])
    h = np.stack([hx, hy, hz], -1)
    assert half_vector_chi2_pvalue(h, 10.0, 100.0) < 1e-12


def test_chi_square_rejects_a_wrong_theta_warp():
    """cos(theta) with exponent 1/(e + 2) instead of 1/(e + 1) (journal eq. 10)."""
    u = np.random.default_rng(41).random((200000, 2))
    nu, nv = 10.0, 100.0
    hx, hy, hz = warps.anisotropic_half_vector(NP, nu, nv, u[:, 0], u[:, 1])
    phi = np.arctan2(hy, hx)
    e = nu * np.cos(phi) ** 2 + nv * np.sin(phi) ** 2
    cz = (1 - u[:, 1]) ** (1 / (e + 2))
    sz = np.sqrt(1 - cz * cz)
    h = np.stack([sz * np.cos(phi), sz * np.sin(phi), cz], -1)
    assert half_vector_chi2_pvalue(h, nu, nv) < 1e-12


def test_mixture_probability_is_per_direction_and_guarded():
    """ps = Fs / (Fs + Ad) depends on wi; pure metal (rs = 1) or rd = 0 never
    samples the cosine lobe; rd > 0 with rs < 1 always can (ps < 1)."""
    from plausible.models.ashikhmin_shirley import specular_probability

    c = np.array([1.0, 0.7, 0.2, 1e-3, 0.0])
    ps = specular_probability(NP, c, 0.05, 0.8)
    fs = 0.05 + 0.95 * (1 - c) ** 5
    ad = 0.8 * 0.95 * (1 - (1 - c / 2) ** 5)
    np.testing.assert_allclose(ps[:4], (fs / (fs + ad))[:4], rtol=1e-13)
    assert np.all(np.diff(ps) > 0) and np.all(ps[:4] < 1)
    assert ps[4] == 1.0  # at the horizon both estimates vanish (Fs = 1, Ad = 0)
    assert np.all(specular_probability(NP, c, 1.0, 0.8) == 1.0)
    # rs = rd = 0 at normal incidence: 0/0, guarded to 1 (the diffuse term is zero)
    assert specular_probability(NP, np.array([1.0]), 0.0, 0.0)[0] == 1.0


# -- NumPy vs Dr.Jit ----------------------------------------------------------------

@pytest.mark.drjit
@pytest.mark.parametrize("model", [
    AshikhminShirley(nu=10.0, nv=1000.0, rs=0.3, rd=0.6),
    AshikhminShirley(nu=50.0, nv=50.0, rs=0.05, rd=1.0),
    AshikhminShirleySpecular(nu=1e4, nv=1.0, rs=0.9),
    AshikhminShirleyDiffuse(rs=0.2, rd=0.7),
], ids=repr)
def test_numpy_and_drjit_agree(model):
    rng = np.random.default_rng(43)
    a, b, u = hemisphere(rng, 4000), hemisphere(rng, 4000), rng.random((4000, 3))
    a[0] = b[0] = [0.0, 0.0, 1.0]  # the pole (0/0 in the exponent)
    hooks_agree(model, a, b, u, rtol=1e-12, atol=1e-300, rtol_sample=1e-12, atol_sample=1e-14, finite=True)
