"""The Ashikhmin--Shirley anisotropic Phong BRDF.

M. Ashikhmin, P. Shirley, "An anisotropic Phong BRDF model", Journal of
Graphics Tools 5(2), 2000 (``ashikhmin-shirley-2000-jgt.txt``, the version that
decides) and the technical report UUCS-00-014 "An anisotropic Phong light
reflection model" (``ashikhmin-shirley-2000-tech-report.txt``, the derivation).

``rho = rho_s + rho_d`` (journal eq. 1, report eqs. 1 and 15):

* ``rho_s`` -- a Fresnel-weighted anisotropic Blinn-Phong lobe about the half
  vector (journal eqs. 2-4, report eqs. 10, 11, 16), written here as
  ``p_h(h) F(k.h) / (4 (k.h) max(n.k1, n.k2))`` with ``p_h`` the half-vector
  density of journal eq. 6, so the lobe exists once (in :mod:`plausible.warps`)
  and is shared with the sampler;
* ``rho_d`` -- the non-Lambertian diffuse term of journal eq. 5 (report eq. 14),
  whose directional albedo is ``rd (1 - rs) (1 - (1 - cos(theta)/2)^5)`` exactly
  (derived in ``docs/models/ashikhmin-shirley.md``).

Notation: ``k1 = wi``, ``k2 = wo``, ``u = x``, ``v = y``, ``n = z``.
"""

from __future__ import annotations

import numpy as np

from .. import vec, warps
from ..bxdf import BxDF, Lobe
from ..fresnel import schlick
from ..arrays.ops import PI
from ..params import Param
from ..registry import register
from ..vec import above

REFERENCES = (
    "Ashikhmin & Shirley, An anisotropic Phong BRDF model, JGT 5(2), 2000",
    "Ashikhmin & Shirley, An anisotropic Phong light reflection model, "
    "tech. report UUCS-00-014, 2000",
)

#: Constant of the diffuse term, ``28 / (23 pi)`` (journal eq. 5).
DIFFUSE_NORM = 28.0 / (23.0 * PI)


def _exponent_param(name, axis):
    return Param(name, 100.0, 0.0, 1e6, "scalar",
                 f"Phong-like exponent of the lobe along the {axis} tangent "
                 f"(larger is narrower along {axis})", (0.0, 1.0, 1e4))


NU = _exponent_param("nu", "u (x)")
NV = _exponent_param("nv", "v (y)")
RS = Param("rs", 0.05, 0.0, 1.0, "color",
           "specular reflectance at normal incidence (Schlick's R0)", (0.0, 1.0))
RD = Param("rd", 0.5, 0.0, 1.0, "color",
           "diffuse reflectance of the substrate under the specular coating", (0.0, 1.0))


# -- the formulas ---------------------------------------------------------------

def half_vector_exponent(ops, h, nu, nv):
    """``nu cos^2(phi_h) + nv sin^2(phi_h) = (nu hu^2 + nv hv^2) / (1 - hn^2)``
    (journal eq. 4, report eq. 16), without trigonometry.

    Isotropic fast path: when ``nu == nv`` as plain floats the exponent is ``nu``
    itself (no division, no 0/0 at ``h = n``); otherwise
    :func:`plausible.warps.anisotropic_exponent`, which equals ``nu`` to rounding
    when ``nu == nv``.  Arrays (parameters as kernel data, differentiable
    textures) always take the general formula: one kernel for every value, and
    derivatives with respect to both exponents (an ``ops.where`` on ``nu == nv``
    would give ``nv`` a zero derivative at ``nu == nv``).
    """
    if isinstance(nu, float) and isinstance(nv, float) and nu == nv:
        return nu
    return warps.anisotropic_exponent(ops, h[0], h[1], nu, nv)


def half_vector_density(ops, h, nu, nv):
    """``p_h(h) = sqrt((nu+1)(nv+1)) / (2 pi) (n.h)^(nu cos^2 phi + nv sin^2 phi)``,
    journal eq. 6 (report eq. 5); zero for ``h.z <= 0``.  Exactly the peak value
    ``sqrt((nu+1)(nv+1)) / (2 pi)`` at ``h = n``."""
    return warps.half_vector_lobe_pdf(ops, nu, nv, h, half_vector_exponent(ops, h, nu, nv))


