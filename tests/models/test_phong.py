"""Lambert and the Phong family against closed forms and the notes' table."""

import math

import numpy as np
import pytest

import plausible
from plausible.analysis import albedo, direction

Z = [0.0, 0.0, 1.0]


@pytest.mark.parametrize("ks,kd,expected", [
    (0.5, 0.5, 7 / (2 * math.pi)),   # table row 1 of modified-phong-brdf-notes.txt
    (0.0, 0.0, 0.0),                 # no reflection
    (0.0, 1.0, 1 / math.pi),         # only diffuse
    (1.0, 0.0, 6 / math.pi),         # only specular: (10 + 2) / (2 pi)
])
def test_modified_phong_table_from_notes(ks, kd, expected):
    m = plausible.make("modified-phong", kd=kd, ks=ks, n=10)
    assert m.eval(Z, Z) == pytest.approx(expected, rel=1e-14, abs=1e-15)


def test_modified_phong_rgb_table_channels():
    m = plausible.make("modified-phong", kd=[0.5, 0.0, 0.0], ks=[0.5, 0.0, 1.0], n=10)
    np.testing.assert_allclose(m.eval(Z, Z), [7 / (2 * math.pi), 0.0, 6 / math.pi], rtol=1e-14)


@pytest.mark.parametrize("n", [0.0, 1.0, 10.0, 30.0, 1000.0, 1e4])
@pytest.mark.parametrize("kd,ks", [(0.5, 0.5), (0.0, 1.0), (0.3, 0.2)])
def test_modified_phong_albedo_at_normal_incidence_is_kd_plus_ks(kd, ks, n):
    # int (n+2)/(2pi) cos^n(theta) cos(theta) d omega = (n+2)/(2pi) * 2pi/(n+2) = 1 at normal incidence
    a = albedo(plausible.make("modified-phong", kd=kd, ks=ks, n=n), Z, tol=1e-10)
    assert a.value == pytest.approx(kd + ks, abs=1e-9)


@pytest.mark.parametrize("theta", [10, 45, 80, 89.9])
def test_cos0_phong_lobe_albedo_closed_form(theta):
    # n = 0: f = 1/pi on {R.wo > 0}; the lune integral gives a = (1 + cos(theta)) / 2.
    a = albedo(plausible.make("reciprocal-phong", ks=1.0, n=0.0), direction(math.radians(theta)))
    exact = (1 + math.cos(math.radians(theta))) / 2
    assert abs(a.value - exact) <= a.error < 1e-4     # the error bound is honest, and below 1e-4


@pytest.mark.parametrize("spec,exact", [
    ("modified-phong:kd=0.3:ks=0.7:n=0", lambda c: 0.3 + 0.7 * (1 + c) / 2),   # lune plus Lambert
    ("phong:ks=1:n=0", lambda c: (1 + c) / (2 * c)),                            # the lune over cos(theta_i)
])
@pytest.mark.parametrize("theta", [10.0, 45.0, 80.0, 89.9])
def test_mirror_cut_lobes_albedo_closed_form(spec, exact, theta):
    # the lune's edge R.wo = 0 is a panel edge (BxDF.mirror_cut): converged, with an honest bound
    c = math.cos(math.radians(theta))
    a = albedo(plausible.make(spec), direction(math.radians(theta)))
    assert abs(a.value - exact(c)) <= a.error < 1e-7 * exact(c)


def test_lune_edge_hint_is_what_converges_the_cut_lobe():
    # without the hint the cut lies inside panels: the bound stays large at 80 degrees (the
    # failure of the half-vector frame alone); with it, 1e-9
    from plausible.models.phong import ReciprocalPhong

    class Uncut(ReciprocalPhong):
        def mirror_cut(self):
            return False

    wi = direction(math.radians(80.0))
    exact = (1 + math.cos(math.radians(80.0))) / 2
    cut, uncut = albedo(ReciprocalPhong(ks=1.0, n=0.0), wi), albedo(Uncut(ks=1.0, n=0.0), wi)
    assert abs(cut.value - exact) <= cut.error < 1e-8
    assert uncut.error > 1e-6


