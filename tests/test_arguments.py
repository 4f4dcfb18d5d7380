"""The library's own keyword arguments checked where a function is called (an outside audit of bad input
found NaN results, NumPy errors from deep inside and values silently taken): each bad value is a
ValueError naming the argument and its range."""

import math

import numpy as np
import pytest

import plausible
from plausible import arguments as A
from plausible.analysis import chi2, direction, energy, reciprocity, sampling_consistency
from plausible.integrals.albedo import hemispherical_albedo


def test_the_helpers_take_good_values_and_refuse_bad_ones_by_name():
    assert A.count("n", np.int64(3)) == 3 and A.real("x", 0.5, 0, 1) == 0.5 and A.probability("a", 0.01) == 0.01
    assert A.angles_deg("t", np.array([0, 45.5])) == (0.0, 45.5)
    for call, words in [(lambda: A.count("n", 0), "n must be a whole number >= 1, got 0"),
                        (lambda: A.count("n", 2.5), "got 2.5"), (lambda: A.count("n", True), "got True"),
                        (lambda: A.count("n", 11, 1, 10), "[1, 10]"),
                        (lambda: A.real("x", math.nan), "x must be a finite number"),
                        (lambda: A.real("x", 0.0, 0.0, open_lo=True), "(0, inf]"),
                        (lambda: A.probability("alpha", 1.5), "alpha must be a finite number in (0, 1)"),
                        (lambda: A.probability("alpha", "x"), "got 'x'"),
                        (lambda: A.angles_deg("t", ()), "t must hold at least one angle"),
                        (lambda: A.angles_deg("t", (10, 95)), "t[1] (degrees) must be a finite number in [0, 90]")]:
        with pytest.raises(ValueError) as e:
            call()
        assert words in str(e.value)


M = plausible.make("modified-phong", n=20.0)
Z = direction(0.3)


@pytest.mark.parametrize("call, words", [
    (lambda: chi2(M, Z, n_samples=1000, min_expected=-1), "min_expected must be"),      # was a NaN statistic
    (lambda: chi2(M, Z, n_samples=1000, alpha=0), "alpha must be"),
    (lambda: chi2(M, Z, n_samples=1000, n_theta=0), "n_theta must be"),
    (lambda: chi2(M, Z, n_samples=10 ** 12), "n_samples must be a whole number [1000, 100000000]"),  # MemoryError
    (lambda: plausible.check(M, alpha=1.5), "alpha must be"),                   # a TypeError about complex numbers
    (lambda: plausible.check(M, alpha=math.nan), "alpha must be"),
    (lambda: plausible.albedo(M, Z, levels=0), "levels must be"),                # was taken
    (lambda: hemispherical_albedo(M, n_theta=0), "n_theta must be"),           # NumPy's "deg must be positive"
    (lambda: reciprocity(M, n_theta=0), "n_theta must be"),                    # a zero-size reduction
    (lambda: reciprocity(M, tol=-1), "tol must be"),
    (lambda: sampling_consistency(M, n_samples=0), "n_samples must be"),
    (lambda: sampling_consistency(M, thetas_deg=(95,)), "thetas_deg[0] (degrees)"),   # passed
    (lambda: energy(M, thetas_deg=()), "thetas_deg must hold at least one angle"),    # an IndexError
    (lambda: energy(M, thetas_deg=(100,)), "thetas_deg[0] (degrees)"),               # passed with figure 0
    (lambda: plausible.fit("ward", "ward:alpha_x=0.2", seed=-1), "seed must be a whole number >= 0"),
    (lambda: plausible.fit("ward", "ward:alpha_x=0.2", time_limit=-1), "time_limit must be"),  # the start returned
    (lambda: plausible.fit("ward", "ward:alpha_x=0.2", thetas_deg=()), "thetas_deg must hold"),
    (lambda: plausible.convert("ward:alpha_x=0.2", to="ward", starts=0), "starts must be"),
    (lambda: plausible.direction("a"), "theta and phi must be angles in radians"),   # NumPy's "could not convert"
    (lambda: plausible.albedo("ward", Z), "pass plausible.make('ward')"),            # an AttributeError
    (lambda: plausible.albedo(lambda wi, wo: 1.0, Z), "model must have the contract's eval"),
])
def test_bad_arguments_are_refused_naming_them(call, words):
    with pytest.raises(ValueError) as e:
        call()
    assert words in str(e.value)
