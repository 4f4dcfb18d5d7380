"""Albedo pumping-up (Neumann, Neumann, Szirmay-Kalos 1999, sec. 3).

An operator on any reciprocal BRDF ``f`` (``neumann-neumann-szirmay-kalos-albedo-pumping-up.txt``):

* eq. 16: ``f*(L, V) = f(L, V) / g(L, V)`` with ``g`` symmetric and
  ``max(a(L), a(V)) <= g(L, V)`` (eq. 17), ``a`` the directional albedo of ``f``;
* eq. 20: ``g1(L, V) = max(a(L), a(V))`` (``correction="max"``);
* eq. 21: ``g2(L, V) = max(a(L), a(V), N.V, N.L)`` (``correction="controlled"``; the
  control term caps the total correction of repeated pumpings, see :func:`correction`);
  ``correction="controlled-product"`` is the other reading of the OCR'd text,
  ``max(a(L), a(V), (N.V)(N.L))`` at every level (docs/models/pumped-up.md says
  why the first is followed).

Then ``a(L) <= a*(L) <= 1`` (eq. 18-19): ``a*(L) = int f / g cos <= int f / a(L) cos = 1``.
The proof needs only ``g >= max(a(L), a(V))``; the upper bound ``g <= 1`` of
eq. 17 is what makes the albedo grow, so a base whose albedo exceeds 1 but stays
bounded (balanced Ward with ``rs = 1, rd = 0.3``) is made energy conserving by one
application ("even if the original BRDF is only symmetric, but is not energy
preserving, then the first pumping-up operation makes it energy preserving").
A base whose albedo diverges at the horizon (Ward 1992, Dür's Ward, Cook-Torrance
with ``G = 1``: the paper's sec. 2.1) has no finite ``g`` and is refused
(:func:`check_bounded_albedo`).

Applied ``times`` times, each level divides by the ``g`` built from the albedo of
the level below: ``f_k = f_{k-1} / g(a_{k-1})`` (for ``"controlled"``, ``f_k = f /
max(prod_j g1(a_j), N.L, N.V)``).  Each level's albedo is
integrated once with :func:`plausible.analysis.albedo_table` (the accurate
quadrature; 1-D in ``theta`` for an isotropic base, 2-D with azimuth otherwise),
interpolated with Catmull-Rom cubics (:class:`plausible.tables.AngleTable`), and
cached in memory and on disk (see :func:`table_cache_dir`).

Colour bases: ``g`` uses the largest channel of the albedo.  It still satisfies
eq. 17's lower bound for every channel (so every channel stays energy
conserving), and it keeps the base's hue.  For a grey base it is the paper's operator.

``times = 0`` is the base itself (no table), times the Fresnel factor: the unpumped
row of the paper's fig. 8, rendered through the same plugin as the pumped one.

Fresnel: the pumped lobe may be multiplied by a Fresnel factor ``F(L.H)``
(:func:`plausible.fresnel.weight`; ``L.H = V.H`` keeps it reciprocal, ``F <= 1``
keeps the albedo ``<= 1``), the way the paper renders its metals (fig. 8).
The albedo tables are built without it, so spectral rendering needs one table.

Sampling and ``pdf`` are the base model's (the paper renders with importance
sampling of the base lobes); the weight ``f* cos / pdf`` carries the correction.
This is the one model that depends on :mod:`plausible.analysis`: the operator is
defined by an integral of its base.
"""

from __future__ import annotations

import numpy as np

from .. import fresnel, vec
from ..bxdf import OfBase
from ..integrals.cache import albedo_table_of, horizon_albedos, spec_of
from ..params import ModelParam, Param
from ..registry import register
from ..vec import above

