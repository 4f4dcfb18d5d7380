"""Deterministic quadrature over the hemisphere, refined toward a lobe.

Directions are parametrised by the spherical angles ``(theta, phi)`` about the
normal, so the horizon ``theta = pi/2`` is an edge of the domain (a lobe clipped
by the horizon needs no special care).  Both angles are cut into panels whose
breakpoints are graded geometrically toward the lobe's peak (the model's
:meth:`~plausible.bxdf.BxDF.peak_directions`, by default the mirror direction)
down to ``2^-K`` of the domain, plus the incidence angle (where ``max(n.k1, n.k2)``
has its kink) and a uniform floor of panels; each panel carries an ``m``-point
Gauss-Legendre rule.  A lobe of angular width ``w`` is therefore always covered
by panels of size ``~w``, whatever the exponent (``w ~ 1/sqrt(n)``: 10^-2 for
``n = 10^4``; the finest panels are ``~10^-4`` rad).

The error estimate compares the ``m``-point and a lower-order rule on the same
panels (the difference bounds the error of the lower rule and, in practice,
overestimates that of the higher one by orders of magnitude).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

HALF_PI = 0.5 * math.pi


@lru_cache(maxsize=None)
def gauss_legendre(m: int):
    x, w = np.polynomial.legendre.leggauss(m)
    return x, w


def graded_breaks(lo: float, hi: float, centers, levels: int = 13, uniform: int = 8) -> np.ndarray:
    """Breakpoints in ``[lo, hi]``: ``uniform`` equal panels, plus points at
    ``c +- (hi - lo) 2^-k`` for every centre ``c`` and ``k = 1..levels``."""
    span = hi - lo
    pts = [np.linspace(lo, hi, uniform + 1)]
    for c in centers:
        if lo <= c <= hi:
            d = span * 0.5 ** np.arange(1, levels + 1)
            pts.append(np.array([c]))
            pts.append(c + d)
            pts.append(c - d)
    b = np.concatenate(pts)
    b = np.unique(np.clip(b, lo, hi))
    # merge breakpoints closer than a tiny tolerance
    keep = np.concatenate([[True], np.diff(b) > 1e-12 * max(span, 1.0)])
    return b[keep]


def panel_rule(breaks: np.ndarray, m: int):
    """Nodes and weights of the composite ``m``-point Gauss-Legendre rule."""
    x, w = gauss_legendre(m)
    a = breaks[:-1, None]
    h = (breaks[1:] - breaks[:-1])[:, None]
    nodes = a + 0.5 * h * (x[None, :] + 1.0)
    weights = 0.5 * h * w[None, :]
    return nodes.ravel(), weights.ravel()


@dataclass
class HemisphereGrid:
    """Tensor-product rule: directions ``wo`` of shape (Nt, Np, 3) and weights
    (solid-angle measure, ``sin(theta) dtheta dphi`` included) of shape (Nt, Np)."""

    theta: np.ndarray
    phi: np.ndarray
    wo: np.ndarray
    weight: np.ndarray


def _angles(d):
    d = np.asarray(d, dtype=np.float64)
    d = d / np.linalg.norm(d)
    theta = math.acos(min(max(d[2], -1.0), 1.0))
    phi = math.atan2(d[1], d[0]) if (d[0] != 0 or d[1] != 0) else 0.0
    return theta, phi


def lobe_breaks(wi, peaks, levels: int = 13, refine: int = 1, theta_range=(0.0, HALF_PI)):
    """Panel breakpoints ``(theta_breaks, phi_breaks, phi0)`` for incidence ``wi``
    (unit, shape (3,)) and lobe ``peaks``: graded toward the peaks' polar angles
    and ``theta_i`` in ``theta``, toward the peaks' azimuths and the plane of
    incidence in ``phi``, over ``[phi0 - pi, phi0 + pi]`` with ``phi0`` the first
    peak's azimuth; ``refine`` multiplies the uniform floor of panels."""
    ti, pi_ = _angles(wi)
    angs = [_angles(p) for p in peaks if np.linalg.norm(p) > 0]
    t_centers = [t for t, _ in angs] + [ti]
    phi0 = angs[0][1] if angs else pi_ + math.pi
    p_centers = [p for t, p in angs if t > 1e-9] + [pi_, pi_ + math.pi]
    # bring the azimuth centres into [phi0 - pi, phi0 + pi]
    p_centers = [phi0 + ((p - phi0 + math.pi) % (2 * math.pi)) - math.pi for p in p_centers]
    theta_breaks = graded_breaks(theta_range[0], theta_range[1], t_centers, levels, 8 * refine)
    phi_breaks = graded_breaks(phi0 - math.pi, phi0 + math.pi, p_centers, levels, 16 * refine)
    return theta_breaks, phi_breaks, phi0


def hemisphere_grid(wi, peaks, m: int = 12, levels: int = 13, theta_range=(0.0, HALF_PI),
                    theta_breaks=None, phi_breaks=None, refine: int = 1) -> HemisphereGrid:
    """Build the graded rule for incidence ``wi`` (unit, shape (3,)) and lobe peaks
    (breakpoints from :func:`lobe_breaks` unless given)."""
    tb, pb, _ = lobe_breaks(wi, peaks, levels, refine, theta_range)
    theta_breaks = tb if theta_breaks is None else theta_breaks
    phi_breaks = pb if phi_breaks is None else phi_breaks
    t, wt = panel_rule(np.asarray(theta_breaks), m)
    p, wp = panel_rule(np.asarray(phi_breaks), m)
    st, ct = np.sin(t), np.cos(t)
    wo = np.stack(np.broadcast_arrays(st[:, None] * np.cos(p)[None, :],
                                      st[:, None] * np.sin(p)[None, :],
                                      ct[:, None]), axis=-1)
    weight = (wt * st)[:, None] * wp[None, :]
    return HemisphereGrid(t, p, wo, weight)
