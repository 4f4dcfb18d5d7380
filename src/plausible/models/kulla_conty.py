"""Kulla-Conty energy compensation of a reciprocal base (Kulla & Conty 2017).

Kulla & Conty, *Revisiting Physically Based Shading at Imageworks*, SIGGRAPH 2017 course
"Physically Based Shading in Theory and Practice" (after Kelemen & Szirmay-Kalos 2001, whose
coupled matte term has the same form).  A single-scattering lobe ``f`` (microfacet, Phong)
with directional albedo ``E(mu) < 1`` gets the energy it loses back as a second, reciprocal
lobe:

* ``f_KC(L, V) = F(L.H) f(L, V) + F_ms f_ms(L, V)``;
* ``f_ms(L, V) = (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))``,
  ``E_avg = (1/pi) int E(w) cos(theta) dw`` (``2 int_0^1 E(mu) mu dmu`` when isotropic), so that
  ``int f_ms cos dV = 1 - E(L)`` and, with ``F = 1``, the albedo is ``E(L) + 1 - E(L) = 1``;
* the Fresnel term of a coloured lobe,
  ``F_ms = F_avg^2 E_avg / (1 - F_avg (1 - E_avg))``, ``F_avg = 2 int_0^1 F(mu) mu dmu``: the
  energy of the bounces after the first, ``sum_{k>=1} F_avg E_avg (F_avg (1 - E_avg))^k``, per
  unit of the colourless ``1 - E_avg`` (:func:`multiple_scattering_fresnel`).

``E`` is the base's albedo table (:func:`plausible.integrals.cache.albedo_table_of`: 1-D in
``theta`` for an isotropic base, 2-D with 32 azimuths otherwise, refined until its Catmull-Rom
interpolation error estimate is ``<= 1e-4``; cached in memory and on disk), the same table
pumped-up divides by.  ``E_avg`` is the integral of the interpolated table itself (Gauss-Legendre,
:data:`AVG_NODES` nodes in ``mu``, :data:`AVG_PHIS` azimuths), so the compensated albedo is 1 up
to the table's own error at the incidence.

As for pumped-up, the base is the colourless lobe (Fresnel factor 1): its deficit is taken as
the energy of the missing bounces.  Colour belongs to ``fresnel``/``rs``/``eta``/``k``; a base
that is coloured itself has its table made of its largest channel and its ``F_avg`` multiplied
by each channel's hemispherical albedo over the largest (:func:`base_tint`), which keeps its
hue and every channel's albedo ``<= 1`` (``F_ms <= F_avg``).

Sampling: a mixture of the base's sampler and a cosine lobe for ``f_ms``, the cosine lobe
chosen with the multiple-scattering share of the albedo at ``wi`` (:meth:`KullaConty.mix`);
``pdf`` is the mixture's, exact.  Divergent bases (albedo unbounded at the horizon) are refused
as pumped-up refuses them.  Operators on any base, foreign BSDFs included:
:func:`plausible.compensate`.
"""

from __future__ import annotations

import math

import numpy as np

from .. import fresnel, vec, warps
from ..bxdf import BxDF, OfBase
from ..integrals.albedo import hemispherical_albedo
from ..integrals.cache import albedo_grid_of, albedo_table_of, horizon_albedos
from ..integrals.quadrature import gauss_legendre
from ..arrays.ops import INV_PI, NP
from ..params import ModelParam, Param
from ..registry import register
from ..tables import AngleTable
from ..vec import above

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
    x, w = gauss_legendre(AVG_NODES)     # computed once per process (an eigenvalue problem of size 256)
    mu, wm = 0.5 * (x + 1.0), 0.5 * w
    thetas = np.arccos(mu)
    if table.isotropic:
        return float(2.0 * np.sum(wm * mu * fn(table.lookup_angles(thetas))))
    phis = np.arange(AVG_PHIS) * (2.0 * math.pi / AVG_PHIS)
    vals = fn(table.lookup_angles(thetas, phis))
    return float(2.0 * np.sum(wm * mu * vals.mean(axis=1)))


