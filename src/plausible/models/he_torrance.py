"""The physical-optics BRDF of He, Torrance, Sillion & Greenberg (1991).

X. D. He, K. E. Torrance, F. X. Sillion, D. P. Greenberg, "A comprehensive
physical model for light reflection", SIGGRAPH 1991 (Computer Graphics 25(4)),
with the errata collected by R. Pacanowski and N. Holzschuch ("Demystifying the
He, Torrance, Sillion and Greenberg BRDF", notes and ``he_errata.pdf``) and the
reading of S. Westin's reference code, as documented in bbm's
``include/bsdfmodel/he.h`` (P. Peers, 2023).  The derivation, the units and the
choices where the sources disagree are in ``docs/models/he-torrance.md``.

``rho = rho_sp + rho_dd + rho_ud`` (eq. 3): a coherent specular term (a delta
lobe in the mirror direction), the directional-diffuse series and a uniform
diffuse term.  With ``k_i = -wi``, ``k_r = wo`` (unit vectors), ``c_i, c_r``
their cosines to the normal and ``F = |F|^2`` the unpolarised Fresnel
reflectance:

* ``rho_sp = F(c_i) exp(-g) S(c_i)^2 delta / (c_i d omega)`` (eq. 9 with eq. 79
  at the mirror direction) -- reported by :meth:`HeTorrance.delta_lobes`, not by
  ``eval`` (a delta has no finite value);
* ``rho_dd = F(k.h) G S(c_i) S(c_r) D / (pi c_i c_r)`` (eq. 76);
* ``rho_ud = rd / pi`` (the paper's ``a(lambda)``).

The parts:

* ``G = (|v|^2 / v_z)^2 [(s_r.k_i)^2 + (p_r.k_i)^2][(s_i.k_r)^2 + (p_i.k_r)^2] / |k_r x k_i|^4``
  with ``v = k_r - k_i`` (eq. 76).  ``(s, p, k)`` is an orthonormal triad for
  each direction, so each bracket is ``1 - (k_i.k_r)^2 = |k_r x k_i|^2`` and
  ``G = (|v|^2 / v_z)^2 = 16 (k.h)^4 / (c_i + c_r)^2`` exactly.
* ``S(c) = (1 - erfc(x) / 2) / (Lambda(x) + 1)`` with ``x = tau cot(theta) / (2 sigma0)``
  (eq. 24) and ``Lambda(x) = exp(-x^2) / (2 sqrt(pi) x) - erfc(x) / 2`` (eq. 25
  with its errata's ``exp(-x^2)``; the paper as printed omits it).
* The effective roughness ``sigma = sigma0 / sqrt(1 + z0^2 / sigma0^2)`` (eq. 80),
  ``z0`` the root of ``sqrt(pi/2) z0 = sigma0 / 4 (K_i + K_r) exp(-z0^2 / (2 sigma0^2))``
  with ``K = tan(theta) erfc(tau / (2 sigma0 tan(theta)))`` (eqs. 81-83); in
  ``y = z0 / sigma0``: ``y exp(y^2 / 2) = (K_i + K_r) / sqrt(8 pi)``, solved by
  Newton's method on ``log y + y^2 / 2`` (:func:`effective_roughness`).
* ``g = (2 pi sigma (c_i + c_r) / lambda)^2`` (eq. 79).
* ``D = pi^2 tau^2 / (4 lambda^2) sum_{m>=1} g^m exp(-g) / (m! m) exp(-V / m)``
  with ``V = tau^2 v_xy^2 / 4`` (eq. 78); ``v_xy = |xy(k_r - k_i)|`` in the paper
  as printed (unit vectors), ``(2 pi / lambda) |xy(k_r - k_i)|`` in Westin's code.

Variants (``variant=``): ``"paper"`` (eq. 25 without the exponential, eq. 78
with unit ``v``), ``"errata"`` (eq. 25 corrected) and ``"westin"`` (eq. 25
corrected and ``v`` in wavenumbers; the default: dimensionally consistent, the
reading of the reference code and of Ngan et al.'s fits).  Lengths (``sigma0``,
``tau``, ``wavelength``) are in micrometres.

The series is summed for every ``g`` (:func:`series`): a fixed number
:data:`N_TERMS` of terms, placed and spaced per direction pair over the Poisson
weights of the terms, so that no rough-surface approximation is needed.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from .. import fresnel, special, vec, warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI, PI
from ..params import Param
from ..registry import register
from ..vec import above

VARIANTS = ("westin", "errata", "paper")
ROUGH = ("series", "beckmann")
#: ``g`` from which ``rough="beckmann"`` uses Beckmann's approximation (blended up to ``+ 1``).
ROUGH_G = 18.0
FRESNEL = ("conductor", "dielectric", "schlick", "none")

REFERENCES = (
    "He, Torrance, Sillion, Greenberg, A comprehensive physical model for light reflection, SIGGRAPH 1991",
    "Pacanowski, Holzschuch, Demystifying the He, Torrance, Sillion and Greenberg BRDF (notes and errata)",
    "Westin, heBRDF reference code (Cornell), as read by bbm include/bsdfmodel/he.h",
)

#: Terms of the series summed one by one (``m = 1 .. N_TERMS``; see :func:`series`).
N_TERMS = 128
#: Terms of the windowed sum of :func:`series` (rough surfaces, ``g > 48``).
N_WINDOW = 40
#: Newton steps of the effective roughness (residual 4e-8 after 4, 7e-15 from 5 on,
#: for ``f0`` from 1e-12 to 1e12).
NEWTON_STEPS = 6
_SQRT_PI = math.sqrt(PI)
_INV_SQRT_8PI = 1.0 / math.sqrt(8.0 * PI)
#: ``x`` used where ``cot(theta)`` is infinite (the normal): ``S = 1``, ``K = 0``.
_X_NORMAL = 1e15


def _cot_arg(ops, w, sigma0, tau):
    """``(x, sin theta)`` with ``x = tau cot(theta) / (2 sigma0)``, ``sin theta``
    from ``|xy|`` (accurate at the normal); ``x = 1e15`` on the normal."""
    s = ops.sqrt(w[0] * w[0] + w[1] * w[1])
    pos = s > 0
    x = ops.where(pos, tau * w[2] / (2.0 * sigma0 * ops.where(pos, s, 1.0)), _X_NORMAL)
    return x, s


def shadowing(ops, x, variant, ec=None):
    """``S = (1 - erfc(x) / 2) / (Lambda + 1)`` (eq. 24) with
    ``Lambda = exp(-x^2) / (2 sqrt(pi) x) - erfc(x) / 2`` (eq. 25 and its errata;
    ``variant="paper"`` drops the ``exp(-x^2)``).  ``x > 0``; ``ec``: ``erfc(x)`` if known."""
    ec = special.erfc(ops, x) if ec is None else ec
    inv = 1.0 / (2.0 * _SQRT_PI * x)
    lam = (inv if variant == "paper" else ops.exp(-x * x) * inv) - 0.5 * ec
    return (1.0 - 0.5 * ec) / (lam + 1.0)


def roughness_root(ops, f0):
    """The root ``y >= 0`` of ``y exp(y^2 / 2) = f0`` for ``f0 >= 0`` (eq. 80 in
    ``y = z0 / sigma0``).  Start ``y = f0`` (``f0 <= 1``) or ``sqrt(2 log f0)``;
    Newton's method on ``log y + y^2 / 2 - log f0`` (no overflow for any ``f0``):
    ``y <- y - y (log y + y^2 / 2 - log f0) / (1 + y^2)``."""
    pos = f0 > 0
    f = ops.where(pos, f0, 1.0)
    lf = ops.log(f)
    y = ops.where(f <= 1.0, f, ops.sqrt(2.0 * ops.maximum(lf, 0.0)))
    for _ in range(NEWTON_STEPS):
        y = y - y * (ops.log(y) + 0.5 * y * y - lf) / (1.0 + y * y)
    return ops.where(pos, y, 0.0)


def effective_roughness(ops, xi, si, ci, xo, so, co, sigma0, ei=None, eo=None):
    """``sigma = sigma0 / sqrt(1 + y^2)`` (eq. 80) with ``y`` from
    :func:`roughness_root` of ``(K_i + K_r) / sqrt(8 pi)``,
    ``K = tan(theta) erfc(x)``, ``x = tau cot(theta) / (2 sigma0)`` (eqs. 82-83);
    ``ei``, ``eo``: ``erfc(xi)``, ``erfc(xo)`` if known."""
    ki = si / ci * (special.erfc(ops, xi) if ei is None else ei)
    ko = so / co * (special.erfc(ops, xo) if eo is None else eo)
    y = roughness_root(ops, (ki + ko) * _INV_SQRT_8PI)
    return sigma0 / ops.sqrt(1.0 + y * y)


#: ``log(m!) + log(m)`` for ``m = 1 .. N_TERMS`` (index 0 unused), constants of the sum.
_LOG_FACT_M = (0.0,) + tuple(math.lgamma(m + 1.0) + math.log(m) for m in range(1, N_TERMS + 1))
_HALF_LOG_2PI = 0.5 * math.log(2.0 * PI)


def _log_term(ops, m, g, lg, V):
    """``log t(m) = log(g^m exp(-g) / (m! m) exp(-V / m))`` for whole ``m >= 1`` with
    Stirling's series for ``log m!`` (Abramowitz & Stegun 6.1.41, three corrections),
    written ``m (log g - log m) - 3/2 log m + (m - g) - ...`` so that ``m log g``
    and ``log m!`` never cancel.  Its error, below 1e-16 for ``m > 10``, reaches
    1e-3 at ``m = 1``; the windowed sum uses it only for ``g > 48``, where the
    terms below ``m = 10`` are under 1e-12 of the sum."""
    lm = ops.log(m)
    r = 1.0 / m
    r2 = r * r
    return m * (lg - lm) - 1.5 * lm + (m - g) - _HALF_LOG_2PI \
        - r * (1.0 / 12.0 - r2 * (1.0 / 360.0 - r2 / 1260.0)) - V * r


def exact_terms(g_max):
    """``(n, complete)``: the number of terms ``m = 1 .. n`` that :func:`series` sums
    one by one when ``g <= g_max`` -- the Poisson window ``g + 12 sqrt(g)`` rounded up
    to a multiple of 16 (so that nearby parameters share a compiled kernel), at most
    :data:`N_TERMS` -- and whether they cover every ``g <= g_max`` (else the windowed
    sum is needed)."""
    need = g_max + 12.0 * math.sqrt(g_max) + 2.0
    n = int(min(N_TERMS, 16 * math.ceil(need / 16.0)))
    return n, need <= N_TERMS + 1.0


def series(ops, g, V, bound=None):
    """``sum_{m>=1} t(m)``, ``t(m) = g^m exp(-g) / (m! m) exp(-V / m)`` (eq. 78
    without its factor), for ``g > 0`` and ``V >= 0``; ``bound`` (a plain number,
    optional) bounds ``g`` and saves work.

    ``t(m) <= P(m) / m`` with ``P`` the Poisson law of mean ``g``, which is below
    ``e^-37`` of its peak outside ``[g - 9 sqrt(g), g + 12 sqrt(g)]``.  When
    ``g + 12 sqrt(g) <= N_TERMS - 1`` (``g < 48``) the terms ``m = 1 .. N_TERMS``
    are summed one by one (fewer when ``bound`` allows); otherwise every
    ``k``-th term of that window, times ``k`` (``k`` the smallest whole step that
    covers it with ``N_WINDOW`` terms, about ``0.54 sqrt(g)``): the trapezoidal
    rule of a smooth bell ``sqrt(g)`` wide, whose difference from the sum of
    every term is of order ``exp(-2 pi^2 g / k^2)`` (below 1e-29); the window's
    lower end lies above ``m = 1`` from ``g = 83`` on, and below that
    ``t(1) = g exp(-g)`` is under 1e-17 of the sum.  The error is
    below 1e-12 of the sum of ``P(m) / m`` (the value at ``V = 0``) for every
    ``g``; it is relative to the value itself except where ``exp(-V / m)`` moves
    the peak of ``t`` far above ``g + 12 sqrt(g)``, where the value is negligible
    beside the lobe's peak."""
    lg = ops.log(g)
    n, complete = (N_TERMS, False) if bound is None else exact_terms(bound)
    exact = 0.0
    for m in range(1, n + 1):
        exact = exact + ops.exp(m * lg - g - _LOG_FACT_M[m] - V * (1.0 / m))
    if complete:
        return exact
    root = ops.sqrt(g)
    top = g + 12.0 * root
    windowed = top > N_TERMS - 1.0
    m0 = ops.where(windowed, ops.floor(ops.maximum(g - 9.0 * root, 1.0)), 1.0)
    k = ops.where(windowed, ops.floor((top - m0) / (N_WINDOW - 1.0)) + 1.0, 1.0)
    total = 0.0
    for j in range(N_WINDOW):
        total = total + ops.exp(_log_term(ops, m0 + j * k, g, lg, V))
    return ops.where(windowed, k * total, exact)


