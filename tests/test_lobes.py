"""A model's lobes (issue 28): each declared :class:`plausible.bxdf.Lobe` is one
term of the model, so their sum is the model, their mixture is the model's
sampler, and a diffuse lobe's declared albedo is the integral of its ``f cos``."""

import numpy as np
import pytest

import plausible
from conftest import model_cases, random_upper
from plausible.bxdf import Lobe, mixture_f, mixture_pdf, mixture_probabilities, mixture_sample
from plausible.models.sum import Sum
from plausible.arrays.ops import NP
from reference import from_angles, hemisphere_rule

CASES = model_cases(max_variants=2)


def split(a):
    return a[..., 0], a[..., 1], a[..., 2]


def material():
    """A Sum of a two-lobe model and a one-lobe one, with colour scales."""
    return Sum([(plausible.make("ashikhmin-shirley", nu=20.0, nv=80.0, rs=0.1, rd=0.6), [0.5, 0.6, 0.7]),
                (plausible.make("lambertian", rd=0.3), 0.5),
                plausible.make("reciprocal-blinn", ks=0.4, n=30.0)])


def _models():
    out = [pytest.param(plausible.make(n, **kw), id=n + "-" + str(i)) for i, (n, kw) in
           enumerate(c.values for c in CASES)]
    return out + [pytest.param(material(), id="sum")]


MODELS = _models()


@pytest.mark.parametrize("model", MODELS)
def test_the_lobes_sum_to_the_model(model, rng):
    """sum of the lobes' f equals the model's f (float64, 1e-12 relative)."""
    wi, wo = random_upper(rng, 500, 0.01), random_upper(rng, 500, 0.01)
    a, b = model._color_axis(split(wi)), model._color_axis(split(wo))
    want = model._f(NP, a, b, model.p)
    got = mixture_f(NP, model, a, b, model.p, components=True)
    np.testing.assert_allclose(np.broadcast_to(got, np.shape(want)), want, rtol=1e-12, atol=1e-300)


@pytest.mark.parametrize("model", MODELS)
def test_the_lobes_mixture_is_the_models_sampler(model, rng):
    """The mixture of the lobes has the model's pdf and draws the model's
    directions from the same u (a Sum: its parts' mixtures, flattened)."""
    wi, wo = random_upper(rng, 500, 0.01), random_upper(rng, 500, 0.01)
    u = rng.random((500, 3))
    np.testing.assert_allclose(mixture_pdf(NP, model, split(wi), split(wo), model.q, components=True),
                               model._pdf(NP, split(wi), split(wo), model.q), rtol=1e-10, atol=1e-300)
    got = np.stack(mixture_sample(NP, model, split(wi), split(u), model.q, components=True)[0], -1)
    want = np.stack(np.broadcast_arrays(*model._sample(NP, split(wi), split(u), model.q)), -1)
    same = np.all(np.isclose(got, want, rtol=1e-9, atol=1e-12), axis=-1)
    assert same.mean() > 0.998, f"{(~same).sum()} of 500 samples differ"


def _quad_albedo(model, fn, wi, n=200):
    dirs, w = hemisphere_rule(n, 2 * n)
    a, b = model._color_axis(split(np.broadcast_to(wi, dirs.shape))), model._color_axis(split(dirs))
    f = np.broadcast_to(fn(NP, a, b), model._out_shape((len(dirs),)))
    cw = dirs[:, 2] * w
    return np.sum(f * (cw[:, None] if f.ndim > 1 else cw), axis=0)


def albedo_errors(model, thetas=(0.0, 40.0, 75.0)):
    """|declared albedo - quadrature of f cos| of every diffuse lobe, per angle."""
    out = []
    for lobe in model.components():
        if lobe.albedo is None:
            continue
        for t in thetas:
            wi = from_angles(t, 30.0)
            want = _quad_albedo(model, lambda ops, a, b: lobe.f(ops, a, b, model.p), wi)
            got = np.asarray(lobe.albedo(NP, split(wi), model.p), dtype=np.float64)
            out.append(np.max(np.abs(got - want)))
    return out


DIFFUSE = [m for m in MODELS if any(lb.kind == "diffuse" for lb in m.values[0].components())]


@pytest.mark.parametrize("model", DIFFUSE)
def test_a_diffuse_lobes_albedo_is_its_integral(model):
    """The declared albedo of each diffuse lobe equals the Gauss-Legendre integral
    of its f cos over the hemisphere at 0, 40 and 75 degrees (1e-6)."""
    errors = albedo_errors(model)
    assert errors and max(errors) < 1e-6


def test_the_albedo_check_detects_a_wrong_albedo():
    """Ashikhmin-Shirley's diffuse lobe declared with rd (1 - rs) (its hemispherical
    form without the angular factor) instead of rd (1 - rs) (1 - (1 - cos/2)^5):
    refused."""
    m = plausible.make("ashikhmin-shirley", rs=0.1, rd=0.6)
    spec, diff = m.lobes()
    broken = diff._replace(albedo=lambda ops, wi, p: p.rd * (1.0 - p.rs))

    class Broken(type(m)):
        def lobes(self):
            return (spec, broken)

    assert max(albedo_errors(Broken(rs=0.1, rd=0.6))) > 1e-2


def test_diffuse_lobes_are_declared_where_models_have_a_diffuse_term():
    """Every model whose LOBES include "diffuse" declares a diffuse lobe of its own
    (registry models; the MERL table is a measured whole)."""
    for name in plausible.names():
        m = plausible.make(name)
        if "diffuse" in m.LOBES:
            kinds = [lb.kind for lb in m.components()]
            assert "diffuse" in kinds, name


def test_probabilities_renormalise_over_the_enabled_lobes():
    """Weights (0.2, 0.6): both on -> (0.25, 0.75); only the second -> (0, 1);
    enabled lobes of zero weight share equally."""
    np.testing.assert_allclose(mixture_probabilities(NP, (0.2, 0.6)), [0.25, 0.75], rtol=1e-15)
    assert mixture_probabilities(NP, (0.2, 0.6), [False, True]) == [0.0, 1.0]
    assert mixture_probabilities(NP, (0.0, 0.0, 1.0), [True, True, False]) == [0.5, 0.5, 0.0]
    p = mixture_probabilities(NP, (np.array([0.0, 1.0]), np.array([0.0, 3.0])))
    np.testing.assert_allclose(np.stack(p), [[0.5, 0.25], [0.5, 0.75]])


def test_a_subclass_that_changes_f_falls_back_to_one_lobe():
    """A subclass redefining _f below the lobes' class is one lobe (its whole f),
    since the inherited lobes no longer add up to it."""
    class Doubled(type(plausible.make("modified-phong"))):
        def _f(self, ops, wi, wo, p):
            return 2.0 * super()._f(ops, wi, wo, p)

    m = Doubled()
    assert len(m.components()) == 1 and isinstance(m.components()[0], Lobe)
    wi, wo = from_angles(20.0, 10.0), from_angles(30.0, 200.0)
    np.testing.assert_allclose(mixture_f(NP, m, wi, wo, m.p, components=True), 2 * plausible.make(
        "modified-phong").eval(wi, wo))
    assert np.isfinite(m.pdf(wi, wo)) and m.pdf(wi, wo) > 0
    assert len(plausible.make("modified-phong").components()) == 2
