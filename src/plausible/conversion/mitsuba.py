"""Mitsuba 3's own BSDFs fitted to a source model, evaluated through Mitsuba.

A *family* is a Mitsuba plugin with its non-colour parameters on a few axes
(``roughconductor``'s ``alpha``; ``principled``'s ``roughness`` and
``metallic``) and its colour parameters *slots*.  At a fixed point of the axes
every family here is affine in its colours, channel by channel:

    f(wi, wo) = B_0 + sum_j x_j B_j,

with ``B_0`` Mitsuba's value with every slot 0 (zero unless the family has an
``offset``: ``principled``'s dielectric coat) and ``B_j`` the value with slot
``j`` white minus ``B_0`` (``roughconductor`` with ``material = "none"``:
``specular_reflectance`` times the microfacet lobe; ``roughplastic`` with
``nonlinear = false``: the diffuse term is ``diffuse_reflectance / (1 - fdr)``
times factors free of it, the coat ``specular_reflectance`` times its lobe;
``principled``: ``base_color`` enters the diffuse term and the metallic Schlick
Fresnel linearly; ``blendbsdf``: ``(1 - weight)`` times a ``diffuse`` plus ``weight``
times a ``roughconductor``, each linear in its colour (``blendbsdf-tir`` likewise, of a
``roughplastic`` with ``nonlinear = false`` and a ``roughconductor``: :func:`blend`); ``gltf-pbr``: see
:data:`PLAUSIBLE_TYPES`; ``tests/conversion/test_convert_mitsuba.py`` checks this affinity
on Mitsuba at random colours, and that it fails for ``nonlinear = true``).
So the fit needs Mitsuba only per axis point: the bases are Mitsuba's values
(:class:`~plausible.analysis.mitsuba_bsdf.MitsubaBSDF`, one launch over the
target's pairs and the albedo nodes together) and the colours are solved in
NumPy.  The steps (:func:`fit_family`):

1. **Probe**: the fitting pairs of :func:`plausible.fitting.metrics.sample_pairs`
   about the source's peaks and the mirror direction, and per incidence of
   :data:`plausible.fitting.metrics.THETAS_DEG` the half-vector rule of
   :func:`plausible.integrals.quadrature.half_vector_rule` (:data:`ALBEDO_RULE`)
   for the albedo of the target (every family's lobes are about the mirror).  The source's ``f cos`` on the pairs and its
   albedo (accurate integrator) are the target.
2. **Scan** every point of the family's grid: bases (cached per probe, so the
   published fits, which share their pairs, share them), colours per channel by
   bounded linear least squares on relative residuals ``(c - g)/(g + eps)`` and
   ``(a - A)/A`` (the albedo rows weighted so that both sets count alike: a
   linearisation of the perceptual metric), scored by the true figure of the
   chosen metric (:func:`plausible.fitting.metrics.errors`).
3. **Refine** the axes from the best grid point by the fitter's optimiser
   (:func:`plausible.fitting.fit.optimise`): line searches of the true figure along each
   axis between the grid's neighbours (:data:`AXIS_POLISH`), then least squares with a
   difference Jacobian on the colours' residuals at each point's best colours
   (:class:`AxesObjective`: a variable projection), the best point by the true figure kept.
4. **Polish** the colours of each channel on the true metric (L-BFGS-B on the
   smooth bound at beta = 20, 200, 2000, then Nelder-Mead), kept if better; a grey
   source's once, one colour for every channel (:func:`_polish`).
5. **Measure** the result as loaded from its dict: every metric through Mitsuba
   again, and the albedo at 0, 45 and 75 degrees by Mitsuba's own sampler
   (:func:`sampler_albedo`).

With ``hard=True`` the albedo band is a constraint of steps 2-4 (:data:`BAND_HARD`):
:func:`plausible.conversion.convert` refits so where the best candidate misses it.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..fitting import metrics as M

__all__ = ["Axis", "FAMILIES", "Family", "FamilyFit", "GLTF_DIELECTRIC", "Probe", "candidates", "fit_family",
           "gltf_dielectric", "gltf_fixed_metallic", "lobe_tint", "measure", "probe_for", "sampler_albedo", "source_target"]

#: Incidences (degrees) of the albedo comparison in every report.
REPORT_THETAS = (0.0, 45.0, 75.0)
#: Incidences (degrees) of the fitting pairs and albedo terms: the fitting package's and 75.
PROBE_THETAS = tuple(sorted(set(M.THETAS_DEG) | set(REPORT_THETAS)))
#: Incidences (degrees) at which a source's albedo is probed for energy conservation: the
#: fit's (:data:`PROBE_THETAS`, 0-80) and 85 (the fit reuses these albedos; :func:`candidates` reads them).
CONSERVE_THETAS = tuple(sorted(set(PROBE_THETAS) | {85.0}))
#: The rule of the albedo inside the fit, ``(m, levels, pole_levels)`` of
#: :func:`plausible.integrals.quadrature.half_vector_rule`: every family here is a
#: diffuse term and lobes about the mirror direction, which the half-vector frame
#: resolves at any width (Mitsuba's GGX alpha 0.003-1 and ``principled`` within 4e-5
#: of the adaptive integrator at 0-80 degrees, about 4,500 nodes an incidence).  The
#: spherical-angle grid used before (``hemisphere_grid``, ``m = 4``, 6 levels) put a
#: sharp lobe at grazing incidence between its nodes: ``principled`` at roughness 0.09
#: had 0.436 at 75 degrees on it against 0.524 by Mitsuba's sampler, and the fit kept a
#: conversion 0.108 off there (``alumina-oxide@low2012/microfacet-e2``).
ALBEDO_RULE = (3, 4, 10)


@dataclass(frozen=True)
class Axis:
    """A non-colour parameter: its grid ``values``, scanned then refined within ``[lo, hi]``."""

    name: str
    values: tuple
    lo: float
    hi: float
    log: bool = True

    def fwd(self, v):
        return math.log(v) if self.log else v

    def inv(self, x):
        return min(max(math.exp(x) if self.log else x, self.lo), self.hi)


@dataclass(frozen=True)
class Family:
    """A Mitsuba plugin as fitted here (module docstring): ``fixed`` entries,
    ``axes``, colour ``slots`` (each in [0, 1]) and whether ``f`` has a part
    independent of the slots (``offset``)."""

    type: str
    fixed: tuple
    axes: tuple
    slots: tuple
    offset: bool = False
    #: A blend of two families (``blendbsdf`` made by :func:`blend`): ``((prefix, Family), (prefix, Family))``,
    #: whose bases are the parts' bases weighted by ``1 - weight`` and ``weight`` (:func:`_basis_now`).
    parts: tuple = ()
    #: ``(axis name, (r, g, b))``: that axis's value times this colour is the entry (a lobe's tint on a grey
    #: level, :func:`gltf_dielectric`); the channels' bases then differ and are kept apart (:func:`_basis_now`).
    tint: tuple = ()
    #: Axes in which the plugin's values are affine (``principled``'s ``metallic``: its diffuse weight
    #: ``1 - metallic`` and its Fresnel a mix of the dielectric's and the metal's by ``metallic``): a point's
    #: bases are those at the axis's two bounds, mixed (:func:`_basis_now`), so the axis costs no evaluation.
    #: tests/conversion/test_convert_mitsuba.py holds Mitsuba to it (2e-7 of the largest value, float32).
    linear: tuple = ()

    def bsdf_dict(self, point: dict, colours: dict) -> dict:
        """The ``mi.load_dict`` description at axis values ``point`` and slot colours
        (a float, grey, or an RGB triple); a dotted name ``bsdf_1.alpha`` is an entry
        of a nested dict."""
        d = {"type": self.type}
        for k, v in self.fixed:
            set_entry(d, k, v)
        for k, v in point.items():
            set_entry(d, k, float(v))
        if self.tint:
            name, rgb = self.tint
            set_entry(d, name, [float(point[name]) * c for c in rgb])
        for k, v in colours.items():
            a = np.broadcast_to(np.asarray(v, float), (3,))
            set_entry(d, k, {"type": "rgb", "value": [float(x) for x in a]})
        return d


def set_entry(d: dict, dotted: str, value):
    """``d[a][b] = value`` for ``dotted = "a.b"`` (nested dicts made as needed)."""
    *path, last = dotted.split(".")
    for k in path:
        d = d.setdefault(k, {})
    d[last] = value


def get_entry(d: dict, dotted: str):
    for k in dotted.split("."):
        d = d[k]
    return d


#: Families that are registered plausible models (the glTF 2.0 BRDF of
#: :mod:`plausible.models.gltf_pbr`, written from the Khronos specification), evaluated
#: through plausible; the others are Mitsuba plugins.  ``gltf-pbr`` is affine in
#: ``base_color`` at fixed ``metallic`` and ``roughness`` (``dielectric_brdf = F_d
#: specular + (1 - max F_d) base / pi``, ``metal_brdf = specular (base + (1 - base) fw)``).
PLAUSIBLE_TYPES = ("gltf-pbr",)
ALPHA = Axis("alpha", tuple(float(x) for x in np.geomspace(0.004, 1.0, 14)), 0.002, 1.0)
ROUGHCONDUCTOR = Family("roughconductor", (("distribution", "ggx"), ("material", "none")), (ALPHA,),
                        ("specular_reflectance",))
#: Families chosen (:func:`plausible.conversion.convert`) over the best of the others only where that
#: one misses the band (:data:`BAND_HARD`) or has the higher figure of the metric itself: ``blendbsdf-tir``
#: moves part of a sharp lobe's energy into a diffuse term, which the figure minimised (the albedo twice,
#: the band's cost) may prefer to a lobe closer to the source's.
BAND_FAMILIES = ("blendbsdf-tir",)
#: Weights of a blend's grid (refined within [0.02, 0.98]).
WEIGHT = Axis("weight", (0.2, 0.5, 0.8), 0.02, 0.98, log=False)


def blend(part0: Family, part1: Family, weight: Axis = WEIGHT) -> Family:
    """``blendbsdf`` of ``part0`` (``bsdf_0``, weight ``1 - w``) and ``part1`` (``bsdf_1``, weight ``w``):
    the parts' entries, axes and slots under their prefixes, and the ``weight`` axis.  Its bases are
    the parts' own (:func:`_basis_now`; Mitsuba's ``blendbsdf`` evaluates ``(1 - w) f_0 + w f_1``),
    so a grid over both parts costs one Mitsuba point per point of each part.  Axes: ``bsdf_1``'s, the
    weight, then ``bsdf_0``'s (the refinement goes axis by axis, the lobe first)."""
    fixed, axes, slots = [], [], []
    for prefix, f in (("bsdf_0", part0), ("bsdf_1", part1)):
        fixed += [(f"{prefix}.type", f.type)] + [(f"{prefix}.{k}", v) for k, v in f.fixed]
        axes += [Axis(f"{prefix}.{a.name}", a.values, a.lo, a.hi, a.log) for a in f.axes]
        slots += [f"{prefix}.{s}" for s in f.slots]
    return Family("blendbsdf", tuple(fixed), tuple(axes[len(part0.axes):] + [weight] + axes[:len(part0.axes)]),
                  tuple(slots), part0.offset or part1.offset, (("bsdf_0", part0), ("bsdf_1", part1)))


