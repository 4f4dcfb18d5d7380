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
    """Two implementations of one BRDF (plausible's plugin, Mitsuba's own), both sampling the
    cosine-weighted hemisphere: the light images agree to 1e-4 (measured 7e-5), so the peaks
    to 1e-3; FLIP is the environment's sampling noise (0.019 measured, 0.024 seed to seed)."""
    looks = plausible.compare_looks("lambertian:rd=0.5", DIFFUSE_05)
    np.testing.assert_allclose(looks.highlight_ratios, 1.0, atol=1e-3)
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


def _reference_peak(model, angle_deg, res, lamp_points=48):
    """The light image of the sphere computed apart, in NumPy: at each pixel centre of an
    orthographic ``res`` x ``res`` view (the camera ``angle_deg`` from the lamp, which is along
    +z), the normal, and the sum over ``lamp_points`` directions spread over the lamp's cone
    (equal solid angle, a Fibonacci lattice) of ``f(l, v) cos(theta_l) L dOmega``; then the
    largest mean over a window of PEAK_WINDOW pixels, as :meth:`Renders.peaks` takes it."""
    a = math.radians(angle_deg)
    v = np.array([math.sin(a), 0.0, math.cos(a)])
    x = ((np.arange(res) + 0.5) / res * 2 - 1) * L.HALF_WIDTH
    X, Y = np.meshgrid(x, x)
    inside = X ** 2 + Y ** 2 < 1
    right = np.cross([0.0, 1.0, 0.0], v)
    n = (X[inside][:, None] * right + Y[inside][:, None] * np.array([0.0, 1.0, 0.0])
         + np.sqrt(1 - X[inside] ** 2 - Y[inside] ** 2)[:, None] * v)
    t = np.cross(n, [0.0, 1.0, 0.0])
    t /= np.linalg.norm(t, axis=1)[:, None]
    b = np.cross(n, t)
    cos_a = math.cos(math.radians(L.LAMP_DEG))
    k = np.arange(lamp_points) + 0.5
    ct = 1 - k / lamp_points * (1 - cos_a)
    phi = k * math.pi * (3 - math.sqrt(5))
    lamp = np.stack([np.sqrt(1 - ct ** 2) * np.cos(phi), np.sqrt(1 - ct ** 2) * np.sin(phi), ct], -1)
    radiance = L.IRRADIANCE / (math.pi * math.sin(math.radians(L.LAMP_DEG)) ** 2)
    d_omega = 2 * math.pi * (1 - cos_a) / lamp_points
    wo = np.stack([t @ v, b @ v, n @ v], -1)
    img = np.zeros((res, res, 3))
    total = np.zeros((len(n), 3))
    for light in lamp:
        wi = np.stack([t @ light, b @ light, n @ light], -1)
        f = np.asarray(model.eval(wi, wo)).reshape(len(n), -1)
        total += f * np.maximum(wi[:, 2], 0.0)[:, None] * radiance * d_omega
    img[inside] = total
    return L._window_max(luminance(img))


def test_the_rendered_peak_is_the_one_computed_apart_in_numpy():
    """Mitsuba's path tracer (the model's plugin, emitter and BSDF sampling) against a NumPy sum of
    f cos over the lamp at each pixel centre (modified-phong n = 15, 128 px): measured 0.1, 0.05
    and 0.4 % apart at 0, 60, 120 deg (a pixel's footprint against its centre; the lamp 1000 radii
    away, so its distance changes by 0.2 % over the sphere), asserted within 1 %; at 150 deg the peak
    is on the limb, whose pixels the sphere covers in part (the centre says all or nothing): 3.6 %,
    asserted within 5 %."""
    spec = "modified-phong:kd=0.2:ks=0.4:n=15"
    peaks = L.render_looks(spec, res=128).peaks()
    want = np.array([_reference_peak(make_from_spec(spec), a, 128) for a in L.LIGHT_ANGLES])
    np.testing.assert_allclose(peaks[:3], want[:3], rtol=0.01)
    np.testing.assert_allclose(peaks[3], want[3], rtol=0.05)


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
    plugin ``plausible_material`` (one BSDF, its own lobe mixture, so other samples): the
    highlights agree to the light image's noise (measured 0.8-1.8 %; 2-5 % seed to seed for this
    fit), the environment's to its noise."""
    fit = plausible.material("alum-bronze", "ngan2005/ward")
    assert L.mitsuba_parts(fit) == [({"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"}, 1.0)]
    parts = plausible.Sum(list(zip(fit.parts, fit.scales)), name="parts")     # not named as the fit: by parts
    assert [d["type"] for d, _ in L.mitsuba_parts(parts)] == ["lambertian", "ward"]
    looks = plausible.compare_looks(parts, {"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"})
    np.testing.assert_allclose(looks.highlight_ratios, 1.0, rtol=0.05)
    assert looks.flip < 0.05


def test_the_adapter_of_a_mitsuba_bsdf_is_rendered_as_its_bsdf():
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    looks = plausible.compare_looks(MitsubaBSDF(load_bsdf_dict(DIFFUSE_05)), DIFFUSE_05)
    assert looks.flip == 0.0 and looks.highlight_ratio == 1.0


def test_the_lamp_strip_predicts_the_peak_of_a_whole_view_computed_apart():
    """LampStrip (the middle rows, lamp and pixel footprint in one sum, half mirrored) against the NumPy
    image of the whole view at pixel centres (_reference_peak) for a broad lobe: measured 0.2-1.3 % at
    0/60/120 deg; at 150 deg the peak is on the limb, where pixel centres say all or nothing (the render
    is 3.6 % from them, above)."""
    model = make_from_spec("modified-phong:kd=0.2:ks=0.4:n=15")
    got = L.LampStrip.make().of(model)
    want = np.array([_reference_peak(model, a, L.RES) for a in L.LIGHT_ANGLES])
    np.testing.assert_allclose(got[:3], want[:3], rtol=0.02)
    np.testing.assert_allclose(got[3], want[3], rtol=0.06)


@pytest.mark.parametrize("spec", ["material:chrome@ngan2005/ward", "material:nickel@ngan2005/ashikhmin-shirley"])
def test_the_lamp_strip_predicts_the_rendered_peak_of_a_sharp_published_fit(spec):
    """The sharpest of the issue's cases (chrome: a 64-point lamp put it 56 % off at 120 deg) and a
    broad one: the predicted peak within 10 % of the render at all four angles, grazing included
    (measured 1-7 %)."""
    got = L.LampStrip.make().of(make_from_spec(spec))
    np.testing.assert_allclose(got, L.render_looks(spec).peaks(), rtol=0.10)


def test_a_lamp_strip_of_too_few_points_misses_the_sharp_peak():
    """The check above can fail: 16 lamp points miss chrome's peak at 120 deg by more than 10 %."""
    spec = "material:chrome@ngan2005/ward"
    got = L.LampStrip.make(points=16).of(make_from_spec(spec))
    assert np.max(np.abs(got / L.render_looks(spec).peaks() - 1.0)) > 0.10
