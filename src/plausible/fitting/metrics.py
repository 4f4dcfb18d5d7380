r"""Error metrics of a fit, and the sample sets they are measured on.

Notation: the target gives ``g_k = f_T(wi_k, wo_k) cos(theta_o,k)`` on a set of
direction pairs ``k = 1..N`` (the response to a point light, pumping-up paper
eq. 3) and, where known, its directional albedo ``A_j = a_T(theta_j)`` at
incidence angles ``theta_j`` (the response to sky light, eq. 4); a candidate
gives ``c_k`` and ``a_j`` likewise.  ``eps`` is a floor under the radiances,
``eps = 1e-3 max_k g_k`` (a contrast of 1000:1; a difference below it is not
counted), the same for every metric.

* ``l2-cos`` -- least squares on the cosine-weighted BRDF, the usual fit:
  ``E_l2 = sqrt( sum_k (c_k - g_k)^2 / sum_k g_k^2 )`` (relative RMS).
* ``log`` -- least squares on the logarithm:
  ``E_log = sqrt( mean_k (ln(c_k + eps) - ln(g_k + eps))^2 )``.
* ``perceptual`` -- Neumann, Neumann & Szirmay-Kalos (1999, section 1.1): the
  maximal relative errors of ``f cos`` and of the albedo, minimised at once,
  in logarithmic units because the eye responds logarithmically:
  ``E_f = max_k |ln((c_k + eps)/(g_k + eps))|``,
  ``E_a = max_j |ln(a_j / A_j)|``, and ``E_perc = E_f + E_a`` (``combine="sum"``,
  the default) or ``max(E_f, E_a)`` (``combine="max"``).  (``|ln r| = 0.01`` is
  a 1% error.)  The sum is the default because under the maximum only the
  larger of the two is ever optimised: fitting a model whose lobe shape cannot
  follow the target's, ``E_f`` dominates and the albedo is left where it falls.
  Without a target albedo (a table of samples and no ``target_albedo``)
  ``E_perc = E_f``.

Colour targets: every figure is taken over all channels at once (the maximum
or the mean over samples *and* channels).
"""

from __future__ import annotations

import numpy as np

METRICS = ("perceptual", "l2-cos", "log")

#: Incidence angles (degrees) of the fitting directions and of the albedo terms.
THETAS_DEG = (0.0, 15.0, 30.0, 45.0, 60.0, 70.0, 80.0)
#: Angular offsets (degrees) of the lobe samples about each peak direction.
LOBE_OFFSETS_DEG = (1.0, 2.0, 4.0, 8.0, 16.0, 32.0)


def floor(g) -> float:
    """The radiance floor ``eps = 1e-3 max g`` (see the module docstring)."""
    m = float(np.max(g)) if np.size(g) else 0.0
    return 1e-3 * m if m > 0 else 1e-12


def _lr(c, g, eps):
    return np.log((np.asarray(c) + eps) / (np.asarray(g) + eps))


def albedo_error(a, A) -> float:
    """``E_a = max_j |ln(a_j / A_j)|`` over the angles where ``A_j > 0``; inf if a
    candidate albedo is 0 where the target's is not."""
    a, A = np.asarray(a, float), np.asarray(A, float)
    ok = A > 1e-12
    if not np.any(ok):
        return 0.0
    with np.errstate(divide="ignore"):
        r = np.abs(np.log(np.maximum(a[ok], 0.0) / A[ok]))
    return float(np.max(r))


COMBINE = ("sum", "max")


def check_combine(combine: str) -> str:
    """``combine`` if it is one of :data:`COMBINE`, else a ValueError naming it."""
    if combine not in COMBINE:
        raise ValueError(f"combine must be one of {', '.join(COMBINE)}, got {combine!r}")
    return combine


def _combine(ef, ea, combine):
    return ef + ea if check_combine(combine) == "sum" else max(ef, ea)


