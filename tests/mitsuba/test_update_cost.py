"""What ``params.update()`` of a plugin costs, against a built-in's (issue 43): counted in
Python calls (``sys.setprofile``), not timed (the times are in docs/benchmarks.md,
``benchmarks/bench_inverse.py``); and what the fast path behind it still checks."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from mi_helpers import dr, interaction, mi, spectrum_np, upper_dirs, vec3

import plausible
from plausible.mitsuba import plugin as plugin_module

pytestmark = pytest.mark.drjit


def rgb(v):
    return {"type": "rgb", "value": v}


def update_calls(bsdf: dict, key: str) -> int:
    """Python calls (functions and builtins) of the third ``params.update()`` after
    ``params[key]`` was scaled (0.9, then 1.05, then 0.9 again)."""
    params = mi.traverse(mi.load_dict(bsdf))
    for scale in (0.9, 1.05, 0.9):
        params[key] = params[key] * scale
        count = [0]

        def profile(frame, event, arg):
            if event in ("call", "c_call"):
                count[0] += 1

        sys.setprofile(profile)
        try:
            params.update()
        finally:
            sys.setprofile(None)
    return count[0]


#: (plugin dict, key scaled, the built-in and key it is held against)
COLOUR = ({"type": "roughplastic", "diffuse_reflectance": rgb([0.5, 0.4, 0.3])}, "diffuse_reflectance.value")
NUMBER = ({"type": "roughconductor", "alpha": 0.2}, "alpha.value")
CASES = [({"type": "ashikhmin_shirley", "rs": rgb([0.2, 0.3, 0.25]), "rd": rgb([0.5, 0.4, 0.3])}, "rs.value", COLOUR),
         ({"type": "modified_phong", "ks": rgb([0.2, 0.3, 0.25]), "kd": rgb([0.5, 0.4, 0.3])}, "kd.value", COLOUR),
         ({"type": "ward", "rs": rgb([0.2, 0.3, 0.25]), "rd": rgb([0.5, 0.4, 0.3])}, "rd.value", COLOUR),
         ({"type": "gltf_pbr", "base_color": rgb([0.2, 0.3, 0.25])}, "base_color.value", COLOUR),
         ({"type": "lambertian", "rd": rgb([0.5, 0.4, 0.3])}, "rd.value", COLOUR),
         ({"type": "ashikhmin_shirley", "nu": 10.0, "nv": 30.0}, "nu", NUMBER),
         ({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3}, "alpha_x", NUMBER),
         ({"type": "cook_torrance", "m": 0.2}, "m", NUMBER)]


# slow (make test-all): in the full parallel run (a clean clone, 5 December) one worker spun for over 7 minutes
# inside params.update() under sys.setprofile after the worker's earlier tests; alone it takes seconds.
@pytest.mark.slow
@pytest.mark.parametrize("bsdf,key,builtin", CASES, ids=[f"{c[0]['type']}-{c[1]}" for c in CASES])
def test_an_update_makes_at_most_twice_the_python_calls_of_a_builtin(bsdf, key, builtin):
    """A new <rgb> colour against roughplastic's colour, a new number against
    roughconductor's alpha (27 calls each, Mitsuba's own SceneParameters.update); the
    plugins made 322-1252 on 41fd504 (a NumPy model, mi.traverse of the texture, the checks)."""
    assert update_calls(bsdf, key) <= 2 * update_calls(*builtin)


def test_a_fast_update_builds_no_model_and_the_model_follows(monkeypatch):
    """An <rgb> update builds no NumPy model (the constructor is not called); the model,
    asked for afterwards, holds the new colour's mean."""
    bsdf = mi.load_dict({"type": "ashikhmin_shirley", "rs": rgb([0.2, 0.3, 0.25])})
    params = mi.traverse(bsdf)
    built = []
    original = plausible.bxdf.BxDF.__init__
    monkeypatch.setattr(plausible.bxdf.BxDF, "__init__", lambda self, **kw: built.append(1) or original(self, **kw))
    params["rs.value"] = mi.Color3f(0.1, 0.2, 0.6)
    params.update()
    assert built == []
    assert bsdf.model.params["rs"] == pytest.approx(0.3, rel=1e-6) and built == [1]


