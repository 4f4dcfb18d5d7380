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
from plausible.arrays.symbolic import direction


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
        spec, value = _spec_and_value(m, specs, pname)
        if kind == "float":
            lo, hi, default = vals
            assert lo <= default <= hi and default == value and spec.lo <= lo and hi <= spec.hi
        else:
            assert kind == "color" and spec.kind == "color" and spec.hi <= 1.0
            assert vals == tuple(np.broadcast_to(m.params[pname], 3))


def _spec_and_value(m, specs, pname):
    """The spec and value behind a .brdf parameter (``eta_g``: channel 1 of ``eta``)."""
    if pname in specs:
        return specs[pname], m.params[pname]
    base, _, c = pname.rpartition("_")
    assert specs[base].kind == "color" and c in "rgb"
    return specs[base], float(np.broadcast_to(m.params[base], 3)["rgb".index(c)])


def usable_slider(lo, hi, default, steps=1000, step=0.01):
    """A BRDF Explorer slider (``steps`` steps from ``lo`` to ``hi``) moves the value
    by at most ``step`` of the default (a default of 0: by at most 1e-3)."""
    return (hi - lo) / steps <= (step * abs(default) if default else 1e-3)


def slider_models():
    from plausible.analysis.suite import variants

    ms = [plausible.make(n, **kw) for n in plausible.names() for kw in variants(n, 3)]
    return ms + [plausible.make("modified-phong", n=n) for n in (0.0, 1.0, 1e4, 1e6)] + [
        plausible.make("cook-torrance", fresnel="conductor", eta=[0.2, 0.9, 1.1], k=[3.9, 2.4, 2.2])]


def test_brdf_sliders_have_a_usable_step():
    """Every float slider of every model's .brdf (defaults, extremes, exponents of
    0 to 1e6) steps by at most 1 % of its default, within the declared range."""
    bad = []
    for m in slider_models():
        parsed = brdf_file.parse(to_brdf(m))
        specs = {p.name: p for p in type(m).PARAMS}
        for kind, pname, (lo, hi, default) in (p for p in parsed["params"] if p[0] == "float"):
            spec, value = _spec_and_value(m, specs, pname)
            if not (usable_slider(lo, hi, default) and spec.lo <= lo <= default <= hi <= spec.hi
                    and default == value):
                bad.append((repr(m), pname, lo, hi, default))
    assert bad == []


def test_the_slider_check_finds_the_declared_exponent_range():
    assert not usable_slider(0.0, 1e6, 20.0)      # one step = 1000 (the old export)
    assert usable_slider(0.0, 200.0, 20.0) and not usable_slider(0.0, 201.0, 20.0)


def test_a_slider_reaches_the_exported_value_and_ten_times_it():
    parsed = brdf_file.parse(to_brdf(plausible.make("reciprocal-phong", n=1e4)))
    assert parsed["params"][-1] == ("float", "n", (0.0, 1e5, 1e4))
    parsed = brdf_file.parse(to_brdf(plausible.make("reciprocal-phong", n=5e5)))
    assert parsed["params"][-1] == ("float", "n", (0.0, 1e6, 5e5))    # the declared bound


def test_colours_that_may_exceed_one_are_three_float_sliders():
    """A conductor's eta and k (declared up to 100) as float triples: the explorer's
    colour dialog picks [0, 1] and keeps half floats (2.345 -> 2.34375)."""
    m = plausible.make("cook-torrance", fresnel="conductor", eta=[0.2, 0.9, 1.1], k=[2.345, 2.4, 2.2])
    parsed = brdf_file.parse(to_brdf(m))
    floats = {name: v[2] for kind, name, v in parsed["params"] if kind == "float"}
    assert {k: floats[k] for k in ("eta_r", "eta_g", "eta_b", "k_r", "k_g", "k_b")} == dict(
        eta_r=0.2, eta_g=0.9, eta_b=1.1, k_r=2.345, k_g=2.4, k_b=2.2)
    assert not [p for p in parsed["params"] if p[0] == "color"]      # rs is not read with 'conductor'
    m = plausible.make("modified-phong", kd=[0.5, 0.3, 0.1])
    assert ("color", "kd", (0.5, 0.3, 0.1)) in brdf_file.parse(to_brdf(m))["params"]


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


