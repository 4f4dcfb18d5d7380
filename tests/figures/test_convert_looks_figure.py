"""The report's figure of published fits converted, source beside result (``convert-looks``, issue 40):
its checks hold for a real conversion and fail for the same conversion without its warning."""

from __future__ import annotations

import dataclasses

import pytest

pytest.importorskip("mitsuba")
pytest.importorskip("flip_evaluator")

from plausible.conversion import convert  # noqa: E402
from plausible.figures import Context  # noqa: E402
from plausible.figures import conversion as F  # noqa: E402

pytestmark = pytest.mark.drjit
SPEC = F.LOOK_FITS[0]


@pytest.fixture(scope="module")
def gltf():
    return convert(SPEC, to="gltf").items[0]


def test_the_warning_check_holds_for_the_conversion_and_fails_without_its_warning(tmp_path, gltf):
    ctx = Context(tmp_path)
    F._check_looks(ctx, SPEC, gltf)
    silent = dataclasses.replace(gltf, warnings=[w for w in gltf.warnings if not w.startswith("highlight ")])
    F._check_looks(ctx, SPEC, silent)
    held, broken = ctx.measurements
    lo, hi = gltf.looks.band
    # out of the band, warned (the issue's 0.02x before issue 40's fitter; since then too bright at grazing)
    assert not lo <= gltf.looks.highlight_ratio <= hi
    assert held["ok"] is True and broken["ok"] is False


def test_the_comparisons_controls_hold(tmp_path):
    ctx = Context(tmp_path)
    F._check_comparison(ctx, SPEC)
    assert [m["ok"] for m in ctx.measurements] == [True, True, True]
