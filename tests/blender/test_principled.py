"""The gltf-pbr -> Principled BSDF mapping (closed forms) and the written node tree."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

from plausible.blender.principled import blender_material, node_script, principled_inputs, write_blender
from plausible.cli import main


class TestMapping:
    def test_isotropic_parameters_carry_over_with_ior_level_half_the_specular_factor(self):
        p = principled_inputs(dict(base_color=[0.5, 0.2, 0.1], metallic=0.25, roughness=0.4, specular=0.6,
                                   specular_color=[1.0, 0.9, 0.8]))
        assert p == {"Base Color": [0.5, 0.2, 0.1], "Metallic": 0.25, "Roughness": 0.4, "IOR": 1.5,
                     "Specular IOR Level": 0.3, "Specular Tint": [1.0, 0.9, 0.8], "distribution": "GGX"}

    def test_a_dielectric_part_becomes_gltfs_formula_as_nodes(self):
        p = blender_material(dict(base_color=[0.5, 0.2, 0.1], metallic=0.25, roughness=0.4, specular=0.6,
                                  specular_color=[1.0, 0.9, 0.8]))
        g = p["gltf_nodes"]
        f0 = 0.04 * np.array([1.0, 0.9, 0.8]) * 0.6                # KHR_materials_specular: min(0.04 c, 1) s
        np.testing.assert_allclose(np.array(g["f0_over_specular"]) * g["specular"], f0, rtol=1e-12)
        np.testing.assert_allclose(g["diffuse"], np.array([0.5, 0.2, 0.1]) * (1 - f0.max()), rtol=1e-12)
        assert (g["metallic"], g["roughness"]) == (0.25, 0.4)
        assert "gltf_nodes" not in blender_material(dict(metallic=1.0))            # a metal: one Principled
        assert "gltf_nodes" not in blender_material(dict(metallic=0.0), nodes="principled")
        with pytest.raises(ValueError, match="nodes: one of source, gltf, principled"):
            blender_material({}, nodes="group")

    @pytest.mark.parametrize("r, s", [(0.3, 0.2), (0.5, 0.4), (0.2, 0.3)])
    def test_anisotropy_keeps_gltfs_alpha_ratio_and_geometric_mean(self, r, s):
        a = r * r
        at, ab = a + (1 - a) * s * s, a                      # glTF: alpha_t = mix(alpha, 1, s^2)
        p = principled_inputs(dict(roughness=r, anisotropy_strength=s, anisotropy_rotation=math.pi / 2))
        aspect = math.sqrt(1 - 0.9 * p["Anisotropic"])          # Cycles' principled: alpha / aspect, alpha aspect
        alpha = p["Roughness"] ** 2
        assert (alpha / aspect) / (alpha * aspect) == pytest.approx(at / ab, rel=1e-12)
        assert alpha == pytest.approx(math.sqrt(at * ab), rel=1e-12)
        assert p["Anisotropic Rotation"] == pytest.approx(0.25)


def test_the_script_connects_a_map_kd_in_srgb_multiplied_and_a_bump_in_non_color():
    text = node_script({"m": principled_inputs({})}, {"m": {"map_Kd": "wood.png", "bump": "h.png"}})
    ns = {}
    exec(compile(text, "x.py", "exec"), ns)       # plain Python: the tables it builds from
    assert ns["TEXTURES"]["m"] == {"map_Kd": "wood.png", "bump": "h.png"}
    assert ns["TEXTURE_NODES"]["map_Kd"] == ["Base Color", "sRGB"]
    assert ns["TEXTURE_NODES"]["bump"] == ["Bump", "Non-Color"]


def test_a_blender_output_must_end_in_blend_or_py(tmp_path):
    with pytest.raises(ValueError, match=r"out: a Blender output ends in \.blend or \.py"):
        write_blender({"m": principled_inputs({})}, tmp_path / "m.gltf")


MTL = "newmtl wood\nKd 0.6 0.4 0.2\nmap_Kd wood.png\nKs 0 0 0\nillum 1\n"


def test_convert_to_blender_writes_a_blend_whose_lambertian_renders_like_its_source(blender, tmp_path):
    from PIL import Image

    Image.fromarray(np.full((4, 4, 3), 200, np.uint8)).save(tmp_path / "wood.png")
    (tmp_path / "wood.mtl").write_text(MTL)
    out = tmp_path / "sub" / "wood.blend"
    out.parent.mkdir()
    r = CliRunner().invoke(main, ["convert", str(tmp_path / "wood.mtl"), "--to", "blender", "--out", str(out),
                                  "--json"], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    import json

    v = json.loads(r.stdout)[0]["blender"]
    assert v["inputs"]["Base Color"] == pytest.approx([0.6, 0.4, 0.2])
    assert v["albedo_difference"] < 5e-3                  # Cycles' Lambertian vs the MTL's Kd / pi
    if v["flip"] is not None:
        assert v["flip"] < 0.02
    assert out.stat().st_size > 0


def test_check_blender_names_a_missing_material_and_exits_2(blender, tmp_path):
    write_blender({"gold": principled_inputs(dict(base_color=[1, 0.8, 0.3], metallic=1.0))}, tmp_path / "g.blend")
    r = CliRunner().invoke(main, ["check", "--blender", str(tmp_path / "g.blend"), "--material", "silver"])
    assert r.exit_code == 2
    assert "--material: 'silver' is not in" in r.output and "(it has gold)" in r.output


def test_check_blender_passes_a_diffuse_material_of_a_blend_file(blender, tmp_path):
    write_blender({"white": principled_inputs(dict(base_color=[0.8, 0.8, 0.8], metallic=0.0, specular=0.0))},
                  tmp_path / "w.blend")
    r = CliRunner().invoke(main, ["check", "--blender", str(tmp_path / "w.blend"), "--material", "white", "--quick",
                                  "--json"])
    import json

    rep = json.loads(r.stdout)
    assert r.exit_code == 0 and rep["passed"]
    assert rep["results"][1]["figure"] == pytest.approx(0.8, abs=2e-3)     # energy: the furnace reads 0.8


def _cycles_beside_gltf(tmp_path, params, inputs):
    from plausible import registry
    from plausible.blender.looks import compare_cycles

    pytest.importorskip("mitsuba")
    write_blender({"m": inputs}, tmp_path / "m.py")
    return compare_cycles(registry.make("gltf-pbr", **params), {"script": str(tmp_path / "m.py")},
                          angles=(0.0, 120.0, 150.0), res=48)


def test_a_rough_metal_renders_as_bright_as_gltf_pbr_single_scatter(blender, tmp_path):
    # Multiscatter GGX (a new node's default) made it 1.2x brighter than gltf-pbr's single scattering
    p = dict(base_color=[0.9, 0.9, 0.9], metallic=1.0, roughness=0.6)
    lk = _cycles_beside_gltf(tmp_path, p, principled_inputs(p))
    np.testing.assert_allclose(lk.highlight_ratios, 1.0, atol=0.03)


def test_a_plastic_keeps_gltfs_schlick_highlight_at_60_degrees(blender, tmp_path):
    # the Principled dielectric's exact Fresnel (IOR 1.5) is 1.25x Schlick's F0 = 0.04 at 60 degrees
    # (the 120-degree view's mirror pair); glTF's formula as nodes keeps Schlick's
    p = dict(base_color=[0.5, 0.1, 0.1], metallic=0.0, roughness=0.35)
    lk = _cycles_beside_gltf(tmp_path, p, blender_material(p))
    np.testing.assert_allclose(lk.highlight_ratios, 1.0, atol=0.03)
    one = _cycles_beside_gltf(tmp_path, p, blender_material(p, nodes="principled"))
    assert one.highlight_ratios[1] > 1.15 and lk.flip < one.flip


class TestSourceLobes:
    def test_a_cook_torrance_fit_is_written_as_its_own_lobes(self):
        from plausible.conversion import read_sources
        from plausible.spectra import luminance

        model = read_sources("material:gold-metallic-paint@ngan2005/cook-torrance")[0].model
        rd, w = model.parts[0].params["rd"], np.asarray(model.scales[1])
        ct = model.parts[1].params
        g = blender_material({}, "source", model)["ct_nodes"]
        np.testing.assert_allclose(g["rd"], rd, rtol=1e-12)
        (lobe,) = g["lobes"]
        # w F_schlick = w rs + w (1 - rs)(1 - cos)^5: the constant part per channel, the rise's luminance
        np.testing.assert_allclose(lobe["colour"], w * ct["rs"], rtol=1e-12)
        assert lobe["grazing"] == pytest.approx(float(luminance(w * (1 - ct["rs"]))), rel=1e-12)
        assert lobe["roughness"] ** 2 == pytest.approx(ct["m"], rel=1e-12)      # Cycles: alpha = roughness^2

    def test_an_mtl_highlight_is_a_glossy_lobe_without_fresnel_and_others_take_the_gltf_fit(self, tmp_path):
        from plausible import registry
        from plausible.conversion import read_sources

        (tmp_path / "p.mtl").write_text(RED_PLASTIC)
        g = blender_material({}, "source", read_sources(str(tmp_path / "p.mtl"))[0].model)["ct_nodes"]
        assert g["rd"] == [0.5, 0.1, 0.1] and g["lobes"][0]["colour"] == [0.04, 0.04, 0.04]
        assert g["lobes"][0]["grazing"] == 0.0                                   # F = rs: no Fresnel rise
        ward = registry.make("ward", alpha_x=0.2, alpha_y=0.2)
        assert "ct_nodes" not in blender_material(dict(metallic=0.0), "source", ward)
        assert "gltf_nodes" in blender_material(dict(metallic=0.0), "source", ward)


RED_PLASTIC = "newmtl red_plastic\nKd 0.5 0.1 0.1\nKs 0.04 0.04 0.04\nNs 200\nillum 2\n"


def test_an_mtl_plastic_written_as_its_own_lobes_renders_like_its_source(blender, tmp_path):
    # the glTF fit made this plastic a metal (highlight 0.66x at 0 degrees, 1.66x at 150; FLIP 0.385);
    # its own lobes (Diffuse + Beckmann Glossy) render like it: FLIP at the floor, highlight 1
    from plausible.blender.looks import FLIP_TOL, compare_cycles
    from plausible.conversion import read_sources

    pytest.importorskip("mitsuba")
    (tmp_path / "p.mtl").write_text(RED_PLASTIC)
    model = read_sources(str(tmp_path / "p.mtl"))[0].model
    write_blender({"p": blender_material({}, "source", model)}, tmp_path / "p.py")
    lk = compare_cycles(model, {"script": str(tmp_path / "p.py")}, angles=(0.0, 120.0, 150.0), res=48)
    np.testing.assert_allclose(lk.highlight_ratios, 1.0, atol=0.05)
    assert lk.flip < FLIP_TOL


@pytest.mark.slow
def test_convert_to_blender_table_names_what_was_written(blender, tmp_path, monkeypatch):
    # the CLI's table (not --json): an MTL plastic written as its own lobes, verified in Cycles (about 40 s)
    (tmp_path / "p.mtl").write_text(RED_PLASTIC)
    import plausible.cli

    monkeypatch.setattr(plausible.cli.console, "width", 250)   # one line a row whatever the runner's terminal
    r = CliRunner().invoke(main, ["convert", str(tmp_path / "p.mtl"), "--to", "blender", "--out",
                                  str(tmp_path / "p.py")], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    assert "source's lobes: Diffuse (0.5, 0.1, 0.1)" in r.output.replace("\n", "")


ANISO = dict(base_color=[0.9, 0.9, 0.9], metallic=1.0, roughness=0.3, anisotropy_strength=0.7)


def _aniso(tmp_path, rotation, spp):
    from plausible import registry
    from plausible.blender.looks import compare_cycles

    pytest.importorskip("mitsuba")
    write_blender({"m": blender_material(dict(ANISO, anisotropy_rotation=rotation))}, tmp_path / f"m{rotation}.py")
    return compare_cycles(registry.make("gltf-pbr", **ANISO), {"script": str(tmp_path / f"m{rotation}.py")},
                          angles=(0.0, 60.0, 150.0), res=48, spp=spp)


def test_an_anisotropic_metal_renders_like_gltf_pbr_and_a_turned_one_does_not(blender, tmp_path):
    # the Cycles sphere's UV tangent is Mitsuba's sphere's dp/du, so the anisotropy's ratio (Anisotropic) and
    # direction (Anisotropic Rotation, the Tangent node) are compared in the image; a quarter turn fails
    from plausible.blender.looks import check_looks

    same, turned = _aniso(tmp_path, 0.0, 16), _aniso(tmp_path, math.pi / 2, 16)
    np.testing.assert_allclose(same.highlight_ratios, 1.0, atol=0.05)
    assert not check_looks(turned).passed and turned.flip > 5 * same.flip


@pytest.mark.slow
def test_an_anisotropic_metal_passes_the_look_check_at_64_spp(blender, tmp_path):
    # a glossy lobe's Monte Carlo noise: at 16 spp FLIP 0.052, at the floor's 64 spp it passes (about 20 s)
    from plausible.blender.looks import check_looks

    assert check_looks(_aniso(tmp_path, 0.0, 64)).passed


class TestNodesOption:
    """``convert --to blender --nodes TREE`` (the Python keyword ``nodes=``), docs/blender.md."""

    def test_the_choices_are_the_writers(self):
        from plausible.blender.principled import NODES

        opt = next(p for p in main.commands["convert"].params if p.name == "nodes")
        assert tuple(opt.type.choices) == NODES

    def test_a_bad_tree_exits_2_naming_the_option_and_the_choices(self, tmp_path):
        (tmp_path / "p.mtl").write_text(RED_PLASTIC)
        r = CliRunner().invoke(main, ["convert", str(tmp_path / "p.mtl"), "--to", "blender", "--nodes", "lobes",
                                      "--out", str(tmp_path / "p.py")])
        assert r.exit_code == 2
        assert "--nodes" in r.output and "'lobes' is not one of 'source', 'gltf', 'principled'" in r.output

    def test_nodes_with_another_target_exits_2(self, tmp_path):
        (tmp_path / "p.mtl").write_text(RED_PLASTIC)
        r = CliRunner().invoke(main, ["convert", str(tmp_path / "p.mtl"), "--to", "gltf", "--nodes", "gltf",
                                      "--out", str(tmp_path / "p.gltf")])
        assert r.exit_code == 2 and "--nodes chooses the node tree of --to blender" in r.output

    @pytest.mark.parametrize("given, passed", [([], "source"), (["--nodes", "principled"], "principled")])
    def test_the_choice_reaches_the_writer(self, tmp_path, monkeypatch, given, passed):
        import plausible.blender.convert as bc

        seen = {}

        def fake(source, out, metric, *, nodes, progress):
            seen["nodes"] = nodes
            raise ValueError("out: stop here")

        monkeypatch.setattr(bc, "convert_to_blender", fake)
        r = CliRunner().invoke(main, ["convert", "lambertian", "--to", "blender", "--out", str(tmp_path / "m.py"),
                                      *given])
        assert r.exit_code == 2 and "--out: stop here" in r.output and seen == {"nodes": passed}


@pytest.mark.slow
def test_convert_nodes_principled_writes_the_gltf_fit_not_the_sources_lobes(blender, tmp_path):
    # the MTL plastic (a Lambertian + Blinn lobe) written as one Principled BSDF of its glTF fit (about 40 s)
    import json

    (tmp_path / "p.mtl").write_text(RED_PLASTIC)
    r = CliRunner().invoke(main, ["convert", str(tmp_path / "p.mtl"), "--to", "blender", "--nodes", "principled",
                                  "--out", str(tmp_path / "p.py"), "--json"], catch_exceptions=False)
    assert r.exit_code == 0, r.output
    v = json.loads(r.stdout)[0]
    assert "ct_nodes" not in v["blender"]["inputs"] and "gltf_nodes" not in v["blender"]["inputs"]
    assert v["blender"]["inputs"]["Metallic"] == pytest.approx(v["params"]["metallic"])
