"""Cycles beside Mitsuba in compare_looks' scene: a material known exactly on both sides, and wrong ones."""

import numpy as np
import pytest

from plausible.blender import material_spec
from plausible.blender.looks import FLIP_TOL, check_looks, compare_cycles, cycles_renders
from plausible.mitsuba.looks import Looks, render_looks

pytest.importorskip("mitsuba")
pytest.importorskip("flip_evaluator")

RD = [0.2, 0.5, 0.9]
KW = dict(angles=(0.0, 60.0, 150.0), res=48, spp=16)


def _diffuse(rd):
    return {"type": "diffuse", "reflectance": {"type": "rgb", "value": list(rd)}}


@pytest.fixture(scope="module")
def same(blender):
    return compare_cycles(_diffuse(RD), material_spec(diffuse=RD), **KW)


def test_cycles_diffuse_renders_like_mitsuba_diffuse(same):
    # f = rd / pi on both sides: the light images (256 spp, nearly noise free) agree to their noise,
    # the views to the renderers' Monte Carlo noise (the floor, docs/blender.md)
    np.testing.assert_allclose(same.highlight_ratios, 1.0, atol=0.01)
    assert same.flip < FLIP_TOL
    assert check_looks(same).passed


def test_the_scene_matches_mitsubas_pixel_for_pixel_in_the_mean(same):
    # the same image, not a mirrored or flipped one: per view, the brightest column under the lamp and
    # the rows' mean under the environment (sky above, ground below) of both renderers
    w = KW["res"]
    for k in range(len(KW["angles"])):
        s, r = same.source.view(k, "light").mean(-1), same.result.view(k, "light").mean(-1)
        assert np.argmax(s.sum(0)) == np.argmax(r.sum(0))
        np.testing.assert_allclose(r.sum(), s.sum(), rtol=0.01)
        se, re = same.source.view(k, "env").mean(-1).mean(1), same.result.view(k, "env").mean(-1).mean(1)
        np.testing.assert_allclose(re[w // 8:-w // 8], se[w // 8:-w // 8], rtol=0.08, atol=0.01)


def test_a_brighter_diffuse_fails_the_check(blender):
    lk = compare_cycles(_diffuse([0.5, 0.5, 0.5]), material_spec(diffuse=[0.8, 0.8, 0.8]), **KW)
    np.testing.assert_allclose(lk.highlight_ratios, 1.6, rtol=0.01)      # 0.8 / 0.5
    rep = check_looks(lk)
    assert not rep.passed and "invented" in rep.details["warnings"][0]


def test_a_metal_in_place_of_the_diffuse_fails_the_check(blender):
    src = render_looks(_diffuse(RD), **KW)
    glossy = cycles_renders(material_spec(principled={"Base Color": RD, "Metallic": 1.0, "Roughness": 0.3}), **KW)
    from plausible.mitsuba.looks import compare_renders

    rep = check_looks(compare_renders(src, glossy))
    assert not rep.passed and rep.figure > 3 * FLIP_TOL


def test_check_looks_fails_on_flip_alone_and_rejects_a_bad_bound():
    lk = Looks(0.2, (0.1, 0.3), 1.0, (1.0, 1.0), (0.0, 60.0), ((1.0, 1.0), (1.0, 1.0)))
    rep = check_looks(lk)
    assert not rep.passed and rep.worst["flip_view_deg"] == 60.0
    assert check_looks(lk, flip_max=0.25).passed
    with pytest.raises(ValueError, match="flip_max"):
        check_looks(lk, flip_max=0.0)


def test_bad_options_name_the_parameter(blender):
    with pytest.raises(ValueError, match="res"):
        cycles_renders(material_spec(diffuse=RD), res=4)
