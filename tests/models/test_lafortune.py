"""Tests of the Lafortune et al. 1997 generalized cosine lobe model.

Truths used: closed-form albedos at normal incidence (a lobe about the normal
integrates to ``rho |C L|^n 2 pi / (n + 2)``), the reciprocal Phong model of
:mod:`plausible.models.phong` (an independent implementation of the same
function), deterministic Gauss-Legendre quadrature over the hemisphere,
Monte Carlo with fixed seeds (n-sigma tolerances) and a chi-square test of the
sampled directions against the integrated pdf.
"""

from __future__ import annotations

import math
from functools import partial
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from reference import TWO_PI, chi2_sampler_pvalue, hooks_agree, from_angles, hemisphere_rule, mc_albedo, quad_albedo, unit

import plausible
from plausible.models.lafortune import Lafortune, albedo_bound



def rho_for(albedo, n, cmax=1.0):
    """The ``rho`` giving a lobe of albedo bound ``albedo``: ``albedo (n+2) / (2 pi cmax^n)``."""
    return albedo * (n + 2.0) / (TWO_PI * cmax ** n)


# An off-specular lobe (|cx| != cz) and a retro-reflective lobe (C = identity).
# At normal incidence their albedos are exactly 0.4 and 0.3 (C L = cz z).
NON_PHONG = [(-0.8, -0.8, 0.9, 15.0, rho_for(0.4, 15.0, 0.9)), (1.0, 1.0, 1.0, 8.0, rho_for(0.3, 8.0))]
RD = 0.2


quad_albedo = partial(quad_albedo, nmu=120, nphi=240)


class WrongExponent(Lafortune):
    """Deliberately broken: samples each lobe with exponent 1.3 n, evaluates the pdf with n."""

    def _sample(self, ops, wi, u, q):
        lobes = tuple((a, b, c, 1.3 * n, rho) for a, b, c, n, rho in q.lobes)
        return super()._sample(ops, wi, u, SimpleNamespace(lobes=lobes, rd=q.rd))


# -- values ---------------------------------------------------------------------------

def test_one_phong_lobe_equals_reciprocal_phong():
    rng = np.random.default_rng(3)
    for ks, n in [(0.7, 20.0), (1.0, 0.0), (0.3, 300.0), (0.5, 1.5)]:
        laf = plausible.make("lafortune", lobes=[(-1, -1, 1, n, ks * (n + 2) / (2 * math.pi))], rd=0.0)
        ph = plausible.make("reciprocal-phong", ks=ks, n=n)
        wi = unit(rng.normal(size=(2000, 3)) * [1, 1, 0] + [0, 0, 0.05] + rng.random((2000, 1)) * [0, 0, 1])
        wo = unit(rng.normal(size=(2000, 3)))
        # push most of wo toward the mirror direction so the lobe is exercised
        wo = unit(0.3 * wo + np.stack([-wi[:, 0], -wi[:, 1], wi[:, 2]], axis=-1))
        np.testing.assert_allclose(laf.eval(wi, wo), ph.eval(wi, wo), rtol=1e-13, atol=0)
        np.testing.assert_allclose(laf.pdf(wi, wo), ph.pdf(wi, wo), rtol=1e-12, atol=0)
        u = rng.random((2000, 3))
        a, b = laf.sample(wi, u), ph.sample(wi, u)
        np.testing.assert_allclose(a.wo, b.wo, atol=1e-12)
        np.testing.assert_allclose(a.weight, b.weight, rtol=1e-9)
        assert np.count_nonzero(ph.eval(wi, wo)) > 1000


def test_value_by_hand():
    """f at one pair, the arithmetic written out from the definition."""
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    L = unit([0.3, -0.2, 0.8])
    V = unit([-0.1, 0.4, 0.7])
    s1 = -0.8 * L[0] * V[0] - 0.8 * L[1] * V[1] + 0.9 * L[2] * V[2]
    s2 = L[0] * V[0] + L[1] * V[1] + L[2] * V[2]
    expect = RD / math.pi + NON_PHONG[0][4] * s1 ** 15 + NON_PHONG[1][4] * s2 ** 8
    assert s1 > 0 and s2 > 0
    np.testing.assert_allclose(m.eval(L, V), expect, rtol=1e-13)


def test_negative_dot_product_gives_zero_lobe():
    m = plausible.make("lafortune", lobes=[(1.0, 1.0, -1.0, 3.0, 0.5)], rd=0.0)
    L, V = unit([0.5, 0.0, 0.5]), unit([0.1, 0.0, 0.9])   # 0.5*0.1 - 0.5*0.9 < 0
    assert float(m.eval(L, V)) == 0.0
    # and a positive one is the lobe
    L2, V2 = unit([0.9, 0.0, 0.1]), unit([0.9, 0.0, 0.1])
    s = L2[0] * V2[0] - L2[2] * V2[2]
    np.testing.assert_allclose(m.eval(L2, V2), 0.5 * s ** 3, rtol=1e-13)


