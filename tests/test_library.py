"""The material library: the data files, the parser, names, specs and errors."""

import re
from importlib import resources

import numpy as np
import pytest

import plausible
from plausible import registry
from plausible.catalogue import fit_sets as library
from plausible.catalogue.fit_sets import FIT_SETS, Term, parse_line


def test_parsed_parameters_match_the_published_file():
    # the lines as they stand in bbm's fits/ngan_ward.fit and fits/low_cooktorrance_E2.fit
    assert library.terms("alum-bronze", "ngan2005/ward") == (
        Term("Lambertian", {"albedo": [0.0851, 0.0586, 0.0294]}),
        Term("NganWard", {"albedo": [0.0484, 0.0274, 0.0135], "roughness": 0.0357}))
    assert library.terms("alum-bronze", "low2012/cook-torrance-e2") == (
        Term("Lambertian", {"albedo": [0.0804, 0.0633, 0.0455]}),
        Term("LowCookTorrance", {"albedo": [0.06907, 0.05105, 0.03765], "roughness": 0.067645,
                                 "eta": 2.15363}))


@pytest.mark.parametrize("fs", FIT_SETS, ids=lambda f: f.key)
def test_every_line_of_every_file_parses_to_the_numbers_of_its_text(fs):
    text = resources.files("plausible").joinpath("data", "materials", fs.file).read_text()
    lines = [l for l in text.splitlines() if l.strip() and not l.startswith("#")]
    data = library.fit_data(fs.key)
    assert len(data) == len(lines) == (86 if fs.key.startswith("ngan") else 100)
    for line in lines:
        name = line.split(" = ")[0]
        nums = [float(x) for x in re.findall(r"[-+]?\d+\.?\d*(?:e[-+]?\d+)?", line.split(" = ", 1)[1])]
        parsed = [x for t in data[name] for v in t.params.values() for x in np.ravel(v)]
        assert parsed == nums, name


def test_material_is_a_lambertian_plus_the_scaled_lobe():
    m = plausible.material("nickel", fit="ngan2005/ward-duer")
    lam, (ward, scale) = m.parts[0], (m.parts[1], m.scales[1])
    np.testing.assert_array_equal(lam.params["rd"], [0.0388, 0.0291, 0.0159])
    assert (ward.params["variant"], ward.params["alpha_x"]) == ("duer", 0.0424)
    np.testing.assert_array_equal(scale, [0.107, 0.0828, 0.054])


def test_materials_lists_names_with_their_fits():
    mats = plausible.materials()
    assert len(mats) == 100 and list(mats) == sorted(mats)
    assert "ngan2005/ward" in mats["alum-bronze"] and "low2012/cook-torrance-e1" in mats["alum-bronze"]
    assert len(plausible.materials("ngan2005/he")) == 86


def test_material_specs_work_wherever_a_model_spec_goes():
    a = registry.make_from_spec("material:alum-bronze@ngan2005/ward")
    b = registry.make_from_spec("material:name=alum-bronze:fit=ngan2005/ward")
    wi, wo = [0.3, 0.1, 0.9], [-0.3, -0.1, 0.9]
    np.testing.assert_array_equal(a.eval(wi, wo), b.eval(wi, wo))
    assert repr(registry.make_from_spec("material:nickel")) == repr(plausible.material("nickel"))


def test_unknown_names_get_the_closest_matches():
    with pytest.raises(ValueError, match=r"unknown material 'alum-bronz'.*did you mean alum-bronze"):
        plausible.material("alum-bronz")
    with pytest.raises(ValueError, match=r"unknown fit 'ngan2005/wrd'.*did you mean ngan2005/ward"):
        plausible.material("nickel", fit="ngan2005/wrd")


def test_a_material_missing_from_a_fit_set_is_named_with_that_fit():
    only_low = sorted(set(plausible.materials("low2012/cook-torrance-e1")) - set(plausible.materials("ngan2005/ward")))
    with pytest.raises(ValueError, match=f"unknown material '{only_low[0]}' in fit 'ngan2005/ward'"):
        plausible.material(only_low[0], "ngan2005/ward")


def test_every_shipped_fit_set_is_built():
    assert all(f.built for f in FIT_SETS)


def test_fits_of_models_not_built_are_refused_with_the_reason(monkeypatch):
    """Every shipped set loads (issue 26); a set without its model is refused with its reason."""
    from plausible.catalogue import fit_sets as library

    fake = library.FitSet("test/unbuilt", "ngan_ward.fit", "NganWard", "test", "test",
                          "the model is not implemented in plausible (test)")
    monkeypatch.setattr(library, "FIT_SETS", FIT_SETS + (fake,))
    with pytest.raises(ValueError, match="cannot be loaded: .* is not implemented in plausible"):
        plausible.material("alum-bronze", "test/unbuilt")


@pytest.mark.parametrize("line,match", [
    ("x = Aggregate(Lambertian(albedo = [0.1, 0.2, 0.3]), NganWard(albedo = [1, 2, 3], roughness = ))",
     "expected a number"),
    ("x = Aggregate(Lambertian(albedo = [0.1, 0.2, 0.3])", "unexpected end"),
    ("x = Foo(a = 1) extra", "trailing text"),
    ("no equals sign", "expected 'name = Model"),
    ("x = Foo(a = 1 ; b = 2)", "cannot parse"),
])
def test_malformed_lines_raise_naming_the_place(line, match):
    with pytest.raises(ValueError, match=match):
        parse_line(line, "f.fit:3")


def test_a_material_spec_takes_no_parameters():
    with pytest.raises(ValueError, match="takes no parameters"):
        registry.make_from_spec("material:nickel", rd=0.5)
