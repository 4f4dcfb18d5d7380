"""plausible check --python / --mitsuba / --mitsuba-xml: the same report and exit codes."""

import json
import math
import textwrap

import pytest
from click.testing import CliRunner

from plausible.cli import main

MODULE = textwrap.dedent("""
    import math
    import numpy as np

    def lambert(wi, wo):
        return np.full(len(wi), 0.8 / math.pi)

    def gain(wi, wo):
        return np.full(len(wi), 1.2 / math.pi)
    """)


def run(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


@pytest.fixture
def brdfs(tmp_path, monkeypatch):
    (tmp_path / "user_brdfs.py").write_text(MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    return "user_brdfs"


def test_python_callable_report_json_and_exit_code(brdfs):
    r = run("check", "--python", f"{brdfs}:lambert", "--quick", "--json")
    assert r.exit_code == 0
    rep = json.loads(r.output)
    res = {x["name"]: x for x in rep["results"]}
    assert res["energy"]["figure"] == pytest.approx(0.8, abs=1e-9)
    assert res["sampling"]["details"]["applicable"] is False and "no sampler" in rep["notes"][0]


def test_python_callable_gaining_energy_exits_1(brdfs):
    r = run("check", "--python", f"{brdfs}:gain", "--quick", "--json")
    assert r.exit_code == 1
    res = {x["name"]: x for x in json.loads(r.output)["results"]}
    assert not res["energy"]["passed"] and res["energy"]["figure"] == pytest.approx(1.2, abs=1e-9)


def test_bad_foreign_inputs_are_usage_errors(brdfs, tmp_path):
    for args, msg in [(["--python", "user_brdfs"], "package.module:function"),
                      (["--python", f"{brdfs}:nope"], "no attribute 'nope'"),
                      (["--mitsuba", "{not json"], "--mitsuba must be a JSON object"),
                      (["--id", "x"], "--id names a BSDF in --mitsuba-xml"),
                      (["lambertian", "--python", f"{brdfs}:lambert"], "give one of MODEL")]:
        r = run("check", *args)
        assert r.exit_code == 2 and msg in r.output, (args, r.output)


mitsuba = pytest.importorskip("mitsuba")


def test_mitsuba_dict_checked_with_closed_form_albedo():
    r = run("check", "--mitsuba", '{"type": "diffuse", "reflectance": 0.5}', "--quick", "--json")
    assert r.exit_code == 0
    res = {x["name"]: x for x in json.loads(r.output)["results"]}
    assert res["energy"]["figure"] == pytest.approx(0.5, abs=1e-6)
    assert res["reciprocity"]["figure"] < 1e-6


def test_mitsuba_refusals_are_usage_errors(tmp_path):
    r = run("check", "--mitsuba", '{"type": "null"}')
    assert r.exit_code == 2 and "not a reflective BSDF" in r.output
    p = tmp_path / "s.xml"
    p.write_text('<scene version="3.0.0"><bsdf type="diffuse" id="wall"/></scene>')
    r = run("check", "--mitsuba-xml", str(p), "--id", "gold")
    assert r.exit_code == 2 and "ids in the file: wall" in r.output
