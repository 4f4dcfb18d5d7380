"""Every parameter in mi.traverse (issue 19): continuous ones differentiable,
choices / integers / structured ones not; params.update() changes the rendering
with the same validation as at load, and keeps the old values when it refuses."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import ON_CUDA, PLUGIN_MODELS, interaction, mi, spectrum_np, upper_dirs, vec3

import plausible

pytestmark = pytest.mark.drjit

PLUGIN_LIST = sorted(PLUGIN_MODELS)
F = mi.ParamFlags


def differentiable(params, key) -> bool:
    """Mitsuba's Differentiable flag is the absence of NonDifferentiable (value 0)."""
    return not params.properties[key][3] & F.NonDifferentiable


def eval_np(bsdf, wi, wo):
    return spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))


def dirs(seed=4, n=64):
    rng = np.random.default_rng(seed)
    return upper_dirs(rng, n, 0.2), upper_dirs(rng, n, 0.2)


def model_eval(model, wi, wo):
    """The NumPy model's ``f(wo, wi) cos(theta_o)`` (Radiance mode), three channels."""
    f = model.eval(wo, wi)
    f = f if f.ndim == 2 else f[:, None]
    return f * wo[:, 2:3] * np.ones((1, 3))


@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_every_parameter_is_traversed_with_its_flags(plugin):
    """Each parameter (but a nested model spec, a string) appears under its own
    name: continuous ones Differentiable, choices / integers / structured ones
    NonDifferentiable; derived defaults (neumann's c) are not separate parameters."""
    info = plausible.info(PLUGIN_MODELS[plugin])
    params = mi.traverse(mi.load_dict({"type": plugin}))
    for prm in info.params:
        if prm.kind == "model" or prm.default is None:
            assert prm.name not in params
            continue
        diff = prm.kind in ("scalar", "color") and not prm.integer
        assert differentiable(params, prm.name) == diff, prm.name


def _new_value(prm):
    """A valid value for ``prm`` other than its default."""
    for v in prm.extremes:
        if not isinstance(v, (tuple, list, str)) and v != prm.default:
            return float(v)
    return 0.5 * float(prm.default)


@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_update_of_each_continuous_parameter_changes_eval(plugin):
    """params[k] = v; params.update(): eval equals the NumPy model built with k = v,
    one continuous parameter at a time (float32 tolerance)."""
    name = PLUGIN_MODELS[plugin]
    info = plausible.info(name)
    bsdf = mi.load_dict({"type": plugin})
    params = mi.traverse(bsdf)
    wi, wo = dirs()
    changed = 0
    for prm in info.params:
        if prm.name not in params or not differentiable(params, prm.name):
            continue
        v = _new_value(prm)
        params[prm.name] = mi.Float(v)
        params.update()
        want = model_eval(plausible.make(name, **{prm.name: v}), wi, wo)
        # CUDA: approximate division leaves 2.8e-17 where the value is 0 (low_smooth, on an H200)
        np.testing.assert_allclose(eval_np(bsdf, wi, wo), want, rtol=2e-4,
                                   atol=max(2e-4 * np.max(np.abs(want)), 1e-15 if ON_CUDA else 0.0),
                                   err_msg=prm.name)
        params[prm.name] = mi.Float(prm.default)
        params.update()
        changed += 1
    assert changed >= 1


def test_update_of_a_choice_takes_its_index():
    """Ward's variant, a choice, is the index into its choices."""
    bsdf = mi.load_dict({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3})
    params = mi.traverse(bsdf)
    choices = plausible.info("ward").param("variant").choices
    params["variant"] = mi.UInt32(choices.index("balanced"))
    params.update()
    assert bsdf.model.params["variant"] == "balanced"
    wi, wo = dirs()
    want = model_eval(plausible.make("ward", alpha_x=0.2, alpha_y=0.3, variant="balanced"), wi, wo)
    np.testing.assert_allclose(eval_np(bsdf, wi, wo), want, rtol=2e-4, atol=1e-6)