def rough_blend(ops, g, V, total, g_ref):
    """``rough="beckmann"``: Beckmann's rough-surface limit of the series,
    ``exp(-V / g) / g`` (Beckmann & Spizzichino 1963, sec. 5.3, eq. 47, the form
    of Westin's code), where ``g_ref >= 19``, the series ``total`` where
    ``g_ref <= 18`` and their linear blend between (bbm's ``he.h``, threshold 18;
    Westin's code switches at 18.5, per channel, without a blend).  ``g_ref`` is
    ``g`` at the model's longest wavelength, the smallest ``g`` of the channels,
    from which bbm takes the weight of every channel."""
    gs = ops.maximum(g, 1e-300)
    approx = ops.exp(-V / gs) / gs
    w = ops.minimum(ops.maximum(g_ref - ROUGH_G, 0.0), 1.0)
    return total + w * (approx - total)


def _varying(v) -> bool:
    """``v`` is a Dr.Jit array of more than one lane (a texture), not one value."""
    if isinstance(v, (int, float, np.ndarray)) or not hasattr(v, "__module__"):
        return False
    if not type(v).__module__.startswith("drjit"):
        return False
    import drjit as dr

    return dr.width(v) > 1


def g_bound(sigma0, wavelength):
    """``g <= (4 pi sigma0 / min(lambda))^2`` (eq. 79: ``sigma <= sigma0``, ``c_i + c_r <= 2``)."""
    return (4.0 * PI * float(sigma0) / float(np.min(wavelength))) ** 2


