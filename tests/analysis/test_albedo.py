"""The albedo integrator against closed forms and against Monte Carlo."""

import math

import numpy as np
import pytest

import plausible
from reference import mc_albedo
from plausible.analysis import albedo, albedo_curve, direction, hemispherical_albedo, is_isotropic

THETAS = (0, 30, 60, 80, 85, 89, 89.9)
EXPONENTS = (0, 1, 10, 100, 1000, 1e4)


@pytest.mark.parametrize("name", ["modified-phong", "reciprocal-phong", "reciprocal-blinn"])
@pytest.mark.parametrize("n", EXPONENTS)
def test_albedo_at_most_one_and_finite_on_the_grid(name, n):
    kw = dict(kd=0.0, ks=1.0) if name == "modified-phong" else dict(ks=1.0)
    m = plausible.make(name, n=n, **kw)
    res = albedo_curve(m, np.radians(THETAS))
    assert np.all(np.isfinite(res.value)) and np.all(np.isfinite(res.error))
    if n == 0 and name != "reciprocal-blinn":
        # cos^0 lobe: a jump at alpha = 90 deg; the closed form a = (1 + cos theta)/2 (Phong part) is the truth
        spec = (1 + np.cos(np.radians(THETAS))) / 2
        assert np.all(np.abs(res.value - spec) < 1e-4)
    else:   # (the Blinn lobe with n = 0 is Lambertian: albedo exactly 1)
        assert np.all(res.error < 1e-4)
    assert np.all(res.value <= 1 + 1e-9)
    assert res.value[0] == pytest.approx(1.0, abs=1e-8)   # normalisation: exactly 1 at normal incidence


@pytest.mark.parametrize("name,kw", [
    ("reciprocal-phong", dict(n=1e4)), ("reciprocal-blinn", dict(n=1e4)), ("reciprocal-blinn", dict(n=3)),
    ("modified-phong", dict(kd=0.3, ks=0.7, n=500)), ("phong", dict(n=50)),
])
@pytest.mark.parametrize("theta", [0, 45, 80, 89.9])
def test_quadrature_agrees_with_monte_carlo(name, kw, theta):
    m = plausible.make(name, **kw)
    wi = direction(math.radians(theta), 0.7)
    q = albedo(m, wi)
    mc, se = mc_albedo(m, wi, n=400_000, seed=0)
    assert abs(q.value - mc) < 5 * se + q.error + 1e-12


def test_reciprocal_phong_albedo_tends_to_cos_theta_as_n_grows():
    # Neumann et al. sec. 1.2: "in this limit case the albedo follows the cosine function"
    m = plausible.make("reciprocal-phong", n=1e5)
    for t in (20, 50, 70):
        assert albedo(m, direction(math.radians(t))).value == pytest.approx(math.cos(math.radians(t)), rel=1e-3)


def test_hemispherical_albedo_closed_forms():
    assert hemispherical_albedo(plausible.make("lambertian", rd=0.6)).value == pytest.approx(0.6, abs=1e-10)
    # n = 0 truncated Phong lobe: a(mu) = (1 + mu)/2 -> 2 int (1 + mu)/2 mu dmu = 1/2 + 1/3
    r = hemispherical_albedo(plausible.make("reciprocal-phong", ks=1.0, n=0.0), n_theta=8)
    assert r.value == pytest.approx(0.5 + 1 / 3, abs=1e-4)


def test_isotropy_probe():
    assert is_isotropic(plausible.make("modified-phong"))


def test_bad_input():
    m = plausible.make("lambertian")
    with pytest.raises(ValueError, match="thetas"):
        albedo_curve(m, [0.1, 2.0])
    with pytest.raises(ValueError, match="wi"):
        albedo(m, [0, 0, 0])
    with pytest.raises(ValueError, match="wi must be a float array.*'up'"):
        albedo(m, "up")
    assert albedo(m, [0, 0, -1]).value == 0


@pytest.mark.parametrize("spec", ["ashikhmin-shirley:nu=11:nv=301", "phong:n=0", "cook-torrance:m=0.2:rs=0.6,0.5,0.4"])
@pytest.mark.parametrize("backend_name", ["numpy", "drjit"])
def test_rule_pairs_sharing_nodes_sum_as_the_whole_grids(spec, backend_name):
    """A pair of rules ``(m, r)``, ``(m, 2 r)`` asked together is computed from the nodes
    they share plus each one's others (``_pieces``); the sums equal those of each rule's
    whole grid (a second computation: ``_grid_sum`` of the full grid, NumPy) to rounding,
    for an anisotropic lobe, a lune-cut lobe (two polar segments) and a colour model; and
    the pieces hold fewer nodes than the two grids."""
    from plausible.arrays import backend
    from plausible.integrals.albedo import _grid_sum, _pieces, _Rules, _sums

    if backend_name == "drjit" and not backend.drjit_available():
        pytest.skip("Dr.Jit LLVM backend unavailable")
    m = plausible.make(spec)
    wis = [direction(math.radians(t), math.radians(p)) for t, p in ((0, 0), (60, 30), (89.9, 10))]
    rules = [_Rules(m, wi, 13, not is_isotropic(m)) for wi in wis]
    requests = [(a, 6, r) for a in range(len(wis)) for r in (1, 2)]
    pieces, _ = _pieces(rules, requests)
    whole = sum(len(g[0]) * len(g[2]) for a, k, r in requests for g in rules[a].nodes(k, r))
    assert sum(len(g[0]) * len(g[2]) for _, g in pieces) < 0.9 * whole
    with plausible.use_backend(backend_name):
        _sums(m, "f", rules, requests)
    for a, k, r in requests:
        ref = sum(_grid_sum(m, "f", wis[a], g) for g in rules[a].nodes(k, r))
        np.testing.assert_allclose(rules[a].sums[(k, r)], ref, rtol=1e-12, atol=0)


@pytest.mark.parametrize("spec", ["ashikhmin-shirley:nu=12:nv=90", "phong:n=0", "cook-torrance:m=0.2"])
def test_the_polar_segments_tile_each_azimuth_once_and_none_is_empty(spec):
    """The rule's grids (a kink, a lune or the V-groove's curves cut the polar range): every column's
    segment has a length, and the segments of each azimuth add up to its whole range ``tmax``
    (``quadrature.half_vector_tmax``); a segment far from the pole takes the light rule, whose
    first panel is no longer than its distance to the pole."""
    from plausible.integrals.albedo import LIGHT_POLE_LEVELS, _Rules
    from plausible.integrals.quadrature import half_vector_tmax

    m = plausible.make(spec)
    for t, p in ((30, 20), (60, 30), (89.9, 10)):
        wi = direction(math.radians(t), math.radians(p))
        rules = _Rules(m, wi, 13, not is_isotropic(m))
        grids = rules.nodes(6, 2)
        phi = np.concatenate([g[2] for g in grids])
        span = np.concatenate([g[5] for g in grids])
        assert np.all(span > 0.0)
        keys, inv = np.unique(phi, return_inverse=True)
        np.testing.assert_allclose(np.bincount(inv, weights=span), half_vector_tmax(wi, keys), rtol=1e-13)
        for g in grids[1:]:
            assert np.all(g[4] >= g[5] * 0.5 ** LIGHT_POLE_LEVELS)
