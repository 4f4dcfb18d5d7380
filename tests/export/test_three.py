"""The three.js example page of docs/export.md (``examples/three/index.html``),
rendered as shipped in headless Chromium with three.js from the npm package
(``make three`` installs it into ``.cache/npm``; the page's CDN requests are
answered from there, nothing else is reachable), its pixels compared with the
NumPy backend on the analytic sphere.

Reference: for each pixel the camera ray (the page's own camera matrices),
its hit on the unit sphere, the frame (normal; tangent along the sphere's
texture coordinate ``u``, which is what ``computeTangents`` gives; bitangent
``n x t``), and ``f(wi, wo) cos(theta_i) L`` of NumPy times the page's exposure,
in 8-bit sRGB (:func:`plausible.figures.scenes.tonemap`, the IEC 61966-2-1
encoding written independently of the page's GLSL).  The page
draws a tessellated sphere (256 x 128 segments), whose interpolated normals
and positions differ from the analytic ones by about 1e-4 rad (0.02 pixel);
criterion (:func:`agree`): every pixel away from the outline and the poles
within 1 of 255 levels of NumPy's range over a quarter pixel about its centre,
and 99 % within 1 level of the value at the centre.
"""

from __future__ import annotations

import base64
import json
import os
import re
from pathlib import Path

import numpy as np
import pytest

import plausible
from plausible.export import to_js
from plausible.figures.scenes import tonemap

pytest.importorskip("playwright.sync_api")
from glsl_cases import RTOL, direction_pairs, relative_errors  # noqa: E402
from glsl_webgl import CHROMIUM_ARGS, WIDTH, chromium  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
PAGE = ROOT / "examples" / "three" / "index.html"
THREE = ROOT / ".cache" / "npm" / "node_modules" / "three"
ORIGIN = "http://plausible.test/"
SIZE = 192


def cdn_prefix() -> str:
    """The three.js location of the page's import map (``https://unpkg.com/three@V/``)."""
    imports = json.loads(re.search(r'<script type="importmap">(.*?)</script>', PAGE.read_text(), re.S).group(1))
    url = imports["imports"]["three"]
    return url[: url.index("build/")]


def missing(why):
    if os.environ.get("CI"):
        pytest.fail(why)
    pytest.skip(why)


@pytest.fixture(scope="module")
def page():
    from playwright.sync_api import sync_playwright

    if chromium() is None:
        missing("chromium is not installed (make chromium installs Debian's)")
    version = re.search(r"three@([0-9.]+)/", cdn_prefix()).group(1)
    pkg = THREE / "package.json"
    if not pkg.exists() or json.loads(pkg.read_text())["version"] != version:
        missing(f"three.js {version} is not installed in {THREE.parent} (make three installs it)")
    state = {"module": ""}

    def route(r):
        url = r.request.url
        if url == ORIGIN + "index.html":
            return r.fulfill(body=PAGE.read_text(), content_type="text/html")
        if url == ORIGIN + "webgl2.html":
            return r.fulfill(body=webgl2_page(), content_type="text/html")
        if url.split("?")[0] == ORIGIN + "brdf.js":
            return r.fulfill(body=state["module"], content_type="text/javascript")
        if url.startswith(cdn_prefix()):
            path = THREE / url[len(cdn_prefix()):]
            if path.is_file():
                return r.fulfill(body=path.read_bytes(), content_type="text/javascript")
        return r.abort()

    pw = sync_playwright().start()
    browser = pw.chromium.launch(executable_path=chromium(), args=CHROMIUM_ARGS)
    pg = browser.new_page(viewport={"width": SIZE, "height": SIZE})
    pg.route("**/*", route)
    errors = []
    pg.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
    pg.on("pageerror", lambda e: errors.append(str(e)))
    pg.state, pg.errors = state, errors
    yield pg
    browser.close()
    pw.stop()


