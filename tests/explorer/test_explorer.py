"""`plausible explore`: the server answers with the library's numbers and refuses
what the API refuses; in a real browser (Debian's chromium via Playwright,
WebGL2 on SwiftShader) the page loads without console errors, every model can
be selected and drawn, a slider changes the sphere and the plots, the albedo
shown is the API's, and the exports download and load."""

import json
import math
import os
import shutil
import socket
import threading
import time

import numpy as np
import pytest

import plausible
from plausible.explorer import views

fastapi = pytest.importorskip("fastapi")
from fastapi.testclient import TestClient  # noqa: E402

from plausible.explorer.app import create_app  # noqa: E402


@pytest.fixture(scope="module")
def client():
    return TestClient(create_app(), base_url="http://127.0.0.1")


def test_models_lists_every_registered_model(client):
    names = [m["name"] for m in client.get("/api/models").json()]
    assert names == plausible.names() + ["material"]


def test_out_of_range_is_refused_with_the_api_message(client):
    with pytest.raises(ValueError) as e:
        plausible.make("ashikhmin-shirley", nu=-3)
    r = client.post("/api/plane", json={"model": "ashikhmin-shirley", "params": {"nu": -3}})
    assert r.status_code == 422 and r.json()["error"] == str(e.value)
    r = client.post("/api/plane", json={"model": "modified-phong", "params": {"kd": 0.8, "ks": 0.5}})
    assert r.status_code == 422 and "kd + ks" in r.json()["error"]
    r = client.post("/api/plane", json={"model": "lambertian", "theta_i": 95})
    assert r.status_code == 422 and "theta_i must lie in [0, 90]" in r.json()["error"]


def test_plane_is_f_cos_in_the_plane_of_incidence(client):
    m = plausible.make("modified-phong", kd=0.2, ks=0.6, n=40)
    d = client.post("/api/plane", json={"model": "modified-phong", "params": {"kd": 0.2, "ks": 0.6, "n": 40},
                                        "theta_i": 30}).json()
    t = np.radians(d["theta_o"][100])
    wo = [math.sin(t), 0, math.cos(t)]
    wi = [-math.sin(math.radians(30)), 0, math.cos(math.radians(30))]
    assert d["fcos"][100] == pytest.approx(float(m.eval(wi, wo)) * math.cos(t), rel=1e-12)


def test_albedo_equals_the_library(client):
    d = client.post("/api/albedo", json={"model": "ashikhmin-shirley-diffuse", "params": {"rd": 0.8}}).json()
    th = np.radians(d["theta"])
    # closed form of the coupled diffuse term: rd (1 - rs) (1 - (1 - cos/2)^5) (JGT 2000, eq. 5)
    exact = 0.8 * (1 - 0.05) * (1 - (1 - np.cos(th) / 2) ** 5)
    assert np.allclose(d["value"], exact, atol=1e-6) and d["energy_gained_at"] == []


def test_energy_gain_is_marked(client):
    # the original Phong model is not energy conserving near grazing (its albedo exceeds 1)
    d = client.post("/api/albedo", json={"model": "phong", "params": {"ks": 1.0, "n": 1}}).json()
    direct = plausible.albedo_curve(plausible.make("phong", ks=1.0, n=1), np.radians(d["theta"]))
    over = [t for t, a, e in zip(d["theta"], direct.value, direct.error) if a - e > 1 + views.ENERGY_TOL]
    assert over and d["energy_gained_at"] == over


def test_slice_is_f_at_the_half_diff_angles(client):
    d = client.post("/api/slice", json={"model": "blinn"}).json()
    from plausible.models.merl import from_half_diff

    wi, wo = from_half_diff(math.radians(d["theta_h"][5]), math.radians(d["theta_d"][20]), math.pi / 2)
    assert d["f"][5][20] == pytest.approx(float(plausible.make("blinn").eval(wi, wo)), rel=1e-12)