def test_below_horizon_is_zero():
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    assert float(m.eval([0.3, 0, 0.9], [0.3, 0, -0.9])) == 0.0
    assert float(m.pdf([0.3, 0, -0.9], [0.3, 0, 0.9])) == 0.0


def test_colour_rd():
    m = plausible.make("lafortune", lobes=NON_PHONG[:1], rd=[0.1, 0.2, 0.3])
    L, V = unit([0.3, -0.2, 0.8]), unit([-0.1, 0.4, 0.7])
    f = m.eval(L, V)
    assert f.shape == (3,)
    np.testing.assert_allclose(np.diff(f), [0.1 / math.pi, 0.1 / math.pi], rtol=1e-12)


coef = st.one_of(st.just(0.0), st.floats(0.05, 2), st.floats(-2, -0.05))
lobe_strategy = st.tuples(
    coef, coef, coef,
    st.floats(0, 60), st.floats(0, 1),
)
direction = st.tuples(st.floats(-1, 1), st.floats(-1, 1), st.floats(0.01, 1))


@settings(max_examples=60, deadline=None)
@given(lobes=st.lists(lobe_strategy, min_size=1, max_size=3), wi=direction, wo=direction)
def test_reciprocity_property(lobes, wi, wo):
    # scale rho so the energy bound holds (fraction of the remaining budget per lobe)
    scaled = []
    for cx, cy, cz, n, frac in lobes:
        cm = max(abs(cx), abs(cy), abs(cz))
        rho = 0.0 if cm == 0 else frac * 0.25 * (n + 2) / (TWO_PI * cm ** n)
        scaled.append((cx, cy, cz, n, rho))
    m = plausible.make("lafortune", lobes=scaled, rd=0.2)
    a, b = float(m.eval(wi, wo)), float(m.eval(wo, wi))
    assert a == pytest.approx(b, rel=1e-12, abs=1e-300)


def test_reciprocity_random_pairs():
    rng = np.random.default_rng(11)
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    wi = unit(np.abs(rng.normal(size=(5000, 3))) * [np.sign(rng.normal()), 1, 1])
    wo = unit(rng.normal(size=(5000, 3)) * [1, 1, 0] + [0, 0, 1] * np.abs(rng.normal(size=(5000, 1))))
    np.testing.assert_allclose(m.eval(wi, wo), m.eval(wo, wi), rtol=1e-12, atol=0)
    assert m.info.reciprocal


# -- energy ---------------------------------------------------------------------------

def test_quadrature_matches_closed_form_at_normal_incidence():
    """A lobe with L = z is rho (cz Vz)^n: albedo rho cz^n 2 pi / (n + 2); here 0.4 + 0.3 + rd."""
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    assert quad_albedo(m, [0, 0, 1]) == pytest.approx(0.4 + 0.3 + RD, rel=1e-9)
    assert albedo_bound(m.params["lobes"], RD) == pytest.approx(0.9, rel=1e-12)


@pytest.mark.parametrize("theta", [0.0, 30.0, 60.0, 80.0])
def test_mc_albedo_matches_quadrature(theta):
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    wi = from_angles(theta, 25.0)
    q = quad_albedo(m, wi)
    mc, err = mc_albedo(m, wi)
    assert abs(mc - q) < 4 * err, (theta, mc, q, err)
    assert q <= 0.9 + 1e-9  # below the validated bound


def test_albedo_bound_holds_and_is_tight_for_phong():
    """rd + rho 2 pi/(n+2) = 1 for a reciprocal-Phong lobe: albedo 1 at normal incidence, < 1 elsewhere."""
    n = 10.0
    m = plausible.make("lafortune", lobes=[(-1, -1, 1, n, 0.6 * (n + 2) / TWO_PI)], rd=0.4)
    assert quad_albedo(m, [0, 0, 1]) == pytest.approx(1.0, rel=1e-9)
    for th in (20.0, 50.0, 85.0):
        assert quad_albedo(m, from_angles(th)) < 1.0


def test_energy_bound_rejects_and_names_parameters():
    with pytest.raises(ValueError, match="lobes.*rd"):
        plausible.make("lafortune", lobes=[(-1, -1, 1, 10.0, 0.61 * 12 / TWO_PI)], rd=0.4)
    # c_max > 1 counts: (1.1)^20 = 6.7 times the Phong budget
    with pytest.raises(ValueError, match="energy"):
        plausible.make("lafortune", lobes=[(-1.1, -1.1, 1.0, 20.0, 0.2 * 22 / TWO_PI)], rd=0.0)
    # the same function written with C / c_max and rho c_max^n is accepted iff the bound is
    ok = plausible.make("lafortune", lobes=[(-1.1, -1.1, 1.0, 20.0, 0.9 * 22 / TWO_PI / 1.1 ** 20)], rd=0.0)
    assert ok.info.energy_conserving


# -- sampling -------------------------------------------------------------------------

