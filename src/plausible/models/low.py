"""The two models of Löw, Kronander, Ynnerman & Unger (2012), built on their ABC curve.

J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF models for accurate and
efficient rendering of glossy surfaces", ACM TOG 31(1), 2012, as read by bbm
(P. Peers, ``include/bsdfmodel/lowsmooth.h``, ``lowmicrofacet.h``, ``low.h``,
``include/ndf/low.h``).  Derivations and choices: ``docs/models/low.md``.

Both use the "ABC" curve ``S(f) = A / (1 + B f^2)^C`` (eq. 8):

* **smooth surface** (``low-smooth``, eqs. 10-14): with the projections
  ``Ip = xy(wi)``, ``Op = xy(wo)`` on the tangent plane, ``D_p = Ip + Op`` (the
  offset of ``Op`` from the mirror of ``Ip``) and
  ``cos(theta_d) = sqrt(1 - |Ip - Op|^2 / 4)`` (eq. 14),
  ``f = A (1 + B |D_p|^2)^-C F(cos theta_d, eta)`` (eq. 12, the geometry factor
  taken as 1, as bbm does);
* **microfacet** (``low-microfacet``, eq. 15): ``D(h) = (1 + B (1 - n.h))^-C``
  (``S`` of ``f = sqrt(1 - n.h)``, unnormalised, ``A`` outside),
  ``f = A D(h) G F(k.h, eta) / (N cos_i cos_o)`` with Cook & Torrance's
  V-groove ``G`` and ``N = pi`` (bbm's normalisation, that of the published fits)
  or ``N = 1`` (eq. 15 as printed, ``normalization="none"``).

``F`` is the exact unpolarised Fresnel reflectance of a dielectric of index
``eta`` in Cook & Torrance's form (:func:`plausible.fresnel.cook`, as bbm),
exactly 0 at ``eta = 1``.
"""

from __future__ import annotations

import numpy as np

from .. import fresnel, vec, warps
from ..bxdf import BxDF
from ..arrays.ops import INV_PI, PI
from ..params import Param
from ..registry import register
from ..vec import above
from .cook_torrance import vgroove_g

REFERENCES = (
    "Löw, Kronander, Ynnerman, Unger, BRDF models for accurate and efficient rendering of "
    "glossy surfaces, ACM TOG 31(1), 2012",
    "bbm (P. Peers), include/bsdfmodel/lowsmooth.h, lowmicrofacet.h, include/ndf/low.h",
)
NORMALIZATION = ("pi", "none")
#: ``|C - 1|`` below which the closed forms use their ``C = 1`` limits.
C_ONE = 1e-6


def _params(default_a):
    return (
        Param("A", default_a, 0.0, 1e12, "color", "scale A of the ABC curve", (0.0, 10.0 * default_a)),
        Param("B", 1000.0, 1e-6, 1e9, doc="sharpness B of the ABC curve", extremes=(10.0, 1e6)),
        Param("C", 1.2, 0.0, 20.0, doc="fall-off exponent C of the ABC curve", extremes=(0.3, 1.0, 3.0)),
        Param("eta", 1.5, 1.0, 100.0, doc="index of refraction of the dielectric (Fresnel factor)",
              extremes=(1.0, 20.0)),
    )


def log_power_integral(ops, L, a):
    """``(1 - exp(-a L)) / a`` for ``L >= 0`` (``int_0^L exp(-a t) dt``), with its
    ``a -> 0`` limit ``L - a L^2 / 2 + a^2 L^3 / 6`` for ``|a| < 1e-6``."""
    small = ops.abs(a) < C_ONE
    asafe = ops.where(small, 1.0, a)
    exact = (1.0 - ops.exp(-asafe * L)) / asafe
    return ops.where(small, L * (1.0 - a * L * (0.5 - a * L / 6.0)), exact)


def _expm1(ops, x):
    """``exp(x) - 1`` for ``x >= 0`` to full relative accuracy (``x + x^2/2 + x^3/6 + x^4/24``
    below 1e-4; Dr.Jit has no ``expm1``)."""
    small = x < 1e-4
    return ops.where(small, x * (1.0 + x * (0.5 + x * (1.0 / 6.0 + x / 24.0))), ops.exp(x) - 1.0)