#: A diffuse base under a smooth-to-rough coat whose index (``int_ior = 1``) is below the outside's
#: (``ext_ior`` > 1), with ``specular_reflectance = 0``: Mitsuba's ``roughplastic`` weights its diffuse
#: term by the coat's transmittance at both directions, which vanishes beyond the critical angle
#: ``asin(1 / ext_ior)`` (total internal reflection, whose reflected light the zero specular colour
#: discards), so the diffuse albedo falls with incidence, smoothly for a rough coat (measured by
#: Mitsuba's sampler, white base: ``ext_ior`` 1.2, ``alpha`` 0.3: 0.909, 0.740, 0.404, 0.131 at
#: 0, 45, 60, 75 degrees; 1.5, 0.3: 0.815, 0.340, 0.124, 0.051 -- about ``cos^2``).  The one Mitsuba
#: mechanism found whose albedo falls by more than a fifth from 0 to 75 degrees (docs/convert.md).
TIR_COAT = Family("roughplastic", (("distribution", "ggx"), ("nonlinear", False), ("int_ior", 1.0),
                                   ("specular_reflectance", 0.0)),
                  (Axis("ext_ior", (1.15, 1.4, 1.8), 1.02, 3.0), Axis("alpha", (0.15, 0.45), 0.02, 1.0)),
                  ("diffuse_reflectance",))
FAMILIES = {
    "diffuse": Family("diffuse", (), (), ("reflectance",)),
    "roughconductor": ROUGHCONDUCTOR,
    "roughplastic": Family("roughplastic", (("distribution", "ggx"), ("nonlinear", False)), (ALPHA,),
                           ("diffuse_reflectance", "specular_reflectance")),
    "blendbsdf": Family("blendbsdf", (("bsdf_0.type", "diffuse"), ("bsdf_1.type", "roughconductor"),
                                      ("bsdf_1.distribution", "ggx"), ("bsdf_1.material", "none")),
                        (Axis("bsdf_1.alpha", ALPHA.values, ALPHA.lo, ALPHA.hi),
                         Axis("weight", (0.2, 0.5, 0.8), 0.02, 0.98, log=False)),
                        ("bsdf_0.reflectance", "bsdf_1.specular_reflectance")),
    #: a sharp lobe beside a diffuse term that fades with incidence (:data:`TIR_COAT`): for sources whose
    #: albedo falls (:data:`FALL`), which no family above follows
    "blendbsdf-tir": blend(TIR_COAT, ROUGHCONDUCTOR),
    "gltf-pbr": Family("gltf-pbr", (),
                       (Axis("roughness", tuple(float(x) for x in np.geomspace(0.06, 1.0, 8)), 0.045, 1.0),
                        Axis("metallic", (0.0, 0.25, 0.5, 0.75, 1.0), 0.0, 1.0, log=False)),
                       ("base_color",), offset=True),
    "principled": Family("principled", (),
                         (Axis("roughness", tuple(float(x) for x in np.geomspace(0.06, 1.0, 8)), 0.045, 1.0),
                          Axis("metallic", (0.0, 0.25, 0.5, 0.75, 1.0), 0.0, 1.0, log=False)),
                         ("base_color",), offset=True, linear=("metallic",)),
}


# -- where the candidates are evaluated -------------------------------------------------------

class Probe:
    """The target's pairs and the albedo nodes, each incidence of ``thetas_deg``
    one half-vector rule (:data:`ALBEDO_RULE`) about its mirror direction (step 1)."""

    def __init__(self, peaks_of, thetas_deg=PROBE_THETAS):
        from ..analysis import direction
        from ..integrals.quadrature import half_vector_rule

        self.peaks = lambda wi: _distinct([p for fn in peaks_of for p in fn(wi)])
        self.wi, self.wo = M.sample_pairs(self.peaks, thetas_deg=thetas_deg)
        self.thetas = np.radians(np.asarray(thetas_deg, float))
        WI, WO, self.weights = [self.wi], [self.wo], []
        for t in self.thetas:
            wi = direction(float(t))
            wo, w = half_vector_rule(wi, m=ALBEDO_RULE[0], levels=ALBEDO_RULE[1], pole_levels=ALBEDO_RULE[2])
            WI.append(np.broadcast_to(wi, wo.shape))
            WO.append(wo)
            self.weights.append(w * wo[:, 2])
        #: the highlight as compare_looks renders it, predicted (:class:`plausible.mitsuba.looks.LampStrip`)
        self.strip = _strip()
        WI.append(self.strip.wi)
        WO.append(self.strip.wo)
        self.all_wi, self.all_wo = np.concatenate(WI), np.concatenate(WO)
        self.key = hash((self.all_wi.tobytes(), self.all_wo.tobytes()))

    def measure(self, bxdf):
        """``(f cos on the pairs (N, C), albedo per incidence (T, C))`` of a contract object
        (one ``eval`` over pairs and nodes); a grey value comes back with one channel."""
        return self.measure_all(bxdf)[:2]

    def measure_all(self, bxdf):
        """:meth:`measure` and ``f`` at the strip's pairs (S, C) (one ``eval`` over all of them)."""
        return self.reduce(bxdf.eval(self.all_wi, self.all_wo))

    def reduce(self, f):
        """:meth:`measure_all` of the values ``f`` (N, C) at :attr:`all_wi`, :attr:`all_wo`."""
        f = np.asarray(f, float)
        f = f.reshape(len(f), -1)
        n = len(self.wi)
        fcos = f[:n] * self.wo[:, 2:3]
        alb, s = [], n
        for w in self.weights:
            alb.append(w @ f[s:s + len(w)])
            s += len(w)
        return fcos, np.array(alb), f[s:]


