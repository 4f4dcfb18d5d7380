"""MaterialX's own GLSL ES (its ``EsslShaderGenerator``) of the written ``gltf_pbr`` and
``open_pbr_surface`` run in the browser harness (headless Chromium, WebGL2 on SwiftShader), against
``gltf-pbr``'s eval at random direction pairs (``docs/materialx.md``, "Verification").

MaterialX's GLSL adds Turquin's multiple-scattering compensation to every GGX lobe
(``mx_ggx_energy_compensation``: ``1 + F (1 - E) / E``, ``E(mu_o, alpha)`` the single-scattering GGX
albedo, which the shader takes from a rational fit, ``mx_ggx_dir_albedo_analytic``).  The reference is
``gltf-pbr`` times that factor with ``E`` integrated here from the model itself (``albedo_curve`` of
the white metal): the tolerance is the fit's error, measured at most 3.9 % (at ``mu_o`` near 0.1)
with a median of 0.7 %, so a 5 % bound on every pair and 1 % on the median.  A Lambertian material
(specular 0) has no GGX lobe: float32 rounding (1e-4).  Compiling MaterialX's shaders on SwiftShader
takes about 2 s each: slow.

An anisotropic metal (KHR_materials_anisotropy, rotation ``r``) checks the direction of the anisotropy
axis: MaterialX's lobe is glTF's NDF of the axis turned by ``r`` with the isotropic Smith ``G`` of the
average ``alpha = sqrt(alpha_t alpha_b)`` (``mx_generalized_schlick_bsdf``), so the reference is
``gltf-pbr`` times ``G_iso / G_aniso`` and the compensation at that alpha; the axis turned by ``-r`` (the
same as ``pi - r``: the GGX lobe is symmetric under ``t -> -t``) must fail.  A texture (``map_Kd``, an
``srgb_texture`` image) is read per pixel from 8-bit texel values: the shader's base colour is their
sRGB decode (IEC 61966-2-1) times the fitted colour.
"""

from __future__ import annotations

import numpy as np
import pytest

from plausible import registry
from plausible.arrays.ops import NP
from plausible.fresnel import dielectric
from plausible.integrals.albedo import albedo_curve
from plausible.models.gltf_pbr import gltf_alphas, rotate_to_anisotropy, smith_visibility
from plausible.spectra import srgb_to_linear

pytest.importorskip("MaterialX")
pytest.importorskip("playwright.sync_api")
from conftest import random_upper  # noqa: E402
from glsl_webgl import Browser, chromium  # noqa: E402
from materialx_glsl import harness_shader  # noqa: E402

from plausible.export.materialx import essl_pixel_shader, materialx_document  # noqa: E402

pytestmark = pytest.mark.slow

MATERIALS = {"gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3},
             "rough_copper": {"base_color": [0.9, 0.5, 0.3], "metallic": 1.0, "roughness": 0.8},
             "black": {"base_color": [0.0, 0.0, 0.0], "metallic": 0.0, "roughness": 0.5},
             "lambert": {"base_color": [0.2, 0.5, 0.8], "metallic": 0.0, "roughness": 0.5, "specular": 0.0},
             "aniso": {"base_color": [0.95, 0.9, 0.85], "metallic": 1.0, "roughness": 0.3,
                       "anisotropy_strength": 0.8, "anisotropy_rotation": 0.6}}
MATERIALS["textured"] = dict(MATERIALS["lambert"])      # times the texture of TEXELS
SHADERS = [(m, k) for m in MATERIALS for k in ("glTF", "OpenPBR")]
#: 8-bit texel values (every level 0..255 among them), one per pixel and channel.
TEXELS = np.random.default_rng(5).permutation(np.arange(1024 * 3) % 256).reshape(1024, 3)


