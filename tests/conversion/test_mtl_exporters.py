"""MTL files as exporters write them (issue 41, item 1): a 3ds Max export (CRLF, tabs, glass of
illum 6 and 7 with Ni, d, Tr, Tf, a shadow catcher of illum 10), a Blender 4 export (map_Kd, Ks 0.5,
no Kd), and one with a .tga map, Ke, d and map_bump.  The glass, the opacity, the emission, the
Lambertian materials and the textures are checked against closed forms, Mitsuba's own sampler,
the pixels of the images and the Khronos validator."""

import json
import math

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.cli import main
from plausible.conversion import CONSERVE_THETAS, convert, degenerate, lambertian_albedo, read_sources
from plausible.conversion import mitsuba as CM

MAX_EXPORT = (
    "# 3ds Max Wavefront OBJ Exporter v0.97b - (c)2007 guruware\r\n"
    "# File Created: 04.12.2026 18:00:00\r\n\r\n"
    "newmtl window\r\n\tNs 96.0000\r\n\tNi 1.5000\r\n\td 0.3000\r\n\tTr 0.7000\r\n\tTf 0.9000 0.9500 0.9000\r\n"
    "\tillum 6\r\n\tKa 0.0000 0.0000 0.0000\r\n\tKd 0.1000 0.1000 0.1000\r\n\tKs 0.9000 0.9000 0.9000\r\n"
    "\tKe 0.0000 0.0000 0.0000\r\n\r\n"
    "newmtl bottle\r\n\tNs 200.0000\r\n\tNi 1.3300\r\n\td 0.2000\r\n\tTr 0.8000\r\n\tTf 1.0000 1.0000 1.0000\r\n"
    "\tillum 7\r\n\tKd 0.2000 0.3000 0.2000\r\n\tKs 1.0000 1.0000 1.0000\r\n\r\n"
    "newmtl pane\r\n\tNi 0.0000\r\n\td 0.0000\r\n\tillum 4\r\n\tKd 0.5000 0.5000 0.5000\r\n\r\n"
    "newmtl wall\r\n\tNs 10.0000\r\n\tNi 1.5000\r\n\td 1.0000\r\n\tTr 0.0000\r\n\tTf 1.0000 1.0000 1.0000\r\n"
    "\tillum 2\r\n\tKa 0.5800 0.5800 0.5800\r\n\tKd 0.5800 0.2000 0.1000\r\n\tKs 0.0000 0.0000 0.0000\r\n"
    "\tKe 0.0000 0.0000 0.0000\r\n\r\n"
    "newmtl shadow\r\n\tillum 10\r\n")

BLENDER_4 = ("# Blender 4.1.0 MTL File: 'scene.blend'\n# www.blender.org\n\n"
             "newmtl Brick\nNs 250.000000\nKa 1.000000 1.000000 1.000000\nKs 0.500000 0.500000 0.500000\n"
             "Ke 0.000000 0.000000 0.000000\nNi 1.450000\nd 1.000000\nillum 2\nmap_Kd textures/brick.tga\n")

EXTRAS = ("newmtl lamp\nKd 0.5 0.25 0.125\nKs 0 0 0\nillum 1\nKe 2 1 0\nd 0.5\nmap_bump -bm 0.3 lamp_n.png\n"
          "norm lamp_n.png\n\n"
          "newmtl decal\nKd 0.4 0.4 0.4\nillum 1\nd 0\nmap_d decal_a.png\n")


def _validate(path) -> dict:
    """The Khronos validator's report (tests/export/gltf_validator.py; skipped where not installed)."""
    import importlib.util
    from pathlib import Path

    spec = importlib.util.spec_from_file_location(
        "gltf_validator", Path(__file__).resolve().parents[1] / "export" / "gltf_validator.py")
    gv = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gv)
    return gv.validate(path)


def write(tmp_path, text, name):
    p = tmp_path / name
    p.write_bytes(text.encode())
    return p


def image(path, rgb, size=(4, 4)):
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    Image.new("RGB", size, tuple(rgb)).save(path)
    return path