def test_exports_load(client):
    mi = pytest.importorskip("mitsuba")
    mi.set_variant("llvm_ad_rgb")
    import plausible.mitsuba as pm

    pm.register()
    params = {"nu": 20, "nv": 300, "rs": [0.9, 0.6, 0.2], "rd": 0.1}
    get = lambda fmt: client.post("/api/export", json={"model": "ashikhmin-shirley", "params": params,
                                                       "format": fmt})
    r = get("mitsuba-dict")
    assert r.headers["content-disposition"] == 'attachment; filename="ashikhmin-shirley.json"'
    bsdf = mi.load_dict(json.loads(r.text))
    import drjit as dr

    wi = np.array([[0.3, 0.1, 0.948]]) / np.linalg.norm([0.3, 0.1, 0.948])
    wo = np.array([[-0.33, -0.08, 0.94]]) / np.linalg.norm([-0.33, -0.08, 0.94])
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(np.ascontiguousarray(wi.T, dtype=np.float32))
    got = np.array(bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(np.ascontiguousarray(wo.T, dtype=np.float32)))).T
    want = plausible.make("ashikhmin-shirley", **params).eval(wi, wo) * wo[:, 2:3]   # reciprocal: order free
    assert np.allclose(got, want, rtol=2e-4)          # the plugin has the exported parameters (float32)
    mi.load_string('<scene version="3.0.0">' + get("mitsuba-xml").text + "</scene>")
    again = plausible.registry.make_from_spec(get("spec").text.strip())
    assert repr(again) == repr(plausible.make("ashikhmin-shirley", **params))
    brdf = get("brdf").text.splitlines()
    assert brdf[0] == "analytic" and "::begin parameters" in brdf and "::begin shader" in brdf
    assert not any(line.startswith(("#define", "#version", "#if")) for line in brdf)   # the loader drops '#' lines
    assert "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)" in "\n".join(brdf)
    assert "plausible_f(" in get("glsl").text
    r = client.post("/api/export", json={"model": "lambertian", "format": "png"})
    assert r.status_code == 422 and "export format must be one of" in r.json()["error"]


def test_cli_binds_localhost_by_default():
    from plausible.cli import explore

    opts = {o.name: o for o in explore.params}
    assert opts["host"].default == "127.0.0.1" and opts["no_browser"].is_flag


# -- in a real browser -----------------------------------------------------------------------

CHROMIUM = shutil.which("chromium") or "/usr/bin/chromium"


def _free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


@pytest.fixture(scope="module")
def page():
    sync_api = pytest.importorskip("playwright.sync_api")
    if not os.path.exists(CHROMIUM):
        pytest.skip("Debian's chromium is not installed (make chromium)")
    import uvicorn

    port = _free_port()
    server = uvicorn.Server(uvicorn.Config(create_app(), host="127.0.0.1", port=port, log_level="warning"))
    th = threading.Thread(target=server.run, daemon=True)
    th.start()
    while not server.started:
        time.sleep(0.05)
    with sync_api.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=[
            "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--no-sandbox",
            "--disable-background-networking", "--disable-component-update", "--disable-sync"])
        pg = browser.new_page(accept_downloads=True)
        pg.errors = []
        pg.on("console", lambda m: pg.errors.append(m.text) if m.type == "error" else None)
        pg.on("pageerror", lambda e: pg.errors.append(str(e)))
        pg.goto(f"http://127.0.0.1:{port}/")
        pg.wait_for_function("window.explorer && window.explorer.ready", timeout=60_000)
        yield pg
        browser.close()
    server.should_exit = True
    th.join(5)


def _idle(page):
    page.wait_for_function("window.explorer.pending === 0", timeout=60_000)
    page.wait_for_timeout(50)
    page.wait_for_function("window.explorer.pending === 0", timeout=60_000)


def _sphere(page, side="A"):
    return page.evaluate(f"document.getElementById('sphere-{side}').toDataURL()")


def test_page_loads_without_console_errors(page):
    _idle(page)
    assert page.errors == []
    assert page.evaluate("window.explorer.sides.A.drawn") >= 1
    assert page.locator("#status").inner_text() == ""


