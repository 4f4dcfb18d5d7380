"""Every checker must be able to fail: deliberately broken models are rejected
with the right figure, and the plausible models pass."""

import math

import numpy as np
import pytest

import plausible
from plausible.analysis import albedo, chi2, direction, energy, reciprocity, sampling_consistency
from plausible.analysis.checks import ENERGY_THETAS
from plausible.bxdf import Sample
from plausible.models.phong import ReciprocalPhong, lobe_pdf, phong_sample


class Asymmetric(ReciprocalPhong):
    """Reciprocal Phong times (1 + 0.3 wi.x): not symmetric."""

    def _f(self, ops, wi, wo, p):
        return super()._f(ops, wi, wo, p) * (1.0 + 0.3 * wi[0])


class OverBright(ReciprocalPhong):
    """5% too bright: albedo 1.05 at normal incidence."""

    def _f(self, ops, wi, wo, p):
        return 1.05 * super()._f(ops, wi, wo, p)


class PdfOffBy10(ReciprocalPhong):
    def _pdf(self, ops, wi, wo, q):
        return 1.1 * lobe_pdf(ops, wi, wo, q.n)


class WrongExponentSampler(ReciprocalPhong):
    """Samples cos^(1.25 n) but claims cos^n."""

    def _sample(self, ops, wi, u, q):
        return phong_sample(ops, wi, 1.25 * q.n, u[1], u[2])


class DropsQuadrant(ReciprocalPhong):
    """Never produces samples whose lobe-frame azimuth lies in the last quarter."""

    def _sample(self, ops, wi, u, q):
        return phong_sample(ops, wi, q.n, u[1], 0.75 * u[2])


class BadWeight(ReciprocalPhong):
    """Returns weights 2% off eval*cos/pdf."""

    def sample(self, wi, u):
        s = super().sample(wi, u)
        return Sample(s.wo, 1.02 * s.weight, s.pdf)


def make(cls, **kw):
    m = cls(**kw)
    return m


def test_reciprocity_rejects_asymmetric_model_and_reports_worst_pair():
    r = reciprocity(make(Asymmetric, n=10))
    assert not r.passed and r.figure > 0.1
    wi, wo = np.array(r.worst["wi"]), np.array(r.worst["wo"])
    m = make(Asymmetric, n=10)
    f1, f2 = m.eval(wi, wo), m.eval(wo, wi)
    assert abs(f1 - f2) / max(f1, f2) == pytest.approx(r.figure)
    assert reciprocity(plausible.make("reciprocal-phong", n=10)).passed


@pytest.mark.parametrize("name", ["phong", "blinn"])
def test_original_phong_and_blinn_fail_reciprocity(name):
    r = reciprocity(plausible.make(name, n=20))
    assert not r.passed and r.figure > 0.5


def test_energy_rejects_overbright_model_at_the_right_direction():
    r = energy(make(OverBright, n=10), thetas_deg=(0, 30, 60, 89))
    assert not r.passed
    assert r.figure == pytest.approx(1.05, abs=1e-6)
    assert r.worst["theta_i_deg"] == 0
    assert r.details["onset_deg"] == 0
    assert energy(plausible.make("reciprocal-phong", n=10), thetas_deg=(0, 30, 60, 89)).passed


def test_energy_reports_onset_for_original_phong():
    r = energy(plausible.make("phong", n=1.0, ks=1.0))
    assert not r.passed
    # albedo at theta: (1/cos theta) * reciprocal albedo; exceeds 1 beyond some angle
    assert r.details["onset_deg"] is not None and r.details["onset_deg"] > 0
    # the grid reaches cos(theta) = 1e-9, where the albedo is a reciprocal Phong's over 1e-9
    t = r.worst["theta_i_deg"]
    assert t == max(ENERGY_THETAS) and math.cos(math.radians(t)) == pytest.approx(1e-9, rel=1e-6)
    recip = albedo(plausible.make("reciprocal-phong", n=1.0, ks=1.0), direction(math.radians(t))).value
    assert r.figure == pytest.approx(recip / math.cos(math.radians(t)), rel=1e-3)


def test_sampling_consistency_rejects_pdf_off_by_10_percent():
    r = sampling_consistency(make(PdfOffBy10, n=20), thetas_deg=(0, 45), n_samples=20000)
    assert not r.passed
    assert r.details["max_pdf_integral"] == pytest.approx(1.1, rel=1e-3)


def test_sampling_consistency_rejects_wrong_weights():
    r = sampling_consistency(make(BadWeight, n=20), thetas_deg=(0,), n_samples=5000)
    assert not r.passed
    assert r.details["weight_rel_err"] == pytest.approx(0.02, rel=1e-6)


