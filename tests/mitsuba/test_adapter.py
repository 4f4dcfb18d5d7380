"""The Mitsuba adapter (issue 15): built-in plugins, Python mi.BSDF subclasses and
the conventions (cosine, si.wi, transport modes, delta and transmission lobes,
sides), each against a closed form or a second method."""

import math

import numpy as np
import pytest

from mi_helpers import dr, mi  # noqa: F401  (sets the variant)

import plausible
from plausible.analysis import chi2, direction, energy, reciprocity, sampling_consistency
from plausible.analysis.adapters import tolerances
from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict, load_bsdf_xml
from plausible.fresnel import dielectric
from plausible.arrays.ops import NP


class PyLambert(mi.BSDF):
    """A Python Lambert BSDF with cosine sampling; subclasses break one thing each."""

    RHO = 0.6

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.m_flags = mi.BSDFFlags.DiffuseReflection | mi.BSDFFlags.FrontSide
        self.m_components = [self.m_flags]

    def value(self, si, wo):   # f cos, Mitsuba's eval
        return self.RHO / math.pi * wo.z

    def true_pdf(self, si, wo):
        return mi.warp.square_to_cosine_hemisphere_pdf(wo)

    def eval(self, ctx, si, wo, active=True):
        ok = active & (si.wi.z > 0) & (wo.z > 0)
        return dr.select(ok, mi.Color3f(self.value(si, wo)), mi.Color3f(0))

    def pdf(self, ctx, si, wo, active=True):
        ok = active & (si.wi.z > 0) & (wo.z > 0)
        return dr.select(ok, self.true_pdf(si, wo), 0.0)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        bs = dr.zeros(mi.BSDFSample3f)
        bs.wo = mi.warp.square_to_cosine_hemisphere(sample2)
        ok = active & (si.wi.z > 0) & (bs.wo.z > 0)
        bs.pdf = dr.select(ok, self.true_pdf(si, bs.wo), 0.0)
        bs.eta = 1.0
        bs.sampled_type = mi.UInt32(int(mi.BSDFFlags.DiffuseReflection))
        bs.sampled_component = mi.UInt32(0)
        w = self.value(si, bs.wo) / dr.select(ok, self.true_pdf(si, bs.wo), 1.0)
        return bs, dr.select(ok, mi.Color3f(w), mi.Color3f(0))

    def traverse(self, callback):
        pass

    def to_string(self):
        return type(self).__name__


class PdfScaled(PyLambert):
    """pdf() 10% too high (the sampler is the true cos/pi)."""

    def pdf(self, ctx, si, wo, active=True):
        return 1.1 * super().pdf(ctx, si, wo, active)


class EnergyGain(PyLambert):
    RHO = 1.2


class Asymmetric(PyLambert):
    """f = rho/pi (1 + 0.3 wi.x): not reciprocal (weights consistent)."""

    def value(self, si, wo):
        return self.RHO / math.pi * (1 + 0.3 * si.wi.x) * wo.z


def load(cls):
    mi.register_bsdf(cls.__name__.lower(), lambda props: cls(props))
    return MitsubaBSDF(mi.load_dict({"type": cls.__name__.lower()}))


def test_correct_python_bsdf_passes_with_closed_form_albedo():
    rep = plausible.check(load(PyLambert), quick=True)
    assert rep.passed, str(rep)
    assert rep["energy"].figure == pytest.approx(0.6, abs=1e-6)   # float32 rho


def test_python_bsdf_with_scaled_pdf_fails_sampling_and_chi2():
    b = load(PdfScaled)
    s = sampling_consistency(b, thetas_deg=(30,), n_samples=20_000, tol=tolerances(b)["sampling"])
    assert not s.passed and s.figure == pytest.approx(0.1, rel=1e-4)   # pdf(wi, sampled wo) vs bs.pdf
    assert s.details["max_pdf_integral"] == pytest.approx(1.1, abs=1e-4)
    assert not chi2(b, direction(0.5), n_samples=20_000).passed


def test_python_bsdf_gaining_energy_fails_energy():
    r = energy(load(EnergyGain), thetas_deg=(0, 45))
    assert not r.passed and r.figure == pytest.approx(1.2, abs=1e-6)