def test_half_vector_lune_is_where_the_mirror_cosine_vanishes():
    # independent truth: wo = 2 (wi.h) h - wi and R = (-wi_x, -wi_y, wi_z) directly
    from plausible.integrals.quadrature import half_vector_lune

    rng = np.random.default_rng(3)
    for _ in range(20):
        ti, pi_ = rng.uniform(0.01, 1.56), rng.uniform(-math.pi, math.pi)
        wi = np.asarray(direction(ti, pi_))
        r = np.array([-wi[0], -wi[1], wi[2]])
        phi = rng.uniform(-math.pi, math.pi, 64)
        big_t = half_vector_lune(wi, phi)
        for t_scale, sign in ((0.999, 1.0), (1.001, -1.0)):
            t = big_t * t_scale
            h = np.stack([np.sin(t) * np.cos(phi), np.sin(t) * np.sin(phi), np.cos(t)], axis=-1)
            wo = 2.0 * (h @ wi)[:, None] * h - wi
            rw = wo @ r
            cross = big_t < 0.5 * math.pi - 1e-12
            assert np.all(sign * rw[cross] > 0)
            if t_scale < 1:
                assert np.all(rw[~cross] >= -1e-12)   # no crossing: R.wo >= 0 up to t = pi/2
        h = np.stack([np.sin(big_t) * np.cos(phi), np.sin(big_t) * np.sin(phi), np.cos(big_t)], axis=-1)
        wo = 2.0 * (h @ wi)[:, None] * h - wi
        np.testing.assert_allclose((wo @ r)[big_t < 0.5 * math.pi - 1e-12], 0.0, atol=1e-12)


@pytest.mark.parametrize("n", [0.0, 1.0, 7.0, 20.0, 150.0, 1e4])
def test_blinn_normalisation_gives_unit_albedo_at_normal_incidence(n):
    a = albedo(plausible.make("reciprocal-blinn", ks=1.0, n=n), Z, tol=1e-9)
    assert a.value == pytest.approx(1.0, abs=1e-8)


def test_blinn_norm_closed_form_special_values():
    from plausible.models.phong import blinn_norm
    from plausible.arrays.ops import NP

    assert blinn_norm(NP, 0.0) == pytest.approx(1 / math.pi)                     # Lambertian
    assert blinn_norm(NP, 2.0) == pytest.approx(4 * 6 / (8 * math.pi * 2.5))     # (n+2)(n+4)/(8 pi (n + 1/2))


def test_lambert_albedo_is_rd_everywhere():
    m = plausible.make("lambertian", rd=[0.2, 0.5, 1.0])
    for t in (0, 60, 89.9):
        np.testing.assert_allclose(albedo(m, direction(math.radians(t))).value, [0.2, 0.5, 1.0], atol=1e-12)


def test_reciprocal_phong_is_modified_phong_without_diffuse(rng):
    from conftest import random_upper

    a, b = random_upper(rng, 500), random_upper(rng, 500)
    np.testing.assert_allclose(plausible.make("reciprocal-phong", ks=0.7, n=33).eval(a, b),
                               plausible.make("modified-phong", kd=0.0, ks=0.7, n=33).eval(a, b), rtol=1e-14)


def test_phong_differs_from_reciprocal_by_cos_theta_i(rng):
    from conftest import random_upper

    a, b = random_upper(rng, 200, 0.05), random_upper(rng, 200)
    np.testing.assert_allclose(plausible.make("phong", n=12).eval(a, b) * a[:, 2],
                               plausible.make("reciprocal-phong", n=12).eval(a, b), rtol=1e-13)
    np.testing.assert_allclose(plausible.make("blinn", n=12).eval(a, b) * a[:, 2],
                               plausible.make("reciprocal-blinn", n=12).eval(a, b), rtol=1e-13)


def test_phong_albedo_decreases_toward_grazing_for_large_n():
    # Neumann et al. fig. 1: the reciprocal Phong albedo follows cos(theta) as n grows.
    m = plausible.make("reciprocal-phong", ks=1.0, n=1e4)
    for t in (30, 60, 85):
        assert albedo(m, direction(math.radians(t))).value == pytest.approx(math.cos(math.radians(t)), rel=2e-3)


def test_kd_plus_ks_above_one_is_refused():
    with pytest.raises(ValueError, match="'kd' \\+ 'ks'"):
        plausible.make("modified-phong", kd=0.6, ks=0.5)
    with pytest.raises(ValueError, match="kd"):
        plausible.make("modified-phong", kd=[0.5, 0.9, 0.1], ks=0.2)


@pytest.mark.parametrize("bad", [-1.0, float("nan"), float("inf"), "x"])
def test_bad_exponent_is_refused_with_its_range(bad):
    with pytest.raises(ValueError, match=r"'n' must .*\[0, 1e\+06\]"):
        plausible.make("reciprocal-phong", n=bad)


def test_reflectance_outside_unit_interval_is_refused():
    with pytest.raises(ValueError, match=r"'ks' must lie in \[0, 1\]"):
        plausible.make("reciprocal-phong", ks=1.5)
    with pytest.raises(ValueError, match="'rd'"):
        plausible.make("lambertian", rd=[0.5, -0.1, 0.2])
    with pytest.raises(ValueError, match="unknown parameter"):
        plausible.make("lambertian", kd=0.5)
    with pytest.raises(ValueError, match="unknown model"):
        plausible.make("no-such-model")
