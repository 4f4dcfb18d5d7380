"""The output files of ``plausible convert`` (issue 32): a bad ``--out`` refused before any
fitting, a file written whole or not at all (a write that fails half-way, a Ctrl-C), an MTL's
texture names read past their options, and its textures referenced from the ``.gltf`` (which
the Khronos validator then checks, images included) and the Mitsuba XML, relative to wherever
the output is written."""

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import plausible.conversion as conversion
from plausible.conversion.mtl import read_mtl, texture_file
from plausible.text import write_atomic

ROOT = Path(__file__).resolve().parents[2]


def _cli(*args):
    from click.testing import CliRunner

    from plausible.cli import main

    return CliRunner().invoke(main, ["convert", *map(str, args)])


@pytest.mark.parametrize("out, words", [
    ("{tmp}/no/such/folder/out.json", "--out: the folder of"),
    ("{tmp}/out.gltf", "--out: a .gltf file holds glTF materials"),
    ("{tmp}/out.txt", "--out: the output file must end in .json, .xml or .gltf")])
def test_a_bad_output_is_refused_before_anything_is_converted(tmp_path, monkeypatch, out, words):
    def never(*a, **k):
        raise AssertionError("convert was called before --out was checked")

    monkeypatch.setattr(conversion, "convert", never)
    r = _cli("lambertian:rd=0.5", "--to", "mitsuba", "--out", out.format(tmp=tmp_path))
    assert r.exit_code == 2 and words in r.output, r.output
    assert "Traceback" not in r.output and list(tmp_path.iterdir()) == []


def test_write_atomic_leaves_the_old_file_when_interrupted(tmp_path, monkeypatch):
    path = tmp_path / "out.json"
    path.write_text("old")

    def interrupted(src, dst):
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "replace", interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(path, "new " * 1000)
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["out.json"]


# A write that fails half-way (here: the file size limit, as a full disk would): the output
# must keep its old content, with no temporary file beside it, and the error name --out.
_HALF_WAY = """
import resource, signal, sys
from plausible.conversion import Conversion, Converted
signal.signal(signal.SIGXFSZ, signal.SIG_IGN)          # a write past the limit fails with EFBIG
resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))
items = [Converted(f"m{k}", "lambertian", "mitsuba:diffuse",
                   {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}},
                   {}, {}, result={"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.5, 0.5]}})
         for k in range(300)]
try:
    Conversion("mitsuba", "perceptual", items).write(sys.argv[1])
except ValueError as e:
    print(e)
"""


@pytest.mark.skipif(sys.platform == "win32", reason="RLIMIT_FSIZE is POSIX")
def test_a_write_that_fails_half_way_leaves_no_half_written_file(tmp_path):
    path = tmp_path / "out.json"
    path.write_text("old")
    env = {**os.environ, "PYTHONPATH": str(ROOT / "src")}
    r = subprocess.run([sys.executable, "-c", _HALF_WAY, str(path)], capture_output=True, text=True, env=env,
                       timeout=120)
    assert r.returncode == 0, r.stderr
    assert f"out: cannot write {str(path)!r}: File too large" in r.stdout
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["out.json"]


@pytest.mark.parametrize("line, name", [("wood.png", "wood.png"), ("-s 1 1 1 wood.png", "wood.png"),
                                        ("-o 0.5 tex/wood.png", "tex/wood.png"), ("-bm 0.3 bump.png", "bump.png"),
                                        ("-clamp on -mm 0 1 -imfchan r my wood.png", "my wood.png"),
                                        ("-s 1 -1 x.png", "x.png"), ("-12.png", "-12.png"), ("-s 1 1 1", "")])
def test_a_texture_statements_file_name_follows_its_options(line, name):
    assert texture_file(line.split()) == name


def test_a_texture_statement_without_a_file_is_refused_naming_the_line(tmp_path):
    (tmp_path / "lib.mtl").write_text("newmtl m\nKd 0.5 0.5 0.5\nmap_Kd -s 1 1 1\n")
    with pytest.raises(ValueError, match=r"lib.mtl:3 \(material 'm'\): map_Kd needs a file name"):
        read_mtl(tmp_path / "lib.mtl")


TEXTURED = """newmtl wood
Kd 0.6 0.4 0.2
illum 1
map_Kd -s 1 1 1 tex/wood.png
bump bump.png
newmtl painted
Kd 0.2 0.3 0.7
illum 1
map_Kd my paint.png
newmtl stone
Kd 0.5 0.5 0.5
illum 1
map_Kd -o 0 0 0 tex/wood.png
newmtl plain
Kd 0.3 0.3 0.3
illum 1
"""


@pytest.fixture(scope="module")
def textured(tmp_path_factory):
    """An MTL library with textures (one shared, one with a space in its name), the images beside it."""
    import matplotlib.pyplot as plt

    src = tmp_path_factory.mktemp("mtl")
    (src / "tex").mkdir()
    (src / "lib.mtl").write_text(TEXTURED)
    for k, name in enumerate(["tex/wood.png", "my paint.png"]):
        plt.imsave(src / name, np.random.default_rng(k).random((8, 8, 3)))
    return src


