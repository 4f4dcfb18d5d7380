"""The plugins in the variants besides llvm_ad_rgb (issue 43): spatially varying
textures in scalar_rgb, the RGB-only plugins (published fits, MERL tables) in the
monochrome variants as their luminance."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import VARIANT, LogCapture, dr, mi, upper_dirs, variant  # noqa: F401 (a fixture)

import plausible
import plausible.mitsuba as pm
from plausible.models.merl import RES, read_merl, write_merl

pytestmark = pytest.mark.drjit

#: Rec. 709 / sRGB luminance weights of linear R, G, B (ITU-R BT.709, the Y row of
#: the sRGB-to-XYZ matrix), what a monochrome variant makes of a colour.
LUMINANCE = np.array([0.212671, 0.715160, 0.072169])


def one_point(wi, uv=(0.5, 0.5)):
    si = dr.zeros(mi.SurfaceInteraction3f) if not dr.is_array_v(mi.Float) else dr.zeros(mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.uv = mi.Point2f(*[float(x) for x in uv])
    return si


def value(bsdf, si, wo):
    ctx = mi.BSDFContext()
    return np.array(bsdf.eval(ctx, si, mi.Vector3f(*[float(x) for x in wo])), dtype=np.float64).ravel()


# -- scalar_rgb: one point per call --------------------------------------------------

@pytest.mark.parametrize("variant", ["scalar_rgb"], indirect=True)
def test_a_checkerboard_loads_and_evaluates_as_diffuse_in_scalar_rgb(variant):
    """lambertian with a checkerboard rd in scalar_rgb (the range check evaluates the
    texture one point per call): eval equals Mitsuba's diffuse with the same checkerboard
    at points of both colours (0.4 and 0.2)."""
    board = {"type": "checkerboard", "color0": {"type": "rgb", "value": [0.4, 0.1, 0.3]},
             "color1": {"type": "rgb", "value": [0.2, 0.6, 0.05]}}
    ours = mi.load_dict({"type": "lambertian", "rd": board})
    ref = mi.load_dict({"type": "diffuse", "reflectance": board})
    wi, wo = np.array([0.3, 0.1, 0.948683]), np.array([-0.6, 0.0, 0.8])
    seen = set()
    for uv in [(0.1, 0.1), (0.6, 0.1), (0.3, 0.8), (0.9, 0.7)]:
        got, want = value(ours, one_point(wi, uv), wo), value(ref, one_point(wi, uv), wo)
        np.testing.assert_allclose(got, want, rtol=1e-6)
        seen.add(round(float(got[0]), 5))
    assert len(seen) == 2


@pytest.mark.parametrize("variant", ["scalar_rgb"], indirect=True)
def test_a_textured_constraint_is_still_checked_in_scalar_rgb(variant):
    """modified_phong's kd + ks <= 1 at every texel, in scalar_rgb: a checkerboard kd
    whose colour1 (0.8) breaks it with ks = 0.3 is refused naming the constraint's point."""
    board = {"type": "checkerboard", "color0": {"type": "rgb", "value": 0.2},
             "color1": {"type": "rgb", "value": 0.8}}
    mi.load_dict({"type": "modified_phong", "kd": board, "ks": 0.1})
    with pytest.raises(Exception, match="break a constraint at uv"):
        mi.load_dict({"type": "modified_phong", "kd": board, "ks": 0.3})


# -- monochrome variants: RGB data as luminance -------------------------------------

MONO = ["llvm_ad_mono", "llvm_ad_mono_polarized"]


def mono_value(bsdf, wi, wo):
    """eval of one pair; in a polarized variant the M00 entry (the others are 0)."""
    v = value(bsdf, one_point(wi), wo)
    return v[0]


@pytest.mark.parametrize("variant", MONO, indirect=True)
def test_a_published_fit_is_its_luminance_in_a_mono_variant(variant):
    """plausible_material in a monochrome variant: eval is the Rec. 709 luminance of the
    NumPy model's RGB value f(wo, wi) cos(theta_o), at random pairs (before: a TypeError
    at the first eval, a Color1f given three channels)."""
    bsdf = mi.load_dict({"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"})
    model = plausible.material("alum-bronze", "ngan2005/ward")
    rng = np.random.default_rng(5)
    for wi, wo in zip(upper_dirs(rng, 4, 0.2), upper_dirs(rng, 4, 0.2)):
        want = float(model.eval(wo, wi) @ LUMINANCE) * wo[2]
        np.testing.assert_allclose(mono_value(bsdf, wi, wo), want, rtol=2e-4)


