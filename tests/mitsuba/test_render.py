"""Renders with the plugins: white furnace (energy) and XML scenes."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import mi, to_dict

import plausible

pytestmark = pytest.mark.drjit

FURNACE = [
    ("lambertian", dict(rd=0.7)),
    ("modified_phong", dict(kd=0.4, ks=0.5, n=30.0)),
    ("reciprocal_blinn", dict(ks=0.9, n=40.0)),
    ("ashikhmin_shirley", dict(nu=20.0, nv=80.0, rs=0.3, rd=0.5)),
]
PLUGIN_TO_MODEL = {"lambertian": "lambertian", "modified_phong": "modified-phong",
                   "reciprocal_blinn": "reciprocal-blinn", "ashikhmin_shirley": "ashikhmin-shirley"}


def furnace_scene(bsdf: dict, width: float, res: int):
    """Unit sphere in a constant unit-radiance environment, orthographic camera
    looking down -z (so the image centre sees the sphere at normal incidence)."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": {
            "type": "orthographic",
            "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0])
            @ mi.ScalarTransform4f().scale([width, width, 1.0]),
            "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"},
                     "pixel_format": "rgb"},
            "sampler": {"type": "independent", "sample_count": 64},
        },
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })


def mc_albedo_normal(model, n=1_000_000, seed=0):
    """Directional albedo at normal incidence by Monte Carlo with the model's own
    sampler (NumPy, float64): mean and standard error of the weights."""
    rng = np.random.default_rng(seed)
    w = model.sample(np.array([0.0, 0.0, 1.0]), rng.random((n, 3))).weight
    w = w if w.ndim == 1 else w.mean(axis=-1)
    return float(w.mean()), float(w.std() / np.sqrt(n))


@pytest.mark.parametrize("plugin,params", FURNACE, ids=[f[0] for f in FURNACE])
def test_white_furnace(plugin, params):
    """(1) A zoomed view of the sphere's pole (8x8 pixels, all within 0.6 deg of
    normal incidence, 64 spp): the mean pixel equals the NumPy Monte Carlo albedo
    at normal incidence within 4 combined standard errors (pixel scatter + MC).
    (2) The whole sphere (32x32, 64 spp): no pixel exceeds 1 by more than 5 sigma
    of the per-pixel noise (estimated from two independent renders)."""
    model = plausible.make(PLUGIN_TO_MODEL[plugin], **params)
    want, want_se = mc_albedo_normal(model)
    bsdf = to_dict(plugin, params)

    pole = np.array(mi.render(furnace_scene(bsdf, 0.01, 8), seed=1), dtype=np.float64)
    vals = pole.mean(axis=-1).ravel()
    got, got_se = vals.mean(), vals.std(ddof=1) / np.sqrt(vals.size)
    tol = 4.0 * np.hypot(got_se, want_se)
    assert abs(got - want) < tol, (got, want, tol)

    scene = furnace_scene(bsdf, 1.1, 32)
    a = np.array(mi.render(scene, seed=2), dtype=np.float64)
    b = np.array(mi.render(scene, seed=3), dtype=np.float64)
    sigma = np.std(a - b) / np.sqrt(2.0)
    assert np.max((a + b) / 2) <= 1.0 + 5.0 * sigma / np.sqrt(2.0) + 1e-6
    # the background (constant emitter seen directly) is exactly 1: the test can see 1
    assert np.isclose(a[0, 0].mean(), 1.0, atol=1e-6)


def test_furnace_checker_detects_a_wrong_albedo():
    """The comparison above fails for a plugin whose albedo differs (rd 0.7 vs 0.65)."""
    model = plausible.make("lambertian", rd=0.65)
    want, want_se = mc_albedo_normal(model)
    pole = np.array(mi.render(furnace_scene({"type": "lambertian", "rd": 0.7}, 0.01, 8), seed=1))
    vals = pole.mean(axis=-1).ravel()
    got, got_se = vals.mean(), vals.std(ddof=1) / np.sqrt(vals.size)
    assert abs(got - want) >= 4.0 * np.hypot(got_se, want_se)


XML = """<scene version="3.0.0">
    <integrator type="path"><integer name="max_depth" value="2"/></integrator>
    <sensor type="orthographic">
        <transform name="to_world">
            <scale x="1.1" y="1.1"/>
            <lookat origin="0, 0, 5" target="0, 0, 0" up="0, 1, 0"/>
        </transform>
        <film type="hdrfilm"><integer name="width" value="8"/><integer name="height" value="8"/>
            <rfilter type="box"/><string name="pixel_format" value="rgb"/></film>
        <sampler type="independent"><integer name="sample_count" value="16"/></sampler>
    </sensor>
    <shape type="sphere">
        <bsdf type="ashikhmin_shirley">
            <float name="nu" value="20"/>
            <float name="nv" value="200"/>
            <rgb name="specular_reflectance" value="0.1, 0.2, 0.3"/>
            <rgb name="diffuse_reflectance" value="0.5, 0.4, 0.3"/>
        </bsdf>
    </shape>
    <emitter type="constant"><rgb name="radiance" value="1.0"/></emitter>
</scene>"""


def test_xml_scene_with_aliases_renders_like_native_names():
    """An XML scene using <bsdf type="ashikhmin_shirley"> with Mitsuba-style names
    (specular_reflectance, diffuse_reflectance) renders exactly the same image as
    the same scene built with the native names rs / rd (same seed), and the image
    is not trivial (sphere darker than the background, finite)."""
    img_xml = np.array(mi.render(mi.load_string(XML), seed=0))
    native = XML.replace('name="specular_reflectance"', 'name="rs"').replace(
        'name="diffuse_reflectance"', 'name="rd"')
    img_native = np.array(mi.render(mi.load_string(native), seed=0))
    np.testing.assert_array_equal(img_xml, img_native)
    assert np.all(np.isfinite(img_xml))
    assert img_xml[4, 4].mean() < 0.95 and np.isclose(img_xml[0, 0].mean(), 1.0)
