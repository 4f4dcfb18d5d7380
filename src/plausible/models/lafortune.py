"""Lafortune's generalized cosine lobes (Lafortune, Foo, Torrance, Greenberg 1997).

``f(L, V) = rd / pi + sum_k rho_k max(cx_k Lx Vx + cy_k Ly Vy + cz_k Lz Vz, 0)^n_k``

Each lobe is a "generalised dot product" ``(C L) . V`` with the diagonal
matrix ``C = diag(cx, cy, cz)`` in the local shading frame.  ``cx = cy = -1,
cz = 1`` gives the reciprocal Phong lobe ``(R . V)^n`` (``R`` the mirror
direction of ``L``); ``cx = cy = -s, cz = s'`` (``|cx| > cz``) moves the peak
toward grazing angles (off-specular peaks); ``cx = cy = cz = 1`` is a
retro-reflective lobe ``(L . V)^n``; ``cx = cy = 0`` a lobe about the normal.
The albedo pumping-up paper (Neumann, Neumann, Szirmay-Kalos 1999) writes one
such lobe as its eq. 7, ``C_Lafortune (R_x V_x + R_y V_y + s R_z V_z)^n``, i.e.
``C = diag(-1, -1, s)`` applied to ``L``.

The lobe is symmetric in ``L`` and ``V`` (``C`` is diagonal), so the model is
reciprocal for any parameters.

Notation used below, for one lobe and a given ``wi = L``: ``a = C L`` (the
"lobe vector"), ``d = a / |a|`` (the lobe axis), so the lobe value is
``rho |a|^n max(d . V, 0)^n``: a ``cos^n`` lobe about ``d``, scaled by
``rho |a|^n``.

Energy
------
The directional albedo at ``L`` is
``a(L) = rd + sum_k rho_k |C_k L|^n_k I(d_k)`` with
``I(d) = int_{V.z > 0} max(d . V, 0)^n (V . z) dV``.  By Hoelder's inequality
with exponents ``(n+1)/n`` and ``n+1``,
``I(d) <= (int max(d.V,0)^(n+1) dV)^(n/(n+1)) (int max(z.V,0)^(n+1) dV)^(1/(n+1))
= 2 pi / (n + 2)`` (both integrals equal ``2 pi / (n + 2)``), with equality for
``d = z``; and ``|C L| <= c_max = max(|cx|, |cy|, |cz|)`` for unit ``L``.  So

``max(rd) + sum_k rho_k c_max,k^n_k 2 pi / (n_k + 2) <= 1``

guarantees ``a(L) <= 1`` for every ``L``.  The model validates this sufficient
bound (ValueError otherwise); for a single reciprocal-Phong lobe
(``c_max = 1``, axis ``d = R``, equality at normal incidence) it is exactly the
necessary condition ``rd + rho 2 pi / (n + 2) <= 1``, i.e. ``rd + ks <= 1``.

Any lobe can be rewritten with ``c_max = 1`` without changing ``f``:
``rho (C L . V)^n = (rho c_max^n) ((C / c_max) L . V)^n``.  The hooks use this
normalised form internally, so ``|C L|^n`` never overflows.

Sampling
--------
Component ``k`` is chosen with probability ``E_k / (rd_mean + sum_j E_j)``,
the diffuse part with probability ``rd_mean / (...)``, using ``u[..., 0]``;
``E_k = rho_k |C_k L|^n_k 2 pi / (n_k + 2) (1 + d_z) / 2`` estimates the lobe's
albedo at ``L``: exact for ``d = z``, never smaller than half the bound above
for axes above the horizon, and zero only when the lobe has no support above
the horizon (``d = -z``) or vanishes (``C L = 0``).  A lobe is sampled with the
``cos^n`` warp about its own axis ``d`` (density ``(n+1)/(2 pi) (d . V)^n`` on
``d . V > 0``), which is proportional to the lobe itself; the diffuse part is
cosine weighted.  ``pdf`` is the same mixture.
"""

from __future__ import annotations

import math

import numpy as np

from .. import vec, warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI, PI
from ..params import LobesParam, Param
from ..registry import register
from ..vec import above

#: Default: one reciprocal-Phong lobe of exponent 20 and albedo 0.5 at normal
#: incidence (``rho = 0.5 (n + 2) / (2 pi)``), with ``rd = 0.3``.
DEFAULT_LOBES = ((-1.0, -1.0, 1.0, 20.0, 0.5 * 22.0 / (2.0 * math.pi)),)


def c_max(lobe) -> float:
    """``max(|cx|, |cy|, |cz|)`` of one lobe: the largest ``|C L|`` over unit ``L``."""
    return max(abs(lobe[0]), abs(lobe[1]), abs(lobe[2]))


