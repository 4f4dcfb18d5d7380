"""The Mitsuba 3 plugins agree with the NumPy models, pass Mitsuba's chi-square
test, read textures and aliases, and expose the documented frame/direction
conventions.  Parametrised over the registry: a new model is covered at once."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import (PLUGIN_MODELS, interaction, mi, moderate, spectrum_np, to_dict,
                        upper_dirs, vec3)

import plausible

pytestmark = pytest.mark.drjit

PLUGIN_LIST = sorted(PLUGIN_MODELS)
N = 512


def _model_and_plugin(plugin):
    name = PLUGIN_MODELS[plugin]
    params = moderate(name)
    return plausible.make(name, **params), mi.load_dict(to_dict(plugin, params)), params


def _directions(model, rng):
    """Random pairs plus pairs near the model's peak (so lobes are exercised)."""
    wi = upper_dirs(rng, N)
    wo = upper_dirs(rng, N)
    u = rng.random((N, 3)).astype(np.float32).astype(np.float64)
    near = model.sample(wi[: N // 2], u[: N // 2]).wo
    ok = near[:, 2] > 0.05
    wo[: N // 2][ok] = near[ok]
    wo = wo.astype(np.float32).astype(np.float64)
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    return wi, wo


def _close(got, want, what):
    scale = max(float(np.max(np.abs(want))), 1e-30)
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-4 * scale, err_msg=what)


@pytest.mark.parametrize("mode", ["Radiance", "Importance"])
@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_eval_pdf_match_numpy(plugin, mode):
    """eval == f(light, view) cos(theta_o) and pdf == model.pdf(si.wi, wo), float32 tolerance.

    Radiance mode: plausible's wi (light) is Mitsuba's wo; Importance: si.wi.
    """
    model, bsdf, _ = _model_and_plugin(plugin)
    rng = np.random.default_rng(7)
    wi, wo = _directions(model, rng)
    ctx = mi.BSDFContext(getattr(mi.TransportMode, mode))
    si = interaction(wi)
    got_f = spectrum_np(bsdf.eval(ctx, si, vec3(wo)))
    light, view = (wo, wi) if mode == "Radiance" else (wi, wo)
    want_f = model.eval(light, view) * wo[:, 2:3] * np.ones((1, 3))
    _close(got_f, np.broadcast_to(want_f, got_f.shape), f"{plugin} eval")
    got_p = np.array(bsdf.pdf(ctx, si, vec3(wo)), dtype=np.float64)
    _close(got_p, model.pdf(wi, wo), f"{plugin} pdf")


@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_sample_matches_numpy(plugin):
    """sample: wo, pdf and weight (= f(wo, si.wi) cos / pdf) equal the NumPy model's
    for the same u (u[...,0] <- sample1, u[...,1:] <- sample2)."""
    model, bsdf, _ = _model_and_plugin(plugin)
    rng = np.random.default_rng(11)
    wi = upper_dirs(rng, N, zmin=0.1)
    u = rng.random((N, 3)).astype(np.float32).astype(np.float64)
    # keep u away from the measure-zero switch points where float32 and float64
    # may legitimately choose different branches (lobe choice, quadrant split)
    u = np.clip(u, 1e-3, 1 - 1e-3)
    ref = model.sample(wi, u)
    bs, w = bsdf.sample(mi.BSDFContext(), interaction(wi), mi.Float(u[:, 0].astype(np.float32)),
                        mi.Point2f(np.ascontiguousarray(u[:, 1:].T, dtype=np.float32)))
    wo = np.array(bs.wo, dtype=np.float64).T
    pdf = np.array(bs.pdf, dtype=np.float64)
    weight = spectrum_np(w)
    ok = ref.pdf > 0
    assert np.mean(ok) > 0.5
    np.testing.assert_allclose(wo[ok], ref.wo[ok], atol=2e-4, err_msg=f"{plugin} wo")
    _close(pdf[ok], ref.pdf[ok], f"{plugin} pdf")
    want_w = np.zeros((N, 3))
    want_w[ok] = (model.eval(ref.wo[ok], wi[ok]) * ref.wo[ok, 2:3] / ref.pdf[ok, None]
                  * np.ones((1, 3)))
    _close(weight[ok], want_w[ok], f"{plugin} weight")
    assert np.all(weight[~ok] == 0) and np.all(pdf[~ok] == 0)


CHI2_ANGLES = [0.0, 45.0, 82.0]


@pytest.mark.parametrize("theta", CHI2_ANGLES)
@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_chi2(plugin, theta):
    """Mitsuba's chi-square harness: sample() is distributed as pdf() says.

    Default resolution (res=101, ires=4) with 2e5 samples suffices for the
    moderate parameters used here; the significance is Sidak-corrected over
    every chi-square test in this module.
    """
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    params = moderate(PLUGIN_MODELS[plugin])
    t = np.radians(theta)
    wi = [float(np.sin(t)), 0.0, float(np.cos(t))]
    sample_func, pdf_func = BSDFAdapter(plugin, to_dict(plugin, params), wi=wi)
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=sample_func, pdf_func=pdf_func,
                         sample_dim=3, sample_count=200_000, res=101, ires=4, seed=3)
    ok = chi2.run(significance_level=0.01,
                  test_count=len(PLUGIN_LIST) * len(CHI2_ANGLES), quiet=True)
    assert ok, chi2.messages


def test_chi2_detects_a_wrong_pdf():
    """The harness as used above rejects a plugin whose pdf is not its sampler's
    density (pdf of the n=30 lobe while sampling n=15)."""
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    s_func, _ = BSDFAdapter("reciprocal_phong", {"type": "reciprocal_phong", "n": 15.0},
                            wi=[0.5, 0.0, 0.866])
    _, p_func = BSDFAdapter("reciprocal_phong", {"type": "reciprocal_phong", "n": 30.0},
                            wi=[0.5, 0.0, 0.866])
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=s_func, pdf_func=p_func,
                         sample_dim=3, sample_count=200_000, res=101, ires=4, seed=3)
    assert not chi2.run(significance_level=0.01, quiet=True)


