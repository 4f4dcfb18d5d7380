"""Energy compensation of any reciprocal BSDF: albedo pumping-up and Kulla-Conty, side by side.

A single-scattering BRDF ``f`` (a microfacet lobe, a Phong lobe) reflects less than all the
light it receives: its directional albedo ``E(mu) = int f cos`` falls below 1 (Mitsuba's
GGX ``roughconductor`` at ``alpha = 1`` returns 31 % at grazing).  Two operators give the
energy back while keeping ``f`` reciprocal; :func:`compensate` applies either to any base:
a registered model or spec, a published material (``material:NAME@FIT``), or a foreign
BSDF through :func:`plausible.analysis.adapters.as_bxdf` (a ``mitsuba.BSDF``, a callable).

* ``"pumping-up"`` (Neumann, Neumann & Szirmay-Kalos 1999, eq. 16, 20, 21):
  ``f* = f / g``, ``g = max(E(L), E(V))`` (:class:`plausible.models.pumped_up.PumpedUp`,
  whose operator is defined for any reciprocal base; ``times`` repeats it).  It rescales
  the lobe, so its shape, its sampler and its hue stay the base's.
* ``"kulla-conty"`` (Kulla & Conty 2017, *Revisiting Physically Based Shading at
  Imageworks*, SIGGRAPH course "Physically Based Shading in Theory and Practice";
  after Kelemen & Szirmay-Kalos 2001): :class:`KullaConty`,
  ``f_KC = F(L.H) f + F_ms f_ms`` with the multiple-scattering lobe
  ``f_ms(L, V) = (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))``,
  ``E_avg = (1/pi) int E(w) cos dw`` (``2 int E(mu) mu dmu`` when isotropic), and the
  Fresnel term of a coloured base ``F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))``,
  ``F_avg = 2 int_0^1 F(mu) mu dmu``.  With ``F = 1`` the albedo is
  ``E(L) + (1 - E(L)) = 1`` at every incidence: it adds a diffuse-like lobe.

The tables ``E`` are the albedo tables of pumped-up (:func:`plausible.analysis.albedo_table`,
1-D in ``theta`` for an isotropic base, 2-D with 32 azimuths otherwise, refined until the
Catmull-Rom interpolation error estimate is ``<= 1e-4``; cached in memory and on disk).

``"incident-albedo"`` is the non-reciprocal practice kept as a reference
(:class:`IncidentScaled`, ``f / E(wi)``, what a renderer does that scales by the
incident albedo only): its albedo is 1 by construction, and it fails the reciprocity check.

The table building is analysis (it integrates the base), so this module lives above
:mod:`plausible.models`; its models are registry entries like the others.
"""

from __future__ import annotations

import itertools
import math

import numpy as np

from .. import backend as _backend
from .. import fresnel, vec, warps
from ..bxdf import BxDF, above, split, stack
from ..ops import INV_PI, NP
from ..params import Param
from ..registry import register
from ..tables import AngleTable
from ..models.pumped_up import ModelParam, PumpedUp, albedo_table_of, horizon_albedos

#: The operators of :func:`compensate` (the last one the non-reciprocal reference).
METHODS = ("pumping-up", "kulla-conty", "incident-albedo")
#: Gauss-Legendre nodes of ``F_avg`` (:func:`fresnel_average`, computed in the hooks): the
#: conductor factor of gold is integrated to 1e-12 with them.
FAVG_NODES = 24
_FAVG_RULE = tuple(tuple(float(v) for v in a) for a in (
    0.5 * (np.polynomial.legendre.leggauss(FAVG_NODES)[0] + 1.0),
    np.polynomial.legendre.leggauss(FAVG_NODES)[1]))    # nodes in [0, 1] and weights 2 * (1/2)
#: Gauss-Legendre nodes of ``E_avg`` (per ``mu``): far beyond the table's
#: cubic pieces (91 nodes in ``theta``), so the integral of the interpolated table is
#: exact to rounding and the compensated albedo is 1 up to the table's own error.
AVG_NODES = 256
#: Azimuths of ``E_avg`` for a 2-D table (uniform, periodic: 8 per table column).
AVG_PHIS = 256
#: Smallest probability of either mixture component of :class:`KullaConty`'s sampler.
MIX_FLOOR = 0.02
#: A loss ``1 - E`` at a table node below this is the integrals' rounding (the nodes are
#: integrated to 1e-5; near the normal a smooth mirror's ``1 - E`` is 1e-14 of noise) and
#: counts as 0: interpolating noise of either sign cancels, and the lobe's last digits would
#: then depend on the order of the operations (NumPy and Dr.Jit differed by 8e-12).
LOSS_FLOOR = 1e-9
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