def normalised_lobes(lobes):
    """The same lobes rewritten with ``c_max = 1``: ``(C / c_max, n, rho c_max^n)``.

    ``rho (C L . V)^n == rho c_max^n ((C / c_max) L . V)^n`` exactly, so ``f`` is
    unchanged; the power of the normalised dot product never overflows.  A lobe
    with ``C = 0`` is dropped (its value is zero: the dot product is never
    positive).  Plain Python floats (parameters), not arrays.
    """
    out = []
    for cx, cy, cz, n, rho in lobes:
        m = c_max((cx, cy, cz))
        if m == 0.0:
            continue
        log_scale = n * math.log(m)   # m^n; exactly 1 for m == 1 (inf past the float range:
        scale = math.exp(log_scale) if log_scale < 709.0 else math.inf   # the bound then refuses it)
        out.append((cx / m, cy / m, cz / m, n, rho * scale if rho > 0 else 0.0))
    return out


def albedo_bound(lobes, rd_max: float) -> float:
    """``rd_max + sum_k rho_k c_max,k^n_k 2 pi / (n_k + 2)``: an upper bound of the
    directional albedo at every incident direction (see the module docstring)."""
    total = rd_max
    for cx, cy, cz, n, rho in normalised_lobes(lobes):
        total += rho * 2.0 * PI / (n + 2.0)
    return total


def lobe_vector(wi, lobe):
    """``a = C wi = (cx wi_x, cy wi_y, cz wi_z)``."""
    return (lobe[0] * wi[0], lobe[1] * wi[1], lobe[2] * wi[2])


def lobe_value(ops, wi, wo, lobe):
    """``rho max(cx Lx Vx + cy Ly Vy + cz Lz Vz, 0)^n`` (Lafortune et al. 1997;
    albedo pumping-up paper eq. 7).  ``lobe`` in normalised form.

    Near the peak the power is taken from
    ``1 - a.V = (|a - V|^2 + sum_k (1 - c_k^2) L_k^2) / 2`` (unit ``L``, ``V``;
    every term is >= 0 for a normalised lobe, so nothing cancels) by
    :func:`plausible.warps.power_near_one`, which keeps float32 evaluations
    (shaders) accurate for exponents of 10^4."""
    a = lobe_vector(wi, lobe)
    s = vec.dot(a, wo)
    d = (a[0] - wo[0], a[1] - wo[1], a[2] - wo[2])
    rest = sum((1.0 - c * c) * w * w for c, w in zip(lobe[:3], wi) if c * c != 1.0)
    one_minus = 0.5 * (vec.dot(d, d) + rest)
    return ops.where(s > 0, lobe[4] * warps.power_near_one(ops, s, one_minus, lobe[3]), 0.0)


def lafortune(ops, wi, wo, rd, lobes):
    """``f = rd / pi + sum_k lobe_k`` for both directions above the horizon, else 0."""
    val = rd * INV_PI
    for lobe in lobes:
        val = val + lobe_value(ops, wi, wo, lobe)
    return ops.where(above(ops, wi, wo), val, 0.0)


def lobe_axis_and_estimate(ops, wi, lobe):
    """Lobe axis ``d = C wi / |C wi|`` and the albedo estimate
    ``E = rho |C wi|^n 2 pi / (n + 2) (1 + d_z) / 2`` used as mixture weight."""
    a = lobe_vector(wi, lobe)
    len2 = vec.dot(a, a)
    ok = len2 > 0
    length = ops.sqrt(ops.where(ok, len2, 1.0))
    d = vec.scale(a, ops.where(ok, 1.0 / length, 0.0))
    n, rho = lobe[3], lobe[4]
    e = rho * ops.power(length, n) * (2.0 * PI / (n + 2.0)) * (0.5 * (1.0 + d[2]))
    return d, ops.where(ok, e, 0.0)


#: The logarithm standing for a weight of zero (finite, so that every backend,
#: the GLSL export included, can subtract from it).
LOG_ZERO = -1e30


