"""Textured parameters are range-checked (issue 19): bitmap and checkerboard
textures at load from their data (out of range: clamped with a warning, issue 43),
cross-parameter constraints at every texel,
textures of unknown range clamped per shading point; every alias of every
plugin sets the parameter it names."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mi_helpers import PLUGIN_MODELS, interaction, mi, spectrum_np, upper_dirs, vec3

import plausible
import plausible.mitsuba as pm
from plausible.mitsuba import props as P

pytestmark = pytest.mark.drjit

#: Mitsuba's loader re-raises a plugin's ValueError as a RuntimeError with the same text
LOAD_ERRORS = (RuntimeError, ValueError)


def checker(a, b):
    return {"type": "checkerboard", "color0": a, "color1": b}


def bitmap(values):
    """A nearest-filtered raw bitmap of shape (h, w, channels)."""
    arr = np.asarray(values, dtype=np.float32)
    return {"type": "bitmap", "data": mi.TensorXf(arr), "raw": True, "filter_type": "nearest"}


class Ramp(mi.Texture):
    """A texture whose range cannot be read: lo + (hi - lo) u."""

    def __init__(self, props):
        mi.Texture.__init__(self, props)
        self.lo, self.hi = props.get("lo", 0.0), props.get("hi", 1.0)

    def eval(self, si, active=True):
        return mi.Color3f(self.lo + (self.hi - self.lo) * si.uv.x)

    def mean(self):
        return 0.5 * (self.lo + self.hi)

    def is_spatially_varying(self):
        return True

    def to_string(self):
        return "Ramp[]"


mi.register_texture("plausible_test_ramp", lambda props: Ramp(props))


@pytest.mark.parametrize("plugin,name,tex,bad", [
    ("ashikhmin_shirley", "nu", checker(-5.0, 10.0), "-5"),
    ("ashikhmin_shirley", "nv", bitmap([[[10.0], [-10.0]], [[20.0], [30.0]]]), "-10"),
    ("ward", "alpha_x", bitmap([[[0.2], [-0.1]]]), "-0.1"),
    ("reciprocal_phong", "n", checker(10.0, 2e6), "2e\\+06"),
    ("modified_phong", "kd", bitmap([[[0.1, 0.2, 1.5]], [[0.1, 0.2, 0.3]]]), "1.5"),
])
def test_out_of_range_texels_are_clamped_with_a_warning(plugin, name, tex, bad):
    """As Mitsuba (issue 43; refused before): the texture loads, is clamped per shading
    point (not known), and the one warning names the plugin, the parameter, its range and
    the texel value."""
    b = mi.load_dict({"type": plugin, name: tex})
    assert b.state.known[name] is False and len(b.state.warnings) == 1
    assert re.search(f"{plugin}: parameter '{name}' must lie in .*values from .*{bad}", b.state.warnings[0])


def test_in_range_textures_load_and_are_known():
    """The same textures with valid texels load, and their range counts as known
    (so they are not clamped at eval)."""
    b = mi.load_dict({"type": "ashikhmin_shirley", "nu": checker(5.0, 10.0),
                      "nv": bitmap([[[10.0], [100.0]]])})
    assert b.state.known == {"nu": True, "nv": True}


def test_texels_read_from_a_bitmap_and_a_checkerboard():
    """texture_texels returns every texel (bitmap data row by row; checkerboard's
    two colours)."""
    data = np.arange(12, dtype=np.float32).reshape(2, 2, 3)
    got = P.texture_texels(mi, mi.load_dict(bitmap(data)))
    np.testing.assert_array_equal(got, data.reshape(4, 3))
    got = P.texture_texels(mi, mi.load_dict(checker({"type": "rgb", "value": [0.1, 0.2, 0.3]}, 0.9)))
    np.testing.assert_allclose(got, [[0.1, 0.2, 0.3], [0.9, 0.9, 0.9]], rtol=1e-6)
    assert P.texture_texels(mi, mi.load_dict({"type": "plausible_test_ramp"})) is None


def test_kd_plus_ks_is_checked_at_every_texel():
    """Modified Phong: a kd checkerboard (0.1 | 0.9) with ks = 0.5 breaks kd + ks <= 1
    on half the surface (its mean 0.5 does not): refused, naming the point and kd."""
    with pytest.raises(LOAD_ERRORS, match=r"modified_phong: .* uv = .* kd=\[0\.9.*'kd' \+ 'ks' must not exceed 1"):
        mi.load_dict({"type": "modified_phong", "kd": checker(0.1, 0.9), "ks": 0.5})


def test_kd_plus_ks_is_checked_pointwise_not_on_the_extremes():
    """Complementary checkerboards kd (0.1 | 0.9), ks (0.9 | 0.1) have kd + ks = 1
    everywhere although max kd + max ks = 1.8: they load."""
    b = mi.load_dict({"type": "modified_phong", "kd": checker(0.1, 0.9), "ks": checker(0.9, 0.1)})
    assert b.flags() & mi.BSDFFlags.SpatiallyVarying


def test_a_texture_of_unknown_range_is_clamped_per_shading_point():
    """reciprocal_phong with n from a ramp texture -10 .. 50 (not readable): at
    u = 0.05 (n = -7) eval equals the model with n = 0 (the range's lower end)."""
    b = mi.load_dict({"type": "reciprocal_phong", "ks": 0.8,
                      "n": {"type": "plausible_test_ramp", "lo": -10.0, "hi": 50.0}})
    assert b.state.known == {"n": False}
    rng = np.random.default_rng(2)
    wi, wo = upper_dirs(rng, 32, 0.2), upper_dirs(rng, 32, 0.2)
    for u, n in [(0.05, 0.0), (0.5, 20.0)]:
        si = interaction(wi)
        si.uv = mi.Point2f(u, 0.5)
        got = spectrum_np(b.eval(mi.BSDFContext(), si, vec3(wo)))[:, 0]
        want = plausible.make("reciprocal-phong", ks=0.8, n=n).eval(wo, wi) * wo[:, 2]
        np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-6)
    assert np.all(np.isfinite(got))


