"""The BRDF contract, asserted for every registered model (new models are covered
automatically): shapes, reciprocity, sampling consistency, finiteness, bad input,
and the one-math rule (NumPy and Dr.Jit give the same numbers)."""

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import plausible
from conftest import model_cases, random_upper
from reference import hooks_agree

CASES = model_cases()


def channels_of(m):
    return () if m.channels is None else (m.channels,)


@pytest.mark.parametrize("name,kw", CASES)
def test_shapes_and_broadcasting(name, kw, rng):
    m = plausible.make(name, **kw)
    wi = random_upper(rng, 6)[:, None, :]          # (6, 1, 3)
    wo = random_upper(rng, 5)[None, :, :]          # (1, 5, 3)
    assert m.eval(wi, wo).shape == (6, 5) + channels_of(m)
    assert m.pdf(wi, wo).shape == (6, 5)
    s = m.sample(wi[:, 0, :], rng.random((6, 3)))
    assert s.wo.shape == (6, 3) and s.pdf.shape == (6,) and s.weight.shape == (6,) + channels_of(m)
    # a single direction pair gives a scalar (or one value per channel)
    assert m.eval([0, 0, 1], [0, 0.6, 0.8]).shape == channels_of(m)


@pytest.mark.parametrize("name,kw", CASES)
def test_reciprocity_on_random_pairs(name, kw, rng):
    m = plausible.make(name, **kw)
    a, b = random_upper(rng, 4000), random_upper(rng, 4000)
    f1, f2 = m.eval(a, b), m.eval(b, a)
    scale = np.maximum(np.abs(f1), np.abs(f2)) + 1e-300
    asym = np.max(np.abs(f1 - f2) / scale)
    if m.info.reciprocal:
        assert asym < 1e-10
    elif np.max(f1) > 0:
        assert asym > 0.1   # the implausible baselines must show it (unless f == 0)


@pytest.mark.parametrize("name,kw", CASES)
def test_sample_weight_and_pdf_agree_with_eval(name, kw, rng):
    m = plausible.make(name, **kw)
    for theta in (0.0, 30.0, 60.0, 85.0, 89.9):
        wi = np.array([math.sin(math.radians(theta)), 0.0, math.cos(math.radians(theta))])
        s = m.sample(wi, rng.random((4000, 3)))
        valid = s.pdf > 0
        assert np.all(np.isfinite(s.weight)) and np.all(np.isfinite(s.pdf)) and np.all(s.pdf >= 0)
        assert np.all(s.wo[valid, 2] > 0)
        np.testing.assert_allclose(np.linalg.norm(s.wo, axis=-1), 1.0, rtol=1e-12)
        # pdf(wi, sampled wo) == returned pdf
        np.testing.assert_allclose(m.pdf(wi, s.wo)[valid], s.pdf[valid], rtol=1e-9)
        # weight == eval * cos / pdf, zero for invalid samples
        f = m.eval(wi, s.wo)
        ratio = np.where(valid, s.wo[:, 2] / np.where(valid, s.pdf, 1), 0.0)
        expect = f * (ratio[:, None] if f.ndim > 1 else ratio)
        np.testing.assert_allclose(s.weight, expect, rtol=1e-9, atol=1e-300)
        w = s.weight if s.weight.ndim == 1 else s.weight
        assert np.all(w[~valid] == 0)


@pytest.mark.parametrize("name,kw", CASES)
def test_no_nan_or_inf_on_a_grid_including_horizon_and_pole(name, kw):
    m = plausible.make(name, **kw)
    th = np.radians([0, 1e-6, 10, 45, 80, 89, 89.9, 89.999, 90, 95])
    ph = np.radians([0, 30, 90, 180, 270])
    d = np.stack(np.meshgrid(th, ph, indexing="ij"), -1).reshape(-1, 2)
    w = np.stack([np.sin(d[:, 0]) * np.cos(d[:, 1]), np.sin(d[:, 0]) * np.sin(d[:, 1]), np.cos(d[:, 0])], -1)
    f = m.eval(w[:, None], w[None, :])
    p = m.pdf(w[:, None], w[None, :])
    assert np.all(np.isfinite(f)) and np.all(f >= 0)
    assert np.all(np.isfinite(p)) and np.all(p >= 0)
    below = w[:, 2] <= 0
    assert np.all(f[below] == 0) and np.all(f[:, below] == 0)
    for u in ([0, 0, 0], [0.999999, 0.999999, 0.999999], [0.5, 1.0, 0.0], [0.25, 0.0, 1.0]):
        s = m.sample(w, np.broadcast_to(u, w.shape))
        assert np.all(np.isfinite(s.weight)) and np.all(np.isfinite(s.pdf)) and np.all(np.isfinite(s.wo))


