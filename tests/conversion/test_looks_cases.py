"""Issue 40's first bullet: the conversions and fits whose albedo held while the highlight was lost
or invented.  Each carries its image scores (plausible.compare_looks), and a warning exactly when
the highlight leaves the band; today's numbers are in docs/convert.md ("The look of a conversion")."""

import pytest

pytest.importorskip("mitsuba")
pytest.importorskip("flip_evaluator")

import plausible  # noqa: E402
from plausible.conversion import convert  # noqa: E402
from plausible.mitsuba.looks import HIGHLIGHT_BAND, LIGHT_ANGLES as L_ANGLES, compare_looks  # noqa: E402

LO, HI = HIGHLIGHT_BAND

#: An MTL file as exporters write them: ``Ns 0`` (the exponent 0, a flat lobe) and ``Ks 1`` (a white
#: highlight of full strength); glTF made both a hotspot (22-25x in the issue).
MTL = "newmtl ns0\nKd 0.5 0.5 0.5\nKs 0.5 0.5 0.5\nNs 0\nillum 2\nnewmtl ks1\nKd 0 0 0\nKs 1 1 1\nNs 10\nillum 2\n"


def _flagged_exactly_when_off_band(c):
    """The conversion's looks were rendered, and its warnings say "highlight lost" / "highlight
    invented" exactly when a per-angle ratio is below / above the band (numbers in the warning)."""
    assert c.looks is not None and c.to_dict()["looks"]["highlight_ratio"] == c.looks.highlight_ratio
    lost = any(r < LO for r in c.looks.highlight_ratios)
    invented = any(r > HI for r in c.looks.highlight_ratios)
    assert any(w.startswith("highlight lost") for w in c.warnings) == lost
    assert any(w.startswith("highlight invented") for w in c.warnings) == invented
    for w in c.warnings:        # each warning names every ratio out of the band on its side
        if w.startswith("highlight lost"):
            assert all(f"{r:.3g}x" in w for r in c.looks.highlight_ratios if r < LO)
        elif w.startswith("highlight invented"):
            assert all(f"{r:.3g}x" in w for r in c.looks.highlight_ratios if r > HI)
    return lost, invented


@pytest.mark.parametrize("spec", ["material:alum-bronze@ngan2005/ward",          # 0.02x in the issue
                                  "material:nickel@ngan2005/ashikhmin-shirley",  # 0.02x
                                  "material:red-specular-plastic@ngan2005/ashikhmin-shirley",  # a red metal
                                  "material:chrome@ngan2005/ward"])              # chrome turned copper
def test_published_fits_converted_to_gltf_carry_their_looks(spec):
    (c,) = convert(spec, to="gltf").items
    _flagged_exactly_when_off_band(c)
    # the scores are those of the comparison itself, rendered again from the source and the target
    again = compare_looks(spec, c.result)
    assert again.highlight_ratios == pytest.approx(c.looks.highlight_ratios, rel=1e-6)


@pytest.mark.parametrize("to", ["gltf", "mitsuba"])
def test_mtl_materials_with_ns_0_or_ks_1_carry_their_looks(tmp_path, to):
    (tmp_path / "m.mtl").write_text(MTL)
    for c in convert(str(tmp_path / "m.mtl"), to=to).items:
        _flagged_exactly_when_off_band(c)


def test_a_lobe_converted_to_a_diffuse_target_loses_its_highlight_and_says_so():
    # the highlight of a Blinn lobe (n = 50) cannot survive a Lambertian target: its peak falls below
    # the band at some angle (0.19-0.29 before the fitter held the highlight, about 0.4 since)
    (c,) = convert("lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50", to="mitsuba:diffuse").items
    lost, invented = _flagged_exactly_when_off_band(c)
    assert lost and not invented and c.looks.highlight_ratio < LO


def test_the_command_prints_the_scores_and_warns_on_stderr(tmp_path):
    from click.testing import CliRunner

    from plausible.cli import main

    r = CliRunner().invoke(main, ["convert", "lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50", "--to",
                                  "mitsuba:diffuse", "--out", str(tmp_path / "o.json")], terminal_width=400)
    assert r.exit_code == 0, r.output
    assert "FLIP" in r.stdout and "highlight" in r.stdout
    assert "warning: sum: highlight lost" in r.stderr


def test_the_perceptual_fit_of_ward_to_gold_metallic_paint_prints_its_looks(tmp_path):
    """The issue's fit (alpha 0.84, a matte ball): ``plausible fit`` prints FLIP and the highlight
    ratio beside the errors, and a warning on stderr exactly when the highlight leaves the band."""
    from click.testing import CliRunner

    from plausible.cli import main

    target = "material:gold-metallic-paint@low2012/smooth-e2"
    r = CliRunner().invoke(main, ["fit", "ward", "--target", target, "--starts", "1"], terminal_width=400)
    assert r.exit_code == 0, r.output
    line = next(x for x in r.stdout.splitlines() if x.startswith("looks, rendered beside the target"))
    ratio = float(line.split("highlight x", 1)[1].split()[0])
    assert ("warning: highlight lost" in r.stderr) == (ratio < LO)
    assert ("warning: highlight invented" in r.stderr) == (ratio > HI)
    assert "FLIP" in line and plausible.compare_looks is compare_looks


@pytest.mark.slow
@pytest.mark.parametrize("spec", ["material:nickel@ngan2005/ashikhmin-shirley",           # 0.62x at 0 deg before
                                  "material:red-specular-plastic@ngan2005/ashikhmin-shirley"])  # 0.42x at 150
def test_published_fits_converted_to_mitsuba_keep_albedo_and_highlight(spec):
    """Issue 40, item 2: where the family can, both -- the albedo within 0.05 at 0/45/75 deg by Mitsuba's
    own sampler, and the rendered highlight within the band at all four light angles (grazing too)."""
    from plausible.conversion import albedo_check

    c = convert(spec, to="mitsuba").items[0]
    assert albedo_check(plausible.make(spec), c.params)[0]
    assert all(LO <= r <= HI for r in c.looks.highlight_ratios), c.looks.highlight_ratios
    assert not any(w.startswith("highlight") for w in c.warnings)


@pytest.mark.slow
def test_a_target_that_cannot_hold_both_keeps_the_albedo_and_names_the_highlight_it_loses():
    """alum-bronze@ngan2005/ward to glTF: before, the albedo was 0.08-0.13 off and the highlight 25.9x at
    150 deg, with no word that the two compete.  Now the albedo holds (the constraint; Mitsuba's sampler)
    and one warning says the highlight was traded for it, naming every light angle whose rendered ratio
    is outside the band, lost or invented as the render has it."""
    from plausible.conversion import albedo_check

    spec = "material:alum-bronze@ngan2005/ward"
    c = convert(spec, to="gltf").items[0]
    assert albedo_check(plausible.make(spec), {"type": "gltf-pbr", **c.params})[0]
    (trade,) = [w for w in c.warnings if w.startswith("highlight traded for the albedo")]
    for a, r in zip(L_ANGLES, c.looks.highlight_ratios):
        if r < LO or r > HI:
            assert f"{'lost' if r < LO else 'invented'} at {a:g} deg" in trade
