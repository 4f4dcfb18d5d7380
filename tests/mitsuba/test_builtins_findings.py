"""What the checker found in Mitsuba's own roughconductor (docs/mitsuba-builtins.md),
reproduced by float64 formulas written here: the findings are Mitsuba's, not the adapter's."""

import math

import numpy as np
import pytest
from scipy.special import erf

from mi_helpers import mi  # noqa: F401  (sets the variant)

from plausible.analysis import direction, pdf_integral, sampling_consistency
from plausible.analysis.adapters import CallableBxDF, tolerances
from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict


def half(wi, wo):
    h = wi + wo
    return h / np.linalg.norm(h, axis=-1, keepdims=True)


def beckmann_d(h, a):
    c2 = h[:, 2] ** 2
    return np.exp(-(1 - c2) / c2 / a ** 2) / (math.pi * a * a * c2 * c2)


def beckmann_g1(w, a, walter):
    """Smith G1 for Beckmann: exact (erf), or Walter et al. 2007's rational approximation (eq. 27)."""
    c = w[:, 2]
    x = c / (a * np.sqrt(1 - c * c))
    if walter:
        return np.where(x >= 1.6, 1.0, (3.535 * x + 2.181 * x * x) / (1 + 2.276 * x + 2.577 * x * x))
    return 1 / (1 + (erf(x) - 1) / 2 + np.exp(-x * x) / (2 * x * math.sqrt(math.pi)))


def visible_pdf(a, walter):
    """pdf of wo for visible-normal sampling: G1(wi) <wi, h> D(h) / cos(theta_i) / (4 <wo, h>)."""
    def pdf(wi, wo):
        h = half(wi, wo)
        return beckmann_g1(wi, a, walter) * beckmann_d(h, a) / wi[:, 2] / 4
    return pdf


def test_beckmann_visible_pdf_uses_walters_g1_while_the_sampler_draws_the_exact_one():
    """roughconductor beckmann a=0.3 at 89 degrees: the adapter's pdf integral equals
    the float64 integral with Walter's approximate G1 (above 1), not the exact G1's."""
    wi = direction(math.radians(89))
    b = MitsubaBSDF(load_bsdf_dict({"type": "roughconductor", "distribution": "beckmann", "alpha": 0.3}))
    walter = pdf_integral(CallableBxDF(lambda x, y: np.ones(len(x)), pdf=visible_pdf(0.3, True)), wi).value
    exact = pdf_integral(CallableBxDF(lambda x, y: np.ones(len(x)), pdf=visible_pdf(0.3, False)), wi).value
    assert walter == pytest.approx(1.000808, abs=2e-6) and exact < 1
    assert pdf_integral(b, wi).value == pytest.approx(walter, abs=2e-5)
    # the sampler follows the exact distribution: its invalid fraction is 1 - exact, not 1 - walter
    s = b.sample(wi, np.random.default_rng(0).random((400_000, 3)))
    invalid = float(np.mean(s.pdf == 0))
    sigma = math.sqrt((1 - exact) * exact / 400_000)
    assert abs(invalid - (1 - exact)) < 4 * sigma < abs(invalid - (1 - walter))


def test_sharp_lobe_sampler_reports_a_pdf_off_by_1e3_where_pdf_is_exact():
    """ggx a=0.01, sample_visible off, normal incidence: pdf() at the sampled directions agrees
    with the float64 formula to 1e-5, the sampler's own pdf is off by more than 1e-3
    (float32), and the sampling check says so."""
    b = MitsubaBSDF(load_bsdf_dict({"type": "roughconductor", "distribution": "ggx", "alpha": 0.01,
                                    "sample_visible": False}))
    wi = direction(0.0)
    s = b.sample(wi, np.random.default_rng(1).random((50_000, 3)))
    ok = s.pdf > 0
    wo = s.wo[ok]
    h = half(np.broadcast_to(wi, wo.shape), wo)
    a2 = 1e-4
    d = a2 / (math.pi * (h[:, 2] ** 2 * (a2 - 1) + 1) ** 2)
    ref = d * h[:, 2] / (4 * np.sum(wo * h, axis=-1))
    np.testing.assert_allclose(b.pdf(wi, wo), ref, rtol=1e-5)
    assert np.max(np.abs(s.pdf[ok] - ref) / ref) > 1e-3
    r = sampling_consistency(b, thetas_deg=(0,), n_samples=50_000, tol=tolerances(b)["sampling"])
    assert not r.passed and "weight != eval*cos/pdf" in r.worst["problems"][0]
