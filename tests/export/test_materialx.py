"""MaterialX (OpenPBR, glTF PBR) and USD (UsdPreviewSurface) output of glTF-shaped materials: the
documents MaterialX's own ``validate()`` accepts, the parameter mapping against closed forms, the USD
read back (``docs/materialx.md``).  The shaders run in the browser: ``test_materialx_glsl.py``."""

from __future__ import annotations

import math

import numpy as np
import pytest

from plausible.models.gltf_pbr import ior_f0

pytest.importorskip("MaterialX")
from plausible.export.materialx import (check_materialx, ior_of_f0, materialx_document,  # noqa: E402
                                        materialx_text, open_pbr_anisotropy, open_pbr_inputs, read_materialx)

MATERIALS = {"gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3},
             "red plastic": {"base_color": [0.5, 0.1, 0.1], "metallic": 0.0, "roughness": 0.4,
                             "specular": 0.7, "specular_color": [1.0, 0.5, 2.0],
                             "anisotropy_strength": 0.6, "anisotropy_rotation": 0.5},
             "glass": {"base_color": [0.9, 0.95, 1.0], "metallic": 0.0, "roughness": 0.01}}
SURFACES = {"gold": {"alpha": 0.5, "emissive": [2.0, 1.0, 0.0]}, "glass": {"transmission": 1.0, "ior": 1.45}}


def _document():
    return materialx_document(MATERIALS, textures={"red plastic": "tex/wood 2.png"}, surfaces=SURFACES)


def _inputs(text, node):
    doc = read_materialx(text)          # held: MaterialX elements die with their document
    n = doc.getChild(node)
    return {i.getName(): i.getValue() for i in n.getInputs()}


def test_every_material_s_openpbr_and_gltf_pbr_validate_in_materialx():
    text = materialx_text(MATERIALS, textures={"red plastic": "tex/wood 2.png"}, surfaces=SURFACES)
    doc = read_materialx(text)
    assert check_materialx(text) == []
    assert sorted(m.getName() for m in doc.getMaterialNodes()) == [
        "glass_OpenPBR", "glass_glTF", "gold_OpenPBR", "gold_glTF", "red_plastic_OpenPBR", "red_plastic_glTF"]


@pytest.mark.parametrize("break_it", [
    lambda t: t.replace('name="specular_roughness"', 'name="specular_roughnes"'),         # no such input
    lambda t: t.replace('name="base_metalness" type="float"', 'name="base_metalness" type="color3"'),
    lambda t: t.replace('nodename="gold_gltf_pbr"', 'nodename="no_such_shader"')])      # a dangling material
def test_check_materialx_rejects_a_broken_document(break_it):
    text = materialx_text(MATERIALS, surfaces=SURFACES)
    broken = break_it(text)
    assert broken != text and check_materialx(broken) != []


def test_the_openpbr_anisotropy_gives_the_gltf_alphas_exactly():
    for r in (0.05, 0.3, 0.7, 1.0):
        for s in (0.0, 0.2, 0.6, 1.0):
            ro, a = open_pbr_anisotropy(r, s)
            at = ro ** 2 * math.sqrt(2.0 / (1.0 + (1.0 - a) ** 2))      # the OpenPBR specification's
            assert at == pytest.approx(r * r + (1 - r * r) * s * s, rel=1e-12)
            assert (1.0 - a) * at == pytest.approx(r * r, rel=1e-12)


def test_ior_of_f0_inverts_the_f0_of_an_ior():
    for ior in (1.0, 1.2, 1.5, 2.4, 10.0):
        assert ior_of_f0(float(ior_f0(ior))) == pytest.approx(ior, rel=1e-12)


def test_the_written_openpbr_reflects_the_gltf_f0_at_normal_incidence_per_channel():
    inputs = _inputs(materialx_text(MATERIALS), "red_plastic_open_pbr_surface")
    f0 = inputs["specular_weight"] * float(ior_f0(inputs["specular_ior"])) * np.asarray(inputs["specular_color"])
    want = 0.7 * np.minimum(0.04 * np.array([1.0, 0.5, 2.0]), 1.0)           # glTF: min(0.04 sc, 1) specular
    assert np.allclose(f0, want, rtol=1e-7)


def test_the_gltf_pbr_node_takes_the_model_parameters_as_they_are():
    inputs = _inputs(materialx_text(MATERIALS), "red_plastic_gltf_pbr")
    assert inputs["specular"] == pytest.approx(0.7) and list(inputs["specular_color"]) == [1.0, 0.5, 2.0]
    assert inputs["anisotropy_rotation"] == pytest.approx(0.5) and inputs["ior"] == 1.5


def test_a_metal_keeps_openpbr_s_specular_at_schlick_s_curve_and_surfaces_map():
    o, warn = open_pbr_inputs(MATERIALS["gold"], SURFACES["gold"])
    assert o["specular_weight"] == 1.0 and o["specular_color"] == [1.0, 1.0, 1.0] and warn == []
    assert o["geometry_opacity"] == 0.5 and o["emission_color"] == [1.0, 0.5, 0.0] and o["emission_luminance"] == 2.0
    g, _ = open_pbr_inputs(MATERIALS["glass"], SURFACES["glass"])
    assert g["transmission_weight"] == 1.0 and g["specular_ior"] == pytest.approx(1.45)


def test_a_coloured_specular_is_warned_inexact_at_grazing():
    assert any("grazing" in w for w in open_pbr_inputs(MATERIALS["red plastic"])[1])


def test_the_texture_is_an_srgb_image_times_the_base_colour():
    doc = read_materialx(materialx_text(MATERIALS, textures={"red plastic": "tex/wood 2.png"}))
    img = doc.getChild("red_plastic_map_Kd")
    f = img.getInput("file")
    assert f.getValueString() == "tex/wood 2.png" and f.getColorSpace() == "srgb_texture"
    mul = doc.getChild("red_plastic_base_color")
    assert mul.getInput("in1").getNodeName() == "red_plastic_map_Kd"
    assert list(mul.getInput("in2").getValue()) == pytest.approx([0.5, 0.1, 0.1])
    for shader in ("red_plastic_open_pbr_surface", "red_plastic_gltf_pbr"):
        assert doc.getChild(shader).getInput("base_color").getNodeName() == "red_plastic_base_color"


def test_the_anisotropy_rotation_turns_the_openpbr_tangent_about_the_normal():
    doc = read_materialx(materialx_text(MATERIALS))
    rot = doc.getChild("red_plastic_rotated_tangent")
    assert rot.getInput("amount").getValue() == pytest.approx(-math.degrees(0.5))      # rotate3d turns clockwise
    assert rot.getInput("axis").getNodeName() == "red_plastic_normal"
    assert doc.getChild("red_plastic_open_pbr_surface").getInput("geometry_tangent").getNodeName() == rot.getName()


def test_a_bad_parameter_names_the_material_and_the_parameter():
    with pytest.raises(ValueError, match="'bad'.*roughness"):
        materialx_document({"bad": {"roughness": 2.0}})
