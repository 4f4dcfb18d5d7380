"""The Wavefront MTL reader (issue 32): statements, defaults, the plausible reading
(albedo at normal incidence Kd + Ks: the normalisation's closed form) and the
errors of bad input, each naming the statement."""

import numpy as np
import pytest

import plausible
from plausible.conversion import read_sources
from plausible.conversion.mtl import as_model, read_mtl

LIBRARY = """# two materials
newmtl shiny
Ka 0.2 0.2 0.2
Kd 0.5 0.25 0.1
Ks 0.3
Ns 50
illum 2
map_Kd -s 1 1 1 textures/shiny.png
bump shiny_bump.png

newmtl matte
Kd 0.4 0.4 0.4
Ks 0.5 0.5 0.5
illum 1
"""


def write(tmp_path, text, name="lib.mtl"):
    p = tmp_path / name
    p.write_text(text)
    return p


def test_every_newmtl_is_read_in_file_order_with_its_statements(tmp_path):
    shiny, matte = read_mtl(write(tmp_path, LIBRARY))
    assert (shiny.name, matte.name) == ("shiny", "matte")
    assert shiny.Kd.tolist() == [0.5, 0.25, 0.1] and shiny.Ks.tolist() == [0.3, 0.3, 0.3]
    assert (shiny.Ns, shiny.illum, matte.illum) == (50.0, 2, 1)


def test_textures_are_carried_by_reference_and_ka_is_noted(tmp_path):
    shiny = read_mtl(write(tmp_path, LIBRARY))[0]
    assert shiny.texture_files == {"map_Kd": "textures/shiny.png", "bump": "shiny_bump.png"}
    assert any(n.startswith("Ka:") for n in shiny.notes)


def test_illum_2_has_albedo_kd_plus_ks_at_normal_incidence(tmp_path):
    # reciprocal-blinn is normalised to albedo ks at normal incidence (closed form)
    model, spec, _ = as_model(read_mtl(write(tmp_path, LIBRARY))[0])
    a = plausible.albedo(model, [0, 0, 1]).value
    assert np.allclose(a, [0.8, 0.55, 0.4], atol=1e-6)
    assert spec == "lambertian:rd=0.5,0.25,0.1 + reciprocal-blinn:ks=0.3,0.3,0.3:n=50.0"


def test_illum_1_is_lambertian_and_notes_the_unused_ks(tmp_path):
    model, spec, notes = as_model(read_mtl(write(tmp_path, LIBRARY))[1])
    assert spec == "lambertian:rd=0.4,0.4,0.4"
    assert np.allclose(plausible.albedo(model, plausible.direction(np.radians(60))).value, 0.4, atol=1e-6)
    assert any("Ks is unused" in n for n in notes)


def test_the_spec_of_a_reading_builds_the_same_model_again(tmp_path):
    src = read_sources(str(write(tmp_path, LIBRARY)))[0]
    again = read_sources(src.spec)[0].model
    wi, wo = plausible.direction(0.4, 0.1), plausible.direction(0.5, 3.0)
    assert np.allclose(again.eval(wi, wo), src.model.eval(wi, wo), rtol=1e-14)


def test_kd_plus_ks_above_one_is_noted_as_not_conserving(tmp_path):
    m = read_mtl(write(tmp_path, "newmtl hot\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNs 10\nillum 2\n"))[0]
    assert any("not energy conserving" in n for n in as_model(m)[2])


@pytest.mark.parametrize("line, words", [
    ("illum 7", ["illum 7", "0 (", "3 ("]),
    ("illum two", ["illum must be one integer"]),
    ("Ns -3", ["Ns must be one number in [0, 1e+06]", "-3"]),
    ("Ns lots", ["Ns must be one number", "lots"]),
    ("Kd 1.5 0 0", ["Kd must be", "[0, 1]"]),
    ("Ks 0.1 0.2", ["Ks must be one number or three numbers"]),
])
def test_bad_statements_name_the_statement_the_line_and_the_range(tmp_path, line, words):
    p = write(tmp_path, f"newmtl m\n{line}\n")
    with pytest.raises(ValueError) as e:
        read_mtl(p)
    msg = str(e.value)
    assert f"{p}:2 (material 'm')" in msg
    for w in words:
        assert w in msg


def test_a_missing_file_and_a_file_without_materials_are_refused(tmp_path):
    with pytest.raises(ValueError, match="not found"):
        read_mtl(tmp_path / "none.mtl")
    with pytest.raises(ValueError, match="no newmtl"):
        read_mtl(write(tmp_path, "# empty\n"))
    with pytest.raises(ValueError, match="before the first newmtl"):
        read_mtl(write(tmp_path, "Kd 0.5 0.5 0.5\n"))
