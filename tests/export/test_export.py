"""GLSL text and .brdf files: their form (the browser tests run them)."""

from __future__ import annotations

import re

import numpy as np
import pytest
from click.testing import CliRunner

import brdf_file
import plausible
from plausible.cli import main
from plausible.export import to_brdf, to_glsl
from plausible.export.glsl import Emitter, literal
from plausible.symbolic import direction


def test_literals_are_floats():
    assert [literal(x) for x in (1, 0.5, 1e-12, -2, 1e16)] == ["1.0", "0.5", "1.0e-12", "(-2.0)", "1.0e+16"]
    assert literal(float("inf")) == "uintBitsToFloat(0x7F800000u)"
    with pytest.raises(ValueError, match="NaN"):
        literal(float("nan"))


def _integer_literals(code):
    """Numbers without a decimal point or exponent, outside identifiers and
    array sizes / int() indices (GLSL ES rejects int-float mixing)."""
    code = re.sub(r"\b[A-Za-z_]\w*\b", " ", code)          # identifiers (t12, plausible_table0)
    code = re.sub(r"\[\s*\d+\s*\]", " ", code)               # array sizes
    code = re.sub(r"0x[0-9A-Fa-f]+u", " ", code)
    return re.findall(r"(?<![\d.eE+-])\d+(?![\d.eE])", code)


@pytest.mark.parametrize("name", plausible.names())
def test_every_exported_literal_is_a_float(name):
    text = to_glsl(plausible.make(name), uniforms=True).text
    code = "\n".join(ln.split("//")[0] for ln in text.split("\n"))
    assert _integer_literals(code) == []


def test_the_literal_check_finds_an_integer():
    assert _integer_literals("float t0 = 2 * wi.x + 1.0;") == ["2"]


def test_a_shared_subexpression_is_computed_once():
    wi, wo = direction("wi"), direction("wo")
    a = wi[0] + wo[0]
    b = wi[0] + wo[0]  # built again: the same structure
    lines, (text,) = Emitter("p", lambda v: v).statements([a * b])
    assert lines == ["highp float t0 = wi.x + wo.x;", "highp float t1 = t0 * t0;"] and text == "t1"


def test_glsl_bakes_parameters_or_declares_uniforms():
    m = plausible.make("modified-phong", kd=[0.5, 0.3, 0.1], n=50)
    baked = to_glsl(m)
    assert baked.uniforms == [] and "uniform" not in baked.text
    assert "highp vec3 plausible_f(highp vec3 wi, highp vec3 wo)" in baked.text and "plausible_sample(" in baked.text
    uni = to_glsl(m, uniforms=["n"])
    assert [(u.name, u.type, u.value) for u in uni.uniforms] == [("plausible_n", "float", (50.0,))]
    assert "uniform highp float plausible_n;" in uni.text
    assert [u.declaration() for u in to_glsl(m, uniforms=True).uniforms] == [
        "uniform highp vec3 plausible_kd;", "uniform highp vec3 plausible_ks;", "uniform highp float plausible_n;"]
    with pytest.raises(ValueError, match=r"cannot make 'nope' a uniform; .*kd, ks, n"):
        to_glsl(m, uniforms=["nope"])


def test_structural_parameters_stay_baked():
    s = to_glsl(plausible.make("cook-torrance", fresnel="conductor"), uniforms=True)
    # rs is not read with fresnel='conductor' (and eta, k are not read with 'schlick')
    assert [u.name for u in s.uniforms] == ["plausible_m", "plausible_eta", "plausible_k"]
    assert s.baked["fresnel"] == "'conductor'" and s.baked["geometry"] == "'vgroove'"
    s = to_glsl(plausible.make("cook-torrance"), uniforms=True)
    assert [u.name for u in s.uniforms] == ["plausible_m", "plausible_rs"]


def test_pumped_up_carries_its_albedo_table_as_a_const_array():
    m = plausible.make("pumped-up")
    s = to_glsl(m)
    n = len(m.tables[0]._padded)
    assert f"const highp float plausible_table0[{n}] = float[{n}](" in s.text


def test_more_than_three_channels_are_refused():
    class Spectral(type(plausible.make("lambertian"))):
        CHANNELS = (1, 3, 5)        # a spectral model: the library takes 5 wavelengths, GLSL does not

    with pytest.raises(ValueError, match="grey or RGB.*5 channels"):
        to_glsl(Spectral(rd=[0.1, 0.2, 0.3, 0.4, 0.5]))


@pytest.mark.parametrize("name", plausible.names())
def test_brdf_file_loads_as_the_explorer_reads_it(name):
    m = plausible.make(name)
    text = to_brdf(m)
    parsed = brdf_file.parse(text)
    assert text.split("\n")[0] == "analytic"
    assert "vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)" in parsed["sections"]["shader"]
    assert ("isFunc" in parsed["sections"]) == to_glsl(m).sampling
    # every line of code survives the loader (none begins with '#')
    assert all(not ln.strip().startswith("#") for sec in parsed["sections"].values() for ln in sec.split("\n"))
    specs = {p.name: p for p in type(m).PARAMS}
    for kind, pname, vals in parsed["params"]:
        spec = specs[pname]
        if kind == "float":
            lo, hi, default = vals
            assert spec.kind == "scalar" and lo <= default <= hi and default == m.params[pname]
            assert (spec.lo, spec.hi) == (lo, hi) or not np.isfinite([spec.lo, spec.hi]).all()
        else:
            assert kind == "color" and spec.kind == "color"
            assert vals == tuple(np.broadcast_to(m.params[pname], 3))


def test_the_brdf_reader_rejects_what_the_explorer_rejects():
    good = "analytic\n::begin parameters\nfloat n 0 10 1\n::end parameters\n::begin shader\nx\n::end shader\n"
    assert brdf_file.parse(good)["params"] == [("float", "n", (0.0, 10.0, 1.0))]
    assert brdf_file.parse(good.replace("\nx\n", "\n#define A 1\nx\n"))["sections"]["shader"] == "x\n"
    for bad in (good.replace("analytic", "measured"), good.replace("float n 0 10 1", "int n 0 10 1"),
                good.replace("::end shader\n", ""), good.replace("::end parameters", "::end shader")):
        with pytest.raises(brdf_file.BRDFFileError):
            brdf_file.parse(bad)


def test_cli_writes_the_shader(tmp_path):
    out = tmp_path / "phong.glsl"
    r = CliRunner().invoke(main, ["export", "reciprocal-phong", "-p", "n=50", "--format", "glsl",
                                  "--out", str(out)])
    assert r.exit_code == 0, r.output
    assert out.read_text() == to_glsl(plausible.make("reciprocal-phong", n=50)).text
    r = CliRunner().invoke(main, ["export", "ward", "--format", "brdf", "--out", str(tmp_path / "w.brdf")])
    assert r.exit_code == 0 and (tmp_path / "w.brdf").read_text() == to_brdf(plausible.make("ward"))


def test_cli_reports_a_bad_parameter(tmp_path):
    r = CliRunner().invoke(main, ["export", "reciprocal-phong", "-p", "n=-3", "--out", str(tmp_path / "x")])
    assert r.exit_code == 2 and "parameter 'n' must lie in [0, 1e+06], got -3" in r.output
    assert not (tmp_path / "x").exists()
