"""The Sum model: value, sampling mixture, claims, bad input."""

import math

import numpy as np
import pytest

import plausible
from plausible.models.sum import Sum
from reference import chi2_sampler_pvalue, check_sampling, hemisphere_rule, quad_albedo


def parts():
    return [plausible.make("lambertian", rd=[0.2, 0.3, 0.4]),
            (plausible.make("reciprocal-phong", ks=1.0, n=40), [0.3, 0.2, 0.1]),
            (plausible.make("ward", alpha_x=0.2, alpha_y=0.2, rd=0.0), 0.25)]


def test_value_is_the_scaled_sum_of_the_parts(rng):
    m = Sum(parts())
    wi, wo = rng.normal(size=(50, 3)), rng.normal(size=(50, 3))
    wi[:, 2], wo[:, 2] = np.abs(wi[:, 2]), np.abs(wo[:, 2])
    a, (b, sb), (c, sc) = parts()
    want = a.eval(wi, wo) + b.eval(wi, wo)[:, None] * np.array(sb) + c.eval(wi, wo)[:, None] * sc
    np.testing.assert_allclose(m.eval(wi, wo), want, rtol=1e-14)


def test_albedo_is_the_scaled_sum_of_the_albedos():
    m = Sum(parts())
    wi = np.array([math.sin(0.5), 0, math.cos(0.5)])
    a, (b, sb), (c, sc) = parts()
    want = np.array(a.params["rd"]) * 1.0 + quad_albedo(b, wi) * np.array(sb) + quad_albedo(c, wi) * sc
    np.testing.assert_allclose(plausible.albedo(m, wi).value, want, rtol=2e-4)


def test_pdf_integrates_to_the_sampled_fraction_and_the_sampler_follows_it():
    m = Sum(parts())
    assert math.isclose(sum(m.probabilities), 1.0, rel_tol=1e-15)
    for t in (0.0, 60.0):
        wi = np.array([math.sin(math.radians(t)), 0, math.cos(math.radians(t))])
        d, w = hemisphere_rule(200, 200)
        # the pdf's mass on the hemisphere is the fraction of samples above the horizon
        above = np.mean(m.sample(wi, np.random.default_rng(5).random((200_000, 3))).pdf > 0)
        assert abs(np.sum(m.pdf(wi, d) * w) - above) < 3e-3
        check_sampling(m, wi, n=5000)
    assert chi2_sampler_pvalue(m, np.array([0.5, 0.0, math.sqrt(0.75)]), n=40_000) > 1e-4


def test_probabilities_follow_the_scaled_albedo_estimates():
    lam = plausible.make("lambertian", rd=1.0)
    m = Sum([(lam, 0.3), (lam, 0.1)])
    np.testing.assert_allclose(m.probabilities, (0.75, 0.25), rtol=1e-12)


def test_a_part_with_no_estimated_albedo_keeps_a_positive_probability():
    m = Sum([plausible.make("lambertian", rd=0.5), (plausible.make("lambertian", rd=0.5), 0.0)])
    assert min(m.probabilities) > 0


def test_reciprocal_exactly_when_every_part_claims_it():
    assert Sum(parts()).reciprocal
    assert not Sum(parts() + [plausible.make("phong")]).reciprocal


@pytest.mark.parametrize("bad,match", [([], "non-empty"), ("lambertian", "parameter 'parts'"),
                                       ([1.0], "part 0 must be a model"),
                                       ([(plausible.make("lambertian"), -1.0)], "parameter 'scale'"),
                                       ([(plausible.make("lambertian"), [1.0, 2.0])], "channel counts")])
def test_bad_parts_raise_naming_the_parameter(bad, match):
    with pytest.raises(ValueError, match=match):
        Sum(bad if match != "channel counts" else bad + [plausible.make("lambertian", rd=[0.1, 0.2, 0.3])])
