"""`plausible materials` and material specs on the command line."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.integrals.albedo import direction
from plausible.cli import main


def run(*args):
    return CliRunner().invoke(main, list(args), terminal_width=300)


def test_materials_lists_fit_sets_and_every_material_with_its_fits():
    r = run("materials")
    assert r.exit_code == 0
    for word in ("ngan2005/ward-duer", "low2012/cook-torrance-e2", "ngan2005/he", "alum-bronze", "yellow-plastic"):
        assert word in r.output
    only = run("materials", "--fit", "ngan2005/ward")
    assert "(86) of ngan2005/ward" in only.output


def test_an_unknown_fit_is_a_usage_error_with_suggestions():
    r = run("materials", "--fit", "ngan2005/wrd")
    assert r.exit_code == 2 and "did you mean ngan2005/ward" in r.output


def test_eval_accepts_a_material_spec():
    r = run("eval", "material:alum-bronze@ngan2005/ward", "--wi", "30,0", "--wo", "30,180")
    assert r.exit_code == 0
    want = plausible.material("alum-bronze", "ngan2005/ward").eval(direction(math.radians(30), 0),
                                                                    direction(math.radians(30), math.pi))
    assert [float(x) for x in r.output.split()] == pytest.approx(np.asarray(want).tolist(), rel=1e-9)


def test_eval_of_an_unknown_material_suggests_names():
    r = run("eval", "material:alum-bronz", "--wi", "30,0", "--wo", "30,180")
    assert r.exit_code == 2 and "did you mean alum-bronze" in r.output


# -- plausible check --materials ---------------------------------------------------------

def _table_row(material, fit):
    """The row of docs/materials-table.md for ``material`` in ``fit`` (largest albedo,
    angle, gains energy), written by an earlier full run."""
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "materials-table.md").read_text()
    for line in text.splitlines():
        cells = [c.strip() for c in line.strip("|").split("|")]
        if len(cells) == 8 and cells[0] == material and cells[1] == fit:
            return float(cells[3]), float(cells[4].rstrip("°")), cells[7] != "no"
    raise KeyError((material, fit))


def test_the_published_table_covers_every_fit_of_every_set():
    """docs/materials-table.csv has one row per material of every fit set (1202: the He and
    Löw ABC sets included), and the He fits printed with eta = 1.0 (Fresnel exactly 0, scales
    up to 1.96e9) have the largest albedo of their Lambertian term alone, at every angle."""
    import csv
    from pathlib import Path

    from plausible import catalogue

    with open(Path(__file__).resolve().parents[1] / "docs" / "materials-table.csv") as fh:
        rows = {(r["material"], r["fit"]): r for r in csv.DictReader(fh)}
    want = {(n, f.key) for f in catalogue.fits() for n in catalogue.materials(f.key)}
    assert set(rows) == want and len(want) == 1202
    he = catalogue.fit_data("ngan2005/he")
    zero = [n for n, terms in he.items() if terms[1].params["eta"] == 1.0]
    assert "black-obsidian" in zero and len(zero) == 4
    for n in zero:
        assert float(rows[(n, "ngan2005/he")]["max_albedo"]) == pytest.approx(
            max(he[n][0].params["albedo"]), abs=1e-6)


def test_check_materials_json_reports_the_published_table_numbers():
    """Two fits of ngan2005/ward-duer, quick: the JSON list has one report each,
    whose largest albedo and its angle are docs/materials-table.md's (full
    accuracy, to its 4 decimals); gold-metallic-paint gains energy, so the status is 1."""
    r = run("check", "--materials", "--fit", "ngan2005/ward-duer", "--material", "gold-metallic-paint",
            "--material", "alum-bronze", "--quick", "--json", "--jobs", "1")
    assert r.exit_code == 1, r.output
    import json

    reps = json.loads(r.output)
    assert [x["material"] for x in reps] == ["gold-metallic-paint", "alum-bronze"]   # the order asked
    for x in reps:
        want, theta, gains = _table_row(x["material"], "ngan2005/ward-duer")
        assert x["max_albedo"] == pytest.approx(want, abs=6e-5)
        assert x["theta_deg"] == theta and x["gains_energy"] == gains
        assert x["error"] <= 1e-5 * 1.01 and x["reciprocal"]


def test_check_materials_table_of_a_plausible_fit_exits_zero_and_writes_the_tables(tmp_path):
    r = run("check", "--materials", "--fit", "ngan2005/ward", "--material", "alum-bronze", "--quick",
            "--out", str(tmp_path), "--jobs", "1")
    assert r.exit_code == 0, r.output
    assert "1 fits of 1 fit sets checked (quick): 1 plausible, 0 not" in r.output
    md = (tmp_path / "materials-table.md").read_text()
    assert "| alum-bronze | ngan2005/ward |" in md
    csv = (tmp_path / "materials-table.csv").read_text().splitlines()
    assert csv[0].startswith("material,fit,") and csv[1].startswith("alum-bronze,ngan2005/ward,")


def test_check_materials_in_two_processes_gives_the_rows_of_one():
    from plausible.analysis.materials import check_fits

    one = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True, jobs=1)
    two = check_fits(["ngan2005/ward"], ["alum-bronze", "beige-fabric"], quick=True, jobs=2)
    assert [r.material for r in two] == ["alum-bronze", "beige-fabric"]
    for a, b in zip(one, two):
        assert b.max_albedo == pytest.approx(a.max_albedo, rel=1e-12) and b.theta_deg == a.theta_deg


@pytest.mark.parametrize("args,words", [
    (("--fit", "ngan2005/ward"), "go with --materials"),
    (("--materials", "lambertian"), "takes no MODEL"),
    (("--materials", "--fit", "ngan2005/wrd"), "did you mean ngan2005/ward"),
    (("--materials", "--material", "alum-bronz"), "did you mean alum-bronze"),
])
def test_check_materials_usage_errors(args, words):
    r = run("check", *args)
    assert r.exit_code == 2 and words in r.output, r.output
