"""The Phong family: Modified Phong, the original Phong and Blinn, and their
reciprocal forms.

Notation: ``R`` is the mirror direction of ``wi`` about the normal, ``alpha``
the angle between ``R`` and ``wo``, ``h`` the half vector of ``wi`` and ``wo``.
The Phong lobe is ``cos^n(alpha)`` where ``cos(alpha) > 0`` and zero beyond
(the limit ``n -> 0+`` and the support of its sampler); the Blinn lobe is
``(n.h)^n``.

References
----------
* B. T. Phong, "Illumination for computer generated pictures", CACM 18(6), 1975.
* J. F. Blinn, "Models of light reflection for computer synthesized pictures",
  SIGGRAPH 1977.
* R. Lewis, "Making shaders more physically plausible", EGWR 1993.
* E. Lafortune, Y. Willems, "Using the modified Phong reflectance model for
  physically based rendering", KU Leuven CW197, 1994 (``modified-phong-brdf-notes.txt``).
* L. Neumann, A. Neumann, L. Szirmay-Kalos, "Compact metallic reflectance
  models" / albedo pumping-up, 1999, eqs. 5 and 6.
"""

from __future__ import annotations

import numpy as np

from .. import vec, warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI, PI
from ..params import Param
from ..registry import register
from ..text import fmt
from ..vec import above

EXPONENT = dict(lo=0.0, hi=1e6, doc="Phong exponent n (larger is sharper)", extremes=(0.0, 1.0, 1e4))


def phong_cos(wi, wo):
    """``cos(alpha) = R.wo`` with ``R = 2 (n.wi) n - wi`` the mirror direction."""
    return vec.dot(vec.mirror(wi), wo)


def phong_lobe(ops, wi, wo, n):
    """``cos^n(alpha)`` for ``cos(alpha) > 0``, else 0.

    Near the peak the power is taken from ``1 - cos(alpha) = |R - wo|^2 / 2``
    (unit vectors) by :func:`plausible.warps.power_near_one`: in float32
    (shaders, Dr.Jit's single precision) ``R.wo`` rounds to within 6e-8 of 1,
    a relative error of 6e-4 in ``cos^n`` for ``n = 10^4``; the difference
    vector keeps its digits.  Symmetric in ``wi`` and ``wo`` bitwise, and the
    same arithmetic as a Lafortune lobe ``(-1, -1, 1)``.
    """
    c = phong_cos(wi, wo)
    r = vec.mirror(wi)
    d = (r[0] - wo[0], r[1] - wo[1], r[2] - wo[2])
    return ops.where(c > 0, warps.power_near_one(ops, c, 0.5 * vec.dot(d, d), n), 0.0)


def phong_norm(n):
    """``(n + 2) / (2 pi)``: the constant that makes the albedo at normal
    incidence exactly 1, since ``int cos^n(theta) cos(theta) d omega = 2 pi / (n + 2)``
    (Lewis 1993; Lafortune & Willems 1994)."""
    return (n + 2.0) / (2.0 * PI)


def blinn_lobe(ops, wi, wo, n):
    """``(n.h)^n``, computed from ``sin^2`` of the half vector (accurate near the peak)."""
    h = vec.half_vector(ops, wi, wo)
    return ops.where(h[2] > 0, warps.pow_cos_from_sin2(ops, h[0] * h[0] + h[1] * h[1], n, h[2]), 0.0)


def blinn_norm(ops, n):
    """``(n + 2)(n + 4) / (8 pi (n + 2^(-n/2)))``.

    Derived here: at normal incidence ``theta_h = theta_o / 2`` and
    ``int (n.h)^n cos(theta_o) d omega_o = 8 pi (n + 2^(-n/2)) / ((n + 2)(n + 4))``
    (substitute ``x = cos(theta_o / 2)``: ``8 pi int_{1/sqrt 2}^1 x^(n+1) (2x^2 - 1) dx``),
    so with this constant the albedo at normal incidence is exactly 1.
    ``n = 0`` gives ``1 / pi``.
    """
    return (n + 2.0) * (n + 4.0) / (8.0 * PI * (n + ops.exp(-0.5 * n * 0.6931471805599453)))