def dielectric_reflectance_at_normal_incidence(d, n=20000):
    """The fraction of Mitsuba's own samples reflected at normal incidence (a smooth dielectric:
    Fresnel's ((n - 1)/(n + 1))^2 for ``dielectric``; ``thindielectric`` adds the inner reflections)."""
    mi = pytest.importorskip("mitsuba")
    from plausible.mitsuba.variant import ensure_variant

    ensure_variant()
    b = mi.load_dict(d)
    si = mi.SurfaceInteraction3f()
    si.wi = mi.Vector3f(0, 0, 1)
    si.n = mi.Normal3f(0, 0, 1)
    si.sh_frame = mi.Frame3f(si.n)
    rng = np.random.default_rng(3)
    bs, _ = b.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)), mi.Point2f(rng.random(n), rng.random(n)))
    return float(np.mean(np.asarray(bs.wo.z) > 0))


def test_a_3ds_max_export_converts_its_glass_and_skips_only_the_shadow_catcher(tmp_path):
    c = convert(str(write(tmp_path, MAX_EXPORT, "max.mtl")), to="mitsuba")
    assert [s["name"] for s in c.skipped] == ["shadow"] and "illum 10" in c.skipped[0]["skipped"]
    got = {i.name: i for i in c.items}
    assert set(got) == {"window", "bottle", "pane", "wall"}
    assert got["window"].result == {"type": "dielectric", "int_ior": 1.5, "ext_ior": 1.0,
                                    "specular_transmittance": {"type": "rgb", "value": [0.9, 0.95, 0.9]}}
    assert got["bottle"].result == {"type": "dielectric", "int_ior": 1.33, "ext_ior": 1.0}
    assert got["pane"].result["type"] == "thindielectric" and got["pane"].result["int_ior"] == 1.5
    assert got["pane"].warnings == ["illum 4 (glass): Ni 0 (below 1): the index of glass, 1.5, read"]   # d 0 unread
    # Fresnel at normal incidence by Mitsuba's own sampler: 0.04 for index 1.5, 0.0201 for 1.33
    for name, n in (("window", 1.5), ("bottle", 1.33)):
        assert dielectric_reflectance_at_normal_incidence(got[name].result) == pytest.approx(
            ((n - 1) / (n + 1)) ** 2, abs=0.005)
    # the opaque wall (Ks 0): Lambertian, exactly its Kd
    assert got["wall"].result == {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.58, 0.2, 0.1]}}


def test_the_command_line_exits_1_naming_the_skipped_material_and_writes_the_rest(tmp_path):
    src, out = write(tmp_path, MAX_EXPORT, "max.mtl"), tmp_path / "max.xml"
    r = CliRunner().invoke(main, ["convert", str(src), "--to", "mitsuba", "--out", str(out)], terminal_width=300)
    assert r.exit_code == 1, r.output
    assert "warning: illum 10" in r.output and "'shadow' skipped" in r.output and "Traceback" not in r.output
    text = out.read_text()
    for name in ("window", "bottle", "pane", "wall"):
        assert f'id="{name}"' in text
    assert "shadow" not in text
    mi = pytest.importorskip("mitsuba")
    from plausible.mitsuba.variant import ensure_variant

    ensure_variant()
    assert mi.load_file(str(out)) is not None


def test_a_glass_material_to_a_registered_model_is_refused_per_material(tmp_path):
    c = convert(str(write(tmp_path, MAX_EXPORT, "max.mtl")), to="mitsuba:diffuse")
    assert {s["name"] for s in c.skipped} == {"window", "bottle", "pane", "shadow"}
    assert "converts to 'mitsuba' or 'gltf'" in c.skipped[0]["skipped"]


def test_the_gltf_of_the_3ds_max_glass_has_transmission_and_ior_and_validates(tmp_path):
    c = convert(str(write(tmp_path, MAX_EXPORT, "max.mtl")), to="gltf")
    out = c.write(tmp_path / "max.gltf")
    doc = json.loads(out.read_text())
    mats = {m["name"]: m for m in doc["materials"]}
    assert mats["window"]["extensions"]["KHR_materials_transmission"] == {"transmissionFactor": 1.0}
    assert mats["bottle"]["extensions"]["KHR_materials_ior"] == {"ior": 1.33}
    assert mats["window"]["pbrMetallicRoughness"]["baseColorFactor"] == [0.9, 0.95, 0.9, 1.0]
    # the Lambertian wall: metallic 0, specular 0, the base colour its Kd (before: metallic 0.14 for such a wall)
    wall = mats["wall"]
    assert wall["pbrMetallicRoughness"]["metallicFactor"] == 0.0
    assert wall["pbrMetallicRoughness"]["baseColorFactor"][:3] == [0.58, 0.2, 0.1]
    assert wall["extensions"]["KHR_materials_specular"]["specularFactor"] == 0.0
    assert {"KHR_materials_transmission", "KHR_materials_ior"} <= set(doc["extensionsUsed"])
    issues = _validate(out)["issues"]
    assert issues["numErrors"] == 0, issues["messages"]