def _alias_value(prm):
    """A valid value for ``prm`` that differs from its default."""
    for v in prm.extremes:
        if not isinstance(v, (tuple, list, str)) and v != prm.default:
            return float(v)
    return 0.5 * float(prm.default)


ALIASES = sorted((plugin, alias) for plugin, model in PLUGIN_MODELS.items()
                 for alias in pm.aliases_for(plugin, plausible.info(model)))


def test_every_plugin_with_diffuse_or_specular_terms_has_aliases():
    """The alias table is not empty where Mitsuba names exist (teeth for the test below)."""
    assert ("ward", "alpha") in ALIASES and ("phong", "exponent") in ALIASES
    assert ("cook_torrance", "roughness") in ALIASES and len(ALIASES) > 20


@pytest.mark.parametrize("plugin,alias", ALIASES)
def test_every_alias_sets_its_parameter(plugin, alias):
    """Loading with the alias gives the model the value under the native name(s),
    and the same eval as loading with the native name(s)."""
    info = plausible.info(PLUGIN_MODELS[plugin])
    target = pm.aliases_for(plugin, info)[alias]
    targets = target if isinstance(target, tuple) else (target,)
    value = _alias_value(info.param(targets[0]))
    a = mi.load_dict({"type": plugin, alias: value})
    b = mi.load_dict({"type": plugin, **{t: value for t in targets}})
    for t in targets:
        assert a.model.params[t] == value != info.param(t).default
    rng = np.random.default_rng(1)
    wi, wo = upper_dirs(rng, 16, 0.2), upper_dirs(rng, 16, 0.2)
    ea = spectrum_np(a.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))
    eb = spectrum_np(b.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))
    np.testing.assert_array_equal(ea, eb)


def test_ward_alpha_is_isotropic_roughness():
    """Mitsuba's isotropic 'alpha' sets both of Ward's slopes; giving it with
    alpha_x as well is refused as a repeat."""
    b = mi.load_dict({"type": "ward", "alpha": 0.3})
    assert b.model.params["alpha_x"] == b.model.params["alpha_y"] == 0.3
    assert not b.flags() & mi.BSDFFlags.Anisotropic
    with pytest.raises(LOAD_ERRORS, match="'alpha_x' given twice"):
        mi.load_dict({"type": "ward", "alpha": 0.3, "alpha_x": 0.2})


@pytest.mark.parametrize("plugin,name,choices", [
    ("neumann_metal", "fresnel", "{none, schlick, conductor}"),
    ("pumped_up", "correction", "{max, controlled, controlled-product, controlled-stepwise}"),
])
def test_a_texture_on_a_choice_parameter_is_refused_in_one_line(plugin, name, choices):
    """A texture where a choice is expected: the message's last line (what Mitsuba shows)
    names the plugin, the parameter, the texture's class and ends with the allowed
    choices, not with the texture printed over many lines (issue 43: it ended in ']')."""
    with pytest.raises(LOAD_ERRORS) as err:
        mi.load_dict({"type": plugin, name: checker(0.2, 0.4)})
    last = str(err.value).strip().splitlines()[-1]
    assert f"{plugin}: parameter '{name}' takes no texture (got Checkerboard)" in last
    assert last.endswith(f"it must be {choices}")
