"""The command line on bad input and on failures (issue 21): every case ends in a
clear message and the right exit code, never a traceback."""

import json
import math

import pytest
from click.testing import CliRunner

import plausible
from plausible import registry
from plausible.cli import main


def run(*args, **kw):
    return CliRunner().invoke(main, [str(a) for a in args], terminal_width=400, **kw)


# -- model spec strings (what JSON holds for a nested model) -------------------------

@pytest.mark.parametrize("name", plausible.names())
def test_spec_of_reads_back_into_the_same_model(name):
    m = registry.make(name)
    assert repr(registry.make_from_spec(registry.spec_of(m))) == repr(m)


def test_spec_of_grouped_colour_and_nested_values():
    m = registry.make("lafortune", lobes=[[-1, -1, 1, 20, 1.5], [1, 1, 1, 5, 0.1]], rd=[0.1, 0.2, 1 / 3])
    back = registry.make_from_spec(registry.spec_of(m))
    assert repr(back) == repr(m) and back.params["rd"].tolist() == [0.1, 0.2, 1 / 3]   # floats exactly
    p = registry.make("pumped-up", base="reciprocal-phong:n=7")
    assert registry.spec_of(p).startswith("pumped-up:base=[reciprocal-phong:ks=1.0:n=7.0]:")


# -- check ------------------------------------------------------------------------------

def test_check_json_of_a_model_with_a_nested_model():
    r = run("check", "pumped-up:base=[reciprocal-phong:n=7]", "--quick", "--json")
    d = json.loads(r.output)
    assert d["params"]["base"] == "reciprocal-phong:ks=1.0:n=7.0"
    assert r.exit_code == (0 if d["passed"] else 1)


@pytest.fixture
def two_models(monkeypatch):
    """`check --all` over two small models only (the full registry takes minutes)."""
    import plausible.analysis.suite as suite

    real = suite.model_variants
    monkeypatch.setattr(suite, "model_variants",
                        lambda n: real(n, 1) if n in ("lambertian", "reciprocal-blinn") else [])


def test_check_all_json_reports_every_model_and_a_failing_one(two_models, monkeypatch):
    import plausible.cli as cli

    real = cli.run_check

    def broken(m, **kw):
        if m.name == "lambertian":
            raise RuntimeError("broken on purpose")
        return real(m, **kw)

    monkeypatch.setattr(cli, "run_check", broken)    # in this process: --jobs 1
    r = run("check", "--all", "--quick", "--json", "--jobs", "1")
    d = json.loads(r.output)
    assert r.exit_code == 1 and [x["model"] for x in d] == ["lambertian", "reciprocal-blinn"]
    assert d[0]["passed"] is False and d[0]["error"] == "RuntimeError: broken on purpose"
    assert d[0]["params"] == {"rd": 0.8} and d[1]["passed"] is True
    r = run("check", "--all", "--quick", "--jobs", "1")
    assert r.exit_code == 1
    assert "failed with an error: RuntimeError: broken on purpose" in r.output
    last = r.output.strip().splitlines()[-1]
    assert "2 parameter sets" in last and "1 as claimed" in last and "1 failed with an error" in last


def test_check_all_ends_with_a_summary(two_models):
    r = run("check", "--all", "--quick")
    assert r.exit_code == 0, r.output
    assert "2 parameter sets of" in r.output.strip().splitlines()[-1]
    assert "2 as claimed, 0 not as claimed, 0 failed with an error" in r.output


def test_check_all_refuses_a_model_or_parameters():
    r = run("check", "lambertian", "--all")
    assert r.exit_code == 2 and "--all" in r.output and "takes no MODEL or -p" in r.output
    r = run("check", "--all", "-p", "n=5")
    assert r.exit_code == 2 and "-p n=5" in r.output


# -- albedo ----------------------------------------------------------------------------

@pytest.mark.parametrize("n", ["-3", "0"])
def test_albedo_needs_at_least_one_angle(n):
    r = run("albedo", "lambertian", "-n", n)
    assert r.exit_code == 2 and "--points" in r.output and f"{n} is not in the range 1<=x<=100000" in r.output


@pytest.mark.parametrize("phi", ["nan", "inf"])
def test_albedo_phi_must_be_finite(phi):
    r = run("albedo", "lambertian", "-n", "2", "--phi", phi)
    assert r.exit_code == 2 and "--phi" in r.output and f"must be a finite number, got {phi}" in r.output


def test_albedo_plot_path_checked_before_the_work(tmp_path, monkeypatch):
    import plausible.cli as cli

    monkeypatch.setattr(cli, "albedo_curve", lambda *a, **k: pytest.fail("computed before checking --plot"))
    r = run("albedo", "lambertian", "--plot", "/nonexistent/dir/x.png")
    assert r.exit_code == 2 and "--plot: folder '/nonexistent/dir' does not exist" in r.output
    r = run("albedo", "lambertian", "--plot", str(tmp_path / "x.unknownext"))
    assert r.exit_code == 2 and "unknown image type '.unknownext'; use one of" in r.output and ".png" in r.output
    blocker = tmp_path / "file"
    blocker.write_text("")
    r = run("albedo", "lambertian", "--plot", str(blocker / "x.png"))
    assert r.exit_code == 2 and "does not exist" in r.output


@pytest.mark.skipif(not hasattr(__import__("os"), "geteuid") or __import__("os").geteuid() == 0,
                    reason="root writes into read-only folders")
def test_albedo_plot_into_a_read_only_folder(tmp_path):
    ro = tmp_path / "ro"
    ro.mkdir(mode=0o555)
    r = run("albedo", "lambertian", "-n", "2", "--plot", str(ro / "x.png"))
    assert r.exit_code == 2 and "--plot: cannot write into" in r.output and "Permission denied" in r.output


