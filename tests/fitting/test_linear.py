"""The bounded linear least squares of every colour step (plausible.fitting.linear), against closed forms
and a second method; and that fit and convert both solve there (one colour solver)."""

import inspect

import numpy as np
import pytest

from plausible.fitting.linear import bounded, within_band

TOL = 0.04


def test_bounded_is_the_unconstrained_optimum_where_that_lies_inside():
    rng = np.random.default_rng(3)
    R = rng.uniform(size=(40, 3))
    x_true = np.array([0.2, 0.5, 0.7])
    r = R @ x_true + 1e-3 * rng.normal(size=40)
    np.testing.assert_allclose(bounded(R, r), np.linalg.lstsq(R, r, rcond=None)[0], atol=1e-10)


def test_bounded_against_a_brute_force_search_where_a_bound_is_active():
    # a second method: the best of a dense grid over [0, 1]^2 (the optimum lies on x_1 = 1)
    R = np.array([[1.0, 0.3], [0.2, 1.0], [0.5, 0.5]])
    r = np.array([0.4, 1.6, 1.0])
    x = bounded(R, r)
    g = np.linspace(0.0, 1.0, 1001)
    X = np.stack(np.meshgrid(g, g, indexing="ij"), -1).reshape(-1, 2)
    best = X[np.argmin(np.sum((X @ R.T - r) ** 2, axis=1))]
    assert x[1] == 1.0
    np.testing.assert_allclose(x, best, atol=1.5e-3)
    assert np.sum((R @ x - r) ** 2) <= np.sum((R @ best - r) ** 2) + 1e-12


def test_within_band_against_closed_forms():
    # one colour pulled toward x = 1, its albedo 0.5 x held within TOL of 0.2: x = (0.2 + TOL) / 0.5
    R, r, P = np.eye(1), np.ones(1), np.array([[0.5]])
    x = within_band(R, r, P, np.array([0.2]), TOL, np.array([1.0]))
    assert x[0] == pytest.approx((0.2 + TOL) / 0.5, abs=1e-5)
    # already within: unchanged
    assert within_band(R, r, P, np.array([0.49]), TOL, np.array([1.0]))[0] == 1.0
    # no colour meets it (0.1 and 0.4 at two incidences from one 0.5 x): the nearest, x = 0.5, 0.15 off both
    x = within_band(R, r, np.array([[0.5], [0.5]]), np.array([0.1, 0.4]), TOL, np.array([1.0]))
    assert x[0] == pytest.approx(0.5, abs=1e-6)


def test_fit_and_convert_solve_their_colours_here():
    import importlib

    from plausible.conversion import mitsuba as CM

    F = importlib.import_module("plausible.fitting.fit")

    for fn in (CM._lsq, F._linear_colours):
        src = inspect.getsource(fn)
        assert "linear import" in src and "lsq_linear" not in src
    assert "scipy" not in inspect.getsource(CM)
