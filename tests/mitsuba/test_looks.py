"""plausible.compare_looks: two BSDFs rendered side by side, against independent truths."""

import math

import numpy as np
import pytest

from mi_helpers import mi  # noqa: F401 (sets the variant)

import plausible
from plausible.mitsuba import looks as L
from plausible.registry import make_from_spec
from plausible.spectra import luminance

DIFFUSE_05 = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}}


def test_a_bsdf_against_itself_has_flip_0_and_ratio_1():
    looks = plausible.compare_looks("ward:alpha_x=0.2:alpha_y=0.2", make_from_spec("ward:alpha_x=0.2:alpha_y=0.2"))
    assert looks.flip == 0.0
    assert looks.highlight_ratios == (1.0,) * len(L.LIGHT_ANGLES)
    assert looks.ok and looks.warnings == []


def test_the_lambertian_plugin_and_mitsubas_diffuse_agree_to_the_noise():
    """Two implementations of one BRDF (plausible's plugin, Mitsuba's own): the point-light
    images have no noise but the pixel jitter, so the peaks agree to 1e-3 where the peak is
    inside the disc; at 150 deg it sits on the limb, in partly covered pixels (2 %).  FLIP is
    the environment's sampling noise (0.019 measured, 0.024 seed to seed for one BSDF)."""
    looks = plausible.compare_looks("lambertian:rd=0.5", DIFFUSE_05)
    np.testing.assert_allclose(looks.highlight_ratios[:3], 1.0, atol=1e-3)
    assert abs(looks.highlight_ratios[3] - 1.0) < 0.02
    assert looks.flip < 0.03
    assert looks.ok


def test_a_lambertian_scaled_by_k_has_highlight_ratio_k_and_is_flagged():
    up = plausible.compare_looks("lambertian:rd=0.2", {"type": "diffuse", "reflectance": 0.6})
    np.testing.assert_allclose(up.highlight_ratios, 3.0, rtol=1e-4)
    assert up.highlight_ratio == pytest.approx(3.0, rel=1e-4)
    assert [w.split(":")[0] for w in up.warnings] == ["highlight invented"]
    down = plausible.compare_looks({"type": "diffuse", "reflectance": 0.6}, "lambertian:rd=0.2")
    np.testing.assert_allclose(down.highlight_ratios, 1 / 3, rtol=1e-4)
    assert [w.split(":")[0] for w in down.warnings] == ["highlight lost"]


def _closed_form_peak(model, angle_deg, n=801):
    """max over the visible, lit sphere of luminance(f(l, v) cos(theta_l) E): the light along +z,
    the camera at ``angle_deg`` from it, the normals on a fine grid of the visible disc."""
    a = math.radians(angle_deg)
    v, light = np.array([math.sin(a), 0.0, math.cos(a)]), np.array([0.0, 0.0, 1.0])
    x = np.linspace(-1, 1, n)
    X, Y = np.meshgrid(x, x)
    ok = X ** 2 + Y ** 2 < 1
    X, Y = X[ok], Y[ok]
    right = np.cross([0.0, 1.0, 0.0], v)
    normals = X[:, None] * right + Y[:, None] * np.array([0.0, 1.0, 0.0]) + np.sqrt(1 - X ** 2 - Y ** 2)[:, None] * v
    t = np.cross(normals, [0.0, 1.0, 0.0])
    t /= np.linalg.norm(t, axis=1)[:, None]
    b = np.cross(normals, t)
    wi = np.stack([t @ light, b @ light, normals @ light], -1)
    wo = np.stack([t @ v, b @ v, normals @ v], -1)
    f = np.asarray(model.eval(wi, wo)).reshape(len(wi), -1)
    val = np.broadcast_to(f * np.maximum(wi[:, 2], 0.0)[:, None] * L.IRRADIANCE, (len(wi), 3))
    return float(luminance(val).max())


