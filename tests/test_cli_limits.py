"""The command line on hostile specs (issue 27): deep nesting, overflowing
Lafortune lobes, booleans and odd channel counts get one clear line, no traceback."""

import pytest
from click.testing import CliRunner

import plausible
from plausible.cli import main


@pytest.mark.parametrize("spec,says", [
    ("pumped-up:base=[" * 5 + "lambertian" + "]" * 5, "nests more than 4 levels"),
    ("pumped-up:base=[" * 300 + "lambertian" + "]" * 300, "nests more than 4 levels"),   # was RecursionError
    ("lafortune:lobes=2,2,2,1e6,0.5;", "got inf"),                                       # was OverflowError
    ("lambertian:rd=0.1,0.2", "1 or 3 channels"),
])
def test_eval_refuses_with_one_line(spec, says):
    r = CliRunner().invoke(main, ["eval", spec, "--wi", "30,0", "--wo", "30,180"])
    assert r.exit_code != 0 and says in r.output and "Traceback" not in r.output


def test_four_levels_of_nesting_are_still_read():
    spec = "pumped-up:base=[" * 4 + "reciprocal-phong:n=5" + "]" * 4
    name, base = plausible.registry.split_spec(spec)
    assert name == "pumped-up" and base == "base=" + "pumped-up:base=[" * 3 + "reciprocal-phong:n=5" + "]" * 3


def test_booleans_are_not_numbers():
    with pytest.raises(ValueError, match="alpha_x.*boolean"):
        plausible.make("ward", alpha_x=True)
