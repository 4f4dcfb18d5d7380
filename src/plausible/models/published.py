"""Exact variants of the family models that the published MERL fits need.

Thin wrappers over the family modules (every formula is imported from there;
the derivations are in ``docs/materials.md``).  Not registered: they exist to
be parts of a :class:`plausible.models.sum.Sum` built by
:mod:`plausible.materials`, and each one claims what its parent claims.

* :class:`NganBlinnPhong` -- ``f = ks (n + 2) / (2 pi) (n.h)^n``: the Blinn lobe
  of :func:`plausible.models.phong.blinn_lobe` with the Phong constant
  :func:`plausible.models.phong.phong_norm` (Ngan, Durand, Matusik 2005).  Its
  albedo at normal incidence is ``4 (n + 2^(-n/2)) / (n + 4)``, about 4 for sharp
  lobes: not energy conserving (measured in the docs).
* :class:`AshikhminShirleyDielectric` -- the isotropic specular lobe of Ashikhmin
  & Shirley 2000 (journal eq. 4) with the exact dielectric Fresnel factor of
  index ``eta`` in place of Schlick's (Löw et al. 2012, as bbm's
  ``LowAshikhminShirley``): ``specular(rs=1) * F_dielectric(k.h, eta)``.
* :class:`CookTorranceWide` -- :class:`plausible.models.cook_torrance.CookTorrance`
  with the Beckmann slope ``m`` allowed up to 10 (Löw's fits reach 2.09).

References
----------
* A. Ngan, F. Durand, W. Matusik, "Experimental analysis of BRDF models",
  EGSR 2005.
* J. Löw, J. Kronander, A. Ynnerman, J. Unger, "BRDF models for accurate and
  efficient rendering of glossy surfaces", ACM TOG 31(1), 2012.
* P. Peers, bbm (``include/bsdfmodel/ngan.h``, ``low.h``), 2023.
"""

from __future__ import annotations

from .. import fresnel, vec
from ..bxdf import BxDF
from ..params import Param
from ..vec import above
from . import ashikhmin_shirley as AS
from .cook_torrance import CookTorrance
from .phong import EXPONENT, _BlinnLobeModel, blinn_lobe, phong_norm

REFERENCES = (
    "Ngan, Durand, Matusik, Experimental analysis of BRDF models, EGSR 2005",
    "Löw, Kronander, Ynnerman, Unger, BRDF models for accurate and efficient rendering of "
    "glossy surfaces, ACM TOG 31(1), 2012",
)


class NganBlinnPhong(_BlinnLobeModel):
    """``f = ks (n + 2) / (2 pi) (n.h)^n`` for both directions above the horizon
    (Ngan et al. 2005's Blinn-Phong); sampled like ``reciprocal-blinn`` (the half
    vector from ``(n + 1) / (2 pi) (n.h)^n``, reflected)."""

    reciprocal = True
    PARAMS = (
        Param("ks", 1.0, 0.0, 1.0, "color", "specular scale", (0.0, 1.0)),
        Param("n", 20.0, kind="scalar", **EXPONENT),
    )

    def _f(self, ops, wi, wo, p):
        return ops.where(above(ops, wi, wo), p.ks * phong_norm(p.n) * blinn_lobe(ops, wi, wo, p.n), 0.0)


class AshikhminShirleyDielectric(BxDF):
    """``rho_s = p_h(h) F_d(k.h, eta) / (4 (k.h) max(n.k1, n.k2))``, isotropic
    (``nu = nv = n``): :func:`plausible.models.ashikhmin_shirley.specular` with
    ``rs = 1`` (Schlick's factor is then exactly 1) times
    :func:`plausible.fresnel.dielectric`.  Sampled through the half vector like
    ``ashikhmin-shirley-specular``."""

    reciprocal = True
    PARAMS = (
        Param("n", 100.0, 0.0, 1e6, "scalar", "Phong-like exponent of the isotropic lobe", (0.0, 1e4)),
        Param("eta", 1.5, 1.0, 100.0, "scalar", "relative index of refraction of the dielectric", (1.0, 10.0)),
    )

    def _f(self, ops, wi, wo, p):
        kh = vec.half_vector_cos(ops, wi, wo)[1]   # k.h from |k1 + k2| / 2, as in AS.specular
        return AS.specular(ops, wi, wo, p.n, p.n, 1.0) * fresnel.dielectric(ops, kh, p.eta)

    def _pdf(self, ops, wi, wo, q):
        return AS.specular_pdf(ops, wi, wo, q.n, q.n)

    def _sample(self, ops, wi, u, q):
        return AS.specular_sample(ops, wi, q.n, q.n, u[1], u[2])

    def level_kink(self):
        return True     # max(n.k1, n.k2)


def _wide_params():
    out = []
    for prm in CookTorrance.PARAMS:
        if prm.name == "m":
            prm = Param("m", prm.default, prm.lo, 10.0, prm.kind, prm.doc, prm.extremes)
        out.append(prm)
    return tuple(out)


class CookTorranceWide(CookTorrance):
    """:class:`~plausible.models.cook_torrance.CookTorrance` with ``m`` in ``[1e-4, 10]``."""

    reciprocal = True
    PARAMS = _wide_params()


__all__ = ["AshikhminShirleyDielectric", "CookTorranceWide", "NganBlinnPhong", "REFERENCES"]