def test_after_fast_updates_eval_pdf_and_sample_match_the_numpy_model():
    """Both colours of Ashikhmin-Shirley and nu changed through the fast path: eval, pdf
    and the sampled directions equal the NumPy model of the new values (its sampling
    constants are the colours' channel means)."""
    bsdf = mi.load_dict({"type": "ashikhmin_shirley", "nu": 10.0, "nv": 40.0, "rs": rgb([0.2, 0.3, 0.25]),
                         "rd": rgb([0.5, 0.4, 0.3])})
    params = mi.traverse(bsdf)
    rs, rd = [0.05, 0.1, 0.4], [0.7, 0.2, 0.1]
    params["rs.value"], params["rd.value"], params["nu"] = mi.Color3f(rs), mi.Color3f(rd), mi.Float(25.0)
    params.update()
    assert bsdf.state.pending  # the fast path took them
    model = plausible.make("ashikhmin-shirley", nu=25.0, nv=40.0, rs=rs, rd=rd)
    rng = np.random.default_rng(5)
    wi, wo = upper_dirs(rng, 200, 0.1), upper_dirs(rng, 200, 0.1)
    ctx, si = mi.BSDFContext(), interaction(wi)
    f = spectrum_np(bsdf.eval(ctx, si, vec3(wo)))
    np.testing.assert_allclose(f, model.eval(wi, wo) * wo[:, 2:3], rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(np.array(bsdf.pdf(ctx, si, vec3(wo))), model.pdf(wi, wo), rtol=2e-4, atol=1e-6)
    u = rng.uniform(0.01, 0.99, (200, 3))
    bs, _ = bsdf.sample(ctx, si, mi.Float(u[:, 0]), mi.Point2f(np.ascontiguousarray(u[:, 1:].T)))
    want = model.sample(wi, u)
    ok = np.array(bs.pdf) > 0
    assert ok.sum() > 150
    np.testing.assert_allclose(np.array(bs.wo).T[ok], want.wo[ok], atol=2e-4)


@pytest.mark.parametrize("bsdf,key,value,match", [
    ({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3}, "alpha_x", mi.Float(-0.5), "'alpha_x' must lie in"),
    ({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3}, "alpha_x", mi.Float(float("nan")), "'alpha_x' must lie in"),
    ({"type": "modified_phong", "kd": rgb([0.3, 0.3, 0.3]), "ks": rgb([0.2, 0.2, 0.2])}, "kd.value",
     mi.Color3f(0.9, 0.9, 0.9), "'kd' \\+ 'ks' must not exceed 1"),
], ids=["below-range", "nan", "constraint"])
def test_the_fast_path_leaves_a_broken_value_to_the_full_check(bsdf, key, value, match):
    """Values the fast path must not take (out of range, NaN, a broken constraint between
    kd and ks) are refused with the model's message after a fast update."""
    b = mi.load_dict(bsdf)
    params = mi.traverse(b)
    params[key] = params[key] * 1.01
    params.update()
    assert b.state.pending  # that one went through the fast path
    params[key] = value
    with pytest.raises(ValueError, match=match):
        params.update()


def test_an_out_of_range_rgb_is_clamped_and_warned_not_taken_fast():
    """An <rgb> rd pushed above 1 goes to the full path: clamped per shading point, one warning."""
    b = mi.load_dict({"type": "lambertian", "rd": rgb([0.5, 0.4, 0.3])})
    params = mi.traverse(b)
    params["rd.value"] = mi.Color3f(1.5, 0.4, 0.3)
    params.update()
    assert b.state.known["rd"] is False and "1 of 1 texels" in b.state.warnings[-1]
    ctx, si = mi.BSDFContext(), interaction(np.array([[0.0, 0.0, 1.0]]))
    f = spectrum_np(b.eval(ctx, si, vec3(np.array([[0.0, 0.0, 1.0]]))))
    np.testing.assert_allclose(f[0], np.array([1.0, 0.4, 0.3]) / np.pi, rtol=1e-6)


def test_a_scalar_that_makes_the_model_anisotropic_sets_the_flag():
    """Ward at alpha_x = alpha_y is isotropic; alpha_x changed: the flag turns Anisotropic
    (the fast path does not take a scalar that can change it while the flag is off)."""
    b = mi.load_dict({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.2})
    assert not b.flags() & mi.BSDFFlags.Anisotropic
    params = mi.traverse(b)
    params["alpha_x"] = mi.Float(0.4)
    params.update()
    assert b.flags() & mi.BSDFFlags.Anisotropic


def test_isotropic_anywhere_is_false_for_an_anisotropic_model():
    """The load-time probe behind the fast path's flag rule: Cook-Torrance is isotropic at
    any m, Ashikhmin-Shirley at nu = nv is not at a generic point."""
    ct = mi.load_dict({"type": "cook_torrance", "m": 0.2}).state.fast
    asr = mi.load_dict({"type": "ashikhmin_shirley", "nu": 10.0, "nv": 10.0}).state.fast
    assert ct.iso_free and not asr.iso_free
    assert isinstance(ct, plugin_module.FastUpdate)