def test_a_lambertian_gltf_is_kd_over_pi_exactly(tmp_path):
    """glTF's BRDF at metallic 0, specular 0 against the closed form Kd / pi at random pairs."""
    src = read_sources(str(write(tmp_path, MAX_EXPORT, "max.mtl")))[3]
    c = convert(src.spec, to="gltf").items[0]
    rng = np.random.default_rng(5)
    from conftest import random_upper

    wi, wo = random_upper(rng, 50), random_upper(rng, 50)
    np.testing.assert_allclose(c.result.eval(wi, wo), np.broadcast_to([0.58, 0.2, 0.1], (50, 3)) / math.pi,
                               rtol=1e-12)
    assert c.params["metallic"] == 0.0 and c.params["specular"] == 0.0


def test_lambertian_albedo_rejects_a_source_with_any_highlight():
    def albedo(m):
        a = np.asarray(plausible.albedo_curve(m, thetas_deg=CONSERVE_THETAS).value, float)
        return np.broadcast_to(a.reshape(len(CONSERVE_THETAS), -1), (len(CONSERVE_THETAS), 3))

    lam = plausible.make("lambertian:rd=0.3")
    np.testing.assert_array_equal(lambertian_albedo(lam, albedo(lam)), [0.3, 0.3, 0.3])
    weak = plausible.make("lambertian:rd=0.3 + reciprocal-blinn:ks=0.01:n=20")
    assert lambertian_albedo(weak, albedo(weak)) is None


def test_a_blender_4_export_reads_the_map_as_the_diffuse_colour(tmp_path):
    (src,) = read_sources(str(write(tmp_path, BLENDER_4, "b.mtl")))
    assert src.spec.startswith("lambertian:rd=1.0,1.0,1.0 + cook-torrance")      # before: no Lambertian at all
    assert CM.diffuse_albedo(src.model).tolist() == [1.0, 1.0, 1.0]
    assert any("Kd not given beside map_Kd: Kd 1" in n for n in src.notes)


def test_a_tga_map_is_written_as_png_for_gltf_and_validates(tmp_path):
    from PIL import Image

    image(tmp_path / "textures" / "brick.tga", (200, 120, 40))
    text = "newmtl brick\nKd 1 1 1\nillum 1\nmap_Kd textures/brick.tga\n"
    (tmp_path / "out").mkdir()
    c = convert(str(write(tmp_path, text, "t.mtl")), to="gltf")
    out = c.write(tmp_path / "out" / "t.gltf")
    doc = json.loads(out.read_text())
    assert [i["uri"] for i in doc["images"]] == ["t.brick.png"]
    png = np.asarray(Image.open(tmp_path / "out" / "t.brick.png"))
    assert png.shape == (4, 4, 3) and np.all(png == [200, 120, 40])
    issues = _validate(out)["issues"]
    assert not [m for m in issues["messages"] if m["code"] == "IMAGE_UNRECOGNIZED_FORMAT"], issues["messages"]
    assert issues["numErrors"] == 0, issues["messages"]


def test_tga_maps_of_one_name_in_two_folders_become_two_pngs_and_a_shared_one_one(tmp_path):
    from PIL import Image

    image(tmp_path / "a" / "wood.tga", (10, 20, 30))
    image(tmp_path / "b" / "wood.tga", (200, 100, 50))
    text = "".join(f"newmtl {n}\nKd 1 1 1\nillum 1\nmap_Kd {f}\n" for n, f in
                   (("one", "a/wood.tga"), ("two", "b/wood.tga"), ("three", "a/wood.tga")))
    c = convert(str(write(tmp_path, text, "t.mtl")), to="gltf")
    doc = json.loads(c.write(tmp_path / "t.gltf").read_text())
    uri = {m["name"]: doc["images"][doc["textures"][m["pbrMetallicRoughness"]["baseColorTexture"]["index"]]["source"]]["uri"]
           for m in doc["materials"]}
    assert uri["one"] == uri["three"] != uri["two"]
    for name, rgb in (("one", (10, 20, 30)), ("two", (200, 100, 50))):
        assert np.all(np.asarray(Image.open(tmp_path / uri[name])) == rgb)


