"""Deterministic quadrature over the hemisphere, refined toward a lobe.

Two parametrisations: the half-vector frame of :func:`half_vector_breaks` (the
albedo and pdf integrals of :mod:`plausible.analysis.albedo`: the mirror
direction is the pole), and spherical angles about the normal (below; the
chi-square cells and the fits' grids).

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


# -- the half-vector frame ------------------------------------------------------------------

#: Geometric levels toward the pole of the half-vector frame (the mirror direction):
#: panels down to ``2^-POLE_LEVELS`` of the polar range, ~1e-6 rad, a hundred times
#: narrower than the narrowest declared lobe (Cook-Torrance and Ward at ``m = 1e-4``).
POLE_LEVELS = 20
#: Geometric levels toward the horizon (``s = 1``; the ``sqrt(cos theta_o)`` of Ward 1992).
HORIZON_LEVELS = 8
#: Deepest geometric grading in azimuth (toward the edge of the half-vector domain
#: at grazing incidence, whose width is ``cot(theta_i)``).
MAX_LEVELS = 40


def half_vector_tmax(wi, phi):
    """Largest polar angle of a half vector ``h(t, phi)`` whose mirror image of
    ``wi`` lies above the horizon, for each azimuth ``phi`` (radians).

    With ``wo = 2 (wi.h) h - wi`` and ``psi = phi - phi_i``,
    ``wo_z = sin(theta_i) cos(psi) sin(2t) + cos(theta_i) cos(2t) = R cos(2t - delta)``,
    ``delta = atan2(sin(theta_i) cos(psi), cos(theta_i))``; so ``wo_z > 0`` exactly for
    ``t < pi/4 + delta/2`` (and then ``wi.h > 0`` too)."""
    ti, pi_ = _angles(wi)
    delta = np.arctan2(math.sin(ti) * np.cos(np.asarray(phi) - pi_), math.cos(ti))
    return 0.25 * math.pi + 0.5 * delta


def half_vector_lune(wi, phi):
    """Polar angle ``T(phi)`` of the half vector where ``wo`` crosses the great
    circle ``R.wo = 0`` (``R`` the mirror direction of ``wi``), for each azimuth.

    Reflecting about ``n`` and then about ``h`` rotates by ``2t`` about the unit axis
    ``a = (-sin phi, cos phi, 0)``, so ``R.wo = cos(2t) + (1 - cos 2t) q`` with
    ``q = (wi.a)^2 = sin^2(theta_i) sin^2(phi - phi_i)``: decreasing in ``t``, zero at
    ``cos(2t) = -q / (1 - q)`` (``T = pi/2``, no crossing, where ``q >= 1/2``).  So
    ``{R.wo > 0}`` is ``t < T(phi)`` at every azimuth: a curve of the frame, which
    :class:`plausible.analysis.albedo` makes a panel edge for models with
    :meth:`~plausible.bxdf.BxDF.mirror_cut`."""
    ti, pi_ = _angles(wi)
    q = (math.sin(ti) * np.sin(np.asarray(phi) - pi_)) ** 2
    return 0.5 * np.arccos(np.clip(-q / np.maximum(1.0 - q, 1e-300), -1.0, 1.0))


def half_vector_level(wi, phi):
    """Polar angle of the half vector where ``wo`` is as high as ``wi``
    (``wo_z = wi_z``), for each azimuth: ``delta`` of :func:`half_vector_tmax` where
    it is positive (``wo_z = R cos(2t - delta)`` equals ``wi_z = R cos(delta)`` at
    ``t = delta``), else ``0`` (``wo_z < wi_z`` for every ``t > 0``)."""
    ti, pi_ = _angles(wi)
    delta = np.arctan2(math.sin(ti) * np.cos(np.asarray(phi) - pi_), math.cos(ti))
    return np.maximum(delta, 0.0)


def half_vector_vgroove(wi, phi):
    """Polar angles ``(t_i, t_o)`` of the half vector, for each azimuth ``phi``, where the
    V-groove shadowing ``G = min(1, 2 (n.h)(n.wo) / (wo.h), 2 (n.h)(n.wi) / (wi.h))``
    (Cook & Torrance 1982) has its kinks: where the ``wi`` term reaches 1 (``t_i``) and where
    the ``wo`` term does (``t_o``); ``inf`` where a curve misses the azimuth's range
    ``[0, tmax]`` (:func:`half_vector_tmax`).

    With ``a = sin(theta_i) cos(psi)`` and ``wi.h = a sin t + ci cos t`` (``delta = atan2(a, ci)``
    of :func:`half_vector_tmax`): the ``wi`` term is 1 where ``ci cos t = a sin t``,
    ``t_i = pi/2 - delta``, inside the range only for ``delta > pi/6``.  The ``wo`` term
    (``n.wo = 2 (wi.h) cos t - ci``) is 1 where ``(wi.h)(4 cos^2 t - 1) = 2 ci cos t``; divided by
    ``cos^3 t`` this is the cubic ``a (u^3 - 3 u) = ci (1 - 3 u^2)`` in ``u = tan t``, i.e.
    ``tan 3t = -ci / a = tan(delta + pi/2)``: ``t_o = (delta + pi/2) / 3``, the one root in
    ``(0, tmax)`` at every azimuth (``delta > -pi/2``)."""
    ti, pi_ = _angles(wi)
    delta = np.arctan2(math.sin(ti) * np.cos(np.asarray(phi, dtype=np.float64) - pi_), math.cos(ti))
    return np.where(delta > math.pi / 6, 0.5 * math.pi - delta, np.inf), (delta + 0.5 * math.pi) / 3.0


def half_vector_rule(wi, peaks=(), m: int = 3, levels: int = 4, pole_levels: int = 10):
    """A fixed rule for ``int g(wo) d omega_o`` over the upper hemisphere in the
    half-vector frame of :func:`half_vector_breaks` (no tangent axes, no lune):
    ``(wo (N, 3), weight (N,))``, the weight the solid angle of the node
    (``ws wp tmax sin(t) 4 (wi.h)``, the change of variables of
    :func:`plausible.integrals.albedo._grid_sum`).  The mirror direction is the
    edge ``s = 0`` of the domain, so any isotropic lobe about it is resolved
    whatever its width down to ``2^-pole_levels`` of the polar range: at ``m = 3``,
    ``levels = 4``, ``pole_levels = 10`` (about 4,500 nodes an incidence) the albedo of
    Mitsuba's GGX ``roughconductor`` (alpha 0.003-1) and ``principled`` is within
    4e-5 of the adaptive integrator's at 0-80 degrees (``tests/conversion``)."""
    wi = np.asarray(wi, dtype=np.float64)
    sb, pb = half_vector_breaks(wi, peaks, levels, 1, pole_levels=pole_levels, axes=False)
    s, ws = panel_rule(sb, m)
    p, wp = panel_rule(pb, m)
    tmax = half_vector_tmax(wi, p)
    t = s[:, None] * tmax[None, :]
    st, ct = np.sin(t), np.cos(t)
    h = np.stack(np.broadcast_arrays(st * np.cos(p)[None, :], st * np.sin(p)[None, :], ct), axis=-1)
    d = h @ wi
    wo = 2.0 * d[..., None] * h - wi
    w = ws[:, None] * (wp * tmax)[None, :] * st * (4.0 * d)
    return wo.reshape(-1, 3), w.reshape(-1)


