"""Schlick's inexpensive BRDF (C. Schlick, "An inexpensive BRDF model for
physically-based rendering", Computer Graphics Forum 13(3):233-246, 1994).

No copy of the paper is in the project's library; the formulas below are
reconstructed from the published model as it is widely reproduced, checked
against its own stated properties (normalisations, invertible sampling
formulas), and the choices are listed in ``docs/models/schlick.md``.

Variables (Schlick's notation), for ``wi = V``, ``wo = V'`` and the half
vector ``h``:

* ``t = n . h`` (cosine of the half vector's zenith angle),
* ``u = V . h = V' . h`` (cosine of the angle of incidence on the microfacet),
* ``v = n . V``, ``v' = n . V'``,
* ``w = cos(phi_h)``: cosine of the azimuth of ``h`` projected onto the
  tangent plane, measured from the tangent ``x``.

Parameters: roughness ``r`` in ``(0, 1]`` (``r -> 0`` mirror, ``r = 1``
Lambertian-like), isotropy ``p`` in ``(0, 1]`` (``p = 1`` isotropic, ``p -> 0``
strongly anisotropic, with the highlight stretched across ``x``), ``rs`` the
normal-incidence reflectance of the Fresnel term, ``rd`` a Lambertian diffuse
term.

Implemented ("single slope" specular plus Lambert):

``f = rd / pi + F(u) G(v) G(v') Z(t) A(w) / (4 pi v v')``

with ``F(u) = rs + (1 - rs)(1 - u)^5`` (:func:`plausible.fresnel.schlick`),
``G(v) = v / (r - r v + v)``, ``Z(t) = r / (1 + r t^2 - t^2)^2`` and the
azimuth factor ``A(w) = p / (p^2 - p^2 w^2 + w^2)``.  ``D = Z A / pi`` is a
normalised microfacet distribution (``int D (n.h) d omega_h = 1``), so the
specular term is the microfacet form ``F G D / (4 v v')``.

Schlick's ``A`` is often reproduced with a square root,
``sqrt(p / (p^2 - p^2 w^2 + w^2))``; that form does not satisfy the
normalisation ``(1 / 2 pi) int A d phi = 1`` (it equals
``sqrt(p) 4 K(1 - p^2) / (2 pi)``: 0.971 for ``p = 0.5``, 0.744 for ``p = 0.1``),
whereas the form without the root satisfies it exactly and is precisely the
density that Schlick's published inversion ``w = sqrt(p^2 b^2 / (1 - b^2 +
b^2 p^2))`` samples (with ``b = cos(pi xi / 2)``).  The mathematics decides:
the default is the normalised form; ``azimuth="sqrt"`` selects the root form
(sampled with the same, still exact, density).
"""

from __future__ import annotations

import numpy as np

from .. import fresnel, vec, warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI, PI
from ..params import Param
from ..registry import register
from ..vec import above


def zenith(ops, sin2_h, r):
    """``Z(t) = r / (1 + r t^2 - t^2)^2`` (Schlick 1994, slope distribution).

    Written as ``r / (r + (1 - r) sin^2(theta_h))^2`` (the same expression,
    since ``1 - t^2 = sin^2``), which keeps its digits near the peak.
    Normalised as ``int_0^1 2 Z(t) t dt = 1``, i.e. ``int Z t / pi d omega_h = 1``.
    """
    den = r + (1.0 - r) * sin2_h
    return r / (den * den)


#: ``sin^2(theta_h)`` below which a half vector counts as the pole ``h = n``
#: (see :func:`azimuth_normalised`).
POLE_SIN2 = 1e-12


