"""The Cook-Torrance microfacet BRDF with the Beckmann distribution.

References
----------
* R. L. Cook, K. E. Torrance, "A reflectance model for computer graphics",
  ACM TOG 1(1), 1982 (SIGGRAPH 1981), eqs. for ``D`` (Beckmann) and ``G``.
* P. Beckmann, A. Spizzichino, *The scattering of electromagnetic waves from rough
  surfaces*, 1963.
* L. Szirmay-Kalos (ed.), *Theory of Three-Dimensional Computer Graphics*, 1995
  ([SKe95]), for the V-groove ``G`` as printed in Neumann et al. 1999, eq. 10.
* Neumann, Neumann, Szirmay-Kalos 1999, eqs. 9-11.
* B. Walter, S. Marschner, H. Li, K. Torrance, "Microfacet models for refraction
  through rough surfaces", EGSR 2007, eqs. 20-21 and 28 (normalisation, sampling).

Normalisation.  ``D(h) = exp(-tan^2(delta) / m^2) / (pi m^2 cos^4(delta))``
integrates to 1 against ``cos(delta) d omega_h`` (the microfacet convention), and
``f = F D G / (4 (N.L)(N.V))``.  This is the factor in eq. 11 of the pumping-up
paper, ``1 / (4 pi m^2 cos^4 delta)``.  Cook & Torrance 1982 write
``D = exp(-tan^2/m^2) / (m^2 cos^4)`` (no ``pi``) and ``f = F D G / (pi (N.L)(N.V))``,
which is ``4`` times larger for the same ``D`` shape; the later derivation of the
Jacobian (Walter et al. 2007, eq. 20) gives the ``1/4`` used here.
"""

from __future__ import annotations

import numpy as np

from .. import fresnel, vec, warps
from ..bxdf import BxDF
from ..arrays.ops import PI
from ..params import Param
from ..registry import register
from ..vec import above

GEOMETRY = ("vgroove", "none")
#: Microfacet distributions: Beckmann's, and the normalised Blinn (Phong) distribution
#: ``(n.h)^n`` of :func:`blinn_d` (Blinn 1977's ``D1``; the reading of Wavefront MTL's
#: highlight, ``docs/convert.md``).
DISTRIBUTIONS = ("beckmann", "blinn")


def beckmann_d(ops, h, m):
    """``exp(-tan^2(delta) / m^2) / (pi m^2 cos^4(delta))``, ``cos(delta) = hz``; zero for ``hz <= 0``.

    Computed as ``exp(-tan^2 / m^2 - 4 log(hz)) / (pi m^2)``: near the horizon
    ``hz^4`` underflows (below 1e-38 in float32, where vectorised code flushes it
    to zero) while the Gaussian is already zero, and the quotient as written
    would be 0/0.  The exponent is finite for every ``hz > 0`` and at most
    ``log(4) - 1``, so the value never overflows either.
    """
    ok = h[2] > 0
    z = ops.where(ok, h[2], 1.0)
    tan2 = (h[0] * h[0] + h[1] * h[1]) / (z * z)
    return ops.where(ok, ops.exp(-tan2 / (m * m) - 4.0 * ops.log(z)) / (PI * m * m), 0.0)


def blinn_exponent(m):
    """``n = 2 / m^2 - 2``: the exponent of the Blinn distribution of RMS slope ``m``
    (Walter et al. 2007, section 5.2: the Phong distribution ``alpha_p = 2 alpha_b^-2 - 2``
    matches Beckmann's of slope ``alpha_b`` near the peak)."""
    return 2.0 / (m * m) - 2.0


def blinn_d(ops, h, m):
    """``(n + 2) / (2 pi) (n.h)^n = (n.h)^n / (pi m^2)``, ``n = 2 / m^2 - 2``
    (:func:`blinn_exponent`); zero for ``hz <= 0``.

    Blinn 1977's ``D1 = (N.H)^c``, normalised so that ``int D cos(delta) d omega_h = 1``
    (``int_0^1 x^(n+1) dx 2 pi = 2 pi / (n + 2)``; Walter et al. 2007, eq. 30).  The power
    is taken from ``sin^2(delta)`` (:func:`plausible.warps.pow_cos_from_sin2`), accurate near
    the peak for large ``n``."""
    n = blinn_exponent(m)
    ok = h[2] > 0
    lobe = warps.pow_cos_from_sin2(ops, h[0] * h[0] + h[1] * h[1], n, h[2])
    return ops.where(ok, lobe / (PI * m * m), 0.0)


def vgroove_g(ops, wi, wo, h, vh):
    """``min(1, 2 (N.H)(N.V) / (V.H), 2 (N.H)(N.L) / (V.H))`` (Cook & Torrance 1982;
    pumping-up paper eq. 10).  ``V.H = L.H`` (``vh``, from
    :func:`plausible.vec.half_vector_cos`) so the formula is symmetric."""
    ok = vh > 0
    d = ops.where(ok, vh, 1.0)
    g = ops.minimum(1.0, ops.minimum(2.0 * h[2] * wo[2] / d, 2.0 * h[2] * wi[2] / d))
    return ops.where(ok, g, 0.0)