def test_agreement_checker_detects_swapped_directions():
    """The eval comparison distinguishes f(light, view) from f(view, light) for the
    non-reciprocal Phong (so the Radiance/Importance test has teeth)."""
    model = plausible.make("phong", ks=0.8, n=20.0)
    rng = np.random.default_rng(7)
    wi, wo = _directions(model, rng)
    bsdf = mi.load_dict({"type": "phong_original", "ks": 0.8, "n": 20.0})
    got = spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))[:, 0]
    wrong = model.eval(wi, wo) * wo[:, 2]
    with pytest.raises(AssertionError):
        _close(got, wrong, "swapped")


# -- names, aliases, textures -------------------------------------------------------

def test_plugin_names_cover_registry():
    """One plugin per model ('-' -> '_'; registry 'phong' -> 'phong_original') plus
    Mitsuba 0.5's 'phong' = Modified Phong."""
    want = {("phong_original" if n == "phong" else n.replace("-", "_")) for n in plausible.names()}
    assert want | {"phong"} == set(PLUGIN_MODELS)
    assert PLUGIN_MODELS["phong"] == "modified-phong"
    assert PLUGIN_MODELS["phong_original"] == "phong"


def test_mitsuba05_phong_names_equal_native():
    """<bsdf type="phong"> with exponent / diffuse_reflectance / specular_reflectance
    evaluates exactly like modified_phong with n / kd / ks."""
    a = mi.load_dict({"type": "phong", "exponent": 25.0,
                      "diffuse_reflectance": {"type": "rgb", "value": [0.2, 0.3, 0.4]},
                      "specular_reflectance": 0.3})
    model = plausible.make("modified-phong", kd=[0.2, 0.3, 0.4], ks=0.3, n=25.0)
    rng = np.random.default_rng(3)
    wi, wo = _directions(model, rng)
    got = spectrum_np(a.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))
    _close(got, model.eval(wo, wi) * wo[:, 2:3], "phong aliases")


def test_unknown_and_out_of_range_parameters_raise():
    with pytest.raises(Exception, match="unknown parameter 'roughness'"):
        mi.load_dict({"type": "modified_phong", "roughness": 0.1})
    with pytest.raises(Exception, match="'kd' \\+ 'ks' must not exceed 1"):
        mi.load_dict({"type": "phong", "diffuse_reflectance": 0.8, "specular_reflectance": 0.5})
    with pytest.raises(Exception, match="parameter 'n' must lie in"):
        mi.load_dict({"type": "phong", "exponent": -1.0})


