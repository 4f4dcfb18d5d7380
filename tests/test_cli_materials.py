"""`plausible materials` and material specs on the command line."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.analysis.albedo import direction
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
