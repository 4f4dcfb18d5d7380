"""docs/mitsuba.md, "What is clamped, and where": each row of its table, by the name in its
`check` column, against what the plugins do (issue 43 item 3)."""

from __future__ import annotations

import pathlib
import re

import numpy as np
import pytest

from mi_helpers import interaction, mi, spectrum_np, vec3

pytestmark = pytest.mark.drjit

DOC = pathlib.Path(__file__).resolve().parents[2] / "docs" / "mitsuba.md"


def doc_rows() -> dict:
    """``{check name: the row's 'what happens' text}`` of the table."""
    text = DOC.read_text()
    at = text.index("### What is clamped, and where")
    rows = {}
    for line in text[at:text.index("\n### ", at + 10)].splitlines():
        cells = [c.strip() for c in line.strip().strip("|").split("|")]
        if len(cells) == 4 and re.fullmatch(r"`[a-z-]+`", cells[3]):
            rows[cells[3].strip("`")] = cells[2]
    return rows


def albedo_at_normal(bsdf) -> np.ndarray:
    """pi f cos at wi = wo = n: a Lambertian's reflectance."""
    n = np.array([[0.0, 0.0, 1.0]])
    return np.pi * spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(n), vec3(n)))[0]


def number_at_load():
    with pytest.raises(RuntimeError, match="parameter 'rd' must lie in"):
        mi.load_dict({"type": "lambertian", "rd": 1.5})


def number_at_update():
    b = mi.load_dict({"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3})
    params = mi.traverse(b)
    params["alpha_x"] = mi.Float(1.5)
    with pytest.raises(ValueError, match="'alpha_x' must lie in .*previous values are kept"):
        params.update()
    assert params["alpha_x"][0] == pytest.approx(0.2)


def texels_outside(warnings):
    b = mi.load_dict({"type": "lambertian", "rd": {"type": "checkerboard", "color0": 1.6, "color1": 0.5}})
    assert b.state.known["rd"] is False and len(warnings) == 1 and "texels" in warnings[0]
    # the same at params.update(): an <rgb> pushed above 1, channel by channel
    bsdf = mi.load_dict({"type": "lambertian", "rd": {"type": "rgb", "value": [0.5, 0.4, 0.3]}})
    params = mi.traverse(bsdf)
    params["rd.value"] = mi.Color3f(1.5, 0.4, 0.3)
    params.update()
    np.testing.assert_allclose(albedo_at_normal(bsdf), [1.0, 0.4, 0.3], rtol=1e-6)
    assert len(warnings) == 2


def texel_nan():
    with pytest.raises(RuntimeError, match="not a number"):
        mi.load_dict({"type": "lambertian", "rd": {"type": "checkerboard", "color0": float("nan"), "color1": 0.5}})


def unreadable(warnings):
    inner = {"type": "checkerboard", "color0": 1.6, "color1": 1.6}
    b = mi.load_dict({"type": "lambertian", "rd": {"type": "checkerboard", "color0": inner, "color1": inner}})
    assert b.state.known["rd"] is False and warnings == []
    np.testing.assert_allclose(albedo_at_normal(b), [1.0, 1.0, 1.0], rtol=1e-6)


def mean():
    b = mi.load_dict({"type": "lambertian", "rd": {"type": "checkerboard", "color0": 1.6, "color1": 1.2}})
    assert b.model.params["rd"] == 1.0


def subnormal():
    b = mi.load_dict({"type": "lambertian", "rd": 1e-39})
    assert b.state.values()["rd"] == 0.0


CHECKS = {"number-at-load": number_at_load, "number-at-update": number_at_update,
          "texels-outside": texels_outside, "texel-nan": texel_nan, "unreadable": unreadable,
          "mean": mean, "subnormal": subnormal}


def test_every_row_of_the_table_has_a_check_and_every_check_a_row():
    assert set(doc_rows()) == set(CHECKS)


@pytest.fixture
def warnings(monkeypatch):
    """The plugins' warnings (each one Mitsuba's log gets)."""
    seen = []
    import plausible.mitsuba.plugin as plugin

    original = plugin.ParamState.__init__

    def init(self, *args, **kwargs):
        kwargs["warn"] = seen.append
        original(self, *args, **kwargs)

    monkeypatch.setattr(plugin.ParamState, "__init__", init)
    return seen


@pytest.mark.parametrize("name", sorted(CHECKS))
def test_the_row_holds(name, warnings):
    fn = CHECKS[name]
    fn(warnings) if fn.__code__.co_argcount else fn()