# -- the Fresnel factor and its average --------------------------------------------------------

FRESNEL_PARAMS = (
    Param("fresnel", "none", kind="choice", choices=fresnel.FRESNEL_CHOICES,
          doc="Fresnel factor at L.H multiplied on the single-scattering lobe"),
    Param("rs", 1.0, 0.0, 1.0, "color", "constant factor (fresnel='none') or Schlick R0"),
    Param("eta", 0.2, 0.0, 100.0, "color", "conductor index n (fresnel='conductor')"),
    Param("k", 3.0, 0.0, 100.0, "color", "conductor extinction k (fresnel='conductor')"),
)


def fresnel_average(ops, kind, rs, eta, k):
    """``F_avg = 2 int_0^1 F(mu) mu dmu`` (Kulla & Conty 2017) by Gauss-Legendre with
    :data:`FAVG_NODES` nodes, written against ``ops`` (so the Mitsuba plugin and the Dr.Jit
    backend compute it from the parameters at the shading point, differentiably), per
    channel.  Exact for Schlick (a polynomial of degree 6 in ``mu``: ``(20 R0 + 1) / 21``)."""
    total = 0.0
    for mu, w in zip(*_FAVG_RULE):
        total = total + (w * mu) * fresnel.weight(ops, kind, mu + 0.0 * rs, rs, eta, k)
    return total


def multiple_scattering_fresnel(f_avg, e_avg):
    """``F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))`` (Kulla & Conty 2017): the energy of
    the bounces after the first, ``sum_k F_avg E_avg (F_avg (1 - E_avg))^k`` for ``k >= 1``,
    per unit of the colourless multiple-scattering lobe's ``1 - E_avg``.  It is 1 for
    ``F_avg = 1`` and at most ``F_avg`` (so the compensated albedo stays ``<= 1``)."""
    return f_avg * f_avg * e_avg / (1.0 - f_avg * (1.0 - e_avg))


def table_average(table, fn=lambda v: v) -> float:
    """``(1/pi) int fn(table(w)) cos dw`` of an :class:`~plausible.tables.AngleTable` read as
    its interpolant (Gauss-Legendre in ``mu`` with :data:`AVG_NODES` nodes, :data:`AVG_PHIS`
    azimuths for a 2-D table)."""
    x, w = np.polynomial.legendre.leggauss(AVG_NODES)
    mu, wm = 0.5 * (x + 1.0), 0.5 * w
    thetas = np.arccos(mu)
    if table.isotropic:
        return float(2.0 * np.sum(wm * mu * fn(table.lookup_angles(thetas))))
    phis = np.arange(AVG_PHIS) * (2.0 * math.pi / AVG_PHIS)
    vals = fn(table.lookup_angles(thetas, phis))
    return float(2.0 * np.sum(wm * mu * vals.mean(axis=1)))


# -- Kulla-Conty --------------------------------------------------------------------------------

@register("kulla-conty",
          "Kulla-Conty energy compensation of a reciprocal base (Kulla & Conty 2017): "
          "F f + F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg)), E the base's albedo table.",
          references=("Kulla, Conty, Revisiting Physically Based Shading at Imageworks, SIGGRAPH 2017 "
                      "course Physically Based Shading in Theory and Practice",
                      "Kelemen, Szirmay-Kalos, A microfacet based coupled specular-matte BRDF model with "
                      "importance sampling, Eurographics 2001"))