@lru_cache(maxsize=1)
def _strip():
    from ..mitsuba.looks import LampStrip

    return LampStrip.make()


def _distinct(peaks):
    out = []
    for p in peaks:
        p = np.asarray(p, float) / np.linalg.norm(p)
        if not any(np.allclose(p, q, atol=1e-12) for q in out):
            out.append(p)
    return out


def _load(d):
    """The contract of a family's description: a Mitsuba plugin through the adapter, or
    (:data:`PLAUSIBLE_TYPES`) a registered model built from the same entries."""
    if d["type"] in PLAUSIBLE_TYPES:
        from .. import registry

        return registry.make(d["type"], **model_params(d))
    from ..analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    return MitsubaBSDF(load_bsdf_dict(d))


def model_params(d: dict) -> dict:
    """A family description of a registered model as its parameters (RGB dicts -> lists)."""
    return {k: (v["value"] if isinstance(v, dict) else v) for k, v in d.items() if k != "type"}


#: Bases kept (:func:`basis`): 60-230 kB each (a tinted family's three channels on the ~4,800 pairs), so at
#: most about 250 MB; a conversion visits 300-500 points (a Mitsuba conversion's four families), and a
#: table of many materials went 4096 entries (about 1 GB) before.
BASES_KEPT = 1024


@lru_cache(maxsize=BASES_KEPT)
def _basis_cached(probe_key, family: Family, point: tuple):
    return _basis_now(_PROBES[probe_key], family, dict(point))


#: The probes of the cached bases, by key, the most recently used last; at most :data:`PROBES_KEPT` (each
#: holds ~100k pairs, 5 MB; published fits share a few, a table of other sources may bring one each).
_PROBES: OrderedDict = OrderedDict()
PROBES_KEPT = 16


def _keep_probe(probe):
    """Put ``probe`` in :data:`_PROBES` (the cached functions name it by key), forgetting the least
    recently used beyond :data:`PROBES_KEPT`."""
    _PROBES[probe.key] = probe
    _PROBES.move_to_end(probe.key)
    while len(_PROBES) > PROBES_KEPT:
        _PROBES.popitem(last=False)


def _basis_now(probe: Probe, family: Family, point: dict):
    """``(F, Alb, H)``: rows ``B_0`` (zero without an offset) and ``B_j``, channel 0 of
    Mitsuba's value at white / zero slots (RGB variants treat channels alike), on the pairs
    (``f cos``), as albedos, and as the highlight strip's images (``H``: (1 + J, views, rows, res),
    :attr:`Probe.strip`)."""
    if family.parts:
        w = float(point["weight"])
        parts = []
        for (prefix, part), scale in zip(family.parts, (1.0 - w, w)):
            sub = {k[len(prefix) + 1:]: v for k, v in point.items() if k.startswith(prefix + ".")}
            parts.append([scale * B for B in basis(probe, part, sub)])
        return tuple(np.concatenate([[a[0] + b[0]], a[1:], b[1:]]) for a, b in zip(*parts))
    for a in family.axes:       # an affine axis between its bounds: the bases at the two bounds, mixed
        if a.name in family.linear and a.name in point and a.lo < float(point[a.name]) < a.hi:
            w = (float(point[a.name]) - a.lo) / (a.hi - a.lo)
            lo, hi = (basis(probe, family, {**point, a.name: v}) for v in (a.lo, a.hi))
            return tuple((1.0 - w) * x + w * y for x, y in zip(lo, hi))
    if family.type == "gltf-pbr" and {k for k, _ in family.fixed} | set(point) <= GLTF_COMBINED:
        return _gltf_basis(probe, family, point)
    ch = slice(None) if family.tint else 0           # a tinted family's channels differ: all three kept
    zero = {s: 0.0 for s in family.slots}
    raw = [probe.measure_all(_load(family.bsdf_dict(point, zero)))] if family.offset else []
    raw += [tuple(v - v0 for v, v0 in zip(probe.measure_all(_load(family.bsdf_dict(point, {**zero, s: 1.0}))),
                                           raw[0] if raw else (0.0, 0.0, 0.0))) for s in family.slots]
    if not family.offset:
        raw = [(0.0, 0.0, 0.0)] + raw
    c = (3,) if family.tint else ()
    Fs, As, Hs = ([np.zeros((n,) + c) + (B[:, ch] if np.ndim(B) else B)]
                  for n, B in zip((len(probe.wi), len(probe.thetas), len(probe.strip.wi)), raw[0]))
    for F, A, H in raw[1:]:
        Fs.append(np.broadcast_to(F[:, ch], Fs[0].shape))
        As.append(np.broadcast_to(A[:, ch], As[0].shape))
        Hs.append(np.broadcast_to(H[:, ch], Hs[0].shape))
    # the strip's values as its images (linear in f): a blend's, a candidate's images are sums of these
    Hs = np.array(Hs)                                                  # (1 + J, S[, C])
    flat = np.moveaxis(Hs, 0, -1).reshape(len(Hs[0]), -1)              # (S, [C x] (1 + J))
    img = np.stack(probe.strip.images(flat))                          # (views, rows, res, [C x] (1 + J))
    if family.tint:                                                   # -> (1 + J, C, views, rows, res)
        img = np.moveaxis(img.reshape(img.shape[:3] + Hs.shape[2:] + Hs.shape[:1]), (-1, -2), (0, 1))
        return np.array(Fs), np.array(As), img
    return np.array(Fs), np.array(As), np.moveaxis(img, -1, 0)


def basis(probe: Probe, family: Family, point: dict):
    """The bases of ``family`` at ``point`` on ``probe`` (cached)."""
    _keep_probe(probe)
    return _basis_cached(probe.key, family, tuple(sorted(point.items())))


def _gltf_eval(probe, roughness, **kw):
    """The registered ``gltf-pbr``'s values (N, 3) on the probe's pairs."""
    from .. import registry

    f = np.asarray(registry.make("gltf-pbr", roughness=roughness, **kw).eval(probe.all_wi, probe.all_wo), float)
    return np.broadcast_to(f.reshape(len(f), -1), (len(f), 3))


#: The glTF parameters :func:`_gltf_combine` combines; a family fixing or searching any other (``viewer``,
#: anisotropy) is evaluated point by point.
GLTF_COMBINED = frozenset({"roughness", "metallic", "specular", "specular_color"})
#: Roughnesses whose glTF parts are kept (:func:`_gltf_parts`, reduced: about 77 kB a roughness, 5 MB in all);
#: a conversion's three glTF families visit about 50.
GLTF_PARTS_CACHE = 64


@lru_cache(maxsize=GLTF_PARTS_CACHE)
def _gltf_parts(probe_key, roughness: float):
    """The parts ``S, SW, P, WP`` of ``gltf-pbr`` at ``roughness`` on the probe, each reduced as a basis is
    (:meth:`Probe.reduce`, the strip as its images): ``(fcos (N,), albedo (T,), images (views, rows, res))``
    per part.  ``S = Vis D`` and ``SW = Vis D w`` are one evaluation of the registered model read channel by
    channel (metallic 1, base colour (1, 0, 0): channels 0 and 1; ``w`` the Fresnel weight ``(1 - V.H)^5``);
    ``P = 1/pi`` above the horizon and ``WP = w P`` are the same at every roughness
    (:func:`_gltf_diffuse_parts`).  Every glTF material of that roughness is a combination of these
    (:func:`_gltf_combine`), and reduction is linear: one evaluation per roughness, and a point of the
    metallic and KHR_materials_specular axes combines arrays of the reduced size (a 20th of the pairs')."""
    probe = _PROBES[probe_key]
    f = _gltf_eval(probe, roughness, metallic=1.0, base_color=[1.0, 0.0, 0.0])
    return tuple(_reduced(probe, x) for x in (f[:, 0], f[:, 1])) + _gltf_diffuse_parts(probe_key)


@lru_cache(maxsize=16)
def _gltf_diffuse_parts(probe_key):
    """``(P, WP)`` of :func:`_gltf_parts`: metallic 0, base colour 1, ``specular`` 0 (the diffuse term
    alone, ``1/pi``) and ``specular`` 1 with ``specular_color`` 0 (``f0 = 0``, ``f90 = 1``: ``SW + P - WP``)."""
    probe = _PROBES[probe_key]
    P = _gltf_eval(probe, 0.5, metallic=0.0, specular=0.0, base_color=1.0)[:, 0]
    SW = _gltf_eval(probe, 0.5, metallic=1.0, base_color=0.0)[:, 0]
    return _reduced(probe, P), _reduced(probe, SW + P - _gltf_eval(probe, 0.5, metallic=0.0, specular=1.0,
                                                                     specular_color=0.0, base_color=1.0)[:, 0])