# -- microfacet ------------------------------------------------------------------------

def abc_ndf(ops, h, B, C):
    """``(1 + B (1 - n.h))^-C`` for ``n.h > 0``, else 0 (Löw et al. eq. 15's ``D``, unnormalised)."""
    ok = h[2] > 0
    z = ops.where(ok, h[2], 1.0)
    omz = (h[0] * h[0] + h[1] * h[1]) / (1.0 + z)     # 1 - n.h of a unit h, without cancellation
    return ops.where(ok, ops.exp(-C * ops.log1p(B * omz)), 0.0)


def abc_ndf_integral(ops, B, C):
    """``int_{H^2} D domega_h = 2 pi int_0^1 (1 + B (1 - z))^-C dz
    = 2 pi (1 - (1 + B)^(1 - C)) / (B (C - 1))`` (``2 pi log(1 + B) / B`` at ``C = 1``)."""
    return 2.0 * PI * log_power_integral(ops, ops.log1p(B), C - 1.0) / B


def abc_half_vector(ops, B, C, u1, u2):
    """``h`` with density ``D(h) / int D`` per solid angle: ``t = 1 + B (1 - z)`` from
    ``t^(1 - C) = 1 - u1 (1 - (1 + B)^(1 - C))`` (``t = (1 + B)^u1`` at ``C = 1``)."""
    a = C - 1.0
    L = ops.log1p(B)
    small = ops.abs(a) < C_ONE
    asafe = ops.where(small, 1.0, a)
    w = 1.0 - u1 * (1.0 - ops.exp(-asafe * L))
    lt = ops.where(small, u1 * L, -ops.log(ops.maximum(w, 1e-300)) / asafe)
    omz = ops.minimum(ops.maximum(_expm1(ops, lt) / B, 0.0), 1.0)     # 1 - z, without cancellation
    z = 1.0 - omz
    s = ops.sqrt(omz * (2.0 - omz))
    phi = 2.0 * PI * u2
    return (s * ops.cos(phi), s * ops.sin(phi), z)


def microfacet(ops, wi, wo, p):
    """``A D(h) G F(k.h) / (N cos_i cos_o)``, ``N = pi`` or 1 (module docstring)."""
    ok = above(ops, wi, wo)
    h, kh = vec.half_vector_cos(ops, wi, wo)
    ci = ops.where(ok, wi[2], 1.0)
    co = ops.where(ok, wo[2], 1.0)
    F = fresnel.cook(ops, kh, p.eta)
    g = vgroove_g(ops, wi, wo, h, kh)
    inv_n = INV_PI if p.normalization == "pi" else 1.0
    return ops.where(ok, p.A * (abc_ndf(ops, h, p.B, p.C) * g * F * inv_n) / (ci * co), 0.0)


@register("low-microfacet",
          "Löw et al. (2012) microfacet model: A (1 + B (1 - n.h))^-C G F / (pi cos_i cos_o), "
          "V-groove G, exact dielectric Fresnel (eta); normalization 'none' drops the pi (eq. 15 as printed).",
          reciprocal=True, energy_conserving=False, references=REFERENCES)
class LowMicrofacet(BxDF):
    """Sampling: ``h`` from ``D / int D`` (:func:`abc_half_vector`), reflected;
    ``pdf = D / (int D) / (4 k.h)``.  Not energy conserving (``A`` is free; the
    published fits reach albedos far above 1, docs/models/low.md)."""

    PARAMS = _params(100.0) + (
        Param("normalization", "pi", kind="choice", choices=NORMALIZATION,
              doc="'pi': f = A D G F / (pi cos_i cos_o) (bbm, the published fits); 'none': eq. 15 as printed"),
    )

    def _f(self, ops, wi, wo, p):
        return microfacet(ops, wi, wo, p)

    def _pdf(self, ops, wi, wo, q):
        norm = abc_ndf_integral(ops, q.B, q.C)
        return warps.reflected_pdf(ops, wi, wo, lambda h: abc_ndf(ops, h, q.B, q.C) / norm)

    def _sample(self, ops, wi, u, q):
        return vec.reflect(wi, abc_half_vector(ops, q.B, q.C, u[1], u[2]))


