"""What real Mitsuba scenes bring (issue 28): 8-bit PNG and JPEG textures
(``TensorXu8``, sRGB-decoded unless ``raw``) and vertex colours
(``mesh_attribute``, a texture without a mean), each compared with Mitsuba's
own ``diffuse`` given the same texture."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import ON_CUDA, dr, interaction, mi, spectrum_np, upper_dirs, vec3

from plausible.mitsuba import props as P

pytestmark = pytest.mark.drjit

LOAD_ERRORS = (RuntimeError, ValueError)


@pytest.fixture(scope="module")
def images(tmp_path_factory):
    """An 8 x 8 RGB ramp of 8-bit texels written as PNG and JPEG by ``mi.Bitmap``;
    and a flat 128-grey PNG."""
    d = tmp_path_factory.mktemp("tex")
    y, x = np.mgrid[0:8, 0:8]
    img = np.stack([x * 32 + 10, y * 30 + 5, 255 - x * 20 - y * 10], -1).astype(np.uint8)
    out = {}
    for ext in ("png", "jpg"):
        path = d / f"ramp.{ext}"
        mi.Bitmap(img, mi.Bitmap.PixelFormat.RGB).write(str(path))
        out[ext] = str(path)
    grey = np.full((4, 4, 3), 128, np.uint8)
    out["grey"] = str(d / "grey.png")
    mi.Bitmap(grey, mi.Bitmap.PixelFormat.RGB).write(out["grey"])
    return out


def _tex(path, raw=False):
    return {"type": "bitmap", "filename": path, "raw": raw}


@pytest.mark.parametrize("ext", ["png", "jpg"])
@pytest.mark.parametrize("raw", [False, True])
def test_8bit_texels_are_read_as_mitsuba_evaluates_them(images, ext, raw):
    """The texels read from a TensorXu8 equal Mitsuba's own eval at the texel
    centres (nearest filter), to float32 rounding: 0..255 -> [0, 1], decoded
    from sRGB unless raw."""
    tex = mi.load_dict({**_tex(images[ext], raw), "filter_type": "nearest"})
    assert np.array(mi.traverse(tex)["data"]).dtype == np.uint8
    texels = P.texture_texels(mi, tex)
    c = (np.arange(8) + 0.5) / 8
    u, v = np.meshgrid(c, c, indexing="xy")
    want = P.eval_at_uv(mi, tex, np.stack([u.ravel(), v.ravel()], -1))
    # CUDA: Mitsuba's own read of an 8-bit sRGB texel is not the exact decode there (0.83203125
    # = 213/256 against 0.83077 on an H200: the GPU's texture path, measured, not the plugin's)
    np.testing.assert_allclose(texels, want, rtol=1e-5, atol=2e-3 if ON_CUDA and not raw else 1e-7)
    assert P.bitmap_is_raw(tex, "data") is raw


@pytest.mark.parametrize("ext", ["png", "jpg"])
@pytest.mark.parametrize("plugin,name", [("lambertian", "rd"), ("modified_phong", "kd")])
def test_8bit_textures_load_and_shade_as_diffuse(images, ext, plugin, name):
    """An 8-bit PNG / JPEG bound to a diffuse colour loads (it was refused: 'got
    128'), and the plugin's diffuse part equals Mitsuba's diffuse with the same
    texture at 64 uv points (Modified Phong with ks = 0: its f is kd / pi)."""
    extra = {"ks": 0.0} if plugin == "modified_phong" else {}
    ours = mi.load_dict({"type": plugin, name: _tex(images[ext]), **extra})
    ref = mi.load_dict({"type": "diffuse", "reflectance": _tex(images[ext])})
    rng = np.random.default_rng(3)
    wi, wo = upper_dirs(rng, 64, 0.1), upper_dirs(rng, 64, 0.1)
    si = interaction(wi)
    si.uv = mi.Point2f(np.ascontiguousarray(rng.random((2, 64)), dtype=np.float32))
    got = spectrum_np(ours.eval(mi.BSDFContext(), si, vec3(wo)))
    want = spectrum_np(ref.eval(mi.BSDFContext(), si, vec3(wo)))
    np.testing.assert_allclose(got, want, rtol=1e-5, atol=1e-7)
    assert ours.state.known == {name: True} and np.ptp(want) > 0.05


def test_srgb_decoding_decides_the_constraint(images):
    """A flat 128 texture is 0.2158 decoded and 0.502 raw: with ks = 0.7,
    Modified Phong's kd + ks <= 1 holds for the sRGB texture and fails raw (so the
    check sees the decoded value, not the byte)."""
    mi.load_dict({"type": "modified_phong", "kd": _tex(images["grey"]), "ks": 0.7})
    with pytest.raises(LOAD_ERRORS, match="'kd' \\+ 'ks' must not exceed 1"):
        mi.load_dict({"type": "modified_phong", "kd": _tex(images["grey"], raw=True), "ks": 0.7})


def test_an_8bit_texel_outside_the_range_is_clamped_with_a_warning(images):
    """Ward's roughness range starts at 1e-4: a raw 8-bit grey PNG with one black
    texel loads clamped (issue 43, as roughconductor), and the warning counts it
    and names the value."""
    img = np.full((2, 2, 1), 100, np.uint8)
    img[0, 0, 0] = 0
    path = images["grey"].replace("grey", "black")
    mi.Bitmap(img, mi.Bitmap.PixelFormat.Y).write(path)
    b = mi.load_dict({"type": "ward", "alpha_x": _tex(path, raw=True)})
    assert b.state.known["alpha_x"] is False
    assert "parameter 'alpha_x' must lie in [0.0001, 1]; 1 of 4 texels" in b.state.warnings[0]
    assert "values from 0 to 0.392157" in b.state.warnings[0]


# -- vertex colours ------------------------------------------------------------------

COLOURS = [[0.1, 0.2, 0.3], [0.9, 0.8, 0.7], [0.5, 1.6, 0.5], [0.2, 0.2, 0.2]]


@pytest.fixture(scope="module")
def ply(tmp_path_factory):
    """A unit quad (z = 0, normal +z) with a vertex colour per corner, one of them
    above 1 (1.6 green), written as PLY by Mitsuba."""
    mesh = mi.Mesh("quad", 4, 2, has_vertex_normals=False, has_vertex_texcoords=True)
    p = mi.traverse(mesh)
    p["vertex_positions"] = mi.Float([-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0])
    p["faces"] = mi.UInt32([0, 1, 2, 0, 2, 3])
    p["vertex_texcoords"] = mi.Float([0, 0, 1, 0, 1, 1, 0, 1])
    p.update()
    mesh.add_attribute("vertex_color", 3, [x for c in COLOURS for x in c])
    path = str(tmp_path_factory.mktemp("ply") / "quad.ply")
    mesh.write_ply(path)
    return path


def _hits(ply, bsdf, n=256, seed=4):
    """Surface interactions of rays from above onto the quad with ``bsdf``."""
    scene = mi.load_dict({"type": "scene", "quad": {"type": "ply", "filename": ply, "bsdf": bsdf}})
    rng = np.random.default_rng(seed)
    xy = rng.uniform(-0.95, 0.95, (2, n))
    o = mi.Point3f(mi.Float(xy[0]), mi.Float(xy[1]), mi.Float(np.full(n, 2.0)))
    si = scene.ray_intersect(mi.Ray3f(o, mi.Vector3f(0, 0, -1)))
    assert bool(dr.all(si.is_valid()))
    return scene, si


def test_vertex_colours_load_and_are_clamped_per_shading_point(ply):
    """lambertian with rd from the PLY's vertex colours (mesh_attribute, which has
    no mean) loads, is spatially varying, and at 256 hit points equals Mitsuba's
    diffuse with the same colours clamped to [0, 1] (the plugin's range) -- and
    differs from the unclamped diffuse where green exceeds 1."""
    attr = {"type": "mesh_attribute", "name": "vertex_color"}
    scene, si = _hits(ply, {"type": "lambertian", "rd": attr})
    ours = scene.shapes()[0].bsdf()
    assert ours.flags() & mi.BSDFFlags.SpatiallyVarying and ours.state.known == {"rd": False}
    ref = mi.load_dict({"type": "diffuse", "reflectance": attr})
    si.wi = mi.Vector3f(0.3, 0.1, 0.948683)
    wo = mi.Vector3f(-0.2, 0.4, 0.894427)
    got = spectrum_np(ours.eval(mi.BSDFContext(), si, wo))
    want = spectrum_np(ref.eval(mi.BSDFContext(), si, wo))
    cos = 0.894427
    np.testing.assert_allclose(got, np.minimum(want, cos / np.pi), rtol=1e-5, atol=1e-7)
    assert np.max(want[:, 1]) > 1.1 * cos / np.pi  # the clamp acted
    assert np.ptp(got[:, 0]) > 0.1 * cos / np.pi   # the colour varies per point
