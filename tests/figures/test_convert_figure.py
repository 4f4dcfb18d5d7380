"""The report's section of legacy materials converted (``convert-legacy``, issue 32): its checks
hold for the conversion, fail for the same conversion with its colours scaled by 0.85, and the
rule of thumb's albedo is the one computed here apart (Mitsuba's own sampler of the
``principled`` dict written here)."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")

from plausible.figures import Context  # noqa: E402
from plausible.figures import conversion as F  # noqa: E402

pytestmark = pytest.mark.drjit


@pytest.fixture(scope="module")
def rows():
    return F._read(F.QUICK)


def _run(tmp_path, monkeypatch, rows):
    monkeypatch.setattr(F, "_read", lambda names: rows)
    ctx = Context(tmp_path, quick=True)
    F.convert_legacy(ctx, "")
    return {m["quantity"]: m for m in ctx.measurements}


def _scaled(d, s):
    if d.get("type") == "rgb":
        return {"type": "rgb", "value": [s * v for v in d["value"]]}
    return {k: (_scaled(v, s) if isinstance(v, dict) else v) for k, v in d.items()}


def test_the_checks_hold_for_the_conversion_and_fail_for_a_darker_one(tmp_path, monkeypatch, rows):
    (m, s, c), = rows
    got = _run(tmp_path / "a", monkeypatch, rows)
    conv = got[f"{m.name}: converted ({c.target}), largest |albedo difference| at 0/45/75 deg"]
    rule = got[f"{m.name}: rule of thumb, largest |albedo difference| at 0/45/75 deg"]
    assert conv["ok"] and conv["measured"] < 0.02 and rule["ok"]
    # the rule of thumb: a dielectric principled of base colour Kd, roughness sqrt(2/(Ns+2)) = 0.1400; its
    # albedo at normal incidence in red, by Mitsuba's sampler written here: 0.53, against the source's 0.80
    assert F.rule_of_thumb(m.Kd, m.Ns)["roughness"] == pytest.approx(math.sqrt(2 / 102))
    a0 = _sampled(F.rule_of_thumb(m.Kd, m.Ns))
    assert a0 == pytest.approx(0.533, abs=0.01)
    assert rule["measured"] >= abs(0.80 - a0) - 0.01
    # colours scaled by 0.85: 0.12 darker at normal incidence, beyond the band: the check fails
    dark = [(m, s, dataclasses.replace(c, params=_scaled(c.params, 0.85)))]
    bad = _run(tmp_path / "b", monkeypatch, dark)[conv["quantity"]]
    assert bad["ok"] is False and bad["measured"] > 0.1


def _sampled(d, n=200_000):
    """Albedo at normal incidence (red) of the Mitsuba dict ``d`` by its ``sample``'s weights."""
    import drjit as dr

    from plausible.analysis.mitsuba_bsdf import ensure_variant

    ensure_variant()
    b = mi.load_dict(d)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.0, 0.0, 1.0)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    u = np.random.default_rng(2).random((3, n))
    _, w = b.sample(mi.BSDFContext(), si, mi.Float(u[0]), mi.Point2f(mi.Float(u[1]), mi.Float(u[2])), True)
    return float(np.array(w, dtype=float).reshape(3, n)[0].mean())