# -- smooth surface ----------------------------------------------------------------------

def smooth(ops, wi, wo, p):
    """``A (1 + B |Ip + Op|^2)^-C F(sqrt(1 - |Ip - Op|^2 / 4), eta)`` (eqs. 12, 14)."""
    ok = above(ops, wi, wo)
    dx, dy = wi[0] + wo[0], wi[1] + wo[1]
    ex, ey = wi[0] - wo[0], wi[1] - wo[1]
    cd = ops.sqrt(ops.maximum(1.0 - 0.25 * (ex * ex + ey * ey), 0.0))
    s = ops.exp(-p.C * ops.log1p(p.B * (dx * dx + dy * dy)))
    return ops.where(ok, p.A * (s * fresnel.cook(ops, cd, p.eta)), 0.0)


#: Exponent of the sampling density of ``D_p`` (at least 1.5: integrable on the plane).
SMOOTH_SAMPLING_MIN_C = 1.5


@register("low-smooth",
          "Löw et al. (2012) smooth-surface model: A (1 + B |Ip + Op|^2)^-C F(theta_d), "
          "Ip, Op the directions projected on the tangent plane; exact dielectric Fresnel (eta).",
          reciprocal=True, energy_conserving=False, references=REFERENCES)
class LowSmooth(BxDF):
    """Sampling: with probability 0.9 the offset ``D_p = Ip + Op`` from the planar
    density ``(c - 1) B / pi (1 + B |D_p|^2)^-c``, ``c = max(C, 1.5)`` (inverse CDF
    ``B r^2 = (1 - u)^(-1 / (c - 1)) - 1``), ``Op = D_p - Ip``, invalid outside
    the unit disc; else the cosine-weighted hemisphere.  ``pdf = cos(theta_o)
    p(D_p)`` per solid angle (``d^2 Op = cos(theta_o) d omega``).  (bbm samples
    the untruncated disc density of its eqs. 17-22 instead.)"""

    PARAMS = _params(100.0)
    #: Probability of the ABC lobe in the sampling mixture.
    LOBE_PROBABILITY = 0.9

    @staticmethod
    def _c(ops, q):
        return ops.maximum(q.C, SMOOTH_SAMPLING_MIN_C)

    def _f(self, ops, wi, wo, p):
        return smooth(ops, wi, wo, p)

    def _pdf(self, ops, wi, wo, q):
        c = self._c(ops, q)
        dx, dy = wi[0] + wo[0], wi[1] + wo[1]
        lobe = (c - 1.0) * q.B * INV_PI * ops.exp(-c * ops.log1p(q.B * (dx * dx + dy * dy)))
        pl = self.LOBE_PROBABILITY
        z = ops.maximum(wo[2], 0.0)
        return ops.where(above(ops, wi, wo), z * (pl * lobe + (1.0 - pl) * INV_PI), 0.0)

    def _sample(self, ops, wi, u, q):
        c = self._c(ops, q)
        pl = self.LOBE_PROBABILITY
        # (1 - u)^(-1/(c-1)) - 1, as expm1 of the log (small u: no cancellation)
        t = -ops.log(ops.maximum(1.0 - u[1], 1e-300)) / (c - 1.0)
        r = ops.sqrt(ops.maximum(ops.exp(t) - 1.0, 0.0) / q.B)
        lobe = warps.projected_offset(ops, wi, r, 2.0 * PI * u[2])
        return warps.mixture(ops, u[0] < pl, lobe, warps.cosine_hemisphere(ops, u[1], u[2]))

    def peak_directions(self, wi):
        return [np.array([-wi[0], -wi[1], wi[2]])]


__all__ = ["LowMicrofacet", "LowSmooth", "abc_half_vector", "abc_ndf", "abc_ndf_integral",
           "log_power_integral", "microfacet", "smooth"]