def check_bounded_albedo(model, owner: str = "PumpedUp", progress=None) -> None:
    """Raise ValueError when the albedo of ``model`` (a base) grows without bound
    toward the horizon.

    Eq. 17 needs ``g >= max(a(L), a(V))`` at every pair of directions, and eq. 18
    (``a* <= 1``) holds only where it does.  A table holds finite values: for a
    base whose albedo diverges at grazing incidence (Ward 1992 as ``1/sqrt(cos)``,
    Dür's Ward and Cook-Torrance with ``G = 1`` as ``1/cos``, paper sec. 2.1) no
    table bounds it, and the pumped albedo exceeds 1 there (10 at ``cos = 1e-7``
    and 1000 at ``1e-9`` for Cook-Torrance with ``G = 1``, ``m = 0.3``).  The test:
    the albedo at ``cos(theta) = 1e-9`` exceeds the one at ``1e-6`` (the table's
    last node) by more than 0.1 % + 1e-4 (a bounded albedo changes by
    ``O(1e-6)`` between them; the divergent ones by 3.2x and 1000x).
    """
    a6, a9 = horizon_albedos(model, progress)
    if a9 > a6 * (1.0 + 1e-3) + 1e-4:
        raise ValueError(
            f"{owner}: parameter 'base': the albedo of {spec_of(model)} grows without bound toward the "
            f"horizon (a = {a6:.4g} at cos(theta) = 1e-6, {a9:.4g} at 1e-9); pumping-up divides by "
            f"g >= max(a(L), a(V)) (eq. 17), which no finite table provides, so the result would not "
            f"conserve energy near the horizon. Use a base with a bounded albedo, e.g. "
            f"'cook-torrance' with geometry=vgroove or 'ward' with variant=balanced.")


#: The corrections: eq. 20; eq. 21 read as a four-way maximum that caps the total
#: correction; eq. 21 read as the OCR prints it, a product, at every level; eq. 21's
#: four-way maximum taken literally as a recursion, afresh at every level.
CORRECTIONS = ("max", "controlled", "controlled-product", "controlled-stepwise")


def correction(ops, kind, albedos, wi, wo):
    """The divisor ``G_k`` of ``f_k = f / G_k`` after ``k = len(albedos)`` pumpings;
    ``albedos`` holds the pairs ``(a_j(L), a_j(V))`` of the levels ``j = 0 .. k-1``
    (``a_j``: the albedo of the model pumped ``j`` times).

    * ``"max"`` (eq. 20): ``G_k = prod_j g1_j``, ``g1_j = max(a_j(L), a_j(V))``.
    * ``"controlled"`` (eq. 21, ``g2 = max(a(L), a(V), N.V, N.L)``, the OCR's
      ``max(a(L)v a(V)v (N : V)) (N ) L))`` with its commas restored):
      ``G_k = max(prod_j g1_j, N.L, N.V)``.  One pumping is eq. 21 exactly; the
      control term caps the total correction, so ``f_k cos(theta_L) <= f`` at every
      level (the output radiance never exceeds the base's, sec. 3.2 and 5) and the
      limit ``k -> oo`` is ``f / max(N.L, N.V)``: eq. 22 for the Phong base.  Each
      level's own factor ``G_k / G_(k-1)`` lies between ``max(a_(k-1)(L), a_(k-1)(V))``
      and 1, so every level satisfies eq. 17.
    * ``"controlled-product"``: eq. 21 read as printed, ``max(a(L), a(V), (N.V)(N.L))``,
      applied at every level: ``G_k = prod_j max(g1_j, (N.V)(N.L))``.
    * ``"controlled-stepwise"``: eq. 21's four-way maximum as a literal recursion,
      ``f_k = f_(k-1) / max(a_(k-1)(L), a_(k-1)(V), N.L, N.V)``, so
      ``G_k = prod_j max(g1_j, N.L, N.V)``; one pumping is ``"controlled"``.  Not the
      reading followed (docs/models/pumped-up.md): for the unit-albedo Phong it is eq. 20
      (``a >= cos``), and it lifts Blinn's albedo at 80 deg 0.2202 -> 0.5138 -> 0.7652.
    """
    total = 1.0
    for a_l, a_v in albedos:
        g = ops.maximum(a_l, a_v)
        if kind == "controlled-product":
            g = ops.maximum(g, wi[2] * wo[2])
        elif kind == "controlled-stepwise":
            g = ops.maximum(g, ops.maximum(wi[2], wo[2]))
        total = total * g
    if kind == "controlled":
        total = ops.maximum(total, ops.maximum(wi[2], wo[2]))
    return total