def test_sampling_consistency_rejects_wrong_exponent_via_albedo():
    # The weights are consistent with eval/pdf but the sampler draws another
    # distribution: the Monte Carlo albedo no longer matches the quadrature.
    r = sampling_consistency(make(WrongExponentSampler, n=20), thetas_deg=(0, 45), n_samples=50000)
    assert not r.passed
    assert r.details["max_albedo_mismatch_sigma"] > 10


@pytest.mark.parametrize("cls", [WrongExponentSampler, DropsQuadrant, PdfOffBy10])
@pytest.mark.parametrize("theta", [0, 45, 85])
def test_chi2_rejects_broken_samplers(cls, theta):
    r = chi2(make(cls, n=30), direction(math.radians(theta)), n_samples=100_000)
    assert not r.passed and r.p_value < 1e-8, r.message


@pytest.mark.parametrize("n", [1e3, 1e4])
@pytest.mark.parametrize("theta", [0, 60, 85, 89.5])
def test_chi2_passes_sharp_lobes_at_grazing(n, theta):
    for name in ("reciprocal-phong", "reciprocal-blinn"):
        r = chi2(plausible.make(name, n=n), direction(math.radians(theta), 0.4), n_samples=100_000, alpha=0.001)
        assert r.passed, (name, r.message)


def test_chi2_fixed_coarse_grid_gives_false_failures_where_adaptive_passes():
    m = plausible.make("reciprocal-phong", n=1e4)
    wi = direction(math.radians(60))
    fixed = chi2(m, wi, n_samples=100_000, method="fixed")
    adaptive = chi2(m, wi, n_samples=100_000)
    assert not fixed.passed and fixed.p_value < 1e-10
    assert adaptive.passed


def test_chi2_takes_a_binning_object_and_a_broken_one_fails():
    """The binning is an object: the fixed one given directly is the test method="fixed"
    names; a binning whose expected counts are off by 10% is rejected."""
    from plausible.analysis.chi2 import Cells, FixedBinning

    m = plausible.make("reciprocal-phong", n=20)
    wi = direction(math.radians(30))
    by_name = chi2(m, wi, n_samples=20_000, method="fixed", n_theta=8, n_phi=8)
    by_object = chi2(m, wi, n_samples=20_000, binning=FixedBinning(8, 8))
    assert by_object.statistic == by_name.statistic and by_name.passed

    class Skewed(FixedBinning):
        def cells(self, model, wi):
            c = super().cells(model, wi)
            bands = [(a, b, e, x * (1.1 if k % 2 else 0.9)) for k, (a, b, e, x) in enumerate(c.bands)]
            return Cells(c.t_edges, bands, c.phi0)

    assert chi2(m, wi, n_samples=20_000, binning=Skewed(8, 8)).p_value < 1e-10


def test_chi2_errors_echo_the_value_given():
    m = plausible.make("lambertian")
    with pytest.raises(ValueError, match="method must be one of 'adaptive', 'fixed', got 'naive'"):
        chi2(m, [0, 0, 1], method="naive")
    with pytest.raises(ValueError, match=r"n_samples must be a whole number \[1000, 100000000\], got 10"):
        chi2(m, [0, 0, 1], n_samples=10)


def test_chi2_sidak_correction():
    from plausible.analysis import sidak

    assert sidak(0.01, 1) == pytest.approx(0.01)
    assert (1 - sidak(0.01, 10)) ** 10 == pytest.approx(0.99)


def test_check_report_is_json_and_passes_for_modified_phong():
    import json

    rep = plausible.check(plausible.make("modified-phong"), quick=True)
    d = json.loads(rep.to_json())
    assert d["passed"] is True
    assert [r["name"] for r in d["results"]] == ["reciprocity", "energy", "sampling", "chi2"]


def test_check_report_names_failures_for_phong():
    rep = plausible.check(plausible.make("phong", n=20), quick=True)
    assert not rep.passed
    assert not rep["reciprocity"].passed and not rep["energy"].passed
    assert rep["sampling"].passed and rep["chi2"].passed


@pytest.mark.parametrize("cls,fails", [(Asymmetric, "reciprocity"), (OverBright, "energy"),
                                       (PdfOffBy10, "sampling"), (WrongExponentSampler, "chi2"),
                                       (DropsQuadrant, "chi2"), (BadWeight, "sampling")])
def test_quick_check_catches_every_broken_model(cls, fails):
    """``check(quick=True)`` (its samples on the compiled kernels where Dr.Jit is there,
    its albedos to ``QUICK_ALBEDO_TOL``) fails each broken model on the property it breaks,
    and passes the model they break."""
    rep = plausible.check(make(cls, n=30), quick=True)
    assert not rep[fails].passed and not rep.passed, str(rep)
    assert plausible.check(plausible.make("reciprocal-phong", n=30), quick=True).passed