@pytest.mark.parametrize("variant", MONO, indirect=True)
def test_a_merl_table_is_its_luminance_in_a_mono_variant(variant, tmp_path):
    """merl in a monochrome variant: eval is the luminance of the table's RGB value, and the
    sample weight of a pure cosine sampler is luminance(f) pi (eval / pdf with pdf = cos/pi)."""
    v = np.random.default_rng(3).uniform(0.05, 2.0, (3,) + RES)
    path = write_merl(tmp_path / "random.binary", v)
    bsdf = mi.load_dict({"type": "merl", "filename": str(path)})
    model = read_merl(path)
    wi, wo = np.array([0.3, 0.1, 0.948683]), np.array([-0.25, -0.1, 0.963])
    wo = wo / np.linalg.norm(wo)
    want = float(model.eval(wo, wi) @ LUMINANCE) * wo[2]
    np.testing.assert_allclose(mono_value(bsdf, wi, wo), want, rtol=1e-4)
    bs, w = bsdf.sample(mi.BSDFContext(), one_point(wi), mi.Float(0.3), mi.Point2f(0.2, 0.6))
    got_wo = np.array(bs.wo, dtype=np.float64).ravel()
    f = float(model.eval(got_wo, wi) @ LUMINANCE)
    np.testing.assert_allclose(np.array(w, dtype=np.float64).ravel()[0], f * np.pi, rtol=1e-4)


# -- switching variants --------------------------------------------------------------

def test_register_with_a_variant_says_that_it_changed_the_global_one():
    """register('llvm_ad_mono') leaves llvm_ad_mono set (documented) and says so in Mitsuba's
    log, naming the variant it replaced and how to go back; the RGB plugins stay registered."""
    if "llvm_ad_mono" not in mi.variants():
        pytest.skip("llvm_ad_mono not in this Mitsuba build")
    log = LogCapture()
    logger = mi.logger()
    level = logger.log_level()
    logger.set_log_level(mi.LogLevel.Info)
    logger.add_appender(log)
    try:
        pm.register("llvm_ad_mono")
        assert mi.variant() == "llvm_ad_mono"
        said = [t for _, t in log.lines if "plausible.mitsuba.register" in t]
        assert len(said) == 1 and "'llvm_ad_mono' (was 'llvm_ad_rgb'" in said[0] and "mi.set_variant('llvm_ad_rgb')" in said[0]
    finally:
        logger.remove_appender(log)
        logger.set_log_level(level)
        mi.set_variant(VARIANT)
    assert mi.load_dict({"type": "lambertian"}) is not None


def test_a_plugin_missing_after_switching_variant_gets_the_register_hint():
    """After mi.set_variant to a variant never registered, plausible.mitsuba.load_dict (and
    the inverse-rendering scene built with it) ends its error with the hint to call
    register() again; an unknown non-plausible plugin keeps Mitsuba's own error."""
    fresh = next((v for v in ("llvm_ad_spectral_polarized", "llvm_ad_mono_polarized", "scalar_spectral_polarized")
                  if v in mi.variants() and v not in pm._REGISTERED), None)
    if fresh is None:
        pytest.skip("no variant left without the plugins")
    mi.set_variant(fresh)
    try:
        with pytest.raises(RuntimeError, match=rf"(?s)not found.*'lambertian' is not registered in the variant "
                                               rf"'{fresh}'.*call plausible.mitsuba.register\(\) again"):
            pm.load_dict({"type": "lambertian"})
        if fresh.startswith("llvm_ad"):  # sphere_scene's prb needs an AD variant
            from plausible.mitsuba.inverse import sphere_scene

            with pytest.raises(RuntimeError, match=r"call plausible.mitsuba.register\(\) again"):
                sphere_scene({"type": "ward"})
        with pytest.raises(RuntimeError) as err:
            pm.load_dict({"type": "no_such_bsdf"})
        assert "register()" not in str(err.value)
    finally:
        mi.set_variant(VARIANT)
