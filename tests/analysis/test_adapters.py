"""Adapters (issue 15): plain callables and spec strings through plausible.check.

Each broken callable is rejected by the check that its defect concerns; correct
ones pass, with figures equal to closed forms or to the registered model the
callable wraps (a second method)."""

import math

import numpy as np
import pytest

import plausible
from plausible.analysis import chi2, direction, energy, reciprocity, sampling_consistency
from plausible.analysis.adapters import CallableBxDF, as_bxdf, load_python


def lambert(rho):
    def f(wi, wo):
        return np.full(len(wi), rho / math.pi)

    def pdf(wi, wo):
        return np.maximum(wo[:, 2], 0) / math.pi

    def sample(wi, u):
        r, phi = np.sqrt(u[:, 1]), 2 * math.pi * u[:, 2]
        return np.stack([r * np.cos(phi), r * np.sin(phi), np.sqrt(1 - u[:, 1])], axis=-1)

    f.pdf, f.sample = pdf, sample
    return f


def test_spec_string_is_a_registered_model():
    rep = plausible.check("lambertian:rd=0.6", quick=True)
    assert rep.passed and rep["energy"].figure == pytest.approx(0.6, abs=1e-9)


def test_correct_callable_passes_with_closed_form_albedo():
    rep = plausible.check(lambert(0.7), quick=True)
    assert rep.passed
    assert rep["energy"].figure == pytest.approx(0.7, abs=1e-9)
    assert rep["reciprocity"].figure == 0.0


def test_callable_without_sampler_reports_sampling_not_applicable():
    rep = plausible.check(lambda wi, wo: np.full(len(wi), 0.5 / math.pi), quick=True)
    assert rep.passed and rep["energy"].figure == pytest.approx(0.5, abs=1e-9)
    for name in ("sampling", "chi2"):
        assert rep[name].details["applicable"] is False
        assert "no sampler given" in rep[name].bound
    assert [r[3] for r in rep.rows()] == ["PASS", "PASS", "N/A", "N/A"]


def test_callable_wrapping_a_model_gives_the_models_figures():
    m = plausible.make("modified-phong", kd=0.3, ks=0.6, n=30)
    c = CallableBxDF(m.eval, m.pdf, m.sample, name="wrapped")
    wi = direction(math.radians(60))
    assert float(plausible.albedo(c, wi)) == pytest.approx(float(plausible.albedo(m, wi)), abs=1e-12)
    u = np.random.default_rng(0).random((100, 3))
    s1, s2 = m.sample(wi, u), c.sample(wi, u)
    np.testing.assert_allclose(s2.weight, s1.weight, rtol=1e-12)
    np.testing.assert_allclose(s2.pdf, s1.pdf, rtol=1e-12)


def test_asymmetric_callable_fails_reciprocity():
    f = lambda wi, wo: (1 + 0.3 * wi[:, 0]) * 0.5 / math.pi  # noqa: E731
    r = reciprocity(CallableBxDF(f))
    # worst pair: wi.x = +-1 gives (1.3 - 0.7) / 1.3 = 0.46 at most
    assert not r.passed and 0.3 < r.figure <= 0.6 / 1.3 + 1e-9


def test_energy_gaining_callable_fails_energy():
    r = energy(CallableBxDF(lambert(1.2)), thetas_deg=(0, 60))
    assert not r.passed and r.figure == pytest.approx(1.2, abs=1e-9)


def test_scaled_pdf_callable_fails_sampling_and_chi2():
    good = lambert(0.8)
    c = CallableBxDF(good, pdf=lambda wi, wo: 1.1 * good.pdf(wi, wo), sample=good.sample)
    s = sampling_consistency(c, thetas_deg=(30,), n_samples=20_000)
    assert not s.passed and s.details["max_pdf_integral"] == pytest.approx(1.1, abs=1e-4)
    assert not chi2(c, direction(math.radians(30)), n_samples=20_000).passed


def test_sampler_from_another_distribution_fails_chi2():
    good = lambert(0.8)

    def uniform(wi, u):   # uniform hemisphere, while the pdf claims cos/pi
        z, phi = u[:, 1], 2 * math.pi * u[:, 2]
        r = np.sqrt(1 - z * z)
        return np.stack([r * np.cos(phi), r * np.sin(phi), z], axis=-1)

    c = CallableBxDF(good, pdf=good.pdf, sample=uniform)
    r = chi2(c, direction(0.3), n_samples=20_000)
    assert not r.passed and r.p_value < 1e-10


def test_callable_output_shape_and_bad_objects_give_clear_errors():
    with pytest.raises(ValueError, match=r"must return shape \(1,\)"):
        CallableBxDF(lambda wi, wo: np.zeros(5))
    with pytest.raises(TypeError, match="model must be a registered model.*got int"):
        plausible.check(42)
    with pytest.raises(ValueError, match="unknown model 'nosuch'"):
        as_bxdf("nosuch")


def test_load_python_names_the_target():
    assert load_python("math:pi") == math.pi
    with pytest.raises(ValueError, match="package.module:function"):
        load_python("math.pi")
    with pytest.raises(ValueError, match="no attribute 'nope'"):
        load_python("math:nope")