def lobe_axis_and_log_estimate(ops, wi, lobe):
    """:func:`lobe_axis_and_estimate` with the estimate as its logarithm
    ``log E = log rho + (n/2) log |C wi|^2 + log(2 pi / (n + 2)) + log((1 + d_z)/2)``
    (:data:`LOG_ZERO` where ``E = 0``): ``rho |C wi|^n`` may be a float64
    subnormal, which Dr.Jit flushes to zero (the pdf then lost the lobe while
    NumPy kept it, so the answer depended on the batch size)."""
    a = lobe_vector(wi, lobe)
    len2 = vec.dot(a, a)
    ok = len2 > 0
    safe = ops.where(ok, len2, 1.0)
    d = vec.scale(a, ops.where(ok, 1.0 / ops.sqrt(safe), 0.0))
    n, rho = lobe[3], lobe[4]
    half = 0.5 * (1.0 + d[2])
    good = ok & (half > 0)
    if not rho > 0:
        return d, ops.where(good, LOG_ZERO, LOG_ZERO)
    log_e = (0.5 * n) * ops.log(safe) + (math.log(rho) + math.log(2.0 * PI / (n + 2.0))) \
        + ops.log(ops.where(half > 0, half, 1.0))
    return d, ops.where(good, log_e, LOG_ZERO)


def mixture_weights(ops, rd, log_estimates):
    """``(w_d, [w_k])``: the diffuse weight ``rd`` and the lobes' estimates divided by
    the largest of them (computed from the logarithms, so a lobe whose estimate is
    subnormal still has its share when every component is that small)."""
    log_rd = math.log(rd) if isinstance(rd, (int, float)) and rd > 0 else LOG_ZERO \
        if isinstance(rd, (int, float)) else ops.where(rd > 0, ops.log(ops.maximum(rd, 1e-300)), LOG_ZERO)
    top = log_rd
    for le in log_estimates:
        top = ops.maximum(top, le)
    return ops.exp(log_rd - top), [ops.exp(le - top) for le in log_estimates]


def lobe_pdf(ops, wi, wo, lobe):
    """``(n + 1) / (2 pi) max(d . wo, 0)^n``: density of the ``cos^n`` warp about
    ``d = C wi / |C wi|``, with ``d . wo`` taken as ``(C wi . wo) / |C wi|`` so
    that it is positive exactly where the lobe of ``f`` is (:func:`lobe_value`
    tests ``C wi . wo > 0``): a direction on the lobe's rim (``u = 0`` in the
    warp) rounded to one side in ``f`` and to the other in the pdf, and a
    mixture with a tiny diffuse part weighted it ``rho / (rd / pi)``, 1e58."""
    a = lobe_vector(wi, lobe)
    len2 = vec.dot(a, a)
    ok = len2 > 0
    cos = vec.dot(a, wo) / ops.sqrt(ops.where(ok, len2, 1.0))
    return ops.where(ok, warps.power_cosine_lobe_pdf(ops, lobe[3], cos), 0.0)


def _lobe_f(k):
    """``f`` of the ``k``-th (normalised) lobe alone."""
    return lambda ops, wi, wo, p: ops.where(above(ops, wi, wo),
                                            lobe_value(ops, wi, wo, normalised_lobes(p.lobes)[k]), 0.0)


def _lobe_pdf(k):
    def pdf(ops, wi, wo, q):
        return ops.where(above(ops, wi, wo), lobe_pdf(ops, wi, wo, normalised_lobes(q.lobes)[k]), 0.0)
    return pdf


def _lobe_sample(k):
    def sample(ops, wi, u, q):
        lobe = normalised_lobes(q.lobes)[k]
        d = lobe_axis_and_log_estimate(ops, wi, lobe)[0]
        return warps.power_cosine_lobe_about(ops, d, lobe[3], u[1], u[2])
    return sample


@register("lafortune",
          "Lafortune et al. 1997 generalized cosine lobes: f = rd/pi + sum rho (cx Lx Vx + "
          "cy Ly Vy + cz Lz Vz)^n; energy bound rd + sum rho cmax^n 2pi/(n+2) <= 1 enforced.",
          references=("E. Lafortune, S.-C. Foo, K. Torrance, D. Greenberg, 'Non-linear "
                      "approximation of reflectance functions', SIGGRAPH 1997",
                      "Neumann et al. 1999 (albedo pumping-up), eq. 7"))
