"""The exported GLSL executed in a real browser (headless Chromium, WebGL2 on
SwiftShader), compared with the NumPy backend on the same float32 inputs.

Criterion (float32 shaders): relative error at most ``RTOL = 1e-4`` wherever f
is above ``1e-6`` of its maximum over the case (``cases.relative_errors``).  The
reference is the NumPy hooks at exactly the values the shader receives (the
front end's normalisation is the caller's job in a shader).  One browser page
compiles every shader of the session.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import plausible
from plausible.analysis.suite import variants
from plausible.export import to_brdf, to_glsl

import brdf_file
from glsl_cases import RTOL, direction_pairs, relative_errors

pytest.importorskip("playwright.sync_api")
from glsl_webgl import Browser, chromium  # noqa: E402

F_BODY = "outColor = vec4(plausible_f(a.xyz, b.xyz), 1.0);"


@pytest.fixture(scope="module")
def browser():
    if chromium() is None:
        pytest.skip("chromium is not installed (make chromium installs Debian's)")
    b = Browser()
    if not b.ready:
        b.close()
        pytest.skip("no WebGL2 with EXT_color_buffer_float in this chromium")
    yield b
    b.close()


@pytest.fixture(scope="module")
def pairs():
    return direction_pairs()


def reference_f(m, wi, wo):
    """NumPy f at exactly the shader's inputs (float32 values, as float64), as (N, 3)."""
    r = m._eval_block(wi.astype(np.float64), wo.astype(np.float64), (len(wi),))
    return np.broadcast_to(r[:, None] if r.ndim == 1 else r, (len(wi), 3))


def job(shader, body=F_BODY):
    return (shader.text, body), {u.name: list(u.value) for u in shader.uniforms}