READ = """(stops) => {
  const { renderer, scene, camera, light, uniforms, setExposure } = window.example;
  setExposure(stops);
  renderer.render(scene, camera);
  const gl = renderer.getContext();
  const w = gl.drawingBufferWidth, h = gl.drawingBufferHeight;
  const px = new Uint8Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
  let s = '';
  for (let i = 0; i < px.length; i += 8192) s += String.fromCharCode.apply(null, px.subarray(i, i + 8192));
  const mesh = scene.children[0];
  return { w, h, data: btoa(s), world: camera.matrixWorld.elements, projInv: camera.projectionMatrixInverse.elements,
           light: light.direction.toArray(), radiance: light.radiance.toArray(),
           radius: mesh.geometry.parameters.radius, mesh: mesh.matrixWorld.elements,
           exposure: uniforms.exposure.value };
}"""


def render(page, module_text, stops=0.0):
    """The page with ``brdf.js`` = ``module_text`` at ``stops`` EV of exposure: its
    pixels (rows bottom-up, RGB 0-255) and its camera, light and exposure."""
    page.state["module"] = module_text
    page.errors.clear()
    page.goto(ORIGIN + "index.html")
    page.wait_for_function("window.example !== undefined", timeout=60000)
    r = page.evaluate(READ, stops)
    px = np.frombuffer(base64.b64decode(r["data"]), dtype=np.uint8).reshape(r["h"], r["w"], 4)
    return px[..., :3].astype(int), r


def reference(model, r, swap_xy=False, offset=(0.0, 0.0)):
    """NumPy's picture of the page's scene, in 8 bits, shaded at the pixel centres
    moved by ``offset`` (pixels), and the pixels to compare."""
    assert r["radius"] == 1.0 and np.allclose(np.array(r["mesh"]).reshape(4, 4), np.eye(4))
    w, h = r["w"], r["h"]
    world = np.array(r["world"]).reshape(4, 4).T      # three.js stores column-major
    proj_inv = np.array(r["projInv"]).reshape(4, 4).T
    jj, ii = np.meshgrid(np.arange(w) + 0.5 + offset[0], np.arange(h) + 0.5 + offset[1])
    one = np.ones_like(jj)
    ndc = np.stack([jj / w * 2 - 1, ii / h * 2 - 1, one, one], -1).reshape(-1, 4)
    far = ndc @ proj_inv.T
    far = (far[:, :3] / far[:, 3:]) @ world[:3, :3].T + world[:3, 3]
    eye = world[:3, 3]
    d = far - eye
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    b = d @ eye
    disc = b * b - (eye @ eye - 1.0)
    hit = disc > 0
    p = eye + (-b - np.sqrt(np.where(hit, disc, 0.0)))[:, None] * d
    n = p / np.linalg.norm(p, axis=1, keepdims=True)
    tan = np.stack([p[:, 2], np.zeros(len(p)), -p[:, 0]], -1)      # d p / d u of SphereGeometry
    tan /= np.maximum(np.linalg.norm(tan, axis=1, keepdims=True), 1e-30)
    bit = np.cross(n, tan)
    if swap_xy:
        tan, bit = bit, tan
    v = eye - p
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    light = np.array(r["light"])
    wi = np.stack([tan @ light, bit @ light, n @ light], -1)
    wo = np.stack([(v * tan).sum(1), (v * bit).sum(1), (v * n).sum(1)], -1)
    f = model._eval_block(wi, wo, (len(wi),))
    f = np.broadcast_to(f[:, None] if f.ndim == 1 else f, (len(wi), 3))
    rgb = f * np.maximum(wi[:, 2], 0.0)[:, None] * np.array(r["radiance"])
    want = tonemap(rgb, r.get("exposure", 1.0)).astype(float)
    keep = hit & (wo[:, 2] > 0.2) & (np.abs(p[:, 1]) < 0.97)
    return want.reshape(h, w, 3), keep.reshape(h, w)


#: Where within its pixel the page may shade (rasterisation and the tessellated
#: sphere move the shaded point by far less: about 0.02 pixel here).
SLACK = 0.25


