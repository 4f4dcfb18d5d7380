"""`plausible fit`: recovers known parameters from a CSV table, fixes -p parameters,
writes the plots, and reports bad input naming the option."""

import json

import numpy as np
from click.testing import CliRunner

import plausible
from plausible.cli import main
from plausible.fitting import sample_pairs, save_table


def _table(tmp_path, **truth):
    m = plausible.make("modified-phong", **truth)
    wi, wo = sample_pairs(m.peak_directions, thetas_deg=(0.0, 30.0, 60.0, 80.0))
    return str(save_table(tmp_path / "mp.csv", wi, wo, m.eval(wi, wo)))


def test_fit_recovers_and_writes_plots(tmp_path):
    csv = _table(tmp_path, kd=0.3, ks=0.5, n=40.0)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["fit", "modified-phong", "--target", csv, "--metric", "l2-cos",
                                  "--starts", "2", "--out", str(out)])
    assert r.exit_code == 0, r.output
    data = json.loads((out / "fit.json").read_text())
    assert np.allclose([data["params"][k] for k in ("kd", "ks", "n")], [0.3, 0.5, 40.0], rtol=1e-6)
    assert data["errors"]["l2-cos"] < 1e-6 and data["errors"]["albedo_max"] is None
    for name in ("plane.png", "albedo.png"):
        assert (out / name).read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    assert "n/a (no target albedo)" in r.output


def test_fit_with_a_fixed_parameter(tmp_path):
    csv = _table(tmp_path, kd=0.3, ks=0.5, n=40.0)
    out = tmp_path / "out"
    r = CliRunner().invoke(main, ["fit", "modified-phong", "--target", csv, "--metric", "log",
                                  "-p", "n=20", "--starts", "1", "--out", str(out)])
    assert r.exit_code == 0, r.output
    data = json.loads((out / "fit.json").read_text())
    assert data["params"]["n"] == 20.0 and data["errors"]["log"] > 0.01   # n wrong: cannot fit exactly


def test_fit_bad_input(tmp_path):
    csv = _table(tmp_path, kd=0.3, ks=0.5, n=40.0)
    run = CliRunner().invoke
    r = run(main, ["fit", "modified-phong", "--target", csv, "--metric", "l1"])
    assert r.exit_code == 2 and "--metric" in r.output
    r = run(main, ["fit", "modified-phong", "--target", str(tmp_path / "missing.csv")])
    assert r.exit_code == 2 and "not found" in r.output
    r = run(main, ["fit", "modified-phong", "--target", csv, "-p", "kd=2"])
    assert r.exit_code == 2 and "'kd' must lie in [0, 1]" in r.output
    r = run(main, ["fit", "no-such-model", "--target", csv])
    assert r.exit_code == 2 and "unknown model" in r.output
    bad = tmp_path / "bad.csv"
    bad.write_text("1,2,3\n")
    r = run(main, ["fit", "modified-phong", "--target", str(bad)])
    assert r.exit_code == 2 and "expected 7 or 9 columns" in r.output


def test_fit_says_each_bound_on_stderr_and_keeps_an_isotropic_target_isotropic():
    """Issue 40: ``plausible fit ashikhmin-shirley --target gold-metallic-paint --metric l2-cos``
    gave nu 5.3, nv 0 and rd_r = 1 without a word.  Now nu = nv (the note says why) and every
    parameter at an end of its range is named on standard error (exit 0)."""
    r = CliRunner().invoke(main, ["fit", "ashikhmin-shirley", "--target",
                                  "material:gold-metallic-paint@low2012/smooth-e2", "--metric", "l2-cos"])
    assert r.exit_code == 0, r.output
    rows = {line.split("│")[1].strip(): line.split("│")[2].strip() for line in r.stdout.splitlines()
            if line.count("│") == 3}
    assert rows["nu"] == rows["nv"]
    assert "isotropic target" in r.stdout
    assert "warning:" not in r.stdout
    for name in ("rs", "rd"):        # each channel printed as exactly 0 or 1 is named on stderr
        for i, v in enumerate(rows[name].split(",")):
            if v in ("0", "1"):
                end = "lower bound 0" if v == "0" else "upper bound 1"
                assert f"{name}[{i}] = {v} (its {end})" in r.stderr
    assert r.stderr.count("its upper bound") + r.stderr.count("its lower bound") >= 1