def test_every_model_can_be_selected_and_drawn(page):
    for name in plausible.names():
        page.select_option("#model-A", name)
        page.wait_for_function(f"window.explorer.sides.A && window.explorer.sides.A.name === '{name}' "
                               "&& window.explorer.sides.A.drawn >= 1 && window.explorer.data.A.plane", timeout=60_000)
        assert page.locator("#status").inner_text() == "", name
        # the sphere shows the model: some pixels inside the disc are lit
        lit = page.evaluate("""() => { const c = document.getElementById('sphere-A');
            const g = c.getContext('webgl2'); const px = new Uint8Array(4 * c.width * c.height);
            g.readPixels(0, 0, c.width, c.height, g.RGBA, g.UNSIGNED_BYTE, px);
            let n = 0; for (let i = 0; i < px.length; i += 4) if (px[i] > 80 || px[i+1] > 80 || px[i+2] > 80) n++;
            return n; }""")
        assert lit > 50, name
    assert page.errors == []


def test_slider_changes_sphere_and_plots(page):
    page.select_option("#model-A", "ashikhmin-shirley")
    page.wait_for_function("window.explorer.sides.A.name === 'ashikhmin-shirley' && window.explorer.data.A.plane")
    _idle(page)
    before_img = _sphere(page)
    before_plane = page.evaluate("window.explorer.data.A.plane.fcos")
    page.locator("[data-param=nu] input[type=range]").fill("0.2")
    page.wait_for_timeout(300)
    _idle(page)
    asked = page.evaluate("window.explorer.data.A.asked")
    assert asked["params"]["nu"] == page.evaluate("window.explorer.sides.A.params.nu") < 100
    assert _sphere(page) != before_img
    after_plane = page.evaluate("window.explorer.data.A.plane.fcos")
    expected = views.plane(views.build("ashikhmin-shirley", asked["params"]), asked["theta_i"])["fcos"]
    assert np.allclose(after_plane, expected, rtol=1e-12) and not np.allclose(after_plane, before_plane)


def test_albedo_shown_is_the_api_albedo(page):
    page.select_option("#model-A", "reciprocal-phong")
    page.wait_for_function("window.explorer.sides.A.name === 'reciprocal-phong'")
    page.wait_for_function("document.querySelectorAll('#albedo-table tr[data-side=A]').length === 3 && "
                           "window.explorer.data.A.albedo", timeout=60_000)
    rows = page.locator("#albedo-table tr[data-side=A]")
    m = plausible.make("reciprocal-phong")
    for i in range(rows.count()):
        theta = float(rows.nth(i).get_attribute("data-theta"))
        shown = float(rows.nth(i).locator(".albedo-value").inner_text())
        direct = float(plausible.albedo(m, plausible.analysis.direction(math.radians(theta))).value)
        assert shown == pytest.approx(direct, rel=1e-5, abs=1e-6)


def test_compare_two_models(page):
    page.select_option("#model-B", "lambertian")
    page.wait_for_function("window.explorer.sides.B && window.explorer.sides.B.drawn >= 1", timeout=60_000)
    _idle(page)
    assert page.locator("#sphere-B").is_visible() and page.evaluate("!!window.explorer.data.B.plane")
    page.select_option("#model-B", "")
    assert page.locator("#sphere-B").is_hidden()


def test_exports_download(page, tmp_path):
    page.select_option("#model-A", "ward")
    page.wait_for_function("window.explorer.sides.A.name === 'ward' && window.explorer.sides.A.drawn >= 1")
    _idle(page)
    with page.expect_download() as dl:
        page.click("#exports button[data-format=mitsuba-dict]")
    path = tmp_path / dl.value.suggested_filename
    dl.value.save_as(path)
    assert path.name == "ward.json" and json.loads(path.read_text())["type"] == "ward"
    with page.expect_download() as dl:
        page.click("#exports button[data-format=brdf]")
    assert dl.value.suggested_filename == "ward.brdf"
    assert page.errors == []