@pytest.fixture(scope="module")
def rendered():
    if chromium() is None:
        pytest.skip("chromium is not installed (make chromium installs Debian's)")
    rng = np.random.default_rng(3)
    wi, wo = random_upper(rng, 1024), random_upper(rng, 1024)
    doc = materialx_document(MATERIALS, textures={"textured": "texels.png"})
    b = Browser()
    try:
        if not b.ready:
            pytest.skip("no WebGL2 with EXT_color_buffer_float in this chromium")
        b.set_inputs([wi, wo, TEXELS / 255.0])
        out = b.run([(harness_shader(*essl_pixel_shader(doc, f"{m}_{k}"),
                                     image="textured_map_Kd_file" if m == "textured" else None), {})
                     for m, k in SHADERS])
    finally:
        b.close()
    return wi.astype(np.float64), wo.astype(np.float64), dict(zip(SHADERS, out))


def _f(name, wi, wo):
    m = registry.make("gltf-pbr", **MATERIALS[name])
    return np.asarray(m._eval_block(wi, wo, (len(wi),))).reshape(len(wi), -1)


def _measured(rendered, key):
    wi, wo, out = rendered
    assert not isinstance(out[key], str), out[key][:400]
    return out[key][:, :3] / wi[:, 2:3]          # the pixel is f cos(theta_i)


def _compensation(roughness, wi, wo, fresnel):
    """Turquin's ``1 + F (1 - E) / E`` with ``E(mu_o)`` integrated from the white ``gltf-pbr`` metal."""
    th = np.linspace(0.0, 89.5, 60)
    white = registry.make("gltf-pbr", base_color=1.0, metallic=1.0, roughness=roughness)
    e = np.interp(np.degrees(np.arccos(wo[:, 2])), th, np.asarray(albedo_curve(white, thetas_deg=th).value,
                                                                   float).reshape(len(th), -1)[:, 0])[:, None]
    return 1.0 + fresnel * (1.0 - e) / e


def _cos_vh(wi, wo):
    h = wi + wo
    return np.sum(wo * h / np.linalg.norm(h, axis=1, keepdims=True), axis=1)[:, None]


@pytest.mark.parametrize("kind", ["glTF", "OpenPBR"])
@pytest.mark.parametrize("name", ["gold", "rough_copper"])
def test_a_metal_is_the_gltf_lobe_times_turquins_compensation(rendered, name, kind):
    wi, wo, _ = rendered
    f0 = np.asarray(MATERIALS[name]["base_color"])
    fresnel = f0 + (1.0 - f0) * (1.0 - _cos_vh(wi, wo)) ** 5
    want = _f(name, wi, wo) * _compensation(MATERIALS[name]["roughness"], wi, wo, fresnel)
    err = np.abs(_measured(rendered, (name, kind)) / want - 1.0)
    assert err.max() <= 0.05 and np.median(err) <= 0.01, (err.max(), np.median(err))


def test_a_black_gltf_dielectric_is_its_schlick_lobe_times_the_compensation(rendered):
    wi, wo, _ = rendered
    fresnel = 0.04 + 0.96 * (1.0 - _cos_vh(wi, wo)) ** 5
    want = _f("black", wi, wo) * _compensation(0.5, wi, wo, fresnel)
    err = np.abs(_measured(rendered, ("black", "glTF")) / want - 1.0)
    assert err.max() <= 0.05 and np.median(err) <= 0.01, (err.max(), np.median(err))


def test_a_black_openpbr_dielectric_reflects_by_the_exact_fresnel_not_schlicks(rendered):
    wi, wo, _ = rendered
    c = _cos_vh(wi, wo)
    exact = np.asarray(dielectric(NP, c, 1.5))
    schlick = 0.04 + 0.96 * (1.0 - c) ** 5
    want = _f("black", wi, wo) * exact / schlick * _compensation(0.5, wi, wo, exact)
    err = np.abs(_measured(rendered, ("black", "OpenPBR")) / want - 1.0)
    assert err.max() <= 0.05 and np.median(err) <= 0.01, (err.max(), np.median(err))


def test_gltf_pbr_without_specular_is_lambert_to_float32(rendered):
    wi, wo, _ = rendered
    want = np.asarray(MATERIALS["lambert"]["base_color"]) / np.pi
    assert np.allclose(_measured(rendered, ("lambert", "glTF")), want, rtol=1e-4, atol=0.0)