def lobe_pdf(ops, wi, wo, n):
    """Density of :func:`phong_sample`: ``(n + 1) / (2 pi) cos^n(alpha)`` on ``wo.z > 0``,
    with ``cos^n`` from :func:`phong_lobe`, the arithmetic of ``f``: a power of the
    dot product instead would differ from ``f``'s lobe by ``n`` float32 roundings
    (1-4 % of the sample weight at exponents of 10^5, found by the plugin fuzzer)."""
    return ops.where(above(ops, wi, wo), (n + 1.0) / (2.0 * PI) * phong_lobe(ops, wi, wo, n), 0.0)


def phong_sample(ops, wi, n, u1, u2):
    """``cos^n`` lobe about the mirror direction (Lafortune & Willems 1994)."""
    return warps.power_cosine_lobe_about(ops, vec.mirror(wi), n, u1, u2)


def diffuse_pdf(ops, wi, wo):
    return ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)


def modified_phong_diffuse(ops, wi, wo, p):
    """The Lambertian term ``kd / pi`` of Modified Phong."""
    return ops.where(above(ops, wi, wo), p.kd * INV_PI, 0.0)


def modified_phong_glossy(ops, wi, wo, p):
    """The lobe ``ks (n + 2) / (2 pi) cos^n(alpha)`` of Modified Phong."""
    return ops.where(above(ops, wi, wo), p.ks * phong_norm(p.n) * phong_lobe(ops, wi, wo, p.n), 0.0)


@register("modified-phong",
          "Modified Phong (Lafortune & Willems 1994; Mitsuba 0.5 'phong'): "
          "f = kd/pi + ks (n+2)/(2 pi) cos^n(alpha).",
          references=("Lafortune & Willems, KU Leuven CW197, 1994",
                      "modified-phong-brdf-notes.txt"))