def test_lobe3d_is_f_cos_on_its_grid(client):
    for params in ({}, {"rs": [0.9, 0.5, 0.1]}):          # grey and RGB
        m = plausible.make("ashikhmin-shirley", **params)
        d = client.post("/api/lobe3d", json={"model": "ashikhmin-shirley", "params": params, "theta_i": 40}).json()
        t, p = math.radians(d["theta"][7]), math.radians(d["phi"][11])
        wo = [math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)]
        wi = [-math.sin(math.radians(40)), 0.0, math.cos(math.radians(40))]
        assert d["fcos"][7][11] == pytest.approx(float(np.mean(m.eval(wi, wo))) * math.cos(t), rel=1e-12)


def test_published_materials_are_in_the_catalogue_and_export(client):
    entry = client.get("/api/models").json()[-1]
    assert entry["name"] == "material"
    assert set(entry["params"][0]["choices"]) == set(plausible.materials())
    body = {"model": "material", "params": {"name": "gold-metallic-paint", "fit": "ngan2005/ward-duer"}}
    d = client.post("/api/albedo", json=body).json()
    with plausible.use_backend("numpy"):      # an independent run of the same integral
        direct = plausible.albedo_curve(plausible.material("gold-metallic-paint", fit="ngan2005/ward-duer"),
                                        np.radians(d["theta"]))
    # the same integral (the backend auto picks may differ between the two calls:
    # equal within the error bounds, not bit for bit)
    assert np.all(np.abs(np.array(d["value"]) - direct.value) <= np.array(d["error"]) + direct.error)
    assert d["energy_gained_at"] == [t for t, a, e in zip(d["theta"], np.max(direct.value, -1),
                                                          np.max(direct.error, -1)) if a - e > 1 + views.ENERGY_TOL]
    spec = client.post("/api/export", json=dict(body, format="spec")).text.strip()
    assert spec == "material:gold-metallic-paint@ngan2005/ward-duer"
    assert repr(plausible.registry.make_from_spec(spec)) == repr(plausible.material("gold-metallic-paint",
                                                                                      fit="ngan2005/ward-duer"))
    r = client.post("/api/plane", json={"model": "material", "params": {"name": "alum-brnze"}})
    assert r.status_code == 422 and "alum-bronze" in r.json()["error"]      # the closest name is suggested


def test_a_material_can_be_selected_in_the_page(page):
    page.select_option("#model-A", "material")
    page.wait_for_function("window.explorer.sides.A.name === 'material' && window.explorer.sides.A.drawn >= 1 "
                           "&& window.explorer.data.A.plane", timeout=60_000)
    page.select_option("[data-param=name] select", "gold-metallic-paint")
    page.wait_for_timeout(400)
    _idle(page)
    asked = page.evaluate("window.explorer.data.A.asked")
    assert asked["params"]["name"] == "gold-metallic-paint"
    want = views.plane(plausible.material("gold-metallic-paint"), asked["theta_i"])["fcos"]
    assert np.allclose(page.evaluate("window.explorer.data.A.plane.fcos"), want, rtol=1e-12)
    assert page.locator("#status").inner_text() == "" and page.errors == []


# -- what a user meets first (issue 29) ---------------------------------------------------

def test_a_pending_verdict_says_computing_and_the_old_one_goes(page):
    page.select_option("#model-A", "lambertian")
    page.wait_for_function("window.explorer.data.A.verdict", timeout=60_000)
    page.select_option("#model-A", "reciprocal-phong")
    # at once: no verdict of the previous model, a sign that one is coming
    assert "computing" in page.locator("#verdict-A").inner_text()
    assert "lambertian" not in page.locator("#verdict-A").inner_text()
    page.wait_for_function("window.explorer.data.A.verdict", timeout=60_000)
    text = page.locator("#verdict-A").inner_text()
    assert "computing" not in text and "reciprocal-phong" in text


