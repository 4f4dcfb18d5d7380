"""A ``.gltf`` of :func:`plausible.export.gltf.write_gltf` rendered by three.js (``GLTFLoader``,
its ``MeshStandardMaterial`` / ``MeshPhysicalMaterial`` built from the file) in headless
Chromium (SwiftShader), three.js from the npm package in ``.cache/npm`` (``make three``).

The scene: the file's spheres seen by an orthographic camera along ``-z``, lit by one
directional light from the camera (``wi = wo``, irradiance ``pi cos``), no environment,
linear output, no tone mapping, so a pixel is ``f(wi, wo) cos(theta) pi`` in 8 bits.

* three.js reads the factors as written (material type, colour, metalness, roughness, the
  extensions' specular and anisotropy values).
* Where three.js and the glTF specification compute the same thing, the pixels equal
  ``gltf-pbr``'s ``f cos pi`` (``GltfPBR.eval``): a material with ``specular = 0`` (pure
  Lambert) and a rough dielectric (``roughness = 1``, where three.js's added geometric
  roughness is clamped away; its multiple-scattering compensation of the ``f0 = 0.04`` lobe
  changes a pixel by under 0.1 level).  Within 1.5 levels of 255 for every pixel whose normal
  is within 60 degrees of the view (measured: 1.02 at most, 0.27 on average; 0.5 is the 8-bit
  rounding, the rest the tessellated sphere's interpolated normals; beyond 60 degrees the
  radiance changes by several levels across a pixel, 1.97 at most up to 72 degrees).
* A metal differs from a dielectric as expected: its lobe falls off faster than Lambert's
  ``cos``, and it has the colour of its base (glTF's metal Fresnel at ``V.H = 1`` is
  ``base_color``; a grey metal stays grey); three.js brightens metals by a multiple-scattering compensation that
  glTF's single-scattering formula lacks, so its pixels are at least the model's.
"""

from __future__ import annotations

import base64
import json
import math
import os
from pathlib import Path

import numpy as np
import pytest

import plausible
from plausible.export.gltf import SPACING, write_gltf

pytest.importorskip("playwright.sync_api")
from glsl_webgl import CHROMIUM_ARGS, chromium  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
THREE = ROOT / ".cache" / "npm" / "node_modules" / "three"
ORIGIN = "http://plausible.test/"
PX = 40          # pixels per scene unit (a sphere of radius 1 is 40 pixels)
COLS = 2         # write_gltf's grid for 4 materials
SIZE = int(PX * SPACING * COLS)

MATERIALS = {
    "lambert": {"base_color": [0.8, 0.5, 0.2], "roughness": 0.5, "specular": 0.0},
    "rough dielectric": {"base_color": [0.3, 0.6, 0.9], "roughness": 1.0},
    "gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.8},   # broad: little saturation
    "brushed": {"base_color": 0.9, "metallic": 1.0, "roughness": 0.4, "specular": 0.5,
                "specular_color": [1.0, 2.0, 1.0], "anisotropy_strength": 0.6, "anisotropy_rotation": 1.0},
}

PAGE = """<!doctype html><html><body style="margin:0">
<script type="importmap">{"imports": {"three": "%(o)sthree/build/three.module.js",
                                     "three/addons/": "%(o)sthree/examples/jsm/"}}</script>
<script type="module">
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
const size = %(size)d, half = %(half)f;
const renderer = new THREE.WebGLRenderer({ antialias: false, preserveDrawingBuffer: true });
renderer.setPixelRatio(1);
renderer.setSize(size, size);
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
renderer.toneMapping = THREE.NoToneMapping;
document.body.appendChild(renderer.domElement);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0, 0, 0);
// the grid spans x in [-1.25, 3.75], y in [-3.75, 1.25]
const cx = %(cx)f, cy = %(cy)f;
const camera = new THREE.OrthographicCamera(-half, half, half, -half, 0.1, 100);   // about its position
camera.position.set(cx, cy, 10);
const light = new THREE.DirectionalLight(0xffffff, Math.PI);
light.position.set(cx, cy, 10);
light.target.position.set(cx, cy, 0);
scene.add(light, light.target);
new GLTFLoader().load('%(o)smaterials.gltf', (gltf) => {
  scene.add(gltf.scene);
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const px = new Uint8Array(size * size * 4);
  gl.readPixels(0, 0, size, size, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let s = '';
  for (let i = 0; i < px.length; i += 8192) s += String.fromCharCode.apply(null, px.subarray(i, i + 8192));
  const mats = {};
  gltf.scene.traverse((o) => { if (o.isMesh) { const m = o.material; mats[m.name] = {
    type: m.type, color: m.color.toArray(), metalness: m.metalness, roughness: m.roughness,
    specularIntensity: m.specularIntensity, specularColor: m.specularColor ? m.specularColor.toArray() : null,
    anisotropy: m.anisotropy, anisotropyRotation: m.anisotropyRotation, map: m.map ? m.map.name || 'texture' : null,
    centre: o.getWorldPosition(new THREE.Vector3()).toArray() }; } });
  window.result = { data: btoa(s), mats };
}, undefined, (e) => { window.result = { error: String(e) }; });
</script></body></html>"""