def agree(got, model, r, swap_xy=False):
    """``(ok, share equal to the centre's value within 1 level, largest excess)``:
    every pixel kept lies, to 1 level, between the smallest and the largest of
    NumPy's values at the pixel centre and at the corners of the square of
    half-side ``SLACK`` pixels around it (one pixel spans 0.013 rad of the sphere
    here, over which a highlight changes by up to 100 levels)."""
    pics = [reference(model, r, swap_xy, (a, b)) for a, b in
            ((0, 0), (-SLACK, -SLACK), (-SLACK, SLACK), (SLACK, -SLACK), (SLACK, SLACK))]
    keep = np.logical_and.reduce([k for _, k in pics])
    stack = np.stack([p for p, _ in pics])
    lo, hi = stack.min(0) - 1, stack.max(0) + 1
    excess = np.maximum(lo - got, got - hi)[keep]
    within1 = float(np.mean(np.all(np.abs(got - pics[0][0])[keep] <= 1, axis=-1)))
    return bool(excess.max() <= 0), within1, int(excess.max())


CASES = [
    ("anisotropic, the docs' example", plausible.make("ashikhmin-shirley", nu=20.0, nv=400.0)),
    ("modified-phong, kd from its default", plausible.make("modified-phong", n=200.0, ks=0.3)),
    ("pumped-up, its table as a texture", plausible.make("pumped-up")),
]


@pytest.mark.parametrize("label,model", CASES, ids=[c[0] for c in CASES])
def test_the_three_js_example_page_renders_what_numpy_computes(page, label, model):
    got, r = render(page, to_js(model))
    assert page.errors == []
    want, keep = reference(model, r)
    assert keep.sum() > 0.3 * keep.size and want[keep].max() > 100      # the sphere, lit
    ok, within1, excess = agree(got, model, r)
    assert ok and within1 > 0.99, (label, within1, excess)


def test_the_page_writes_srgb_and_its_exposure_control_scales_the_radiance(page):
    """The canvas holds sRGB of radiance x 2^EV: at -2 EV and +1.5 EV the pixels
    match NumPy's; the linear values of the old page (no encoding) do not."""
    m = plausible.make("modified-phong", n=200.0, ks=0.3)
    for stops in (-2.0, 1.5):
        got, r = render(page, to_js(m), stops)
        assert r["exposure"] == 2.0 ** stops and page.errors == []
        ok, within1, excess = agree(got, m, r)
        assert ok and within1 > 0.99, (stops, within1, excess)
    linear = dict(r, exposure=1.0)
    want, keep = reference(m, linear)
    assert np.mean(np.abs(got - want)[keep] > 8) > 0.5       # sRGB at +1.5 EV is not the linear picture


def test_the_comparison_sees_an_unset_uniform_and_a_turned_frame(page):
    """The check can fail: the page with ``kd`` left unset (reads 0, as in the old
    docs' snippet), and the anisotropic model against a reference whose tangent
    and bitangent are swapped."""
    m = plausible.make("modified-phong", n=200.0, ks=0.3)
    text = re.sub(r'"plausible_kd": \[[^\]]*\], ', "", to_js(m))
    assert "plausible_kd\": [" not in text
    got, r = render(page, text)
    assert not agree(got, m, r)[0]
    m = plausible.make("ashikhmin-shirley", nu=20.0, nv=400.0)
    got, r = render(page, to_js(m))
    assert agree(got, m, r)[0] and not agree(got, m, r, swap_xy=True)[0]


# -- the plain WebGL2 function of docs/export.md ---------------------------------------

DOCS = ROOT / "docs" / "export.md"


def docs_function() -> str:
    """The ``plausibleProgram`` block of docs/export.md, as written there."""
    blocks = re.findall(r"^```js\n(.*?)^```", DOCS.read_text(), flags=re.S | re.M)
    found = [b for b in blocks if "function plausibleProgram(" in b]
    assert len(found) == 1, "docs/export.md: one js block defines plausibleProgram"
    return found[0]