@pytest.mark.parametrize("name", plausible.names())
def test_non_unit_directions_are_normalised(name, rng):
    m = plausible.make(name)
    a, b = random_upper(rng, 50), random_upper(rng, 50)
    np.testing.assert_allclose(m.eval(3.7 * a, 0.01 * b), m.eval(a, b), rtol=1e-12)
    np.testing.assert_allclose(m.pdf(2 * a, 5 * b), m.pdf(a, b), rtol=1e-12)


@pytest.mark.parametrize("name", plausible.names())
def test_directions_whose_squared_length_over_or_underflows_are_normalised(name, rng):
    """|a|^2 of [1e200, 0, 1e200] overflows and of [1e-170, 0, 1e-170] underflows;
    both are still the direction of [1, 0, 1] (issue 21)."""
    m = plausible.make(name)
    a, b = random_upper(rng, 20), random_upper(rng, 20)
    for s, t in ((1e200, 1e-170), (1e-170, 1e300), (1e-300, 1e-300)):
        np.testing.assert_allclose(m.eval(s * a, t * b), m.eval(a, b), rtol=1e-12)
        np.testing.assert_allclose(m.pdf(s * a, t * b), m.pdf(a, b), rtol=1e-12)
    np.testing.assert_allclose(m.eval([1e200, 0, 1e200], [0, 0, 1]), m.eval([1, 0, 1], [0, 0, 1]), rtol=1e-12)


@pytest.mark.parametrize("name", plausible.names())
def test_bad_directions_and_samples_are_refused(name):
    m = plausible.make(name)
    with pytest.raises(ValueError, match="wi must have shape"):
        m.eval([0, 1], [0, 0, 1])
    with pytest.raises(ValueError, match="wo must be non-zero"):
        m.eval([0, 0, 1], [0, 0, 0])
    with pytest.raises(ValueError, match="wi must be finite"):
        m.pdf([0, np.nan, 1], [0, 0, 1])
    with pytest.raises(ValueError, match=r"u must lie in \[0, 1\], got 1\.5"):
        m.sample([0, 0, 1], [0.5, 1.5, 0.5])
    with pytest.raises(ValueError, match="u must have shape"):
        m.sample([0, 0, 1], [0.5, 0.5])


@pytest.mark.parametrize("name", plausible.names())
def test_every_parameter_is_validated_with_its_range(name):
    info = plausible.info(name)
    for p in info.params:
        if p.kind in ("scalar", "color") and math.isfinite(p.hi):
            with pytest.raises(ValueError, match=f"'{p.name}'"):
                plausible.make(name, **{p.name: p.hi + 1.0})
        if p.kind in ("scalar", "color") and math.isfinite(p.lo):
            with pytest.raises(ValueError, match=f"'{p.name}'"):
                plausible.make(name, **{p.name: p.lo - 1.0})
        if p.kind in ("scalar", "color"):
            with pytest.raises(ValueError, match=f"'{p.name}'"):
                plausible.make(name, **{p.name: float("nan")})


unit = st.tuples(st.floats(0.0, 1.0), st.floats(0.0, 2 * math.pi)).map(
    lambda t: np.array([math.sqrt(1 - t[0] ** 2) * math.cos(t[1]), math.sqrt(1 - t[0] ** 2) * math.sin(t[1]), t[0]]))


@pytest.mark.parametrize("name", plausible.names())
@settings(max_examples=60, deadline=None)
@given(wi=unit, u=st.tuples(st.floats(0, 1), st.floats(0, 1), st.floats(0, 1)))
def test_contract_properties(name, wi, u):
    """Hypothesis: for any wi and any u, a sample is finite, unit length, its pdf is
    what pdf() says, and its weight is eval * cos / pdf (or zero)."""
    m = plausible.make(name)
    s = m.sample(wi, np.array(u))
    assert np.all(np.isfinite(s.wo)) and abs(np.linalg.norm(s.wo) - 1) < 1e-9
    assert np.isfinite(s.pdf) and s.pdf >= 0 and np.all(np.isfinite(s.weight)) and np.all(s.weight >= 0)
    if s.pdf > 0 and wi[2] > 0:
        assert s.wo[2] > 0
        assert m.pdf(wi, s.wo) == pytest.approx(float(s.pdf), rel=1e-9)
        np.testing.assert_allclose(s.weight, m.eval(wi, s.wo) * s.wo[2] / s.pdf, rtol=1e-9)
    else:
        assert np.all(s.weight == 0)
    f = m.eval(wi, s.wo)
    assert np.all(np.isfinite(f)) and np.all(f >= 0)


# ---- one math: the same hooks on Dr.Jit arrays ---------------------------------------

@pytest.mark.drjit
@pytest.mark.parametrize("name,kw", CASES)
def test_numpy_and_drjit_agree(name, kw, rng):
    n = 256
    hooks_agree(plausible.make(name, **kw), random_upper(rng, n), random_upper(rng, n), rng.random((n, 3)),
                rtol=1e-11, atol=1e-14, rtol_sample=1e-10, atol_sample=1e-12)
