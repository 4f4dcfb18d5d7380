"""Bounded linear least squares: the colour step of every fit that is linear in its colours.

Where a model is affine in its colour variables at fixed other parameters (Ward's ``rd`` and
``rs``; every Mitsuba family of :mod:`plausible.conversion.mitsuba` in its slots), the colours
minimising a least-squares figure within their bounds are an exact problem,

    min |R x - r|^2  subject to  lo <= x <= hi,

solved by :func:`bounded` (SciPy's BVLS, an active-set method: the exact optimum, about ten
times faster than the trust-region method here).  :func:`within_band` adds the albedo held
within a band of the target's at a few incidences (``|P x - q| <= tol``), a constraint of
:func:`plausible.convert`.  :func:`plausible.fit`'s closed-form colour step
(:func:`plausible.fitting.fit._linear_colours`) and :func:`plausible.convert`'s colours at every
point of a family's axes (:func:`plausible.conversion.mitsuba.fit_family`) both solve here.
"""

from __future__ import annotations

import numpy as np

__all__ = ["bounded", "within_band"]


def bounded(R, r, lo=0.0, hi=1.0) -> np.ndarray:
    """``argmin |R x - r|^2`` over ``lo <= x <= hi`` (scalars or one bound per column of ``R``),
    by SciPy's ``lsq_linear(method="bvls")``; clipped to the bounds against rounding."""
    from scipy.optimize import lsq_linear

    R, r = np.asarray(R, float), np.asarray(r, float)
    lo = np.broadcast_to(np.asarray(lo, float), (R.shape[1],))
    hi = np.broadcast_to(np.asarray(hi, float), (R.shape[1],))
    return np.clip(lsq_linear(R, r, bounds=(lo, hi), method="bvls").x, lo, hi)


def within_band(R, r, P, q, tol: float, x0) -> np.ndarray:
    """The ``x`` in ``[0, 1]`` minimising ``|R x - r|^2`` with ``|P x - q| <= tol`` row by row
    (SLSQP from the nearest feasible point), where one exists; where none does, the ``x`` of the
    smallest largest ``|P x - q|`` (a linear program: ``min t`` with ``|P x - q| <= t``).  ``x0``,
    the unconstrained optimum (:func:`bounded`), is returned as it is when it meets the band."""
    from scipy.optimize import linprog, minimize

    R, r, P, q = (np.asarray(a, float) for a in (R, r, P, q))
    x0 = np.asarray(x0, float)
    if np.all(np.abs(P @ x0 - q) <= tol):
        return x0
    J, ones = len(x0), -np.ones((len(q), 1))
    lp = linprog(np.r_[np.zeros(J), 1.0], A_ub=np.block([[P, ones], [-P, ones]]), b_ub=np.r_[q, -q],
                 bounds=[(0.0, 1.0)] * J + [(0.0, None)], method="highs")
    if not lp.success:
        return x0
    xf = lp.x[:J]
    if lp.x[J] > tol:
        return xf
    inner = tol - 1e-6
    cons = [{"type": "ineq", "fun": lambda x: inner - (P @ x - q), "jac": lambda x: -P},
            {"type": "ineq", "fun": lambda x: inner + (P @ x - q), "jac": lambda x: P}]
    scale = max(float(np.sum(r * r)), 1e-30)
    res = minimize(lambda x: float(np.sum((R @ x - r) ** 2)) / scale, xf,
                   jac=lambda x: 2.0 * R.T @ (R @ x - r) / scale, method="SLSQP", bounds=[(0.0, 1.0)] * J,
                   constraints=cons, options=dict(maxiter=200, ftol=1e-12))
    x = np.clip(res.x, 0.0, 1.0)
    return x if np.all(np.abs(P @ x - q) <= tol) else xf
