"""The plausible_material plugin: a published fit rendered through the generic plugin."""

import numpy as np
import pytest

from mi_helpers import dr, interaction, mi, spectrum_np, upper_dirs, vec3  # noqa: F401 (sets the variant)

import plausible


def test_plugin_eval_and_pdf_equal_the_library_model(rng):
    bsdf = mi.load_dict({"type": "plausible_material", "name": "gold-metallic-paint", "fit": "ngan2005/ward"})
    model = plausible.material("gold-metallic-paint", "ngan2005/ward")
    wi, wo = upper_dirs(rng, 256), upper_dirs(rng, 256)
    ctx = mi.BSDFContext()
    got = spectrum_np(bsdf.eval(ctx, interaction(wi), vec3(wo)))
    # Radiance mode: plausible's wi (toward the light) is Mitsuba's wo; the fit is reciprocal anyway
    want = model.eval(wo, wi) * wo[:, 2:3]
    np.testing.assert_allclose(got, want, rtol=2e-4, atol=1e-6)
    np.testing.assert_allclose(np.array(bsdf.pdf(ctx, interaction(wi), vec3(wo))), model.pdf(wi, wo),
                               rtol=2e-4, atol=1e-6)


def test_furnace_pixel_is_the_directional_albedo():
    """One bounce in a unit constant environment: the mean of many samples at
    normal incidence is the albedo plausible integrates."""
    bsdf = mi.load_dict({"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/cook-torrance"})
    n = 200_000
    si = interaction(np.tile([[0.0, 0.0, 1.0]], (n, 1)))
    s = mi.PCG32(n)
    _, w = bsdf.sample(mi.BSDFContext(), si, s.next_float32(), mi.Point2f(s.next_float32(), s.next_float32()))
    a = plausible.albedo(plausible.material("alum-bronze", "ngan2005/cook-torrance"), [0, 0, 1]).value
    np.testing.assert_allclose(spectrum_np(w).mean(axis=0), a, rtol=0.02)


def test_unknown_material_names_the_closest_ones():
    with pytest.raises(Exception, match="did you mean alum-bronze"):
        mi.load_dict({"type": "plausible_material", "name": "alum-bronz"})


def test_an_unknown_fit_is_refused_naming_the_fits():
    with pytest.raises(Exception, match="ngan2005/ward"):
        mi.load_dict({"type": "plausible_material", "name": "nickel", "fit": "ngan2005/hee"})