def missing(why):
    if os.environ.get("CI"):
        pytest.fail(why)
    pytest.skip(why)


def render(gltf: str, files: dict | None = None):
    """``gltf`` (the file's text) rendered by three.js in headless Chromium, the files it
    references (``{uri: bytes}``) served beside it: ``(pixels (SIZE, SIZE, 3) top-down, the
    materials three.js built, the view's centre)``."""
    from playwright.sync_api import sync_playwright

    if chromium() is None:
        missing("chromium is not installed (make chromium installs Debian's)")
    if not (THREE / "examples" / "jsm" / "loaders" / "GLTFLoader.js").is_file():
        missing(f"three.js is not installed in {THREE.parent} (make three installs it)")
    files = files or {}
    cx, cy = 0.5 * SPACING * (COLS - 1), -0.5 * SPACING * (COLS - 1)
    page_text = PAGE % dict(o=ORIGIN, size=SIZE, half=SIZE / (2 * PX), cx=cx, cy=cy)

    def route(r):
        url = r.request.url
        if url == ORIGIN + "index.html":
            return r.fulfill(body=page_text, content_type="text/html")
        if url == ORIGIN + "materials.gltf":
            return r.fulfill(body=gltf, content_type="model/gltf+json")
        if url[len(ORIGIN):] in files:
            return r.fulfill(body=files[url[len(ORIGIN):]], content_type="image/png")
        if url.startswith(ORIGIN + "three/"):
            path = THREE / url[len(ORIGIN + "three/"):]
            if path.is_file():
                return r.fulfill(body=path.read_bytes(), content_type="text/javascript")
        return r.abort()

    errors = []
    with sync_playwright() as pw:
        browser = pw.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
        page = browser.new_page(viewport={"width": SIZE, "height": SIZE})
        page.route("**/*", route)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.goto(ORIGIN + "index.html")
        page.wait_for_function("window.result !== undefined", timeout=120000)
        res = page.evaluate("window.result")
        browser.close()
    assert "error" not in res and errors == [], (res.get("error"), errors)
    px = np.frombuffer(base64.b64decode(res["data"]), dtype=np.uint8).reshape(SIZE, SIZE, 4)[::-1, :, :3]
    return px.astype(float), res["mats"], (cx, cy)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    return render(write_gltf(MATERIALS, tmp_path_factory.mktemp("gltf") / "materials.gltf").read_text())


def sphere_pixels(px, centre, view_centre):
    """The pixels of the sphere at ``centre`` (rows top-down): their values, the normals of
    the unit sphere at their centres, and a mask of the pixels inside its outline."""
    cx, cy = view_centre
    j = np.arange(SIZE) + 0.5
    x = (j - SIZE / 2) / PX + cx - centre[0]
    y = -(j - SIZE / 2) / PX + cy - centre[1]
    X, Y = np.meshgrid(x, y)
    r2 = X * X + Y * Y
    n = np.stack([X, Y, np.sqrt(np.maximum(1 - r2, 0))], -1)
    return px, n, r2


def expected(model, n):
    """``f(v, v) cos(theta) pi`` in 8 bits, ``v`` the view (= light) direction, in the frame of ``n``."""
    c = n[..., 2]
    s = np.sqrt(np.maximum(1 - c * c, 0))
    wi = np.stack([s, 0 * s, c], -1)        # isotropic: only the angle to the normal matters
    return 255 * model.eval(wi, wi) * c[..., None] * math.pi


def test_three_reads_the_factors_as_written(rendered):
    _, mats, _ = rendered
    assert mats["lambert"]["type"] == "MeshPhysicalMaterial" and mats["gold"]["type"] == "MeshStandardMaterial"
    for name, p in MATERIALS.items():
        m = mats[name]
        assert m["color"] == pytest.approx(np.broadcast_to(p["base_color"], 3).tolist(), abs=1e-7)
        assert (m["metalness"], m["roughness"]) == pytest.approx((p.get("metallic", 0.0), p["roughness"]), abs=1e-7)
    assert mats["lambert"]["specularIntensity"] == 0.0
    assert mats["brushed"]["specularColor"] == pytest.approx([1.0, 2.0, 1.0])
    assert (mats["brushed"]["anisotropy"], mats["brushed"]["anisotropyRotation"]) == pytest.approx((0.6, 1.0))