def _validator():
    import importlib.util

    spec = importlib.util.spec_from_file_location("gltf_validator", ROOT / "tests" / "export" / "gltf_validator.py")
    gv = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(gv)
    return gv


def test_the_gltf_of_a_textured_mtl_references_its_textures_from_anywhere(textured, tmp_path):
    gv = _validator()
    gv.require()
    res = conversion.convert(str(textured / "lib.mtl"), to="gltf")
    for where in (textured, tmp_path / "elsewhere"):
        where.mkdir(exist_ok=True)
        path = res.write(where / "out.gltf")
        doc = json.loads(path.read_text())
        rel = Path(os.path.relpath(textured, where))
        assert [im["uri"] for im in doc["images"]] == [(rel / "tex/wood.png").as_posix(),
                                                       (rel / "my%20paint.png").as_posix()]
        mats = {m["name"]: m["pbrMetallicRoughness"] for m in doc["materials"]}
        tex = {k: doc["textures"][m["baseColorTexture"]["index"]]["source"] for k, m in mats.items()
               if "baseColorTexture" in m}
        assert tex == {"wood": 0, "painted": 1, "stone": 0}          # one image per file
        # texture coordinates only where a material reads a texture
        att = {m["name"]: set(m["primitives"][0]["attributes"]) for m in doc["meshes"]}
        assert att["plain"] == {"POSITION", "NORMAL"} and att["wood"] == {"POSITION", "NORMAL", "TEXCOORD_0"}
        issues = gv.validate(path)["issues"]              # the validator reads the images too
        assert issues["numErrors"] == 0 and issues["numWarnings"] == 0, issues["messages"]
    # a missing image is an error the validator reports: the check above reads them
    (textured / "my paint.png").rename(textured / "gone.png")
    try:
        issues = gv.validate(res.write(tmp_path / "broken.gltf"))["issues"]
        assert ("IO_ERROR", "/images/1/uri") in [(m["code"], m["pointer"]) for m in issues["messages"]]
    finally:
        (textured / "gone.png").rename(textured / "my paint.png")
    notes = {c.name: c.notes for c in res.items}
    assert any("baseColorTexture" in n for n in notes["wood"])
    # a bump map a glTF cannot take is dropped with a warning (issue 41: a note before)
    assert any("bump bump.png: dropped, carried by reference only" in w for w in res.items[0].warnings)


def test_the_mitsuba_xml_of_a_textured_mtl_loads_from_anywhere(textured, tmp_path):
    mi = pytest.importorskip("mitsuba")
    from plausible.analysis.mitsuba_bsdf import ensure_variant

    ensure_variant()
    res = conversion.convert(str(textured / "lib.mtl"), to="mitsuba")
    assert res.items[0].params["reflectance"] == {"type": "bitmap", "filename": "tex/wood.png"}   # the report: as read
    path = res.write(tmp_path / "out.xml")
    # Kd x map_Kd baked beside the output (issue 41), the shared texture referenced relative to it
    assert '<string name="filename" value="out.wood.map_Kd.png"/>' in path.read_text()
    assert (tmp_path / "out.wood.map_Kd.png").is_file()
    mi.load_file(str(path))                                  # every bitmap found relative to the file


def test_out_dash_writes_the_files_text_to_standard_output(tmp_path):
    # the convention of every command (README): --out - writes to standard output; before, refused
    r = _cli("lambertian:rd=0.5,0.4,0.3", "--to", "mitsuba:diffuse", "--out", "-")
    assert r.exit_code == 0, r.output
    assert json.loads(r.output) == {"lambertian": {"type": "diffuse", "reflectance": {
        "type": "rgb", "value": pytest.approx([0.5, 0.4, 0.3], abs=1e-6)}}}
    r = _cli("lambertian:rd=0.5", "--to", "mitsuba", "--out", "-", "--json")
    assert r.exit_code == 2 and "--out - and --json both write to standard output" in r.output


@pytest.mark.parametrize("to, suffix", [("materialx", ".mtlx"), ("usd", ".usda")])
def test_convert_to_materialx_and_usd_writes_a_file_its_checker_accepts(tmp_path, to, suffix):
    pytest.importorskip("MaterialX")
    pytest.importorskip("pxr")
    from plausible.export.materialx import check_materialx
    from plausible.export.usd import check_usd, read_usd_materials

    out = tmp_path / f"out{suffix}"
    r = _cli("lambertian:rd=0.25", "--to", to, "--out", out)
    assert r.exit_code == 0, r.output
    if to == "materialx":
        assert check_materialx(out.read_text()) == [] and 'name="base_color" type="color3" value="0.25, 0.25, 0.25"' in out.read_text()
    else:
        assert check_usd(out) == [] and np.allclose(read_usd_materials(out)["lambertian"]["diffuseColor"], 0.25)


@pytest.mark.parametrize("to, out, words", [("gltf", "x.mtlx", "a .mtlx file holds MaterialX materials"),
                                            ("materialx", "x.usda", "a .usda file holds USD materials")])
def test_a_mtlx_or_usda_output_needs_its_target(tmp_path, to, out, words):
    r = _cli("lambertian:rd=0.5", "--to", to, "--out", tmp_path / out)
    assert r.exit_code == 2 and words in r.output and list(tmp_path.iterdir()) == [], r.output
