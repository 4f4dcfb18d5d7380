"""The Lambertian (perfectly diffuse) BRDF."""

from __future__ import annotations

from .. import warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI
from ..params import Param
from ..registry import register
from ..vec import above


def lambert(ops, wi, wo, rd):
    """``f = rd / pi`` for both directions above the horizon (Lambert 1760)."""
    return ops.where(above(ops, wi, wo), rd * INV_PI, 0.0)


@register("lambertian", "Lambertian diffuse reflector, f = rd / pi.",
          references=("J. H. Lambert, Photometria, 1760.",))
class Lambertian(BxDF):
    """``Lambertian(rd)``: ``f = rd / pi``; sampled cosine-weighted, so ``weight = rd``."""

    LOBES = frozenset({"diffuse"})
    PARAMS = (Param("rd", 0.8, 0.0, 1.0, "color", "diffuse reflectance (albedo)", (0.0, 1.0)),)

    def _f(self, ops, wi, wo, p):
        return lambert(ops, wi, wo, p.rd)

    def _pdf(self, ops, wi, wo, q):
        return ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)

    def _sample(self, ops, wi, u, q):
        return warps.cosine_hemisphere(ops, u[1], u[2])

    def lobes(self):
        """One diffuse lobe whose albedo is ``rd``."""
        return (Lobe("diffuse", self._f, self._pdf, self._sample, lambda ops, wi, p: p.rd),)