def test_asymmetric_python_bsdf_fails_reciprocity():
    b = load(Asymmetric)
    r = reciprocity(b, tol=tolerances(b)["reciprocity"])
    assert not r.passed and 0.3 < r.figure <= 0.6 / 1.3 + 1e-6


def test_builtin_diffuse_albedo_and_float32_reciprocity():
    b = MitsubaBSDF(load_bsdf_dict({"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.2, 0.5, 0.8]}}))
    a = plausible.albedo(b, direction(math.radians(40)))
    np.testing.assert_allclose(a.value, [0.2, 0.5, 0.8], atol=1e-6)
    r = reciprocity(b, tol=b.precision)
    assert r.passed and r.figure < 1e-6   # a smooth lobe in float32: a few units of 2^-24


def test_eval_divides_mitsubas_cosine_and_maps_si_wi():
    """A non-reciprocal plausible plugin (original Phong, divided by cos(theta_light)):
    importance mode is the float64 model f(wi, wo) and radiance mode its transpose."""
    import plausible.mitsuba as pm

    pm.register()
    model = plausible.make("phong", ks=0.5, n=10.0)
    b = MitsubaBSDF(mi.load_dict({"type": "phong_original", "ks": 0.5, "n": 10.0}))
    rng = np.random.default_rng(3)
    wi = np.stack([plausible.analysis.direction(math.acos(z), p) for z, p in
                   zip(rng.uniform(0.2, 1, 50), rng.uniform(0, 6, 50))])
    wo = np.stack([plausible.analysis.direction(math.acos(z), p) for z, p in
                   zip(rng.uniform(0.2, 1, 50), rng.uniform(0, 6, 50))])
    imp = b.with_(mode="importance")
    np.testing.assert_allclose(imp.eval(wi, wo)[:, 0], model.eval(wi, wo), rtol=2e-5)
    np.testing.assert_allclose(b.eval(wi, wo)[:, 0], model.eval(wo, wi), rtol=2e-5)
    assert [lb for lb, _ in b.views()] == ["importance"]


@pytest.mark.slow
def test_non_reciprocal_plugin_is_checked_in_both_modes():
    import plausible.mitsuba as pm

    pm.register()
    rep = plausible.check(mi.load_dict({"type": "phong_original", "ks": 0.5, "n": 10.0}), quick=True)
    names = [r.name for r in rep.results]
    assert "reciprocity [importance]" in names and "energy [importance]" in names
    assert not rep["reciprocity"].passed and not rep["reciprocity [importance]"].passed


def test_plastic_delta_lobe_is_excluded_and_its_fresnel_reflectance_reported():
    b = MitsubaBSDF(load_bsdf_dict({"type": "plastic", "int_ior": 1.5, "ext_ior": 1.0}))
    assert b.delta_components == [0] and b.smooth_components == [1]
    for t in (0.0, 60.0, 85.0):
        wi = direction(math.radians(t))
        np.testing.assert_allclose(b.delta_reflectance(wi), dielectric(NP, math.cos(math.radians(t)), 1.5),
                                   rtol=1e-5)
    # the smooth part alone: its albedo is (1 - F) times the rest, below 1 - F(0)
    assert float(np.max(plausible.albedo(b, direction(0.0)).value)) < 1 - 0.04


def test_conductor_is_pure_delta_all_checks_not_applicable():
    rep = plausible.check(load_bsdf_dict({"type": "conductor"}), quick=True)
    assert [r[3] for r in rep.rows()][:4] == ["N/A"] * 4
    assert rep["energy+delta"].figure == pytest.approx(1.0, abs=1e-6)   # a perfect mirror (material none)


def test_transmission_is_excluded_and_said():
    b = MitsubaBSDF(load_bsdf_dict({"type": "roughdielectric", "alpha": 0.3}))
    assert b.transmission_components and any("NOT checked" in n for n in b.notes)
    s = sampling_consistency(b, thetas_deg=(30,), n_samples=20_000, tol=tolerances(b)["sampling"])
    assert s.passed, s.worst   # reflection-only sampling, consistent with the masked pdf


def test_twosided_back_side_is_a_view_only_where_it_differs():
    same = MitsubaBSDF(load_bsdf_dict({"type": "twosided", "bsdf": {"type": "diffuse"}}))
    assert same.has_back and same.views() == []
    two = MitsubaBSDF(load_bsdf_dict({"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": 0.2},
                                      "bsdf2": {"type": "diffuse", "reflectance": 0.8}}))
    (label, back), = two.views()
    assert label == "back"
    assert float(np.mean(plausible.albedo(back, direction(0.5)).value)) == pytest.approx(0.8, abs=1e-6)
    assert float(np.mean(plausible.albedo(two, direction(0.5)).value)) == pytest.approx(0.2, abs=1e-6)


def test_non_reflective_and_non_bsdf_objects_are_refused():
    with pytest.raises(ValueError, match="not a reflective BSDF"):
        MitsubaBSDF(load_bsdf_dict({"type": "null"}))
    with pytest.raises(TypeError, match="is not a BSDF"):
        plausible.check(mi.load_dict({"type": "sphere"}))
    with pytest.raises(ValueError, match="not a BSDF"):
        load_bsdf_dict({"type": "sphere"})


def test_xml_bsdf_found_by_id(tmp_path):
    p = tmp_path / "scene.xml"
    p.write_text('<scene version="3.0.0"><bsdf type="roughconductor" id="metal"><float name="alpha" value="0.3"/>'
                 '</bsdf><bsdf type="diffuse" id="wall"/><shape type="rectangle"><ref id="metal"/></shape></scene>')
    b = load_bsdf_xml(str(p), "metal")
    assert float(mi.traverse(b)["alpha.value"][0]) == pytest.approx(0.3)
    assert "SmoothDiffuse" in str(load_bsdf_xml(str(p), "wall"))   # not on a shape: loaded on its own
    with pytest.raises(ValueError, match="ids in the file: metal, wall"):
        load_bsdf_xml(str(p), "gold")


def ggx_f(alpha):
    """GGX with uncorrelated Smith masking and Fresnel 1 (Walter et al. 2007, eqs. 20, 33, 34), float64."""
    def f(wi, wo):
        h = wi + wo
        h /= np.linalg.norm(h, axis=-1, keepdims=True)
        a2 = alpha * alpha
        d = a2 / (math.pi * (h[:, 2] ** 2 * (a2 - 1) + 1) ** 2)

        def g1(w):
            c2 = w[:, 2] ** 2
            return 2 / (1 + np.sqrt(1 + a2 * (1 - c2) / c2))

        return d * g1(wi) * g1(wo) / (4 * wi[:, 2] * wo[:, 2])
    return f


def test_roughconductor_matches_the_ggx_formula_through_both_adapters():
    """Mitsuba's roughconductor (white) and Walter's formula written here in NumPy agree
    to float32 precision, value by value and as albedos (energy lost 1.2% at normal incidence)."""
    b = MitsubaBSDF(load_bsdf_dict({"type": "roughconductor", "distribution": "ggx", "alpha": 0.1}))
    ref = plausible.analysis.adapters.CallableBxDF(ggx_f(0.1))
    rng = np.random.default_rng(8)
    wi, wo = (np.stack([direction(math.acos(z), p) for z, p in zip(rng.uniform(0.1, 1, 64), rng.uniform(0, 6, 64))])
              for _ in range(2))
    np.testing.assert_allclose(b.eval(wi, wo)[:, 0], ref.eval(wi, wo), rtol=b.precision)
    for t in (0, 60, 80):
        a_mi = float(np.mean(plausible.albedo(b, direction(math.radians(t))).value))
        assert a_mi == pytest.approx(float(plausible.albedo(ref, direction(math.radians(t))).value), abs=1e-6)
    assert float(plausible.albedo(ref, direction(0.0)).value) == pytest.approx(0.98830, abs=1e-5)


def test_furnace_render_of_a_diffuse_patch_is_its_reflectance():
    from plausible.figures.mitsuba_builtins import furnace_albedo

    v, se = furnace_albedo({"type": "diffuse", "reflectance": 0.5}, spp=16, res=8)
    assert se < 0.01 and abs(v - 0.5) <= 4 * se + 1e-4
