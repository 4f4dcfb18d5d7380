"""The fuzzer shared by tests/test_fuzz.py (NumPy, float64) and
tests/mitsuba/test_fuzz_plugins.py (Dr.Jit, float32): random parameters from each
model's declared ranges (extremes included), direction pairs that stress the
formulas, and each model's analytic bound on the sample weight.

Directions (:func:`direction_pairs`): random pairs, plus incidences with
``cos(theta)`` from 1 down to 1e-14 and the exact horizon (``cos = 0``), each
paired with its exact mirror (``h = n``), a near-mirror (1e-7 rad off), itself
(``wi = wo``), the normal, a grazing direction and random directions.

Weight bounds (:func:`weight_bound`), derived from each model's formulas and
sampler (``weight = f cos(theta_o) / pdf``; for a mixture sampled with
probabilities ``p_k``, ``weight <= sum_k sup(f_k cos / pdf_k) / p_k``):

* Lambert: ``rd``;
* Ashikhmin-Shirley (JGT 2000): the specular ratio is ``F(k.h) cos_o / max(cos_i, cos_o) <= 1``
  (journal eqs. 4, 8); the diffuse one is ``pi rho_d <= 28/23 rd (1 - rs) (1 - (1 - cos_i/2)^5)``;
* reciprocal / modified Phong: ``ks (n + 2) / (n + 1)`` (lobe ``(n+2)/(2 pi) cos^n``,
  sampled with ``(n+1)/(2 pi) cos^n``); the diffuse part ``kd``;
* reciprocal Blinn: ``8 pi ks c(n) (k.h) cos_o / (n + 1) <= 8 pi ks c(n) / (n + 1)``;
  original Phong and Blinn: the same over ``cos_i``;
* Neumann metal (eq. 22): ``2 pi c / (n + 1)`` (``F <= 1``, ``cos_o / max <= 1``);
* Cook-Torrance (Beckmann): ``F G (k.h) / (cos_i h_z)``; with the V-groove ``G <= 2 h_z cos_i / (k.h)``
  this is ``<= 2``; with ``G = 1``, ``cos_o = 2 (k.h) h_z - cos_i > 0`` gives ``< 2 / cos_i^2``;
* Ward: ``rs sqrt(cos_o / cos_i) (k.h) h_z^3 <= rs / sqrt(cos_i)`` (1992),
  ``rs (k.h) h_z^3 / cos_i <= rs / cos_i`` (Dür), ``rs cos_o / ((k.h) h_z) <= 2 rs``
  (balanced); diffuse ``rd``;
* Schlick: ``F (G(v)/v) G(v') (k.h) / h_z <= 2 / (r cos_i)`` (``G(v)/v <= 1/r``, ``G <= 1``,
  ``(k.h)/h_z < 2 / cos_i`` as above), times ``1/sqrt(p)`` for ``azimuth="sqrt"``
  (``f`` has ``sqrt(A)`` where the sampler has ``A``, ``A >= p``); diffuse ``rd``;
* pumped-up (eq. 16-17): ``F w_base / prod g_k <= bound(base) / prod a_k(wi)``;
* Lafortune: no closed bound derived here (``None``: finiteness and consistency only).
"""

from __future__ import annotations

import math
import zlib

import numpy as np

import plausible
from plausible.analysis.suite import variants
from plausible.bxdf import mixture_probabilities
from plausible.models import ashikhmin_shirley as AS
from plausible.models import phong as PH
from plausible.arrays.ops import NP

#: ``cos(theta)`` of the special incidences (1e-14 and 0 lie at or below the
#: models' horizon, 1e-12, where every value must be 0).
COSINES = (1.0, 0.9999999, 0.5, 1e-2, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12, 1e-14, 0.0)


def _dir(c, phi):
    s = np.sqrt(np.maximum(1.0 - c * c, 0.0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), c * np.ones_like(phi)], axis=-1)


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def direction_pairs(rng, n_random: int = 256, per_cos: int = 8):
    """``(wi, wo)`` arrays of shape (N, 3): the special pairs of the module
    docstring for each of :data:`COSINES`, then ``n_random`` random pairs with
    log-uniform cosines in ``[1e-14, 1]``."""
    wis, wos = [], []
    for c in COSINES:
        wi = _dir(c, rng.uniform(0, 2 * math.pi, per_cos))
        mirror = wi * [-1.0, -1.0, 1.0]
        near = _unit(mirror + 1e-7 * rng.normal(size=mirror.shape))
        grazing = _dir(10.0 ** rng.uniform(-14, -1, per_cos), rng.uniform(0, 2 * math.pi, per_cos))
        other = _dir(rng.uniform(0, 1, per_cos), rng.uniform(0, 2 * math.pi, per_cos))
        normal = np.tile([0.0, 0.0, 1.0], (per_cos, 1))
        for wo in (mirror, near, wi, normal, grazing, other):
            wis.append(wi)
            wos.append(wo)
    c = 10.0 ** rng.uniform(-14, 0, (2, n_random))
    wis.append(_dir(c[0], rng.uniform(0, 2 * math.pi, n_random)))
    wos.append(_dir(c[1], rng.uniform(0, 2 * math.pi, n_random)))
    return np.concatenate(wis), np.concatenate(wos)


def incidences(rng, n: int):
    """``n`` incident directions: each of :data:`COSINES` in turn, then log-uniform cosines."""
    c = 10.0 ** rng.uniform(-14, 0, n)
    c[:len(COSINES)] = COSINES[:n]
    return _dir(c, rng.uniform(0, 2 * math.pi, n))