def specular(ops, wi, wo, nu, nv, rs):
    """Specular term, journal eq. 4 (report eq. 16):

    ``rho_s = sqrt((nu+1)(nv+1)) / (8 pi) (n.h)^e / ((h.k) max(n.k1, n.k2)) F(h.k)``
    ``      = p_h(h) F(h.k) / (4 (h.k) max(n.k1, n.k2))``

    with ``F`` Schlick's approximation (journal eq. 3) and ``p_h`` journal eq. 6.
    ``h.k = |k1 + k2| / 2`` (:func:`plausible.vec.half_vector_cos`; equal to
    ``k1.h`` and ``k2.h`` in exact arithmetic): bitwise reciprocal, accurate at
    grazing incidence where the dot products cancel, and the same ``h.k`` as
    the density :func:`specular_pdf`, so ``f cos / pdf`` stays bounded in
    float32 too.  Zero unless both directions are above the horizon.
    """
    ok = above(ops, wi, wo)
    h, kh = vec.half_vector_cos(ops, wi, wo)
    ok = ok & (kh > 0)
    den = 4.0 * ops.where(ok, kh * ops.maximum(wi[2], wo[2]), 1.0)
    val = half_vector_density(ops, h, nu, nv) * schlick(ops, kh, rs) / den
    return ops.where(ok, val, 0.0)


def diffuse_factor(cos_theta):
    """``1 - (1 - cos(theta)/2)^5`` (journal eq. 5, report eq. 14), in the
    expanded Horner form ``x (5 - 10x + 10x^2 - 5x^3 + x^4)``, ``x = cos(theta)/2``,
    which keeps full relative accuracy near grazing (the difference form
    cancels).  It is also the diffuse term's normalised directional albedo."""
    x = 0.5 * cos_theta
    return x * (5.0 + x * (-10.0 + x * (10.0 + x * (-5.0 + x))))


def diffuse(ops, wi, wo, rs, rd):
    """Diffuse term, journal eq. 5 (report eq. 14):

    ``rho_d = 28 rd / (23 pi) (1 - rs) (1 - (1 - n.k1/2)^5) (1 - (1 - n.k2/2)^5)``.
    """
    ok = above(ops, wi, wo)
    ci = ops.where(ok, wi[2], 0.0)
    co = ops.where(ok, wo[2], 0.0)
    # The product of the two factors first: f(a, b) == f(b, a) bitwise.
    val = (DIFFUSE_NORM * rd * (1.0 - rs)) * (diffuse_factor(ci) * diffuse_factor(co))
    return ops.where(ok, val, 0.0)


def diffuse_albedo(cos_theta, rs, rd):
    """Directional albedo of :func:`diffuse`: ``rd (1 - rs) (1 - (1 - cos(theta)/2)^5)``.

    Derived (docs): ``int_{H^2} (1 - (1 - z/2)^5) z d omega = 23 pi / 28``, so the
    constant ``28 / (23 pi)`` of journal eq. 5 cancels exactly.  The hemispherical
    albedo is ``23/28 rd (1 - rs)``.
    """
    return rd * (1.0 - rs) * diffuse_factor(cos_theta)


def specular_probability(ops, cos_i, rs, rd):
    """Probability of sampling the specular lobe, per incident direction.

    ``ps = Fs / (Fs + Ad)`` with ``Fs = F(cos theta_i)`` (Schlick, mean ``rs``),
    an estimate of the specular albedo, and ``Ad`` the diffuse albedo
    :func:`diffuse_albedo` (mean ``rs``, ``rd``).  ``Fs + Ad == 0`` happens only
    where the diffuse term vanishes (``rd == 0`` or ``rs == 1``) or at the
    horizon; ``ps = 1`` there.  ``ps < 1`` wherever the diffuse term can be
    non-zero, and the cosine-weighted diffuse sampler covers the whole
    hemisphere, so the mixture's support always contains the BRDF's.
    """
    return lobe_probabilities(ops, cos_i, rs, rd)[0]


def lobe_probabilities(ops, cos_i, rs, rd, ks=1.0):
    """``(ps, pd) = (Fs, Ad) / (Fs + Ad)``: the probabilities of the specular lobe
    (:func:`specular_probability`) and of the diffuse one, each computed as its
    own quotient.  ``pd`` is not ``1 - ps``: at grazing incidence ``Ad`` is
    ``O(cos(theta))`` and ``Fs`` near 1, so ``ps`` rounds to 1 (in float32 below
    ``cos = 1e-7``) and ``1 - ps`` to 0, and the pdf lost its diffuse part while
    ``f`` kept it (sample weights of 6e6).  ``(1, 0)`` where ``Fs + Ad == 0``.
    Each is a true quotient, not a product with ``1/(Fs + Ad)``: with ``rs = 0``
    and ``rd = 1e-310`` (float32: ``1e-39``) the sum is subnormal, its reciprocal
    overflows, and ``0 * inf`` made the pdf NaN.  ``ks``: the specular scale of
    :class:`AshikhminShirleyScaled` (``Fs = ks F``, ``Ad`` of ``ks rs``; 1: the paper's)."""
    c = ops.maximum(cos_i, 0.0)
    fs = ks * schlick(ops, c, rs)
    ad = diffuse_albedo(c, ks * rs, rd)
    s = fs + ad
    pos = s > 0
    den = ops.where(pos, s, 1.0)
    return ops.where(pos, fs / den, 1.0), ops.where(pos, ad / den, 0.0)