class ModifiedPhong(BxDF):
    """``f = kd / pi + ks (n + 2) / (2 pi) cos^n(alpha)``, ``kd + ks <= 1``.

    Directional albedo at normal incidence: exactly ``kd + ks`` (the lobe's
    normalisation). Sampling: with probability ``ps = mean(ks) / (mean(kd) +
    mean(ks))`` (Mitsuba 0.5's choice) the ``cos^n`` lobe about the mirror
    direction, otherwise the cosine-weighted hemisphere; ``pdf`` is the same
    mixture.
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (
        Param("kd", 0.5, 0.0, 1.0, "color", "diffuse reflectance", (0.0, 1.0)),
        Param("ks", 0.2, 0.0, 1.0, "color", "specular reflectance", (0.0, 1.0)),
        Param("n", 30.0, kind="scalar", **EXPONENT),
    )

    def _validate(self):
        total = np.asarray(self.params["kd"]) + np.asarray(self.params["ks"])
        if (total > 1.0 + 1e-12).any():
            raise ValueError("ModifiedPhong: parameters 'kd' + 'ks' must not exceed 1 "
                             f"(energy conservation), got kd + ks = {fmt(total)}")

    @staticmethod
    def spec_probability(ops, q):
        """``ks / (ks + kd)`` (channel means), 0.5 when both are zero (:func:`~plausible.warps.mixture_weight`)."""
        return warps.mixture_weight(ops, q.ks, q.kd)

    def _f(self, ops, wi, wo, p):
        return modified_phong_diffuse(ops, wi, wo, p) + modified_phong_glossy(ops, wi, wo, p)

    def mirror_cut(self):
        """The ``cos^n`` lobe ends at ``R.wo = 0``."""
        return True

    def lobes(self):
        """The ``cos^n`` lobe, then the Lambertian term (albedo ``kd``)."""
        return (Lobe("glossy", modified_phong_glossy, lambda ops, wi, wo, q: lobe_pdf(ops, wi, wo, q.n),
                     lambda ops, wi, u, q: phong_sample(ops, wi, q.n, u[1], u[2])),
                Lobe("diffuse", modified_phong_diffuse, lambda ops, wi, wo, q: diffuse_pdf(ops, wi, wo),
                     lambda ops, wi, u, q: warps.cosine_hemisphere(ops, u[1], u[2]),
                     lambda ops, wi, p: p.kd))

    def lobe_weights(self, ops, wi, q):
        ps = self.spec_probability(ops, q)
        return ps, 1.0 - ps


class _PhongLobeModel(BxDF):
    """Shared sampling of the models whose lobe is ``cos^n(alpha)``."""

    PARAMS = (
        Param("ks", 1.0, 0.0, 1.0, "color", "specular reflectance (albedo at normal incidence)", (0.0, 1.0)),
        Param("n", 20.0, kind="scalar", **EXPONENT),
    )

    def _pdf(self, ops, wi, wo, q):
        return lobe_pdf(ops, wi, wo, q.n)

    def _sample(self, ops, wi, u, q):
        return phong_sample(ops, wi, q.n, u[1], u[2])

    def mirror_cut(self):
        """The ``cos^n`` lobe ends at ``R.wo = 0``."""
        return True


class _BlinnLobeModel(BxDF):
    """Shared sampling of the models whose lobe is ``(n.h)^n``: the half vector
    is drawn from ``(n + 1)/(2 pi) (n.h)^n`` and reflected."""

    PARAMS = _PhongLobeModel.PARAMS

    def _pdf(self, ops, wi, wo, q):
        return warps.reflected_half_vector_pdf(ops, wi, wo, q.n, q.n)

    def _sample(self, ops, wi, u, q):
        return warps.reflected_half_vector(ops, wi, q.n, q.n, u[1], u[2])


@register("reciprocal-phong",
          "Reciprocal Phong (Lewis 1993): f = ks (n+2)/(2 pi) cos^n(alpha); albedo <= ks.",
          references=("Lewis, EGWR 1993", "Neumann et al. 1999, eq. 6"))
class ReciprocalPhong(_PhongLobeModel):
    """``f = ks (n + 2) / (2 pi) cos^n(alpha)`` (Lewis 1993; pumping-up paper eq. 6).

    Its albedo is ``ks`` at normal incidence and smaller elsewhere.
    """

    def _f(self, ops, wi, wo, p):
        return ops.where(above(ops, wi, wo), p.ks * phong_norm(p.n) * phong_lobe(ops, wi, wo, p.n), 0.0)


@register("phong",
          "Original Phong (1975) with the division by cos(theta_i): not reciprocal "
          "(implausible baseline).",
          reciprocal=False, energy_conserving=False,
          references=("Phong, CACM 1975", "Neumann et al. 1999, eq. 5"))
class Phong(_PhongLobeModel):
    """``f = ks (n + 2) / (2 pi) cos^n(alpha) / cos(theta_i)`` (pumping-up paper eq. 5).

    The division by ``cos(theta_i)`` breaks reciprocity; kept as the baseline
    the papers compare against.
    """

    def _f(self, ops, wi, wo, p):
        ok = above(ops, wi, wo)
        ci = ops.where(ok, wi[2], 1.0)
        return ops.where(ok, p.ks * phong_norm(p.n) * phong_lobe(ops, wi, wo, p.n) / ci, 0.0)


@register("reciprocal-blinn",
          "Reciprocal Blinn (Lewis 1993): f = ks c(n) (n.h)^n, normalised to albedo ks at normal incidence.",
          references=("Blinn, SIGGRAPH 1977", "Lewis, EGWR 1993", "Neumann et al. 1999, eq. 6"))
class ReciprocalBlinn(_BlinnLobeModel):
    """``f = ks c(n) (n.h)^n`` with ``c(n) = (n+2)(n+4) / (8 pi (n + 2^(-n/2)))``
    (see :func:`blinn_norm`); albedo ``ks`` at normal incidence."""

    def _f(self, ops, wi, wo, p):
        return ops.where(above(ops, wi, wo), p.ks * blinn_norm(ops, p.n) * blinn_lobe(ops, wi, wo, p.n), 0.0)


@register("blinn",
          "Original Blinn (1977) with the division by cos(theta_i): not reciprocal "
          "(implausible baseline).",
          reciprocal=False, energy_conserving=False,
          references=("Blinn, SIGGRAPH 1977", "Neumann et al. 1999, eq. 5"))
class Blinn(_BlinnLobeModel):
    """``f = ks c(n) (n.h)^n / cos(theta_i)`` (pumping-up paper eq. 5)."""

    def _f(self, ops, wi, wo, p):
        ok = above(ops, wi, wo)
        ci = ops.where(ok, wi[2], 1.0)
        return ops.where(ok, p.ks * blinn_norm(ops, p.n) * blinn_lobe(ops, wi, wo, p.n) / ci, 0.0)