def _smooth_albedo(t, p):
    return 0.6 + 0.3 * np.cos(t) ** 3 + 0.05 * np.sin(t) ** 2 * np.cos(2 * p)


def test_a_resampled_table_measures_its_own_interpolation_error():
    """``AngleTable.difference`` (at the fine nodes and the midpoints) against the
    error of the resampled table with respect to the tabulated function itself,
    at 20,000 random directions: within 10 % (the fine table's own error is 1e-8)."""
    from plausible.tables import AngleTable

    th, ph = np.linspace(0, np.pi / 2, 361), np.arange(32) * (2 * np.pi / 32)
    fine = AngleTable(_smooth_albedo(*np.meshgrid(th, ph, indexing="ij")))
    coarse = fine.resampled(31, 8)
    assert (coarse.n_theta, coarse.n_phi, coarse.size) == (31, 8, 33 * 11)
    rng = np.random.default_rng(1)
    t, p = rng.uniform(0, np.pi / 2, 20000), rng.uniform(0, 2 * np.pi, 20000)
    w = (np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t))
    from plausible.arrays.ops import NP

    true = np.max(np.abs(coarse.lookup(NP, w) - _smooth_albedo(t, p)) / _smooth_albedo(t, p))
    assert 1e-5 < true and fine.difference(coarse) == pytest.approx(true, rel=0.1)


def test_brdf_tables_fit_the_limit():
    from types import SimpleNamespace

    from plausible.export import brdf_tables
    from plausible.tables import AngleTable

    th, ph = np.linspace(0, np.pi / 2, 361), np.arange(32) * (2 * np.pi / 32)
    big = AngleTable(_smooth_albedo(*np.meshgrid(th, ph, indexing="ij")))
    assert big.size == 12705
    m, notes = brdf_tables(SimpleNamespace(tables=[big]), 1200)
    assert m.tables[0].size <= 1200 and len(notes) == 1 and "12705 values" in notes[0]
    same, none = brdf_tables(SimpleNamespace(tables=[big]), 20000)
    assert same.tables[0] is big and none == []


def test_the_js_module_carries_every_uniform_and_the_tables_as_textures(tmp_path):
    """``--format js``: each uniform's value is the model's parameter (none left to
    read 0), each table's texels are its values (float32, row by row, zero padded)."""
    import json

    m = plausible.make("pumped-up", rs=[0.9, 0.8, 0.7])
    out = tmp_path / "brdf.js"
    r = CliRunner().invoke(main, ["export", "pumped-up", "-p", "rs=0.9,0.8,0.7", "--format", "js",
                                  "--out", str(out)])
    assert r.exit_code == 0, r.output
    text = out.read_text()
    assert text == plausible.export.to_js(m)
    uni = json.loads(re.search(r"export const uniforms = (\{.*\});", text).group(1))
    assert uni == {"plausible_rs": [0.9, 0.8, 0.7]}
    w, h, data = re.search(r'"plausible_table0": \{width: (\d+), height: (\d+), data: new Float32Array\(\[(.*?)\]\)',
                           text).groups()
    vals = np.array([float(x) for x in data.split(",")])
    table = m.tables[0]._padded
    assert int(w) * int(h) == len(vals) >= len(table)
    assert np.array_equal(vals[:len(table)], table.astype(np.float32)) and not vals[len(table):].any()
    assert "uniform highp sampler2D plausible_table0;" in text and "const highp float" not in text


def test_cli_table_limit_resamples_the_brdf_table_and_refuses_too_small_a_limit():
    r = CliRunner().invoke(main, ["export", "pumped-up", "--format", "brdf", "--table-limit", "20", "--out", "-"])
    assert r.exit_code == 0, r.output
    parsed = brdf_file.parse(r.stdout)
    assert "const highp float plausible_table0[20]" in parsed["sections"]["shader"]
    assert "resampled from 91 nodes (93 values) to 18 (20 values)" in r.stdout
    r = CliRunner().invoke(main, ["export", "pumped-up", "--format", "brdf", "--table-limit", "4", "--out", "-"])
    assert r.exit_code == 2 and "too small for a table of 91 nodes: it needs at least 5 values" in r.output