def errors(c, g, a=None, A=None, eps=None, combine: str = "sum", rows=None) -> dict:
    """Every metric's figure for candidate values ``c`` against target ``g`` (f cos),
    and albedos ``a`` against ``A`` when given.  Keys: ``l2-cos``, ``log``,
    ``perceptual``, ``fcos_max`` (``E_f``), ``albedo_max`` (``E_a``, or None); with the
    highlight ``rows`` (:func:`highlight_rows`) also ``highlight``, the largest
    ``|ln|`` ratio of ``f cos`` at them (``ln 2``: a highlight half or twice the target's)."""
    c, g = np.asarray(c, float), np.asarray(g, float)
    if c.shape != g.shape:
        raise ValueError(f"candidate and target shapes differ: {c.shape} vs {g.shape}")
    eps = floor(g) if eps is None else eps
    den = float(np.sum(g * g))
    l2 = float(np.sqrt(np.sum((c - g) ** 2) / den)) if den > 0 else float(np.sqrt(np.sum(c * c)))
    lr = _lr(c, g, eps)
    out = {"l2-cos": l2, "log": float(np.sqrt(np.mean(lr ** 2))), "fcos_max": float(np.max(np.abs(lr)))}
    if a is not None and A is not None:
        out["albedo_max"] = albedo_error(a, A)
        out["perceptual"] = _combine(out["fcos_max"], out["albedo_max"], combine)
    else:
        out["albedo_max"] = None
        out["perceptual"] = out["fcos_max"]
    if rows is not None:
        out["highlight"] = float(np.max(np.abs(lr.reshape(len(lr), -1)[rows]))) if len(rows) else 0.0
    return out


#: The highlight band: a fit keeps the target's highlight when its ``f cos`` at the target's
#: brightest sample of every incidence (:func:`highlight_rows`) is within this factor of the
#: target's.  Beyond it each log unit of excess costs :data:`HIGHLIGHT_WEIGHT` times its square
#: in what the fit minimises (:func:`highlight_excess`): a constraint the fit meets wherever the
#: model can, and no cost at all inside the band, so a fit that keeps its highlight is unchanged.
#: ``HIGHLIGHT_WEIGHT`` is the default of :func:`plausible.fit`'s ``highlight`` argument (0: the plain
#: metrics, as the papers fit).
HIGHLIGHT_BAND, HIGHLIGHT_WEIGHT = 1.75, 100.0


#: The highlight is held at incidences up to this angle (degrees).  Beyond, lobes differ by
#: construction (Ashikhmin-Shirley's ``1 / max(cos)`` and Schlick's rise make its grazing peak
#: about 30 times a Blinn lobe's at 80 degrees when both agree at normal incidence), and a
#: constraint there would pull the highlight off at every other incidence.
HIGHLIGHT_MAX_THETA = 60.0


def highlight_rows(wi, g, max_theta_deg: float = HIGHLIGHT_MAX_THETA) -> np.ndarray:
    """The highlight of a target: per distinct incidence ``wi`` (rows of an ``(N, 3)`` array)
    up to ``max_theta_deg`` from the normal, the index of its largest ``g`` (``f cos``; channel
    mean for colours), the peak of what a point light shows.  Sorted by index."""
    wi = np.asarray(wi, float).reshape(-1, 3)
    g = np.asarray(g, float)
    g = g.mean(axis=-1) if g.ndim == 2 else g
    r = np.round(wi, 12) + 0.0              # -0.0 and 0.0 one incidence
    # the distinct incidences by a lexicographic sort (np.unique(axis=0) sorts a structured view: 10x slower)
    o = np.lexsort(r.T[::-1])
    new = np.r_[True, np.any(r[o][1:] != r[o][:-1], axis=1)]
    group = np.empty(len(r), dtype=np.intp)
    group[o] = np.cumsum(new) - 1
    order = np.lexsort((-g, group))
    first = np.r_[True, group[order][1:] != group[order][:-1]]
    rows = order[first]
    cos = wi[rows, 2] / np.linalg.norm(wi[rows], axis=-1)
    return np.sort(rows[cos >= np.cos(np.radians(max_theta_deg)) - 1e-12])


def highlight_ratio(c, g, rows, eps) -> np.ndarray:
    """``ln((c_k + eps) / (g_k + eps))`` at the highlight ``rows`` (:func:`highlight_rows`)."""
    return _lr(np.asarray(c)[rows], np.asarray(g)[rows], eps)


def highlight_excess(c, g, rows, eps) -> np.ndarray:
    """The highlight's log ratio beyond the band (:data:`HIGHLIGHT_BAND`), signed, zero inside:
    ``sign(d) max(0, |d| - ln B)`` with ``d`` of :func:`highlight_ratio`.  The fit adds
    ``w sum excess^2`` to every metric's figure (least squares: rows ``sqrt(w) excess``), ``w`` its
    ``highlight`` argument (default :data:`HIGHLIGHT_WEIGHT`)."""
    d = highlight_ratio(c, g, rows, eps)
    return np.sign(d) * np.maximum(np.abs(d) - np.log(HIGHLIGHT_BAND), 0.0)