@register("cook-torrance",
          "Cook-Torrance (1982) microfacet model, Beckmann D, V-groove G: "
          "f = F D G / (4 N.L N.V). Albedo grows without bound at grazing incidence for G = 1.",
          reciprocal=True, energy_conserving=False,
          references=("Cook & Torrance, ACM TOG 1982", "Neumann et al. 1999, eqs. 9-11",
                      "Walter et al., EGSR 2007"))
class CookTorrance(BxDF):
    """``f = F(wi.h) D(h) G / (4 cos_i cos_o)`` (see the module docstring).

    ``fresnel``: ``"schlick"`` (``R0 = rs``), ``"none"`` (``F = rs``; the papers'
    ``F = 1`` is ``rs = 1``) or ``"conductor"`` (``eta + i k``).  ``geometry``:
    ``"vgroove"`` or ``"none"`` (``G = 1``).  ``distribution``: ``"beckmann"`` (default)
    or ``"blinn"`` (:func:`blinn_d`, exponent ``n = 2 / m^2 - 2``).  Sampling: the half
    vector of density ``p_h = D cos(delta)`` (Beckmann's; for Blinn's a ``(n.h)^(n+1)`` lobe,
    :func:`plausible.warps.reflected_half_vector`), reflected, ``pdf = p_h / (4 wi.h)``
    (Walter et al. 2007, eqs. 28, 14).
    """

    PARAMS = (
        Param("m", 0.1, 1e-4, 1.0, doc="Beckmann RMS slope m", extremes=(0.01, 0.5)),
        Param("rs", 1.0, 0.0, 1.0, "color", "specular reflectance / Schlick R0", (0.0, 1.0)),
        Param("fresnel", "schlick", kind="choice", choices=fresnel.FRESNEL_CHOICES),
        Param("geometry", "vgroove", kind="choice", choices=GEOMETRY),
        Param("eta", 0.2, 0.0, 100.0, "color", "conductor index n (fresnel='conductor')"),
        Param("k", 3.0, 0.0, 100.0, "color", "conductor extinction k (fresnel='conductor')"),
        Param("distribution", "beckmann", kind="choice", choices=DISTRIBUTIONS),
    )

    def _f(self, ops, wi, wo, p):
        ok = above(ops, wi, wo)
        h, kh = vec.half_vector_cos(ops, wi, wo)
        ci = ops.where(ok, wi[2], 1.0)
        co = ops.where(ok, wo[2], 1.0)
        g = vgroove_g(ops, wi, wo, h, kh) if p.geometry == "vgroove" else 1.0
        F = fresnel.weight(ops, p.fresnel, kh, p.rs, p.eta, p.k)
        d = blinn_d(ops, h, p.m) if p.distribution == "blinn" else beckmann_d(ops, h, p.m)
        return ops.where(ok, F * d * g / (4.0 * ci * co), 0.0)

    def kink_curves(self, wi, phi):
        """The V-groove's two kinks (:func:`~plausible.integrals.quadrature.half_vector_vgroove`),
        each left out where the distribution there is below ``exp(-36)`` of its peak (the
        exponent ``tan^2 t / m^2``, Blinn's ``-n log cos t``): a kink in a lobe's far tail
        moves no digit of the albedo and would only cost nodes."""
        if self.params["geometry"] != "vgroove":
            return []
        from ..integrals.quadrature import half_vector_vgroove

        m = float(np.max(self.params["m"]))
        out = []
        for t in half_vector_vgroove(wi, phi):
            with np.errstate(invalid="ignore", over="ignore", divide="ignore"):
                if self.params["distribution"] == "blinn":
                    tail = -blinn_exponent(m) * np.log(np.cos(t))
                else:
                    tail = np.tan(t) ** 2 / (m * m)
            out.append(np.where(np.isfinite(t) & (tail < 36.0), t, np.inf))
        return out

    def kink_azimuths(self, wi):
        """Where the ``wi`` term's kink enters the range: ``delta = pi/6``
        (:func:`~plausible.integrals.quadrature.half_vector_vgroove`), at ``psi = +-acos(cot(theta_i) / sqrt(3))``
        from the incidence's azimuth (beyond 60 degrees of incidence); the ``wo`` term's is inside at every azimuth."""
        if self.params["geometry"] != "vgroove":
            return []
        wi = np.asarray(wi, dtype=np.float64)
        si, ci = float(np.hypot(wi[0], wi[1])), float(wi[2])
        if si <= np.sqrt(3.0) * ci:
            return []
        psi, phi_i = float(np.arccos(ci / (np.sqrt(3.0) * si))), float(np.arctan2(wi[1], wi[0]))
        return [phi_i - psi, phi_i + psi]

    def _pdf(self, ops, wi, wo, q):
        if q.distribution == "blinn":
            e = blinn_exponent(q.m) + 1.0
            return warps.reflected_half_vector_pdf(ops, wi, wo, e, e)
        return warps.beckmann_reflected_pdf(ops, wi, wo, q.m, q.m)

    def _sample(self, ops, wi, u, q):
        if q.distribution == "blinn":
            e = blinn_exponent(q.m) + 1.0
            return warps.reflected_half_vector(ops, wi, e, e, u[1], u[2])
        h = warps.beckmann_half_vector(ops, q.m, q.m, u[1], u[2])
        return vec.reflect(wi, h)