def parts(ops, wi, wo, p, bound=None, lam_ref=None):
    """``(F, G, S_i S_r / (c_i c_r), D)`` of the directional-diffuse term for both
    directions above the horizon (other values are finite and unused); ``bound``
    as in :func:`series`; ``lam_ref`` the longest wavelength (``rough="beckmann"``,
    :func:`rough_blend`; the channel's own by default)."""
    ok = above(ops, wi, wo)
    ci = ops.where(ok, wi[2], 1.0)
    co = ops.where(ok, wo[2], 1.0)
    wi = (wi[0], wi[1], ci)
    wo = (wo[0], wo[1], co)
    xi, si = _cot_arg(ops, wi, p.sigma0, p.tau)
    xo, so = _cot_arg(ops, wo, p.sigma0, p.tau)
    ei, eo = special.erfc(ops, xi), special.erfc(ops, xo)
    sig = effective_roughness(ops, xi, si, ci, xo, so, co, p.sigma0, ei, eo)
    vz = ci + co
    a = 2.0 * PI * sig * vz / p.wavelength
    g = a * a
    vx, vy = wi[0] + wo[0], wi[1] + wo[1]
    vxy2 = vx * vx + vy * vy
    V = 0.25 * p.tau * p.tau * vxy2
    if p.variant == "westin":
        V = V * (2.0 * PI / p.wavelength) ** 2
    total = series(ops, g, V, bound)
    if p.rough == "beckmann":
        b = 2.0 * PI * sig * vz / (p.wavelength if lam_ref is None else lam_ref)
        total = rough_blend(ops, g, V, total, b * b)
    D = (0.25 * PI * PI) * (p.tau / p.wavelength) ** 2 * total
    kh = vec.half_vector_cos(ops, wi, wo)[1]
    k2 = kh * kh
    G = 16.0 * k2 * k2 / (vz * vz)
    S = (shadowing(ops, xi, p.variant, ei) / ci) * (shadowing(ops, xo, p.variant, eo) / co)
    return _fresnel(ops, p, kh), G, S, D