@register("pumped-up",
          "Albedo pumping-up of a reciprocal base (Neumann et al. 1999, eq. 16, 20, 21): "
          "f* = f / g, g = max(a(L), a(V)) [max] or max(a(L), a(V), N.L, N.V) [controlled], "
          "applied 'times' times.",
          references=("Neumann, Neumann, Szirmay-Kalos, albedo pumping-up, 1999, sec. 3, eq. 16-21",))
class PumpedUp(OfBase):
    """``f* = F(L.H) f / (g_1 g_2 ... g_times)``, each ``g_k`` built from the albedo
    of the model pumped ``k - 1`` times (see the module docstring); sampled as the base
    (:class:`~plausible.bxdf.OfBase`; the albedo tables enter every kernel as arrays already)."""

    PARAMS = (
        ModelParam("base", "reciprocal-phong:ks=1:n=20",
                   doc="the reciprocal base model, 'name:k=v:...'",
                   extremes=("reciprocal-blinn:ks=1:n=20",)),
        Param("correction", "max", kind="choice", choices=CORRECTIONS,
              doc="g1 = max(a(L), a(V)) (eq. 20), controlled g2 = max(a(L), a(V), N.V, N.L) capping the "
                  "total (eq. 21), eq. 21 as printed, max(a(L), a(V), (N.V)(N.L)) at every level, or g2 "
                  "afresh at every level (controlled-stepwise, the literal recursion)",
              extremes=("controlled",)),
        Param("times", 1, 0, 8, integer=True, doc="how many times the operator is applied (0: the base, "
              "times the Fresnel factor)",
              extremes=(3,)),
        Param("fresnel", "none", kind="choice", choices=fresnel.FRESNEL_CHOICES,
              doc="Fresnel factor at L.H multiplied on the pumped lobe"),
        Param("rs", 1.0, 0.0, 1.0, "color", "constant factor (fresnel='none') or Schlick R0"),
        Param("eta", 0.2, 0.0, 100.0, "color", "conductor index n (fresnel='conductor')"),
        Param("k", 3.0, 0.0, 100.0, "color", "conductor extinction k (fresnel='conductor')"),
    )

    def __init__(self, progress=None, **params):
        """``progress``: a :mod:`plausible.progress` factory reporting the albedo
        tables built here (none when cached); None: the ambient reporter."""
        super().__init__(**params)
        base = self.params["base"]
        self.base = base
        self.disk_cache = getattr(base, "disk_cache", True)   # a base known only in this process
        if self.params["times"] > 0:
            check_bounded_albedo(base, progress=progress)
        self.tables = []
        level = base
        for t in range(1, self.params["times"] + 1):
            self.tables.append(albedo_table_of(level, progress=progress))
            if t < self.params["times"]:
                # one controlled pumping is the same operator read either way: its table is shared
                corr = "controlled" if self.params["correction"] == "controlled-stepwise" and t == 1 \
                    else self.params["correction"]
                level = PumpedUp(base=base, correction=corr, times=t)
        # colours of the base and of the Fresnel factor share the channel axis
        chans = {c for c in (base.channels, self.channels) if c}
        if len(chans) > 1:
            raise ValueError(f"PumpedUp: the base has {base.channels} colour channels and "
                             f"rs/eta/k have {self.channels}; give them the same count")
        self.channels = chans.pop() if chans else None

    def g(self, ops, wi, wo):
        """The total correction of every level (:func:`correction`)."""
        return correction(ops, self.params["correction"],
                          [(tab.lookup(ops, wi), tab.lookup(ops, wo)) for tab in self.tables], wi, wo)

    def level_kink(self):
        return True     # g = max(a(L), a(V), ...): a(L) = a(V) where wo_z = wi_z (an albedo of theta alone)

    def _f(self, ops, wi, wo, p):
        f = self.base._f(ops, wi, wo, self.base.p)
        g = self.g(ops, wi, wo)
        ok = above(ops, wi, wo) & (g > 0.0)
        kh = vec.half_vector_cos(ops, wi, wo)[1]
        F = fresnel.weight(ops, p.fresnel, kh, p.rs, p.eta, p.k)
        return ops.where(ok, F * f / ops.where(ok, g, 1.0), 0.0)