def _smooth_max_abs(r, beta):
    r = np.concatenate([r, -r])
    m = float(np.max(r))
    return m + float(np.log(np.sum(np.exp(beta * (r - m))))) / beta


def objective(metric: str, c, g, a=None, A=None, eps=None, beta: float = 50.0,
              combine: str = "sum") -> float:
    """The function the optimiser minimises for ``metric``.

    ``l2-cos`` and ``log`` are the squares of their figures (smooth).  For
    ``perceptual`` each maximum of ``|ln|`` residuals (``E_f`` and ``E_a``) is
    replaced by its smooth upper bound ``(1/beta) ln sum exp(beta r)`` over
    ``r = +-residuals``, which exceeds the maximum by at most ``ln(2 M)/beta``
    for ``M`` residuals (``combine="max"``: one bound over both sets); the
    reported figure is always the true one (:func:`errors`).
    """
    c, g = np.asarray(c, float), np.asarray(g, float)
    eps = floor(g) if eps is None else eps
    if metric == "l2-cos":
        den = float(np.sum(g * g)) or 1.0
        return float(np.sum((c - g) ** 2) / den)
    if metric == "log":
        return float(np.mean(_lr(c, g, eps) ** 2))
    if metric == "perceptual":
        rf = _lr(c, g, eps).ravel()
        if a is None or A is None:
            return _smooth_max_abs(rf, beta)
        a, A = np.asarray(a, float).ravel(), np.asarray(A, float).ravel()
        ok = A > 1e-12
        ra = np.log(np.maximum(a[ok], 1e-300) / A[ok])
        if combine == "max":
            return _smooth_max_abs(np.concatenate([rf, ra]), beta)
        check_combine(combine)
        return _smooth_max_abs(rf, beta) + (_smooth_max_abs(ra, beta) if ra.size else 0.0)
    raise ValueError(f"metric must be one of {', '.join(METRICS)}, got {metric!r}")


#: Incidence azimuths (degrees): three, so that an anisotropic model fitted to
#: an isotropic target is constrained along both tangents.
AZIMUTHS_DEG = (0.0, 45.0, 90.0)


def sample_pairs(peaks_of, thetas_deg=THETAS_DEG, azimuths_deg=AZIMUTHS_DEG):
    """The deterministic fitting directions: ``(wi, wo)`` arrays of shape (N, 3).

    For each incidence ``theta_i`` in ``thetas_deg`` and azimuth in
    ``azimuths_deg``: a uniform set of outgoing directions
    (``theta_o`` = 5, 15, ..., 85 degrees times ``phi_o`` = 0, 30, ..., 330
    degrees, and the normal), and lobe samples about each direction of
    ``peaks_of(wi)`` (the target's ``peak_directions``: the peak itself and 8
    azimuths at each offset of :data:`LOBE_OFFSETS_DEG`); outgoing directions
    within 0.6 degrees of the horizon are dropped.
    """
    from ..analysis import direction

    to = np.radians(np.arange(5.0, 90.0, 10.0))
    po = np.radians(np.arange(0.0, 360.0, 30.0))
    T, P = np.meshgrid(to, po, indexing="ij")
    uni = np.concatenate([np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
                          .reshape(-1, 3), [[0.0, 0.0, 1.0]]])
    offs = np.radians(np.asarray(LOBE_OFFSETS_DEG))
    az = np.radians(np.arange(0.0, 360.0, 45.0))
    O, Z = np.meshgrid(offs, az, indexing="ij")
    ring = np.stack([np.sin(O) * np.cos(Z), np.sin(O) * np.sin(Z), np.cos(O)], -1).reshape(-1, 3)
    ring = np.concatenate([[[0.0, 0.0, 1.0]], ring])
    phis = tuple(azimuths_deg)
    WI, WO = [], []
    for ph in phis:
        for t in thetas_deg:
            wi = direction(np.radians(t), np.radians(ph))
            outs = [uni]
            for p in peaks_of(wi):
                p = np.asarray(p, float) / np.linalg.norm(p)
                outs.append(_rotate_to(ring, p))
            wo = np.concatenate(outs)
            wo = wo[wo[:, 2] > 0.01]
            WI.append(np.broadcast_to(wi, wo.shape))
            WO.append(wo)
    return np.concatenate(WI), np.concatenate(WO)


def _rotate_to(local, axis):
    from .. import vec
    from ..arrays.ops import NP

    s, t = vec.frame(NP, tuple(float(x) for x in axis))
    s, t = np.array(s), np.array(t)
    return local[:, :1] * s + local[:, 1:2] * t + local[:, 2:3] * axis
