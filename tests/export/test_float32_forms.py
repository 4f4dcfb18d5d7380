"""The formula forms that keep float32 shaders accurate: equal to the plain
formulas in float64, and accurate where the plain ones lose their digits."""

from __future__ import annotations

import numpy as np

from plausible import warps
from plausible.arrays.ops import NP


def test_power_near_one_is_the_power():
    x = np.concatenate([np.linspace(-0.5, 1.0, 301), 1.0 - np.geomspace(1e-12, 0.5, 200)])
    for e in (0.0, 1.0, 2.5, 300.0, 1e4):
        got = warps.power_near_one(NP, x, 1.0 - x, e)
        want = np.where(x > 0, np.power(np.maximum(x, 0.0), e), 1.0 if e == 0 else 0.0)
        np.testing.assert_allclose(got, want, rtol=1e-11, atol=1e-300)


def test_power_near_one_keeps_float32_digits_where_the_power_does_not():
    """x = 1 - t with t known exactly: from t, float32 gives x^1e4 to 1e-6; the
    float32 value of x itself (rounded to within 6e-8 of 1) is off by up to 3e-4."""
    t = np.geomspace(1e-7, 1e-3, 50)
    want = np.exp(1e4 * np.log1p(-t))
    x32, t32 = (1.0 - t).astype(np.float32), t.astype(np.float32)
    with np.errstate(all="ignore"):
        good = warps.power_near_one(NP, x32, t32, np.float32(1e4))
    plain = np.power(x32, np.float32(1e4)).astype(np.float64)
    assert np.max(np.abs(good / want - 1)) < 1e-5 < 1e-4 < np.max(np.abs(plain / want - 1))


def test_pow_cos_from_sin2_with_the_cosine_near_the_horizon():
    theta = np.linspace(0.0, np.pi / 2 - 1e-6, 400)
    for e in (0.0, 1.0, 20.0, 1e4):
        got = warps.pow_cos_from_sin2(NP, np.sin(theta) ** 2, e, np.cos(theta))
        np.testing.assert_allclose(got, np.cos(theta) ** e, rtol=1e-12, atol=1e-300)
    # float32: from cos, (cos theta)^1 at 89.9 degrees keeps its digits; 1 - sin^2 does not
    c = np.float32(np.cos(np.radians(89.9)))
    s2 = np.float32(1.0) - c * c
    exact = float(c)
    assert abs(float(warps.pow_cos_from_sin2(NP, s2, np.float32(1.0), c)) / exact - 1) < 1e-6
    assert abs(float(warps.pow_cos_from_sin2(NP, s2, np.float32(1.0))) / exact - 1) > 1e-4