def _reduced(probe, f):
    """``(fcos (N,), albedo (T,), images (views, rows, res))`` of one channel's values ``f`` on the probe's
    pairs (:meth:`Probe.reduce`; the strip as :meth:`LampStrip.images`)."""
    fcos, alb, h = probe.reduce(f)
    return fcos[:, 0], alb[:, 0], np.stack(probe.strip.images(h))[..., 0]


def _gltf_combine(parts, family, point):
    """``gltf-pbr``'s values at base colour 0, ``B0`` (per channel, ``(..., 3)``), and their change from
    base colour 0 to 1, ``B1`` (``(...)``), at ``point``, exactly, from the parts ``S, SW, P, WP`` (any one
    shape: the values on pairs, or reduced, :func:`_gltf_parts`): with ``m`` metallic, ``s`` specular,
    ``f0 = min(0.04 specular_color, 1) s`` per channel and ``f0m`` the same of the largest channel (the
    specification's ``max_value``),

        f = (1 - m) (f0 S + (s - f0) SW) + m SW + base (m (S - SW) + (1 - m) ((1 - f0m) P - (s - f0m) WP))

    (:mod:`plausible.models.gltf_pbr`: ``dielectric_brdf`` and ``metal_brdf`` mixed by ``m``;
    tests/conversion/test_convert_mitsuba.py holds it to the model's own evaluation)."""
    p = {**dict(family.fixed), **point}
    sc = np.full(3, float(p.get("specular_color", 1.0)))
    if family.tint:
        sc = sc * np.asarray(family.tint[1], float)
    m, s = float(p.get("metallic", 0.0)), float(p.get("specular", 1.0))
    S, SW, P, WP = parts
    f0 = np.minimum(0.04 * sc, 1.0) * s
    f0m = float(np.minimum(0.04 * sc.max(), 1.0) * s)
    B0 = (1.0 - m) * (S[..., None] * f0 + SW[..., None] * (s - f0)) + m * SW[..., None]
    B1 = m * (S - SW) + (1.0 - m) * ((1.0 - f0m) * P - (s - f0m) * WP)
    return B0, B1


def _gltf_basis(probe, family, point):
    """:func:`_basis_now` of a ``gltf-pbr`` family: its two bases (base colour 0, and the change to 1)
    combined from the reduced parts of its roughness (:func:`_gltf_parts`, :func:`_gltf_combine`) in the
    shapes of the Mitsuba families' (a tinted family's three channels, else channel 0)."""
    _keep_probe(probe)
    parts = _gltf_parts(probe.key, float({**dict(family.fixed), **point}["roughness"]))
    out = []
    for k in range(3):                                  # f cos, albedo, images
        B0, B1 = _gltf_combine([q[k] for q in parts], family, point)
        if family.tint:
            out.append(np.stack([B0, np.broadcast_to(B1[..., None], B0.shape)]))
        else:
            out.append(np.stack([B0[..., 0], B1]))
    if family.tint:                                     # images (1 + J, C, views, rows, res)
        out[2] = np.moveaxis(out[2], -1, 1)
    return tuple(out)


# -- the colours at one point ---------------------------------------------------------------------

def _predict(B, x):
    """``B_0 + sum_j x_j B_j`` per channel: ``B`` (1 + J, K), or (1 + J, K, C) where the channels' bases
    differ (a tinted family), ``x`` (J, C) -> (K, C)."""
    if B.ndim == 3:
        return np.stack([B[0][:, c] + B[1:, :, c].T @ x[:, c] for c in range(x.shape[1])], -1)
    return B[0][:, None] + B[1:].T @ x


def _ch(B, c):
    """Channel ``c``'s bases: ``B`` itself where the channels share them."""
    return B[..., c] if B.ndim == 3 else B


#: Weight of the albedo term ``E_a`` beside the lobe's ``E_f`` in what the fit minimises
#: (the reported ``perceptual`` figure is the metric's own ``E_f + E_a``).  With one
#: colour per channel both are piecewise linear in ``ln x`` and their sum is often flat
#: between the two optima; a weight above 1 takes the end where the albedo is right.
ALBEDO_WEIGHT = 2.0


#: The albedo band of a conversion: beyond ``BAND`` (absolute, any channel) from the
#: source's at the incidences of :data:`REPORT_THETAS`, each unit of excess costs
#: ``BAND_WEIGHT`` in the figure minimised.  The metric alone weighs albedo in
#: logarithmic units over 0-80 degrees, and a source whose albedo falls at grazing
#: (the normalised Blinn-Phong lobe: as cos^2) pulls a one-colour family to the geometric
#: mean of its albedo curve, 0.16 off at normal incidence for ``reciprocal-blinn:ks=0.6:n=0.5``
#: (measured); the band keeps the energy a renderer sees first, where the family allows.
BAND, BAND_WEIGHT = 0.02, 50.0


#: The band as a constraint (:func:`fit_family` with ``hard=True``): beyond ``BAND_HARD`` from the
#: source's albedo at :data:`REPORT_THETAS` (the probe's albedo; the Done-when's band is 0.05) each unit
#: costs ``HARD_WEIGHT`` more, an exact penalty: far above what a unit of albedo is worth to the lobe's
#: figure or the highlight's (:data:`PEAK_WEIGHT`), so every conversion fits with the albedo first and
#: meets the constraint wherever the family can.  0.04, not 0.045: with the highlight held second the fit
#: ends on the band's edge, and the probe's albedo of ``blendbsdf-tir`` is up to 7e-3 from Mitsuba's
#: sampler (chrome@ngan2005/blinn-phong: 0.045 by the probe, 0.052 by the sampler at 0.045).
BAND_HARD, HARD_WEIGHT = 0.04, 1e5
#: A family other than :data:`BAND_FAMILIES` within this of the source's albedo (the probe's) is kept over the
#: coat's blend where its metric's figure is lower too (:func:`plausible.conversion.convert`'s choice): the
#: Done-when's 0.05 less the probe's largest difference from Mitsuba's sampler.
BAND_KEEP = 0.045
#: ... and where its metric's figure is at most this fraction above the coat's blend's: the blend adds a
#: diffuse term the source may not have (a metal's MTL ``Ks 0.9 0.7 0.4``, ``Ns 60``: ``roughconductor``
#: 2.36, the blend 2.34 with a red diffuse under its coat), a difference of 1 % is not a reason for it.
BAND_KEEP_MARGIN = 0.05


def _band(a, A, rows, hard=False):
    if rows is None or a.shape[0] != A.shape[0]:
        return 0.0
    d = float(np.max(np.abs(a[rows] - A[rows])))
    return BAND_WEIGHT * max(0.0, d - BAND) + (HARD_WEIGHT * max(0.0, d - BAND_HARD) if hard else 0.0)


#: The highlight a conversion holds: the peak of the sphere under the lamp at each of compare_looks'
#: light angles (0, 60, 120, 150 degrees: mirror incidence 0-75, grazing included), predicted from the
#: bases (:class:`plausible.mitsuba.looks.LampStrip`, within 1-13 % of the render), within ``PEAK_BAND``
#: of the source's: inside compare_looks' band (1.5) by a margin for the prediction and the render's
#: noise.  Each log unit beyond costs ``PEAK_WEIGHT`` times its square in the figure minimised: far
#: less than the albedo band as a constraint (:data:`HARD_WEIGHT`) -- where a family cannot keep both,
#: the albedo is kept and the highlight said lost (:func:`plausible.convert`'s warning).
PEAK_BAND, PEAK_WEIGHT = 1.35, 100.0