def azimuth_normalised(ops, hx, hy, p):
    """``A(w) = p / (p^2 - p^2 w^2 + w^2)`` with ``w^2 = hx^2 / (hx^2 + hy^2)``.

    Computed as ``p (hx^2 + hy^2) / (hx^2 + p^2 hy^2)`` (no division by zero
    off the pole); at the pole, where ``w`` is undefined, the value is 1, the
    mean over ``phi``.  "The pole" is ``hx^2 + hy^2 <= POLE_SIN2`` (``theta_h``
    below 1e-6 rad): there ``hx, hy`` of a unit half vector are rounding noise
    (about 1e-16 in float64, 1e-7 in float32, e.g. at the exact mirror direction,
    where the sampler and ``pdf()`` would otherwise get any ``A`` in
    ``[p, 1/p]`` from the last bits).  The cap has solid angle ``pi 1e-12``.
    Normalised: ``(1 / 2 pi) int_0^{2 pi} A(cos phi) d phi = 1``.
    """
    s = hx * hx + hy * hy
    den = hx * hx + p * p * hy * hy
    pos = s > POLE_SIN2
    return ops.where(pos, p * s / ops.where(pos, den, 1.0), 1.0)


def azimuth(ops, hx, hy, p, form):
    """Schlick's azimuth factor; ``form="sqrt"`` gives ``sqrt(p / (p^2 - p^2 w^2 + w^2))``."""
    a = azimuth_normalised(ops, hx, hy, p)
    return ops.sqrt(a) if form == "sqrt" else a


def smith_g_over_v(ops, v, r):
    """Schlick 1994's rational approximation of Smith's shadowing,
    ``G(v) = v / (r - r v + v)``, divided by ``v``: ``G(v) / v = 1 / (r - r v + v)``, finite at grazing ``v -> 0`` (where
    ``G(v) G(v') / (v v')`` computed as written would underflow to 0/0)."""
    c = ops.minimum(ops.maximum(v, 0.0), 1.0)
    den = r - r * c + c
    return ops.where(den > 0, 1.0 / ops.where(den > 0, den, 1.0), 0.0)


def half_vector_pdf(ops, h, r, p):
    """``p_h(h) = Z(t) t A(w) / pi`` (normalised ``A``), ``t = h.z > 0``: the
    density of :func:`sample_half_vector` per unit solid angle of ``h``."""
    s = h[0] * h[0] + h[1] * h[1]
    t = ops.maximum(h[2], 0.0)
    val = zenith(ops, s, r) * t * azimuth_normalised(ops, h[0], h[1], p) * INV_PI
    return ops.where(h[2] > 0, val, 0.0)


def sample_half_vector(ops, r, p, u1, u2):
    """Half vector with density :func:`half_vector_pdf`.

    Zenith (inverse CDF of ``2 Z(t) t dt``, Schlick's formula):
    ``t^2 = x / (r - x r + x)`` with ``x = u2``, and
    ``sin^2 = r (1 - x) / (r - x r + x)``.  Azimuth: inverse CDF of
    ``A(cos phi) / (2 pi)``, ``tan(phi) = tan(pi xi / 2) / p`` per quadrant,
    i.e. Schlick's ``w = sqrt(p^2 b^2 / (1 - b^2 + b^2 p^2))`` with
    ``b = cos(pi xi / 2)``.  That is the Ashikhmin-Shirley quadrant warp with
    ``sqrt((nu + 1) / (nv + 1)) = 1 / p``; it is reused (evaluated at the
    horizon, ``u2 = 1``, where it returns ``(cos phi, sin phi, 0)``) rather
    than written again.
    """
    one = u2 * 0.0 + 1.0
    az = warps.anisotropic_half_vector(ops, 1.0 / (p * p) - 1.0, 0.0, u1, one)
    x = u2
    den = r - x * r + x
    inv = 1.0 / ops.where(den > 0, den, 1.0)
    cos_t = ops.sqrt(ops.maximum(x * inv, 0.0))
    sin_t = ops.sqrt(ops.maximum(r * (1.0 - x) * inv, 0.0))
    return (sin_t * az[0], sin_t * az[1], cos_t)