@pytest.mark.parametrize("key,value,match", [
    ("n", -1.0, "parameter 'n' must lie in"),
    ("kd", 0.9, "'kd' \\+ 'ks' must not exceed 1"),
])
def test_update_refuses_what_load_refuses_and_keeps_the_old_values(key, value, match):
    bsdf = mi.load_dict({"type": "modified_phong", "kd": 0.5, "ks": 0.2, "n": 30.0})
    wi, wo = dirs()
    before = eval_np(bsdf, wi, wo)
    params = mi.traverse(bsdf)
    params[key] = mi.Float(value)
    with pytest.raises(ValueError, match=match + ".*previous values are kept"):
        params.update()
    np.testing.assert_array_equal(eval_np(bsdf, wi, wo), before)
    assert np.array(params[key])[0] == np.float32({"n": 30.0, "kd": 0.5}[key])


def test_update_of_texture_data_is_checked():
    """A bitmap nu edited through traverse to hold a NaN texel is refused (one outside
    the range is clamped with a warning: tests/mitsuba/test_texture_ranges.py)."""
    data = np.full((2, 2, 1), 20.0, dtype=np.float32)
    bsdf = mi.load_dict({"type": "ashikhmin_shirley",
                         "nu": {"type": "bitmap", "data": mi.TensorXf(data), "raw": True}})
    params = mi.traverse(bsdf)
    data[0, 1, 0] = np.nan
    params["nu.data"] = mi.TensorXf(data)
    with pytest.raises(ValueError, match="parameter 'nu' must lie in .*1 texel.* not a number.*clamped"):
        params.update()
    assert bsdf.state.known["nu"] is False


def test_update_of_n_recomputes_the_derived_normalisation():
    """neumann_metal's c defaults to (n + 2) / (2 pi): after n changes, eval equals
    the NumPy model with the new n and its own default c."""
    bsdf = mi.load_dict({"type": "neumann_metal", "n": 40.0})
    params = mi.traverse(bsdf)
    params["n"] = mi.Float(10.0)
    params.update()
    wi, wo = dirs()
    want = model_eval(plausible.make("neumann-metal", n=10.0), wi, wo)
    np.testing.assert_allclose(eval_np(bsdf, wi, wo), want, rtol=2e-4, atol=1e-6)


def test_update_of_fresnel_rebuilds_the_pumped_up_model():
    """pumped_up's choice 'fresnel' none -> schlick (the same albedo table, so quick):
    eval equals the NumPy model with Schlick's factor, R0 = rs = 0.5."""
    base = "reciprocal-phong:ks=1:n=20"
    bsdf = mi.load_dict({"type": "pumped_up", "base": base, "rs": 0.5})
    params = mi.traverse(bsdf)
    choices = plausible.info("pumped-up").param("fresnel").choices
    params["fresnel"] = mi.UInt32(choices.index("schlick"))
    params.update()
    wi, wo = dirs()
    want = model_eval(plausible.make("pumped-up", base=base, rs=0.5, fresnel="schlick"), wi, wo)
    assert not np.allclose(want, model_eval(plausible.make("pumped-up", base=base, rs=0.5), wi, wo))
    np.testing.assert_allclose(eval_np(bsdf, wi, wo), want, rtol=2e-4, atol=1e-5)


@pytest.mark.slow
def test_update_of_times_rebuilds_the_pumped_up_tables():
    """pumped_up's integer 'times' (non-differentiable): 1 -> 2 rebuilds the albedo
    tables; eval equals the NumPy model pumped twice.  Slow without a table cache
    (about 45 s on 2 busy cores: a new albedo table is integrated)."""
    base = "reciprocal-phong:ks=1:n=20"
    bsdf = mi.load_dict({"type": "pumped_up", "base": base})
    params = mi.traverse(bsdf)
    params["times"] = mi.UInt32(2)
    params.update()
    assert len(bsdf.model.tables) == 2
    wi, wo = dirs()
    want = model_eval(plausible.make("pumped-up", base=base, times=2), wi, wo)
    np.testing.assert_allclose(eval_np(bsdf, wi, wo), want, rtol=2e-4, atol=1e-5)
