"""``gltf-pbr`` against Mitsuba 3's own ``principled`` BSDF, where the two coincide.

Which parameters.  ``metallic = 1``: principled's diffuse, sheen and transmission are
weighted by ``1 - metallic`` (zero) and its Fresnel is Schlick's on ``base_color`` at
``wi.h`` (its ``eta`` from the default ``specular = 0.5`` is 1.5 > 1, so the cosine is
``wi.h``), which is glTF's ``metal_brdf``; its GGX has ``alpha = roughness^2`` like glTF's.
Principled's anisotropy ``(alpha_u, alpha_v) = (r^2 / a, r^2 a)``, ``a = sqrt(1 - 0.9 anisotropic)``,
is glTF's ``(alpha_t, alpha_b)`` at rotation 0 for ``r = (alpha_t alpha_b)^(1/4)`` and
``anisotropic = (1 - alpha_b / alpha_t) / 0.9``.  The masking differs: Mitsuba's microfacet
``G`` is the separable ``G1(wi) G1(wo)``, glTF's the height-correlated
``1 / (1 + Lambda(wi) + Lambda(wo))`` (Heitz 2014, eqs. 98-99); they are equal when one
direction is the normal (``Lambda(n) = 0``), and otherwise differ by the factor written here
from ``Lambda`` (up to 37 % isotropic, 51 % anisotropic, at the directions drawn).

Tolerance: relative 1e-5.  Mitsuba evaluates in float32 (the ``llvm_ad_rgb`` variant); the
largest difference measured is 1.1e-6 (about 10 float32 ulp), and a change of 1 % in
roughness changes the values by more than 1e-3, so 1e-5 tells them apart.
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import random_upper

from mi_helpers import mi  # noqa: F401  (sets the variant; skips without Mitsuba)

import plausible
from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

RTOL = 1e-5


def principled(base, roughness, anisotropic=0.0):
    return MitsubaBSDF(load_bsdf_dict({"type": "principled", "base_color": {"type": "rgb", "value": base},
                                       "roughness": roughness, "metallic": 1.0, "anisotropic": anisotropic}))


def separable_over_correlated(wi, wo, ax, ay):
    """``G1(wi) G1(wo) (1 + Lambda(wi) + Lambda(wo))`` with GGX's
    ``Lambda(w) = (sqrt(1 + (ax^2 wx^2 + ay^2 wy^2) / wz^2) - 1) / 2`` (Heitz 2014, eq. 86)."""
    lam = lambda w: 0.5 * (np.sqrt(1 + ((ax * w[:, 0]) ** 2 + (ay * w[:, 1]) ** 2) / w[:, 2] ** 2) - 1)  # noqa: E731
    return (1 + lam(wi) + lam(wo)) / ((1 + lam(wi)) * (1 + lam(wo)))


BASE = [0.95, 0.64, 0.54]


@pytest.mark.parametrize("roughness", [0.3, 0.6, 1.0])
def test_a_metal_is_principled_where_one_direction_is_the_normal(roughness):
    rng = np.random.default_rng(1)
    g = plausible.make("gltf-pbr", base_color=BASE, metallic=1.0, roughness=roughness)
    m = principled(BASE, roughness)
    wo = random_upper(rng, 2000, 0.05)
    n = np.tile([0.0, 0.0, 1.0], (len(wo), 1))
    np.testing.assert_allclose(m.eval(n, wo), g.eval(n, wo), rtol=RTOL)
    np.testing.assert_allclose(m.eval(wo, n), g.eval(wo, n), rtol=RTOL)


@pytest.mark.parametrize("strength", [0.0, 0.5])
def test_a_metal_is_principled_up_to_the_masking_term(strength):
    rng = np.random.default_rng(2)
    r = 0.5
    g = plausible.make("gltf-pbr", base_color=BASE, metallic=1.0, roughness=r, anisotropy_strength=strength)
    at, ab = r * r + (1 - r * r) * strength ** 2, r * r
    m = principled(BASE, (at * ab) ** 0.25, (1 - ab / at) / 0.9)
    wi, wo = random_upper(rng, 2000, 0.05), random_upper(rng, 2000, 0.05)
    ratio = separable_over_correlated(wi, wo, at, ab)[:, None]
    np.testing.assert_allclose(m.eval(wi, wo), g.eval(wi, wo) * ratio, rtol=RTOL)
    assert np.max(np.abs(ratio - 1)) > 0.1        # the masking terms do differ


def test_the_comparison_tells_a_one_percent_roughness_apart():
    rng = np.random.default_rng(3)
    wo = random_upper(rng, 500, 0.05)
    n = np.tile([0.0, 0.0, 1.0], (len(wo), 1))
    got = principled(BASE, 0.505).eval(n, wo)
    want = plausible.make("gltf-pbr", base_color=BASE, metallic=1.0, roughness=0.5).eval(n, wo)
    assert np.max(np.abs(got / want - 1)) > 100 * RTOL


def test_the_plugin_reduces_an_rgb_specular_color_as_numpy_does():
    # the Mitsuba plugin gets specular_color as a Color3f and takes max_value over its channels
    # (the registry-wide plugin tests use the grey default); float32, so 1e-5 as above
    kw = dict(base_color=[0.9, 0.5, 0.2], specular=0.7, specular_color=[0.5, 3.0, 1.0], roughness=0.4,
              metallic=0.2, anisotropy_strength=0.5, anisotropy_rotation=0.8)
    d = {"type": "gltf_pbr", **{k: ({"type": "rgb", "value": v} if isinstance(v, list) else v)
                                for k, v in kw.items()}}
    rng = np.random.default_rng(4)
    wi, wo = random_upper(rng, 1000, 0.05), random_upper(rng, 1000, 0.05)
    np.testing.assert_allclose(MitsubaBSDF(load_bsdf_dict(d)).eval(wi, wo),
                               plausible.make("gltf-pbr", **kw).eval(wi, wo), rtol=RTOL)
