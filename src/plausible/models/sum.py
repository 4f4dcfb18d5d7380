"""A sum of models: ``f = sum_k s_k f_k`` (the composition the published fits use).

Every fit of the MERL materials (Ngan et al. 2005, Löw et al. 2012; see
:mod:`plausible.materials`) is a Lambertian term plus one specular lobe scaled
by an RGB albedo: bbm's ``Aggregate(Lambertian(...), Model(albedo=...))``.
:class:`Sum` is that composition for any models of the contract:

* ``eval``: ``f(wi, wo) = sum_k s_k f_k(wi, wo)``, ``s_k`` a grey or RGB scale
  (default 1).  A sum of reciprocal terms is reciprocal (``f_k(wi, wo) =
  f_k(wo, wi)`` for each term), so :attr:`Sum.reciprocal` is true exactly when
  every part claims it.
* ``sample``: part ``k`` is chosen with probability ``P_k = w_k / sum_j w_j``
  (``u[..., 0]`` picks the part; the remainder of ``u[..., 0]``, rescaled to
  ``[0, 1)``, drives the part's own lobe choice), then sampled with its own
  sampler; ``pdf(wi, wo) = sum_k P_k pdf_k(wi, wo)``, the same mixture (one-sample
  multiple importance sampling with the balance heuristic, Veach 1997, sec. 9.2.4).
* ``w_k`` estimates the part's albedo: ``mean(s_k)`` times the mean, over the
  incidences ``cos(theta_i) = 1, 0.75, 0.5, 0.25``, of the Monte Carlo estimate
  ``mean(weight)`` of its own sampler on a stratified 32 x 32 grid (the sampler's
  weight is ``f cos / pdf``, so the mean is an unbiased estimate of the directional
  albedo).  Computed once per model in NumPy; the weights are plain floats, so
  the hooks run unchanged on Dr.Jit.  ``w_k`` is floored at ``1e-3 sum_j w_j``:
  every part keeps a positive probability, so the mixture's support contains each
  part's support and the estimator stays unbiased whatever the estimate.

References: bbm's ``aggregatebsdf`` (P. Peers, 2023) chooses parts by their
hemispherical reflectance the same way; E. Veach, *Robust Monte Carlo methods
for light transport simulation*, PhD thesis, Stanford 1997, sec. 9.2.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from .. import warps
from ..bxdf import BxDF, Lobe, mixture_probabilities
from ..kernel_params import is_data
from ..params import spec_value
from ..registry import provide_sum
from ..text import fmt

#: Cosines of the incidences at which a part's albedo is estimated.
ESTIMATE_COSINES = (1.0, 0.75, 0.5, 0.25)
#: Samples per side of the stratified grid of the estimate.
ESTIMATE_GRID = 32
#: Smallest selection weight, relative to the sum of the weights.
WEIGHT_FLOOR = 1e-3


def _scale_array(scale, k):
    """``scale`` validated: ``None`` (1), a non-negative float or a 1-D channel array."""
    if scale is None:
        return None
    try:
        a = np.asarray(scale, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"Sum: part {k}: parameter 'scale' must be a number or a list of numbers in "
                         f"[0, inf), got {scale!r}") from None
    if a.ndim > 1 or a.size == 0 or not np.all(np.isfinite(a)) or np.any(a < 0):
        raise ValueError(f"Sum: part {k}: parameter 'scale' must be a number or a 1-D channel array "
                         f"(e.g. RGB) in [0, inf), got {scale!r}")
    return float(a) if a.ndim == 0 else a


def albedo_estimate(model) -> float:
    """Mean over :data:`ESTIMATE_COSINES` of the channel-mean Monte Carlo albedo of
    ``model`` with its own sampler (``ESTIMATE_GRID^2`` stratified samples each)."""
    g = ESTIMATE_GRID
    i, j = np.meshgrid(np.arange(g), np.arange(g), indexing="ij")
    u = np.stack([np.full(g * g, 0.5), ((i + 0.5) / g).ravel(), ((j + 0.5) / g).ravel()], axis=-1)
    # u[..., 0] over its range too (it picks the model's own lobes)
    u[:, 0] = ((np.arange(g * g) * 0.6180339887498949) % 1.0)
    total = 0.0
    for c in ESTIMATE_COSINES:
        wi = np.array([np.sqrt(1.0 - c * c), 0.0, c])
        s = model.sample(wi, u)
        w = np.nan_to_num(np.asarray(s.weight, dtype=np.float64), nan=0.0, posinf=0.0)
        total += float(np.mean(w))
    return total / len(ESTIMATE_COSINES)


class Sum(BxDF):
    """``Sum(parts)``: ``f = sum_k s_k f_k``; ``parts`` a list of models or of
    ``(model, scale)`` pairs (``scale`` a float or an RGB triple, default 1).

    >>> import plausible
    >>> from plausible.models.sum import Sum
    >>> m = Sum([plausible.make("lambertian", rd=0.5), (plausible.make("lambertian", rd=1.0), 0.25)])
    >>> round(float(m.eval([0, 0, 1], [0, 0, 1])) * 3.141592653589793, 12)
    0.75
    """

    PARAMS = ()

    def __init__(self, parts, name: str | None = None, spec: str | None = None):
        super().__init__()
        #: The spec this sum was read from where it is shorter than its parts' (``material:NAME@FIT``).
        self.source_spec = spec
        if isinstance(parts, (str, bytes, BxDF)) or not hasattr(parts, "__iter__"):
            raise ValueError(f"Sum: parameter 'parts' must be a non-empty list of models or "
                             f"(model, scale) pairs, got {parts!r}")
        models, scales = [], []
        for k, item in enumerate(parts):
            if isinstance(item, BxDF):
                model, scale = item, None
            elif isinstance(item, (tuple, list)) and len(item) == 2 and isinstance(item[0], BxDF):
                model, scale = item
            else:
                raise ValueError(f"Sum: part {k} must be a model (BxDF) or a (model, scale) pair, "
                                 f"got {item!r}")
            models.append(model)
            scales.append(_scale_array(scale, k))
        if not models:
            raise ValueError("Sum: parameter 'parts' must be a non-empty list of models, got an empty list")
        chans = {m.channels for m in models if m.channels} | {np.size(s) for s in scales if np.ndim(s) == 1}
        if len(chans) > 1:
            raise ValueError(f"Sum: parts and scales have different channel counts {sorted(chans)}")
        self.channels = chans.pop() if chans else None
        self.parts = tuple(models)
        self.scales = tuple(scales)
        self.label = name
        est = [albedo_estimate(m) * (1.0 if s is None else float(np.mean(s)))
               for m, s in zip(models, scales)]
        total = sum(est)
        floor = WEIGHT_FLOOR * total if total > 0 else 1.0
        w = [max(e, floor) for e in est]
        #: Selection probability of each part (sums to 1).
        self.probabilities = tuple(x / sum(w) for x in w)
        self._part_p = tuple(m.p for m in models)
        self._part_q = tuple(m.q for m in models)
        self._scale_p = self.scales

    # -- what the sum claims ------------------------------------------------------
    @property
    def reciprocal(self) -> bool:
        """True when every part claims reciprocity (its registry entry, or its own
        ``reciprocal`` attribute): a sum of symmetric terms is symmetric."""
        return all(_claims_reciprocal(m) for m in self.parts)

    @property
    def name(self) -> str:
        return self.label or "sum"

    def with_backend_colors(self, convert):
        """A copy whose parts' colour parameters and scales are passed through
        ``convert`` (a NumPy channel array -> the backend's colour type), e.g. to
        ``mi.Color3f`` for the Mitsuba plugin (Dr.Jit cannot mix NumPy arrays in)."""
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)

        def conv_ns(ns):
            return SimpleNamespace(**{k: (convert(v) if isinstance(v, np.ndarray) else v)
                                      for k, v in vars(ns).items()})

        out._part_p = tuple(conv_ns(p) for p in self._part_p)
        out._scale_p = tuple(convert(s) if isinstance(s, np.ndarray) else s for s in self.scales)
        return out

    def _kernel_view(self, convert):
        """Parts, scales and selection probabilities as kernel data
        (:mod:`plausible.kernel_params`)."""
        out = object.__new__(type(self))
        out.__dict__.update(self.__dict__)
        out.parts = tuple(m._kernel_view(convert) for m in self.parts)
        out._part_p = tuple(m.p for m in out.parts)
        out._part_q = tuple(m.q for m in out.parts)
        out._scale_p = tuple(convert(s) if is_data(s) else s for s in self._scale_p)
        out.probabilities = tuple(convert(float(x)) for x in self.probabilities)
        return out

    def _structure(self):
        return ("Sum", self.channels, tuple(m._structure() for m in self.parts),
                tuple(None if s is None else np.shape(s) for s in self.scales))

    # -- hooks ----------------------------------------------------------------------
    def _f(self, ops, wi, wo, p):
        total = 0.0
        for m, mp, s in zip(self.parts, self._part_p, self._scale_p):
            v = m._f(ops, wi, wo, mp)
            total = total + (v if s is None else v * s)
        return total

    def _pdf(self, ops, wi, wo, q):
        total = 0.0
        for m, mq, pk in zip(self.parts, self._part_q, self.probabilities):
            total = total + pk * m._pdf(ops, wi, wo, mq)
        return total

    def _sample(self, ops, wi, u, q):
        out = None
        start = 0.0
        for m, mq, pk in zip(self.parts, self._part_q, self.probabilities):
            # the part's own u0: where u[0] falls inside this part's interval, in [0, 1)
            u0 = ops.minimum(ops.maximum((u[0] - start) / pk, 0.0), 0.9999999999999999)
            wo = m._sample(ops, wi, (u0, u[1], u[2]), mq)
            out = wo if out is None else warps.mixture(ops, u[0] >= start, wo, out)
            start = start + pk
        return out

    def lobes(self):
        """Every part's components (:meth:`BxDF.components`), each scaled by its
        part's scale and bound to its part's parameters, part after part (the
        order of :meth:`_sample`'s intervals)."""
        out = []
        for m, mp, mq, s in zip(self.parts, self._part_p, self._part_q, self._scale_p):
            for lobe in m.components():
                out.append(Lobe(lobe.kind, _scaled(lambda ops, wi, wo, p, f=lobe.f, mp=mp: f(ops, wi, wo, mp), s),
                                lambda ops, wi, wo, q, g=lobe.pdf, mq=mq: g(ops, wi, wo, mq),
                                lambda ops, wi, u, q, g=lobe.sample, mq=mq: g(ops, wi, u, mq),
                                None if lobe.albedo is None else
                                _scaled(lambda ops, wi, p, a=lobe.albedo, mp=mp: a(ops, wi, mp), s)))
        return tuple(out)

    def lobe_weights(self, ops, wi, q):
        """Part ``k``'s probability times its own lobes' shares."""
        out = []
        for m, mq, pk in zip(self.parts, self._part_q, self.probabilities):
            out.extend(pk * w for w in mixture_probabilities(ops, m.component_weights(ops, wi, mq)))
        return tuple(out)

    def peak_directions(self, wi):
        out = []
        for m in self.parts:
            out.extend(m.peak_directions(wi))
        return out

    def mirror_cut(self):
        return any(m.mirror_cut() for m in self.parts)

    def level_kink(self):
        return any(m.level_kink() for m in self.parts)

    def kink_curves(self, wi, phi):
        return [c for m in self.parts for c in m.kink_curves(wi, phi)]

    def kink_azimuths(self, wi):
        return [a for m in self.parts for a in m.kink_azimuths(wi)]

    def terms(self, scale=None) -> list:
        """``[(model, scale or None), ...]``: the parts, a nested sum's own terms in its place, each
        scale times ``scale`` (a sum of sums is the sum of all their terms)."""
        out = []
        for m, s in zip(self.parts, self.scales):
            k = s if scale is None else (scale if s is None else np.asarray(s) * scale)
            if type(m) is Sum and not m.source_spec:        # not a subclass with its own spec
                out.extend(m.terms(k))
            else:
                out.append((m, k))
        return out

    def spec(self) -> str:
        """The sum as a spec that :func:`plausible.make` reads back into an equal model:
        ``"a + SCALE * b"`` (each part's own spec, :meth:`plausible.bxdf.BxDF.spec`, a scale
        written exactly, a number or ``r,g,b``, before ``" * "``; a nested sum's terms in its
        place), or the spec it was read from (``material:NAME@FIT``).  The label is not part
        of it.

        >>> import plausible
        >>> plausible.make("lambertian:rd=0.5 + 0.25 * lambertian:rd=1.0").spec()
        'lambertian:rd=0.5 + 0.25 * lambertian:rd=1.0'
        """
        if self.source_spec:
            return self.source_spec
        return " + ".join(("" if s is None else spec_value(s) + " * ") + m.spec() for m, s in self.terms())

    def __repr__(self) -> str:
        parts = ", ".join(repr(m) if s is None else f"({m!r}, {fmt(s, '.6g')})"
                          for m, s in zip(self.parts, self.scales))
        head = f"{self.label}: " if self.label else ""
        return f"Sum({head}[{parts}])"


def _scaled(fn, s):
    """``fn`` times the part's scale ``s`` (None: 1)."""
    if s is None:
        return fn
    return lambda *args: fn(*args) * s


def _claims_reciprocal(model) -> bool:
    return bool(model.reciprocal)       # BxDF.reciprocal: the registry's claim, or the model's own


provide_sum(Sum)