def worst(cases, results, refs):
    """Per case the largest error (or the compile error); the cases over RTOL."""
    bad = []
    for case, got, ref in zip(cases, results, refs):
        if isinstance(got, str):
            bad.append((case, got[:300]))
            continue
        e = relative_errors(got[:, :3], ref)
        if not (np.all(np.isfinite(got)) and e.max() <= RTOL):
            i = int(np.argmax(e) // 3)
            bad.append((case, f"max error {e.max():.3g} at pair {i}"))
    return bad


def f_cases(max_variants):
    """(label, model, uniforms) -- defaults and extremes (at most max_variants - 1 of
    them; 0: all), baked; defaults as uniforms;
    RGB colours."""
    out = []
    for name in plausible.names():
        for kw in variants(name, max_variants):
            out.append((f"{name} {kw}", plausible.make(name, **kw), False))
        out.append((f"{name} uniforms", plausible.make(name), True))
    out.append(("ashikhmin-shirley rgb", plausible.make("ashikhmin-shirley", rs=[0.9, 0.6, 0.2],
                                                        rd=[0.1, 0.5, 0.3]), True))
    out.append(("cook-torrance conductor rgb", plausible.make(
        "cook-torrance", fresnel="conductor", eta=[0.2, 0.9, 1.1], k=[3.9, 2.4, 2.2]), False))
    return out


def extreme_exponents():
    return [("modified-phong n=1e4", plausible.make("modified-phong", n=1e4), False),
            ("neumann-metal n=1e4", plausible.make("neumann-metal", n=1e4), True),
            ("ashikhmin-shirley nu=1e4", plausible.make("ashikhmin-shirley", nu=1e4, nv=10.0), False),
            ("reciprocal-blinn n=1e4", plausible.make("reciprocal-blinn", n=1e4), False),
            ("ward alpha_y=0.01", plausible.make("ward", alpha_y=0.01), False)]


def check_f(browser, pairs, cases):
    wi, wo = pairs
    browser.set_inputs([wi, wo])
    results = browser.run([job(to_glsl(m, uniforms=u)) for _, m, u in cases])
    return worst([c[0] for c in cases], results, [reference_f(m, wi, wo) for _, m, _ in cases])


def test_every_model_agrees_with_numpy_in_webgl(browser, pairs):
    cases = f_cases(2) + extreme_exponents()
    assert len(pairs[0]) >= 4096
    assert check_f(browser, pairs, cases) == []


@pytest.mark.slow
def test_every_model_at_every_extreme_agrees_with_numpy_in_webgl(browser, pairs):
    assert check_f(browser, pairs, f_cases(0)) == []


def test_a_wrong_formula_is_caught(browser, pairs):
    """The comparison can fail: a shader exported from n = 10001 against NumPy at n = 10000."""
    wi, wo = pairs
    browser.set_inputs([wi, wo])
    got, = browser.run([job(to_glsl(plausible.make("reciprocal-phong", n=10001.0)))])
    ref = reference_f(plausible.make("reciprocal-phong", n=1e4), wi, wo)
    assert relative_errors(got[:, :3], ref).max() > 10 * RTOL


def test_power_helper_follows_the_ops_contract(browser):
    """``plausible_pow``: 0^0 = 1, 0^e = 0, negative bases as 0 (ops.power), and
    near 1 with e = 1e4 within 1e-5 of float64 (GLSL pow errs by ~1e-4 there)."""
    b = np.array([0.0, 0.0, -1.0, -0.5, 1.0 - 1e-4, 1.0 - 1e-6, 0.3, 2.0] * 8, dtype=np.float32)
    e = np.array([0.0, 2.0, 2.0, 0.0, 1e4, 1e4, 3.5, 10.0] * 8, dtype=np.float32)
    browser.set_inputs([np.stack([b, e, b], -1)])
    shader = to_glsl(plausible.make("lafortune", lobes=[(-1, -1, 1, 1e4, 0.1)], rd=0.0))
    got, = browser.run([((shader.text, "outColor = vec4(plausible_pow(a.x, a.y));"), {})])
    bd, ed = b.astype(np.float64), e.astype(np.float64)
    want = np.where(bd > 0, np.power(np.where(bd > 0, bd, 1.0), ed), np.where(ed == 0, 1.0, 0.0))
    assert np.allclose(got[:8, 0], want[:8], rtol=1e-5, atol=0.0)


def test_sampling_agrees_with_numpy_in_webgl(browser):
    """pdf at the same pairs (same criterion as f); the sampled direction for the
    same (wi, u) (median within 1e-6 rad, all within 1e-4: float32 warps; no lobe
    choice flips at these seeds), and weight and pdf of the sample against NumPy
    at the shader's own direction."""
    rng = np.random.default_rng(3)
    wi, wo = direction_pairs(seed=11)
    u = rng.random((len(wi), 3)).astype(np.float32)
    shaders = [(plausible.make(n), to_glsl(plausible.make(n))) for n in plausible.names()]
    shaders = [(m, s) for m, s in shaders if s.sampling]
    models = [m for m, _ in shaders]
    browser.set_inputs([wi, wo, u])
    body_pdf = "outColor = vec4(plausible_pdf(a.xyz, b.xyz));"
    body_s = "vec3 w; float p; vec3 d = plausible_sample(a.xyz, c.xyz, w, p); outColor = vec4(d, p);"
    body_w = "vec3 w; float p; vec3 d = plausible_sample(a.xyz, c.xyz, w, p); outColor = vec4(w, 0.0);"
    res = browser.run([job(s, b) for _, s in shaders for b in (body_pdf, body_s, body_w)])
    w64, u64 = wi.astype(np.float64), u.astype(np.float64)
    bad = []
    for k, m in enumerate(models):
        pdf, smp, wgt = res[3 * k: 3 * k + 3]
        assert not isinstance(pdf, str), pdf
        ref_pdf = m._pdf_block(w64, wo.astype(np.float64), (len(wi),))
        if relative_errors(pdf[:, 0], ref_pdf).max() > RTOL:
            bad.append((m.name, "pdf", relative_errors(pdf[:, 0], ref_pdf).max()))
        ref = m._sample_block(w64, u64, (len(wi),))
        g = smp[:, :3].astype(np.float64) / np.linalg.norm(smp[:, :3], axis=-1, keepdims=True)
        ang = 2.0 * np.arcsin(np.minimum(np.linalg.norm(g - ref.wo, axis=-1) / 2.0, 1.0))
        if np.median(ang) > 1e-6 or ang.max() > 1e-4:  # radians (measured: 5e-7, 6.5e-5)
            bad.append((m.name, "directions", np.median(ang), ang.max()))
        wo_g = smp[:, :3].astype(np.float64)
        pdf_at = m._pdf_block(w64, wo_g, (len(wi),))
        f_at = reference_f(m, wi, smp[:, :3])
        ok = (pdf_at > 0) & (wo_g[:, 2] > 1e-12)
        want_w = np.where(ok[:, None], f_at * (wo_g[:, 2] / np.where(ok, pdf_at, 1.0))[:, None], 0.0)
        if relative_errors(smp[:, 3], np.where(ok, pdf_at, 0.0)).max() > RTOL \
                or relative_errors(wgt[:, :3], want_w).max() > RTOL:
            bad.append((m.name, "weight/pdf of the sample",
                        relative_errors(smp[:, 3], np.where(ok, pdf_at, 0.0)).max(),
                        relative_errors(wgt[:, :3], want_w).max()))
    assert bad == []


def _frame(angles):
    a, b, c = angles
    ca, sa, cb, sb, cc, sc = math.cos(a), math.sin(a), math.cos(b), math.sin(b), math.cos(c), math.sin(c)
    rz = np.array([[ca, -sa, 0], [sa, ca, 0], [0, 0, 1]])
    ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
    rx = np.array([[1, 0, 0], [0, cc, -sc], [0, sc, cc]])
    r = rz @ ry @ rx
    return r[:, 0], r[:, 1], r[:, 2]  # X, Y, N


BRDF_MAIN = "outColor = vec4(BRDF(a.xyz, b.xyz, frameN, frameX, frameY), 1.0);"


def brdf_job(text, x, y, n):
    parsed = brdf_file.parse(text)
    code = (brdf_file.uniforms(parsed) + "uniform vec3 frameN;\nuniform vec3 frameX;\nuniform vec3 frameY;\n"
            + parsed["sections"]["shader"] + parsed["sections"].get("isFunc", ""))
    uni = brdf_file.defaults(parsed)
    uni.update(frameN=[float(v) for v in n], frameX=[float(v) for v in x], frameY=[float(v) for v in y])
    return (code, BRDF_MAIN), uni


def test_brdf_files_agree_with_numpy_through_the_explorer_signature(browser):
    """Each model's .brdf file, read as BRDF Explorer reads it (uniforms from the
    parameter block at their defaults), through BRDF(L, V, N, X, Y) with a
    rotated frame; the reference is NumPy at the pair's coordinates in that frame."""
    wi, wo = direction_pairs(seed=5, n=8192)
    keep = (np.minimum(wi[:, 2], wo[:, 2]) > 0.01) | (wo[:, 2] < 0)  # float32 projection noise at grazing
    wi, wo = wi[keep][:4096], wo[keep][:4096]
    x, y, n = (v.astype(np.float32) for v in _frame((0.7, -1.1, 2.3)))
    frame = np.stack([x, y, n]).astype(np.float64)
    to_world = lambda w: (w.astype(np.float64) @ frame).astype(np.float32)  # noqa: E731
    lw, vw = to_world(wi), to_world(wo)
    browser.set_inputs([lw, vw])
    models = [plausible.make(nm) for nm in plausible.names()] + [plausible.make("modified-phong", n=1e4)] + [
        plausible.make(nm, fresnel="conductor", eta=[0.2, 0.9, 1.1], k=[3.9, 2.4, 2.2])   # eta_r, k_g, ... sliders
        for nm in ("cook-torrance", "neumann-metal")]
    res = browser.run([brdf_job(to_brdf(m), x, y, n) for m in models])
    refs = []
    for m in models:
        li = lw.astype(np.float64) @ frame.T  # (L.X, L.Y, L.N) in float64
        vi = vw.astype(np.float64) @ frame.T
        r = m._eval_block(li, vi, (len(li),))
        refs.append(np.broadcast_to(r[:, None] if r.ndim == 1 else r, (len(li), 3)))
    assert worst([m.name for m in models], res, refs) == []


def test_two_prefixed_exports_in_one_shader_agree_with_numpy(browser, pairs):
    """Ashikhmin-Shirley (uniforms, prefix 'as') and Lafortune (baked, prefix 'laf')
    in one fragment shader, sharing the guarded helpers: each equals NumPy."""
    wi, wo = pairs
    m_as = plausible.make("ashikhmin-shirley", nu=20.0, nv=400.0)
    m_laf = plausible.make("lafortune", lobes=[(-1, -1, 1, 1e3, 50.0), (0.5, 0.5, 1.0, 8.0, 0.2)], rd=0.1)
    a, b = to_glsl(m_as, uniforms=True, prefix="as"), to_glsl(m_laf, prefix="laf")
    code = a.text + b.text
    uni = {u.name: list(u.value) for u in a.uniforms}
    browser.set_inputs([wi, wo])
    got = browser.run([((code, f"outColor = vec4({p}_f(a.xyz, b.xyz), 1.0);"), uni) for p in ("as", "laf")])
    refs = [reference_f(m, wi, wo) for m in (m_as, m_laf)]
    assert worst(["as", "laf"], got, refs) == []


def test_a_resampled_table_in_a_brdf_file_stays_within_its_stated_error(browser):
    """A .brdf file whose albedo table was resampled (here the 93 values of the
    default pumped-up to at most 20) against NumPy with the full table: its
    error exceeds the float32 criterion (a different table) but stays within
    the interpolation error the file states (g = max(a(L), a(V)) divides f)."""
    import re

    m = plausible.make("pumped-up")
    text = to_brdf(m, table_limit=20)
    stated = float(re.search(r"interpolation error at most ([0-9.e+-]+)", text).group(1))
    wi, wo = direction_pairs(seed=5)
    x, y, n = (np.eye(3, dtype=np.float32)[k] for k in range(3))
    browser.set_inputs([wi, wo])
    got, = browser.run([brdf_job(text, x, y, n)])
    err = relative_errors(got[:, :3], reference_f(m, wi, wo)).max()
    assert RTOL < err <= stated + RTOL
