"""The fuzzer on the Dr.Jit path: every plugin in float32 (``llvm_ad_rgb``), in
batches of 4096 (the vectorised code path, where float32 denormals are flushed
to zero), with the directions, uniforms and weight bounds of tests/fuzzing.py;
plus the cases of issue 21 that it found (fireflies from the Ashikhmin-Shirley
plugin at grazing incidence, NaN at cos 1e-10, a NaN direction at u1 = 1).

Independent truths: the float64 NumPy path (the same model, another precision
and another array library), the quadrature albedo, and the analytic weight bounds.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from mi_helpers import PLUGIN_MODELS, dr, interaction, mi, spectrum_np, to_dict, vec3

import plausible
from fuzzing import direction_pairs, incidences, random_params, uniforms, weight_bound
from plausible.analysis import albedo

BATCH = 4096
ONE_MINUS_F32 = 1.0 - 2.0 ** -24
#: the pair of issue 21 (a direction the plugin's own sampler returned), default parameters
ISSUE_WI = np.array([0.93742257, 0.34819373, 1e-4])
ISSUE_WO = np.array([-0.93742228, -0.3481946, 2.6012349e-06])


def f32(a):
    """``a`` rounded to float32 and back (the directions the plugin sees)."""
    return np.asarray(a, dtype=np.float32).astype(np.float64)


def pad(a, rng):
    """``a`` (n, 3) padded to :data:`BATCH` rows with random upper directions."""
    extra = rng.normal(size=(BATCH - len(a), 3))
    extra[:, 2] = np.abs(extra[:, 2])
    extra /= np.linalg.norm(extra, axis=1, keepdims=True)
    return np.concatenate([a, extra])[:BATCH]


def plugin_eval_pdf(b, wi, wo):
    ctx, si = mi.BSDFContext(), interaction(wi)
    return spectrum_np(b.eval(ctx, si, vec3(wo))), np.array(b.pdf(ctx, si, vec3(wo)), dtype=np.float64)


def plugin_sample(b, wi, u):
    ctx, si = mi.BSDFContext(), interaction(wi)
    u32 = np.asarray(u, dtype=np.float32)
    bs, w = b.sample(ctx, si, mi.Float(u32[:, 0]), mi.Point2f(mi.Float(u32[:, 1]), mi.Float(u32[:, 2])))
    wo = np.array(bs.wo, dtype=np.float64).T
    return wo, spectrum_np(w), np.array(bs.pdf, dtype=np.float64)


def fuzz_plugin(plugin, params, rng):
    """Run the fuzzer on ``plugin`` with ``params``; return the problems found."""
    b = mi.load_dict(to_dict(plugin, params))
    problems = []
    wi, wo = direction_pairs(rng, n_random=0)
    wi, wo = f32(pad(wi, rng)), f32(pad(wo, rng))
    e, p = plugin_eval_pdf(b, wi, wo)
    for what, v in (("eval", e), ("pdf", p)):
        bad = ~np.isfinite(v) | (v < 0)
        if np.any(bad):
            problems.append(f"{what}: {np.mean(bad):.3%} NaN/inf/negative")
    wi = f32(incidences(rng, BATCH))
    wo, w, pdf = plugin_sample(b, wi, uniforms(rng, BATCH, ONE_MINUS_F32))
    w = w.max(axis=-1)
    for what, v in (("weight", w), ("sample pdf", pdf), ("wo", wo)):
        if not np.all(np.isfinite(v) & (v >= 0 if what != "wo" else True)):
            problems.append(f"{what}: non-finite or negative values")
    again = plugin_eval_pdf(b, wi, wo)[1]
    valid = pdf > 0
    rel = np.abs(again - pdf)[valid] / (np.maximum(again, pdf)[valid] + 1e-2)
    if rel.size and np.max(rel) > 1e-4:
        problems.append(f"sample pdf != pdf(): max rel. difference {np.max(rel):.3g}")
    up = wi[:, 2] > 0
    bound = np.full(BATCH, np.inf)
    wb = weight_bound(b.model, wi[up] / np.linalg.norm(wi[up], axis=1, keepdims=True))
    if wb is not None:
        bound[up] = wb
    over = w > bound * (1 + 1e-3) + 1e-6
    if np.any(over):
        k = np.argwhere(over)[0][0]
        problems.append(f"weight {w[k]} > bound {bound[k]} at wi={wi[k].tolist()} ({np.sum(over)} samples)")
    return problems


def plugin_cases(n_random, seed=5):
    rng = np.random.default_rng(seed)
    out = []
    for plugin, name in sorted(PLUGIN_MODELS.items()):
        out.append(pytest.param(plugin, {}, id=f"{plugin}-default"))
        if name != "pumped-up":  # a new base's table takes minutes
            out += [pytest.param(plugin, random_params(name, rng, grey=True), id=f"{plugin}-random{i}")
                    for i in range(n_random)]
    return out


@pytest.mark.parametrize("plugin, params", plugin_cases(1))
def test_fuzz_plugin_float32_quick(plugin, params):
    assert fuzz_plugin(plugin, params, np.random.default_rng(len(plugin))) == [], params


@pytest.mark.slow
@pytest.mark.parametrize("plugin, params", plugin_cases(12, seed=11))
def test_fuzz_plugin_float32_long(plugin, params):
    rng = np.random.default_rng(3)
    for _ in range(8):
        assert fuzz_plugin(plugin, params, rng) == [], params


def test_fuzzer_finds_a_pdf_that_loses_its_specular_part():
    """A plugin whose pdf is the diffuse part alone (what float32 cancellation in
    wi.h did to the A-S pdf at grazing incidence) breaks the weight bound."""
    from plausible.models import ashikhmin_shirley as AS

    b = mi.load_dict({"type": "ashikhmin_shirley"})
    orig = type(b.model).lobe_weights
    try:
        # the mixture's weights with the specular share zeroed: pdf = the diffuse lobe's
        type(b.model).lobe_weights = lambda self, ops, wi, q: (0.0 * orig(self, ops, wi, q)[0],
                                                               AS.lobe_probabilities(ops, wi[2], q.rs, q.rd)[1])
        assert any("> bound" in p for p in fuzz_plugin("ashikhmin_shirley", {}, np.random.default_rng(0)))
    finally:
        type(b.model).lobe_weights = orig


# -- the cases of issue 21 -------------------------------------------------------

def test_ashikhmin_shirley_pdf_keeps_its_specular_part_at_grazing_incidence():
    """Issue 21's pair: the plugin's pdf was 9.8e-11 (its specular part lost to
    cancellation in wi.h) against 78013 on the float64 path; eval 2029."""
    b = mi.load_dict({"type": "ashikhmin_shirley"})
    m = plausible.make("ashikhmin-shirley")
    wi, wo = f32(ISSUE_WI)[None], f32(ISSUE_WO)[None]
    e, p = plugin_eval_pdf(b, wi, wo)
    wo_u = wo / np.linalg.norm(wo)
    assert p[0] == pytest.approx(m.pdf(wi, wo_u)[0], rel=1e-2)
    assert e[0, 0] == pytest.approx(m.eval(wi, wo_u)[0] * wo_u[0, 2], rel=1e-2)


def test_ashikhmin_shirley_mean_weight_at_grazing_incidence_is_the_albedo():
    """Mean sample weight at cos(theta) = 1e-4 was 1.7e9 in the plugin; it is the
    directional albedo (quadrature, float64), within 5 standard errors."""
    b = mi.load_dict({"type": "ashikhmin_shirley"})
    wi1 = f32(np.array([0.93742257, 0.34819373, 0.0]) * math.sqrt(1 - 1e-8) / math.hypot(0.93742257, 0.34819373)
              + [0, 0, 1e-4])
    n = 1 << 16
    _, w, _ = plugin_sample(b, np.tile(wi1, (n, 1)), np.random.default_rng(2).random((n, 3)))
    w = w.mean(axis=-1)
    ref = float(albedo(plausible.make("ashikhmin-shirley"), wi1).value)
    assert abs(w.mean() - ref) <= 5 * w.std() / math.sqrt(n) + 1e-4
    assert w.max() <= 1.2


@pytest.mark.parametrize("params", [{"type": "cook_torrance"}, {"type": "ward", "variant": "balanced"},
                                    {"type": "pumped_up"}])
def test_no_nan_at_cos_1e_10_in_batches_of_4096(params):
    """92 % NaN for cook_torrance with both directions at cos 1e-10 (hz^4 flushed to
    zero, then 0/0); the values agree with the float64 path."""
    rng = np.random.default_rng(8)
    b = mi.load_dict(params)
    phi = rng.uniform(0, 2 * math.pi, (2, BATCH))
    c, s = 1e-10, math.sqrt(1 - 1e-20)
    wi = f32(np.stack([s * np.cos(phi[0]), s * np.sin(phi[0]), np.full(BATCH, c)], -1))
    wo = f32(np.stack([s * np.cos(phi[1]), s * np.sin(phi[1]), np.full(BATCH, c)], -1))
    e, p = plugin_eval_pdf(b, wi, wo)
    assert np.all(np.isfinite(e)) and np.all(np.isfinite(p))
    want = b.model.eval(wi, wo) * c
    np.testing.assert_allclose(e.mean(axis=-1), want.mean(axis=-1) if want.ndim > 1 else want,
                               rtol=1e-2, atol=1e-6 * max(1.0, np.max(want)))


@pytest.mark.parametrize("plugin", ["ward", "cook_torrance"])
def test_beckmann_sample_at_u1_equal_to_one_is_a_direction(plugin):
    """sample2.x = 1.0 gave a NaN direction (tan^2 = inf); the half vector is on the
    horizon, so wo = reflect(wi, h) = (-wi_x.., -wi_z) lies below it: weight and pdf 0."""
    b = mi.load_dict({"type": plugin})
    wi = np.tile([0.6, 0.0, 0.8], (BATCH, 1))
    u = np.column_stack([np.full(BATCH, 0.25), np.ones(BATCH), np.linspace(0, 0.99, BATCH)])
    wo, w, pdf = plugin_sample(b, wi, u)
    assert np.all(np.isfinite(wo)) and np.all(np.isfinite(w)) and np.all(np.isfinite(pdf))
    np.testing.assert_allclose(wo[:, 2], -0.8, atol=1e-6)
    assert np.all(w == 0) and np.all(pdf == 0)


@pytest.mark.parametrize("params", [{"fresnel": "none", "rs": 0.0, "eta": 72.43, "k": 22.60},
                                    {"fresnel": "none", "rs": 0.0, "eta": 1.46, "k": 0.0}])
def test_kulla_conty_of_no_albedo_has_the_floor_mixture_pdf_in_float32(params):
    """The long fuzzer's kulla_conty-random0/3: with ``rs = 0`` both shares of the sampling
    mixture are 0, and the guard ``max(total, 1e-300)`` is 0 in float32: 0/0 made 98.5 % of the
    pdf NaN.  Truths: the share of no albedo is 0, floored at MIX_FLOOR, so the pdf is the closed
    mixture ``MIX_FLOOR cos/pi + (1 - MIX_FLOOR) pdf_base`` of the base's float64 NumPy pdf, and
    the float64 NumPy model's pdf; the sampled pdf equals pdf()."""
    from plausible.models.kulla_conty import MIX_FLOOR
    from mi_helpers import upper_dirs

    rng = np.random.default_rng(4)
    b = mi.load_dict(to_dict("kulla_conty", params))
    m = b.model
    wi, wo = upper_dirs(rng, BATCH, zmin=1e-3), upper_dirs(rng, BATCH, zmin=1e-3)
    e, p = plugin_eval_pdf(b, wi, wo)
    assert np.all(np.isfinite(e)) and np.all(np.isfinite(p))
    want = MIX_FLOOR * wo[:, 2] / math.pi + (1.0 - MIX_FLOOR) * m.base.pdf(wi, wo)
    np.testing.assert_allclose(m.pdf(wi, wo), want, rtol=1e-12)
    np.testing.assert_allclose(p, want, rtol=1e-5)
    ws, w, spdf = plugin_sample(b, wi, rng.random((BATCH, 3)))
    assert np.all(np.isfinite(w)) and np.all(np.isfinite(spdf))
    np.testing.assert_allclose(spdf, plugin_eval_pdf(b, wi, ws)[1], rtol=1e-4, atol=1e-6)
