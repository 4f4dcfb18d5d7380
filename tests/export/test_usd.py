"""USD output (UsdPreviewSurface, usd-core): written, read back, checked (``docs/materialx.md``)."""

from __future__ import annotations

import numpy as np
import pytest

from plausible.models.gltf_pbr import ior_f0

pytest.importorskip("pxr")
from plausible.export.usd import check_usd, preview_inputs, read_usd_materials, usd_text  # noqa: E402

MATERIALS = {"gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3},
             "grey plastic": {"base_color": [0.5, 0.5, 0.5], "metallic": 0.0, "roughness": 0.4,
                              "specular_color": [2.0, 2.0, 2.0]},
             "red plastic": {"base_color": [0.5, 0.1, 0.1], "metallic": 0.0, "roughness": 0.4,
                             "specular_color": [1.0, 0.5, 0.25], "anisotropy_strength": 0.5}}


def _written(tmp_path, **kw):
    path = tmp_path / "out.usda"
    path.write_text(usd_text(MATERIALS, **kw))
    return path


def test_the_preview_surfaces_read_back_with_the_gltf_values(tmp_path):
    back = read_usd_materials(_written(tmp_path))
    assert sorted(back) == ["gold", "grey_plastic", "red_plastic"] and check_usd(tmp_path / "out.usda") == []
    gold = back["gold"]
    assert gold["id"] == "UsdPreviewSurface" and gold["useSpecularWorkflow"] == 0
    assert np.allclose(gold["diffuseColor"], [1.0, 0.77, 0.34]) and gold["metallic"] == 1.0
    assert gold["roughness"] == pytest.approx(0.3)


def test_a_grey_specular_is_the_ior_of_the_gltf_f0(tmp_path):
    grey = read_usd_materials(_written(tmp_path))["grey_plastic"]
    assert float(ior_f0(grey["ior"])) == pytest.approx(0.08, rel=1e-6)      # min(0.04 * 2, 1)


def test_a_coloured_dielectric_f0_is_the_specular_workflow_s_colour(tmp_path):
    red = read_usd_materials(_written(tmp_path))["red_plastic"]
    assert red["useSpecularWorkflow"] == 1 and np.allclose(red["specularColor"], [0.04, 0.02, 0.01])
    assert any("anisotropy" in w for w in preview_inputs(MATERIALS["red plastic"])[1])


def test_a_texture_is_an_srgb_uv_texture_scaled_by_the_base_colour(tmp_path):
    from pxr import Usd, UsdShade

    path = _written(tmp_path, textures={"gold": "tex/gold.png"})
    assert read_usd_materials(path)["gold"]["diffuseColor"] == ("connected", "/Materials/gold/map_Kd")
    stage = Usd.Stage.Open(str(path))          # held: a prim is valid while its stage lives
    tex = UsdShade.Shader(stage.GetPrimAtPath("/Materials/gold/map_Kd"))
    assert tex.GetInput("sourceColorSpace").Get() == "sRGB" and tex.GetInput("file").Get().path == "tex/gold.png"
    assert np.allclose(tex.GetInput("scale").Get(), [1.0, 0.77, 0.34, 1.0])


@pytest.mark.parametrize("old, new", [('float inputs:roughness = 0.3', 'float inputs:roughness = 1.5'),
                                      ('info:id = "UsdPreviewSurface"', 'info:id = "UsdUVTexture"'),
                                      ('float inputs:ior = 1.5', 'float inputs:ior = 0.5')])
def test_check_usd_rejects_a_broken_file(tmp_path, old, new):
    path = _written(tmp_path)
    text = path.read_text()
    assert old in text
    path.write_text(text.replace(old, new, 1))
    assert check_usd(path) != []
