"""The fuzzer on the NumPy path (float64), over every registered model: random
parameters from the declared ranges (extremes included) and the direction pairs
and uniforms of tests/fuzzing.py (grazing down to cos 1e-14, the exact horizon,
h = n, wi = wo, near-mirror, u exactly 0 and 1 - 2^-53).

Asserted: no NaN, inf or negative value in eval, pdf, weight or wo; the pdf
returned by ``sample`` equals ``pdf()`` at the sampled direction; the weight
stays within the model's analytic bound (derived in tests/fuzzing.py).  The
quick version runs in ``make test``; the long one (``slow``) in ``make test-all``.
"""

from __future__ import annotations

import numpy as np
import pytest

import plausible
from fuzzing import cases, direction_pairs, incidences, uniforms, weight_bound
from plausible.vec import HORIZON


def fuzz(m, rng, n_pairs: int, n_samples: int):
    """Run the fuzzer on model ``m``; return a list of the problems found."""
    problems = []
    wi, wo = direction_pairs(rng, n_pairs)
    f, pdf = m.eval(wi, wo), m.pdf(wi, wo)
    for what, v in (("eval", f), ("pdf", pdf)):
        bad = ~np.isfinite(v) | (v < 0)
        if np.any(bad):
            k = np.argwhere(bad)[0][0]
            problems.append(f"{what} = {v[k]} at wi={wi[k].tolist()}, wo={wo[k].tolist()}")
    wi = incidences(rng, n_samples)
    s = m.sample(wi, uniforms(rng, n_samples))
    w = s.weight if s.weight.ndim == 1 else s.weight.max(axis=-1)
    for what, v in (("weight", w), ("sample pdf", s.pdf), ("wo", s.wo)):
        if not np.all(np.isfinite(v) & (v >= 0 if what != "wo" else True)):
            problems.append(f"{what}: non-finite or negative values")
    again = m.pdf(wi, s.wo)
    again = np.where(again > 1e-250, again, 0.0)  # sample's pdf: below 1e-250 a sample that cannot occur
    # rounding: renormalising a sampled wo moves a pdf that comes from cancellation
    # (a cos^1 lobe near its zero, wo.z near the horizon) by ~1e-16 absolute
    rel = np.abs(again - s.pdf) / (np.maximum(again, s.pdf) + 1e-2)
    if np.max(rel) > 1e-6:
        k = int(np.argmax(rel))
        problems.append(f"sample pdf {s.pdf[k]} != pdf() {again[k]} at wi={wi[k].tolist()}")
    bound = weight_bound(m, wi)
    if bound is not None:
        ok = (w <= bound * (1 + 1e-9) + 1e-300) | (wi[:, 2] <= HORIZON)
        if not np.all(ok):
            k = np.argwhere(~ok)[0][0]
            problems.append(f"weight {w[k]} > bound {bound[k]} at wi={wi[k].tolist()}")
    return problems


CASES = cases(np.random.default_rng(2026), n_random=2)


@pytest.mark.parametrize("name,kw", [pytest.param(n, kw, id=f"{n}-{i}") for i, (n, kw) in enumerate(CASES)])
def test_fuzz_numpy_quick(name, kw):
    m = plausible.make(name, **kw)
    rng = np.random.default_rng(len(name) + 7 * len(kw))
    assert fuzz(m, rng, n_pairs=256, n_samples=1024) == [], kw


@pytest.mark.slow
@pytest.mark.parametrize("name", plausible.names())
def test_fuzz_numpy_long(name):
    """40 random parameter sets per model (the declared ones for pumped-up), 10^5
    pairs and samples each."""
    rng = np.random.default_rng(99)
    sets = [kw for n, kw in cases(rng, n_random=40) if n == name]
    for kw in sets:
        m = plausible.make(name, **kw)
        assert fuzz(m, rng, n_pairs=100_000, n_samples=100_000) == [], kw


def test_fuzzer_finds_a_weight_above_the_bound():
    """The A-S pdf without its fix (wi.h as a dot product, which cancels at grazing
    incidence) is what produced fireflies in float32; here a pdf halved on
    purpose gives weights twice the bound, and the fuzzer reports them."""
    m = plausible.make("ashikhmin-shirley-specular")
    m._pdf = lambda ops, wi, wo, q: 0.5 * type(m)._pdf(m, ops, wi, wo, q)
    problems = fuzz(m, np.random.default_rng(1), n_pairs=16, n_samples=256)
    assert any("> bound" in p for p in problems)


def test_fuzzer_finds_a_nan():
    m = plausible.make("lambertian")
    m._f = lambda ops, wi, wo, p: ops.where(wi[2] < 1e-8, np.nan, 0.8 / np.pi)
    problems = fuzz(m, np.random.default_rng(1), n_pairs=16, n_samples=16)
    assert any(p.startswith("eval = nan") for p in problems)