def _set_number(page, name, value):
    box = page.locator(f"#params-A [data-param={name}] input[type=number]")
    box.fill(str(value))
    box.dispatch_event("change")


def test_a_refused_parameter_set_goes_back_to_the_last_valid_one(page):
    page.select_option("#model-A", "modified-phong")
    page.wait_for_function("window.explorer.sides.A.name === 'modified-phong' && window.explorer.data.A.plane")
    _idle(page)
    # kd, ks are colours; n is the scalar with a number box: set a valid n first, then a refused kd
    _set_number(page, "n", 12)
    page.wait_for_timeout(300)
    _idle(page)
    assert page.evaluate("window.explorer.data.A.asked.params.n") == 12
    before = _sphere(page)
    # a colour slider to full brightness: kd = 1 with ks = 0.2 breaks kd + ks <= 1
    page.locator("#params-A [data-param=kd] input[type=range]").fill("1")
    page.wait_for_timeout(300)
    _idle(page)
    page.wait_for_timeout(300)
    _idle(page)
    status = page.locator("#status").inner_text()
    assert "refused" in status and "kd' + 'ks' must not exceed 1" in status and "Back to the last valid" in status
    assert "array(" not in status and "[1.2 1.2 1.2]" not in status and "[1.2, 1.2, 1.2]" in status
    params = page.evaluate("window.explorer.sides.A.params")
    assert params["kd"] == 0.5 and params["n"] == 12                # the defaults' kd, the accepted n
    assert page.evaluate("window.explorer.data.A.asked.params") == params   # the plots show those values
    slider = float(page.locator("#params-A [data-param=kd] input[type=range]").input_value())
    assert slider == pytest.approx(0.5, abs=1e-3)                   # the control shows them too
    assert _sphere(page) == before                                  # and the sphere
    want = views.plane(plausible.make("modified-phong", n=12), page.evaluate("window.explorer.thetaI"))["fcos"]
    assert np.allclose(page.evaluate("window.explorer.data.A.plane.fcos"), want, rtol=1e-12)


def test_the_albedo_axis_covers_the_curves_and_names_the_channel_mean(page):
    page.select_option("#model-A", "phong")          # the original Phong gains energy toward grazing
    page.wait_for_function("window.explorer.sides.A.name === 'phong' && window.explorer.data.A.albedo", timeout=60_000)
    _idle(page)
    a = page.evaluate("window.explorer.data.A.albedo")
    axis = page.evaluate("window.explorer.albedoAxis")
    highest = max(max(v + e for v, e in zip(a["value"], a["error"])), max(a["max"]))
    assert highest > 1.0 and axis["top"] >= highest and axis["ticks"][-1] >= 1.0
    assert page.locator("#albedo-note").inner_text() == ""           # a grey model: nothing to say
    page.select_option("#model-A", "material")
    page.wait_for_function("window.explorer.sides.A.name === 'material' && window.explorer.data.A.albedo",
                           timeout=60_000)
    _idle(page)
    assert "channel mean" in page.locator("#albedo-note").inner_text()
    assert "A: mean of its 3 channels" in page.locator("#albedo-note").inner_text()


def test_the_verdict_is_in_view_at_1280x720(page):
    page.set_viewport_size({"width": 1280, "height": 720})
    page.select_option("#model-A", "ward")
    page.wait_for_function("window.explorer.sides.A.name === 'ward' && window.explorer.data.A.verdict", timeout=60_000)
    page.evaluate("window.scrollTo(0, 0)")
    box = page.locator("#verdict-A").bounding_box()
    assert box["height"] > 20 and box["y"] >= 0 and box["y"] + box["height"] <= 720


