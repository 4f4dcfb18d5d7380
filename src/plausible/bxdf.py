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

A model made of several lobes (a diffuse term and a glossy one) may also
declare them, as pbrt-v4's BxDFs declare their flags and Mitsuba's BSDFs their
components: :meth:`BxDF.lobes` returns one :class:`Lobe` per term (its kind, its
``f``, its own sampler and density, and for a diffuse lobe its directional
albedo) and :meth:`BxDF.lobe_weights` the selection weights of the model's
one-sample mixture.  :func:`mixture_f`, :func:`mixture_pdf` and
:func:`mixture_sample` compose them, over every lobe or over a chosen subset
(the Mitsuba plugins' ``BSDFContext.type_mask`` / ``component``); over every
lobe they equal the model's own ``_f``, ``_pdf`` and ``_sample``
(``tests/test_lobes.py`` checks it for every registered model).

A model implements three component-wise hooks, written against an ops
namespace (:mod:`plausible.arrays.ops`), which the NumPy front end here and the
Mitsuba 3 plugins both call: ``_f(ops, wi, wo, p)``, ``_pdf(ops, wi, wo, q)``
and ``_sample(ops, wi, u, q)``.  ``p`` holds the parameters as validated
(colours as channel arrays); ``q`` the same with every colour reduced to its
channel mean (sampling probabilities are scalars).
"""

from __future__ import annotations

import copy
from types import SimpleNamespace
from typing import Callable, ClassVar, NamedTuple

import numpy as np

from .arrays import backend as _backend
from . import directions as D
from . import kernel_params, vec
from .arrays.ops import NP
from .params import Param, spec_value
from .text import fmt
from .vec import HORIZON

class Sample(NamedTuple):
    """Result of :meth:`BxDF.sample`."""

    wo: np.ndarray
    weight: np.ndarray
    pdf: np.ndarray


class Lobe(NamedTuple):
    """One term of a model, a component of its mixture (see the module docstring).

    ``kind``: ``"diffuse"`` or ``"glossy"`` (or, for a model that declares no
    lobes, its whole ``LOBES`` set); ``f(ops, wi, wo, p)`` the term's value;
    ``pdf(ops, wi, wo, q)`` and ``sample(ops, wi, u, q)`` its own sampler (``u``
    the model's three numbers; ``u[0]`` comes rescaled to ``[0, 1)`` within the
    lobe's share, for a lobe that is itself a mixture); ``albedo(ops, wi, p)``
    the directional albedo ``int f cos`` of a diffuse lobe (None for a glossy one).
    """

    kind: object
    f: Callable
    pdf: Callable
    sample: Callable
    albedo: Callable | None = None


class Params(dict):
    """A model's validated parameters, read-only: the formulas read them once,
    when the model is built, so a changed value would show in the ``repr``, the
    spec and an exported shader while ``eval`` kept the old one.  A changed
    model is a new model: :meth:`BxDF.replace`.  (A ``dict`` subclass, so JSON,
    ``dict(m.params)`` and ``isinstance(..., dict)`` work; colour arrays are
    made read-only too.)"""

    def _refuse(self, *args, **kwargs):
        raise TypeError("model parameters are read-only; m.replace(name=value) returns a new, "
                        "validated model")

    __setitem__ = __delitem__ = update = pop = popitem = clear = setdefault = __ior__ = _refuse

    def __reduce__(self):
        return (_unpickled_params, (dict(self),))

    def copy(self) -> dict:
        """A plain (mutable) ``dict`` of the parameters."""
        return dict(self)


def _unpickled_params(values: dict) -> Params:
    """:class:`Params` of an unpickled model, its arrays read-only again (pickle
    restores arrays writable; the model's ``p`` shares these objects)."""
    for v in values.values():
        if isinstance(v, np.ndarray):
            v.flags.writeable = False
    return Params(values)


def _frozen(v):
    """``v``, a NumPy array copied and made read-only (the caller's array stays
    the caller's: changing it later does not change the model)."""
    if isinstance(v, np.ndarray):
        v = np.array(v)
        v.flags.writeable = False
    return v


class BxDF:
    """Base class of every model: parameter handling plus the NumPy contract."""

    #: Parameter specifications (set by each model).
    PARAMS: ClassVar[tuple] = ()
    #: Registry entry (set by :func:`plausible.registry.register`).
    info: ClassVar = None
    #: What the model is made of, declared as pbrt-v4's ``BxDF::Flags()``: a
    #: subset of ``{"diffuse", "glossy"}`` (reflection lobes; no model here is
    #: specular or transmissive).  The Mitsuba plugins' flags are read from it.
    LOBES: ClassVar[frozenset] = frozenset({"glossy"})
    #: Parameters whose default ``None`` the model computes from the others:
    #: ``{name: function(p)}`` of the parameter namespace, written against any
    #: backend (the Mitsuba plugins recompute it from differentiable values).
    DERIVED: ClassVar[dict] = {}
    #: Channel counts a colour parameter may have: one (grey) or three (RGB).  A
    #: spectral model widens it to its wavelength count.
    CHANNELS: ClassVar[tuple] = (1, 3)

    def __init__(self, **params):
        owner = type(self).__name__
        names = [p.name for p in self.PARAMS]
        unknown = sorted(set(params) - set(names))
        if unknown:
            raise ValueError(f"{owner}: unknown parameter(s) {', '.join(unknown)}; "
                             f"allowed: {', '.join(names) or 'none'}")
        values = {}
        for p in self.PARAMS:
            value = params.get(p.name, p.default)
            checked = p.validate(value, owner, self.CHANNELS) if p.is_color else p.validate(value, owner)
            values[p.name] = _frozen(checked)
        sizes = {np.size(v) for p, v in zip(self.PARAMS, values.values())
                 if p.is_color and np.ndim(v) == 1}
        if len(sizes) > 1:
            raise ValueError(f"{owner}: colour parameters have different channel counts {sorted(sizes)}")
        self.channels = sizes.pop() if sizes else None
        self._params = Params(values)
        self._validate()
        self.p = SimpleNamespace(**values)
        self.q = SimpleNamespace(**{
            k: (float(np.mean(v)) if isinstance(v, np.ndarray) else v) for k, v in values.items()
        })

    @property
    def params(self) -> Params:
        """The validated parameters (read-only; :meth:`replace` makes a changed model)."""
        return self._params

    def replace(self, **changes) -> "BxDF":
        """A new model of the same kind with ``changes`` applied, validated as at
        construction (the original is unchanged).  A derived parameter (e.g.
        Neumann's ``c = (n + 2) / (2 pi)``) left at its derived value is derived
        again from the new values.

        >>> import plausible
        >>> m = plausible.make("ward", alpha_x=0.2)
        >>> m.replace(alpha_x=0.3).params["alpha_x"], m.params["alpha_x"]
        (0.3, 0.2)
        """
        if not self.PARAMS:                  # a sum, a measured table: built from parts, not values
            if changes:
                raise ValueError(f"{type(self).__name__} has no parameters to replace "
                                 f"(got {', '.join(sorted(changes))})")
            return self
        values = dict(self.params)
        for k, derive in self.DERIVED.items():
            if k not in changes and k in values:
                try:
                    if np.all(np.asarray(values[k]) == np.asarray(derive(self.p))):
                        values[k] = None
                except (TypeError, ValueError):
                    pass
        values.update(changes)
        return type(self)(**values)

    @classmethod
    def check_constraints(cls, params: dict) -> None:
        """Raise ValueError where ``params`` (every parameter, each already in its
        range) break the model's constraints between parameters, without building a
        model: :meth:`_validate` run on a bare instance holding only ``params``.  The
        Mitsuba plugins check a new value of ``params.update()`` so (a model's
        construction costs 30-100 us; this, a few)."""
        bare = cls.__new__(cls)
        bare._params = params
        bare._validate()

    # -- hooks a model implements -------------------------------------------------
    def _validate(self):
        """Model-level constraints between parameters (raise ValueError).  Reads only
        ``self.params`` (:meth:`check_constraints` runs it on nothing else)."""

    def _f(self, ops, wi, wo, p):
        raise NotImplementedError

    def _pdf(self, ops, wi, wo, q):
        """The mixture of the declared :meth:`lobes` (:func:`mixture_pdf`); a model that
        declares none defines its own."""
        if type(self).lobes is BxDF.lobes:
            raise NotImplementedError
        return mixture_pdf(ops, self, wi, wo, q)

    def _sample(self, ops, wi, u, q):
        """One sample of the mixture of the declared :meth:`lobes` (:func:`mixture_sample`);
        a model that declares none defines its own."""
        if type(self).lobes is BxDF.lobes:
            raise NotImplementedError
        return mixture_sample(ops, self, wi, u, q)[0]

    def lobes(self) -> tuple:
        """The model's terms as :class:`Lobe` components, in the order of its
        mixture.  Default: one lobe, the whole model (kind: its ``LOBES``)."""
        kind = next(iter(self.LOBES)) if len(self.LOBES) == 1 else self.LOBES
        return (Lobe(kind, self._f, self._pdf, self._sample),)

    def lobe_weights(self, ops, wi, q) -> tuple:
        """Selection weights of :meth:`lobes` in the model's mixture, given ``wi``
        (need not sum to one; :func:`mixture_probabilities` normalises them)."""
        return (1.0,)

    def components(self) -> tuple:
        """:meth:`lobes`, or one lobe of the model's own ``_f``, ``_pdf`` and
        ``_sample`` where a subclass redefines one of them (or the weights) below
        the class that declared the lobes (its lobes would no longer be its terms)."""
        cls = type(self)
        owner = next(c for c in cls.__mro__ if "lobes" in vars(c))
        for hook in ("_f", "_pdf", "_sample", "lobe_weights"):
            if not issubclass(owner, next(c for c in cls.__mro__ if hook in vars(c))):
                return BxDF.lobes(self)
        return self.lobes()

    def component_weights(self, ops, wi, q) -> tuple:
        """:meth:`lobe_weights` for :meth:`components`."""
        lobes = self.components()
        return self.lobe_weights(ops, wi, q) if len(lobes) > 1 else (1.0,)

    def peak_directions(self, wi: np.ndarray) -> list:
        """Directions where the lobe may peak, for a given ``wi`` of shape (3,).

        A hint for the integrators of :mod:`plausible.analysis` (they refine
        their grids toward these); the default is the mirror direction.
        """
        return [np.array([-wi[0], -wi[1], wi[2]])]

    def mirror_cut(self) -> bool:
        """Whether the lobe is cut off along the great circle ``R.wo = 0`` (``R`` the
        mirror direction): a ``cos^n(alpha)`` lobe clamped to ``R.wo > 0``, which
        jumps there when ``n = 0``.  A hint for the albedo integrator of
        :mod:`plausible.integrals.albedo`: it makes that circle a panel edge of its
        half-vector frame (:func:`~plausible.integrals.quadrature.half_vector_lune`).
        The default: no such cut."""
        return False

    def level_kink(self) -> bool:
        """Whether ``f cos(theta_o)`` has a kink where ``wo`` is as high as ``wi``
        (``wo_z = wi_z``): a ``max(n.k1, n.k2)`` in a denominator (Ashikhmin-Shirley,
        Neumann), which turns ``f cos(theta_o)`` from ``~1`` into ``~cos(theta_o) / cos(theta_i)``
        there.  A hint for the albedo integrator of :mod:`plausible.integrals.albedo`:
        it makes that curve a panel edge of its half-vector frame
        (:func:`~plausible.integrals.quadrature.half_vector_level`); inside a panel
        the kink converges slowly and hides from the error estimate (3e-6 errors
        under a 3e-8 bound, issue 45).  The default: no such kink."""
        return False

    def kink_curves(self, wi, phi) -> list:
        """Further curves along which ``f cos(theta_o)`` has a kink, in the half-vector frame of
        :func:`plausible.integrals.quadrature.half_vector_breaks` at the incidence ``wi``: a list
        of arrays, each the half vector's polar angle ``t`` at every azimuth of ``phi`` (``inf``
        where the curve misses that azimuth, or where the lobe is negligible along it).  A hint
        for the albedo integrator, which makes each curve a panel edge (as :meth:`level_kink`'s):
        Cook-Torrance's V-groove ``min()`` (issue 45: 9.04e-7 error under an 8.60e-7 bound
        without).  The default: none."""
        return []

    def kink_azimuths(self, wi) -> list:
        """Azimuths (radians) where a curve of :meth:`kink_curves` enters or leaves the
        half-vector frame's range at the incidence ``wi`` (meets the horizon): the polar
        segments change there, and the integrator grades its azimuth panels toward them.  The
        default: none."""
        return []

    # -- parameters as kernel data (plausible.kernel_params) ------------------------
    def _kernel_view(self, convert):
        """A shallow copy whose data parameters (the floats and channel arrays of
        ``p`` and ``q``) went through ``convert``; a model holding other models or
        parameter-derived state overrides it to convert those too."""
        out = copy.copy(self)
        out.p = kernel_params.convert_namespace(self.p, convert)
        out.q = kernel_params.convert_namespace(self.q, convert)
        return out

    def _structure(self):
        """What the traced kernel depends on besides data
        (:func:`plausible.kernel_params.default_structure`)."""
        return kernel_params.default_structure(self)

    def for_changing_data(self):
        """The model to trace once and run at many values of its data parameters (a
        Mitsuba plugin under ``params.update()``): one whose traced code depends on
        those values only through ``p`` and ``q`` (:mod:`plausible.kernel_params`), so
        a new value compiles nothing.  The model itself where its structure is the
        default one; a model whose structure depends on values (He-Torrance's number
        of series terms) returns a copy whose structure does not, or None where it
        cannot.  Returns itself when it is such a model already."""
        return self if type(self)._structure is BxDF._structure else None

    @property
    def reciprocal(self) -> bool:
        """Whether the model claims ``f(wi, wo) = f(wo, wi)``: the one place to ask.
        Its registry entry's claim (``register(reciprocal=...)``); a model outside the
        registry (a variant in :mod:`plausible.models.published`, a
        :class:`~plausible.models.sum.Sum`) states its own by overriding this."""
        return bool(self.info.reciprocal) if self.info is not None else False

    # -- the NumPy contract --------------------------------------------------------
    @property
    def name(self) -> str:
        return self.info.name if self.info else type(self).__name__

    def _color_axis(self, c):
        if self.channels is None:
            return c
        return tuple(x[..., None] for x in c)

    def _out_shape(self, shape):
        return shape + ((self.channels,) if self.channels else ())

    def _fused(self, kind: str, backend, names: tuple, args: tuple):
        """The Dr.Jit front end with the checks and the normalisation inside the
        kernel (:func:`plausible.arrays.backend.eval_fused`): NumPy arrays enter
        without a NumPy pass (float32 ones without a float64 copy) and the result is
        the kernel's output.  Returns ``(result, args)``: ``result`` None where it
        does not apply (NumPy is picked, a broadcast that is neither one vector nor
        whole rows) or a kernel found a bad input; the NumPy front end then runs on
        ``args`` (each converted at most once) and raises its errors in its order."""
        raw = tuple(D.raw_rows(w) for w in args)
        if any(r is None for r in raw):
            return None, args
        try:
            if _backend.requested(backend) == "numpy":
                return None, raw
            shape = np.broadcast_shapes(*(r.shape for r in raw))[:-1]
            n = int(np.prod(shape))
            if (n * (self.channels or 1) > _backend.FUSED_MAX_LANES
                    or _backend.choose(n, self, backend, kernel=kind) != "drjit"):
                return None, raw
            inputs = tuple(self._fused_input(name, r, shape) for name, r in zip(names, raw))
        except ValueError:   # the NumPy front end raises it, after the checks that come first
            return None, raw
        fused = {"eval": _backend.eval_fused, "pdf": _backend.pdf_fused}.get(kind)
        if fused is None:
            run = lambda: _backend.sample_fused(self, *inputs, shape, HORIZON, D.unit_lanes,  # noqa: E731
                                                D.interval_lanes)
        else:
            run = lambda: fused(self, *inputs, shape, D.unit_lanes)  # noqa: E731
        out = _backend.run(self, kind, lambda: None, run)
        if out is None or out[-1]:
            return None, raw
        return (out[0] if len(out) == 2 else Sample(*out[:3])), raw

    @staticmethod
    def _fused_input(name: str, a: np.ndarray, shape: tuple) -> np.ndarray:
        """One input of :meth:`_fused`: one vector checked (and normalised) here, as
        float64 ``(3,)``; else whole rows of ``shape``, raw and C-contiguous.  Raises
        ValueError where the fused path does not apply."""
        if a.size == 3:
            a = np.asarray(a, dtype=np.float64).reshape(3)
            return D.as_unit_interval(a) if name == "u" else D.checked_unit(name, a)
        if a.shape[:-1] != shape:
            raise ValueError("a broadcast the fused front end does not read")
        return np.ascontiguousarray(a).reshape(-1, 3)

    def eval(self, wi, wo, *, backend: str | None = None) -> np.ndarray:
        """BRDF value ``f(wi, wo)`` (no cosine factor).  Batches of more than
        :data:`plausible.directions.CHUNK` pairs are evaluated ``CHUNK`` pairs at a time.  ``backend``:
        ``"auto"``, ``"numpy"`` or ``"drjit"`` (:mod:`plausible.arrays.backend`); on Dr.Jit the
        checks and the normalisation run in the kernel (:meth:`_fused`)."""
        out, (wi, wo) = self._fused("eval", backend, ("wi", "wo"), (wi, wo))
        if out is not None:
            return out
        (wi, wi_unit), (wo, wo_unit) = D.prepare("wi", wi), D.prepare("wo", wo)
        shape = D.batch_shape(wi=wi, wo=wo)
        n = int(np.prod(shape))
        be = _backend.choose(n, self, backend, kernel="eval")
        if n <= D.CHUNK:
            return self._eval_block(D.unit_fn(wi_unit)(wi), D.unit_fn(wo_unit)(wo), shape, be)
        out = np.empty((n,) + self._out_shape(())[:1])
        ni, no = D.unit_fn(wi_unit), D.unit_fn(wo_unit)
        D.chunked(shape, (wi, wo), lambda a, b, sh: self._eval_block(ni(a), no(b), sh, be), (out,))
        return out.reshape(self._out_shape(shape))

    def _eval_block(self, wi, wo, shape, backend="numpy"):
        if backend == "drjit":
            return _backend.run(self, "eval", lambda: self._eval_block(wi, wo, shape),
                                lambda: _backend.eval_block(self, wi, wo, shape))
        with np.errstate(all="ignore"):
            v = self._f(NP, self._color_axis(D.split(wi)), self._color_axis(D.split(wo)), self.p)
        return np.array(np.broadcast_to(v, self._out_shape(shape)), dtype=np.float64)

    def pdf(self, wi, wo, *, backend: str | None = None) -> np.ndarray:
        """Solid-angle density of :meth:`sample` producing ``wo`` from ``wi``
        (chunked like :meth:`eval`; ``backend`` as there)."""
        out, (wi, wo) = self._fused("pdf", backend, ("wi", "wo"), (wi, wo))
        if out is not None:
            return out
        (wi, wi_unit), (wo, wo_unit) = D.prepare("wi", wi), D.prepare("wo", wo)
        shape = D.batch_shape(wi=wi, wo=wo)
        n = int(np.prod(shape))
        be = _backend.choose(n, self, backend, kernel="pdf")
        if n <= D.CHUNK:
            return self._pdf_block(D.unit_fn(wi_unit)(wi), D.unit_fn(wo_unit)(wo), shape, be)
        out = np.empty(n)
        ni, no = D.unit_fn(wi_unit), D.unit_fn(wo_unit)
        D.chunked(shape, (wi, wo), lambda a, b, sh: self._pdf_block(ni(a), no(b), sh, be), (out,))
        return out.reshape(shape)

    def _pdf_block(self, wi, wo, shape, backend="numpy"):
        if backend == "drjit":
            return _backend.run(self, "pdf", lambda: self._pdf_block(wi, wo, shape),
                                lambda: _backend.pdf_block(self, wi, wo, shape))
        with np.errstate(all="ignore"):
            v = self._pdf(NP, D.split(wi), D.split(wo), self.q)
        return np.array(np.broadcast_to(v, shape), dtype=np.float64)

    def sample(self, wi, u, *, backend: str | None = None) -> Sample:
        """Importance-sample ``wo`` given ``wi`` from uniform numbers ``u`` (..., 3)
        (chunked like :meth:`eval`; ``backend`` as there)."""
        out, (wi, u) = self._fused("sample", backend, ("wi", "u"), (wi, u))
        if out is not None:
            return out
        wi, wi_unit = D.prepare("wi", wi)
        u = D.as_unit_interval(u)
        shape = D.batch_shape(wi=wi, u=u)
        n = int(np.prod(shape))
        be = _backend.choose(n, self, backend, kernel="sample")
        ni = D.unit_fn(wi_unit)
        if n <= D.CHUNK:
            return self._sample_block(ni(wi), u, shape, be)
        wo = np.empty((n, 3))
        weight = np.empty((n,) + self._out_shape(())[:1])
        pdf = np.empty(n)
        D.chunked(shape, (wi, u), lambda a, b, sh: tuple(self._sample_block(ni(a), b, sh, be)),
                 (wo, weight, pdf))
        return Sample(wo.reshape(shape + (3,)), weight.reshape(self._out_shape(shape)), pdf.reshape(shape))

    def _sample_block(self, wi, u, shape, backend="numpy") -> Sample:
        if backend == "drjit":
            return _backend.run(self, "sample", lambda: self._sample_block(wi, u, shape),
                                lambda: Sample(*_backend.sample_block(self, wi, u, shape, HORIZON)))
        wi = np.broadcast_to(wi, shape + (3,))
        u = np.broadcast_to(u, shape + (3,))
        with np.errstate(all="ignore"):
            wo_c = self._sample(NP, D.split(wi), D.split(u), self.q)
            wo = D.stack(wo_c)
            wo = np.broadcast_to(wo, shape + (3,))
            n = np.sqrt(D.norm2(wo))[..., None]
            wo = np.where(n > 0, wo / np.where(n > 0, n, 1.0), np.array([0.0, 0.0, -1.0]))
            wo_c = D.split(wo)
            pdf = np.broadcast_to(self._pdf(NP, D.split(wi), wo_c, self.q), shape)
            f = self._f(NP, self._color_axis(D.split(wi)), self._color_axis(wo_c), self.p)
            # a pdf below 1e-250 is a sample that cannot occur (and cos/pdf would overflow)
            ok = (pdf > 1e-250) & (wo[..., 2] > HORIZON) & (wi[..., 2] > HORIZON)
            ratio = np.where(ok, wo[..., 2] / np.where(ok, pdf, 1.0), 0.0)
            if self.channels:
                ratio = ratio[..., None]
            out_shape = self._out_shape(shape)
            weight = np.broadcast_to(f * ratio, out_shape)
            weight = np.where(np.broadcast_to(ok[..., None] if self.channels else ok, out_shape),
                              weight, 0.0)
        return Sample(np.array(wo), np.array(weight, dtype=np.float64),
                      np.where(ok, pdf, 0.0).astype(np.float64))

    # -- conveniences -------------------------------------------------------------
    def __repr__(self) -> str:
        args = ", ".join(f"{k}={fmt(v, other=repr)}" for k, v in self.params.items())
        return f"{type(self).__name__}({args})"

    def spec(self) -> str:
        """The model as a registry spec, ``"name:k=v:..."``, that
        :func:`plausible.make` reads back into an equal model: floats exactly
        (``repr``), colours as ``r,g,b``, groups of tuples as ``a,b;c,d;``, a nested
        model in square brackets (:func:`plausible.params.spec_value`).  A model
        whose own class is not registered gives its ``repr``."""
        inf = self.info
        if inf is None or inf.cls is not type(self):
            return repr(self)
        return ":".join([inf.name] + [f"{k}={spec_value(v)}" for k, v in self.params.items()])

    def _repr_html_(self) -> str:
        """The model in a notebook: its name and parameters as a table."""
        from .text import html_table

        return html_table(f"{self.name} ({type(self).__name__})", ["parameter", "value"],
                          [(k, fmt(v, other=str)) for k, v in self.params.items()])


# -- a model's lobes as a mixture -----------------------------------------------------

def mixture_probabilities(ops, weights, enabled=None) -> list:
    """``P_k = w_k / sum_{j enabled} w_j`` for the enabled lobes (0 for the others),
    each its own quotient (``1 - sum`` of the others would round a small share
    to zero); equal shares of the enabled lobes where their weights sum to 0.
    ``enabled``: a sequence of booleans (Python), None for every lobe."""
    enabled = _switched_on(enabled, len(weights))
    count = sum(enabled)
    if count == 0:
        return [0.0] * len(weights)
    total = 0.0
    for w, on in zip(weights, enabled):
        if on:
            total = total + w
    if isinstance(total, (int, float)):   # constant weights: plain numbers
        return [(w / total if total > 0 else 1.0 / count) if on else 0.0
                for w, on in zip(weights, enabled)]
    pos = total > 0
    inv = 1.0 / ops.where(pos, total, 1.0)
    return [ops.where(pos, w * inv, 1.0 / count) if on else 0.0 for w, on in zip(weights, enabled)]


def _lobes_of(model, components: bool):
    """``(lobes, weights function)``: what ``model`` declares (its own hooks use
    it), or its :meth:`BxDF.components` (what a renderer uses)."""
    if components:
        return model.components(), model.component_weights
    return model.lobes(), model.lobe_weights


def mixture_f(ops, model, wi, wo, p, enabled=None, components=False):
    """The sum of the enabled lobes' ``f`` (0 where none is enabled).  ``components``:
    over :meth:`BxDF.components` instead of :meth:`BxDF.lobes`."""
    lobes = _lobes_of(model, components)[0]
    return add_values([lobe.f(ops, wi, wo, p) for lobe, on in zip(lobes, _switched_on(enabled, len(lobes)))
                       if on])


def add_values(values):
    """The sum of model values, each a number, an array or a tuple of channel
    components (a model may return its colour as a tuple, e.g. a MERL table);
    0.0 for none."""
    if not values:
        return 0.0
    total = values[0]
    for v in values[1:]:
        if isinstance(total, tuple) or isinstance(v, tuple):
            a = total if isinstance(total, tuple) else (total,) * len(v)
            b = v if isinstance(v, tuple) else (v,) * len(a)
            total = tuple(x + y for x, y in zip(a, b))
        else:
            total = total + v
    return total


def mixture_pdf(ops, model, wi, wo, q, enabled=None, components=False):
    """``sum_k P_k pdf_k(wi, wo)`` over the enabled lobes (:func:`mixture_probabilities`)."""
    lobes, weights = _lobes_of(model, components)
    probs = mixture_probabilities(ops, weights(ops, wi, q), enabled)
    total = 0.0
    for lobe, pk, on in zip(lobes, probs, _switched_on(enabled, len(lobes))):
        if on:
            total = total + pk * lobe.pdf(ops, wi, wo, q)
    return total


def mixture_sample(ops, model, wi, u, q, enabled=None, components=False):
    """One-sample mixture over the enabled lobes: lobe ``k`` where ``u[0]`` falls
    in its share ``[c_k, c_k + P_k)`` (a later match wins, as
    :func:`plausible.warps.mixture` in the models), sampled with ``u[0]``
    rescaled to ``[0, 1)`` inside that share.  Returns ``(wo, k)`` (``k`` the
    lobe index, a float of the backend)."""
    lobes, weights = _lobes_of(model, components)
    probs = mixture_probabilities(ops, weights(ops, wi, q), enabled)
    out, index, start = None, None, 0.0
    for k, (lobe, pk, on) in enumerate(zip(lobes, probs, _switched_on(enabled, len(lobes)))):
        if not on:
            continue
        u0 = ops.minimum(ops.maximum((u[0] - start) / ops.where(pk > 0, pk, 1.0), 0.0),
                         0.9999999999999999)
        wo = lobe.sample(ops, wi, (u0, u[1], u[2]), q)
        if out is None:
            out, index = wo, 0.0 * u0 + k
        else:
            pick = (u[0] >= start) & (pk > 0)
            out = warps_mixture(ops, pick, wo, out)
            index = ops.where(pick, 0.0 * u0 + k, index)
        start = start + pk
    return out, index


def _switched_on(enabled, n: int) -> list:
    return [True] * n if enabled is None else [bool(e) for e in enabled]


def warps_mixture(ops, choose_a, a, b):
    """Component-wise select between two directions (:func:`plausible.warps.mixture`;
    imported here, not at the top: :mod:`plausible.warps` imports this module)."""
    from .warps import mixture  # import cycle: warps -> bxdf

    return mixture(ops, choose_a, a, b)


class OfBase(BxDF):
    """A model made of another one, ``self.base`` (set by the subclass's ``__init__``),
    whose reflectance it reweights and whose sampler it keeps (albedo pumping-up,
    energy compensation): the pdf, the sampler and the integrators' hints are the
    base's, and the base's kernel data travel with the model's own
    (:mod:`plausible.kernel_params`).  A subclass that samples otherwise overrides
    :meth:`_pdf` and :meth:`_sample`."""

    def _kernel_view(self, convert):
        out = super()._kernel_view(convert)
        out.base = self.base._kernel_view(convert)
        return out

    def _pdf(self, ops, wi, wo, q):
        return self.base._pdf(ops, wi, wo, self.base.q)

    def _sample(self, ops, wi, u, q):
        return self.base._sample(ops, wi, u, self.base.q)

    def peak_directions(self, wi):
        return self.base.peak_directions(wi)

    def mirror_cut(self):
        return self.base.mirror_cut()

    def level_kink(self):
        return self.base.level_kink()

    def kink_curves(self, wi, phi):
        return self.base.kink_curves(wi, phi)

    def kink_azimuths(self, wi):
        return self.base.kink_azimuths(wi)


__all__ = ["BxDF", "OfBase", "Lobe", "Params", "Sample", "Param", "above", "as_directions", "vec",
           "mixture_probabilities", "mixture_f", "mixture_pdf", "mixture_sample", "add_values"]
