"""Exact Fresnel reflectances against closed forms and an independent complex-number computation."""

import cmath
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from plausible import fresnel
from plausible.arrays.ops import NP


def fresnel_cmath(cos_i, n, k):
    """Independent reference: the Fresnel amplitude coefficients with complex N = n + ik
    (Born & Wolf sec. 1.5.2 / 14.2), ``Rs = |rs|^2``, ``Rp = |rp|^2``."""
    N = complex(n, k)
    sin2 = 1.0 - cos_i * cos_i
    ct = cmath.sqrt(N * N - sin2)          # N cos(theta_t)
    rs = (cos_i - ct) / (cos_i + ct)
    rp = (N * N * cos_i - ct) / (N * N * cos_i + ct)
    return abs(rs) ** 2, abs(rp) ** 2


@given(st.floats(0.05, 5.0), st.floats(0.0, 10.0))
def test_conductor_normal_incidence_closed_form(n, k):
    expect = ((n - 1) ** 2 + k * k) / ((n + 1) ** 2 + k * k)
    assert fresnel.conductor(NP, 1.0, n, k) == pytest.approx(expect, rel=1e-12, abs=1e-15)


@given(st.floats(1.0001, 4.0), st.floats(0.0, 1.0))
def test_conductor_with_k0_equals_dielectric(eta, c):
    rs1, rp1 = fresnel.conductor_polarized(NP, c, eta, 0.0)
    rs2, rp2 = fresnel.dielectric_polarized(NP, c, eta)
    assert rs1 == pytest.approx(rs2, abs=1e-12)
    assert rp1 == pytest.approx(rp2, abs=1e-12)


@given(st.floats(0.2, 0.99), st.floats(0.0, 1.0))
def test_k0_below_one_total_internal_reflection_agrees(eta, c):
    # eta < 1 (light inside the denser medium): conductor with k = 0 must reproduce TIR.
    assert fresnel.conductor(NP, c, eta, 0.0) == pytest.approx(fresnel.dielectric(NP, c, eta), abs=1e-10)
    if (1 - c * c) / eta ** 2 >= 1.0 + 1e-9:
        assert fresnel.dielectric(NP, c, eta) == 1.0


@given(st.floats(1.0001, 4.0))
def test_dielectric_normal_incidence(eta):
    assert fresnel.dielectric(NP, 1.0, eta) == pytest.approx(((eta - 1) / (eta + 1)) ** 2, rel=1e-12)


@pytest.mark.parametrize("n,k", [(1.5, 0.0), (0.2, 3.0), (1.1, 7.0), (0.05, 4.2)])
def test_grazing_gives_one(n, k):
    assert fresnel.conductor(NP, 0.0, n, k) == pytest.approx(1.0, abs=1e-15)
    assert fresnel.conductor(NP, 1e-9, n, k) == pytest.approx(1.0, abs=1e-7)
    if k == 0:
        assert fresnel.dielectric(NP, 0.0, n) == pytest.approx(1.0, abs=1e-15)


@pytest.mark.parametrize("eta", [1.33, 1.5, 2.4])
def test_brewster_angle_zeroes_p_polarisation(eta):
    cb = math.cos(math.atan(eta))
    rs, rp = fresnel.dielectric_polarized(NP, cb, eta)
    assert rp == pytest.approx(0.0, abs=1e-15)
    assert rs > 0.05
    # and only there: a degree away it is clearly positive
    assert fresnel.dielectric_polarized(NP, math.cos(math.atan(eta) + 0.02), eta)[1] > 1e-5


@pytest.mark.parametrize("n,k", [(0.27, 2.78), (0.14, 3.98), (1.2, 7.3), (1.5, 0.0), (0.47, 2.4), (2.5, 0.5)])
@pytest.mark.parametrize("deg", [0.0, 20.0, 45.0, 70.0, 85.0, 89.9])
def test_against_complex_fresnel_equations(n, k, deg):
    c = math.cos(math.radians(deg))
    rs_ref, rp_ref = fresnel_cmath(c, n, k)
    rs, rp = fresnel.conductor_polarized(NP, c, n, k)
    assert rs == pytest.approx(rs_ref, abs=1e-12)
    assert rp == pytest.approx(rp_ref, abs=1e-12)
    assert fresnel.conductor(NP, c, n, k) == pytest.approx(0.5 * (rs_ref + rp_ref), abs=1e-12)
    if k == 0.0:
        assert fresnel.dielectric(NP, c, n) == pytest.approx(0.5 * (rs_ref + rp_ref), abs=1e-12)


def test_reference_checker_detects_a_wrong_formula():
    # The cmath reference must disagree with a deliberately broken conductor (k dropped).
    c = math.cos(math.radians(10))
    rs_ref, rp_ref = fresnel_cmath(c, 0.27, 2.78)
    rs_bad, rp_bad = fresnel.conductor_polarized(NP, c, 0.27, 0.0)
    assert abs(rs_bad - rs_ref) > 0.1


@settings(max_examples=50)
@given(st.floats(0.01, 5.0), st.floats(0.0, 10.0), st.floats(0.0, 1.0))
def test_conductor_in_unit_interval_and_rp_le_rs(n, k, c):
    rs, rp = fresnel.conductor_polarized(NP, c, n, k)
    assert -1e-12 <= rp <= rs + 1e-12 <= 1.0 + 2e-12


def test_vectorised_and_weight_dispatch():
    c = np.linspace(0, 1, 11)
    assert np.allclose(fresnel.weight(NP, "conductor", c, 0.5, 0.2, 3.0), fresnel.conductor(NP, c, 0.2, 3.0))
    assert np.allclose(fresnel.weight(NP, "schlick", c, 0.5, 0.2, 3.0), fresnel.schlick(NP, c, 0.5))
    assert np.allclose(fresnel.weight(NP, "none", c, 0.5, 0.2, 3.0), 0.5)
    with pytest.raises(ValueError, match="fresnel"):
        fresnel.weight(NP, "fancy", c, 0.5, 0.2, 3.0)


def test_numpy_and_drjit_agree():
    dr = pytest.importorskip("drjit")
    from drjit.llvm import Float64

    from plausible.arrays.ops import drjit_ops
    ops = drjit_ops(Float64)
    c = np.linspace(0.0, 1.0, 33)
    for n, k in [(0.27, 2.78), (1.5, 0.0), (0.7, 0.0)]:
        a = fresnel.conductor(NP, c, n, k)
        b = np.array(fresnel.conductor(ops, Float64(c), n, k))
        assert np.allclose(a, b, rtol=1e-12, atol=1e-14)
    a = fresnel.dielectric(NP, c, 0.7)
    b = np.array(fresnel.dielectric(ops, Float64(c), 0.7))
    assert np.allclose(a, b, rtol=1e-12, atol=1e-14)
    del dr
