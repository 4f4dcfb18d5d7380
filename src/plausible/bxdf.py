"""The one contract every model implements, and its NumPy front end.

Directions are float arrays of shape ``(..., 3)`` in the local shading frame
(``z`` the normal, ``x`` the tangent ``u``, ``y`` the bitangent ``v``), both
pointing away from the surface.  ``wi`` is the direction the albedo is a
function of (``L`` or ``k1``, toward the light, in the papers); ``wo`` is the
other one (``V`` or ``k2``).  For a reciprocal model the order does not matter.

* ``eval(wi, wo)`` -- the BRDF ``f`` without the cosine factor; zero when either
  direction is below the horizon.
* ``pdf(wi, wo)`` -- the solid-angle density with which :meth:`BxDF.sample`
  produces ``wo`` given ``wi``; zero below the horizon.
* ``sample(wi, u)`` -- ``u`` of shape ``(..., 3)`` in ``[0, 1)``; ``u[..., 0]``
  picks a lobe, ``u[..., 1:]`` drive the warp.  Returns
  :class:`Sample` ``(wo, weight, pdf)`` with ``weight = eval * cos(theta_o) / pdf``;
  a sample below the horizon has ``weight = 0`` and ``pdf = 0`` (so the pdf
  integrates to one minus the fraction of such samples).

Non-unit directions are normalised (a direction is a direction, whatever its
length); zero-length or non-finite directions raise :class:`ValueError`.
Colour parameters give ``eval`` and ``weight`` a trailing channel axis.

A model implements three component-wise hooks, written against an ops
namespace (:mod:`plausible.ops`), which the NumPy front end here and the
Mitsuba 3 plugins both call: ``_f(ops, wi, wo, p)``, ``_pdf(ops, wi, wo, q)``
and ``_sample(ops, wi, u, q)``.  ``p`` holds the parameters as validated
(colours as channel arrays); ``q`` the same with every colour reduced to its
channel mean (sampling probabilities are scalars).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import ClassVar, NamedTuple

import numpy as np

from . import vec
from .ops import NP
from .params import Param

#: Largest number of direction pairs evaluated in one NumPy pass; bigger batches
#: are processed in chunks so memory stays bounded.
CHUNK = 1 << 20


class Sample(NamedTuple):
    """Result of :meth:`BxDF.sample`."""

    wo: np.ndarray
    weight: np.ndarray
    pdf: np.ndarray


def as_directions(name: str, w) -> np.ndarray:
    """Validate and normalise an array of directions of shape ``(..., 3)``."""
    try:
        a = np.asarray(w, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a float array of shape (..., 3)") from None
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name} must be finite (found NaN or inf)")
    n = np.sqrt(np.sum(a * a, axis=-1, keepdims=True))
    if np.any(n == 0):
        raise ValueError(f"{name} must be non-zero vectors (a zero vector has no direction)")
    return a / n


def split(a):
    return (a[..., 0], a[..., 1], a[..., 2])


def stack(c):
    return np.stack(np.broadcast_arrays(*c), axis=-1)


class BxDF:
    """Base class of every model: parameter handling plus the NumPy contract."""

    #: Parameter specifications (set by each model).
    PARAMS: ClassVar[tuple] = ()
    #: Registry entry (set by :func:`plausible.registry.register`).
    info: ClassVar = None

    def __init__(self, **params):
        owner = type(self).__name__
        names = [p.name for p in self.PARAMS]
        unknown = sorted(set(params) - set(names))
        if unknown:
            raise ValueError(f"{owner}: unknown parameter(s) {', '.join(unknown)}; "
                             f"allowed: {', '.join(names) or 'none'}")
        values = {}
        for p in self.PARAMS:
            values[p.name] = p.validate(params.get(p.name, p.default), owner)
        sizes = {np.size(v) for p, v in zip(self.PARAMS, values.values())
                 if p.kind == "color" and np.ndim(v) == 1}
        if len(sizes) > 1:
            raise ValueError(f"{owner}: colour parameters have different channel counts {sorted(sizes)}")
        self.channels = sizes.pop() if sizes else None
        self.params = values
        self._validate()
        self.p = SimpleNamespace(**values)
        self.q = SimpleNamespace(**{
            k: (float(np.mean(v)) if isinstance(v, np.ndarray) else v) for k, v in values.items()
        })

    # -- hooks a model implements -------------------------------------------------
    def _validate(self):
        """Model-level constraints between parameters (raise ValueError)."""

    def _f(self, ops, wi, wo, p):
        raise NotImplementedError

    def _pdf(self, ops, wi, wo, q):
        raise NotImplementedError

    def _sample(self, ops, wi, u, q):
        raise NotImplementedError

    def peak_directions(self, wi: np.ndarray) -> list:
        """Directions where the lobe may peak, for a given ``wi`` of shape (3,).

        A hint for the integrators of :mod:`plausible.analysis` (they refine
        their grids toward these); the default is the mirror direction.
        """
        return [np.array([-wi[0], -wi[1], wi[2]])]

    # -- the NumPy contract --------------------------------------------------------
    @property
    def name(self) -> str:
        return self.info.name if self.info else type(self).__name__

    def _color_axis(self, c):
        if self.channels is None:
            return c
        return tuple(x[..., None] for x in c)

    def eval(self, wi, wo) -> np.ndarray:
        """BRDF value ``f(wi, wo)`` (no cosine factor)."""
        wi = as_directions("wi", wi)
        wo = as_directions("wo", wo)
        shape = np.broadcast_shapes(wi.shape, wo.shape)[:-1]
        with np.errstate(all="ignore"):
            v = self._f(NP, self._color_axis(split(wi)), self._color_axis(split(wo)), self.p)
        out_shape = shape + ((self.channels,) if self.channels else ())
        return np.array(np.broadcast_to(v, out_shape), dtype=np.float64)

    def pdf(self, wi, wo) -> np.ndarray:
        """Solid-angle density of :meth:`sample` producing ``wo`` from ``wi``."""
        wi = as_directions("wi", wi)
        wo = as_directions("wo", wo)
        shape = np.broadcast_shapes(wi.shape, wo.shape)[:-1]
        with np.errstate(all="ignore"):
            v = self._pdf(NP, split(wi), split(wo), self.q)
        return np.array(np.broadcast_to(v, shape), dtype=np.float64)

    def sample(self, wi, u) -> Sample:
        """Importance-sample ``wo`` given ``wi`` from uniform numbers ``u`` (..., 3)."""
        wi = as_directions("wi", wi)
        try:
            u = np.asarray(u, dtype=np.float64)
        except (TypeError, ValueError):
            raise ValueError("u must be a float array of shape (..., 3)") from None
        if u.ndim == 0 or u.shape[-1] != 3:
            raise ValueError(f"u must have shape (..., 3), got {u.shape}")
        if not np.all((u >= 0) & (u <= 1)):
            raise ValueError("u must lie in [0, 1]")
        shape = np.broadcast_shapes(wi.shape, u.shape)[:-1]
        wi = np.broadcast_to(wi, shape + (3,))
        u = np.broadcast_to(u, shape + (3,))
        with np.errstate(all="ignore"):
            wo_c = self._sample(NP, split(wi), split(u), self.q)
            wo = stack(wo_c)
            wo = np.broadcast_to(wo, shape + (3,))
            n = np.sqrt(np.sum(wo * wo, axis=-1, keepdims=True))
            wo = np.where(n > 0, wo / np.where(n > 0, n, 1.0), np.array([0.0, 0.0, -1.0]))
            wo_c = split(wo)
            pdf = np.broadcast_to(self._pdf(NP, split(wi), wo_c, self.q), shape)
            f = self._f(NP, self._color_axis(split(wi)), self._color_axis(wo_c), self.p)
            # a pdf below 1e-250 is a sample that cannot occur (and cos/pdf would overflow)
            ok = (pdf > 1e-250) & (wo[..., 2] > HORIZON) & (wi[..., 2] > HORIZON)
            ratio = np.where(ok, wo[..., 2] / np.where(ok, pdf, 1.0), 0.0)
            if self.channels:
                ratio = ratio[..., None]
            out_shape = shape + ((self.channels,) if self.channels else ())
            weight = np.broadcast_to(f * ratio, out_shape)
            weight = np.where(np.broadcast_to(ok[..., None] if self.channels else ok, out_shape),
                              weight, 0.0)
        return Sample(np.array(wo), np.array(weight, dtype=np.float64),
                      np.where(ok, pdf, 0.0).astype(np.float64))

    # -- conveniences -------------------------------------------------------------
    def __repr__(self) -> str:
        args = ", ".join(f"{k}={_fmt(v)}" for k, v in self.params.items())
        return f"{type(self).__name__}({args})"


def _fmt(v):
    if isinstance(v, np.ndarray):
        return "[" + ", ".join(f"{x:g}" for x in v) + "]"
    if isinstance(v, float):
        return f"{v:g}"
    return repr(v)


#: Directions with ``cos(theta) <= HORIZON`` count as on the horizon (f = 0).
#: Models that divide by ``cos(theta)`` (original Phong/Blinn, Ward, Cook-Torrance
#: with G = 1) would otherwise overflow for denormal cosines.
HORIZON = 1e-12


def above(ops, wi, wo):
    """Both directions above the horizon (``cos(theta) > HORIZON``)."""
    return (wi[2] > HORIZON) & (wo[2] > HORIZON)


__all__ = ["BxDF", "Sample", "Param", "above", "as_directions", "vec"]
