"""Adapters: anything a user calls a BRDF, turned into the contract of :mod:`plausible.bxdf`.

The checks (:mod:`.checks`, :mod:`.chi2`, :mod:`.albedo`) see only the contract
(``eval``, ``pdf``, ``sample``, ``peak_directions``, ``name``, ``params``,
``channels``); an adapter knows one foreign convention and turns an object into
that contract, in the spirit of the adapters of Mitsuba 3's ``mitsuba.chi2``
(``BSDFAdapter``: a plugin becomes a sample function and a pdf function).

:func:`as_bxdf` accepts

* a registered model (a :class:`~plausible.bxdf.BxDF`; returned as is),
* a model spec string, ``"lambertian"`` or ``"modified-phong:n=20"``
  (:func:`plausible.registry.make_from_spec`),
* a ``mitsuba.BSDF`` (any plugin: built in, third party, a Python ``mi.BSDF``
  subclass, loaded from a dict or XML): :class:`~.mitsuba_bsdf.MitsubaBSDF`,
* a plain Python callable ``f(wi, wo)`` or an object with an ``eval(wi, wo)``
  method, optionally with ``pdf(wi, wo)`` and ``sample(wi, u)`` (as attributes
  of the function or methods of the object, or given to :class:`CallableBxDF`):
  :class:`CallableBxDF`.

Beyond the contract an adapter may declare (all optional; the registered models
declare none of them):

* ``not_applicable``: ``{check name: reason}`` for what the object cannot do
  (no sampler: ``sampling`` and ``chi2``); :func:`plausible.check` reports those
  checks as not applicable, with the reason, instead of guessing;
* ``precision``: the relative precision of ``eval`` (default 1e-9 for the
  float64 models; float32 renderers declare more), from which
  :func:`plausible.check` derives its tolerances (:func:`tolerances`);
* ``notes``: lines for the report (what was excluded, and why);
* ``views()``: further contracts of the same object that differ from this one
  (a renderer's importance transport, the back side of a two-sided plugin),
  each checked like the first, as ``[(label, contract), ...]``;
* ``annotate(report)``: add notes that need the checks' results (e.g. delta
  lobes' reflectance added to the smooth albedo).
"""

from __future__ import annotations

import importlib
import inspect
import sys

import numpy as np

from ..bxdf import Sample
from ..text import shorten
from ..vec import HORIZON
from .foreign import ForeignBxDF

__all__ = ["CallableBxDF", "as_bxdf", "load_python", "tolerances"]

#: Relative precision of a float64 model's ``eval`` (the registered models).
FLOAT64_PRECISION = 1e-9


def tolerances(model) -> dict:
    """Tolerances of :func:`plausible.check` for ``model``, from its declared
    ``precision`` ``eps`` (relative error of one ``eval``; 1e-9 when undeclared).

    * reciprocity: ``eps`` (two evaluations that should agree, each within ``eps``
      of the truth; ``eps`` already holds the margin);
    * sampling (``weight == eval cos / pdf``, ``pdf(wi, sampled wo) == pdf``):
      ``max(1e-6, 10 eps)``: a sampler's weight and pdf take other arithmetic
      paths than ``eval`` (a simplified weight such as ``F G1`` for a visible-normal
      sampler), and the pdf is re-evaluated at the sampled direction after it was
      rounded to the object's precision.

    The energy bound (1 + 1e-4) is the integrator's accuracy and does not depend on it.
    """
    eps = float(getattr(model, "precision", FLOAT64_PRECISION))
    return dict(reciprocity=eps, sampling=max(1e-6, 10 * eps))


def as_bxdf(x):
    """``x`` as an object with the contract (see the module docstring for what is accepted).

    Raises :class:`TypeError` for an object that is neither a model, a spec, a
    Mitsuba BSDF nor a callable.
    """
    from ..bxdf import BxDF

    if isinstance(x, BxDF) or _is_contract(x):
        return x
    if isinstance(x, str):
        from ..registry import make_from_spec

        return make_from_spec(x)
    if _is_mitsuba_bsdf(x):
        from .mitsuba_bsdf import MitsubaBSDF

        return MitsubaBSDF(x)
    if _is_mitsuba_object(x):
        raise TypeError(f"model: a Mitsuba {type(x).__name__} is not a BSDF; give a mitsuba.BSDF "
                        "(e.g. mi.load_dict({'type': 'diffuse'})) or a shape's .bsdf()")
    if callable(x) or callable(getattr(x, "eval", None)):
        return CallableBxDF(x)
    raise TypeError(f"model must be a registered model, a model spec string, a mitsuba.BSDF, or a callable "
                    f"f(wi, wo) (optionally with pdf and sample); got {type(x).__name__}: {shorten(repr(x))}")