@pytest.mark.parametrize("theta", [10.0, 55.0, 80.0])
def test_sample_weight_and_pdf_consistent(theta):
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    wi = from_angles(theta, -40.0)
    u = np.random.default_rng(5).random((20_000, 3))
    s = m.sample(wi, u)
    ok = s.pdf > 0
    assert ok.mean() > 0.8
    np.testing.assert_allclose(s.pdf[ok], m.pdf(wi, s.wo[ok]), rtol=1e-12)
    np.testing.assert_allclose(s.weight[ok], m.eval(wi, s.wo[ok]) * s.wo[ok, 2] / s.pdf[ok], rtol=1e-12)
    assert np.all(s.weight[~ok] == 0)


@pytest.mark.parametrize("theta", [0.0, 45.0, 75.0])
def test_pdf_mass_matches_fraction_of_valid_samples(theta):
    """The pdf integrates over the hemisphere to the fraction of samples above it."""
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=0.0)
    wi = from_angles(theta, 10.0)
    dirs, w = hemisphere_rule(120, 240)
    mass = float(np.sum(m.pdf(wi, dirs) * w))
    n = 200_000
    frac = float(np.mean(m.sample(wi, np.random.default_rng(9).random((n, 3))).pdf > 0))
    assert mass <= 1.0 + 1e-9
    assert abs(frac - mass) < 4 * math.sqrt(max(mass * (1 - mass), 1e-12) / n) + 1e-9


@pytest.mark.parametrize("theta", [5.0, 50.0, 78.0])
def test_chi_square_sampler(theta):
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    assert chi2_sampler_pvalue(m, from_angles(theta, 30.0)) > 1e-3


def test_chi_square_detects_wrong_exponent():
    m = WrongExponent(lobes=NON_PHONG, rd=RD)
    assert chi2_sampler_pvalue(m, from_angles(50.0, 30.0)) < 1e-8


def test_peak_directions_are_lobe_axes():
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=0.0)
    wi = from_angles(40.0, 20.0)
    peaks = m.peak_directions(wi)
    axis = unit([-0.8 * wi[0], -0.8 * wi[1], 0.9 * wi[2]])
    assert any(np.allclose(p, axis, atol=1e-12) for p in peaks)
    assert any(np.allclose(p, wi, atol=1e-12) for p in peaks)   # retro lobe
    # the off-specular lobe's axis maximises that lobe: f there beats a dense sample
    one = plausible.make("lafortune", lobes=NON_PHONG[:1], rd=0.0)
    dirs, _ = hemisphere_rule(200, 400)
    assert float(one.eval(wi, axis)) >= one.eval(wi, dirs).max()


# -- parameters -----------------------------------------------------------------------

@pytest.mark.parametrize("bad, what", [
    ([(-1, -1, 1, -2.0, 0.1)], "exponent n must lie in"),
    ([(-1, -1, 1, float("nan"), 0.1)], "NaN"),
    ([(-1, -1, 1, 5.0, -0.1)], "rho must lie in"),
    ([(-1, -1, 1, 5.0)], "5 entries"),
    ([(-1, -1, 1, 5.0, 0.1, 2.0)], "5 entries"),
    ([("a", -1, 1, 5.0, 0.1)], "5 numbers"),
    (3.0, "list of"),
    ("lobes", "list of"),
])
def test_bad_lobes(bad, what):
    with pytest.raises(ValueError) as e:
        plausible.make("lafortune", lobes=bad)
    assert "lobes" in str(e.value) and what in str(e.value)


def test_bad_rd_and_unknown():
    with pytest.raises(ValueError, match="'rd'"):
        plausible.make("lafortune", rd=1.5)
    with pytest.raises(ValueError, match="unknown"):
        plausible.make("lafortune", ks=0.1)


def test_defaults_and_registry():
    m = plausible.make("lafortune")
    assert m.info.reciprocal and m.info.energy_conserving
    assert albedo_bound(m.params["lobes"], m.params["rd"]) == pytest.approx(0.8)
    for ext in m.info.param("lobes").extremes:
        plausible.make("lafortune", lobes=ext)
    assert plausible.make("lafortune", lobes=[], rd=0.5).eval([0, 0, 1], [0, 0, 1]) == pytest.approx(0.5 / math.pi)


# -- NumPy vs Dr.Jit --------------------------------------------------------------------

def test_numpy_and_drjit_hooks_agree():
    rng = np.random.default_rng(2)
    n = 4000
    wi = unit(rng.normal(size=(n, 3)) * [1, 1, 0] + [0, 0, 1] * rng.random((n, 1)))
    wo = unit(rng.normal(size=(n, 3)))
    u = rng.random((n, 3))
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=[0.1, 0.2, 0.15])
    _, smp = hooks_agree(m, wi, wo, u)
    assert np.count_nonzero(smp[2] > 0) > n // 2


def test_cross_check_with_analysis_albedo():
    """plausible.analysis.albedo (adaptive quadrature, written independently) agrees
    with this file's Gauss-Legendre rule."""
    analysis = pytest.importorskip("plausible.analysis")
    m = plausible.make("lafortune", lobes=NON_PHONG, rd=RD)
    for th in (0.0, 60.0, 80.0):
        wi = from_angles(th, 25.0)
        r = analysis.albedo(m, wi)
        assert r.value == pytest.approx(quad_albedo(m, wi), abs=1e-9 + 3 * r.error)