class KullaConty(BxDF):
    """``f = F(L.H) f_base + F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))`` (see the module
    docstring); sampled as a mixture of the base's sampler and a cosine lobe."""

    LOBES = frozenset({"diffuse", "glossy"})
    PARAMS = (
        ModelParam("base", "cook-torrance:m=0.5:fresnel=none",
                   doc="the reciprocal single-scattering base, 'name:k=v:...' (its Fresnel factor 1)",
                   extremes=("cook-torrance:m=0.05:fresnel=none",)),
    ) + FRESNEL_PARAMS

    def __init__(self, progress=None, **params):
        """``progress``: a :mod:`plausible.progress` factory reporting the albedo table (none
        when cached); None: the ambient reporter."""
        super().__init__(**params)
        base = self.params["base"]
        self.base = base
        _inherit(self, base)
        check_finite_albedo(base, "KullaConty", progress)
        self.table = albedo_table_of(base, progress=progress)
        #: ``1 - E`` tabulated (floored at 0): subtracted once here, in NumPy, not at every lookup,
        #: where ``1 - E`` near the horizon (1.4e-4 at 88 degrees for Cook-Torrance ``m = 0.5``)
        #: would turn the last bit of ``E`` into 1e-12 of the lobe and NumPy and Dr.Jit would differ
        # (and a loss below LOSS_FLOOR, where 1 - E is the rounding of the integrals, counts as none)
        loss = 1.0 - self.table.values
        self.loss_table = AngleTable(np.where(loss > LOSS_FLOOR, loss, 0.0))
        #: ``(1/pi) int (1 - E) cos``: the energy the base loses, averaged (``1 - E_avg``).
        self.loss = table_average(self.loss_table, lambda v: np.where(v > LOSS_FLOOR, v, 0.0))
        self.e_avg = 1.0 - self.loss
        #: a coloured base's own tint (:func:`_base_tint`), multiplied on ``F_avg``
        self.tint = _base_tint(base) if base.channels else 1.0
        self.channels = _channels(self, base)
        #: ``F_avg`` and ``F_ms`` of the parameters (as the hooks compute them), per channel
        self.f_avg = np.asarray(fresnel_average(NP, self.p.fresnel, self.p.rs, self.p.eta, self.p.k)
                                * self.tint, dtype=np.float64)
        self.f_ms = multiple_scattering_fresnel(self.f_avg, self.e_avg)
        self.tint_mean = float(np.mean(self.tint))

    def _kernel_view(self, convert):
        out = super()._kernel_view(convert)
        out.base = self.base._kernel_view(convert)
        if isinstance(self.tint, np.ndarray):
            out.tint = convert(self.tint)
        return out

    def loss_at(self, ops, w):
        """``1 - E(w)`` from the loss table; 0 below :data:`LOSS_FLOOR` (a base that reflects
        all there, and the interpolant's cancellations between nodes of no loss)."""
        d = self.loss_table.lookup(ops, w)
        return ops.where(d > LOSS_FLOOR, d, 0.0)

    def _single(self, ops, wi, wo, p):
        f = self.base._f(ops, wi, wo, self.base.p)
        kh = vec.half_vector_cos(ops, wi, wo)[1]
        return fresnel.weight(ops, p.fresnel, kh, p.rs, p.eta, p.k) * f

    def _multiple(self, ops, wi, wo, p):
        """``F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))``, ``F_ms`` from the parameters."""
        if self.loss <= 1e-12:                 # a base that loses nothing: nothing to add
            return 0.0
        f_avg = fresnel_average(ops, p.fresnel, p.rs, p.eta, p.k) * self.tint
        fms = multiple_scattering_fresnel(f_avg, self.e_avg)
        return fms * (INV_PI / self.loss) * self.loss_at(ops, wi) * self.loss_at(ops, wo)

    def _f(self, ops, wi, wo, p):
        ok = above(ops, wi, wo)
        return ops.where(ok, self._single(ops, wi, wo, p) + self._multiple(ops, wi, wo, p), 0.0)

    def mix(self, ops, wi, q):
        """Probability of the cosine lobe: the multiple-scattering share of the albedo at
        ``wi``, ``F_ms (1 - E(wi)) / (F_avg E(wi) + F_ms (1 - E(wi)))`` (``F_avg`` of the
        channel means ``q``), kept in ``[MIX_FLOOR, 1 - MIX_FLOOR]`` so that each lobe covers
        its own support."""
        d = self.loss_at(ops, wi)
        f_avg = fresnel_average(ops, q.fresnel, q.rs, q.eta, q.k) * self.tint_mean
        ss = f_avg * (1.0 - d)
        ms = multiple_scattering_fresnel(f_avg, self.e_avg) * d
        t = ms / ops.maximum(ms + ss, 1e-300)
        return ops.minimum(ops.maximum(t, MIX_FLOOR), 1.0 - MIX_FLOOR)

    def _pdf(self, ops, wi, wo, q):
        t = self.mix(ops, wi, q)
        cos_pdf = ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)
        return t * cos_pdf + (1.0 - t) * self.base._pdf(ops, wi, wo, self.base.q)

    def _sample(self, ops, wi, u, q):
        t = self.mix(ops, wi, q)
        pick_cos = u[0] < t
        u0 = ops.minimum(ops.maximum((u[0] - t) / (1.0 - t), 0.0), 1.0 - 1e-16)
        b = self.base._sample(ops, wi, (u0, u[1], u[2]), self.base.q)
        c = warps.cosine_hemisphere(ops, u[1], u[2])
        return warps.mixture(ops, pick_cos, c, b)

    def lobes(self):
        return BxDF.lobes(self)

    def peak_directions(self, wi):
        return self.base.peak_directions(wi)

    def mirror_cut(self):
        return self.base.mirror_cut()