def test_an_unreadable_map_is_dropped_from_the_gltf_with_a_warning(tmp_path):
    (tmp_path / "broken.bmp").write_bytes(b"not an image")
    c = convert(str(write(tmp_path, "newmtl m\nKd 0.5 0.5 0.5\nillum 1\nmap_Kd broken.bmp\n", "t.mtl")), to="gltf")
    doc = json.loads(c.write(tmp_path / "t.gltf").read_text())
    assert "images" not in doc
    assert any("map_Kd broken.bmp: glTF allows PNG and JPEG images only" in w for w in c.items[0].warnings)


def test_kd_times_map_kd_is_baked_for_mitsuba(tmp_path):
    """Kd 0.5 with a white map: Mitsuba's albedo (its own sampler) 0.5, as MTL's Kd x map_Kd (before:
    1.0, the map replacing Kd); the baked texel is Kd times the texel in linear RGB."""
    from PIL import Image

    from plausible.spectra import srgb_to_linear

    image(tmp_path / "white.png", (255, 255, 255))
    image(tmp_path / "grey.png", (128, 64, 200))
    text = "newmtl w\nKd 0.5 0.5 0.5\nillum 1\nmap_Kd white.png\n\nnewmtl g\nKd 0.5 0.25 1\nillum 1\nmap_Kd grey.png\n"
    c = convert(str(write(tmp_path, text, "t.mtl")), to="mitsuba")
    out = c.write(tmp_path / "t.json")
    dicts = json.loads(out.read_text())
    assert dicts["w"]["reflectance"] == {"type": "bitmap", "filename": "t.w.map_Kd.png"}
    baked = srgb_to_linear(np.asarray(Image.open(tmp_path / "t.g.map_Kd.png"), float)[0, 0] / 255.0)
    want = np.array([0.5, 0.25, 1.0]) * srgb_to_linear(np.array([128, 64, 200]) / 255.0)
    np.testing.assert_allclose(baked, want, rtol=0.02, atol=2e-3)       # 8-bit sRGB quantisation
    pytest.importorskip("mitsuba")
    import os

    os.chdir(tmp_path)                 # the bitmap's file name is relative to the output's folder
    np.testing.assert_allclose(CM.sampler_albedo(dicts["w"], side=16), 0.5, atol=0.01)


def test_ke_d_and_map_bump_become_glTF_properties_or_warnings(tmp_path):
    c = convert(str(write(tmp_path, EXTRAS, "x.mtl")), to="gltf")
    doc = json.loads(c.write(tmp_path / "x.gltf").read_text())
    lamp = {m["name"]: m for m in doc["materials"]}["lamp"]
    assert lamp["emissiveFactor"] == [1.0, 0.5, 0.0]
    assert lamp["extensions"]["KHR_materials_emissive_strength"] == {"emissiveStrength": 2.0}
    assert lamp["alphaMode"] == "BLEND" and lamp["pbrMetallicRoughness"]["baseColorFactor"][3] == 0.5
    items = {i.name: i for i in c.items}
    for stmt in ("map_bump", "norm"):
        assert any(w.startswith(f"{stmt} ") and "dropped" in w for w in items["lamp"].warnings)
        assert not any(n.startswith(f"{stmt} ") for n in items["lamp"].notes)
    assert any(w.startswith("d 0 (fully transparent) read as opaque") for w in items["decal"].warnings)
    assert any(w.startswith("map_d decal_a.png: dropped") for w in items["decal"].warnings)
    issues = _validate(tmp_path / "x.gltf")["issues"]
    assert issues["numErrors"] == 0, issues["messages"]


def test_d_and_map_d_are_a_mitsuba_mask_and_ke_a_warning(tmp_path):
    c = convert(str(write(tmp_path, EXTRAS, "x.mtl")), to="mitsuba")
    items = {i.name: i for i in c.items}
    lamp, decal = items["lamp"].result, items["decal"].result
    assert lamp["type"] == "mask" and lamp["opacity"] == 0.5 and lamp["bsdf"]["type"] == "diffuse"
    assert decal["type"] == "mask" and decal["opacity"] == {"type": "bitmap", "filename": "decal_a.png", "raw": True}
    assert any(w.startswith("Ke 2 1 0 (emission) dropped") and "'area'" in w for w in items["lamp"].warnings)
    mi = pytest.importorskip("mitsuba")
    from plausible.mitsuba.variant import ensure_variant

    ensure_variant()
    # a mask of opacity 0.5 over a diffuse of Kd 0.5 0.25 0.125: Mitsuba's value is half of Kd / pi
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF

    f = MitsubaBSDF(mi.load_dict(lamp)).eval(np.array([0.0, 0.0, 1.0]), np.array([0.6, 0.0, 0.8]))
    np.testing.assert_allclose(f, 0.5 * np.array([0.5, 0.25, 0.125]) / math.pi, rtol=1e-6)


