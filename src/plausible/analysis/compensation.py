"""Energy compensation of any reciprocal BSDF: albedo pumping-up and Kulla-Conty, side by side.

A single-scattering BRDF ``f`` (a microfacet lobe, a Phong lobe) reflects less than all the
light it receives: its directional albedo ``E(mu) = int f cos`` falls below 1 (Mitsuba's
GGX ``roughconductor`` at ``alpha = 1`` returns 33 % at 29 degrees).  Two operators give the
energy back while keeping ``f`` reciprocal; :func:`compensate` applies either to any base:
a registered model or spec, a published material (``material:NAME@FIT``), or a foreign
BSDF through :func:`plausible.analysis.adapters.as_bxdf` (a ``mitsuba.BSDF``, a callable),
held as a :class:`ForeignBase`.

* ``"pumping-up"`` (Neumann, Neumann & Szirmay-Kalos 1999, eq. 16, 20, 21):
  ``f* = f / g``, ``g = max(E(L), E(V))`` (:class:`plausible.models.pumped_up.PumpedUp`,
  whose operator is defined for any reciprocal base; ``times`` repeats it).  It rescales
  the lobe, so its shape, its sampler and its hue stay the base's.
* ``"kulla-conty"`` (Kulla & Conty 2017): ``F f + F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))``,
  :class:`plausible.models.kulla_conty.KullaConty`.  With ``F = 1`` its albedo is 1.
* ``"incident-albedo"``: the non-reciprocal practice, ``f / E(wi)`` (a renderer that scales by
  the incident albedo only), kept as a reference (:class:`IncidentScaled`, not registered):
  its albedo is 1 by construction, and it fails the reciprocity check.

The tables ``E`` are those of :mod:`plausible.integrals.cache` (the floor below the models).
"""

from __future__ import annotations

import itertools

import numpy as np

from ..arrays import backend as _backend
from ..bxdf import BxDF, OfBase
from ..directions import split
from ..integrals.cache import albedo_table_of
from ..models.kulla_conty import FRESNEL_PARAMS, KullaConty
from ..models.pumped_up import PumpedUp
from ..params import ModelParam
from ..arrays.ops import NP
from ..vec import above

#: The operators of :func:`compensate` (the last one the non-reciprocal reference).
METHODS = ("pumping-up", "kulla-conty", "incident-albedo")
#: Serial numbers of the foreign bases that have no name outside the process.
_SERIALS = itertools.count(1)


# -- a foreign contract as a model -------------------------------------------------------------

class ForeignBase(BxDF):
    """A foreign object with the contract (a :class:`~.mitsuba_bsdf.MitsubaBSDF`, a
    :class:`~.adapters.CallableBxDF`) as a NumPy-only :class:`~plausible.bxdf.BxDF`, so the
    operators can hold it as their base.  Its hooks stack the component tuples into
    ``(n, 3)`` rows and call the adapter's ``eval``/``pdf``/``sample``; on Dr.Jit they do not run
    (the backend keeps the model, and every model built on it, on NumPy).

    ``key``: the text that identifies the object in the albedo-table cache; for a Mitsuba BSDF
    its ``str()`` (the plugin and every parameter), else None: no disk cache (a callable's
    behaviour is not named by anything that outlives the process)."""

    PARAMS = ()

    def __init__(self, adapter, key: str | None = None):
        super().__init__()
        self.adapter = adapter
        self.channels = adapter.channels
        self.key = key
        self.disk_cache = key is not None
        self._serial = next(_SERIALS)
        self.precision = getattr(adapter, "precision", 1e-9)
        self.not_applicable = dict(getattr(adapter, "not_applicable", {}) or {})
        if hasattr(adapter, "isotropic"):
            self.isotropic = bool(adapter.isotropic)
        _backend._NUMPY_ONLY.add(self)

    @property
    def name(self) -> str:
        return self.adapter.name

    def __repr__(self):
        return f"ForeignBase({self.cache_key()})"

    def cache_key(self) -> str:
        """The table-cache key: :attr:`key`, else this object's serial number in the process."""
        return f"foreign:{self.key}" if self.key is not None else f"{self.adapter!r} #{self._serial}"

    def _rows(self, ops, *ws):
        if ops is not NP:
            raise TypeError(f"{self.name}: a foreign BSDF runs on NumPy only")
        comps = np.broadcast_arrays(*(c for w in ws for c in w))
        shape = comps[0].shape
        if self.channels and shape and shape[-1] == 1:
            comps, shape = [c[..., 0] for c in comps], shape[:-1]
        rows = [np.stack(comps[3 * k:3 * k + 3], axis=-1).reshape(-1, 3) for k in range(len(ws))]
        return rows, shape

    def _f(self, ops, wi, wo, p):
        (a, b), shape = self._rows(ops, wi, wo)
        v = self.adapter.eval(a, b)
        return v.reshape(shape + v.shape[1:])

    def _pdf(self, ops, wi, wo, q):
        (a, b), shape = self._rows(ops, wi, wo)
        return self.adapter.pdf(a, b).reshape(shape)

    def _sample(self, ops, wi, u, q):
        (a, uu), shape = self._rows(ops, wi, u)
        wo = self.adapter.sample(a, np.clip(uu, 0.0, 1.0)).wo
        return split(wo.reshape(shape + (3,)))

    def peak_directions(self, wi):
        return self.adapter.peak_directions(wi)