def webgl2_page() -> str:
    return """<!doctype html><html><body><script>
%s
function b64f(s) { const b = atob(s); const u = new Uint8Array(b.length);
  for (let i = 0; i < b.length; i++) u[i] = b.charCodeAt(i); return new Float32Array(u.buffer); }
function f64b(a) { const u = new Uint8Array(a.buffer); let s = '';
  for (let i = 0; i < u.length; i += 8192) s += String.fromCharCode.apply(null, u.subarray(i, i + 8192));
  return btoa(s); }
window.runPairs = async function (url, wi, wo, w, h) {
  const brdf = await import(url);
  const gl = document.createElement('canvas').getContext('webgl2');
  gl.getExtension('EXT_color_buffer_float');
  const VS = `#version 300 es
void main() { vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0); }`;
  const MAIN = `
uniform highp sampler2D inWi;
uniform highp sampler2D inWo;
out vec4 outColor;
void main() {
  ivec2 ij = ivec2(gl_FragCoord.xy);
  outColor = vec4(${brdf.functions.f}(texelFetch(inWi, ij, 0).xyz, texelFetch(inWo, ij, 0).xyz), 1.0);
}`;
  const { program, unit } = plausibleProgram(gl, brdf, VS, MAIN);
  [['inWi', wi], ['inWo', wo]].forEach(([name, data], k) => {
    gl.activeTexture(gl.TEXTURE0 + unit + k);
    gl.bindTexture(gl.TEXTURE_2D, gl.createTexture());
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
    gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
    gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, b64f(data));
    gl.uniform1i(gl.getUniformLocation(program, name), unit + k);
  });
  const fb = gl.createFramebuffer();
  gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
  gl.activeTexture(gl.TEXTURE0 + unit + 2);
  const target = gl.createTexture();
  gl.bindTexture(gl.TEXTURE_2D, target);
  gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA32F, w, h, 0, gl.RGBA, gl.FLOAT, null);
  gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, target, 0);
  gl.viewport(0, 0, w, h);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
  const px = new Float32Array(w * h * 4);
  gl.readPixels(0, 0, w, h, gl.RGBA, gl.FLOAT, px);
  return f64b(px);
};
</script></body></html>""" % docs_function()


def _b64(a):
    full = np.zeros((len(a), 4), dtype=np.float32)
    full[:, :3] = a
    return base64.b64encode(full.tobytes()).decode()


def test_the_docs_plain_webgl2_function_sets_every_uniform_and_table(page):
    """``plausibleProgram`` of docs/export.md, as written, with the modules of
    pumped-up (its table a texture; a colour uniform) and Modified Phong (three
    uniforms), on the 4096 direction pairs of the other browser tests: NumPy's f
    within RTOL; the same pairs with a pumped-up of another base differ (the
    check can fail)."""
    wi, wo = direction_pairs()
    models = [plausible.make("pumped-up", rs=[0.9, 0.7, 0.5]), plausible.make("modified-phong", n=200.0, ks=0.3),
              plausible.make("pumped-up", base="reciprocal-phong:ks=1:n=60")]
    page.goto(ORIGIN + "webgl2.html")
    got = []
    for k, m in enumerate(models[:2]):
        page.state["module"] = to_js(m)
        data = page.evaluate("([u, a, b, w, h]) => runPairs(u, a, b, w, h)",
                             [f"{ORIGIN}brdf.js?{k}", _b64(wi), _b64(wo), WIDTH, len(wi) // WIDTH])
        got.append(np.frombuffer(base64.b64decode(data), dtype=np.float32).reshape(-1, 4)[:, :3])
    assert page.errors == []
    ref = lambda m: np.broadcast_to(m._eval_block(wi.astype(float), wo.astype(float), (len(wi),)).reshape(  # noqa: E731
        len(wi), -1), (len(wi), 3))
    assert [relative_errors(g, ref(m)).max() <= RTOL for g, m in zip(got, models)] == [True, True]
    assert relative_errors(got[0], ref(models[2])).max() > 10 * RTOL


def test_make_installs_the_three_js_version_of_the_page():
    """``make three`` pins the version the page's import map loads (else the test
    would skip, or serve another three.js than the page names)."""
    pinned = re.search(r"^THREE_VERSION\s*:=\s*(\S+)", (ROOT / "Makefile").read_text(), re.M).group(1)
    assert f"three@{pinned}/" in cdn_prefix()