def _fit(d, key):
    return CM.FamilyFit(d["type"], d, {}, {}, {}, 0, 0.0, key)


def test_a_candidate_that_renders_nothing_is_rejected():
    """The issue's metal: a blendbsdf whose coat (int_ior 1) has zero colours evaluates to its conductor
    and samples to nothing; the conductor alone is accepted."""
    pytest.importorskip("mitsuba")
    conductor = {"type": "roughconductor", "distribution": "ggx", "material": "none", "alpha": 0.104,
                 "specular_reflectance": {"type": "rgb", "value": [1.0, 1.0, 0.956]}}
    blend = {"type": "blendbsdf", "weight": 0.8, "bsdf_1": conductor,
             "bsdf_0": {"type": "roughplastic", "distribution": "ggx", "nonlinear": False, "int_ior": 1.0,
                        "specular_reflectance": 0.0, "ext_ior": 1.31, "alpha": 0.1525,
                        "diffuse_reflectance": {"type": "rgb", "value": [0.0, 0.0, 0.0]}}}
    probe = CM.probe_for(plausible.make("lambertian"))
    assert "renders other than it evaluates" in degenerate(_fit(blend, "blendbsdf-tir"), probe)
    assert degenerate(_fit(conductor, "roughconductor"), probe) is None


def test_the_issues_metal_converts_to_a_target_that_reflects(tmp_path):
    src = write(tmp_path, "newmtl m\nKd 0 0 0\nKs 0.8 0.8 0.75\nNs 40\nillum 3\n", "metal.mtl")
    (c,) = convert(str(src), to="mitsuba").items
    for t, v in c.albedo.items():                         # Mitsuba's own sampler against the source
        assert v["max_abs_difference"] < 0.05, (t, v)
    # no warning but the image comparison's (its highlight 1.6x the source's is a finding of issue 40)
    assert not [w for w in c.warnings if not w.startswith("highlight ")]


@pytest.mark.parametrize("fitted, ends, kept", [(1.0, (1.05, 2.0), 0.0),     # within 10 %: the better end
                                                (0.5, (3.0, 1.0), 0.3),      # 50 % lower: the fraction kept
                                                (0.95, (1.2, 1.0), 1.0)])    # 5 % lower: metallic 1
def test_a_fractional_metallic_is_kept_only_where_it_lowers_the_figure_by_the_margin(monkeypatch, fitted, ends, kept):
    from plausible.conversion import METALLIC_MARGIN, metallic_decision

    assert METALLIC_MARGIN == 0.10
    fake = {0.0: ends[0], 1.0: ends[1]}

    def fit_family(model, fam, metric, probe=None, target=None, hard=False):
        v = dict(fam.fixed)["metallic"]
        return CM.FamilyFit("gltf-pbr", {"type": "gltf-pbr", "metallic": v}, {}, {}, {}, 0, fake[v], "gltf-pbr")

    monkeypatch.setattr(CM, "fit_family", fit_family)
    r = CM.FamilyFit("gltf-pbr", {"type": "gltf-pbr", "metallic": 0.3}, {"metallic": 0.3}, {}, {}, 0, fitted, "gltf-pbr")
    notes = []
    out = metallic_decision(None, r, "perceptual", None, None, notes)
    assert out.dict["metallic"] == kept and len(notes) == 1
    # a metallic already at an end is judged beside both ends fitted (issue 40: the band drove a red plastic
    # to metallic 1, kept unjudged): the free fit at metallic 1 is the metal end, the dielectric fitted beside it
    end = CM.FamilyFit("gltf-pbr", {"type": "gltf-pbr", "metallic": 1.0}, {"metallic": 1.0}, {}, {}, 0, 9.0, "gltf-pbr")
    assert metallic_decision(None, end, "perceptual", None, None, []).figure == ends[0]
    end.figure = 0.5
    assert metallic_decision(None, end, "perceptual", None, None, []) is end