def _is_contract(x) -> bool:
    """An adapter already (or any object with the whole contract and its metadata)."""
    return all(callable(getattr(x, k, None)) for k in ("eval", "pdf", "sample", "peak_directions")) and \
        hasattr(x, "channels") and hasattr(x, "params") and hasattr(x, "name")


def _is_mitsuba_object(x) -> bool:
    return type(x).__module__.split(".")[0] == "mitsuba" or any(
        c.__module__.split(".")[0] == "mitsuba" for c in type(x).__mro__[1:])


def _is_mitsuba_bsdf(x) -> bool:
    mi = sys.modules.get("mitsuba")
    if mi is None or not _is_mitsuba_object(x):
        return False
    try:
        return isinstance(x, mi.BSDF)
    except (AttributeError, ImportError):   # no variant set: mi.BSDF does not exist yet
        return False


def load_python(target: str):
    """The object named by ``"package.module:name"`` (``name`` may be dotted).

    Raises :class:`ValueError` naming the target when the form is wrong or the
    module or name does not exist.
    """
    mod_name, sep, attr = target.partition(":")
    if not sep or not mod_name or not attr:
        raise ValueError(f"target must look like package.module:function, got {target!r}")
    try:
        obj = importlib.import_module(mod_name)
    except ImportError as e:
        raise ValueError(f"target {target}: cannot import module {mod_name!r} ({e})") from None
    for part in attr.split("."):
        try:
            obj = getattr(obj, part)
        except AttributeError:
            raise ValueError(f"target {target}: module {mod_name!r} has no attribute {attr!r}") from None
    return obj