def _grade(c, lo, hi, levels):
    """``c`` and ``c +- (hi - lo) 2^-k``, ``k = 1..levels``."""
    d = (hi - lo) * 0.5 ** np.arange(1, levels + 1)
    return np.concatenate([[c], c + d, c - d])


def _merge(lo, hi, pts):
    b = np.unique(np.clip(np.concatenate(pts), lo, hi))
    keep = np.concatenate([[True], np.diff(b) > 1e-13 * (hi - lo)])
    return b[keep]


def half_vector_breaks(wi, peaks, levels: int = 13, refine: int = 1, pole_levels: int = POLE_LEVELS,
                       axes: bool = True, lune: bool = False, azimuths=()):
    """Panel breakpoints ``(s_breaks, phi_breaks)`` of the half-vector frame for the
    incidence ``wi`` (unit, ``wi_z > 0``) and lobe ``peaks``.

    A direction ``wo`` is written through its half vector
    ``h = (sin t cos phi, sin t sin phi, cos t)``, ``wo = 2 (wi.h) h - wi``,
    ``d omega_o = 4 (wi.h) d omega_h``, and ``t = s tmax(phi)``
    (:func:`half_vector_tmax`), ``s`` in ``[0, 1]``: the rectangle ``[0, 1] x
    [phi_i - pi, phi_i + pi]`` covers the upper hemisphere once, the horizon is its
    edge ``s = 1``, and the mirror direction, where every microfacet and
    mirror-centred lobe peaks, is its edge ``s = 0`` whatever the incidence.
    Breakpoints in ``s``: a uniform floor of ``8 refine`` panels, graded toward
    ``s = 0`` down to ``2^-pole_levels`` (lobes of any width down to ``~1e-6`` rad),
    toward the horizon and toward each other peak.  In ``phi``: ``16 refine``
    panels, graded toward the plane of incidence, the peaks' azimuths, the
    tangent axes if ``axes`` (the principal directions of an anisotropic lobe: a
    lobe ``(n.h)^(nu cos^2 + nv sin^2)`` with ``nu = 0``, ``nv = 10^6`` is a band of
    width ``~1/(t sqrt(nv))`` about an axis), and the azimuths ``phi_i +- pi/2``,
    where ``tmax`` turns from ``~0`` to ``~pi/2`` within ``cot(theta_i)`` at grazing
    incidence (and where a lobe round in ``wo`` is stretched in ``h``), graded
    down to that width.  With ``lune`` also toward the azimuths of the two half
    vectors where the circle ``R.wo = 0`` meets the horizon (``wo`` at
    ``phi_i +- pi/2``), where the cut :func:`half_vector_lune` leaves the domain
    (a kink of the panels' outer edge ``min(T, tmax)``), and toward each of ``azimuths``
    (:meth:`~plausible.bxdf.BxDF.kink_azimuths`: where a kink curve enters the range, the
    same kind of edge)."""
    ti, pi_ = _angles(wi)
    lo, hi = pi_ - math.pi, pi_ + math.pi
    # toward the horizon four levels deeper per floor refinement (seen by the refinement's
    # estimate): at grazing incidence the half vector reaches the horizon, where
    # (n.h)^e with a small exponent e (an anisotropic lobe beside its nu = 0 axis) has an
    # endpoint singularity (n.h)^0.09 that eight levels leave at 3e-7 (issue 45)
    horizon = min(pole_levels, HORIZON_LEVELS + 4 * int(round(math.log2(max(refine, 1)))))
    s_pts = [np.linspace(0.0, 1.0, 8 * refine + 1), 0.5 ** np.arange(1, pole_levels + 1),
             1.0 - 0.5 ** np.arange(1, horizon + 1)]
    p_centres = [(pi_, levels // 2), (pi_ + math.pi, levels // 2)]
    if axes:      # two levels deeper per floor refinement (so the refinement's error estimate sees
        # the depth too), down to the pole's: Ward alpha_x = 1e-4, alpha_y = 0.2 is a band 1e-4 / t wide
        deep = min(pole_levels, levels + 2 * int(round(math.log2(max(refine, 1)))))
        p_centres += [(k * 0.5 * math.pi, deep) for k in range(4)]
    for p in peaks:
        p = np.asarray(p, dtype=np.float64)
        h = wi + p / max(np.linalg.norm(p), 1e-300)
        if p[2] <= 0 or np.linalg.norm(h) < 1e-12:
            continue
        th, ph = _angles(h)
        if th > 1e-9:
            s_pts.append(_grade(min(th / float(half_vector_tmax(wi, ph)), 1.0), 0.0, 1.0, levels))
            p_centres.append((ph, levels))
    p_pts = [np.linspace(lo, hi, 16 * refine + 1)]
    perp = int(min(MAX_LEVELS, max(0, math.ceil(math.log2(8 * math.pi * max(math.sin(ti), 1e-300)
                                                          / max(math.cos(ti), 1e-300))))))
    p_centres += [(pi_ - 0.5 * math.pi, perp), (pi_ + 0.5 * math.pi, perp)]
    if lune and ti > 1e-9:
        for sg in (-1.0, 1.0):
            a = pi_ + sg * 0.5 * math.pi
            h = wi + np.array([math.cos(a), math.sin(a), 0.0])
            p_centres.append((math.atan2(h[1], h[0]), levels))
    p_centres += [(float(a), levels) for a in azimuths]
    for c, lv in p_centres:    # each centre and its images a period away (a centre on the seam grades both ends)
        c = lo + (c - lo) % (2 * math.pi)
        p_pts += [_grade(c + k * 2 * math.pi, lo, hi, lv) for k in (-1, 0, 1)]
    return _merge(0.0, 1.0, s_pts), _merge(lo, hi, p_pts)
