"""The gltf-pbr -> Principled BSDF mapping (closed forms) and the written node tree."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

from plausible.blender.principled import node_script, principled_inputs, write_blender
from plausible.cli import main


class TestMapping:
    def test_isotropic_parameters_carry_over_with_ior_level_half_the_specular_factor(self):
        p = principled_inputs(dict(base_color=[0.5, 0.2, 0.1], metallic=0.25, roughness=0.4, specular=0.6,
                                   specular_color=[1.0, 0.9, 0.8]))
        assert p == {"Base Color": [0.5, 0.2, 0.1], "Metallic": 0.25, "Roughness": 0.4, "IOR": 1.5,
                     "Specular IOR Level": 0.3, "Specular Tint": [1.0, 0.9, 0.8]}

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
