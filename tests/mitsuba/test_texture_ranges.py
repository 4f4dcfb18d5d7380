"""Textures whose values leave a model's range (issue 43): as Mitsuba's own BSDFs, the
plugins load them, clamp the value into the range at each shading point and say so in
ONE warning (Mitsuba's log) naming the parameter, the texture and how many texels, the
same in RGB, monochrome and spectral variants."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import LogCapture, dr, mi, variant  # noqa: F401 (a fixture)

import plausible

pytestmark = pytest.mark.drjit

LOAD_ERRORS = (RuntimeError, ValueError)


def load_logged(desc):
    cap = LogCapture()
    mi.logger().add_appender(cap)
    try:
        bsdf = mi.load_dict(desc)
        return bsdf, [t for level, t in cap.lines if level == mi.LogLevel.Warn and "must lie in" in t]
    finally:
        mi.logger().remove_appender(cap)


def write_exr(path, values):
    arr = np.asarray(values, dtype=np.float32)
    mi.Bitmap(arr, mi.Bitmap.PixelFormat.Y if arr.shape[2] == 1 else mi.Bitmap.PixelFormat.RGB).write(str(path))
    return {"type": "bitmap", "filename": str(path), "filter_type": "nearest"}


def at_texel(bsdf, uv, wi, wo):
    """eval at one UV point; the first channel (wavelength)."""
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.uv = mi.Point2f(*[float(x) for x in uv])
    value = bsdf.eval(mi.BSDFContext(), si, mi.Vector3f(*[float(x) for x in wo]))
    return float(np.array(value, dtype=np.float64).ravel()[0])


#: A 6 x 6 roughness map: four texels at 0 (below Ward's 1e-4), one at 1.5 (above 1), 0.3 elsewhere.
ROUGH = np.full((6, 6, 1), 0.3)
ROUGH[0, :4] = 0.0
ROUGH[5, 5] = 1.5


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_mono", "llvm_ad_spectral"], indirect=True)
def test_a_roughness_map_outside_the_range_loads_with_one_warning(variant, tmp_path):
    """Ward's alpha from a map with 5 of 36 texels outside [1e-4, 1] (0 and 1.5) loads,
    as roughconductor does, with exactly one warning naming the parameter, the texture
    and the count; at the texel 1.5, eval equals the NumPy Ward of alpha 1 (the
    clamped value), at a texel 0.3 the Ward of 0.3 (before: refused in RGB and mono)."""
    tex = write_exr(tmp_path / "rough.exr", ROUGH)
    bsdf, warnings = load_logged({"type": "ward", "rd": 0.0, "alpha": tex})
    assert len(warnings) == 1
    assert "'alpha_x' (given as 'alpha')" in warnings[0] and "5 of 36 texels" in warnings[0]
    assert "rough.exr" in warnings[0] and "[0.0001, 1]" in warnings[0]
    wi, wo = np.array([0.3, 0.1, 0.948683]), np.array([-0.5, 0.1, 0.860233])
    for uv, alpha in [((11 / 12, 11 / 12), 1.0), ((0.5, 0.5), 0.3)]:
        want = plausible.make("ward", rd=0.0, alpha_x=alpha, alpha_y=alpha).eval(wo, wi) * wo[2]
        np.testing.assert_allclose(at_texel(bsdf, uv, wi, wo), np.ravel(want)[0], rtol=1e-4)


@pytest.mark.parametrize("variant", ["llvm_ad_rgb", "llvm_ad_mono"], indirect=True)
def test_an_hdr_reflectance_is_clamped_to_one_with_one_warning(variant, tmp_path):
    """lambertian.rd from an EXR with texels 19.3 and 3 (a light probe's range): one
    warning naming 'rd', the file and "2 of 16 texels"; at the 19.3 texel eval is the
    closed form of rd = 1, cos / pi, and 0.5 cos / pi elsewhere."""
    img = np.full((4, 4, 3), 0.5)
    img[0, 0], img[1, 1] = 19.3, 3.0
    bsdf, warnings = load_logged({"type": "lambertian", "rd": write_exr(tmp_path / "museum.exr", img)})
    assert len(warnings) == 1
    assert "parameter 'rd'" in warnings[0] and "museum.exr" in warnings[0] and "2 of 16 texels" in warnings[0]
    wi, wo = [0.0, 0.0, 1.0], [0.6, 0.0, 0.8]
    np.testing.assert_allclose(at_texel(bsdf, (0.125, 0.125), wi, wo), 0.8 / np.pi, rtol=1e-6)
    np.testing.assert_allclose(at_texel(bsdf, (0.625, 0.625), wi, wo), 0.4 / np.pi, rtol=1e-6)


def test_a_texture_inside_the_range_gives_no_warning(tmp_path):
    """The same map with every texel in range: no warning, known (not clamped)."""
    bsdf, warnings = load_logged({"type": "ward", "alpha": write_exr(tmp_path / "ok.exr", np.full((6, 6, 1), 0.3))})
    assert warnings == [] and bsdf.state.known == {"alpha_x": True, "alpha_y": True}


def test_a_nan_texel_is_refused_naming_the_texture(tmp_path):
    """NaN cannot be clamped: refused, naming the parameter, the texture and the count."""
    img = np.full((2, 2, 1), 0.3)
    img[1, 0] = np.nan
    with pytest.raises(LOAD_ERRORS, match=r"ward: parameter 'alpha_x' .*nan\.exr.* 1 texel\(s\) that are not a number"):
        mi.load_dict({"type": "ward", "alpha": write_exr(tmp_path / "nan.exr", img)})


def test_an_update_out_of_the_range_is_clamped_and_warned_once():
    """A bitmap nu edited through traverse to hold a negative texel: params.update()
    accepts it, clamps it (eval at that texel equals nu = 0's), warns once, and a second
    such update does not warn again."""
    data = np.full((2, 2, 1), 20.0, dtype=np.float32)
    bsdf = mi.load_dict({"type": "ashikhmin_shirley", "nv": 20.0, "rd": 0.0,
                         "nu": {"type": "bitmap", "data": mi.TensorXf(data), "raw": True, "filter_type": "nearest"}})
    params = mi.traverse(bsdf)
    data[0, 1, 0] = -5.0
    params["nu.data"] = mi.TensorXf(data)
    params.update()
    assert bsdf.state.known["nu"] is False and len(bsdf.state.warnings) == 1
    wi, wo = np.array([0.3, 0.1, 0.948683]), np.array([-0.5, 0.1, 0.860233])
    want = plausible.make("ashikhmin-shirley", nu=0.0, nv=20.0, rd=0.0).eval(wo, wi) * wo[2]
    np.testing.assert_allclose(at_texel(bsdf, (0.75, 0.25), wi, wo), np.ravel(want)[0], rtol=1e-4)
    data[0, 1, 0] = -6.0
    params["nu.data"] = mi.TensorXf(data)
    params.update()
    assert len(bsdf.state.warnings) == 1