def uniforms(rng, n: int, one_minus: float = 1.0 - 2.0 ** -53):
    """``u`` of shape (n, 3) in ``[0, 1)``; a third of the entries are exactly 0 or
    ``one_minus`` (the largest number below 1 of the precision under test)."""
    u = rng.random((n, 3))
    edge = rng.random((n, 3)) < 1 / 3
    return np.where(edge, np.where(rng.random((n, 3)) < 0.5, 0.0, one_minus), u)


def random_params(name: str, rng, grey: bool = False) -> dict:
    """A random valid parameter set of ``name``: each number from its declared
    range (log-uniform over wide ranges, the ends and declared extremes
    sometimes), choices at random; structured and model parameters keep their
    default.  ``grey``: colour parameters as one number."""
    info = plausible.info(name)
    for _ in range(50):
        kw = {}
        for p in info.params:
            if p.kind == "choice":
                kw[p.name] = str(rng.choice(p.choices))
            elif p.kind in ("scalar", "color") and p.default is not None:
                lo, hi = p.lo, min(p.hi, 1e6)
                r = rng.random()
                cands = [lo, hi] + [x for x in p.extremes if isinstance(x, float)]
                if r < 0.3:
                    v = float(rng.choice(cands))
                elif hi > 100 * max(lo, 1e-3):
                    v = float(10.0 ** rng.uniform(math.log10(max(lo, 1e-3)), math.log10(hi)))
                else:
                    v = float(rng.uniform(lo, hi))
                if p.integer:
                    v = int(round(v))
                if p.kind == "color" and not grey:
                    v = [float(np.clip(v * rng.uniform(0.5, 1.0), lo, hi)) for _ in range(3)]
                kw[p.name] = v
        try:
            info.cls(**kw)
        except ValueError:
            continue
        return kw
    return {}


def cases(rng, n_random: int = 2, skip=("pumped-up",)) -> list:
    """``(name, params)``: defaults and declared extremes of every model, plus
    ``n_random`` random parameter sets (not for ``skip``: pumped-up tables take
    minutes per new base, so it keeps its declared variants)."""
    out = []
    seed = int(rng.integers(1 << 31))
    for name in plausible.names():
        out += [(name, kw) for kw in variants(name, 0)]
        if name not in skip:  # one stream per model: the same sets whatever else is registered
            r = np.random.default_rng([seed, zlib.crc32(name.encode())])
            out += [(name, random_params(name, r)) for _ in range(n_random)]
    return out


def _cmax(v) -> float:
    return float(np.max(v))


def _mix(ps, spec, diff):
    """``spec / ps + diff / (1 - ps)``, a lobe with zero bound contributing 0."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a = np.where(spec > 0, spec / ps, 0.0)
        b = np.where(diff > 0, diff / (1.0 - ps), 0.0)
    return np.where(np.isnan(a), np.inf, a) + np.where(np.isnan(b), np.inf, b)


def weight_bound(m, wi):
    """The analytic bound on ``sample(wi, u).weight`` (module docstring), per
    row of ``wi`` (shape (N, 3), unit, z > 0); ``None`` where none is derived."""
    ci = np.clip(wi[:, 2], 1e-150, 1.0)
    p, q, name = m.params, m.q, m.name
    one = np.ones_like(ci)
    if name == "lambertian":
        return _cmax(p["rd"]) * one
    if name == "ashikhmin-shirley-specular":
        return one
    if name in ("ashikhmin-shirley-diffuse", "ashikhmin-shirley"):
        diff = 28.0 / 23.0 * _cmax(np.asarray(p["rd"]) * (1 - np.asarray(p["rs"]))) * AS.diffuse_factor(ci)
        if name == "ashikhmin-shirley-diffuse":
            return diff
        return _mix(AS.specular_probability(NP, ci, q.rs, q.rd), one, diff)
    n = p.get("n")
    if name in ("reciprocal-phong", "phong"):
        return _cmax(p["ks"]) * (n + 2) / (n + 1) / (ci if name == "phong" else 1.0)
    if name in ("reciprocal-blinn", "blinn"):
        return 8 * math.pi * _cmax(p["ks"]) * PH.blinn_norm(NP, n) / (n + 1) / (ci if name == "blinn" else 1.0)
    if name == "modified-phong":
        ps = type(m).spec_probability(NP, q)
        return _mix(ps, _cmax(p["ks"]) * (n + 2) / (n + 1) * one, _cmax(p["kd"]) * one)
    if name == "neumann-metal":
        return 2 * math.pi * p["c"] / (n + 1) * one
    if name == "cook-torrance":
        return 2.0 * one if p["geometry"] == "vgroove" else 2.0 / ci ** 2
    if name == "ward":
        spec = {"ward": 1 / np.sqrt(ci), "duer": 1 / ci, "balanced": 2.0 * one}[p["variant"]]
        return _mix(type(m).spec_probability(NP, q), _cmax(p["rs"]) * spec, _cmax(p["rd"]) * one)
    if name == "schlick":
        ps = mixture_probabilities(NP, m.lobe_weights(NP, wi.T, q))[0]
        # azimuth="sqrt": f has sqrt(A) where the sampler has A, A in [p, 1/p]: 1/sqrt(p) more
        az = 1.0 / math.sqrt(p["p"]) if p["azimuth"] == "sqrt" else 1.0
        return _mix(ps, 2.0 * az / (p["r"] * ci), _cmax(p["rd"]) * one)
    if name == "pumped-up":
        b = weight_bound(m.base, wi)
        if b is None:
            return None
        g = np.prod([tab.lookup(NP, tuple(wi.T)) for tab in m.tables], axis=0)
        return b / g
    return None


__all__ = ["COSINES", "cases", "direction_pairs", "incidences", "random_params", "uniforms", "weight_bound"]