def test_textures_are_evaluated_at_the_surface_point():
    """A checkerboard kd and a checkerboard exponent: eval at uv in each checker cell
    equals the NumPy model built with that cell's values."""
    bsdf = mi.load_dict({
        "type": "modified_phong",
        "kd": {"type": "checkerboard", "color0": {"type": "rgb", "value": [0.1, 0.2, 0.3]},
               "color1": {"type": "rgb", "value": [0.5, 0.4, 0.2]}},
        "ks": 0.3,
        "n": {"type": "checkerboard", "color0": 10.0, "color1": 40.0},
    })
    assert bsdf.flags() & mi.BSDFFlags.SpatiallyVarying
    rng = np.random.default_rng(5)
    wi = upper_dirs(rng, 64, zmin=0.2)
    wo = upper_dirs(rng, 64, zmin=0.2)
    for uv, kd, n in [((0.25, 0.25), [0.1, 0.2, 0.3], 10.0), ((0.75, 0.25), [0.5, 0.4, 0.2], 40.0)]:
        si = interaction(wi)
        si.uv = mi.Point2f(*uv)
        model = plausible.make("modified-phong", kd=kd, ks=0.3, n=n)
        got = spectrum_np(bsdf.eval(mi.BSDFContext(), si, vec3(wo)))
        _close(got, model.eval(wo, wi) * wo[:, 2:3], f"texture at {uv}")
        # the sampling density uses the local exponent and the local kd (the lobe
        # choice is an ops.where on the parameters, so it follows the texture)
        got_p = np.array(bsdf.pdf(mi.BSDFContext(), si, vec3(wo)), dtype=np.float64)
        _close(got_p, model.pdf(wi, wo), f"texture pdf at {uv}")
        assert not np.allclose(got_p, plausible.make("modified-phong", kd=kd, ks=0.3,
                                                     n=50.0 - n).pdf(wi, wo), rtol=1e-2)


def test_flags():
    """Glossy | FrontSide for every plugin; Diffuse where a kd/rd lobe exists;
    Anisotropic only when the parameters make the model anisotropic."""
    F = mi.BSDFFlags
    aniso = mi.load_dict({"type": "ashikhmin_shirley", "nu": 10.0, "nv": 100.0})
    iso = mi.load_dict({"type": "ashikhmin_shirley", "nu": 50.0, "nv": 50.0})
    assert aniso.flags() & F.Anisotropic and not iso.flags() & F.Anisotropic
    assert mi.load_dict({"type": "phong"}).flags() & F.DiffuseReflection
    rp = mi.load_dict({"type": "reciprocal_phong"}).flags()
    assert rp & F.GlossyReflection and rp & F.FrontSide and not rp & F.DiffuseReflection
    assert mi.load_dict({"type": "blinn"}).flags() & F.NonSymmetric


# -- tangent orientation --------------------------------------------------------------

def test_cylinder_shading_frame():
    """On Mitsuba's default cylinder (axis z), sh_frame.s -- plausible's x, the axis
    of nu -- runs around the circumference and sh_frame.t along the axis."""
    scene = mi.load_dict({"type": "scene", "cyl": {"type": "cylinder", "radius": 1.0,
                                                   "bsdf": {"type": "ashikhmin_shirley"}}})
    angles = np.radians([0.0, 60.0, 135.0])
    o = np.stack([3 * np.cos(angles), 3 * np.sin(angles), np.full(3, 0.5)], -1)
    ray = mi.Ray3f(vec3(o), vec3(-o * np.array([1, 1, 0]) / 3.0))
    si = scene.ray_intersect(ray)
    s = np.array(si.sh_frame.s).T
    t = np.array(si.sh_frame.t).T
    n = np.array(si.sh_frame.n).T
    around = np.stack([-np.sin(angles), np.cos(angles), np.zeros(3)], -1)
    np.testing.assert_allclose(np.abs(np.sum(s * around, -1)), 1.0, atol=1e-5)
    np.testing.assert_allclose(np.abs(t[:, 2]), 1.0, atol=1e-5)
    np.testing.assert_allclose(n[:, :2], np.stack([np.cos(angles), np.sin(angles)], -1), atol=1e-5)


def test_anisotropic_lobe_is_wider_along_the_small_exponent():
    """Ashikhmin-Shirley with nu < nv: the lobe (and so the highlight) extends
    further along x = sh_frame.s than along y (checked on the plugin)."""
    bsdf = mi.load_dict({"type": "ashikhmin_shirley", "nu": 10.0, "nv": 1000.0,
                         "rd": 0.0, "rs": 0.5})
    wi = np.array([[0.0, 0.0, 1.0], [0.0, 0.0, 1.0]])
    d = np.radians(10.0)
    wo = np.array([[np.sin(d), 0.0, np.cos(d)], [0.0, np.sin(d), np.cos(d)]])
    f = spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))[:, 0]
    assert f[0] > 20 * f[1]