def test_compare_draws_each_lobe_to_its_own_scale(page):
    page.select_option("#model-A", "reciprocal-phong")      # a lobe 12 times the Lambertian's height
    page.wait_for_function("window.explorer.sides.A.name === 'reciprocal-phong' && window.explorer.data.A.plane")
    page.select_option("#model-B", "lambertian")
    page.wait_for_function("window.explorer.sides.B && window.explorer.data.B.plane", timeout=60_000)
    _idle(page)
    page.evaluate("window.explorer.perLobe || document.getElementById('per-lobe').click()")
    scale = page.evaluate("window.explorer.plotScale")
    for k in "AB":
        assert scale[k] == max(page.evaluate(f"window.explorer.data.{k}.plane.fcos"))   # each reaches the rim
    assert scale["A"] > 3 * scale["B"]
    assert "each lobe to its own scale" in page.evaluate("document.getElementById('per-lobe').parentNode.innerText")
    page.locator("#per-lobe").click()                                  # one shared scale again
    scale = page.evaluate("window.explorer.plotScale")
    assert scale["A"] == scale["B"] == max(page.evaluate("window.explorer.data.A.plane.fcos"))
    page.locator("#per-lobe").click()
    page.select_option("#model-B", "")


def test_incidence_goes_to_89_9_degrees(page):
    page.select_option("#model-A", "lambertian")
    page.wait_for_function("window.explorer.sides.A.name === 'lambertian' && window.explorer.data.A.plane")
    page.locator("#theta-i").fill("89.9")
    page.wait_for_timeout(300)
    _idle(page)
    assert page.evaluate("window.explorer.data.A.asked.theta_i") == 89.9
    assert page.locator("#theta-i-out").inner_text() == "89.9°"
    want = views.plane(plausible.make("lambertian"), 89.9)["fcos"]
    assert np.allclose(page.evaluate("window.explorer.data.A.plane.fcos"), want, rtol=1e-12)
    page.locator("#theta-i").fill("30")
    page.wait_for_timeout(300)
    _idle(page)


def test_the_slice_has_a_colour_bar_with_its_maximum(page, client):
    page.select_option("#model-A", "ward")
    page.wait_for_function("window.explorer.sides.A.name === 'ward' && window.explorer.data.A.slice", timeout=60_000)
    _idle(page)
    top = max(map(max, client.post("/api/slice", json={"model": "ward", "params": {}}).json()["f"]))
    label = page.locator("#slice-scale").inner_text()
    assert f"A {float(f'{top:.4g}'):.4g}"[:6] in label.replace("\n", " ") and "10⁻⁴ max" in label
    # the bar: viridis, bright at the top, dark at the bottom
    px = page.evaluate("""() => { const g = document.getElementById('slice-bar').getContext('2d');
        return [Array.from(g.getImageData(5, 0, 1, 1).data), Array.from(g.getImageData(5, 191, 1, 1).data)]; }""")
    assert px[0][:3] == [253, 231, 37] and px[1][:3] == [68, 1, 84]


# -- at laptop width (issue 47 item 2) -------------------------------------------------------

def _boxes_apart(a, b):
    return a["x"] + a["width"] <= b["x"] or b["x"] + b["width"] <= a["x"] or \
        a["y"] + a["height"] <= b["y"] or b["y"] + b["height"] <= a["y"]


