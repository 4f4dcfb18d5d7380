"""The Neumann-Neumann-Szirmay-Kalos metal model (the limit of controlled pumping-up).

L. Neumann, A. Neumann, L. Szirmay-Kalos, "Compact metallic reflectance models"
/ "albedo pumping-up", 1999 (``neumann-neumann-szirmay-kalos-albedo-pumping-up.txt``),
eq. 22: ``f = c_n (R.V)^n / max(N.L, N.V)`` with ``c_n <= (n + 2) / (2 pi)``.
"""

from __future__ import annotations

from .. import fresnel, vec
from ..bxdf import BxDF
from ..params import Param
from ..registry import register
from ..vec import above
from .phong import EXPONENT, lobe_pdf, phong_lobe, phong_norm, phong_sample


def neumann_metal(ops, wi, wo, n, c):
    """``c (R.V)^n / max(N.L, N.V)`` for both directions above the horizon (eq. 22)."""
    ok = above(ops, wi, wo)
    m = ops.where(ok, ops.maximum(wi[2], wo[2]), 1.0)
    return ops.where(ok, c * phong_lobe(ops, wi, wo, n) / m, 0.0)


@register("neumann-metal",
          "Neumann-Neumann-Szirmay-Kalos metal model (1999, eq. 22): "
          "f = F c_n (R.V)^n / max(N.L, N.V), c_n <= (n+2)/(2 pi).",
          references=("Neumann, Neumann, Szirmay-Kalos, albedo pumping-up, 1999, eq. 22",))
class NeumannMetal(BxDF):
    """``f = F c_n cos^n(alpha) / max(cos(theta_i), cos(theta_o))``.

    * ``c`` defaults to ``(n + 2) / (2 pi)`` (:func:`~plausible.models.phong.phong_norm`),
      the largest value the paper allows for energy balance (eq. 22 and fig. 7);
      at normal incidence the albedo is then exactly ``F``.  ``c`` above this bound
      raises ValueError.
    * ``F`` (``fresnel``): ``"none"`` -> ``rs``; ``"schlick"`` -> Schlick with
      ``R0 = rs``; ``"conductor"`` -> exact conductor Fresnel with ``eta + i k``;
      all evaluated at ``cos = wi.h`` with ``h`` the half vector of ``wi`` and ``wo``.
      ``wi.h = wo.h`` keeps the model reciprocal, ``F <= 1`` keeps the albedo
      bounded, and at the mirror direction ``wi.h = cos(theta_i)``, the angle of
      incidence of the ideal mirror this lobe approximates.
    * Sampling: the ``cos^n`` lobe about the mirror direction (Lafortune & Willems 1994),
      shared with :mod:`plausible.models.phong`.
    """

    PARAMS = (
        # The paper's bound c_n <= (n+2)/(2 pi) does not keep the albedo <= 1 below
        # n = 2 (measured: 1.0858 at n = 0, 1 + 2.9e-4 at n = 1), so n >= 2 is required.
        Param("n", 100.0, kind="scalar", **dict(EXPONENT, lo=2.0, extremes=(2.0, 1e4),
                                                doc="Phong exponent n >= 2 (the paper's energy "
                                                    "bound fails below 2)")),
        Param("c", None, 0.0, kind="scalar",
              doc="normalisation c_n; default (n + 2) / (2 pi), the largest energy-conserving value"),
        Param("rs", 1.0, 0.0, 1.0, "color", "specular reflectance / Schlick R0", (0.0, 1.0)),
        Param("fresnel", "none", kind="choice", choices=fresnel.FRESNEL_CHOICES,
              doc="Fresnel factor evaluated at wi.h"),
        Param("eta", 0.2, 0.0, 100.0, "color", "conductor index n (fresnel='conductor')"),
        Param("k", 3.0, 0.0, 100.0, "color", "conductor extinction k (fresnel='conductor')"),
    )

    #: ``c=None`` means the largest energy-conserving normalisation (n + 2) / (2 pi)
    DERIVED = {"c": lambda p: phong_norm(p.n)}

    def __init__(self, **params):
        # ``c=None`` means the default (n + 2) / (2 pi); resolve it before validation.
        n = params.get("n", self.PARAMS[0].default)
        if params.get("c") is None:
            try:
                params["c"] = phong_norm(float(n))
            except (TypeError, ValueError):
                params["c"] = 0.0  # the 'n' check below reports the bad value
        super().__init__(**params)

    def _validate(self):
        bound = phong_norm(self.params["n"])
        c = self.params["c"]
        if c > bound * (1.0 + 1e-12):
            raise ValueError(f"NeumannMetal: parameter 'c' must not exceed (n + 2) / (2 pi) = {bound:g} "
                             f"for n = {self.params['n']:g} (energy balance, eq. 22), got {c:g}")

    def _fresnel(self, ops, wi, wo, p):
        kh = vec.half_vector_cos(ops, wi, wo)[1]
        return fresnel.weight(ops, p.fresnel, kh, p.rs, p.eta, p.k)

    def _f(self, ops, wi, wo, p):
        return self._fresnel(ops, wi, wo, p) * neumann_metal(ops, wi, wo, p.n, p.c)

    def _pdf(self, ops, wi, wo, q):
        return lobe_pdf(ops, wi, wo, q.n)

    def _sample(self, ops, wi, u, q):
        return phong_sample(ops, wi, q.n, u[1], u[2])

    def level_kink(self):
        return True     # max(N.L, N.V) of eq. 22
