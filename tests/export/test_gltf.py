"""The glTF writer (:mod:`plausible.export.gltf`): the file holds each material's factors as
given, its sphere is a closed outward-facing unit sphere, and the Khronos validator finds no
error or warning in it -- while it reports errors in files broken on purpose."""

from __future__ import annotations

import base64
import json

import numpy as np
import pytest

from gltf_validator import validate

import plausible
from plausible.export.gltf import gltf_document, sphere, write_gltf

MATERIALS = {
    "gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3},
    "blue plastic": {"base_color": [0.1, 0.3, 0.8], "roughness": 0.5, "specular": 0.5,
                     "specular_color": [1.0, 2.0, 1.0]},
    "brushed": {"base_color": 0.9, "metallic": 1.0, "roughness": 0.25, "anisotropy_strength": 0.6,
                "anisotropy_rotation": 1.0},
}


def arrays(doc):
    """Every accessor of ``doc`` read back from its embedded buffer."""
    blob = base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1])
    out = []
    for a in doc["accessors"]:
        v = doc["bufferViews"][a["bufferView"]]
        dt = np.uint16 if a["componentType"] == 5123 else np.float32
        width = {"SCALAR": 1, "VEC3": 3, "VEC4": 4}[a["type"]]
        out.append(np.frombuffer(blob, dt, a["count"] * width, v["byteOffset"]).reshape(a["count"], width))
    return out


def test_each_material_is_written_with_its_factors():
    doc = gltf_document(MATERIALS)
    gold, plastic, brushed = doc["materials"]
    assert gold == {"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.77, 0.34, 1.0],
                                                              "metallicFactor": 1.0, "roughnessFactor": 0.3}}
    assert plastic["extensions"] == {"KHR_materials_specular": {"specularFactor": 0.5,
                                                                "specularColorFactor": [1.0, 2.0, 1.0]}}
    assert brushed["pbrMetallicRoughness"]["baseColorFactor"] == [0.9, 0.9, 0.9, 1.0]
    assert brushed["extensions"] == {"KHR_materials_anisotropy": {"anisotropyStrength": 0.6,
                                                                  "anisotropyRotation": 1.0}}
    assert doc["extensionsUsed"] == ["KHR_materials_anisotropy", "KHR_materials_specular"]
    assert [n["name"] for n in doc["nodes"]] == list(MATERIALS)
    assert [m["primitives"][0]["material"] for m in doc["meshes"]] == [0, 1, 2]
    # a model object is written as its parameters
    m = plausible.make("gltf-pbr", **MATERIALS["gold"])
    assert gltf_document({"gold": m})["materials"] == [gold]


def test_the_sphere_is_closed_unit_and_faces_outward():
    pos, nrm, tan, idx = sphere(8, 12)
    np.testing.assert_allclose(np.linalg.norm(pos, axis=1), 1.0, atol=1e-6)
    np.testing.assert_allclose(nrm, pos)
    np.testing.assert_allclose(np.einsum("ij,ij->i", tan[:, :3], nrm), 0.0, atol=1e-6)
    a, b, c = pos[idx[:, 0]], pos[idx[:, 1]], pos[idx[:, 2]]
    cross = np.cross(b - a, c - a)
    assert np.all(np.einsum("ij,ij->i", cross, (a + b + c) / 3) > 0)   # counter-clockwise from outside
    # closed: the triangles' area converges to 4 pi, and their solid angles sum to exactly 4 pi
    area = 0.5 * np.linalg.norm(np.cross(*(np.array(x, float) for x in (b - a, c - a))), axis=1).sum()
    assert 0.9 * 4 * np.pi < area < 4 * np.pi
    num = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = 1 + np.einsum("ij,ij->i", a, b) + np.einsum("ij,ij->i", b, c) + np.einsum("ij,ij->i", c, a)
    assert 2 * np.arctan2(num, den).sum() == pytest.approx(4 * np.pi, rel=1e-5)


def test_the_buffer_holds_the_sphere():
    doc = gltf_document(MATERIALS, rings=6, segments=10)
    pos, nrm, tan, idx = arrays(doc)
    ref = sphere(6, 10)
    for got, want in zip((pos, nrm, tan, idx.reshape(-1, 3)), ref):
        np.testing.assert_array_equal(got, want)
    assert doc["accessors"][0]["min"] == pos.min(0).tolist() and doc["accessors"][0]["max"] == pos.max(0).tolist()
    # only the anisotropic material's mesh carries tangents
    assert ["TANGENT" in m["primitives"][0]["attributes"] for m in doc["meshes"]] == [False, False, True]


@pytest.mark.parametrize("materials,text", [
    ({"x": {"roughness": 0.0}}, "material 'x': GltfPBR: parameter 'roughness' must lie in [0.01, 1]"),
    ({"x": {"shininess": 3}}, "material 'x': GltfPBR: unknown parameter(s) shininess"),
    ({"x": 0.5}, "material 'x': parameters must be a dict"),
    ({}, "materials must be a non-empty dict")])
