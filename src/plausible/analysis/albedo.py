"""Directional and hemispherical albedo.

The directional albedo ``a(wi) = int f(wi, wo) cos(theta_o) d omega_o`` is
computed by deterministic quadrature (:mod:`plausible.analysis.quadrature`):
a tensor Gauss-Legendre rule on panels graded toward the lobe, evaluated at two
orders; the difference is returned as the error bound.  Accurate to better than
1e-4 absolute for every registered model, exponents up to 10^4 and incidence up
to 89.9 degrees (tested against closed forms and against Monte Carlo with the
model's own sampler).  It uses only the model contract (``eval`` and the
optional ``peak_directions`` hint).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..bxdf import as_directions
from .quadrature import hemisphere_grid


@dataclass(frozen=True)
class AlbedoResult:
    """``value`` (float, or per-channel array) and ``error``, an estimated bound
    on its absolute error (same shape)."""

    value: np.ndarray | float
    error: np.ndarray | float

    def __float__(self):
        return float(np.mean(self.value))


def direction(theta: float, phi: float = 0.0) -> np.ndarray:
    """Unit vector with polar angle ``theta`` and azimuth ``phi`` (radians)."""
    s = math.sin(theta)
    return np.array([s * math.cos(phi), s * math.sin(phi), math.cos(theta)])


def _integrate_once(model, wi, fn_values, m, levels, refine):
    grid = hemisphere_grid(wi, model.peak_directions(wi), m=m, levels=levels, refine=refine)
    vals = fn_values(grid.wo)
    w = grid.weight
    if vals.ndim == w.ndim + 1:
        w = w[..., None]
    return np.sum(vals * w, axis=(0, 1))


def _integrate(model, wi, fn_values, m, m_low, levels, tol):
    """Integrate with the ``m``-point rule; the error estimate is the larger of
    the differences to the ``m_low``-point rule (smooth integrands) and to the
    same rule on a 2x finer floor of uniform panels (a kink or a jump inside a
    panel, e.g. the truncation of a ``cos^0`` lobe, where both orders err
    alike).  While the estimate exceeds ``tol``, refine the floor 4x (at most
    once) and return the finest estimate."""
    refine = 1
    while True:
        hi = _integrate_once(model, wi, fn_values, m, levels, refine)
        lo = _integrate_once(model, wi, fn_values, m_low, levels, refine)
        fine = _integrate_once(model, wi, fn_values, m, levels, 2 * refine)
        err = np.maximum(np.abs(hi - lo), np.abs(fine - hi)) + 1e-13 * np.abs(hi)
        if np.all(err <= tol) or refine >= 4:
            return fine, err
        refine *= 4


def albedo(model, wi, *, m: int = 12, m_low: int = 8, levels: int = 13,
           tol: float = 2e-5) -> AlbedoResult:
    """Directional albedo ``a(wi) = int f(wi, wo) cos(theta_o) d omega_o``.

    ``wi`` is a direction of shape (3,) (normalised here).  Returns
    :class:`AlbedoResult` with the ``m``-point estimate and the difference to
    the ``m_low``-point rule as its error bound.  Zero for ``wi`` below the horizon.
    """
    wi = as_directions("wi", wi)  # names wi in every error (a string, NaN, a zero vector)
    if wi.shape != (3,):
        raise ValueError(f"wi must be one direction of shape (3,), got {wi.shape}")
    if wi[2] <= 0:
        z = np.zeros(model.channels) if model.channels else 0.0
        return AlbedoResult(z, z)

    def fcos(wo):
        f = model.eval(wi, wo)
        c = wo[..., 2]
        return f * (c[..., None] if f.ndim == c.ndim + 1 else c)

    hi, err = _integrate(model, wi, fcos, m, m_low, levels, tol)
    if np.ndim(hi) == 0:
        return AlbedoResult(float(hi), float(err))
    return AlbedoResult(hi, err)


def pdf_integral(model, wi, *, m: int = 12, m_low: int = 8, levels: int = 13,
                 tol: float = 2e-5) -> AlbedoResult:
    """``int pdf(wi, wo) d omega_o`` over the upper hemisphere (pdf is zero below)."""
    wi = np.asarray(wi, dtype=np.float64)
    wi = wi / np.linalg.norm(wi)
    hi, err = _integrate(model, wi, lambda wo: model.pdf(wi, wo), m, m_low, levels, tol)
    return AlbedoResult(float(hi), float(err))


def albedo_curve(model, thetas, phi: float = 0.0, progress=None, **kw) -> AlbedoResult:
    """Directional albedo at polar angles ``thetas`` (radians) and azimuth ``phi``.

    Returns an :class:`AlbedoResult` whose ``value``/``error`` have shape
    ``(len(thetas),)`` (plus a channel axis for colour models).  ``progress``, if
    given, is called with no argument after each angle.
    """
    thetas = np.atleast_1d(np.asarray(thetas, dtype=np.float64))
    if np.any(~np.isfinite(thetas)) or np.any(thetas < 0) or np.any(thetas > math.pi / 2):
        raise ValueError("thetas must lie in [0, pi/2] radians")
    res = []
    for t in thetas:
        res.append(albedo(model, direction(t, phi), **kw))
        if progress:
            progress()
    return AlbedoResult(np.array([r.value for r in res]), np.array([r.error for r in res]))


def is_isotropic(model, trials: int = 16, seed: int = 7) -> bool:
    """Probe the contract: does rotating both directions about the normal leave ``f``
    unchanged (relative 1e-9) on random pairs?"""
    rng = np.random.default_rng(seed)
    wi = _random_upper(rng, trials)
    wo = _random_upper(rng, trials)
    a = rng.uniform(0, 2 * math.pi, trials)
    c, s = np.cos(a), np.sin(a)

    def rot(w):
        return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=-1)

    f1 = model.eval(wi, wo)
    f2 = model.eval(rot(wi), rot(wo))
    scale = np.maximum(np.abs(f1), np.abs(f2)) + 1e-300
    return bool(np.all(np.abs(f1 - f2) <= 1e-9 * scale + 1e-14))


def _random_upper(rng, n):
    z = rng.uniform(0.05, 1.0, n)
    p = rng.uniform(0, 2 * math.pi, n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(p), s * np.sin(p), z], axis=-1)


def hemispherical_albedo(model, *, n_theta: int = 16, n_phi: int | None = None) -> AlbedoResult:
    """Cosine-weighted average of the directional albedo over the hemisphere,
    ``(1/pi) int a(wi) cos(theta_i) d omega_i = 2 int_0^1 a(mu) mu d mu`` (isotropic),
    by Gauss-Legendre in ``mu = cos(theta_i)`` (and in azimuth for anisotropic models)."""
    from .quadrature import gauss_legendre

    x, w = gauss_legendre(n_theta)
    mu = 0.5 * (x + 1.0)
    wmu = 0.5 * w * 2.0 * mu  # 2 mu d mu on [0, 1]
    if n_phi is None:
        n_phi = 1 if is_isotropic(model) else 8
    phis = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
    tot = 0.0
    err = 0.0
    for ph in phis:
        for m_, wm in zip(mu, wmu):
            r = albedo(model, direction(math.acos(m_), ph))
            tot = tot + wm * np.asarray(r.value) / n_phi
            err = err + wm * np.asarray(r.error) / n_phi
    if np.ndim(tot) == 0:
        return AlbedoResult(float(tot), float(err))
    return AlbedoResult(tot, err)


def albedo_table(model, *, n_phi: int | None = None, n_theta: int = 46, max_theta: int = 361,
                 tol: float = 1e-4, progress=None):
    """The directional albedo of ``model`` tabulated over the hemisphere, as an
    :class:`~plausible.tables.AngleTable` (Catmull-Rom interpolation).

    1-D in the polar angle for an isotropic model (:func:`is_isotropic`), 2-D with
    ``n_phi`` azimuths (default 32) otherwise.  For a colour model the table holds
    the largest channel.  The polar grid starts with ``n_theta`` nodes (2 degrees)
    and is halved while the interpolation error, estimated at the new nodes from
    the coarser table and divided by 8 (the ``O(h^3)`` rate), exceeds ``tol``, up to
    ``max_theta`` nodes.  The node on the horizon is evaluated 1e-6 rad above it
    (at exactly 90 degrees the albedo is zero by convention, not by continuity).
    ``progress``, if given, is called with the number of albedo evaluations just done.
    """
    from ..tables import HALF_PI, AngleTable

    if n_phi is None:
        n_phi = 0 if is_isotropic(model) else 32
    phis = np.arange(n_phi) * (2 * math.pi / n_phi) if n_phi else np.zeros(1)

    def column(theta):
        t = min(theta, HALF_PI - 1e-6)
        row = [np.max(np.atleast_1d(albedo(model, direction(t, ph)).value)) for ph in phis]
        if progress:
            progress(len(phis))
        return np.array(row) if n_phi else row[0]

    thetas = np.linspace(0.0, HALF_PI, n_theta)
    vals = np.array([column(t) for t in thetas])
    while True:
        coarse = AngleTable(vals)
        n = 2 * len(vals) - 1
        if n > max_theta:
            return coarse
        mids = 0.5 * (thetas[:-1] + thetas[1:])
        new = np.array([column(t) for t in mids])
        guess = coarse.lookup_angles(mids, phis if n_phi else None)
        fine = np.empty((n,) + vals.shape[1:])
        fine[0::2] = vals
        fine[1::2] = new
        thetas = np.linspace(0.0, HALF_PI, n)
        vals = fine
        if np.max(np.abs(guess - new)) / 8.0 <= tol:
            return AngleTable(vals)
