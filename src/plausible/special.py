"""Special functions written against an ops namespace (NumPy, Dr.Jit, symbolic).

Neither Dr.Jit nor GLSL has ``erfc`` or ``lgamma``; the physical-optics model of
:mod:`plausible.models.he_torrance` needs both, so they are written here once,
from elementary operations, to double precision.

* :func:`erfcx` / :func:`erfc` -- the scaled complementary error function
  ``erfcx(z) = exp(z^2) erfc(z)`` for ``z >= 0`` as
  ``t exp(sum_j c_j T_j(2t - 1))`` with ``t = 2 / (2 + z)`` (the change of
  variable of Numerical Recipes, 3rd ed., sec. 6.2.2, ``Erf::erfccheb``).  The
  coefficients :data:`ERFCX_CHEB` are ours: the Chebyshev interpolant of degree
  24 of ``log(erfcx(z) (2 + z) / 2)`` on ``x = (2 - z) / (2 + z)`` in
  ``(-1, 1]``, computed with ``scipy.special.erfcx``
  (``numpy.polynomial.chebyshev.chebinterpolate``; the test
  ``tests/test_special.py`` recomputes them).  Relative error of ``erfcx``
  below 5e-15 for every ``z >= 0`` (measured on 3.2e5 points up to 1e8).
* :func:`log_factorial` -- ``log(m!)`` for whole numbers ``m >= 0`` held as
  floats: a table up to :data:`LOG_FACTORIAL_TABLE` and Stirling's series with
  three correction terms above it (error below 1e-15).
"""

from __future__ import annotations

import math

from .arrays.ops import PI

#: Chebyshev coefficients of ``log(erfcx(z) (2 + z) / 2)`` in ``x = (2 - z) / (2 + z)``.
ERFCX_CHEB = (
    -0.6513268598908547, 0.6419697923564904, 0.019476473204185715, -0.009561514786808568,
    -0.0009465953444819579, 0.00036683949785291443, 4.252332480679965e-05, -2.027857811251315e-05,
    -1.6242900047567204e-06, 1.3036558356091068e-06, 1.5626441448391802e-08, -8.523809574262902e-08,
    6.529054393058337e-09, 5.05934373631461e-09, -9.913644026280044e-10, -2.2736487055282986e-10,
    9.646741293200947e-11, 2.394412699365869e-12, -6.8865069278343535e-12, 8.946775929088376e-13,
    3.1317049307510756e-13, -1.1331750666321761e-13, 1.2478300657420061e-15, 6.223457588188943e-15,
    -5.838916362498468e-16,
)


def erfcx(ops, z):
    """``exp(z^2) erfc(z)`` for ``z >= 0`` (negative ``z`` is read as 0; see the
    module docstring).  ``erfcx(0) = 1``, ``erfcx(z) ~ 1 / (z sqrt(pi))`` for large
    ``z``; finite for every finite ``z``."""
    z = ops.maximum(z, 0.0)
    t = 2.0 / (2.0 + z)
    x = 2.0 * t - 1.0
    # Clenshaw's recurrence for sum_j c_j T_j(x)
    b1 = 0.0
    b2 = 0.0
    for c in ERFCX_CHEB[:0:-1]:
        b1, b2 = 2.0 * x * b1 - b2 + c, b1
    s = x * b1 - b2 + ERFCX_CHEB[0]
    return t * ops.exp(s)


def erfc(ops, z):
    """The complementary error function ``erfc(z) = 2/sqrt(pi) int_z^inf exp(-t^2) dt``
    for any real ``z`` (``2 - erfc(-z)`` below zero).  Relative error below 1e-13
    where the value is a normal float (the rounding of ``z^2`` in ``exp(-z^2)``)."""
    a = ops.abs(z)
    e = erfcx(ops, a) * ops.exp(-a * a)
    return ops.where(z >= 0, e, 2.0 - e)


#: ``log(m!)`` is read from a table for ``m <= LOG_FACTORIAL_TABLE``.
LOG_FACTORIAL_TABLE = 64
_LOG_FACTORIALS = tuple(math.lgamma(m + 1.0) for m in range(LOG_FACTORIAL_TABLE + 1))
_HALF_LOG_2PI = 0.5 * math.log(2.0 * PI)


def stirling_log_factorial(ops, m):
    """``log(m!)`` by Stirling's series,
    ``(m + 1/2) log m - m + log(2 pi)/2 + 1/(12 m) - 1/(360 m^3) + 1/(1260 m^5)``
    (Abramowitz & Stegun 6.1.41); error below ``1/(1680 m^7)``, i.e. 1e-16 for
    ``m > 64``.  ``m > 0``."""
    r = 1.0 / m
    r2 = r * r
    return (m + 0.5) * ops.log(m) - m + _HALF_LOG_2PI + r * (1.0 / 12.0 - r2 * (1.0 / 360.0 - r2 / 1260.0))


def log_factorial(ops, m):
    """``log(m!)`` for whole numbers ``m >= 0`` held as floats: the table of
    ``math.lgamma`` up to :data:`LOG_FACTORIAL_TABLE`, Stirling above."""
    tab = ops.table(_LOG_FACTORIALS)
    small = ops.gather(tab, ops.minimum(ops.maximum(m, 0.0), float(LOG_FACTORIAL_TABLE)))
    big = stirling_log_factorial(ops, ops.maximum(m, LOG_FACTORIAL_TABLE + 1.0))
    return ops.where(m <= LOG_FACTORIAL_TABLE, small, big)


__all__ = ["ERFCX_CHEB", "LOG_FACTORIAL_TABLE", "erfc", "erfcx", "log_factorial", "stirling_log_factorial"]