class Highlight:
    """The predicted highlight of a family at one point of its axes against the source's: ``images``, the
    bases' strip images (:func:`basis`), ``peaks`` the source's (one per light angle).
    :meth:`ratios` of colours ``x`` (J, C); :meth:`excess` the log ratios beyond :data:`PEAK_BAND`
    (signed, 0 inside); :meth:`cost` ``PEAK_WEIGHT sum excess^2``.  :meth:`channel` is the same of one
    channel's colours, the others held (the per-channel polish)."""

    def __init__(self, images, peaks, x=None, c=None):
        from ..spectra import LUMINANCE_WEIGHTS

        self.peaks, self.x, self.c = np.asarray(peaks, float), x, c
        #: each basis row's strip images (1 + J, views, rows, res; :func:`basis`): a candidate's luminance
        #: image is ``sum(w) B_0 + sum_j (w . x_j) B_j`` (the render is linear in f; ``w`` the luminance weights)
        self.images = images
        self.w = np.asarray(LUMINANCE_WEIGHTS, float)

    def channel(self, x, c):
        """The highlight of channel ``c``'s colours, the others held at ``x``; ``c = None``: of one colour
        given to every channel (a grey source's polish, :func:`_polish`)."""
        return Highlight(self.images, self.peaks, x, slice(None) if c is None else c)

    def ratios(self, x):
        x = np.asarray(x, float)
        if self.c is not None:
            full = self.x.copy()
            full[:, self.c] = x.reshape(-1) if isinstance(self.c, (int, np.integer)) else x.reshape(-1, 1)
            x = full
        from ..mitsuba.looks import PEAK_FLOOR, _window_max

        if self.images.ndim == 5:                # the channels' own bases (1 + J, C, views, rows, res)
            lum = sum(self.w[c] * (self.images[0, c] + np.tensordot(x[:, c], self.images[1:, c], 1))
                      for c in range(len(self.w)))
        else:
            y = x @ self.w if x.shape[1] == len(self.w) else x.mean(axis=1) * self.w.sum()
            lum = self.images[0] * self.w.sum() + np.tensordot(y, self.images[1:], 1)
        got = _window_max(lum)
        return np.maximum(got, PEAK_FLOOR) / np.maximum(self.peaks, PEAK_FLOOR)

    def excess(self, x):
        d = np.log(self.ratios(x))
        return np.sign(d) * np.maximum(np.abs(d) - math.log(PEAK_BAND), 0.0)

    def cost(self, x):
        return PEAK_WEIGHT * float(np.sum(self.excess(x) ** 2))


def _penalty_rows(hl, x, a, A, rows, hard) -> list:
    """The figure's penalties (:func:`_figure`) as least-squares rows, ``sqrt(weight) excess``: the highlight's
    log ratios beyond :data:`PEAK_BAND` (``hl`` at colours ``x``; none without ``hl``) and the albedo ``a``'s
    distance from ``A`` at ``rows`` beyond :data:`BAND` (and :data:`BAND_HARD` where ``hard``; none without
    ``rows``)."""
    out = [] if hl is None else [math.sqrt(PEAK_WEIGHT) * hl.excess(x)]
    if rows is not None:
        d = np.abs(a[rows] - A[rows]).ravel()
        out.append(math.sqrt(BAND_WEIGHT) * np.maximum(d - BAND, 0.0))
        if hard:
            out.append(math.sqrt(HARD_WEIGHT) * np.maximum(d - BAND_HARD, 0.0))
    return out


def _highlight_cost(hl, x):
    return 0.0 if hl is None else hl.cost(x)


def _figure(metric, F, Alb, x, g, A, eps, rows=None, hard=False, hl=None):
    a = _predict(Alb, x)
    c = _predict(F, x)
    e = M.errors(c, g, a, A, eps)
    base = e["fcos_max"] + ALBEDO_WEIGHT * e["albedo_max"] if metric == "perceptual" else e[metric]
    return base + _band(a, A, rows, hard) + _highlight_cost(hl, x), e


#: Weight of the albedo rows of the least squares, beyond equal weight of the two sets.
LSQ_ALBEDO = 10.0


def _lsq(F, Alb, g, A, eps, metric, band=None):
    """Colours per channel by bounded linear least squares (step 2; :func:`plausible.fitting.linear.bounded`,
    the fitter's colour step); (J, C).  ``band``: the rows of ``Alb`` where the albedo is held within
    :data:`BAND_HARD` of the source's (:func:`plausible.fitting.linear.within_band`)."""
    from ..fitting.linear import bounded, within_band

    J, C = F.shape[0] - 1, g.shape[1]
    x = np.zeros((J, C))
    for c in range(C):
        rows, rhs = _rows(_ch(F, c), _ch(Alb, c), g[:, c], A[:, c], eps, metric)
        x[:, c] = bounded(rows, rhs)
        if band is not None:
            Ac = _ch(Alb, c)
            x[:, c] = within_band(rows, rhs, Ac[1:, band].T, A[band, c] - Ac[0, band], BAND_HARD, x[:, c])
    return x


def _rows(F, Alb, g, A, eps, metric):
    """One channel's least squares in its colours ``x``: ``(rows, rhs)`` with ``|rows x - rhs|^2`` the
    metric's figure (``l2-cos``) or its linearisation (relative residuals ``(c - g) / (g + eps)`` and
    ``(a - A) / A``, the albedo rows weighted by :data:`LSQ_ALBEDO`)."""
    if metric == "l2-cos":
        return F[1:].T, g - F[0]
    w = 1.0 / (g + eps)
    ok = A > 1e-12
    lam = LSQ_ALBEDO * math.sqrt(len(g) / max(int(ok.sum()), 1))
    wa = lam / np.where(ok, A, 1.0) * ok
    return (np.concatenate([F[1:].T * w[:, None], Alb[1:].T * wa[:, None]]),
            np.concatenate([(g - F[0]) * w, (A - Alb[0]) * wa]))


class ColourObjective:
    """The colours of one channel at one point of a family's axes (slots ``0..J-1`` in
    ``[0, 1]``), as an objective of the fitter's optimiser
    (:func:`plausible.fitting.fit.optimise`, whose protocol it follows): so step 4 runs the
    optimiser of :func:`plausible.fit`, not one of its own.  ``fun(z)`` is the figure
    minimised (:func:`_figure`), ``fun(z, beta)`` its smooth bound (``perceptual``: the
    maxima's log-sum-exp bounds, the albedo weighted by :data:`ALBEDO_WEIGHT`);
    :meth:`residuals_many` the least-squares metrics' residuals, the band's and the
    highlight's excesses as rows (``sqrt(weight) excess``).  The best point by the figure is
    kept in ``best_x``."""

    def __init__(self, F, Alb, gc, Ac, eps, metric, rows=None, hard=False, hl=None):
        from types import SimpleNamespace

        self.F, self.Alb, self.gc, self.Ac, self.eps = F, Alb, gc, Ac, eps
        self.rows, self.hard, self.hl = rows, hard, hl
        self.vars = [SimpleNamespace(name=j, bounds=(0.0, 1.0)) for j in range(F.shape[0] - 1)]
        self.problem = SimpleNamespace(metric=metric, maxiter=200)
        self.best_x, self.best_value = None, math.inf
        self.rejected, self.timed_out, self.fd = 0, False, None

    def _keep(self, z, v):
        if v < self.best_value:
            self.best_x, self.best_value = np.array(z, float), v
        return v

    def __call__(self, z, beta=None):
        z = np.clip(np.asarray(z, float), 0.0, 1.0)[:, None]
        if beta is None:
            return self._keep(z[:, 0], _figure(self.problem.metric, self.F, self.Alb, z, self.gc, self.Ac, self.eps,
                                               self.rows, self.hard, self.hl)[0])
        c, a = _predict(self.F, z), _predict(self.Alb, z)
        pen = _band(a, self.Ac, self.rows, self.hard) + _highlight_cost(self.hl, z)
        return (M.objective("perceptual", c, self.gc, eps=self.eps, beta=beta)
                + ALBEDO_WEIGHT * M.objective("perceptual", a, self.Ac, eps=1e-12, beta=beta) + pen)

    def residuals_many(self, xs) -> list:
        return [self._residuals(np.clip(np.asarray(z, float), 0.0, 1.0)) for z in xs]

    def _residuals(self, z):
        c, a = _predict(self.F, z[:, None])[:, 0], _predict(self.Alb, z[:, None])[:, 0]
        g, A = self.gc[:, 0], self.Ac[:, 0]
        if self.problem.metric == "l2-cos":
            r = (c - g) / math.sqrt(max(float(np.sum(g * g)), 1e-300))
        else:
            r = M._lr(c, g, self.eps) / math.sqrt(len(g))
        rows = self.rows if self.rows is not None and len(a) == len(A) else None
        out = [r] + _penalty_rows(self.hl, z[:, None], a, A, rows, self.hard)
        self(z)                                  # the figure, and the best point by it
        return np.concatenate(out)

    def best_params(self, x0) -> dict:
        x = self.best_x if self.best_x is not None else np.asarray(x0, float)
        return {v.name: float(xi) for v, xi in zip(self.vars, x)}