@register("kulla-conty",
          "Kulla-Conty energy compensation of a reciprocal base (Kulla & Conty 2017): "
          "F f + F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg)), E the base's albedo table.",
          references=("Kulla, Conty, Revisiting Physically Based Shading at Imageworks, SIGGRAPH 2017 "
                      "course Physically Based Shading in Theory and Practice",
                      "Kelemen, Szirmay-Kalos, A microfacet based coupled specular-matte BRDF model with "
                      "importance sampling, Eurographics 2001"))
class KullaConty(OfBase):
    """``f = F(L.H) f_base + F_ms (1 - E(L)) (1 - E(V)) / (pi (1 - E_avg))`` (see the module
    docstring); sampled as a mixture of the base's sampler and a cosine lobe."""

    #: one glossy lobe: the multiple-scattering term is the microfacet lobe's lost energy, part
    #: of its specular response (as in Cycles' multiscatter GGX), not a Lambertian lobe; it has
    #: no albedo of a diffuse lobe's form, and the mixture's cosine lobe is a sampler, not a term
    LOBES = frozenset({"glossy"})
    PARAMS = (
        ModelParam("base", "cook-torrance:m=0.5:fresnel=none",
                   doc="the reciprocal single-scattering base, 'name:k=v:...' (its Fresnel factor 1)",
                   extremes=("cook-torrance:m=0.05:fresnel=none",),
                   needs="Kulla-Conty adds a symmetric lobe to the base, which must be symmetric itself, "
                         "f(L, V) = f(V, L), for the sum to be"),
    ) + FRESNEL_PARAMS

    def __init__(self, progress=None, **params):
        """``progress``: a :mod:`plausible.progress` factory reporting the albedo table (none
        when cached); None: the ambient reporter."""
        super().__init__(**params)
        base = self.params["base"]
        self.base = base
        check_finite_albedo(base, "KullaConty", progress)
        self.table = albedo_table_of(base, progress=progress)
        #: ``1 - E`` tabulated (floored at 0): subtracted once here, in NumPy, not at every lookup,
        #: where ``1 - E`` near the horizon (1.4e-4 at 88 degrees for Cook-Torrance ``m = 0.5``)
        #: would turn the last bit of ``E`` into 1e-12 of the lobe and NumPy and Dr.Jit would differ
        # (and a loss below LOSS_FLOOR, where 1 - E is the rounding of the integrals, counts as none)
        loss = 1.0 - self.table.values
        self.loss_table = AngleTable(horizon_safe_loss(base, np.where(loss > LOSS_FLOOR, loss, 0.0)))
        #: ``(1/pi) int (1 - E) cos``: the energy the base loses, averaged (``1 - E_avg``).
        self.loss = table_average(self.loss_table, lambda v: np.where(v > LOSS_FLOOR, v, 0.0))
        self.e_avg = 1.0 - self.loss
        #: a coloured base's own tint (:func:`base_tint`), multiplied on ``F_avg``
        self.tint = base_tint(base) if base.channels else 1.0
        self.channels = _channels(self, base)
        #: ``F_avg`` and ``F_ms`` of the parameters (as the hooks compute them), per channel
        self.f_avg = np.asarray(fresnel_average(NP, self.p.fresnel, self.p.rs, self.p.eta, self.p.k)
                                * self.tint, dtype=np.float64)
        self.f_ms = multiple_scattering_fresnel(self.f_avg, self.e_avg)
        self.tint_mean = float(np.mean(self.tint))

    def _kernel_view(self, convert):
        out = super()._kernel_view(convert)
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
        its own support.  A lobe of no albedo (``F_avg = 0``: ``fresnel='none'``, ``rs = 0``)
        has share 0 (then ``MIX_FLOOR``); the denominator is guarded by a ``where``, not by a
        tiny constant, which float32 (the Mitsuba variants) flushes to 0 (it made ``0 / 0``)."""
        d = self.loss_at(ops, wi)
        f_avg = fresnel_average(ops, q.fresnel, q.rs, q.eta, q.k) * self.tint_mean
        ss = f_avg * (1.0 - d)
        ms = multiple_scattering_fresnel(f_avg, self.e_avg) * d
        total = ms + ss
        t = ops.where(total > 0, ms / ops.where(total > 0, total, 1.0), 0.0)
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



#: Where :func:`horizon_safe_loss` compares the loss table with the base's own loss: these
#: fractions of the table's last interval away from the horizon (with the 1-degree table
#: of a smooth base, ``cos(theta)`` 8.7e-3 down to 2.7e-4).
PROBE_FRACTIONS = (0.5, 0.25, 1.0 / 16, 1.0 / 64)
#: An interpolated loss above the base's own at a probe by more than this (a tenth of the
#: energy check's 1e-4; the probes are integrated to 1e-6) lowers the horizon node.
PROBE_TOL = 1e-5


def horizon_safe_loss(base, loss) -> np.ndarray:
    """The loss table's node values ``loss`` (``1 - E`` at the :class:`AngleTable` nodes,
    shape ``(N,)`` or ``(N, M)``) with the horizon node lowered where the interpolant
    overstates the base's own loss in the last interval.

    The compensated albedo at ``L`` is ``E(L) + F_ms loss_table(L)`` (the multiple-scattering
    lobe integrates to its table's loss exactly), so it exceeds 1 by the table's overstatement
    ``loss_table(L) - (1 - E(L))``.  The last node is the albedo 1e-6 rad above the horizon;
    a base that loses energy only there (Cook-Torrance ``m = 1e-4``, V-groove: ``1 - E`` is
    5e-8 at ``cos(theta) = 1e-3``, 0.06 at 1e-4, 9.4e-4 at the node) is interpolated as a ramp
    over the last interval (8.6e-4 at ``cos = 1e-3``: an albedo of 1.00086, issue 45).  So the
    interpolant is compared with the base's albedo at :data:`PROBE_FRACTIONS` of the last
    interval, every azimuth of the table (:func:`~plausible.integrals.cache.albedo_grid_of`,
    cached); where it exceeds one by more than :data:`PROBE_TOL` the horizon node is lowered
    to the smallest loss of the probes (then to 0 if that is not enough).  The compensation
    then vanishes where the base's albedo is 1, and within the last hundredths of a degree it
    gives back less than the base loses (conserving, not exact).  Only the horizon node
    moves: a lowered inner node makes the cubic interpolant overshoot in the intervals beside
    it (Cook-Torrance ``m = 0.05``: 1.001 at ``cos = 0.02``).  A resolved table (Cook-Torrance
    ``m = 0.05`` and the default ``m = 0.5``) passes unchanged."""
    values = np.array(loss, dtype=np.float64)
    table = AngleTable(values)
    h = 0.5 * math.pi / (table.n_theta - 1)
    probes = 0.5 * math.pi - h * np.asarray(PROBE_FRACTIONS)
    phis = None if table.isotropic else table.phis()
    true = 1.0 - albedo_grid_of(base, probes, table.phis())
    true = true if phis is not None else true[:, 0]
    for floor in (np.min(true, axis=0), 0.0):
        over = AngleTable(values).lookup_angles(probes, phis) - true > PROBE_TOL
        if not over.any():
            break
        values[-1] = np.where(over.any(axis=0), np.minimum(values[-1], np.maximum(floor, 0.0)), values[-1])
    return values


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


def base_tint(base) -> np.ndarray:
    """A coloured base's own Fresnel average, relative: each channel's hemispherical albedo
    over the largest (the table holds the largest channel; Kulla & Conty's base is colourless
    and its colour is ``F``: give it so, with ``fresnel``, for their operator exactly)."""
    h = np.atleast_1d(np.asarray(hemispherical_albedo(base).value, dtype=np.float64))
    return h / max(float(np.max(h)), 1e-300)


def _channels(model, base):
    chans = {n for n in (base.channels, model.channels) if n}
    if len(chans) > 1:
        raise ValueError(f"{type(model).__name__}: the base has {base.channels} colour channels and "
                         f"rs/eta/k have {model.channels}; give them the same count")
    return chans.pop() if chans else None