def specular_pdf(ops, wi, wo, nu, nv):
    """Density of :func:`specular_sample`: ``p_h(h) / (4 (k1.h))``, journal eq. 8
    (the report's eq. 18 prints it inverted; see the docs)."""
    return warps.reflected_half_vector_pdf(ops, wi, wo, nu, nv)


def specular_sample(ops, wi, nu, nv, u1, u2):
    """``h`` from ``p_h`` (journal eqs. 9, 10 with a continuous quadrant map),
    ``k2 = -k1 + 2 (k1.h) h`` (journal eq. 7)."""
    return warps.reflected_half_vector(ops, wi, nu, nv, u1, u2)


def diffuse_pdf(ops, wi, wo):
    return ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)


def diffuse_sample(ops, wi, u, q):
    """Cosine-weighted, the diffuse term's sampler (journal Sec. 3)."""
    return warps.cosine_hemisphere(ops, u[1], u[2])


#: The two terms as components (:class:`plausible.bxdf.Lobe`).
SPECULAR_LOBE = Lobe("glossy",
                     lambda ops, wi, wo, p: specular(ops, wi, wo, p.nu, p.nv, p.rs),
                     lambda ops, wi, wo, q: specular_pdf(ops, wi, wo, q.nu, q.nv),
                     lambda ops, wi, u, q: specular_sample(ops, wi, q.nu, q.nv, u[1], u[2]))
DIFFUSE_LOBE = Lobe("diffuse",
                    lambda ops, wi, wo, p: diffuse(ops, wi, wo, p.rs, p.rd),
                    lambda ops, wi, wo, q: diffuse_pdf(ops, wi, wo),
                    diffuse_sample,
                    lambda ops, wi, p: diffuse_albedo(ops.maximum(wi[2], 0.0), p.rs, p.rd))


# -- the models -------------------------------------------------------------------

@register("ashikhmin-shirley",
          "Ashikhmin-Shirley anisotropic Phong BRDF (JGT 2000): Fresnel-weighted "
          "anisotropic half-vector lobe (nu, nv, rs) plus the coupled non-Lambertian "
          "diffuse term (rd).",
          references=REFERENCES)
