"""Tests of Schlick's 1994 inexpensive BRDF (single slope + Lambert).

Truths used: values computed by hand from the paper's formulas (the arithmetic
written out below on literal numbers, not by calling the module), the
normalisations of Z and A (closed form and scipy quadrature), the complete
elliptic integral for the square-root azimuth variant, the closed-form CDF of
Schlick's zenith sampler (Kolmogorov-Smirnov), symmetry (reciprocity),
deterministic Gauss-Legendre quadrature vs Monte Carlo with fixed seeds, and a
chi-square test of the sampled directions against the integrated pdf.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy import integrate, special, stats

from reference import TWO_PI, chi2_sampler_pvalue, hooks_agree, from_angles, quad_albedo, unit

import plausible
from plausible.models import schlick as S
from plausible.arrays.ops import NP



class WrongRoughness(S.Schlick):
    """Deliberately broken: draws half vectors with 1.5 r but reports the pdf for r."""

    def _sample(self, ops, wi, u, q):
        q2 = SimpleNamespace(**{**vars(q), "r": 1.5 * q.r})
        return super()._sample(ops, wi, u, q2)


# -- values by hand ---------------------------------------------------------------------

def hand_value(L, V, r, p, rs, rd, root):
    """Schlick 1994 single slope + Lambert, every step written out with math.*."""
    lx, ly, lz = L
    vx, vy, vz = V
    hx, hy, hz = lx + vx, ly + vy, lz + vz
    hn = math.sqrt(hx * hx + hy * hy + hz * hz)
    hx, hy, hz = hx / hn, hy / hn, hz / hn
    t = hz
    u = lx * hx + ly * hy + lz * hz
    v, vp = lz, vz
    w = hx / math.sqrt(hx * hx + hy * hy)
    Z = r / (1 + r * t * t - t * t) ** 2
    A = p / (p * p - p * p * w * w + w * w)
    if root:
        A = math.sqrt(A)
    G = v / (r - r * v + v) * (vp / (r - r * vp + vp))
    F = rs + (1 - rs) * (1 - u) ** 5
    return rd / math.pi + F * G * Z * A / (4 * math.pi * v * vp)


L1 = (0.3 / math.sqrt(0.94), 0.2 / math.sqrt(0.94), 0.9 / math.sqrt(0.94))
V1 = (-0.4 / math.sqrt(0.81), 0.1 / math.sqrt(0.81), 0.8 / math.sqrt(0.81))
L2 = (math.sin(math.radians(70)), 0.0, math.cos(math.radians(70)))
V2 = (-math.sin(math.radians(60)) * math.cos(math.radians(30)),
      -math.sin(math.radians(60)) * math.sin(math.radians(30)), math.cos(math.radians(60)))


@pytest.mark.parametrize("L, V", [(L1, V1), (L2, V2), (V1, L2)])
@pytest.mark.parametrize("r, p, rs, rd", [(0.3, 0.6, 0.1, 0.2), (0.05, 0.2, 0.9, 0.0), (1.0, 1.0, 0.04, 0.5)])
@pytest.mark.parametrize("form", ["normalised", "sqrt"])
def test_values_by_hand(L, V, r, p, rs, rd, form):
    m = plausible.make("schlick", r=r, p=p, rs=rs, rd=rd, azimuth=form)
    expect = hand_value(L, V, r, p, rs, rd, form == "sqrt")
    np.testing.assert_allclose(m.eval(L, V), expect, rtol=1e-12)


def test_value_normal_incidence_by_hand():
    """L = V = n: h = n, t = u = v = v' = 1, w undefined (A = 1, its mean),
    F(1) = rs, G(1) = 1, Z(1) = r / r^2 = 1 / r: f = rd / pi + rs / (4 pi r)."""
    r, rs, rd = 0.25, 0.3, 0.1
    m = plausible.make("schlick", r=r, p=0.5, rs=rs, rd=rd)
    np.testing.assert_allclose(m.eval([0, 0, 1], [0, 0, 1]),
                               rd / math.pi + rs * (1 / r) / (4 * math.pi), rtol=1e-13)


def test_colour_channels_by_hand():
    m = plausible.make("schlick", r=0.3, p=0.6, rs=[0.1, 0.5, 0.9], rd=[0.2, 0.1, 0.0])
    got = m.eval(L1, V1)
    expect = [hand_value(L1, V1, 0.3, 0.6, rs, rd, False) for rs, rd in [(0.1, 0.2), (0.5, 0.1), (0.9, 0.0)]]
    np.testing.assert_allclose(got, expect, rtol=1e-12)


def test_reciprocity_random_pairs():
    rng = np.random.default_rng(4)
    for kw in [dict(r=0.1, p=0.3, rs=0.5, rd=0.1), dict(r=0.7, p=1.0, rs=[0.2, 0.9, 0.4], rd=0.0, azimuth="sqrt")]:
        m = plausible.make("schlick", **kw)
        wi = unit(rng.normal(size=(5000, 3)) * [1, 1, 0] + [0, 0, 1] * rng.random((5000, 1)))
        wo = unit(rng.normal(size=(5000, 3)) * [1, 1, 0] + [0, 0, 1] * rng.random((5000, 1)))
        np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12, atol=0)
    assert m.info.reciprocal


def test_below_horizon_zero():
    m = plausible.make("schlick")
    assert float(m.eval([0.3, 0, 0.9], [0.3, 0, -0.9])) == 0.0
    assert float(m.pdf([0.3, 0, -0.9], [0.3, 0, 0.9])) == 0.0


# -- normalisations ---------------------------------------------------------------------

@pytest.mark.parametrize("r", [0.001, 0.05, 0.3, 1.0])
def test_zenith_normalised(r):
    """int_0^1 2 Z(t) t dt = 1 (scipy), and the closed-form CDF r t^2 / (1 + (r - 1) t^2)."""
    z = lambda t: 2.0 * S.zenith(NP, 1.0 - t * t, r) * t
    val, err = integrate.quad(z, 0.0, 1.0, points=[1.0 - math.sqrt(r)] if r < 1 else None, limit=200,
                              epsabs=1e-13, epsrel=1e-12)
    assert val == pytest.approx(1.0, abs=1e-9)
    part, _ = integrate.quad(z, 0.0, 0.7, limit=200, epsabs=1e-13)
    assert part == pytest.approx(r * 0.49 / (1 + (r - 1) * 0.49), rel=1e-9)


@pytest.mark.parametrize("p", [0.01, 0.1, 0.5, 1.0])
def test_azimuth_normalised(p):
    """(1 / 2 pi) int_0^{2 pi} A(cos phi) d phi = 1 for A = p / (p^2 - p^2 w^2 + w^2)."""
    a = lambda ph: float(S.azimuth_normalised(NP, math.cos(ph), math.sin(ph), p))
    val, _ = integrate.quad(a, 0.0, TWO_PI, points=[math.pi / 2, 3 * math.pi / 2], limit=400, epsrel=1e-12)
    assert val / TWO_PI == pytest.approx(1.0, abs=1e-9)


@pytest.mark.parametrize("p", [0.1, 0.5])
def test_sqrt_azimuth_is_not_normalised(p):
    """The square-root form integrates to sqrt(p) 4 K(1 - p^2) / (2 pi) < 1 (complete
    elliptic integral), which is why it is not the default."""
    a = lambda ph: float(S.azimuth(NP, math.cos(ph), math.sin(ph), p, "sqrt"))
    val, _ = integrate.quad(a, 0.0, TWO_PI, points=[math.pi / 2, 3 * math.pi / 2], limit=400, epsrel=1e-12)
    closed = math.sqrt(p) * 4.0 * special.ellipk(1.0 - p * p) / TWO_PI
    assert val / TWO_PI == pytest.approx(closed, rel=1e-9)
    assert closed < 0.98


@pytest.mark.parametrize("r, p", [(0.05, 1.0), (0.2, 0.3), (1.0, 0.05)])
def test_half_vector_density_integrates_to_one(r, p):
    def integrand(phi, mu):
        s = math.sqrt(1 - mu * mu)
        return float(S.half_vector_pdf(NP, (s * math.cos(phi), s * math.sin(phi), mu), r, p))
    val, _ = integrate.dblquad(integrand, 0.0, 1.0, 0.0, TWO_PI, epsabs=1e-10, epsrel=1e-9)
    assert val == pytest.approx(1.0, abs=1e-7)


def test_half_vector_sampler_distribution():
    """KS tests of the sampled half vectors against the closed-form CDFs:
    t^2 has CDF r x / (1 + (r - 1) x) and phi (first quadrant, folded) has CDF
    (2 / pi) atan(p tan phi)."""
    r, p = 0.15, 0.3
    u = np.random.default_rng(21).random((50_000, 2))
    h = np.stack(S.sample_half_vector(NP, r, p, u[:, 0], u[:, 1]), axis=-1)
    np.testing.assert_allclose(np.linalg.norm(h, axis=-1), 1.0, atol=1e-12)
    t2 = h[:, 2] ** 2
    assert stats.kstest(t2, lambda x: r * x / (1 + (r - 1) * x)).pvalue > 1e-3
    phi = np.arctan2(np.abs(h[:, 1]), np.abs(h[:, 0]))
    assert stats.kstest(phi, lambda x: 2 / math.pi * np.arctan(p * np.tan(x))).pvalue > 1e-3
    # and the checker rejects the wrong isotropy
    assert stats.kstest(phi, lambda x: 2 / math.pi * np.arctan(1.3 * p * np.tan(x))).pvalue < 1e-6


# -- sampling ---------------------------------------------------------------------------

MODELS = [dict(r=0.2, p=0.5, rs=0.6, rd=0.2), dict(r=0.05, p=1.0, rs=0.9, rd=0.05),
          dict(r=0.4, p=0.1, rs=[0.3, 0.5, 0.7], rd=[0.3, 0.2, 0.1], azimuth="sqrt")]


@pytest.mark.parametrize("kw", MODELS)
@pytest.mark.parametrize("theta", [10.0, 60.0])
def test_sample_weight_and_pdf_consistent(kw, theta):
    m = plausible.make("schlick", **kw)
    wi = from_angles(theta, 35.0)
    s = m.sample(wi, np.random.default_rng(3).random((20_000, 3)))
    ok = s.pdf > 0
    assert ok.mean() > 0.6
    np.testing.assert_allclose(s.pdf[ok], m.pdf(wi, s.wo[ok]), rtol=1e-12)
    f = m.eval(wi, s.wo[ok])
    ratio = (s.wo[ok, 2] / s.pdf[ok])
    np.testing.assert_allclose(s.weight[ok], f * (ratio[:, None] if f.ndim == 2 else ratio), rtol=1e-12)


@pytest.mark.parametrize("kw", MODELS[:2])
@pytest.mark.parametrize("theta", [0.0, 45.0, 75.0])
def test_mc_albedo_matches_quadrature(kw, theta):
    m = plausible.make("schlick", **kw)
    wi = from_angles(theta, 20.0)
    q = quad_albedo(m, wi)
    n = 200_000
    w = m.sample(wi, np.random.default_rng(17).random((n, 3))).weight
    mc, err = float(w.mean()), float(w.std() / math.sqrt(n))
    assert abs(mc - q) < 4 * err, (mc, q, err)


def test_quadrature_against_closed_form_r1():
    """r = p = 1: Z = A = 1, G(v) = v, so f = rd/pi + F(u)/(4 pi); with rs = 1, F = 1 and
    the albedo is rd + 1/4 exactly."""
    m = plausible.make("schlick", r=1.0, p=1.0, rs=1.0, rd=0.3)
    for th in (0.0, 50.0, 85.0):
        assert quad_albedo(m, from_angles(th)) == pytest.approx(0.55, rel=1e-9)


@pytest.mark.parametrize("kw", MODELS)
@pytest.mark.parametrize("theta", [5.0, 65.0])
def test_chi_square_sampler(kw, theta):
    m = plausible.make("schlick", **kw)
    assert chi2_sampler_pvalue(m, from_angles(theta, 30.0)) > 1e-3


def test_chi_square_detects_wrong_roughness():
    m = WrongRoughness(**MODELS[0])
    assert chi2_sampler_pvalue(m, from_angles(40.0, 30.0)) < 1e-8


# -- parameters -------------------------------------------------------------------------

@pytest.mark.parametrize("name, value, text", [
    ("r", 0.0, "'r' must lie in [0.001, 1]"), ("r", 1.5, "'r'"), ("r", float("nan"), "'r'"),
    ("p", 0.0, "'p' must lie in [0.001, 1]"), ("p", 2.0, "'p'"),
    ("rs", -0.1, "'rs'"), ("rs", [0.1, 1.2, 0.3], "'rs'"), ("rd", 1.1, "'rd'"),
    ("azimuth", "root", "'azimuth' must be one of"),
])
def test_bad_parameters(name, value, text):
    with pytest.raises(ValueError) as e:
        plausible.make("schlick", **{name: value})
    assert text in str(e.value)


def test_registry_flags():
    info = plausible.info("schlick")
    assert info.reciprocal and not info.energy_conserving


def test_energy_not_guaranteed():
    """Why energy_conserving=False: at grazing incidence a sharp, fully reflective
    Schlick lobe (r = 0.01, rs = 1) has a Monte Carlo albedo well above 1."""
    m = plausible.make("schlick", r=0.01, p=1.0, rs=1.0, rd=0.0)
    wi = from_angles(89.0)
    n = 200_000
    w = m.sample(wi, np.random.default_rng(5).random((n, 3))).weight
    mc, err = float(w.mean()), float(w.std() / math.sqrt(n))
    assert mc - 4 * err > 1.0, (mc, err)


# -- NumPy vs Dr.Jit --------------------------------------------------------------------

def test_numpy_and_drjit_hooks_agree():
    rng = np.random.default_rng(8)
    n = 4000
    wi = unit(rng.normal(size=(n, 3)) * [1, 1, 0] + [0, 0, 1] * rng.random((n, 1)))
    wo = unit(rng.normal(size=(n, 3)) * [1, 1, 0] + [0, 0, 1] * rng.random((n, 1)))
    u = rng.random((n, 3))
    for form in ("normalised", "sqrt"):
        m = plausible.make("schlick", r=0.15, p=0.4, rs=[0.2, 0.6, 0.9], rd=[0.1, 0.2, 0.3], azimuth=form)
        pdf, _ = hooks_agree(m, wi, wo, u)
        assert np.count_nonzero(pdf) > n // 2


def test_cross_check_with_analysis_albedo():
    """plausible.analysis.albedo (adaptive quadrature, written independently) agrees
    with this file's Gauss-Legendre rule."""
    analysis = pytest.importorskip("plausible.analysis")
    m = plausible.make("schlick", **MODELS[1])
    for th in (0.0, 75.0):
        wi = from_angles(th, 20.0)
        r = analysis.albedo(m, wi)
        assert r.value == pytest.approx(quad_albedo(m, wi), abs=1e-8 + 3 * r.error)


@pytest.mark.parametrize("p", [0.001, 0.01, 0.5])
def test_pdf_at_the_mirror_direction_does_not_depend_on_rounding(p):
    """u2 = 1 samples the half vector h = n, i.e. the mirror direction up to
    rounding; the azimuth factor is undefined there and taken as its mean, 1, for
    any half vector within 1e-6 rad of n.  The sample's pdf equals pdf() at the
    exact mirror (issue 21: 2.68 against 1.03e5 before)."""
    rng = np.random.default_rng(4)
    m = plausible.make("schlick", p=p)
    wi = unit(rng.normal(size=(500, 3)) * [1, 1, 0] + [0, 0, 0.3])
    u = np.column_stack([np.zeros(500), rng.random(500), np.ones(500)])
    s = m.sample(wi, u)
    np.testing.assert_allclose(s.pdf, m.pdf(wi, wi * [-1, -1, 1]), rtol=1e-12)
