"""The metrics against closed forms, and their reaction to deliberately wrong fits."""

import math

import numpy as np
import pytest

import plausible
from plausible.fitting import metrics as M


@pytest.fixture
def g():
    return np.random.default_rng(3).uniform(0.1, 2.0, 200)


def test_exact_fit_scores_zero(g):
    A = np.array([0.9, 0.8, 0.7])
    e = M.errors(g, g, A, A)
    assert e["l2-cos"] == 0 and e["log"] == 0 and e["fcos_max"] == 0
    assert e["albedo_max"] == 0 and e["perceptual"] == 0


def test_uniform_scale_error_closed_form(g):
    # c = 1.1 g, a = 0.8 A, no floor: every figure has a closed form
    A = np.array([0.9, 0.8, 0.7])
    e = M.errors(1.1 * g, g, 0.8 * A, A, eps=0.0)
    assert e["l2-cos"] == pytest.approx(0.1, rel=1e-12)
    assert e["log"] == pytest.approx(math.log(1.1), rel=1e-12)
    assert e["fcos_max"] == pytest.approx(math.log(1.1), rel=1e-12)
    assert e["albedo_max"] == pytest.approx(-math.log(0.8), rel=1e-12)
    assert e["perceptual"] == pytest.approx(math.log(1.1) - math.log(0.8), rel=1e-12)
    assert M.errors(1.1 * g, g, 0.8 * A, A, eps=0.0, combine="max")["perceptual"] == \
        pytest.approx(-math.log(0.8), rel=1e-12)


def test_perceptual_detects_one_bad_sample_that_averages_hide(g):
    # a single sample off by 2x: the mean-based figures barely move, the max sees it all
    c = g.copy()
    c[17] *= 2.0
    e = M.errors(c, g, eps=0.0)
    assert e["fcos_max"] == pytest.approx(math.log(2.0), rel=1e-12)
    assert e["log"] == pytest.approx(math.log(2.0) / math.sqrt(len(g)), rel=1e-12)
    assert e["log"] < 0.1 * e["fcos_max"]


def test_perceptual_detects_wrong_albedo_that_fcos_metrics_miss(g):
    # f cos perfect on the samples, albedo 30% low at one angle: only the perceptual figure sees it
    A = np.array([0.9, 0.8, 0.7])
    a = A * np.array([1.0, 1.0, 0.7])
    e = M.errors(g, g, a, A)
    assert e["l2-cos"] == 0 and e["log"] == 0
    assert e["perceptual"] == pytest.approx(-math.log(0.7), rel=1e-12)


def test_floor_counts_differences_below_it_as_small():
    g = np.array([1.0, 1e-6])
    c = np.array([1.0, 1e-9])            # 1000x off, but far below eps = 1e-3
    e = M.errors(c, g)
    assert M.floor(g) == 1e-3
    assert e["fcos_max"] == pytest.approx(abs(math.log((1e-9 + 1e-3) / (1e-6 + 1e-3))), rel=1e-12)
    assert e["fcos_max"] < 1e-3


def test_smooth_bound_brackets_the_true_maximum(g):
    rng = np.random.default_rng(5)
    c = g * np.exp(rng.normal(0, 0.1, g.shape))
    A = np.array([0.9, 0.8, 0.7]); a = A * np.array([1.05, 0.9, 1.0])
    for combine in ("sum", "max"):
        true = M.errors(c, g, a, A, combine=combine)["perceptual"]
        for beta in (20.0, 200.0, 2000.0):
            s = M.objective("perceptual", c, g, a, A, beta=beta, combine=combine)
            slack = (2 if combine == "sum" else 1) * math.log(2 * (len(g) + 3)) / beta
            assert true - 1e-12 <= s <= true + slack


def test_least_squares_objectives_are_the_squared_figures(g):
    c = g * 1.05
    e = M.errors(c, g)
    assert M.objective("l2-cos", c, g) == pytest.approx(e["l2-cos"] ** 2, rel=1e-12)
    assert M.objective("log", c, g) == pytest.approx(e["log"] ** 2, rel=1e-12)


def test_bad_input_raises(g):
    with pytest.raises(ValueError, match="metric must be one of"):
        M.objective("l1", g, g)
    with pytest.raises(ValueError, match="shapes differ"):
        M.errors(g[:-1], g)
    with pytest.raises(ValueError, match="combine"):
        M.errors(g, g, g[:3], g[:3], combine="mean")
    with pytest.raises(ValueError, match="combine must be one of sum, max, got 'mean'"):
        M.check_combine("mean")
    assert M.check_combine("max") == "max"


def test_albedo_zero_where_target_is_not_is_infinite():
    assert M.albedo_error([0.0, 0.5], [0.5, 0.5]) == math.inf


def test_sample_pairs_deterministic_above_horizon_and_hit_the_peak():
    m = plausible.make("modified-phong", n=100)
    wi, wo = M.sample_pairs(m.peak_directions)
    wi2, wo2 = M.sample_pairs(m.peak_directions)
    assert np.array_equal(wi, wi2) and np.array_equal(wo, wo2)
    assert np.all(wo[:, 2] > 0.01) and np.all(wi[:, 2] > 0)
    assert np.allclose(np.linalg.norm(wo, axis=1), 1.0, atol=1e-12)
    # every incidence angle has a sample exactly in its mirror direction
    for t in M.THETAS_DEG:
        sel = np.isclose(wi[:, 2], math.cos(math.radians(t)))
        mirror = wi[sel][0] * [-1, -1, 1]
        assert np.min(np.linalg.norm(wo[sel] - mirror, axis=1)) < 1e-12
    # three incidence azimuths by default
    wi3, _ = M.sample_pairs(m.peak_directions, azimuths_deg=(0.0,))
    assert 2.5 * len(wi3) < len(wi)