def test_ns_0_reads_as_0_375_ks_with_blinns_g_against_one_half_without_it():
    """The normalisation Ns is read with (docs/convert.md): at Ns 0, D = 1/pi; without G the albedo at
    normal incidence is the closed form int D / (4 cos) cos dw = 2 pi / (4 pi) = 1/2; with the V-groove G
    it is 0.375 (the reading), and without G it exceeds 1 at grazing incidence (energy created)."""
    from plausible.conversion.mtl import highlight_spec

    read = plausible.make(highlight_spec([1.0, 1.0, 1.0], 0.0))
    no_g = plausible.make(highlight_spec([1.0, 1.0, 1.0], 0.0).replace("geometry=vgroove", "geometry=none"))
    a_read = np.asarray(plausible.albedo_curve(read, thetas_deg=[0, 75]).value, float).reshape(2, -1)[:, 0]
    a_no_g = np.asarray(plausible.albedo_curve(no_g, thetas_deg=[0, 75]).value, float).reshape(2, -1)[:, 0]
    assert a_no_g[0] == pytest.approx(0.5, abs=1e-4) and a_read[0] == pytest.approx(0.375, abs=1e-3)
    assert a_no_g[1] > 1.5 and a_read[1] < 1.0


def test_the_image_error_decides_the_metallic_where_it_can_be_rendered(monkeypatch):
    """With image scores at hand the fraction is judged by them (issue 41: 'a fractional metallic only
    where it lowers the image error by a stated margin'), not by the figure minimised: a figure 50 %
    lower with an image error only 5 % lower gives the better end."""
    import plausible.conversion as C

    fake_fig = {0.0: 3.0, 1.0: 1.0}
    flips = {0.3: 0.19, 0.0: 0.40, 1.0: 0.20}

    def fit_family(model, fam, metric, probe=None, target=None, hard=False):
        v = dict(fam.fixed)["metallic"]
        return CM.FamilyFit("gltf-pbr", {"type": "gltf-pbr", "metallic": v}, {}, {}, {}, 0, fake_fig[v], "gltf-pbr")

    monkeypatch.setattr(CM, "fit_family", fit_family)
    monkeypatch.setattr(C, "_image_error", lambda model, r: flips[r.dict["metallic"]])
    r = CM.FamilyFit("gltf-pbr", {"type": "gltf-pbr", "metallic": 0.3}, {"metallic": 0.3}, {}, {}, 0, 0.5, "gltf-pbr")
    notes = []
    assert C.metallic_decision("source", r, "perceptual", None, None, notes).dict["metallic"] == 1.0
    assert "image error" in notes[0]
    flips[0.3] = 0.10                   # half the better end's: the fraction is kept
    assert C.metallic_decision("source", r, "perceptual", None, None, []).dict["metallic"] == 0.3


def test_the_textures_of_glass_are_warned_where_they_are_dropped(tmp_path):
    # before, glass never went through the texture reading: its maps vanished with neither note nor warning
    p = write(tmp_path, "newmtl window\nKd 0.5 0.5 0.5\nNi 1.45\nillum 4\nd 0.75\nmap_Kd glass.png\n"
                        "map_Bump -bm 0.2 glass_n.png\n", "glass.mtl")
    (m,) = convert(str(p), to="mitsuba").items
    assert m.result == {"type": "thindielectric", "int_ior": 1.45, "ext_ior": 1.0}
    assert sorted(w.split(":")[0] for w in m.warnings) == ["map_Kd glass.png", "map_bump glass_n.png"]
    (g,) = convert(str(p), to="gltf").items
    assert [w.split(":")[0] for w in g.warnings] == ["map_bump glass_n.png"]
    assert any(n.startswith("map_Kd glass.png: the glass's baseColorTexture") for n in g.notes)


def test_a_blender_pbr_material_converts_to_gltf_with_its_own_metallic_and_roughness(tmp_path):
    # the independent truth: the statements themselves (Blender writes its Principled BSDF's base colour,
    # metallic and roughness, which are glTF's); before, Pr and Pm were ignored and the glTF came out a
    # dielectric fitted to Kd and Ks
    p = write(tmp_path, "newmtl Mat1\nKd 0.8 0.276449 0.101911\nKs 0.25 0.25 0.25\nNi 1.45\nd 1\nillum 3\n"
                        "Pr 0.4\nPm 0.9\n", "pbr.mtl")
    (g,) = convert(str(p), to="gltf").items
    assert g.params["metallic"] == pytest.approx(0.9, abs=2e-3)
    assert g.params["roughness"] == pytest.approx(0.4, abs=2e-3)
    assert np.allclose(g.params["base_color"], [0.8, 0.276449, 0.101911], atol=2e-3)
    assert g.looks.flip < 0.01 and not g.warnings