def as_base(base):
    """``base`` as a :class:`~plausible.bxdf.BxDF` an operator can hold: a model as it is;
    a spec (``"cook-torrance:m=0.5"``, ``"material:alum-bronze@ngan2005/ward"``) built;
    a ``mitsuba.BSDF`` or a callable through :func:`~.adapters.as_bxdf`, wrapped in
    :class:`ForeignBase`."""
    from .adapters import as_bxdf

    if isinstance(base, BxDF):
        return base
    if isinstance(base, str):
        from ..registry import make_from_spec

        return make_from_spec(base)
    model = as_bxdf(base)
    if isinstance(model, BxDF):
        return model
    key = None
    if getattr(model, "bsdf", None) is not None and type(model).__name__ == "MitsubaBSDF":
        import mitsuba as mi

        key = f"mitsuba {mi.__version__} {mi.variant()} {model.mode} {model.side} {model.uv}: {model.bsdf}"
    return ForeignBase(model, key)


# -- the non-reciprocal practice, as a reference -------------------------------------------------

class IncidentScaled(OfBase):
    """``f / E(wi)``: the base scaled by its albedo at the incidence only (the common
    non-reciprocal fix; its albedo is 1 at every ``wi`` by construction).  Not registered:
    a reference for the figures and the proof that the reciprocity check catches it."""

    PARAMS = (ModelParam("base", "cook-torrance:m=0.5:fresnel=none", doc="the base"),)

    def __init__(self, progress=None, **params):
        super().__init__(**params)
        self.base = self.params["base"]
        _inherit(self, self.base)
        self.channels = self.base.channels
        self.table = albedo_table_of(self.base, progress=progress)

    @property
    def name(self) -> str:
        return "incident-albedo"


    def _f(self, ops, wi, wo, p):
        e = self.table.lookup(ops, wi)
        ok = above(ops, wi, wo) & (e > 0.0)
        return ops.where(ok, self.base._f(ops, wi, wo, self.base.p) / ops.where(ok, e, 1.0), 0.0)


# -- the face ----------------------------------------------------------------------------------

def compensate(base, method: str = "kulla-conty", *, times: int = 1, correction: str = "max",
               progress=None, **fresnel_params) -> BxDF:
    """``base`` made energy conserving by ``method`` (see the module docstring), as a model of
    the contract (``eval``/``pdf``/``sample``, batched, local frame).

    ``base``: a model, a spec string, a published material spec, a ``mitsuba.BSDF`` or a
    callable (:func:`as_base`).  ``method``: ``"kulla-conty"``, ``"pumping-up"`` (with
    ``times`` and ``correction`` of :class:`~plausible.models.pumped_up.PumpedUp`) or
    ``"incident-albedo"`` (the non-reciprocal reference).  ``fresnel_params``: ``fresnel``,
    ``rs``, ``eta``, ``k``, the Fresnel factor on the compensated lobe (Kulla-Conty also
    averages it, ``F_avg``).  ``progress``: reports the albedo tables built.

    >>> import plausible
    >>> m = plausible.compensate("cook-torrance:m=0.5:fresnel=none", "kulla-conty")
    >>> round(float(plausible.albedo(m, [0.0, 0.0, 1.0]).value), 3)
    1.0
    """
    if method not in METHODS:
        raise ValueError(f"compensate: parameter 'method' must be one of {', '.join(METHODS)}, "
                         f"got {method!r}")
    unknown = sorted(set(fresnel_params) - {p.name for p in FRESNEL_PARAMS})
    if unknown:
        raise ValueError(f"compensate: unknown parameter(s) {', '.join(unknown)}; allowed: "
                         f"base, method, times, correction, progress, fresnel, rs, eta, k")
    model = as_base(base)
    if method == "kulla-conty":
        out = KullaConty(base=model, progress=progress, **fresnel_params)
        _inherit(out, model)
        return out
    if method == "incident-albedo":
        if fresnel_params:
            raise ValueError("compensate: method 'incident-albedo' takes no Fresnel parameters")
        return IncidentScaled(base=model, progress=progress)
    out = PumpedUp(base=model, times=times, correction=correction, progress=progress, **fresnel_params)
    _inherit(out, model)
    return out


def _inherit(model, base):
    """What the checks read from a foreign base, passed on to the operator built on it: its
    precision, what it cannot do, and the NumPy-only rule of the backend."""
    if hasattr(base, "precision"):
        model.precision = base.precision
    na = getattr(base, "not_applicable", None)
    if na:
        model.not_applicable = dict(na)
    if base in _backend._NUMPY_ONLY:
        _backend._NUMPY_ONLY.add(model)
    if getattr(base, "disk_cache", True) is False:
        model.disk_cache = False
    if isinstance(getattr(base, "isotropic", None), bool):
        model.isotropic = base.isotropic   # the operators keep the base's symmetry about the normal


__all__ = ["METHODS", "ForeignBase", "IncidentScaled", "as_base", "compensate"]
