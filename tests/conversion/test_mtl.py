"""The Wavefront MTL reader (issue 32): statements, defaults, the plausible reading
(Lambertian plus Blinn 1977's microfacet highlight: its albedo against a 1-D
integral, the specification's highlight times 1 / (N.V), conservation) and the
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


def _normal_incidence_highlight(ns):
    """Albedo at normal incidence of the highlight as read, per unit Ks, by a 1-D integral:
    ``wi = n``, ``h`` at polar angle ``d``, ``wo`` at ``2d``; V-groove ``G = min(1, 2 cos 2d)``;
    ``int D G (wi.h) / cos(theta_i) d omega_h``, ``D = (ns + 2) / (2 pi) cos^ns d``."""
    from scipy import integrate

    g = lambda d: (ns + 2) / (2 * np.pi) * np.cos(d) ** ns * min(1.0, 2 * np.cos(2 * d)) * np.cos(d)  # noqa: E731
    return integrate.quad(lambda d: g(d) * 2 * np.pi * np.sin(d), 0, np.pi / 4, points=[np.pi / 6], limit=200)[0]


def test_illum_2_is_lambertian_plus_blinns_microfacet_highlight(tmp_path):
    model, spec, _ = as_model(read_mtl(write(tmp_path, LIBRARY))[0])
    assert spec == ("lambertian:rd=0.5,0.25,0.1 + cook-torrance:distribution=blinn:m=0.19611613513818404:"
                    "rs=0.3,0.3,0.3:fresnel=none:geometry=vgroove")
    # the albedo at normal incidence: Kd plus Ks times the 1-D integral of D G
    a = plausible.albedo(model, [0, 0, 1]).value
    assert np.allclose(a, np.array([0.5, 0.25, 0.1]) + 0.3 * _normal_incidence_highlight(50.0), atol=1e-6)


def test_the_highlight_is_the_specifications_times_one_over_n_dot_v(tmp_path):
    # MTL: colour = Ks (N.H)^Ns I per light (no N.L), i.e. f (N.L) = Ks (N.H)^Ns k at a normal view,
    # and reciprocity puts the same 1 / (N.V) at every view: f (N.L)(N.V) / (N.H)^Ns is one constant
    # (where the V-groove G is 1: near the peak)
    ns = 40.0
    model, _, _ = as_model(read_mtl(write(tmp_path, f"newmtl m\nKs 0.5 0.5 0.5\nNs {ns}\nillum 2\n"))[0])
    rng = np.random.default_rng(3)
    wi = plausible.direction(rng.uniform(0, 0.5, 40), rng.uniform(0, 2 * np.pi, 40))
    wo = plausible.direction(rng.uniform(0, 0.5, 40), rng.uniform(0, 2 * np.pi, 40))
    h = (wi + wo) / np.linalg.norm(wi + wo, axis=-1, keepdims=True)
    f = np.asarray(model.eval(wi, wo))[:, 0]
    k = f * wi[:, 2] * wo[:, 2] / h[:, 2] ** ns
    assert np.allclose(k, 0.5 * (ns + 2) / (8 * np.pi), rtol=1e-12)
    assert np.allclose(model.eval(wi, wo), model.eval(wo, wi), rtol=1e-14)


@pytest.mark.parametrize("ns", [0.0, 5.0, 30.0, 300.0])
def test_the_highlight_as_read_conserves_energy_and_stays_nearly_flat(tmp_path, ns):
    from plausible.analysis import albedo_curve

    ks = 0.6
    model, _, _ = as_model(read_mtl(write(tmp_path, f"newmtl m\nKs {ks}\nNs {ns}\nillum 2\n"))[0])
    thetas = [0, 30, 45, 60, 75, 85, 89]
    a = np.asarray(albedo_curve(model, thetas_deg=thetas).value)[..., 0].ravel()
    assert a.max() <= ks + 1e-9
    assert a[0] == pytest.approx(ks * _normal_incidence_highlight(ns), abs=1e-6)
    if ns >= 30:
        # nearly flat: within 0.05 of Ks from 0 to 75 degrees; the reciprocal Blinn lobe (the
        # reading without the cosines) is not (it falls as cos^2: 0.08 at 75 degrees for Ns = 30)
        assert np.all(np.abs(a[:5] - ks) < 0.05)
        old = plausible.make(f"reciprocal-blinn:ks={ks}:n={ns}")
        b = np.asarray(albedo_curve(old, thetas_deg=thetas).value).ravel()
        assert not np.all(np.abs(b[:5] - ks) < 0.05) and b[4] < 0.1


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


def test_kd_plus_ks_above_one_is_noted(tmp_path):
    m = read_mtl(write(tmp_path, "newmtl hot\nKd 0.8 0.8 0.8\nKs 0.5 0.5 0.5\nNs 10\nillum 2\n"))[0]
    assert any("exceeds 1: energy conservation is not guaranteed" in n for n in as_model(m)[2])


@pytest.mark.parametrize("line, words", [
    ("illum 11", ["illum must be one of the specification's illumination models 0-10, got 11"]),
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
    with pytest.raises(ValueError, match="no newmtl"):       # a statement but no material
        read_mtl(write(tmp_path, "Kd 0.5 0.5 0.5\n"))


# What real exporters write beside the specification is read, with a note or a warning, not refused
# (an outside run of 37 real files: Mineways' title line, Tinkercad's "illum 0.0", a Cinema 4D "Ni -1"
# and a name defined twice each refused the whole file before).
def test_a_title_line_before_the_first_newmtl_is_noted_and_a_statement_there_warned(tmp_path):
    a, b = read_mtl(write(tmp_path, "Wavefront OBJ material file\nKd 0.2 0.2 0.2\nnewmtl a\nKd 0.5 0.5 0.5\n"
                                    "newmtl b\nKd 0.1 0.1 0.1\n"))
    assert (a.name, b.name, a.Kd.tolist()) == ("a", "b", [0.5, 0.5, 0.5])
    assert any("line 1: 'Wavefront OBJ material file' before the first newmtl" in n for n in a.notes)
    assert any("line 2: 'Kd 0.2 0.2 0.2' before the first newmtl belongs to no material" in w for w in a.warnings)


def test_a_material_defined_twice_keeps_the_first_and_warns(tmp_path):
    ms = read_mtl(write(tmp_path, "newmtl A\nKd 0.5 0.5 0.5\nnewmtl B\nKd 0.1 0.2 0.3\nnewmtl A\nKd 0.9 0 0\n"))
    assert [m.name for m in ms] == ["A", "B"] and ms[0].Kd.tolist() == [0.5, 0.5, 0.5]
    assert any("'A' is defined again at line 5" in w for w in ms[0].warnings) and not ms[1].warnings
    with pytest.raises(ValueError, match=r"lib.mtl:6 \(material 'A'\): Kd must be"):   # its values still checked
        read_mtl(write(tmp_path, "newmtl A\nKd 0.5 0.5 0.5\nnewmtl B\nKd 0.1 0.2 0.3\nnewmtl A\nKd 2 0 0\n"))


@pytest.mark.parametrize("line, illum", [("illum 0.0", 0), ("illum 2.000000", 2), ("ILLUM 1", 1)])
def test_illum_written_as_a_whole_float_or_in_another_case_is_read(tmp_path, line, illum):
    assert read_mtl(write(tmp_path, f"newmtl m\n{line}\n"))[0].illum == illum


def test_illum_that_is_not_whole_is_still_refused(tmp_path):
    with pytest.raises(ValueError, match="illum must be one integer"):
        read_mtl(write(tmp_path, "newmtl m\nillum 2.5\n"))


def test_ni_outside_its_range_is_noted_and_on_glass_replaced_with_a_warning(tmp_path):
    opaque, glass, air = read_mtl(write(tmp_path, "newmtl o\nKd 0.5 0.5 0.5\nNi -1.000000\nillum 2\n"
                                                  "newmtl g\nNi -1\nillum 7\nnewmtl a\nNi 1.0\nillum 4\n"))
    assert any("Ni -1 is outside the specification's range" in n for n in opaque.notes) and not opaque.warnings
    from plausible.conversion.mtl import reading
    assert not reading(opaque).warnings
    r = reading(glass)
    assert r.surface["ior"] == 1.5 and any("Ni -1 (below 1)" in w for w in r.warnings)
    r = reading(air)        # Ni 1: an invisible glass (Sibenik's windows, Blender's glass)
    assert r.surface["ior"] == 1.5 and any("Ni 1 (the index of air" in w for w in r.warnings)
    for bad in ("glass", "12"):
        with pytest.raises(ValueError, match=r"Ni must be one number in \[0, 10\]"):
            read_mtl(write(tmp_path, f"newmtl m\nNi {bad}\n"))


def test_statements_in_another_case_are_read_as_the_specification_spells_them(tmp_path):
    (m,) = read_mtl(write(tmp_path, "newmtl m\nkd 0.5 0.25 0.1\nNS 20\nmap_kd wood.png\nmap_Bump -bm 0.5 n.png\n"))
    assert m.Kd.tolist() == [0.5, 0.25, 0.1] and m.Ns == 20.0
    assert m.textures == {"map_Kd": "wood.png", "map_bump": "-bm 0.5 n.png"}


def test_the_pbr_extension_is_read_as_gltfs_metallic_roughness_brdf(tmp_path):
    # Blender 3.6's export (its io_tests' materials_pbr.mtl): before, Pr and Pm were noted only and
    # the material read from Kd, Ks 0.25 and no Ns: a Lambertian under a broad lobe, metallic 0
    from plausible.conversion.mtl import reading
    text = ("newmtl Mat1\nKd 0.8 0.276449 0.101911\nKs 0.25 0.25 0.25\nillum 3\nPr 0.4\nPm 0.9\nPs 0.06\n"
            "Pc 0\naniso 0.2\nanisor 0\n"
            "newmtl ns\nKd 0.5 0.5 0.5\nNs 98\nPm 0\nnewmtl none\nKd 0.5 0.5 0.5\nPm 1\n"
            "newmtl smooth\nKd 0.5 0.5 0.5\nPr 0\n")
    mat1, ns, none, smooth = (reading(m) for m in read_mtl(write(tmp_path, text)))
    assert mat1.spec == "gltf-pbr:base_color=0.8,0.276449,0.101911:metallic=0.9:roughness=0.4"
    wi, wo = plausible.direction(0.3, 0.0), plausible.direction(0.5, 2.5)
    direct = plausible.make("gltf-pbr", base_color=[0.8, 0.276449, 0.101911], metallic=0.9, roughness=0.4)
    assert np.allclose(mat1.model.eval(wi, wo), direct.eval(wi, wo), rtol=1e-14)
    got = " ".join(mat1.warnings)
    assert "Ps 0.06 (MTL's physically based extension: sheen) is not read" in got and "aniso 0.2" in got
    assert "Pc 0" not in got and "anisor 0" not in got          # zero: no coat, no rotation (noted)
    assert not any(w.startswith(("Pr", "Pm")) for w in mat1.warnings)
    # Pr missing: from Ns (alpha = sqrt(2 / (Ns + 2)) = 0.1414, roughness its root), else Blender's 0.5
    assert ":metallic=0.0:" in ns.spec and float(ns.spec.rsplit("=", 1)[1]) == pytest.approx(0.02 ** 0.25, rel=1e-14)
    assert none.spec.endswith("metallic=1.0:roughness=0.5")
    assert smooth.spec.endswith("roughness=0.01") and any("raised to the model's smallest" in n for n in smooth.notes)


@pytest.mark.parametrize("words, name", [
    ("-s 1 1 1 my wood.png", "my wood.png"),
    ("-colorspace sRGB -o 0.1 diffuse.jpg", "diffuse.jpg"),       # tinyobjloader's option
    ("-imgchan b x.png", "x.png"),                                 # Blender's spelling, not in the table
    ("-imfchan r bumpmap2.jpg -bm 1.5", "bumpmap2.jpg"),           # an option after the name
    ("-clamp on tex.tga -s 2 2", "tex.tga"),
    ("-unknown 3 4 a b.png", "a b.png"),
    ("a -b.png", "a -b.png"),
    ("-bm 0.5", ""),
])
def test_a_texture_statements_file_name_is_what_its_options_leave(words, name):
    from plausible.conversion.mtl import texture_file
    assert texture_file(words.split()) == name


@pytest.mark.parametrize("data, name, note", [
    # older exporters write Windows-1252: an accented name (0xe9) and an ellipsis (0x85, Latin-1's NEL,
    # which str.splitlines would take for a line end); before: refused as not UTF-8
    (b"newmtl caf\xe9 \x85 rouge\nKd 0.5 0.1 0.1\nillum 1\n", "caf\u00e9 \u2026 rouge", "read as Windows-1252"),
    (b"newmtl caf\x81\nKd 0.5 0.1 0.1\nillum 1\n", "caf\x81", "read as Latin-1"),     # 0x81: not Windows-1252
    ("newmtl caf\u00e9\r\nKd 0.5 0.1 0.1\r\nillum 1\r\n".encode("utf-16"), "caf\u00e9", "read as UTF-16"),  # BOM
    ("\ufeffnewmtl caf\u00e9\rKd 0.5 0.1 0.1\rillum 1\r".encode("utf-8"), "caf\u00e9", None)])   # CR line ends
def test_files_in_the_encodings_of_older_exporters_are_read(tmp_path, data, name, note):
    (tmp_path / "lib.mtl").write_bytes(data)
    (m,) = read_mtl(tmp_path / "lib.mtl")
    assert m.name == name and m.Kd.tolist() == [0.5, 0.1, 0.1] and m.illum == 1
    assert any(note in n for n in m.notes) if note else not any("UTF-8" in n for n in m.notes)


def test_a_binary_file_is_refused_as_not_text(tmp_path):
    (tmp_path / "lib.mtl").write_bytes(b"\x89PNG\r\n\x1a\n\x00\x00\x00\rIHDR")
    with pytest.raises(ValueError, match="is not a text file"):
        read_mtl(tmp_path / "lib.mtl")