def test_albedo_plot_into_an_unwritable_folder_is_refused(tmp_path, monkeypatch):
    """The same as root: a folder that takes no new file (simulated by the OS error)."""
    import tempfile

    def refuse(*a, **k):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(tempfile, "TemporaryFile", refuse)
    r = run("albedo", "lambertian", "-n", "2", "--plot", str(tmp_path / "x.png"))
    assert r.exit_code == 2 and "--plot: cannot write into" in r.output and "(Permission denied)" in r.output
    assert "Traceback" not in r.output


# -- eval and -p ----------------------------------------------------------------------

def test_eval_non_finite_phi_blames_phi():
    r = run("eval", "lambertian", "--wi", "30,nan", "--wo", "0,0")
    assert r.exit_code == 2 and "--wi: phi must be a finite angle in degrees, got nan" in r.output
    r = run("eval", "lambertian", "--wi", "nan,0", "--wo", "0,0")
    assert r.exit_code == 2 and "--wi: theta must lie in [0, 90] degrees, got nan" in r.output


@pytest.mark.parametrize("flag,angle", [("--wi", "95,0"), ("--wo", "90.5,30"), ("--wi", "180,0")])
def test_eval_refuses_a_direction_below_the_horizon(flag, angle):
    other = "--wo" if flag == "--wi" else "--wi"
    r = run("eval", "lambertian", flag, angle, other, "0,0")
    assert r.exit_code == 2 and f"{flag}: theta must lie in [0, 90] degrees" in r.output
    assert "below the horizon" in r.output and "Traceback" not in r.output
    assert run("eval", "lambertian", flag, "90,0", other, "0,0").exit_code == 0      # grazing is allowed


def test_parameter_without_a_name():
    r = run("eval", "lambertian", "-p", "=3", "--wi", "0,0", "--wo", "0,0")
    assert r.exit_code == 2 and "parameter assignment '=3' has no name before '='" in r.output


# -- text is printed as text, not Rich markup ------------------------------------------

def test_models_keeps_bracketed_text(monkeypatch):
    import plausible.cli as cli
    from rich.console import Console

    monkeypatch.setattr(cli, "console", Console(width=2000))    # one line per table row
    r = run("models")
    assert r.exit_code == 0
    for text in ("[not reciprocal; not energy conserving]", "[max]", "[controlled]"):
        assert text in r.output, text


# -- the environment and Mitsuba's parser (an outside audit of bad input: both were tracebacks) ------

@pytest.mark.parametrize("var, value, words", [
    ("PLAUSIBLE_BACKEND", "bogus", "environment variable PLAUSIBLE_BACKEND must be one of auto, numpy"),
    ("PLAUSIBLE_VARIANT", "bogus", "environment variable PLAUSIBLE_VARIANT must be auto, cuda, llvm, scalar")])
def test_a_bad_environment_variable_is_a_usage_error_naming_it(monkeypatch, var, value, words):
    monkeypatch.setenv(var, value)
    r = run("eval", "ward", "--wi", "0,0", "--wo", "0,0")
    assert r.exit_code == 2 and words in r.output and "Traceback" not in r.output, r.output


def test_a_variant_that_is_a_name_does_not_stop_a_command_that_does_not_render(monkeypatch):
    monkeypatch.setenv("PLAUSIBLE_VARIANT", "cuda")      # no GPU needed to evaluate a BRDF
    r = run("eval", "ward", "--wi", "0,0", "--wo", "0,0")
    assert r.exit_code == 0 and float(r.output.split()[-1]) == pytest.approx(7.957747155), r.output


@pytest.mark.parametrize("xml, words", [
    ('<bsdf type="diffuse">\n  <rgb name="reflectance" value="0.5"/>\n</bsdf>\n', "missing version attribute"),
    ('<bsdf type="nosuchplugin" version="3.0.0">\n</bsdf>\n', 'Plugin "nosuchplugin" not found')])
def test_a_bsdf_file_mitsuba_cannot_load_is_refused_naming_the_file(tmp_path, xml, words):
    pytest.importorskip("mitsuba")
    (tmp_path / "b.xml").write_text(xml)
    r = run("convert", tmp_path / "b.xml", "--to", "mitsuba", "--out", tmp_path / "x.json")
    assert r.exit_code == 2 and "Mitsuba cannot load it" in r.output and words in r.output, r.output
    assert not (tmp_path / "x.json").exists()


def test_a_host_that_is_no_address_is_said_to_be_the_host():
    # before: "... choose another port) with --port" for a host name that does not resolve
    r = run("explore", "--host", "not a host", "--no-browser") if "--no-browser" in run("explore", "--help").output \
        else run("explore", "--host", "not a host")
    assert r.exit_code == 2 and "--host: give a name or address of this machine" in r.output, r.output
    assert "port" not in r.output.split("(")[-1]


def test_an_unknown_convert_target_lists_the_targets_beside_the_models():
    r = run("convert", "ward", "--to", "nope", "--out", "x.json")
    assert r.exit_code == 2 and "unknown model 'nope'" in r.output and "or a target: mitsuba, mitsuba:TYPE" in r.output
    assert "gltf" in r.output.split("or a target:")[1]


def test_p_with_a_foreign_bsdf_is_refused():
    pytest.importorskip("mitsuba")
    r = run("check", "--mitsuba", '{"type": "diffuse"}', "-p", "rs=0.5", "--quick")
    assert r.exit_code == 2 and "-p sets the parameters of a registered MODEL" in r.output, r.output  # was ignored


def test_log_without_plot_is_refused():
    r = run("albedo", "lambertian", "--log")
    assert r.exit_code == 2 and "--log sets the albedo axis of --plot FILE" in r.output, r.output   # was ignored