def test_the_rendered_peak_is_the_closed_form_max_of_f_cos():
    """A pixel is the mean radiance over its footprint, so the rendered peak is at most the
    maximum over the sphere and below it by the lobe's fall-off within half a pixel (128 px:
    1/61 of the radius): for n = 15, 0.2-0.5 % measured at 0-120 deg; at 150 deg the peak is
    near the limb, where the edge pixels are partly covered (0.7 % at 256 px, 2 % at 128)."""
    spec = "modified-phong:kd=0.2:ks=0.4:n=15"
    peaks = L.render_looks(spec, res=128).peaks()
    want = np.array([_closed_form_peak(make_from_spec(spec), a) for a in L.LIGHT_ANGLES])
    assert np.all(peaks <= want * (1 + 1e-3))
    np.testing.assert_allclose(peaks[:3], want[:3], rtol=0.01)
    np.testing.assert_allclose(peaks[3], want[3], rtol=0.03)


def test_a_sum_is_rendered_as_the_sum_of_its_parts():
    """The render is linear in the BSDF (one bounce): two Lambertians of 0.2 and 0.3 make
    the image of 0.5 (the same sampling decisions, the same seed: equal to float32 rounding)."""
    a = L.render_looks("lambertian:rd=0.2 + lambertian:rd=0.3")
    b = L.render_looks("lambertian:rd=0.5")
    np.testing.assert_allclose(a.env, b.env, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(a.light, b.light, rtol=1e-5, atol=1e-6)


def _scaled_lambertian_holds(compare) -> bool:
    """The truth ``ratio = k`` for a Lambertian scaled by k, held by a comparison function."""
    looks = compare("lambertian:rd=0.2", {"type": "diffuse", "reflectance": 0.6})
    return bool(np.allclose(looks.highlight_ratios, 3.0, rtol=1e-3) and looks.flip > 0.1)


def test_a_comparison_that_renders_the_source_twice_fails_the_truth(monkeypatch):
    """The checker above holds for compare_looks and rejects a broken one: the result's
    images swapped for the source's (ratio 1, FLIP 0 whatever the result)."""
    assert _scaled_lambertian_holds(plausible.compare_looks)
    real = L.render_looks
    monkeypatch.setattr(L, "render_looks", lambda x, **kw: real("lambertian:rd=0.2", **kw))
    assert not _scaled_lambertian_holds(L.compare_looks)


def test_band_edges_warn_beyond_and_not_at():
    assert L._warnings((1.5, 1 / 1.5), (0.0, 60.0), *L.HIGHLIGHT_BAND) == []
    w = L._warnings((1.51, 0.66), (0.0, 60.0), *L.HIGHLIGHT_BAND)
    assert [x.split(":")[0] for x in w] == ["highlight lost", "highlight invented"]
    assert "0.66x the source's at 60 deg" in w[0] and "1.51x the source's at 0 deg" in w[1]


@pytest.mark.parametrize("kw, name", [(dict(angles=(0.0, 190.0)), "angles"), (dict(angles=()), "angles"),
                                      (dict(res=4), "res"), (dict(spp=0), "spp"), (dict(band=(2.0, 3.0)), "band")])
def test_bad_options_are_refused_naming_the_option(kw, name):
    with pytest.raises(ValueError, match=f"^{name}:"):
        plausible.compare_looks("lambertian", "lambertian", **kw)


def test_a_python_callable_cannot_be_rendered_and_says_so():
    with pytest.raises(ValueError, match="cannot render"):
        plausible.compare_looks("lambertian", lambda wi, wo: 0.1)


def test_a_published_fit_by_its_parts_matches_the_plausible_material_plugin():
    """Two routes to one published fit: its parts rendered one by one and added, and the
    plugin ``plausible_material`` (one BSDF, its own lobe mixture): the point-light images
    agree to float32 rounding, the environment's to its noise."""
    fit = plausible.material("alum-bronze", "ngan2005/ward")
    assert L.mitsuba_parts(fit) == [({"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"}, 1.0)]
    parts = plausible.Sum(list(zip(fit.parts, fit.scales)), name="parts")     # not named as the fit: by parts
    assert [d["type"] for d, _ in L.mitsuba_parts(parts)] == ["lambertian", "ward"]
    looks = plausible.compare_looks(parts, {"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"})
    np.testing.assert_allclose(looks.highlight_ratios, 1.0, rtol=1e-4)
    assert looks.flip < 0.05


def test_the_adapter_of_a_mitsuba_bsdf_is_rendered_as_its_bsdf():
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    looks = plausible.compare_looks(MitsubaBSDF(load_bsdf_dict(DIFFUSE_05)), DIFFUSE_05)
    assert looks.flip == 0.0 and looks.highlight_ratio == 1.0