def test_bad_materials_are_named(materials, text):
    with pytest.raises(ValueError, match=__import__("re").escape(text)):
        gltf_document(materials)


# -- the Khronos validator ----------------------------------------------------------------

def test_the_khronos_validator_finds_no_error_nor_warning(tmp_path):
    path = write_gltf(MATERIALS, tmp_path / "materials.gltf")
    issues = validate(path)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
    # version 2.0.0-dev.3.10 does not know that KHR_materials_anisotropy reads TANGENT: one info
    assert [m["code"] for m in issues["messages"]] == ["UNUSED_MESH_TANGENT"]


def _broken(doc, how):
    if how == "count":           # more positions than the buffer view holds
        doc["accessors"][0]["count"] += 1
    elif how == "index":         # an index past the last vertex
        blob = bytearray(base64.b64decode(doc["buffers"][0]["uri"].split(",", 1)[1]))
        at = doc["bufferViews"][doc["accessors"][3]["bufferView"]]["byteOffset"]
        blob[at:at + 2] = np.uint16(60000).tobytes()
        doc["buffers"][0]["uri"] = "data:application/octet-stream;base64," + base64.b64encode(blob).decode()
    elif how == "factor":        # a factor outside [0, 1]
        doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = 1.5
    elif how == "asset":
        del doc["asset"]
    return doc


@pytest.mark.parametrize("how,code", [("count", "ACCESSOR_TOO_LONG"), ("index", "ACCESSOR_INDEX_OOB"),
                                      ("factor", "VALUE_NOT_IN_RANGE"), ("asset", "UNDEFINED_PROPERTY")])
def test_the_validator_reports_a_broken_file(tmp_path, how, code):
    path = tmp_path / "broken.gltf"
    path.write_text(json.dumps(_broken(gltf_document(MATERIALS, rings=6, segments=10), how)))
    issues = validate(path)["issues"]
    assert issues["numErrors"] > 0
    assert code in [m["code"] for m in issues["messages"] if m["severity"] == 0]


# -- KHR_materials_ior -------------------------------------------------------------------

def _f0(ior):
    return 1.0 if ior == 0 else ((ior - 1) / (ior + 1)) ** 2


@pytest.mark.parametrize("ior,color", [(1.33, [1.0, 0.5, 2.0]), (2.42, 1.0), (1.0, 3.0), (0.0, [0.2, 0.6, 1.0]),
                                       (4.0, 20.0)])
def test_an_ior_material_is_written_with_the_extension_and_read_back_exactly(tmp_path, ior, color):
    from plausible.export.gltf import read_gltf_materials

    given = {"base_color": [0.2, 0.4, 0.6], "roughness": 0.35, "specular": 0.7, "specular_color": color, "ior": ior}
    path = write_gltf({"m": given}, tmp_path / "ior.gltf")
    mat = json.loads(path.read_text())["materials"][0]
    assert mat["extensions"]["KHR_materials_ior"] == {"ior": ior}
    assert np.allclose(mat["extensions"]["KHR_materials_specular"]["specularColorFactor"], color)
    model = read_gltf_materials(path)["m"]
    # the extension's dielectric f0, min(F0(ior) specularColor, 1) specular, written out here: the model's
    # specular_color = that f0 / (0.04 specular) (the equivalence of docs/models/gltf-pbr.md)
    f0 = np.minimum(_f0(ior) * np.broadcast_to(color, (3,)), 1.0) * 0.7
    np.testing.assert_allclose(np.minimum(0.04 * np.broadcast_to(model.params["specular_color"], (3,)), 1) * 0.7,
                               f0, rtol=1e-14)
    issues = validate(path)["issues"]
    assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]


def test_reading_a_file_gives_each_extension_and_the_defaults():
    from plausible.export.gltf import material_model

    m = material_model({"name": "x", "extensions": {"KHR_materials_anisotropy": {"anisotropyStrength": 0.5,
                                                                                 "anisotropyRotation": 4.0}}})
    p = m.params
    assert (p["metallic"], p["roughness"], p["specular"]) == (1.0, 1.0, 1.0)    # glTF's defaults
    assert p["anisotropy_rotation"] == pytest.approx(4.0 - np.pi, abs=1e-15)     # a half turn changes nothing
    for doc in MATERIALS.values():
        back, want = material_model(gltf_document({"m": doc})["materials"][0]), plausible.make("gltf-pbr", **doc)
        wi, wo = np.array([[0.3, 0.1, 0.95], [0.0, 0.6, 0.8]]), np.array([[-0.2, 0.4, 0.89], [0.5, -0.5, 0.71]])
        np.testing.assert_array_equal(back.eval(wi, wo), np.broadcast_to(want.eval(wi, wo).reshape(2, -1), (2, 3)))
    with pytest.raises(ValueError, match=r"material 'bad': KHR_materials_ior: ior must be 0 or lie in \[1, inf\)"):
        material_model({"name": "bad", "extensions": {"KHR_materials_ior": {"ior": 0.5}}})
