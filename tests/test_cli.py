"""The command line: thin layer over the library, checked through click's runner."""

import json
import math

import pytest
from click.testing import CliRunner

import plausible
from plausible.cli import main


def run(*args):
    return CliRunner().invoke(main, list(args), catch_exceptions=False)


def test_help_lists_the_commands():
    r = run("--help")
    assert r.exit_code == 0
    for cmd in ("models", "eval", "check", "albedo"):
        assert cmd in r.output


def test_models_lists_every_registered_model_with_ranges():
    r = CliRunner().invoke(main, ["models"], terminal_width=400)
    assert r.exit_code == 0
    for name in plausible.names():
        assert name in r.output
    assert "[0, 1e+06]" in r.output


def test_eval_prints_the_notes_table_value():
    r = run("eval", "modified-phong", "-p", "kd=0.5", "-p", "ks=0.5", "-p", "n=10", "--wi", "0,0", "--wo", "0,0")
    assert r.exit_code == 0
    assert float(r.output) == pytest.approx(7 / (2 * math.pi), rel=1e-9)


def test_eval_colour_and_grouped_values():
    r = run("eval", "lambertian", "-p", "rd=0.1,0.2,0.3", "--wi", "30,0", "--wo", "60,90")
    assert [float(x) for x in r.output.split()] == pytest.approx([0.1 / math.pi, 0.2 / math.pi, 0.3 / math.pi])
    r = run("eval", "lafortune", "-p", "lobes=-1,-1,1,20,1.5;", "-p", "rd=0", "--wi", "10,0", "--wo", "10,180")
    assert float(r.output) == pytest.approx(1.5, rel=1e-12)   # at the mirror direction the lobe is rho


def test_bad_input_names_the_parameter():
    r = CliRunner().invoke(main, ["eval", "reciprocal-phong", "-p", "n=-3", "--wi", "0,0", "--wo", "0,0"])
    assert r.exit_code == 2 and "'n' must lie in [0, 1e+06]" in r.output
    r = CliRunner().invoke(main, ["eval", "lambertian", "--wi", "30", "--wo", "0,0"])
    assert r.exit_code == 2 and "--wi must be THETA_DEG,PHI_DEG" in r.output


def test_check_exit_codes_and_json():
    ok = run("check", "reciprocal-blinn", "-p", "n=20", "--quick", "--json")
    assert ok.exit_code == 0
    d = json.loads(ok.output)
    assert d["passed"] is True and d["model"] == "reciprocal-blinn"
    bad = run("check", "phong", "-p", "n=20", "--quick", "--json")
    assert bad.exit_code == 1
    d = json.loads(bad.output)
    verdicts = {r["name"]: r["passed"] for r in d["results"]}
    assert verdicts == {"reciprocity": False, "energy": False, "sampling": True, "chi2": True}


def test_check_table_output():
    r = run("check", "lambertian", "--quick")
    assert r.exit_code == 0
    for word in ("reciprocity", "energy", "sampling", "chi2", "PASS"):
        assert word in r.output


def test_albedo_table_and_plot(tmp_path):
    out = tmp_path / "a.png"
    r = CliRunner().invoke(main, ["albedo", "lambertian:rd=0.5", "reciprocal-phong:n=0", "-n", "3",
                                  "--plot", str(out)], terminal_width=200)
    assert r.exit_code == 0
    assert out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and out.stat().st_size > 10_000
    rows = [ln for ln in r.output.splitlines() if ln.strip().startswith("│ 0.00")]
    assert rows and "0.500000" in rows[0] and "1.000000" in rows[0]


def test_albedo_of_a_pumped_up_model_with_a_nested_spec():
    """`plausible albedo` takes a pumped-up model with its base in brackets: at
    normal incidence the unit-albedo Phong and its pumped version both give 1; a
    non-reciprocal base is refused with the model's message."""
    r = CliRunner().invoke(main, ["albedo", "reciprocal-phong:ks=1:n=20",
                                  "pumped-up:base=[reciprocal-phong:ks=1:n=20]", "-n", "3"],
                           terminal_width=200)
    assert r.exit_code == 0, r.output
    rows = [ln for ln in r.output.splitlines() if ln.strip().startswith("│ 0.00")]
    assert rows and rows[0].count("1.000000") == 2
    r = CliRunner().invoke(main, ["albedo", "pumped-up:base=[phong:n=20]", "-n", "3"])
    assert r.exit_code != 0 and "not reciprocal" in r.output


@pytest.mark.parametrize("text", ["-1,-1,1,20,1.5", "-1,-1,1,20,1.5;", "(-1.0, -1.0, 1.0, 20.0, 1.5)",
                                  "[(-1, -1, 1, 20, 1.5)]"])
def test_one_lafortune_lobe_in_every_form_gives_the_mirror_value(text):
    r = run("eval", "lafortune", "-p", f"lobes={text}", "-p", "rd=0", "--wi", "10,0", "--wo", "10,180")
    assert r.exit_code == 0, r.output
    assert float(r.output) == pytest.approx(1.5, rel=1e-12)   # at the mirror direction the lobe is rho


def test_the_lobes_that_plausible_models_prints_read_back():
    from plausible.cli import _fmt

    lobes = ((-1.0, -1.0, 1.0, 20.0, 1.25), (0.5, 0.5, 1.0, 8.0, 0.125))
    printed = _fmt(lobes)          # the text of the 'plausible models' table
    assert printed.startswith("(-1.0, -1.0, 1.0, 20.0, 1.25),(")
    m = plausible.registry.make_from_spec("lafortune", **plausible.registry.parse_assignments([f"lobes={printed}"]))
    assert m.params["lobes"] == lobes


@pytest.mark.parametrize("text", ["-1,-1,1,20", "(-1,-1,1,20,1.5),x", "(-1,-1,1,20)"])
def test_a_malformed_lobe_shows_the_expected_form(text):
    r = CliRunner().invoke(main, ["eval", "lafortune", "-p", f"lobes={text}", "--wi", "0,0", "--wo", "0,0"])
    assert r.exit_code == 2 and "parameter 'lobes'" in r.output
    assert "-p lobes=cx,cy,cz,n,rho" in r.output or "'(a, b, c), (d, e, f)'" in r.output