class CallableBxDF(ForeignBxDF):
    """The contract around plain Python callables.

    ``f(wi, wo)``: the BRDF without the cosine, on NumPy arrays of shape
    ``(n, 3)`` (unit vectors in the local frame, ``z`` the normal, both pointing
    away from the surface), returning shape ``(n,)`` or ``(n, channels)``.
    ``pdf(wi, wo)``: the solid-angle density of ``wo`` given ``wi``, shape ``(n,)``.
    ``sample(wi, u)``: ``u`` of shape ``(n, 3)`` uniform in ``[0, 1)``; returns
    ``wo`` (weight and pdf then follow from ``f`` and ``pdf``), or ``(wo, pdf)``, or
    ``(wo, weight, pdf)`` with ``weight = f cos(theta_o) / pdf``.

    If ``pdf`` / ``sample`` are not given they are taken from attributes of the
    same names on ``f`` (a function with ``f.pdf = ...``) or, for an object with
    an ``eval`` method, from its methods.  The callables are asked only about
    directions above the horizon: below it ``eval`` and ``pdf`` are zero, and a
    sample below it has weight and pdf zero (the contract's conventions), so a
    formula need not clip.  What is missing is reported as not applicable:
    without ``sample`` (or without ``pdf``) the sampling checks are skipped.
    """

    def __init__(self, f, pdf=None, sample=None, *, name: str | None = None, params: dict | None = None,
                 peaks=None):
        if callable(getattr(f, "eval", None)) and not inspect.isroutine(f):
            fn = f.eval   # an object with eval (and perhaps pdf, sample) methods
        elif callable(f):
            fn = f
        else:
            raise TypeError(f"f must be a callable f(wi, wo) or an object with an eval method, "
                            f"got {type(f).__name__}")
        self._f = fn
        self._pdf = pdf if pdf is not None else getattr(f, "pdf", None)
        self._sample = sample if sample is not None else getattr(f, "sample", None)
        for what, g in (("pdf", self._pdf), ("sample", self._sample)):
            if g is not None and not callable(g):
                raise TypeError(f"{what} must be a callable, got {type(g).__name__}")
        self._peaks = peaks
        self.name = name or getattr(f, "__qualname__", None) or type(f).__name__
        self.params = dict(params or {})
        self.not_applicable = {}
        if self._sample is None or self._pdf is None:
            why = ("no sampler given" if self._sample is None else "a sampler but no pdf(wi, wo) given") + \
                ": sampling checks skipped"
            self.not_applicable = dict(sampling=why, chi2=why)
        self.notes = [] if not self.not_applicable else [self.not_applicable["sampling"]]
        probe = self._call_f(np.array([[0.0, 0.0, 1.0]]), np.array([[0.0, 0.0, 1.0]]))
        self.channels = probe.shape[1] if probe.ndim == 2 else None

    def __repr__(self):
        return f"CallableBxDF({self.name})"

    # -- calling the user's functions, with the shape checks that make errors readable --
    def _call_f(self, wi, wo):
        v = np.asarray(self._f(wi, wo), dtype=np.float64)
        if v.shape not in ((len(wi),),) and not (v.ndim == 2 and v.shape[0] == len(wi)):
            raise ValueError(f"{self.name}(wi, wo) must return shape ({len(wi)},) or ({len(wi)}, channels) "
                             f"for {len(wi)} direction pairs, got {v.shape}")
        return v

    def _call_pdf(self, wi, wo):
        v = np.asarray(self._pdf(wi, wo), dtype=np.float64)
        if v.shape != (len(wi),):
            raise ValueError(f"pdf(wi, wo) of {self.name} must return shape ({len(wi)},), got {v.shape}")
        return v

    # -- the contract ------------------------------------------------------------------
    def _value(self, a, b):
        return self._call_f(a, b)

    def _density(self, a, b):
        return self._call_pdf(a, b)

    def pdf(self, wi, wo):
        if self._pdf is None:
            raise NotImplementedError(f"{self.name}: no pdf given")
        return super().pdf(wi, wo)

    def sample(self, wi, u) -> Sample:
        if self._sample is None or self._pdf is None:
            raise NotImplementedError(f"{self.name}: {self.not_applicable['sampling']}")
        a, uu, shape = self._sample_rows(wi, u)
        out = self._sample(a, uu)
        weight = pdf = None
        if isinstance(out, tuple) and len(out) == 3:
            wo, weight, pdf = out
        elif isinstance(out, tuple) and len(out) == 2:
            wo, pdf = out
        else:
            wo = out
        wo = np.asarray(wo, dtype=np.float64)
        if wo.shape != a.shape:
            raise ValueError(f"sample(wi, u) of {self.name} must return wo of shape {a.shape}, got {wo.shape}")
        n = np.linalg.norm(wo, axis=-1)
        good = np.isfinite(n) & (n > 0)
        wo = np.where(good[:, None], wo / np.where(good, n, 1.0)[:, None], np.array([0.0, 0.0, -1.0]))
        ok = good & (wo[:, 2] > HORIZON) & (a[:, 2] > HORIZON)
        pdf = self._call_pdf(a, wo) if pdf is None else np.asarray(pdf, dtype=np.float64).reshape(len(a))
        ok &= pdf > 1e-250
        if weight is None:
            f = self._over_upper(self._call_f, a, wo, (self.channels,) if self.channels else ())
            r = np.where(ok, wo[:, 2] / np.where(ok, pdf, 1.0), 0.0)
            weight = f * (r[:, None] if self.channels else r)
        weight = np.asarray(weight, dtype=np.float64).reshape((len(a),) + ((self.channels,) if self.channels
                                                                           else ()))
        weight = np.where(ok[:, None] if self.channels else ok, weight, 0.0)
        tail = (self.channels,) if self.channels else ()
        return Sample(wo.reshape(shape + (3,)), weight.reshape(shape + tail), np.where(ok, pdf, 0.0).reshape(shape))

    def peak_directions(self, wi):
        if self._peaks is not None:
            return [np.asarray(p, dtype=np.float64) for p in self._peaks(wi)]
        return super().peak_directions(wi)