def _polish(F, Alb, x, g, A, eps, metric, rows=None, hard=False, hl=None):
    """Step 4 on each channel by the fitter's optimiser (:class:`ColourObjective`); the
    better of ``x`` and the polished point per channel.  A grey source (:func:`_grey`) is
    polished once, one colour for every channel: the highlight's penalty reads the luminance,
    in which the channels weigh differently, so polishing them one by one tinted a grey
    material (three.js's WaltHead, Kd 0.64 and Ks 0.25, came out with a green highlight)."""
    from ..fitting.fit import optimise

    x = x.copy()
    grey = _grey(F, Alb, x, g, A, hl)
    for c in ([0] if grey else range(x.shape[1])):
        obj = ColourObjective(_ch(F, c), _ch(Alb, c), g[:, c:c + 1], A[:, c:c + 1], eps, metric, rows, hard,
                              None if hl is None else hl.channel(x, None if grey else c))
        obj(x[:, c])                             # the start is a candidate: never worse than it
        optimise(obj, [x[:, c].copy()], lambda: None)
        x[:, slice(None) if grey else c] = obj.best_x[:, None] if grey else obj.best_x
    return x


def _grey(F, Alb, x, g, A, hl) -> bool:
    """The channels are alike: the source's values ``g`` and albedos ``A`` the same in every channel
    (to 1e-12 relative), the bases shared (an untinted family) and the start ``x`` grey."""
    def same(v):
        v = np.asarray(v, float)
        return bool(np.all(np.abs(v - v[..., :1]) <= 1e-12 * np.maximum(np.abs(v[..., :1]), 1e-300)))

    return (F.ndim == 2 and Alb.ndim == 2 and (hl is None or hl.images.ndim != 5)
            and same(g) and same(A) and same(x))


#: The axes' search (:class:`AxesObjective`): the difference step of the Jacobian in the axes' own units
#: (``ln alpha`` for a roughness; Mitsuba evaluates in single precision, so far above
#: :data:`plausible.fitting.fit.FD_STEP`), least squares' tolerances, and its evaluations (``maxiter``
#: times the axes plus one).
AXIS_STEP, AXIS_TOL, AXIS_MAXITER = 1e-3, 1e-3, 2
#: Before the least squares, the true figure along each axis in turn from the grid's best point, this many
#: evaluations between the grid values either side (:meth:`AxesObjective.bracket`; the Brent search that
#: refined the grid's point before the one fitter, now the fitter's :func:`plausible.fitting.fit._line_polish`):
#: the residuals linearise ``perceptual``'s maxima, and least squares alone from the grid ended
#: ``red-fabric@ngan2005/ward`` to glTF at figure 2.70 (FLIP 0.44) where the line searches reach 1.70 (0.18).
AXIS_POLISH = 8


#: A point of the axes replaces the best so far only where its figure is lower by more than this fraction:
#: least squares steps off a grid value (``metallic`` 0) by 1e-6 for a figure lower by rounding, and a
#: glTF dielectric converted to itself came back at ``metallic`` 1.3e-6.
KEEP_RTOL = 1e-9
#: An axis this close to a bound (a fraction of its span) after the search is tried on the bound
#: (:meth:`AxesObjective.snapped`).
SNAP, SNAP_TOL = 1e-4, 1e-3


class AxesObjective:
    """A family's axes at their best colours -- each point's colours by bounded linear least squares
    (:func:`_lsq`, the band a constraint where ``hard``): a variable projection (Golub and Pereyra 1973)
    -- as an objective of the fitter's optimiser (:func:`plausible.fitting.fit.optimise`, whose protocol
    it follows: line searches of the true figure within :meth:`bracket` first, :data:`AXIS_POLISH`, then
    least squares whatever the metric): ``residuals_many`` the colours' least-squares rows
    (:func:`_rows`: the metric's, or for ``perceptual`` its linearisation) at those colours, with the
    highlight's and the band's excesses as rows (``sqrt(weight) excess``, as :class:`ColourObjective`);
    ``fun(z)`` the true figure minimised (:func:`_figure`), the best point by it kept in ``best_x`` (the
    grid's best is never lost to a least-squares step that worsens the figure).  Variables: the axes in
    their own units (:meth:`Axis.fwd`); :attr:`points` counts the axis points evaluated."""

    def __init__(self, probe, fam, g, A, eps, metric, rows, hard, peaks):
        from types import SimpleNamespace

        self.probe, self.fam, self.g, self.A, self.eps, self.rows, self.hard, self.peaks = \
            probe, fam, g, A, eps, rows, hard, peaks
        self.vars = [SimpleNamespace(name=a.name, bounds=(a.fwd(a.lo), a.fwd(a.hi)),
                                     marks=(a.fwd(a.lo), a.fwd(a.hi)) + tuple(a.fwd(v) for v in a.values))
                     for a in fam.axes]
        self.problem = SimpleNamespace(metric=metric, maxiter=AXIS_MAXITER)
        self.least_squares, self.fd_step, self.tol, self.polish = True, AXIS_STEP, AXIS_TOL, AXIS_POLISH
        self.best_x, self.best_value, self.points = None, math.inf, 0
        self.rejected, self.timed_out, self.fd = 0, False, None
        # each channel's residuals over one constant, the norm of its right-hand side without any basis (the
        # target's own: ``|g_c|`` for ``l2-cos``), so that the scale does not move with the axes
        none = (np.zeros((1, len(g))), np.zeros((1, len(A))))
        self.scale = [math.sqrt(max(float(np.sum(_rows(*none, g[:, c], A[:, c], eps, metric)[1] ** 2)), 1e-300))
                      for c in range(g.shape[1])]

    def point(self, z) -> dict:
        return {a.name: a.inv(float(t)) for a, t in zip(self.fam.axes, z)}

    def _at(self, z):
        self.points += 1
        F, Alb, H = basis(self.probe, self.fam, self.point(z))
        metric = self.problem.metric
        x = _lsq(F, Alb, self.g, self.A, self.eps, metric, self.rows if self.hard else None)
        hl = Highlight(H, self.peaks)
        value = _figure(metric, F, Alb, x, self.g, self.A, self.eps, self.rows, self.hard, hl)[0]
        best = self.best_value
        if self.best_x is None or (value < best - KEEP_RTOL * abs(best) if math.isfinite(best)
                                   else not math.isnan(value)):        # a gain beyond rounding
            self.best_x, self.best_value = np.array(z, float), value
        return F, Alb, x, hl, value

    def __call__(self, z, beta=None):
        return self._at(np.asarray(z, float))[-1]

    def residuals_many(self, zs) -> list:
        out = []
        for z in zs:
            F, Alb, x, hl, _ = self._at(np.asarray(z, float))
            r = []
            for c in range(x.shape[1]):
                R, rhs = _rows(_ch(F, c), _ch(Alb, c), self.g[:, c], self.A[:, c], self.eps, self.problem.metric)
                r.append((R @ x[:, c] - rhs) / self.scale[c])
            r += _penalty_rows(hl, x, _predict(Alb, x), self.A, self.rows, self.hard)
            out.append(np.concatenate(r))
        return out

    def best_params(self, x0) -> dict:
        x = self.best_x if self.best_x is not None else np.asarray(x0, float)
        return {v.name: float(t) for v, t in zip(self.vars, x)}

    def bracket(self, k, z):
        """The interval of axis ``k`` searched by the line polish: between the grid values either side of
        the one nearest ``z[k]`` (the axis's bounds beyond the first and last), in the axis's units."""
        a, (lo, hi) = self.fam.axes[k], self.vars[k].bounds
        marks = sorted(a.fwd(v) for v in a.values)
        j = int(np.argmin([abs(m - z[k]) for m in marks]))
        return (max(lo, marks[j - 1]) if j > 0 else lo), (min(hi, marks[j + 1]) if j + 1 < len(marks) else hi)

    def snapped(self, z):
        """``z`` with each axis within :data:`SNAP` of its span from a bound or a grid value (``metallic`` 0,
        ``specular_color`` 1) put on it, where the figure there
        is at most :data:`SNAP_TOL` higher (of the figure, or absolute below 1: the metrics' figures are
        relative errors and log ratios, 1e-3 of which no one sees): least squares' reflective steps keep inside the bounds, and
        ``metallic`` 1.3e-6 is a dielectric said as a mixture, ``specular`` 0.99998 an extension not needed."""
        z = np.array(z, float)
        here = None
        for k, v in enumerate(self.vars):
            lo, hi = v.bounds
            for b in v.marks:
                if 0.0 < abs(z[k] - b) <= SNAP * (hi - lo):
                    t = z.copy()
                    t[k] = b
                    here = self(z) if here is None else here
                    value = self(t)
                    if value <= here + SNAP_TOL * max(abs(here), 1.0):
                        z, here = t, value
        return z