def _fresnel(ops, p, c):
    """``F`` by ``p.fresnel``: :func:`plausible.fresnel.weight` (``conductor``, ``schlick``,
    ``none``) or Cook & Torrance's real-index form :func:`plausible.fresnel.cook` (``dielectric``)."""
    if p.fresnel == "dielectric":
        return fresnel.cook(ops, c, p.eta)
    return fresnel.weight(ops, p.fresnel, c, p.rs, p.eta, p.k)


def directional_diffuse(ops, wi, wo, p, bound=None, lam_ref=None):
    """``rho_dd = F(k.h) G S_i S_r D / (pi c_i c_r)`` (eq. 76); zero unless both
    directions are above the horizon."""
    F, G, S, D = parts(ops, wi, wo, p, bound, lam_ref)
    return ops.where(above(ops, wi, wo), F * (G * D) * S * INV_PI, 0.0)


def specular_albedo(ops, wi, p):
    """Energy of the coherent specular (delta) lobe, ``F(c_i) exp(-g) S(c_i)^2``
    with ``g`` and ``sigma`` of the mirror pair (eqs. 9, 79, 80)."""
    ci = ops.where(wi[2] > 0, wi[2], 1.0)
    w = (wi[0], wi[1], ci)
    x, s = _cot_arg(ops, w, p.sigma0, p.tau)
    e = special.erfc(ops, x)
    sig = effective_roughness(ops, x, s, ci, x, s, ci, p.sigma0, e, e)
    a = 4.0 * PI * sig * ci / p.wavelength
    sh = shadowing(ops, x, p.variant, e)
    F = _fresnel(ops, p, ci)
    return ops.where(wi[2] > 0, F * ops.exp(-a * a) * sh * sh, 0.0)