class Lafortune(BxDF):
    """``Lafortune(lobes=[(cx, cy, cz, n, rho), ...], rd)``.

    ``f = rd / pi + sum_k rho_k max(cx Lx Vx + cy Ly Vy + cz Lz Vz, 0)^n_k``.
    ``rho`` is a scalar per lobe; ``rd`` may be a colour.  Parameters must
    satisfy ``max(rd) + sum_k rho_k c_max,k^n_k 2 pi / (n_k + 2) <= 1``, a
    sufficient condition for energy conservation (proof in the module
    docstring); for one lobe ``(-1, -1, 1, n, ks (n + 2) / (2 pi))`` the model is
    ``reciprocal-phong(ks, n)`` plus ``rd / pi``.
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (
        LobesParam("lobes", DEFAULT_LOBES, doc="generalized cosine lobes (cx, cy, cz, n, rho)",
                   extremes=(((-1.0, -1.0, 1.0, 0.0, 0.5 / math.pi),),
                             ((1.0, 1.0, 1.0, 10.0, 0.5 * 12.0 / (2.0 * math.pi)),))),
        Param("rd", 0.3, 0.0, 1.0, "color", "diffuse reflectance", (0.0, 0.5)),
    )

    def _validate(self):
        rd_max = float(np.max(self.params["rd"]))
        bound = albedo_bound(self.params["lobes"], rd_max)
        if bound > 1.0 + 1e-12:
            raise ValueError(
                "Lafortune: parameters 'lobes' and 'rd' must satisfy max(rd) + sum over lobes of "
                "rho * max(|cx|,|cy|,|cz|)^n * 2 pi / (n + 2) <= 1 (sufficient condition for "
                f"energy conservation), got {bound:.6g}")

    def _f(self, ops, wi, wo, p):
        return lafortune(ops, wi, wo, p.rd, normalised_lobes(p.lobes))

    def lobes(self):
        """The Lambertian term (albedo ``rd``), then each generalized cosine lobe
        (normalised, :func:`normalised_lobes`), sampled as a ``cos^n`` lobe about
        its axis ``C wi / |C wi|``."""
        out = [Lobe("diffuse", lambda ops, wi, wo, p: ops.where(above(ops, wi, wo), p.rd * INV_PI, 0.0),
                    lambda ops, wi, wo, q: ops.where(above(ops, wi, wo),
                                                     warps.cosine_hemisphere_pdf(ops, wo), 0.0),
                    lambda ops, wi, u, q: warps.cosine_hemisphere(ops, u[1], u[2]),
                    lambda ops, wi, p: p.rd)]
        for k in range(len(normalised_lobes(self.params["lobes"]))):
            out.append(Lobe("glossy", _lobe_f(k), _lobe_pdf(k), _lobe_sample(k)))
        return tuple(out)

    def lobe_weights(self, ops, wi, q):
        """The diffuse term's and each lobe's mixture weight (:meth:`_weights`)."""
        _, w_d, est, _ = self._weights(ops, wi, q)
        return (w_d,) + tuple(est)

    def _weights(self, ops, wi, q):
        """Axes, the mixture weights of the diffuse term and of each lobe (relative
        to the largest: :func:`mixture_weights`) and their sum."""
        axes, logs = [], []
        for lobe in normalised_lobes(q.lobes):
            d, le = lobe_axis_and_log_estimate(ops, wi, lobe)
            axes.append((d, lobe))
            logs.append(le)
        w_d, est = mixture_weights(ops, q.rd, logs)
        total = w_d
        for e in est:
            total = total + e
        return axes, w_d, est, total

    def _pdf(self, ops, wi, wo, q):
        axes, w_d, est, total = self._weights(ops, wi, q)
        val = w_d * warps.cosine_hemisphere_pdf(ops, wo)
        for (d, lobe), e in zip(axes, est):
            val = val + e * lobe_pdf(ops, wi, wo, lobe)
        pos = total > 0
        return ops.where(above(ops, wi, wo) & pos, val / ops.where(pos, total, 1.0), 0.0)

    def _sample(self, ops, wi, u, q):
        axes, w_d, est, total = self._weights(ops, wi, q)
        t = u[0] * total
        out = warps.cosine_hemisphere(ops, u[1], u[2])
        start = w_d
        for (d, lobe_k), e in zip(axes, est):
            lobe = warps.power_cosine_lobe_about(ops, d, lobe_k[3], u[1], u[2])
            # Component k covers t in [start_k, start_k + E_k); a later match wins.
            out = warps.mixture(ops, (t >= start) & (e > 0), lobe, out)
            start = start + e
        return out

    def peak_directions(self, wi: np.ndarray) -> list:
        """Each lobe's axis ``C wi / |C wi|`` (moved just above the horizon when it
        points below), plus the mirror direction."""
        wi = np.asarray(wi, dtype=np.float64)
        wi = wi / np.linalg.norm(wi)
        out = [np.array([-wi[0], -wi[1], wi[2]])]
        for lobe in normalised_lobes(self.params["lobes"]):
            a = np.array(lobe_vector(wi, lobe), dtype=np.float64)
            if not np.any(a):
                continue
            d = a / np.linalg.norm(a)
            if d[2] <= 0:
                if d[0] == 0 and d[1] == 0:
                    continue
                d = np.array([d[0], d[1], 0.0])
                d = d / np.linalg.norm(d)
                d = np.array([d[0], d[1], 1e-6]) / math.sqrt(1.0 + 1e-12)
            out.append(d)
        return out