# -- the fit ---------------------------------------------------------------------------------------

@dataclass
class FamilyFit:
    """A fitted family: its ``dict`` (as ``mi.load_dict`` takes it), axis values,
    colours, every metric's figure (measured on the loaded result), and the
    number of Mitsuba axis points evaluated."""

    family: str
    dict: dict
    point: dict
    colours: dict
    errors: dict
    points: int
    #: The figure minimised (the metric's, the albedo weighted, the band's penalty) at the result.
    figure: float = math.inf
    #: The key of :data:`FAMILIES` (``family`` is the Mitsuba type: ``blendbsdf`` for two of them).
    key: str = ""
    #: The largest albedo difference from the source's at :data:`REPORT_THETAS` (the probe's, loaded result).
    band: float = math.nan
    #: Whether the band was a constraint of the fit (``fit_family(hard=True)``).
    hard: bool = False
    #: The loaded result's highlight over the source's at each of compare_looks' light angles, predicted
    #: (:class:`plausible.mitsuba.looks.LampStrip`; :data:`PEAK_BAND`).
    peak_ratios: list = ()


def source_target(source, probe, albedo=None):
    """The source's ``f cos`` on the pairs and albedo (accurate integrator) at the probe's
    incidences, both with three channels, and the peaks of its highlight (:attr:`Probe.strip`).  ``albedo``: that albedo if already computed,
    (T, C) at the probe's incidences."""
    from ..analysis import albedo_curve

    f = np.asarray(source.eval(probe.wi, probe.wo), float).reshape(len(probe.wi), -1)
    g = np.broadcast_to(f * probe.wo[:, 2:3], (len(f), 3)).copy()
    if albedo is None:
        albedo = albedo_curve(source, probe.thetas).value
    A = np.asarray(albedo, float).reshape(len(probe.thetas), -1)
    peaks = probe.strip.peaks(np.asarray(source.eval(probe.strip.wi, probe.strip.wo), float))
    return g, np.broadcast_to(A, (len(A), 3)).copy(), peaks


def fit_family(source, family: str | Family, metric: str = "perceptual", *, probe=None, target=None,
               hard: bool = False) -> FamilyFit:
    """Fit the Mitsuba ``family`` (a key of :data:`FAMILIES`) to the ``source`` model
    under ``metric`` (steps of the module docstring).  ``probe``/``target``: a
    :class:`Probe` and the source's ``(g, A)`` on it, to reuse across families.
    ``hard``: the band as a constraint -- the colours of every point by least squares within
    :data:`BAND_HARD` of the source's albedo at :data:`REPORT_THETAS` where the point allows
    (:func:`_within_band`), and the figure with the exact penalty :data:`HARD_WEIGHT` beyond it."""
    fam = FAMILIES[family] if isinstance(family, str) else family
    if metric not in M.METRICS:
        raise ValueError(f"metric must be one of {', '.join(M.METRICS)}, got {metric!r}")
    probe = probe or probe_for(source)
    g, A, peaks = target if target is not None else source_target(source, probe)
    eps = M.floor(g)
    rows = [int(np.argmin(np.abs(probe.thetas - math.radians(t)))) for t in REPORT_THETAS]
    # 2. scan; 3. refine the axes from the best grid point by the fitter's optimiser
    obj = AxesObjective(probe, fam, g, A, eps, metric, rows, hard, peaks)
    grid = [[a.fwd(v) for v, a in zip(vals, fam.axes)] for vals in _product([a.values for a in fam.axes])]
    for z in grid:
        obj(z)
    best = obj.point(obj.best_x)
    if fam.axes:
        from ..fitting.fit import optimise

        found = optimise(obj, [obj.best_x.copy()], lambda: None)
        z = np.array([found[a.name] for a in fam.axes])
        best = obj.point(obj.snapped(z))
    F, Alb, H = basis(probe, fam, best)
    hl = Highlight(H, peaks)
    # 4. polish the colours
    x = _polish(F, Alb, _lsq(F, Alb, g, A, eps, metric, rows if hard else None), g, A, eps, metric, rows, hard, hl)
    figure = _figure(metric, F, Alb, x, g, A, eps, rows, hard, hl)[0]
    colours = {s: x[j] for j, s in enumerate(fam.slots)}
    d = fam.bsdf_dict(best, colours)
    # 5. measure the loaded result
    key = family if isinstance(family, str) else next((k for k, f in FAMILIES.items() if f == fam), fam.type)
    r = measure(d, key, probe, (g, A, peaks), metric)
    r.point, r.colours, r.points, r.figure, r.hard = best, {s: [float(v) for v in c] for s, c in colours.items()}, \
        obj.points, figure, hard
    return r


def measure(d: dict, key: str, probe, target, metric: str = "perceptual") -> FamilyFit:
    """The :class:`FamilyFit` of a description ``d`` (a fit's result, or one given rather than fitted: an
    exactly Lambertian source's ``diffuse``): every metric's figure on ``probe`` against ``target = (g, A,
    peaks)`` (:func:`source_target`), the albedo band and the predicted highlight ratios (step 5)."""
    g, A, peaks = target
    eps = M.floor(g)
    fc, alb, hs = probe.measure_all(_load(d))
    errors = M.errors(np.broadcast_to(fc, g.shape), g, np.broadcast_to(alb, A.shape), A, eps)
    rows = [int(np.argmin(np.abs(probe.thetas - math.radians(t)))) for t in REPORT_THETAS]
    band = float(np.max(np.abs(np.broadcast_to(alb, A.shape)[rows] - A[rows])))
    figure = errors[metric] if metric != "perceptual" else errors["fcos_max"] + ALBEDO_WEIGHT * errors["albedo_max"]
    from ..mitsuba.looks import PEAK_FLOOR

    ratios = np.maximum(probe.strip.peaks(hs), PEAK_FLOOR) / np.maximum(peaks, PEAK_FLOOR)
    return FamilyFit(d["type"], d, {}, {}, errors, 0, figure, key, band, peak_ratios=[float(r) for r in ratios])


def gltf_fixed_metallic(value: float) -> Family:
    """``gltf-pbr`` with its ``metallic`` fixed at ``value`` (roughness and base colour fitted)."""
    f = FAMILIES["gltf-pbr"]
    return Family(f.type, (("metallic", float(value)),), tuple(a for a in f.axes if a.name != "metallic"),
                  f.slots, f.offset)


#: The glTF dielectric (``metallic`` 0) with KHR_materials_specular's two factors as axes: its
#: Fresnel runs from ``f0 = min(0.04 specular_color, 1) specular`` at normal incidence to ``f90 =
#: specular`` at grazing (:mod:`plausible.models.gltf_pbr`), so a lobe whose reflectance does not
#: rise at grazing (an MTL ``Ks`` with Blinn's lobe: ``fresnel=none``; Ngan et al.'s fits, whose Schlick
#: ``F0`` is near 1 under a small colour weight) is held with its width and its albedo together.  The core
#: dielectric (``specular = specular_color = 1``: ``f0`` 0.04 rising to 1) must spend roughness to keep
#: such a source's grazing albedo within the band: the MTL ``red_plastic`` (Kd 0.5 0.1 0.1, Ks 0.04,
#: Ns 200) came out at roughness 0.48 and 0.34x its highlight, or as a red metal (metallic 1, FLIP 0.385);
#: with the factors it is roughness 0.30, ``specular`` 0.036, ``specular_color`` 25 (``f0 = f90 = 0.036``),
#: highlight 0.72-0.90x, FLIP 0.077 (docs/convert.md).  Grey here; :func:`gltf_dielectric` tints it.
GLTF_DIELECTRIC = Family("gltf-pbr", (("metallic", 0.0),),
                         (FAMILIES["gltf-pbr"].axes[0],
                          Axis("specular", tuple(float(x) for x in np.geomspace(0.03, 1.0, 7)), 0.01, 1.0),
                          Axis("specular_color", (1.0, 4.0, 25.0), 0.25, 25.0)),
                         ("base_color",), offset=True)