@pytest.mark.parametrize("name", ["lambert", "rough dielectric"])
def test_pixels_are_the_models_where_three_computes_the_specification(rendered, name):
    px, mats, view = rendered
    img, n, r2 = sphere_pixels(px, mats[name]["centre"], view)
    want = expected(plausible.make("gltf-pbr", **MATERIALS[name]), n)
    inside = r2 < math.sin(math.radians(60)) ** 2
    assert inside.sum() > 0.99 * 0.75 * math.pi * PX * PX
    err = np.abs(img[inside] - want[inside])
    assert err.max() <= 1.5, f"{name}: max {err.max()} levels, mean {err.mean():.2f}"
    # the comparison can fail: the other dielectric's model is far from these pixels
    other = "rough dielectric" if name == "lambert" else "lambert"
    assert np.abs(img[inside] - expected(plausible.make("gltf-pbr", **MATERIALS[other]), n)[inside]).max() > 20


def test_every_sphere_covers_its_outline_and_nothing_else(rendered):
    px, mats, view = rendered
    lit = px.max(-1) > 0
    covered = np.zeros_like(lit)
    for name in MATERIALS:
        _, n, r2 = sphere_pixels(px, mats[name]["centre"], view)
        # the lit part: normals within 80 degrees of the light (the rim beyond is dark for a metal)
        assert lit[r2 < math.sin(math.radians(80)) ** 2].mean() > 0.999, name
        covered |= r2 < 1.05
    assert not lit[~covered].any()     # the background is black


def test_a_metal_differs_from_a_dielectric_as_expected(rendered):
    px, mats, view = rendered

    def disc(name):
        _, n, r2 = sphere_pixels(px, mats[name]["centre"], view)
        ring = np.abs(np.sqrt(r2) - math.sin(math.radians(60))) < 1.0 / PX     # normals 60 degrees off
        return n, r2 < math.sin(math.radians(72)) ** 2, r2 < (1.5 / PX) ** 2, ring

    # Lambert falls off as cos: 0.5 at 60 degrees
    _, _, centre, ring = disc("lambert")
    assert px[ring].mean() / px[centre].mean() == pytest.approx(0.5, abs=0.02)
    # three.js adds a multiple-scattering compensation to the metal lobe, which glTF's single-scattering
    # BRDF lacks: its pixels are never below the model's (measured: 1.15 to 1.92 times, 4.5 levels or more)
    n, inside, _, ring = disc("gold")
    want = expected(plausible.make("gltf-pbr", **MATERIALS["gold"]), n)[inside]
    got = px[inside]
    unsaturated = got < 254
    assert np.all(got[unsaturated] >= want[unsaturated] - 1.0)
    # its lobe peaks at the mirror direction: it falls off faster than Lambert's cos (the model: 0.31)
    _, _, centre, _ = disc("gold")
    assert px[ring][:, 1].mean() / px[centre][:, 1].mean() < 0.45
    # the metal's colour is its base's (F = base_color at V.H = 1): red > green > blue, blue/red < 1/2
    r, g, b = px[ring].mean(0)
    assert r > g > b and b / r < 0.5
    # a grey metal stays grey (no diffuse term to tint it: R = G = B to a level)
    _, inside, _, _ = disc("brushed")
    lit = px[inside][px[inside].max(-1) > 10]
    assert np.abs(lit - lit.mean(-1, keepdims=True)).max() <= 1.0


def test_a_base_colour_texture_multiplies_the_factor(tmp_path):
    # a uniform texture of sRGB level 188 (glTF's base colour textures are sRGB: linear 0.5029) on a
    # Lambertian sphere: its pixels are the model's of base_color times 0.5029, and the untextured
    # sphere's are the model's of base_color (a texture not loaded or not applied fails the first)
    import matplotlib.pyplot as plt

    lambert = MATERIALS["lambert"]
    plt.imsave(tmp_path / "grey.png", np.full((4, 4, 3), 188 / 255.0))
    gltf = write_gltf({"plain": lambert, "textured": lambert}, tmp_path / "t.gltf",
                      textures={"textured": {"baseColorTexture": "grey.png"}}).read_text()
    px, mats, view = render(gltf, {"grey.png": (tmp_path / "grey.png").read_bytes()})
    assert mats["textured"]["map"] is not None and mats["plain"]["map"] is None
    level = ((188 / 255 + 0.055) / 1.055) ** 2.4
    for name, scale in (("plain", 1.0), ("textured", level)):
        img, n, r2 = sphere_pixels(px, mats[name]["centre"], view)
        inside = r2 < math.sin(math.radians(60)) ** 2
        base = np.asarray(lambert["base_color"]) * scale
        want = expected(plausible.make("gltf-pbr", **{**lambert, "base_color": base}), n)
        err = np.abs(img[inside] - want[inside])
        assert err.max() <= 1.5, f"{name}: max {err.max()} levels, mean {err.mean():.2f}"
        other = expected(plausible.make("gltf-pbr", **{**lambert, "base_color": np.asarray(lambert["base_color"])
                                                       * (level if scale == 1.0 else 1.0)}), n)
        assert np.abs(img[inside] - other[inside]).max() > 20
