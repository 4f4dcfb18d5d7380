"""Remembered integrals (``plausible.integrals.albedo.remembering``, used by ``plausible figures``):
a remembered albedo equals a fresh computation, and two models that differ anywhere never share one."""

import math

import numpy as np
import pytest

import plausible
from plausible.analysis import albedo, albedos, direction
from plausible.integrals import albedo as A
from plausible.integrals.keys import exact_text
from plausible.models.sum import Sum


def _launches(monkeypatch):
    """Count the integrations (calls of ``_integrate``) and the incidences each one computes."""
    seen = []
    real = A._integrate

    def counted(model, kind, wis, tol, levels):
        seen.append(len(wis))
        return real(model, kind, wis, tol, levels)

    monkeypatch.setattr(A, "_integrate", counted)
    return seen


def test_a_remembered_albedo_equals_a_fresh_one_and_is_not_recomputed(monkeypatch):
    m = plausible.make("cook-torrance", m=0.3)
    wis = [direction(math.radians(t)) for t in (0.0, 45.0, 80.0)]
    fresh = albedos(m, wis)                 # outside the block: computed (the truth)
    seen = _launches(monkeypatch)
    with A.remembering():
        first = albedos(m, wis)
        again = albedos(plausible.make("cook-torrance", m=0.3), wis[1:] + [direction(math.radians(60.0))])
    assert seen == [3, 1]                   # the second call integrates only the new incidence
    for a, b in zip(fresh, first):
        # the same rules (each incidence refined on its own); the backend may differ (auto), so to rounding
        assert float(a.value) == pytest.approx(float(b.value), abs=1e-12)
        assert float(a.error) == pytest.approx(float(b.error), abs=1e-12)
    assert float(again[0].value) == float(first[1].value) and float(again[1].value) == float(first[2].value)
    # the memory ends with the block: computed again
    albedo(m, wis[0])
    assert seen == [3, 1, 1]


def test_different_models_tolerances_and_kinds_never_share(monkeypatch):
    seen = _launches(monkeypatch)
    wi = direction(0.5)
    with A.remembering():
        a = albedo(plausible.make("reciprocal-phong", ks=1.0, n=20.0), wi)
        # the 7th significant digit of a parameter (repr(model) prints 6, "1"): a different model.
        # Not n: this lobe's albedo hardly depends on n here (n = 20.000001 gave the same value
        # to the last bit); it is linear in ks.
        b = albedo(plausible.make("reciprocal-phong", ks=0.9999999, n=20.0), wi)
        albedo(plausible.make("reciprocal-phong", ks=1.0, n=20.0), wi, tol=1e-5)
        plausible.analysis.pdf_integral(plausible.make("reciprocal-phong", ks=1.0, n=20.0), wi)
    assert seen == [1, 1, 1, 1]
    assert float(a.value) != float(b.value)
    assert float(b.value) == pytest.approx(0.9999999 * float(a.value), rel=1e-12)


def test_the_memory_key_is_exact_or_none():
    k1 = exact_text(plausible.make("ward", alpha_x=0.1, alpha_y=0.1000000001))
    k2 = exact_text(plausible.make("ward", alpha_x=0.1, alpha_y=0.1))
    assert k1 is not None and k2 is not None and k1 != k2
    s1 = Sum([plausible.make("lambertian", rd=0.2), (plausible.make("phong", ks=0.5, n=10), np.array([1.0, 0.5, 0.25]))])
    s2 = Sum([plausible.make("lambertian", rd=0.2), (plausible.make("phong", ks=0.5, n=10), np.array([1.0, 0.5, 0.2500001]))])
    assert exact_text(s1) != exact_text(s2)
    # an object with the contract but no parameters that name it: nothing remembered
    assert exact_text(object()) is None


def test_a_colour_result_handed_out_is_a_copy():
    m = plausible.make("lambertian", rd=(0.2, 0.4, 0.6))
    with A.remembering():
        r = albedo(m, direction(0.3))
        r.value[:] = 7.0                    # a caller that changes its result in place
        again = albedo(m, direction(0.3))
    assert np.allclose(again.value, (0.2, 0.4, 0.6), atol=1e-6)