def test_compare_mode_fits_1280x800_with_both_spheres_in_view(page, tmp_path):
    from PIL import Image

    page.set_viewport_size({"width": 1280, "height": 800})
    page.select_option("#model-A", "ashikhmin-shirley")
    page.wait_for_function("window.explorer.sides.A.name === 'ashikhmin-shirley' && window.explorer.data.A.plane")
    page.select_option("#model-B", "phong")
    page.wait_for_function("window.explorer.sides.B && window.explorer.sides.B.drawn >= 1 "
                           "&& window.explorer.data.B.plane", timeout=60_000)
    _idle(page)
    page.evaluate("window.scrollTo(0, 0)")
    assert page.evaluate("document.documentElement.scrollWidth") <= 1280          # no horizontal overflow
    shot = tmp_path / "compare.png"
    page.screenshot(path=str(shot))
    img = np.asarray(Image.open(shot).convert("RGB"), dtype=int)
    assert img.shape[:2] == (800, 1280)
    for k in "AB":
        b = page.locator(f"#sphere-{k}").bounding_box()
        assert b["width"] >= 200 and b["x"] >= 0 and b["y"] >= 0
        assert b["x"] + b["width"] <= 1280 and b["y"] + b["height"] <= 800, (k, b)
        # the screenshot shows the sphere there: grey (#444) corners, a lit disc inside
        x0, y0, w = int(b["x"]), int(b["y"]), int(b["width"])
        corner = img[y0 + 3, x0 + 3]
        disc = img[y0 + w // 4: y0 + 3 * w // 4, x0 + w // 4: x0 + 3 * w // 4].reshape(-1, 3)
        assert np.all(np.abs(corner - 0x44) <= 2), (k, corner)
        assert np.abs(disc - 0x44).max() > 60, k
    page.select_option("#model-B", "")


def test_material_mode_labels_name_the_choice_not_its_set(page):
    page.select_option("#model-A", "material")
    page.wait_for_function("window.explorer.sides.A.name === 'material' && window.explorer.data.A.plane",
                           timeout=60_000)
    labels = page.locator("#params-A label").all_inner_texts()
    assert labels == ["name (100 choices)", "fit (13 choices)"], labels


def test_albedo_caption_and_slice_labels_read_cleanly(page):
    page.set_viewport_size({"width": 1280, "height": 800})
    page.select_option("#model-A", "ward")
    page.wait_for_function("window.explorer.sides.A.name === 'ward' && window.explorer.data.A.albedo "
                           "&& window.explorer.data.A.slice", timeout=60_000)
    page.select_option("#model-B", "lambertian")
    page.wait_for_function("window.explorer.sides.B && window.explorer.data.B.slice", timeout=60_000)
    _idle(page)
    caption = page.locator("#albedo-note").evaluate("e => e.parentNode.innerText")
    assert caption.endswith("red: energy gained)") and "; )" not in caption
    # each colour-bar label is one line beside the bar, over neither slice
    slices = [page.locator(f"#slice-{k}").bounding_box() for k in "AB"]
    spans = page.locator("#slice-scale span")
    assert spans.count() == 3
    for i in range(3):
        b = spans.nth(i).bounding_box()
        assert b["height"] < 20 and all(_boxes_apart(b, s) for s in slices), (i, b, slices)
    page.select_option("#model-B", "")


def test_a_narrow_lobe_says_what_the_sky_dots_are(page):
    page.select_option("#model-A", "material")          # alum-bronze, A-S n = 1350: half-maximum width ~7 deg
    page.wait_for_function("window.explorer.sides.A.name === 'material' && window.explorer.data.A.plane",
                           timeout=60_000)
    _idle(page)
    note = page.locator("#sky-note").inner_text()
    assert "narrow lobe" in note and "32 directional lights" in note
    assert page.evaluate("window.explorer.narrow.A") < 20
    page.locator("#env").fill("0")                       # no sky, no dots: nothing to say
    assert page.locator("#sky-note").inner_text() == ""
    page.locator("#env").fill("0.3")
    page.select_option("#model-A", "lambertian")         # a wide lobe: nothing to say
    page.wait_for_function("window.explorer.sides.A.name === 'lambertian' && window.explorer.data.A.plane")
    _idle(page)
    assert page.locator("#sky-note").inner_text() == ""


def test_the_verdict_says_it_is_computing_from_the_first_paint(page):
    held = []                                   # the catalogue held back: the page as first painted
    page.route("**/api/models", lambda r: held.append(r))
    page.goto(page.url, wait_until="domcontentloaded")
    page.wait_for_function("document.getElementById('verdict-A') !== null")
    assert "computing the verdict" in page.locator("#verdict-A").inner_text()
    page.wait_for_timeout(200)
    assert len(held) == 1
    held[0].continue_()
    page.unroute("**/api/models")
    page.wait_for_function("window.explorer && window.explorer.ready", timeout=60_000)
    page.wait_for_function("window.explorer.data.A.verdict", timeout=60_000)
    assert "computing" not in page.locator("#verdict-A").inner_text()