@register("he-torrance",
          "He, Torrance, Sillion & Greenberg (1991) physical-optics BRDF: directional-diffuse "
          "series (sigma0, tau, wavelength in micrometres; complex index eta + i k) plus uniform "
          "diffuse rd/pi; the coherent specular part is a delta lobe (delta_lobes). Variants "
          "'westin' (default), 'errata', 'paper'.",
          reciprocal=True, energy_conserving=False, references=REFERENCES)
class HeTorrance(BxDF):
    """``f = rho_dd + rd / pi`` (the delta lobe apart, see the module docstring).

    ``energy_conserving=False``: with ``fresnel="none"`` and ``rs = 1`` the
    directional albedo (delta lobe included) exceeds 1 for some roughness
    (measured in docs/models/he-torrance.md); the registry entry cannot claim it.

    Sampling: a mixture of two Gaussians of the projected offset
    ``d = xy(wi) + xy(wo)`` (the variable of the series' ``exp(-V / m)``, with
    the widths of its terms ``m = 1`` and ``m = max(1, g_n)``, ``g_n`` the
    normal-incidence ``g`` of ``sigma0``) and the cosine-weighted hemisphere;
    ``wo_xy = d - wi_xy``, invalid outside the unit disc.  The density in solid
    angle is ``cos(theta_o) N(d)`` (``d^2 wo_xy = cos(theta_o) d omega``).
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (
        Param("sigma0", 0.18, 1e-4, 10.0, doc="RMS roughness sigma0 of the surface heights, micrometres",
              extremes=(0.02, 1.0)),
        Param("tau", 3.0, 1e-2, 1000.0, doc="autocorrelation length tau of the heights, micrometres",
              extremes=(0.5, 30.0)),
        Param("wavelength", 0.55, 0.1, 10.0, "color",
              "wavelength per channel, micrometres (bbm's RGB: 0.645, 0.526, 0.444)"),
        Param("fresnel", "conductor", kind="choice", choices=FRESNEL,
              doc="'conductor': exact, complex index eta + i k (k = 0: a dielectric); 'dielectric': "
                  "Cook & Torrance's real-index form (k unused; exactly 0 at eta = 1); "
                  "'schlick' (R0 = rs); 'none' (F = rs)"),
        Param("eta", 1.5, 0.0, 100.0, "color", "real part of the index of refraction"),
        Param("k", 0.0, 0.0, 100.0, "color", "imaginary part (extinction) of the index"),
        Param("rs", 1.0, 0.0, 1.0, "color", "F for fresnel='none', R0 for 'schlick'", (0.0, 1.0)),
        Param("rd", 0.0, 0.0, 1.0, "color", "uniform diffuse albedo a (rho_ud = rd / pi)", (0.0, 1.0)),
        Param("variant", "westin", kind="choice", choices=VARIANTS,
              doc="'westin': Westin's code (errata eq. 25, v in wavenumbers); 'errata': the "
                  "paper with eq. 25 corrected; 'paper': as printed"),
        Param("rough", "series", kind="choice", choices=ROUGH,
              doc="'series': eq. 78 summed for every g; 'beckmann': Beckmann's rough-surface "
                  "approximation from g = 18 (blended to g = 19), as Westin's code and bbm"),
    )

    def bound(self, p):
        """The bound of ``g`` that lets :func:`series` sum fewer terms, from the
        model's own ``sigma0`` and wavelengths (:func:`g_bound`), unless ``p.sigma0``
        varies per lane (a Mitsuba texture: every term).  The NumPy, Dr.Jit, Mitsuba
        (traversed values rebuild the model at ``params.update()``) and exported
        (GLSL) forms of a model thus sum the same terms; an exported shader whose
        ``sigma0`` uniform is raised above the model's, or its wavelength lowered,
        sums too few (export the model with the new values)."""
        if _varying(p.sigma0) or not self.terms_from_values:
            return None
        return g_bound(self.params["sigma0"], self.params["wavelength"])

    #: Does :meth:`bound` read the model's own values (False: every term, the copy
    #: :meth:`for_changing_data` makes)?
    terms_from_values = True

    def _structure(self):
        """The kernel's structure (:mod:`plausible.kernel_params`) includes the number of
        terms, which the parameters' values choose (:meth:`bound`, :func:`exact_terms`;
        ``None``: every term), and the reference wavelength of ``rough="beckmann"``."""
        from .. import kernel_params

        b = self.bound(self.p)
        return (kernel_params.default_structure(self), None if b is None else exact_terms(b),
                float(np.max(self.params["wavelength"])))

    def for_changing_data(self):
        """A copy that sums every term of the series (:meth:`bound` None, as for a
        per-lane ``sigma0``), so that a new ``sigma0`` or ``wavelength`` compiles
        nothing (the Mitsuba plugin, issue 43); its evaluation costs about 1.9x the
        model's at the default values (docs/benchmarks.md).  None for ``rough="beckmann"``,
        whose reference wavelength is a number in the code."""
        if not self.terms_from_values:
            return self
        if self.params["rough"] == "beckmann":
            return None
        out = copy.copy(self)
        out.terms_from_values = False
        return out

    def _glossy(self, ops, wi, wo, p):
        """The directional-diffuse term (eq. 76)."""
        lam_ref = float(np.max(self.params["wavelength"]))
        return directional_diffuse(ops, wi, wo, p, self.bound(p), lam_ref)

    @staticmethod
    def _diffuse(ops, wi, wo, p):
        """The uniform diffuse term ``rd / pi``."""
        return ops.where(above(ops, wi, wo), p.rd * INV_PI, 0.0)

    def _f(self, ops, wi, wo, p):
        return self._glossy(ops, wi, wo, p) + self._diffuse(ops, wi, wo, p)

    def lobes(self):
        """The directional-diffuse lobe (sampled by the two Gaussians of ``d``), then
        the uniform diffuse one (cosine-weighted, albedo ``rd``)."""
        return (Lobe("glossy", self._glossy, self._glossy_pdf, self._glossy_sample),
                Lobe("diffuse", self._diffuse,
                     lambda ops, wi, wo, q: ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0),
                     lambda ops, wi, u, q: warps.cosine_hemisphere(ops, u[1], u[2]),
                     lambda ops, wi, p: p.rd))

    # -- the delta lobe ---------------------------------------------------------------
    def delta_lobes(self, wi):
        """The coherent specular lobe as Mitsuba reports a delta lobe: a list of
        ``(direction, weight)`` with ``direction`` the mirror of ``wi`` and
        ``weight = F(c_i) exp(-g) S(c_i)^2`` (its energy; the integral of
        ``rho_sp cos(theta_o)``).  ``wi`` of shape ``(..., 3)``."""
        from ..directions import as_directions, split

        w = as_directions("wi", wi)
        c = self._color_axis(split(w))
        with np.errstate(all="ignore"):
            a = specular_albedo(_np_ops(), c, self.p)
        shape = self._out_shape(w.shape[:-1])
        return [(np.stack([-w[..., 0], -w[..., 1], w[..., 2]], axis=-1),
                 np.array(np.broadcast_to(a, shape), dtype=np.float64))]

    # -- sampling -----------------------------------------------------------------------
    @staticmethod
    def lobe_widths(ops, q):
        """Standard deviations (per axis of ``d``) of the two Gaussians: the
        series' term ``exp(-V / m)`` is ``exp(-|d|^2 / (2 s^2))`` with
        ``s^2 = 2 m / (tau^2 kappa^2)``, ``kappa = 2 pi / lambda`` ("westin") or 1."""
        kappa = 2.0 * PI / q.wavelength if q.variant == "westin" else 1.0
        gn = (4.0 * PI * q.sigma0 / q.wavelength) ** 2
        base = math.sqrt(2.0) / (q.tau * kappa)
        return base, base * ops.sqrt(ops.maximum(gn, 1.0))

    def lobe_weights(self, ops, wi, q):
        """``(1 - p_c, p_c)``, ``p_c = min(0.1 + rd, 0.9)``: ``rd``'s share goes to the
        cosine lobe, at least 0.1 of the samples (it also covers the tails of the series)."""
        pc = ops.minimum(0.1 + q.rd, 0.9)
        return 1.0 - pc, pc

    def _glossy_pdf(self, ops, wi, wo, q):
        """``cos(theta_o) (N_1(d) + N_2(d)) / 2``, ``d = xy(wi) + xy(wo)``."""
        s1, s2 = self.lobe_widths(ops, q)
        dx, dy = wi[0] + wo[0], wi[1] + wo[1]
        d2 = dx * dx + dy * dy
        gauss = 0.5 * ops.exp(-0.5 * d2 / (s1 * s1)) / (2.0 * PI * s1 * s1) \
            + 0.5 * ops.exp(-0.5 * d2 / (s2 * s2)) / (2.0 * PI * s2 * s2)
        return ops.where(above(ops, wi, wo), ops.maximum(wo[2], 0.0) * gauss, 0.0)

    def _glossy_sample(self, ops, wi, u, q):
        """``d`` from the narrow (``u[0] < 1/2``) or the wide Gaussian (Box-Muller),
        ``wo_xy = d - wi_xy``; ``(0, 0, -1)`` (invalid) outside the unit disc."""
        s1, s2 = self.lobe_widths(ops, q)
        s = ops.where(u[0] < 0.5, s1, s2)
        r = s * ops.sqrt(-2.0 * ops.log(ops.maximum(1.0 - u[1], 1e-300)))
        return warps.projected_offset(ops, wi, r, 2.0 * PI * u[2])

    def peak_directions(self, wi):
        return [np.array([-wi[0], -wi[1], wi[2]]), np.array([0.0, 0.0, 1.0])]


def _np_ops():
    from ..arrays.ops import NP

    return NP


__all__ = ["HeTorrance", "VARIANTS", "directional_diffuse", "effective_roughness", "roughness_root",
           "series", "shadowing", "specular_albedo"]