def test_openpbr_without_specular_darkens_the_base_at_grazing_view(rendered):
    # specular_weight 0: OpenPBR reflects nothing (F0 0), yet MaterialX's dielectric_bsdf takes the base's
    # throughput from Schlick's albedo with F90 = 1: Lambert seen from above, up to 19 % darker at grazing
    wi, wo, _ = rendered
    ratio = (_measured(rendered, ("lambert", "OpenPBR")) / (np.asarray(MATERIALS["lambert"]["base_color"]) / np.pi)).min(1)
    assert ratio.max() <= 1.0 + 1e-4 and ratio[wo[:, 2] > 0.8].min() > 0.99
    assert 0.75 < ratio[wo[:, 2] < 0.1].min() < 0.9


def _anisotropic_reference(wi, wo, rotation):
    """``gltf-pbr`` of ``aniso`` with its axis turned by ``rotation``, its Smith ``G`` replaced by the
    isotropic one of ``sqrt(alpha_t alpha_b)`` (MaterialX's), times the compensation at that alpha."""
    p = MATERIALS["aniso"]
    at, ab = gltf_alphas(p["roughness"], p["anisotropy_strength"])
    avg = np.sqrt(at * ab)
    c, s = np.cos(rotation), np.sin(rotation)
    g = (smith_visibility(NP, wi.T, wo.T, avg, avg)
         / smith_visibility(NP, rotate_to_anisotropy(NP, wi.T, c, s), rotate_to_anisotropy(NP, wo.T, c, s), at, ab))
    m = registry.make("gltf-pbr", **{**p, "anisotropy_rotation": rotation})
    f = np.asarray(m._eval_block(wi, wo, (len(wi),))).reshape(len(wi), -1)
    f0 = np.asarray(p["base_color"])
    fresnel = f0 + (1.0 - f0) * (1.0 - _cos_vh(wi, wo)) ** 5
    return f * g[:, None] * _compensation(np.sqrt(avg), wi, wo, fresnel)


def _within(err) -> bool:
    return bool(err.max() <= 0.05 and np.median(err) <= 0.01)


@pytest.mark.parametrize("kind", ["glTF", "OpenPBR"])
def test_the_anisotropy_axis_is_the_tangent_turned_counter_clockwise_by_the_rotation(rendered, kind):
    wi, wo, _ = rendered
    measured = _measured(rendered, ("aniso", kind))
    r = MATERIALS["aniso"]["anisotropy_rotation"]
    err = np.abs(measured / _anisotropic_reference(wi, wo, r) - 1.0)
    assert _within(err), (err.max(), np.median(err))
    wrong = np.abs(measured / _anisotropic_reference(wi, wo, np.pi - r) - 1.0)     # the axis at -r
    assert not _within(wrong) and np.median(wrong) > 0.5, (wrong.max(), np.median(wrong))


def test_an_srgb_texture_is_decoded_to_linear_by_the_generated_shader(rendered):
    # gltf_pbr without specular is Lambert: the pixel is (decoded texel x fitted colour) / pi
    wi, _, _ = rendered
    decoded = _measured(rendered, ("textured", "glTF")) * np.pi / np.asarray(MATERIALS["textured"]["base_color"])
    assert np.allclose(decoded, srgb_to_linear(TEXELS / 255.0), rtol=1e-4, atol=1e-6)
    for wrong in (TEXELS / 255.0, (TEXELS / 255.0) ** 2.2):       # no decode; a gamma 2.2 decode
        assert not np.allclose(decoded, wrong, rtol=1e-4, atol=1e-6)


def test_the_openpbr_base_takes_the_same_decoded_texture(rendered):
    # the same base colour without and with the texture: their ratio is the decoded texel
    ratio = _measured(rendered, ("textured", "OpenPBR")) / _measured(rendered, ("lambert", "OpenPBR"))
    assert np.allclose(ratio, srgb_to_linear(TEXELS / 255.0), rtol=1e-4, atol=1e-6)
