"""Command-line conventions (issue 29): standard output for '-', exit status 130
on Ctrl-C, a busy port, machine-readable output, one model's page, tables in a
pipe, the compact --all table, file modes and material targets."""

from __future__ import annotations

import json
import math
import os
import socket
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible import registry
from plausible.cli import main
from plausible.export import to_glsl


def run(*args, **kw):
    return CliRunner().invoke(main, [str(a) for a in args], **kw)


# -- export --out - -----------------------------------------------------------------

def test_export_to_standard_output_writes_no_file(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    r = CliRunner().invoke(main, ["export", "ward", "-p", "alpha_x=0.3", "--out", "-"])
    assert r.exit_code == 0, r.output
    assert r.stdout == to_glsl(plausible.make("ward", alpha_x=0.3)).text
    assert "wrote standard output" in r.stderr and list(tmp_path.iterdir()) == []


# -- Ctrl-C ----------------------------------------------------------------------------

def test_ctrl_c_exits_130_not_1(monkeypatch):
    import plausible.cli as cli

    def interrupted(m, **kw):
        raise KeyboardInterrupt

    monkeypatch.setattr(cli, "run_check", interrupted)
    r = run("check", "lambertian")
    assert r.exit_code == 130 and "interrupted" in r.output
    monkeypatch.setattr(cli, "run_check", lambda m, **kw: (_ for _ in ()).throw(RuntimeError("x")))
    assert run("check", "lambertian").exit_code == 1          # any other error is not 130


# -- explore on a busy port ------------------------------------------------------------

def test_explore_on_a_busy_port_fails_before_announcing_a_url():
    pytest.importorskip("uvicorn")
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    s.listen(1)
    port = s.getsockname()[1]
    try:
        r = run("explore", "--port", port, "--no-browser")
    finally:
        s.close()
    assert r.exit_code == 2 and f"cannot listen on 127.0.0.1:{port}" in r.output and "--port" in r.output
    assert "plausible explorer on" not in r.output


# -- models NAME, --json ---------------------------------------------------------------

def test_models_name_shows_that_model_from_the_registry():
    r = run("models", "ward")
    assert r.exit_code == 0, r.output
    inf = registry.info("ward")
    for p in inf.params:
        assert p.name in r.output and p.range_text() in r.output
    claims = ("reciprocal" if inf.reciprocal else "not reciprocal") + ", " + \
        ("energy conserving" if inf.energy_conserving else "not energy conserving")
    assert f"claims: {claims}" in r.output and "cook-torrance" not in r.output
    r = run("models", "wardd")
    assert r.exit_code == 2 and "did you mean ward" in r.output


def test_models_json_lists_every_model_with_its_parameters():
    d = json.loads(run("models", "--json").output)
    assert [m["name"] for m in d] == plausible.names()
    ward = d[plausible.names().index("ward")]
    assert [p["name"] for p in ward["params"]] == [p.name for p in registry.info("ward").params]
    assert ward["params"][0]["lo"] == registry.info("ward").params[0].lo
    one = json.loads(run("models", "ward", "--json").output)
    assert one == ward


# -- check: as claimed, --json nulls, --all compact table ------------------------------

def test_check_model_says_whether_it_holds_what_it_claims(monkeypatch):
    r = run("check", "phong", "--quick")        # fails reciprocity, which it does not claim
    assert r.exit_code == 1 and "as claimed (phong claims: not reciprocal" in r.output
    import dataclasses

    inf = registry.info("phong")
    monkeypatch.setattr(type(plausible.make("phong")), "info", dataclasses.replace(inf, reciprocal=True))
    r = run("check", "phong", "--quick")
    assert "not as claimed (phong claims: reciprocal" in r.output


def test_check_json_gives_non_applicable_checks_as_null_and_counts_them_apart(tmp_path, monkeypatch):
    (tmp_path / "user_brdfs_29.py").write_text("import math, numpy as np\n"
                                               "def lambert(wi, wo):\n    return np.full(len(wi), 0.8 / math.pi)\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    r = run("check", "--python", "user_brdfs_29:lambert", "--quick", "--json")
    d = json.loads(r.output)
    res = {x["name"]: x for x in d["results"]}
    assert res["sampling"]["passed"] is None and res["sampling"]["figure"] is None
    assert res["energy"]["passed"] is True and res["energy"]["figure"] == pytest.approx(0.8, abs=1e-9)
    assert d["counts"] == {"passed": 2, "failed": 0, "unresolved": 0, "not_applicable": 2}


@pytest.fixture
def two_models(monkeypatch):
    import plausible.analysis.suite as suite

    real = suite.model_variants
    monkeypatch.setattr(suite, "model_variants",
                        lambda n: real(n, 1) if n in ("lambertian", "phong") else [])


def test_check_all_prints_one_compact_row_per_parameter_set(two_models):
    r = run("check", "--all", "--quick", env={"COLUMNS": None})   # a pipe: no width set
    lines = r.output.splitlines()
    rows = [ln for ln in lines if ln.startswith("│")]
    assert len(rows) == 2 and "worst case" not in r.output        # no full reports
    lam = next(ln for ln in rows if "lambertian" in ln)
    pho = next(ln for ln in rows if "phong" in ln)
    assert lam.count("PASS") == 4 and lam.rstrip("│ ").endswith("yes")
    assert "FAIL" in pho and pho.rstrip("│ ").endswith("yes")   # fails only what it does not claim
    assert "worst case" in run("check", "--all", "--quick", "--verbose").output


# -- eval: several pairs, --json; albedo and materials --json ------------------------

def test_eval_takes_several_pairs_and_json():
    m = plausible.make("modified-phong", kd=0.3, ks=0.5, n=20)
    r = run("eval", "modified-phong", "-p", "kd=0.3", "-p", "ks=0.5", "-p", "n=20",
            "--wi", "30,0", "--wo", "30,180", "--wi", "60,0", "--wo", "10,90")
    assert r.exit_code == 0, r.output
    want = m.eval(np.array([plausible.direction(math.radians(30), 0), plausible.direction(math.radians(60), 0)]),
                  np.array([plausible.direction(math.radians(30), math.pi),
                            plausible.direction(math.radians(10), math.pi / 2)]))
    got = [float(x) for x in r.output.split()]
    np.testing.assert_allclose(got, want, rtol=1e-9)
    d = json.loads(run("eval", "lambertian:rd=0.5", "--wi", "0,0", "--wo", "10,0", "--wo", "80,0", "--json").output)
    assert [x["wo"] for x in d] == [[10.0, 0.0], [80.0, 0.0]]
    assert all(x["f"] == [pytest.approx(0.5 / math.pi, rel=1e-15)] for x in d)
    r = run("eval", "lambertian", "--wi", "0,0", "--wi", "1,0", "--wo", "1,0", "--wo", "2,0", "--wo", "3,0")
    assert r.exit_code == 2 and "as many --wi as --wo" in r.output


def test_albedo_json_holds_the_curve():
    d = json.loads(run("albedo", "lambertian:rd=0.5", "modified-phong", "-n", "3", "--json").output)
    assert d[0]["model"] == "lambertian:rd=0.5" and d[0]["theta_deg"][0] == 0.0
    np.testing.assert_allclose(d[0]["value"], 0.5, rtol=1e-10)        # rd, at every angle
    assert len(d[1]["value"]) == 3 and d[1]["model"].startswith("modified-phong:")


def test_materials_json_and_unloadable_fits_left_out(monkeypatch):
    from plausible.catalogue import fit_sets as library

    d = json.loads(run("materials", "--json").output)
    assert {f["key"] for f in d["fits"]} == {f.key for f in library.fits()}
    he = next(f for f in d["fits"] if f["key"] == "ngan2005/he")
    assert he["loadable"] is True               # every shipped set loads since issue 26
    assert "ngan2005/he" in d["materials"]["nickel"]
    # a set whose model is missing is listed as such and left out of the materials
    fake = library.FitSet("test/unbuilt", "ngan_ward.fit", "NganWard", "test", "test",
                          "the model is not implemented in plausible (test)")
    monkeypatch.setattr(library, "FIT_SETS", library.FIT_SETS + (fake,))
    d = json.loads(run("materials", "--json").output)
    un = next(f for f in d["fits"] if f["key"] == "test/unbuilt")
    assert un["loadable"] is False and "not implemented" in un["reason"]
    assert all("test/unbuilt" not in keys for keys in d["materials"].values())
    assert "ngan2005/ward" in d["materials"]["nickel"]


def test_materials_fit_shows_that_fit_alone():
    r = run("materials", "--fit", "ngan2005/ward")
    assert r.exit_code == 0 and "ngan2005/ward " in r.output
    assert "ngan2005/blinn-phong" not in r.output and "low2012" not in r.output
    assert "materials (86) of ngan2005/ward" in r.output


def test_tables_in_a_pipe_are_not_cut():
    env = dict(os.environ, PYTHONPATH=str(Path(plausible.__file__).parents[1]))
    env.pop("COLUMNS", None)
    out = subprocess.run([sys.executable, "-m", "plausible.cli", "materials", "--fits"], capture_output=True,
                         text=True, env=env, check=True).stdout
    for fs in plausible.catalogue.fits():
        assert fs.key in out                     # the keys users copy, whole
    assert "ngan2005/ashikhmin…" not in out


# -- files --------------------------------------------------------------------------------

@pytest.mark.parametrize("umask,mode", [(0o022, 0o755), (0o077, 0o700)])
def test_figure_folders_follow_the_umask(tmp_path, monkeypatch, umask, mode):
    import plausible.figures as F
    from plausible.figures.report import run as run_figures

    def tiny(ctx):
        ctx.table("t", {"x": np.array([1.0])})

    F.names()
    monkeypatch.setitem(F.FIGURES, "tiny", F.Figure("tiny", "Tiny", "test", "caption", tiny, {}))
    old = os.umask(umask)
    try:
        run_figures(tmp_path, only=["tiny"])
    finally:
        os.umask(old)
    assert (tmp_path / "tiny").stat().st_mode & 0o777 == mode


def test_fit_takes_a_material_target():
    # the published fit nickel@ngan2005/ward: Lambertian rd (0.0221, 0.0178, 0.0107) + Ward alpha 0.0432
    # scaled by (0.204, 0.154, 0.0946); plausible's ward fits it back exactly
    r = run("fit", "ward", "--target", "material:nickel@ngan2005/ward", "--metric", "l2-cos", "--starts", "1",
            "-p", "alpha_y=0.0432")
    assert r.exit_code == 0, r.output
    rows = dict(ln.strip("│ ").split("│")[:2] for ln in r.output.splitlines()
                if ln.startswith("│") and ln.count("│") == 3)
    rows = {k.strip(): v.strip() for k, v in rows.items()}
    assert float(rows["alpha_x"]) == pytest.approx(0.0432, rel=1e-4)
    np.testing.assert_allclose([float(x) for x in rows["rs"].split(",")], [0.204, 0.154, 0.0946], rtol=1e-3)