# -- the non-reciprocal practice, as a reference -------------------------------------------------

class IncidentScaled(BxDF):
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

    def _kernel_view(self, convert):
        out = super()._kernel_view(convert)
        out.base = self.base._kernel_view(convert)
        return out

    def _f(self, ops, wi, wo, p):
        e = self.table.lookup(ops, wi)
        ok = above(ops, wi, wo) & (e > 0.0)
        return ops.where(ok, self.base._f(ops, wi, wo, self.base.p) / ops.where(ok, e, 1.0), 0.0)

    def _pdf(self, ops, wi, wo, q):
        return self.base._pdf(ops, wi, wo, self.base.q)

    def _sample(self, ops, wi, u, q):
        return self.base._sample(ops, wi, u, self.base.q)

    def peak_directions(self, wi):
        return self.base.peak_directions(wi)


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
        return KullaConty(base=model, progress=progress, **fresnel_params)
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


def check_finite_albedo(base, owner: str, progress=None) -> None:
    """Raise ValueError naming ``base`` when its albedo grows without bound toward the horizon
    (the test of :func:`plausible.models.pumped_up.check_bounded_albedo`: the albedo at
    ``cos(theta) = 1e-9`` exceeds the one at ``1e-6`` by more than 0.1 % + 1e-4).  Such a base
    reflects more than it receives at grazing: there is no energy to give back, and a table
    holds no infinite value (Cook-Torrance with ``G = 1``, Ward 1992)."""
    a6, a9 = horizon_albedos(base, progress)
    if a9 > a6 * (1.0 + 1e-3) + 1e-4:
        raise ValueError(
            f"{owner}: parameter 'base': the albedo of {base.name} grows without bound toward the horizon "
            f"(a = {a6:.4g} at cos(theta) = 1e-6, {a9:.4g} at 1e-9): it is not energy conserving there, so "
            f"there is no lost energy to compensate and no finite table of it. Use a base with a bounded "
            f"albedo, e.g. 'cook-torrance' with geometry=vgroove.")


def _base_tint(base) -> np.ndarray:
    """A coloured base's own Fresnel average, relative: each channel's hemispherical albedo
    over the largest (the table holds the largest channel; Kulla & Conty's base is colourless
    and its colour is ``F``: give it so, with ``fresnel``, for their operator exactly)."""
    from .albedo import hemispherical_albedo

    h = np.atleast_1d(np.asarray(hemispherical_albedo(base).value, dtype=np.float64))
    return h / max(float(np.max(h)), 1e-300)


def _channels(model, base):
    chans = {n for n in (base.channels, model.channels) if n}
    if len(chans) > 1:
        raise ValueError(f"{type(model).__name__}: the base has {base.channels} colour channels and "
                         f"rs/eta/k have {model.channels}; give them the same count")
    return chans.pop() if chans else None


__all__ = ["METHODS", "ForeignBase", "IncidentScaled", "KullaConty", "as_base", "compensate",
           "fresnel_average", "multiple_scattering_fresnel", "table_average"]