def test_quick_chi2_cells_settle_far_below_the_count_noise():
    """The quick check's cells stop refining at ``QUICK_SETTLE`` (1e-3 of the mean cell);
    for a lobe whose bands never settle (a ``cos^0`` Phong lobe's jump) their expected
    counts at the quick check's 50,000 samples differ from those refined to 1e-4 (a
    second, finer computation) by at most 5 % of each cell's Poisson noise, and shift
    Pearson's statistic by ``sum (delta^2 / expected)`` <= 0.01, against its standard
    deviation ``sqrt(2 dof)``, about 22 for these 256 cells."""
    from plausible.analysis.chi2 import AdaptiveBinning
    from plausible.analysis.report import QUICK_SETTLE

    m = plausible.make("phong", ks=1.0, n=0.0)
    n = 50_000
    for theta in (45, 80):
        wi = direction(math.radians(theta))
        quick, fine = AdaptiveBinning(settle=QUICK_SETTLE).cells(m, wi), AdaptiveBinning().cells(m, wi)
        eq = np.concatenate([e for *_, e in quick.bands]) * n
        ef = np.concatenate([e for *_, e in fine.bands]) * n
        assert len(eq) == len(ef) == 256
        d = np.abs(eq - ef)
        assert d.max() > 0     # the two computations differ: the quick one stopped earlier
        assert np.all(d <= 0.05 * np.sqrt(np.maximum(ef, 1.0)))
        assert np.sum(d ** 2 / np.maximum(ef, 1.0)) <= 0.01


class Negative(ReciprocalPhong):
    """Reciprocal Phong minus a constant: symmetric, albedo below 1, and negative on most pairs."""

    def _f(self, ops, wi, wo, p):
        return super()._f(ops, wi, wo, p) - 0.2


class NotFinite(ReciprocalPhong):
    """NaN (or inf) where wi.x > 0.5; the rest reciprocal Phong."""

    value = math.nan

    def _f(self, ops, wi, wo, p):
        return ops.where(wi[0] > 0.5, self.value, super()._f(ops, wi, wo, p))


class Infinite(NotFinite):
    value = math.inf


class NanPdf(ReciprocalPhong):
    def _pdf(self, ops, wi, wo, q):
        return lobe_pdf(ops, wi, wo, q.n) * math.nan


@pytest.mark.parametrize("cls, words", [(Negative, "f is negative (-0.2"), (NotFinite, "f is not finite (nan)"),
                                        (Infinite, "f is not finite (inf)")])
def test_energy_fails_a_function_that_is_no_brdf_by_name(cls, words):
    # before: f - 0.2 passed energy (its albedo is below 1), NaN raised a TypeError deep inside energy, and an
    # infinite f passed with albedo inf after minutes of refinement (an outside audit of bad input)
    m = make(cls, n=20)
    e = energy(m, thetas_deg=(0, 60, 89))
    assert not e.passed and not e.unresolved and words in e.worst["problems"][0], e.worst
    rep = plausible.check(m, quick=True)
    verdict = {r.name: r.passed for r in rep.results}
    assert not verdict["energy"] and not verdict["sampling"] and not rep.passed
    assert energy(make(ReciprocalPhong, n=20), thetas_deg=(0, 60, 89)).passed       # the same model, a BRDF


def test_chi2_fails_a_pdf_that_is_not_finite():
    r = chi2(make(NanPdf, n=30), direction(math.radians(30)), n_samples=20_000)
    assert not r.passed and "not finite" in r.message, r.message     # before: passed, p-value 1


class RoundsToNegative(ReciprocalPhong):
    """Reciprocal Phong with -1e-17 where it is exactly 0 (the rounding of a formula): still a BRDF."""

    def _f(self, ops, wi, wo, p):
        f = super()._f(ops, wi, wo, p)
        return ops.where(f == 0.0, -1e-17, f)


def test_rounding_below_zero_is_no_negative_brdf_and_the_full_check_takes_few_samples():
    # a second reader: the first floor (f < 0) failed such a model; and check() asked quick mode's 4000
    # samples of the full check too (its chi-square needs 1000)
    from plausible.analysis.checks import value_problem
    assert value_problem(make(RoundsToNegative, n=20), [direction(0.0), direction(1.2)]) is None
    assert "f is negative" in value_problem(make(Negative, n=20), [direction(0.0)])
    assert plausible.check(plausible.make("lambertian"), n_samples=2000).passed