class AshikhminShirley(BxDF):
    """``AshikhminShirley(nu, nv, rs, rd)``: ``rho = rho_s + rho_d`` (journal eq. 1).

    Sampling: with probability :func:`specular_probability` (a function of
    ``wi``) the half-vector lobe, otherwise the cosine-weighted hemisphere;
    ``pdf`` is the same mixture ("a weighted average", journal Sec. 3).
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (NU, NV, RS, RD)

    def spec_probability(self, ops, wi, q):
        """Mixture weight of the specular lobe (override to experiment)."""
        return specular_probability(ops, wi[2], q.rs, q.rd)

    def diffuse_probability(self, ops, wi, q):
        """Mixture weight of the diffuse lobe, ``1 - spec_probability`` computed
        without cancellation (:func:`lobe_probabilities`)."""
        return lobe_probabilities(ops, wi[2], q.rs, q.rd)[1]

    def _f(self, ops, wi, wo, p):
        return specular(ops, wi, wo, p.nu, p.nv, p.rs) + diffuse(ops, wi, wo, p.rs, p.rd)

    def lobes(self):
        """The specular lobe (journal eq. 4), then the coupled diffuse term (eq. 5),
        whose albedo is :func:`diffuse_albedo` at ``wi``."""
        return (SPECULAR_LOBE, DIFFUSE_LOBE)

    def lobe_weights(self, ops, wi, q):
        return self.spec_probability(ops, wi, q), self.diffuse_probability(ops, wi, q)

    def level_kink(self):
        return True     # max(n.k1, n.k2) of eq. 4


@register("ashikhmin-shirley-specular",
          "Specular term of Ashikhmin-Shirley alone (JGT 2000 eq. 4): metals.",
          references=REFERENCES)
class AshikhminShirleySpecular(BxDF):
    """``AshikhminShirleySpecular(nu, nv, rs)``: ``rho_s`` of journal eq. 4,
    sampled through the half vector (journal eqs. 6-10)."""

    PARAMS = (NU, NV, Param("rs", 0.9, 0.0, 1.0, "color", RS.doc, RS.extremes))

    def _f(self, ops, wi, wo, p):
        return specular(ops, wi, wo, p.nu, p.nv, p.rs)

    def _pdf(self, ops, wi, wo, q):
        return specular_pdf(ops, wi, wo, q.nu, q.nv)

    def _sample(self, ops, wi, u, q):
        return specular_sample(ops, wi, q.nu, q.nv, u[1], u[2])

    def level_kink(self):
        return True     # max(n.k1, n.k2) of eq. 4


@register("ashikhmin-shirley-diffuse",
          "Diffuse term of Ashikhmin-Shirley alone (JGT 2000 eq. 5); albedo "
          "rd (1 - rs) (1 - (1 - cos/2)^5).",
          references=REFERENCES)
class AshikhminShirleyDiffuse(BxDF):
    """``AshikhminShirleyDiffuse(rs, rd)``: ``rho_d`` of journal eq. 5, sampled
    cosine-weighted (as the paper does)."""

    LOBES = frozenset({"diffuse"})

    PARAMS = (RS, RD)

    def peak_directions(self, wi):
        return [np.array([0.0, 0.0, 1.0])]

    def _f(self, ops, wi, wo, p):
        return diffuse(ops, wi, wo, p.rs, p.rd)

    def _pdf(self, ops, wi, wo, q):
        return diffuse_pdf(ops, wi, wo)

    def _sample(self, ops, wi, u, q):
        return diffuse_sample(ops, wi, u, q)

    def lobes(self):
        return (DIFFUSE_LOBE,)


# -- the form with a separate specular scale ------------------------------------------

KS = Param("ks", 1.0, 0.0, 1.0, "color",
           "specular scale: the lobe times ks, Schlick's R0 (rs) then only shapes the Fresnel rise "
           "(ks = 1: the paper's model)", (0.0, 1.0))


def scaled(ops, wi, wo, nu, nv, rs, rd, ks):
    """``ks rho_s(rs) + rho_d(ks rs, rd)``: the specular term (journal eq. 4) times a scale
    ``ks`` and the diffuse term (eq. 5) under a coating that reflects ``ks rs`` at normal
    incidence, ``28 rd / (23 pi) (1 - ks rs) (...)(...)``.  ``ks = 1`` is the paper's model.
    Ngan, Durand & Matusik (2005) fitted this lobe with ``rs`` and a colour scale apart
    (their published A-S fits: ``rs = 0.999`` times an RGB albedo), which ``rs`` alone, both
    Fresnel's R0 and the lobe's scale, cannot express.  Energy: the albedo is linear in
    ``ks``, ``ks S(rs) + rd (1 - ks rs) D``, at most 1 at ``ks = 0`` (the diffuse term alone)
    and at ``ks = 1`` (the paper's model), so at most 1 between."""
    return ks * specular(ops, wi, wo, nu, nv, rs) + diffuse(ops, wi, wo, ks * rs, rd)


SCALED_SPECULAR_LOBE = Lobe("glossy",
                            lambda ops, wi, wo, p: p.ks * specular(ops, wi, wo, p.nu, p.nv, p.rs),
                            SPECULAR_LOBE.pdf, SPECULAR_LOBE.sample)
SCALED_DIFFUSE_LOBE = Lobe("diffuse",
                           lambda ops, wi, wo, p: diffuse(ops, wi, wo, p.ks * p.rs, p.rd),
                           DIFFUSE_LOBE.pdf, DIFFUSE_LOBE.sample,
                           lambda ops, wi, p: diffuse_albedo(ops.maximum(wi[2], 0.0), p.ks * p.rs, p.rd))


@register("ashikhmin-shirley-scaled",
          "Ashikhmin-Shirley with a separate specular scale ks (Ngan et al. 2005's form): "
          "ks times the Fresnel-weighted lobe (nu, nv, rs) plus the coupled diffuse term (rd) "
          "under a coating of R0 ks rs.",
          references=REFERENCES + ("Ngan, Durand, Matusik, Experimental analysis of BRDF models, EGSR 2005",))
class AshikhminShirleyScaled(AshikhminShirley):
    """``AshikhminShirleyScaled(nu, nv, rs, rd, ks)``: :func:`scaled`; sampled as the paper's
    model with the specular probability ``ks F / (ks F + A_d)``."""

    PARAMS = (NU, NV, RS, RD, KS)

    def spec_probability(self, ops, wi, q):
        return lobe_probabilities(ops, wi[2], q.rs, q.rd, q.ks)[0]

    def diffuse_probability(self, ops, wi, q):
        return lobe_probabilities(ops, wi[2], q.rs, q.rd, q.ks)[1]

    def _f(self, ops, wi, wo, p):
        return scaled(ops, wi, wo, p.nu, p.nv, p.rs, p.rd, p.ks)

    def lobes(self):
        return (SCALED_SPECULAR_LOBE, SCALED_DIFFUSE_LOBE)