def gltf_dielectric(tint=(1.0, 1.0, 1.0)) -> Family:
    """:data:`GLTF_DIELECTRIC` with ``specular_color`` its axis's value times ``tint`` (RGB, largest 1: the
    channel that sets ``max_value(F_d)``, so the diffuse weight is the same at every colour and the family
    stays affine in ``base_color`` per channel).  ``f0_c = min(0.04 specular_color tint_c, 1) specular``:
    a coloured lobe (a metal's, Ngan's ``chrome``) keeps its colour; ``f90`` is white (``specular``)."""
    t = np.clip(np.asarray(tint, float), 0.0, None)
    t = t / t.max() if np.all(np.isfinite(t)) and t.max() > 0 else np.ones(3)
    t = tuple(float(v) for v in np.where(np.abs(t - 1.0) <= 1e-9, 1.0, t))     # a grey lobe's rounding: white
    if t == (1.0, 1.0, 1.0):
        return GLTF_DIELECTRIC
    f = GLTF_DIELECTRIC
    return Family(f.type, f.fixed, f.axes, f.slots, f.offset, tint=("specular_color", t))


def lobe_tint(model, albedo0) -> np.ndarray:
    """The colour of the lobes ``model`` does not declare diffuse, largest channel 1: its albedo at normal
    incidence ``albedo0`` (three channels) less the declared diffuse lobes' (:func:`diffuse_albedo`);
    white where that is not positive or not known."""
    spec = np.asarray(albedo0, float).reshape(-1)[:3] - diffuse_albedo(model)
    if not np.all(np.isfinite(spec)) or spec.max() <= 1e-9:
        return np.ones(3)
    return np.clip(spec, 0.0, None) / spec.max()


def _product(lists):
    out = [()]
    for vals in lists:
        out = [o + (v,) for o in out for v in vals]
    return out


def _mirror(wi):
    return [np.array([-wi[0], -wi[1], wi[2]])]


def probe_for(source) -> Probe:
    """The :class:`Probe` of ``source``: about its peaks and the mirror direction (every
    family's peak)."""
    return Probe([source.peak_directions, _mirror])


# -- choosing a family ----------------------------------------------------------------------------

#: Below this diffuse (specular) albedo at normal incidence a source counts as having none.
NONE_BELOW = 0.01
#: Largest specular albedo at normal incidence ``roughplastic`` (index 1.49, coat of
#: ``specular_reflectance <= 1``) is given: its Fresnel at normal incidence is 0.039.
PLASTIC_SPECULAR = 0.04


def diffuse_albedo(model) -> np.ndarray:
    """The albedo at normal incidence of the lobes ``model`` declares diffuse (three
    channels; 0 for a model that declares none or a foreign object)."""
    from ..arrays.ops import NP

    total = np.zeros(3)
    for lobe in getattr(model, "components", lambda: ())():
        if lobe.kind == "diffuse" and lobe.albedo is not None:
            try:
                total = total + np.broadcast_to(np.asarray(lobe.albedo(NP, (0.0, 0.0, 1.0), model.p), float), (3,))
            except Exception:  # a lobe whose albedo needs more than a direction: count it as unknown
                return np.full(3, np.nan)
    return total


#: A source whose albedo rises by more than this (any channel) from normal incidence to
#: the largest probed incidence has a Fresnel-like rise that a family without Fresnel
#: (``diffuse``, ``roughconductor``) cannot follow.
RISE = 0.025
#: A source whose albedo falls by more than this (any channel) from normal incidence to any
#: probed incidence is also fitted with ``blendbsdf-tir`` (:data:`TIR_COAT`): every other family's
#: albedo is flat or rises, or falls by at most a fifth (docs/convert.md), and a flat family
#: balanced between the ends is off by half the fall.
FALL = 0.025


def candidates(model, albedo) -> tuple[list, str]:
    """``(families, reason)``: the families fitted to ``model``, of which the one of the lowest
    minimised figure is kept.  ``albedo``: the source's albedo, three channels, at normal
    incidence (shape (3,)) or at the incidences of :data:`plausible.conversion.CONSERVE_THETAS`
    from normal incidence on (shape (T, 3)).  With ``D`` the declared diffuse albedo and
    ``S = albedo - D`` at each incidence: ``diffuse`` alone when ``S < 0.01`` at every
    incidence; when ``D < 0.01``, ``roughconductor``, and also ``roughplastic`` and
    ``principled`` (which have a dielectric Fresnel) when the albedo rises by more than
    :data:`RISE` from normal incidence; else ``diffuse``, ``blendbsdf`` (a diffuse and a
    ``roughconductor`` without Fresnel, the composition of the published fits), ``roughplastic``
    when ``S <= 0.04`` at normal incidence and grey (channels within 10 %) or the albedo rises,
    and ``principled``; ``principled`` for a source that declares no lobes; and besides, for a
    source whose albedo falls by more than :data:`FALL` from normal incidence to any incidence up
    to 75 degrees (given the incidences), ``blendbsdf-tir``.  (Decided at normal
    incidence alone, a published fit with a dielectric Fresnel, ``chrome@low2012/cook-torrance-e2``,
    albedo 0.082 at 0 degrees and 0.287 at 75, was given ``roughconductor`` alone and missed by 0.10
    at both ends; ``colonial-maple-223@ngan2005/cook-torrance``, a specular 0.002 at normal incidence
    rising at grazing, ``diffuse`` alone, 0.10 off.)"""
    D = diffuse_albedo(model)
    a = np.asarray(albedo, float)
    a = a.reshape(1, -1) if a.ndim <= 1 else a
    a = np.broadcast_to(a, (a.shape[0], 3))
    # the fall within the band's incidences (to 75 degrees: every GGX or Beckmann lobe loses a little
    # beyond, by masking, 0.03 at 85 for cook-torrance:m=0.05)
    upto = (np.asarray(CONSERVE_THETAS) <= max(REPORT_THETAS)) if len(a) == len(CONSERVE_THETAS) else slice(None)
    fall = float(np.max(a[0] - a[upto]))
    tir, why_tir = (["blendbsdf-tir"], f", an albedo falling by {fall:.3g}") if fall > FALL else ([], "")
    if not np.all(np.isfinite(D)) or not hasattr(model, "components"):
        return ["principled"] + tir, "the source declares no diffuse/glossy lobes: the most general family" + why_tir
    S = np.maximum(a - D, 0.0)
    S0 = S[0]
    rise = float(np.max(a - a[0]))
    rising = rise > RISE
    if S.max() < NONE_BELOW:
        return ["diffuse"], f"no specular part (albedo {S.max():.3g} beside a diffuse {D.max():.3g})"
    if D.max() < NONE_BELOW:
        if rising:
            return (["roughconductor", "roughplastic", "principled"] + tir,
                    f"no diffuse part (specular albedo {S0.max():.3g}), an albedo rising by {rise:.3g} (Fresnel)"
                    + why_tir)
        return ["roughconductor"] + tir, f"no diffuse part (specular albedo {S0.max():.3g})" + why_tir
    plastic = (S0.max() <= PLASTIC_SPECULAR and S0.max() <= 1.1 * S0.min() + 1e-3) or rising
    return (["diffuse", "blendbsdf"] + (["roughplastic"] if plastic else []) + ["principled"] + tir,
            f"a diffuse part ({D.max():.3g}) and a specular one ({S0.max():.3g} at normal incidence"
            + (f", {S.max():.3g} at most" if S.max() > S0.max() + 1e-3 else "") + ")"
            + (f", an albedo rising by {rise:.3g}" if rising else "")
            + (" within a plastic's coat" if plastic and not rising else "") + why_tir)


# -- Mitsuba's own sampler ------------------------------------------------------------------------

def sampler_albedo(bsdf_dict: dict, thetas_deg=REPORT_THETAS, side: int = 256) -> np.ndarray:
    """The directional albedo ``E[weight]`` of Mitsuba's own ``sample`` (a registered
    model of :data:`PLAUSIBLE_TYPES`: its own sampler) at ``thetas_deg``
    (``side^2`` stratified samples each, the lobe choice by a golden-ratio
    sequence): shape (T, 3).  At ``side = 256`` its standard error is below 1e-3 for
    the families here."""
    from ..analysis import direction

    b = _load(bsdf_dict)
    i, j = np.meshgrid(np.arange(side), np.arange(side), indexing="ij")
    u = np.stack([(np.arange(side * side) * 0.6180339887498949) % 1.0, ((i + 0.5) / side).ravel(),
                  ((j + 0.5) / side).ravel()], axis=-1)
    out = []
    for t in thetas_deg:
        s = b.sample(direction(math.radians(t)), u)
        out.append(np.broadcast_to(np.asarray(s.weight, float).reshape(len(u), -1).mean(axis=0), (3,)))
    return np.array(out)
