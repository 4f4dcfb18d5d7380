"""``plausible convert --to materialx`` and ``--to usd`` of an MTL material and of a published fit
(issue 46, item 3): the written ``.mtlx`` passes MaterialX's own ``validate()``, the ``.usda`` reads back
through ``usd-core`` with the values of the fit, and the report names the target asked for, the model
fitted beside it (``docs/materialx.md``).  The glTF fit of a published fit takes about 8 s: slow."""

import json
import re

import numpy as np
import pytest

from plausible.conversion import convert

pytest.importorskip("MaterialX")
pytest.importorskip("pxr")
from plausible.export.materialx import check_materialx, read_materialx  # noqa: E402
from plausible.export.usd import check_usd, read_usd_materials  # noqa: E402

#: A Lambertian MTL material (its fit is exact, so fast) with a texture and an opacity.
WOOD = "newmtl old wood\nKd 0.6 0.5 0.4\nillum 1\nd 0.5\nmap_Kd tex/wood.png\n"
#: A published fit (Ngan et al. 2005, Cook-Torrance) and a glossy MTL material (Phong lobe).
SLOW_SOURCES = ["material:gold-metallic-paint@ngan2005/cook-torrance", "{tmp}/lib.mtl"]
GLOSSY = "newmtl glossy-red\nKd 0.35 0.05 0.05\nKs 0.6 0.6 0.6\nNs 100\nillum 2\n"


def _cli(*args):
    from click.testing import CliRunner

    from plausible.cli import main

    return CliRunner().invoke(main, ["convert", *map(str, args)])


@pytest.fixture
def wood(tmp_path):
    (tmp_path / "lib.mtl").write_text(WOOD)
    return tmp_path / "lib.mtl"


def _inputs(text, node):
    doc = read_materialx(text)          # held: MaterialX elements die with their document
    return {i.getName(): (i.getValue(), i.getNodeName()) for i in doc.getChild(node).getInputs()}


def test_an_mtl_material_converted_to_materialx_and_usd_validates_with_its_values(wood, tmp_path):
    (tmp_path / "out").mkdir()
    text = convert(str(wood), to="materialx", looks=False).write(tmp_path / "out" / "wood.mtlx").read_text()
    assert check_materialx(text) == []
    g = _inputs(text, "old_wood_gltf_pbr")
    assert g["base_color"][1] == "old_wood_base_color" and g["alpha"][0] == pytest.approx(0.5)
    doc = read_materialx(text)
    assert doc.getChild("old_wood_map_Kd").getInput("file").getValueString() == "../tex/wood.png"
    assert list(doc.getChild("old_wood_base_color").getInput("in2").getValue()) == pytest.approx([0.6, 0.5, 0.4])
    usd = convert(str(wood), to="usd", looks=False).write(tmp_path / "wood.usda")
    back = read_usd_materials(usd)["old_wood"]
    assert check_usd(usd) == [] and back["diffuseColor"] == ("connected", "/Materials/old_wood/map_Kd")
    assert back["opacity"] == pytest.approx(0.5)


@pytest.mark.parametrize("to", ["materialx", "usd"])
def test_the_report_names_the_target_asked_for_and_the_model_fitted(wood, tmp_path, to):
    c = convert(str(wood), to=to, looks=False).items[0]
    assert (c.target, c.model, c.label) == (to, "gltf-pbr", f"{to} (gltf-pbr fit)")
    r = _cli(wood, "--to", to, "--out", tmp_path / ("x.mtlx" if to == "materialx" else "x.usda"), "--json")
    assert r.exit_code == 0, r.output
    row = json.loads(r.output)[0]
    assert (row["target"], row["model"]) == (to, "gltf-pbr")


def test_a_gltf_conversion_keeps_its_target_name(wood):
    c = convert(str(wood), to="gltf", looks=False).items[0]
    assert (c.target, c.model, c.label) == ("gltf", "gltf-pbr", "gltf")


@pytest.mark.slow
@pytest.mark.parametrize("source", SLOW_SOURCES)
def test_a_published_fit_and_a_glossy_mtl_validate_as_materialx_and_usd(tmp_path, source):
    (tmp_path / "lib.mtl").write_text(GLOSSY)
    spec = source.format(tmp=tmp_path)
    res = convert(spec, to="materialx", looks=False)
    text = res.write(tmp_path / "out.mtlx").read_text()
    assert check_materialx(text) == []
    c = res.items[0]
    key = re.sub(r"[^A-Za-z0-9_]", "_", c.name)         # the name as MaterialX and USD names hold it
    g = _inputs(text, f"{key}_gltf_pbr")
    assert np.allclose(g["base_color"][0], c.params["base_color"], rtol=1e-7)          # the fit, as written
    assert g["roughness"][0] == pytest.approx(c.params["roughness"], rel=1e-7)
    assert g["metallic"][0] == pytest.approx(c.params["metallic"], rel=1e-7, abs=1e-12)
    usd = convert(spec, to="usd", looks=False).write(tmp_path / "out.usda")
    back = read_usd_materials(usd)[key]
    assert check_usd(usd) == [] and np.allclose(back["diffuseColor"], c.params["base_color"], rtol=1e-6)
    assert back["roughness"] == pytest.approx(c.params["roughness"], rel=1e-6)