def schlick_specular(ops, wi, wo, r, p, rs, form):
    """``F(u) G(v) G(v') Z(t) A(w) / (4 pi v v')`` (Schlick 1994, single slope)."""
    ok = above(ops, wi, wo)
    h, u = vec.half_vector_cos(ops, wi, wo)
    s = h[0] * h[0] + h[1] * h[1]
    v = ops.where(ok, wi[2], 1.0)
    vp = ops.where(ok, wo[2], 1.0)
    val = (fresnel.schlick(ops, u, rs) * smith_g_over_v(ops, v, r) * smith_g_over_v(ops, vp, r)
           * zenith(ops, s, r) * azimuth(ops, h[0], h[1], p, form) / (4.0 * PI))
    return ops.where(ok, val, 0.0)


def _schlick_glossy(ops, wi, wo, p):
    return ops.where(above(ops, wi, wo), schlick_specular(ops, wi, wo, p.r, p.p, p.rs, p.azimuth), 0.0)


def _schlick_diffuse(ops, wi, wo, p):
    return ops.where(above(ops, wi, wo), p.rd * INV_PI, 0.0)


@register("schlick",
          "Schlick 1994 inexpensive BRDF, single slope: f = rd/pi + F(u) G(v) G(v') Z(t) A(w) / "
          "(4 pi v v'); roughness r, isotropy p.",
          energy_conserving=False,
          references=("C. Schlick, 'An inexpensive BRDF model for physically-based rendering', "
                      "Computer Graphics Forum 13(3), 1994",))
class Schlick(BxDF):
    """``Schlick(r, p, rs, rd, azimuth="normalised")``.

    ``f = rd / pi + F(u) G(v) G(v') Z(t) A(w) / (4 pi v v')``.  Sampling: with
    probability ``ps = F(n.wi) / (F(n.wi) + rd)`` (channel means) the half
    vector from ``Z(t) t A(w) / pi``, reflected; otherwise cosine weighted.
    Not guaranteed energy conserving (a Lambert term is added to a Fresnel
    term that tends to 1 at grazing angles); ``plausible check`` reports it.
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (
        Param("r", 0.2, 1e-3, 1.0, "scalar", "roughness (0 mirror, 1 diffuse)", (1e-3, 1.0)),
        Param("p", 1.0, 1e-3, 1.0, "scalar", "isotropy (1 isotropic, 0 anisotropic)", (1e-3, 0.1)),
        Param("rs", 0.5, 0.0, 1.0, "color", "Fresnel reflectance at normal incidence", (0.0, 1.0)),
        Param("rd", 0.2, 0.0, 1.0, "color", "Lambertian diffuse reflectance", (0.0, 1.0)),
        Param("azimuth", "normalised", kind="choice", choices=("normalised", "sqrt"),
              doc="azimuth factor: normalised p/(p^2-p^2w^2+w^2) or its square root"),
    )

    def _f(self, ops, wi, wo, p):
        return _schlick_glossy(ops, wi, wo, p) + _schlick_diffuse(ops, wi, wo, p)

    def lobes(self):
        """The specular term (half vector from ``Z(t) t A(w) / pi``, reflected), then
        the Lambertian term (albedo ``rd``)."""
        return (Lobe("glossy", _schlick_glossy,
                     lambda ops, wi, wo, q: warps.reflected_pdf(
                         ops, wi, wo, lambda h: half_vector_pdf(ops, h, q.r, q.p)),
                     lambda ops, wi, u, q: vec.reflect(wi, sample_half_vector(ops, q.r, q.p, u[1], u[2]))),
                Lobe("diffuse", _schlick_diffuse,
                     lambda ops, wi, wo, q: ops.where(above(ops, wi, wo),
                                                      warps.cosine_hemisphere_pdf(ops, wo), 0.0),
                     lambda ops, wi, u, q: warps.cosine_hemisphere(ops, u[1], u[2]),
                     lambda ops, wi, p: p.rd))

    def lobe_weights(self, ops, wi, q):
        """``F(n.wi)`` and ``rd`` (channel means): ``ps = F / (F + rd)``."""
        return fresnel.schlick(ops, wi[2], q.rs), q.rd

    def peak_directions(self, wi: np.ndarray) -> list:
        return [np.array([-wi[0], -wi[1], wi[2]]), np.array([0.0, 0.0, 1.0])]
