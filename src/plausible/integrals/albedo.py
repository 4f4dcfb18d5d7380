"""Directional and hemispherical albedo.

The directional albedo ``a(wi) = int f(wi, wo) cos(theta_o) d omega_o`` is
computed by deterministic quadrature (:mod:`plausible.integrals.quadrature`) in
the half-vector frame (:func:`~.quadrature.half_vector_breaks`: the mirror
direction is an edge of the domain at every incidence, the horizon another): a
tensor Gauss-Legendre rule on panels graded toward the lobe, evaluated at two
orders and two floors; the differences are returned as the error bound.
Accurate to better than 1e-6 for the narrowest declared lobes (Cook-Torrance and
Ward at ``m = 1e-4`` up to ``cos(theta_i) = 0.02``, Ashikhmin-Shirley
``nu = 0, nv = 10^6``; tested against the model's sampler, an independent
half-vector quadrature and a closed form).  It uses only the model contract
(``eval`` and the optional ``peak_directions`` hint).  A lobe it cannot see
(one no hint points at) it cannot bound either; :func:`plausible.analysis.checks.energy`
therefore guards every albedo with the model's own sampler.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from dataclasses import dataclass

import numpy as np

from .. import arguments as A
from ..arrays import backend as _backend
from ..arrays.quadrature_sums import tensor_sums
from ..bxdf import BxDF
from ..directions import as_directions
from ..progress import start
from ..vec import direction as _direction
from .keys import exact_text
from .quadrature import half_vector_breaks, half_vector_level, half_vector_lune, half_vector_tmax, panel_rule


@dataclass(frozen=True)
class AlbedoResult:
    """``value`` (float, or per-channel array) and ``error``, an estimated bound
    on its absolute error (same shape)."""

    value: np.ndarray | float
    error: np.ndarray | float

    def __float__(self):
        return float(np.mean(self.value))

    # the numeric protocol: a result computes as its value (sum(results), a + 0,
    # 2 * a, a <= 1, np.asarray(a)); the error bound is dropped
    def __array__(self, dtype=None, copy=None):
        return np.asarray(self.value, dtype=dtype)

    def _repr_html_(self) -> str:
        from ..text import html_table

        v, e = np.atleast_1d(self.value).ravel(), np.atleast_1d(self.error).ravel()
        return html_table("AlbedoResult", ["value", "error bound"], [(f"{a:.6g}", f"{b:.1e}") for a, b in zip(v, e)])


def _value_op(name):
    op = getattr(np.ndarray, name, None) or getattr(float, name)

    def method(self, *other):
        return op(np.asarray(self.value, dtype=np.float64), *(np.asarray(o.value) if isinstance(o, AlbedoResult)
                                                             else o for o in other))
    method.__name__ = name
    return method


for _name in ("__add__", "__radd__", "__sub__", "__rsub__", "__mul__", "__rmul__", "__truediv__",
              "__rtruediv__", "__pow__", "__neg__", "__abs__", "__lt__", "__le__", "__gt__", "__ge__"):
    setattr(AlbedoResult, _name, _value_op(_name))


def direction(theta: float, phi: float = 0.0) -> np.ndarray:
    """Unit vector with polar angle ``theta`` and azimuth ``phi`` (radians):
    :func:`plausible.vec.direction` (``plausible.direction``), for one angle pair."""
    return _direction(float(theta), float(phi))


#: Gauss-Legendre orders of the panel rule, tried in turn (each against the one before).
ORDERS = (4, 6, 8, 12, 16)
#: The uniform floor of panels is refined at most this many times (the estimate
#: then uses twice as many); the finest rule has about 7 million nodes, the
#: budget of an integrand that never meets ``tol`` (a measured table, a lobe cut
#: off along a curve).
MAX_REFINE = 4
#: Default accuracy asked of :func:`albedo` (absolute, on the error bound).
TOL = 1e-6
#: Most levels of grading toward the lobe (``levels``, default 13): panels down to ``2^-60`` of the range.
MAX_LEVELS = 60
#: A polar segment that starts at a cut (a lune, a kink) at least ``2^-LIGHT_POLE_LEVELS`` of its
#: length away from the mirror direction takes the ``s`` rule without the pole's finer grading: its
#: panels near its start are then no larger than their distance to the pole, as the whole rule's
#: are near ``s = 0`` (:meth:`_Rules.nodes`).
LIGHT_POLE_LEVELS = 6


class _Rules:
    """The panel rules of one incidence in the half-vector frame
    (:func:`~.quadrature.half_vector_breaks`): breakpoints per floor refinement
    (cached) and the tensor rule's 1-D nodes and weights per ``(m, refine)``.

    For a model with :meth:`~plausible.bxdf.BxDF.mirror_cut` the polar range of
    every azimuth is cut in two at ``T1 = min(T, tmax)``, ``T`` the lune's edge
    ``R.wo = 0`` (:func:`~.quadrature.half_vector_lune`): the ``s`` rule runs once
    over ``[0, T1]`` and once over ``[T1, tmax]`` (where that is not empty), so
    the jump of a ``cos^0`` lobe is a panel edge as it is for the horizon."""

    def __init__(self, model, wi, levels, axes=True):
        self.model, self.wi, self.levels, self.axes = model, wi, levels, axes
        cut = getattr(model, "mirror_cut", None)
        self.lune = bool(cut()) if callable(cut) else False
        kink = getattr(model, "level_kink", None)
        self.kink = bool(kink()) if callable(kink) else False
        self.curves = callable(getattr(model, "kink_curves", None))     # BxDF.kink_curves: more kinks
        self.curves = self.curves and callable(getattr(model, "kink_azimuths", None))
        self._breaks = {}
        self._nodes = {}
        self.sums = {}

    def nodes(self, m, refine):
        """The tensor grids of the rule ``(m, refine)``, a list of ``(s, ws, phi, wp, t0, span)``:
        the nodes and weights in ``s`` and ``phi`` and the polar range ``[t0, t0 + span]`` of each
        azimuth node (the node of ``(s, phi)`` is the half vector at polar angle ``t0 + s span``;
        see :func:`_grid_sum`).  The first grid holds every azimuth's first polar segment (and
        the later segments that start near the pole); a second, where there are cuts, the
        later segments that start farther than ``2^-LIGHT_POLE_LEVELS`` of their length from the
        pole, on the ``s`` rule without the pole's finer levels (the whole rule's panels there
        would be far smaller than their distance to the pole: half of a split column's nodes).
        Computed once per ``(m, refine)`` (callers only read them)."""
        if (m, refine) not in self._nodes:
            self._nodes[(m, refine)] = self._make_nodes(m, refine)
        return self._nodes[(m, refine)]

    def _make_nodes(self, m, refine):
        if refine not in self._breaks:
            self._breaks[refine] = half_vector_breaks(self.wi, self.model.peak_directions(self.wi),
                                                      self.levels, refine, axes=self.axes, lune=self.lune,
                                                      azimuths=self.model.kink_azimuths(self.wi)
                                                      if self.curves else ())
        sb, pb = self._breaks[refine]
        s, ws = panel_rule(sb, m)
        p, wp = panel_rule(pb, m)
        tmax = half_vector_tmax(self.wi, p)
        cuts = self._cuts(p)
        if not cuts:
            return [(s, ws, p, wp, np.zeros_like(p), tmax)]
        edges = np.sort(np.vstack([np.zeros_like(p)] + [np.minimum(c, tmax) for c in cuts] + [tmax]), axis=0)
        on = edges[1] > 0.0         # an azimuth's first segment, where not empty (a cut at the pole: none)
        first = (s, ws, p[on], wp[on], np.zeros(int(on.sum())), edges[1][on])
        cols = [hi_ > lo_ * (1.0 + 1e-15) for lo_, hi_ in zip(edges[1:-1], edges[2:])]
        t0 = np.concatenate([lo_[c] for lo_, c in zip(edges[1:-1], cols)])
        span = np.concatenate([(hi_ - lo_)[c] for lo_, hi_, c in zip(edges[1:-1], edges[2:], cols)])
        pc, wpc = np.concatenate([p[c] for c in cols]), np.concatenate([wp[c] for c in cols])
        far = t0 >= span * 0.5 ** LIGHT_POLE_LEVELS       # far from the pole: the light rule
        near = (pc[~far], wpc[~far], t0[~far], span[~far])
        first = (s, ws, np.concatenate([first[2], near[0]]), np.concatenate([first[3], near[1]]),
                 np.concatenate([first[4], near[2]]), np.concatenate([first[5], near[3]]))
        if not far.any():
            return [first]
        sl, wsl = panel_rule(self.light_breaks(refine), m)
        return [first, (sl, wsl, pc[far], wpc[far], t0[far], span[far])]

    def light_breaks(self, refine):
        """The ``s`` breakpoints of :meth:`nodes`' second grid: the rule's, less those inside
        ``(0, 2^-LIGHT_POLE_LEVELS)``."""
        sb = self._breaks[refine][0]
        return sb[(sb <= 0.0) | (sb >= 0.5 ** LIGHT_POLE_LEVELS)]

    def _cuts(self, p):
        """The polar angles at each azimuth of ``p`` where a segment ends: the lune, the
        level kink, the model's kink curves."""
        cuts = []
        if self.lune:
            cuts.append(half_vector_lune(self.wi, p))
        if self.kink:
            cuts.append(half_vector_level(self.wi, p))
        if self.curves:
            cuts.extend(np.asarray(c, dtype=np.float64) for c in self.model.kink_curves(self.wi, p))
        return cuts

    def shared(self, m, refine):
        """Which nodes the rules ``(m, refine)`` and ``(m, 2 refine)`` share, grid by grid of
        :meth:`nodes`: a list of ``(s1, c1, s2, c2)``, boolean masks of the ``s`` nodes and the
        azimuth columns of each, true on the panels both floors have (the finer floor splits
        some panels and keeps the others; a kept panel's nodes are the same numbers).  None
        where the two have not the same grids or the shared nodes do not match exactly."""
        gs1, gs2 = self.nodes(m, refine), self.nodes(m, 2 * refine)
        if len(gs1) != len(gs2):
            return None
        out = []
        for j, (g1, g2) in enumerate(zip(gs1, gs2)):
            sb = [self._breaks[r][0] if j == 0 else self.light_breaks(r) for r in (refine, 2 * refine)]
            pb = [self._breaks[r][1] for r in (refine, 2 * refine)]
            s1, s2 = _kept_nodes(sb[0], sb[1], m)
            p1, p2 = _kept_nodes(pb[0], pb[1], m)
            c1 = np.isin(g1[2], panel_rule(pb[0], m)[0][p1])     # an azimuth column on a kept panel
            c2 = np.isin(g2[2], panel_rule(pb[1], m)[0][p2])
            same = (np.array_equal(g1[0][s1], g2[0][s2]) and np.array_equal(g1[1][s1], g2[1][s2])
                    and all(np.array_equal(g1[k][c1], g2[k][c2]) for k in range(2, 6)))
            if not same:
                return None
            out.append((s1, c1, s2, c2))
        return out


def _kept_nodes(b1, b2, m):
    """Boolean masks of the ``m``-point nodes of the panels ``b1`` and ``b2`` (breakpoints) on the
    panels both have (the same two ends)."""
    k1 = set(zip(b1[:-1].tolist(), b1[1:].tolist()))
    k2 = set(zip(b2[:-1].tolist(), b2[1:].tolist()))
    both = k1 & k2
    return tuple(np.repeat([(x, y) in both for x, y in zip(b[:-1].tolist(), b[1:].tolist())], m) for b in (b1, b2))


def _sums(model, kind, rules, requests):
    """Compute the tensor-rule sums ``requests = [(angle index, m, refine), ...]``
    and store them in ``rules[a].sums[(m, refine)]``: on Dr.Jit in one launch when
    the backend rule says so (:mod:`plausible.arrays.backend`), else with ``model.eval``
    (or ``pdf``) per grid (any object with the contract)."""
    if not requests:
        return
    pieces, parts = _pieces(rules, requests)
    grids = [g for _, g in pieces]
    total = sum(len(g[0]) * len(g[2]) for g in grids)
    if isinstance(model, BxDF) and _backend.choose(total, model, min_rows=_backend.AUTO_MIN_NODES,
                                                   kernel="quad-" + kind) == "drjit":
        def numpy():
            return [_grid_sum(model, kind, rules[a].wi, g) for a, g in pieces]

        res = _backend.run(model, "quadrature", numpy, lambda: _jit_sums(model, kind, rules, pieces))
    else:
        res = [_grid_sum(model, kind, rules[a].wi, g) for a, g in pieces]
    for (a, m, r), idx in zip(requests, parts):
        v = res[idx[0]]
        for k in idx[1:]:
            v = v + res[k]
        rules[a].sums[(m, r)] = v if np.ndim(v) else float(v)


def _pieces(rules, requests):
    """The tensor grids that give the sums of ``requests``: ``(pieces, parts)``, each
    piece ``(angle index, grid)`` and each request's sum the sum of its ``parts``'
    pieces.  A request's grid is one piece, but for a pair ``(m, r)``, ``(m, 2 r)`` of one
    incidence in the same call (the first step's ``(6, 1)`` and ``(6, 2)``, and every
    step that raises the order): the nodes the two share (the panels the finer floor
    keeps, :meth:`_Rules.shared`: 40-50 % of the finer rule's for an anisotropic lobe)
    are one piece, counted in both sums, and each rule's other nodes two more (its new
    polar nodes by all its azimuths, the shared polar nodes by its new azimuths)."""
    pieces, parts = [], []
    index = {req: k for k, req in enumerate(requests)}
    done = {}
    for req in requests:
        a, m, r = req
        if req in done:
            parts.append(done.pop(req))
            continue
        fine = (a, m, 2 * r)
        masks = rules[a].shared(m, r) if fine in index else None
        if masks is None:
            grids = rules[a].nodes(m, r)
            parts.append(list(range(len(pieces), len(pieces) + len(grids))))
            pieces += [(a, g) for g in grids]
            continue
        mine = [[], []]
        for g1, g2, mk in zip(rules[a].nodes(m, r), rules[a].nodes(m, 2 * r), masks):
            grids, ids1, ids2 = _split_pair(g1, g2, mk)
            mine[0] += [len(pieces) + i for i in ids1]
            mine[1] += [len(pieces) + i for i in ids2]
            pieces += [(a, g) for g in grids]
        parts.append(mine[0])
        done[fine] = mine[1]
    return pieces, parts


def _split_pair(g1, g2, masks):
    """The pieces of one grid of the rules ``(m, r)`` and ``(m, 2 r)`` (:func:`_pieces`):
    ``(grids, ids1, ids2)``, the sub-grids and which of them each rule's sum adds."""
    s1, c1, s2, c2 = masks
    grids, mine = [], []
    for g, sm, cm in ((g1, s1, c1), (g2, s2, c2)):
        ids = []
        for si, ci in ((~sm, slice(None)), (sm, ~cm)):
            sub = _subgrid(g, si, ci)
            if len(sub[0]) and len(sub[2]):
                ids.append(len(grids))
                grids.append(sub)
        mine.append(ids)
    shared = _subgrid(g1, s1, c1)
    common = []
    if len(shared[0]) and len(shared[2]):
        common = [len(grids)]
        grids.append(shared)
    if not common + mine[0] or not common + mine[1]:     # nothing to sum: keep whole grids
        grids, mine, common = [g1, g2], [[0], [1]], []
    return grids, common + mine[0], common + mine[1]


def _subgrid(g, s_mask, col_mask):
    """The grid ``g`` of :meth:`_Rules.nodes` on the ``s`` nodes ``s_mask`` and the azimuth
    columns ``col_mask`` (a boolean mask or a slice)."""
    s, ws, p, wp, t0, span = g
    return (s[s_mask], ws[s_mask], p[col_mask], wp[col_mask], t0[col_mask], span[col_mask])


def _jit_sums(model, kind, rules, pieces):
    """:func:`plausible.arrays.quadrature_sums.tensor_sums` of the grids of ``pieces``
    (``(angle index, grid)``): one launch for all of them."""
    return tensor_sums(model, kind, [(rules[a].wi, s, ws, p, wp, t0, span) for a, (s, ws, p, wp, t0, span) in pieces])


def _grid_sum(model, kind, wi, grid):
    """One tensor-rule sum through the contract (``eval`` or ``pdf`` on the grid):
    the node ``(s, phi)`` is the half vector ``h`` at polar angle ``t = t0 + s span``,
    the direction ``wo = 2 (wi.h) h - wi`` and the weight
    ``ws wp span sin(t) 4 (wi.h)`` (``d omega_o = 4 (wi.h) d omega_h``)."""
    s, ws, p, wp, t0, tmax = grid
    t = t0[None, :] + s[:, None] * tmax[None, :]
    st, ct = np.sin(t), np.cos(t)
    h = np.stack(np.broadcast_arrays(st * np.cos(p)[None, :], st * np.sin(p)[None, :], ct), axis=-1)
    d = h @ wi
    wo = 2.0 * d[..., None] * h - wi
    if kind == "f":
        vals = model.eval(wi, wo)
        c = wo[..., 2]
        vals = vals * (c[..., None] if vals.ndim == c.ndim + 1 else c)
    else:
        vals = model.pdf(wi, wo)
    w = ws[:, None] * (wp * tmax)[None, :] * st * (4.0 * d)
    if vals.ndim == w.ndim + 1:
        w = w[..., None]
    return np.sum(vals * w, axis=(0, 1))


def pdf_phi_sums(model, wi, theta, theta_w, phi) -> np.ndarray:
    """``sum_i theta_w[i] pdf(wi, wo(theta[i], phi[j]))`` for every ``j``: a tensor
    rule's pdf integrated over ``theta`` at each azimuth node (the chi-square
    test's cells, :mod:`plausible.analysis.chi2`): :func:`pdf_phi_sums_many` of one grid."""
    return pdf_phi_sums_many(model, wi, [(theta, theta_w, phi)])[0]


#: Nodes per ``model.pdf`` call of :func:`pdf_phi_sums_many` on NumPy (grids are
#: grouped up to this size: one call validates many small grids, and no call
#: holds more than a few hundred megabytes).
NUMPY_GROUP = 1 << 20


def pdf_phi_sums_many(model, wi, grids) -> list:
    """:func:`pdf_phi_sums` of many grids ``[(theta, theta_w, phi), ...]`` at one
    incidence ``wi`` (shape ``(3,)``) or each at its own (``wi`` of shape
    ``(len(grids), 3)``), computed together: one Dr.Jit launch for all of them when the
    backend rule says so (for their total node count), else ``model.pdf`` on
    groups of grids (:data:`NUMPY_GROUP` nodes).  Returns one array per grid,
    of its ``len(phi)``."""
    grids = [tuple(np.asarray(x, dtype=np.float64) for x in g) for g in grids]
    wi = np.asarray(wi, dtype=np.float64)
    wi = np.broadcast_to(wi, (len(grids), 3)) if wi.shape == (3,) else wi
    if wi.shape != (len(grids), 3):
        raise ValueError(f"pdf_phi_sums_many: wi must have shape (3,) or ({len(grids)}, 3), got {wi.shape}")
    n = sum(len(t) * len(p) for t, _, p in grids)

    def numpy():
        return _numpy_phi_sums(model, wi, grids)

    if grids and isinstance(model, BxDF) and _backend.choose(n, model, min_rows=_backend.AUTO_MIN_NODES,
                                                             kernel="phi-pdf") == "drjit":
        def jit():
            return tensor_sums(model, "pdf", [(w, t, tw, p, np.ones_like(p), None, None)
                                              for w, (t, tw, p) in zip(wi, grids)], per_phi=True)

        return _backend.run(model, "quadrature", numpy, jit)
    return numpy()


def _numpy_phi_sums(model, wi, grids):
    """:func:`pdf_phi_sums_many` with ``model.pdf`` (``wi``: one row per grid)."""
    out, group, size = [], [], 0
    one = bool(np.all(wi == wi[:1]))    # one incidence: a (3,) wi, as the contract's simplest call
    for k, g in enumerate(grids):
        group.append(k)
        size += len(g[0]) * len(g[2])
        if size >= NUMPY_GROUP or k == len(grids) - 1:
            wo = np.concatenate([_wo_grid(grids[a][0], grids[a][2]).reshape(-1, 3) for a in group])
            counts = [len(grids[a][0]) * len(grids[a][2]) for a in group]
            pdf = model.pdf(np.array(wi[0]) if one else np.repeat(wi[group], counts, axis=0), wo)
            at = 0
            for a, c in zip(group, counts):
                t, w, p = grids[a]
                cell = pdf[at:at + c].reshape(len(t), len(p))
                out.append((cell * w[:, None]).sum(axis=0))
                at += c
            group, size = [], 0
    return out


def _wo_grid(theta, phi):
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st[:, None] * np.cos(phi)[None, :],
                                        st[:, None] * np.sin(phi)[None, :], np.cos(theta)[:, None]), axis=-1)


def _integrate(model, kind, wis, tol, levels):
    """Integrals of ``f cos`` (``kind="f"``) or the pdf over the upper hemisphere for
    the unit incidences ``wis`` (rows), each refined until its error bound meets
    ``tol`` (or the finest rule is reached).  Returns ``(values, errors)``.

    Per incidence, with ``I(m, refine)`` the ``m``-point rule on the graded panels
    of the ``refine``-times finer uniform floor (:func:`~.quadrature.lobe_breaks`)
    and ``m'`` the order before ``m`` in :data:`ORDERS`: the estimate is
    ``I(m, 2 refine)`` and its bound the sum of ``|I(m) - I(m')|`` (the
    lower-order rule's error, which bounds the higher one's for smooth
    integrands) and ``|I(m, 2 refine) - I(m, refine)|`` (a kink or a jump inside
    a panel, where both orders err alike and only smaller panels help), plus
    ``1e-13`` relative: both differences are errors of rules coarser than the
    estimate, and their sum (not the larger) stays honest where a jump makes
    the convergence uneven (a ``cos^0`` lobe cut off at its lune: tested
    against the closed form).  While the bound exceeds ``tol``, the larger of the two causes is
    refined: the next order, or a 2x finer floor.  All incidences still
    refining are computed together (on Dr.Jit, one launch per rule)."""
    axes = not is_isotropic(model)   # grade toward the tangent axes only where they matter
    rules = [_Rules(model, wi, levels, axes) for wi in wis]
    state = {a: (1, 1) for a in range(len(wis))}   # index into ORDERS, floor refinement
    values, errors = [None] * len(wis), [None] * len(wis)
    while state:
        need = []
        for a, (k, r) in state.items():
            for key in ((ORDERS[k - 1], r), (ORDERS[k], r), (ORDERS[k], 2 * r)):
                if key not in rules[a].sums:
                    need.append((a,) + key)
        _sums(model, kind, rules, sorted(set(need)))
        for a, (k, r) in list(state.items()):
            s = rules[a].sums
            lo, hi, fine = s[(ORDERS[k - 1], r)], s[(ORDERS[k], r)], s[(ORDERS[k], 2 * r)]
            e_order, e_floor = np.abs(hi - lo), np.abs(fine - hi)
            err = e_order + e_floor + 1e-13 * np.abs(fine)
            values[a], errors[a] = fine, err
            last_k, last_r = k == len(ORDERS) - 1, r >= MAX_REFINE
            if np.all(err <= tol) or (last_k and last_r):
                del state[a]
            elif last_r or (not last_k and np.max(e_order) >= np.max(e_floor)):
                state[a] = (k + 1, r)
            else:
                state[a] = (k, 2 * r)
    return values, errors


def quadrature_reach(model, wi, *, levels: int = 13, probes: int = 10_000, axes: bool | None = None) -> float:
    """What :func:`albedo` at ``wi`` cannot see: the largest angle (radians) between an
    outgoing direction of the upper hemisphere and the nearest node of the finest rule of
    the first refinement step (order 6 on the twice finer floor, the half-vector frame graded
    toward the mirror direction, the horizon, the model's ``peak_directions`` and, where
    ``axes``, the tangent axes; the extra panel edges of a lune or a kink, which only add
    nodes, left out).  A lobe narrower than this, centred in such a gap and away from every
    hint, adds next to nothing to the first step's sums, so its bound stays small and the
    integration stops there: the lobe is missed.

    Measured on ``probes`` directions of a Fibonacci lattice, and returned plus the lattice's
    spacing ``sqrt(2 pi / probes)`` (0.025 rad by default; every direction lies within it of
    a probe, so the sum bounds the gap from above): each probe's half vector is placed in the tensor rule (``s`` and
    ``phi`` node arrays, by bisection) and its distance to the 3 x 3 nodes around it taken in
    ``wo`` (3 x 4: the map from ``h`` to ``wo`` is not linear).  ``axes`` defaults to :func:`is_isotropic`'s answer."""
    wi = _unit_incidence(wi)
    if wi[2] <= 0:
        return math.pi
    rules = _Rules(model, wi, levels, (not is_isotropic(model)) if axes is None else axes)
    rules.lune = rules.kink = rules.curves = False
    s, _, p, _, _, tmax = rules.nodes(ORDERS[1], 2)[0]
    k = np.arange(probes) + 0.5
    z = 1.0 - k / probes                       # a Fibonacci lattice on the upper hemisphere
    a = k * math.pi * (3.0 - math.sqrt(5.0))
    q = np.stack([np.sqrt(1 - z * z) * np.cos(a), np.sqrt(1 - z * z) * np.sin(a), z], axis=-1)
    h = q + wi
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    lo = p[0] - 0.5 * (p[0] + 2 * math.pi - p[-1])     # the azimuth range of the rule, periodic
    ph = lo + (np.arctan2(h[:, 1], h[:, 0]) - lo) % (2 * math.pi)
    th = np.arccos(np.clip(h[:, 2], -1.0, 1.0))
    j = np.searchsorted(p, ph)[:, None] + np.arange(-2, 1)[None, :]
    j = j % len(p)
    sq = th[:, None] / tmax[j]
    best = np.full(probes, np.inf)
    for c in range(j.shape[1]):
        ii = np.searchsorted(s, sq[:, c])
        for di in (-2, -1, 0, 1):
            n = np.clip(ii + di, 0, len(s) - 1)
            t = s[n] * tmax[j[:, c]]
            pc = p[j[:, c]]
            hn = np.stack([np.sin(t) * np.cos(pc), np.sin(t) * np.sin(pc), np.cos(t)], axis=-1)
            wo = 2.0 * (hn @ wi)[:, None] * hn - wi
            best = np.minimum(best, np.arccos(np.clip(np.sum(wo * q, axis=-1), -1.0, 1.0)))
    return float(np.max(best)) + math.sqrt(2.0 * math.pi / probes)


def _unit_incidence(wi):
    if np.ndim(wi) == 0 and isinstance(wi, (int, float, np.number)):
        raise ValueError(f"wi must be a direction (x, y, z), got the number {wi!r}; for an incidence "
                         f"angle use plausible.direction(theta) with theta in radians, e.g. "
                         f"albedo(m, plausible.direction(math.radians({wi!r})))")
    wi = as_directions("wi", wi)  # names wi and the value in every error (a string, NaN, a zero vector)
    if wi.shape != (3,):
        raise ValueError(f"wi must be one direction of shape (3,), got {wi.shape}")
    return wi


def _check_tol(tol):
    if not (isinstance(tol, (int, float)) and math.isfinite(tol) and tol > 0):
        raise ValueError(f"tol must be a positive number (absolute error bound), got {tol!r}")
    return float(tol)


# -- remembered integrals (the figures) -------------------------------------------------

#: The integrals remembered while :func:`remembering` is active (else None):
#: ``(model text, kind, tol, levels, incidence) -> AlbedoResult``.
_MEMORY: dict | None = None


@contextmanager
def remembering():
    """Within this block, every integral of :func:`albedo`, :func:`albedos`,
    :func:`pdf_integral` and :func:`pdf_integrals` is remembered in this process and
    not computed again when asked again for the same model (its exact text,
    :func:`.keys.exact_text`), incidence, ``tol`` and ``levels``: the same albedo in two
    figures made by one process, or twice in one figure.  The result is the one the
    first call computed (each incidence is refined on its own, so it is the value a
    second computation gives, up to the rounding of a launch's sums).  Off by default:
    a caller that compares two computations (backends, a cache) must compute both.
    Used by ``plausible figures``; nested blocks share the outermost memory."""
    global _MEMORY
    outer = _MEMORY
    if outer is None:
        _MEMORY = {}
    try:
        yield _MEMORY
    finally:
        if outer is None:
            _MEMORY = None


def _copy(r: AlbedoResult) -> AlbedoResult:
    """A remembered result handed out: its arrays copied (a caller may change them in place)."""
    if np.ndim(r.value) == 0:
        return r
    return AlbedoResult(np.array(r.value, dtype=np.float64), np.array(r.error, dtype=np.float64))


def _results(model, kind, wis, tol, levels):
    """:func:`_integrate` for any incidences (zero below the horizon), as results
    (remembered within :func:`remembering`)."""
    A.count("levels", levels, 1, MAX_LEVELS)
    if isinstance(model, str):          # was an AttributeError about 'channels'
        raise ValueError(f"model must be a model object, got the string {model!r}: pass plausible.make({model!r}) "
                         f"(plausible.check takes a spec string; the integrals take the model)")
    if not callable(getattr(model, "eval", None)):
        raise ValueError(f"model must have the contract's eval(wi, wo) (a plausible model, or "
                         f"plausible.analysis.as_bxdf(obj) of a Mitsuba BSDF or a callable), got {type(model).__name__}")
    zero = np.zeros(model.channels) if (kind == "f" and model.channels) else 0.0
    memory = _MEMORY
    mk = exact_text(model) if memory is not None else None
    out = [AlbedoResult(zero, zero)] * len(wis)
    up, keys = [], {}
    for k, w in enumerate(wis):
        if w[2] <= 0:
            continue
        if mk is not None:
            keys[k] = (mk, kind, float(tol), int(levels), tuple(float(x) for x in w))
            if keys[k] in memory:
                out[k] = _copy(memory[keys[k]])
                continue
        up.append(k)
    vals, errs = _integrate(model, kind, [wis[k] for k in up], tol, levels) if up else ([], [])
    for k, v, e in zip(up, vals, errs):
        out[k] = AlbedoResult(float(v), float(e)) if np.ndim(v) == 0 else AlbedoResult(v, e)
        if mk is not None:
            memory[keys[k]] = _copy(out[k])
    return out


def albedo(model, wi, *, tol: float = TOL, levels: int = 13) -> AlbedoResult:
    """Directional albedo ``a(wi) = int f(wi, wo) cos(theta_o) d omega_o``.

    ``wi`` is a direction of shape (3,) (normalised here).  The quadrature is
    refined until its error bound is at most ``tol`` (absolute; default 1e-6) and
    stops there (see :func:`_integrate`).  Returns :class:`AlbedoResult`: the value
    and the bound reached (which exceeds ``tol`` only where the finest rule, order
    16 on an 8x finer floor, does not meet it).  Zero for ``wi`` below the horizon.
    """
    return _results(model, "f", [_unit_incidence(wi)], _check_tol(tol), levels)[0]


def albedos(model, wis, *, tol: float = TOL, levels: int = 13) -> list:
    """:func:`albedo` at many incidences ``wis`` (rows of shape (3,)), refined
    together (on Dr.Jit, each refinement step is one launch for all of them)."""
    tol = _check_tol(tol)
    return _results(model, "f", [_unit_incidence(w) for w in wis], tol, levels)


def pdf_integral(model, wi, *, tol: float = TOL, levels: int = 13) -> AlbedoResult:
    """``int pdf(wi, wo) d omega_o`` over the upper hemisphere (pdf is zero below),
    refined to ``tol`` like :func:`albedo`."""
    r = _results(model, "pdf", [_unit_incidence(wi)], _check_tol(tol), levels)[0]
    return AlbedoResult(float(r.value), float(r.error))


def pdf_integrals(model, wis, *, tol: float = TOL, levels: int = 13) -> list:
    """:func:`pdf_integral` at many incidences, refined together (like :func:`albedos`)."""
    tol = _check_tol(tol)
    res = _results(model, "pdf", [_unit_incidence(w) for w in wis], tol, levels)
    return [AlbedoResult(float(r.value), float(r.error)) for r in res]


def albedo_curve(model, thetas=None, phi: float = 0.0, progress=None, *, thetas_deg=None,
                 phi_deg=None, **kw) -> AlbedoResult:
    """Directional albedo at polar angles ``thetas`` and azimuth ``phi``
    (radians), or ``thetas_deg`` and ``phi_deg`` (degrees): give one of each pair.

    Returns an :class:`AlbedoResult` whose ``value``/``error`` have shape
    ``(len(thetas),)`` (plus a channel axis for colour models).  All angles are
    integrated together (:func:`albedos`; ``tol`` and ``levels`` pass on).
    ``progress``: a :mod:`plausible.progress` factory, ticked once per angle.
    ``thetas`` beyond ``pi/2`` are refused as likely degrees.
    """
    if (thetas is None) == (thetas_deg is None):
        raise ValueError("give the incidence angles as thetas (radians) or thetas_deg (degrees), not "
                         + ("both" if thetas is not None else "neither"))
    if phi_deg is not None:
        if phi != 0.0:
            raise ValueError("give the azimuth as phi (radians) or phi_deg (degrees), not both")
        phi = math.radians(float(phi_deg))
    if thetas is None:
        thetas = np.radians(np.asarray(thetas_deg, dtype=np.float64))
    thetas = np.atleast_1d(np.asarray(thetas, dtype=np.float64))
    if np.any(~np.isfinite(thetas)) or np.any(thetas < 0) or np.any(thetas > math.pi / 2):
        bad = thetas[~(np.isfinite(thetas) & (thetas >= 0) & (thetas <= math.pi / 2))]
        hint = (" (degrees? pass thetas_deg=..., or np.radians(thetas))"
                if np.all(np.isfinite(bad)) and np.all(bad > math.pi / 2) and np.all(bad <= 90) else "")
        raise ValueError(f"thetas must lie in [0, pi/2] radians, got {float(bad[0]):g}{hint}")
    tick = start(progress, len(thetas), f"albedo {model.name}")
    res = albedos(model, [direction(t, phi) for t in thetas], **kw)
    tick(len(res))
    return AlbedoResult(np.array([r.value for r in res]), np.array([r.error for r in res]))


def is_isotropic(model, trials: int = 16, seed: int = 7) -> bool:
    """Probe the contract: does rotating both directions about the normal leave ``f``
    unchanged (relative 1e-9) on random pairs, and on pairs near the mirror
    direction at angular offsets 1e-1 to 1e-5 rad (where a narrow lobe is
    non-zero: Ward with ``alpha_x = 1e-4`` is zero on every random pair)?

    An object that declares its isotropy (``isotropic``, a bool: a Mitsuba BSDF's
    ``Anisotropic`` flag, read by :class:`plausible.analysis.mitsuba_bsdf.MitsubaBSDF`, since the
    probe's 1e-9 would find float32 rounding anisotropic) is taken at its word."""
    declared = getattr(model, "isotropic", None)
    if isinstance(declared, bool):
        return declared
    rng = np.random.default_rng(seed)
    wi = _random_upper(rng, trials)
    wo = _random_upper(rng, trials)
    near_i = np.repeat(_random_upper(rng, trials), 5, axis=0)
    mirror = near_i * np.array([-1.0, -1.0, 1.0])
    eps = np.tile(10.0 ** -np.arange(1, 6), trials)[:, None]
    side = np.cross(mirror, rng.normal(size=mirror.shape))
    side /= np.linalg.norm(side, axis=-1, keepdims=True)
    near_o = mirror * np.cos(eps) + side * np.sin(eps)
    near_o[:, 2] = np.abs(near_o[:, 2])
    wi, wo = np.concatenate([wi, near_i]), np.concatenate([wo, near_o])
    a = rng.uniform(0, 2 * math.pi, len(wi))
    c, s = np.cos(a), np.sin(a)

    def rot(w):
        return np.stack([c * w[:, 0] - s * w[:, 1], s * w[:, 0] + c * w[:, 1], w[:, 2]], axis=-1)

    f1 = model.eval(wi, wo)
    f2 = model.eval(rot(wi), rot(wo))
    scale = np.maximum(np.abs(f1), np.abs(f2)) + 1e-300
    return bool(np.all(np.abs(f1 - f2) <= 1e-9 * scale + 1e-14))


def _random_upper(rng, n):
    z = rng.uniform(0.05, 1.0, n)
    p = rng.uniform(0, 2 * math.pi, n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(p), s * np.sin(p), z], axis=-1)


def hemispherical_albedo(model, *, n_theta: int = 16, n_phi: int | None = None) -> AlbedoResult:
    """Cosine-weighted average of the directional albedo over the hemisphere,
    ``(1/pi) int a(wi) cos(theta_i) d omega_i = 2 int_0^1 a(mu) mu d mu`` (isotropic),
    by Gauss-Legendre in ``mu = cos(theta_i)`` (and in azimuth for anisotropic models)."""
    from .quadrature import gauss_legendre

    A.count("n_theta", n_theta, 1)
    if n_phi is not None:
        A.count("n_phi", n_phi, 1)
    x, w = gauss_legendre(n_theta)
    mu = 0.5 * (x + 1.0)
    wmu = 0.5 * w * 2.0 * mu  # 2 mu d mu on [0, 1]
    if n_phi is None:
        n_phi = 1 if is_isotropic(model) else 8
    phis = (np.arange(n_phi) + 0.5) * (2 * math.pi / n_phi)
    grid = [(ph, m_, wm) for ph in phis for m_, wm in zip(mu, wmu)]
    res = albedos(model, [direction(math.acos(m_), ph) for ph, m_, _ in grid])
    tot = sum(wm * np.asarray(r.value) / n_phi for (_, _, wm), r in zip(grid, res))
    err = sum(wm * np.asarray(r.error) / n_phi for (_, _, wm), r in zip(grid, res))
    if np.ndim(tot) == 0:
        return AlbedoResult(float(tot), float(err))
    return AlbedoResult(tot, err)


def albedo_table(model, *, n_phi: int | None = None, n_theta: int = 46, max_theta: int = 361,
                 tol: float = 1e-4, progress=None):
    """The directional albedo of ``model`` tabulated over the hemisphere, as an
    :class:`~plausible.tables.AngleTable` (Catmull-Rom interpolation).

    1-D in the polar angle for an isotropic model (:func:`is_isotropic`), 2-D with
    ``n_phi`` azimuths (default 32) otherwise.  For a colour model the table holds
    the largest channel.  The polar grid starts with ``n_theta`` nodes (2 degrees)
    and is halved while the interpolation error, estimated at the new nodes from
    the coarser table and divided by 8 (the ``O(h^3)`` rate), exceeds ``tol``, up to
    ``max_theta`` nodes; each node's albedo is integrated to ``tol / 10`` (all the
    nodes of a step together, :func:`albedos`).  The node on the horizon is
    evaluated 1e-6 rad above it (at exactly 90 degrees the albedo is zero by
    convention, not by continuity).  ``progress``: a :mod:`plausible.progress`
    factory, announced once per refinement level (the number of albedos it
    evaluates) and ticked when they are done.
    """
    from ..tables import HALF_PI, AngleTable

    if n_phi is None:
        n_phi = 0 if is_isotropic(model) else 32
    phis = np.arange(n_phi) * (2 * math.pi / n_phi) if n_phi else np.zeros(1)

    def columns(ths):
        """Albedos at polar angles ``ths`` (all azimuths), integrated together to
        ``tol / 10`` (a share of the error budget: node errors add at most 10 % to
        the interpolation error)."""
        tick = start(progress, len(ths) * len(phis), f"albedo table {model.name}")
        dirs = [direction(min(t, HALF_PI - 1e-6), ph) for t in ths for ph in phis]
        # in about 20 batches, for a progress bar that moves (each albedo is refined on its
        # own, so the batches give the same values as one call; an anisotropic base with an
        # exponent of 1e4 integrates 11,552 albedos for 12 minutes)
        res, step = [], max(64, -(-len(dirs) // 20))
        for k in range(0, len(dirs), step):
            res += albedos(model, dirs[k:k + step], tol=tol / 10)
            tick(len(dirs[k:k + step]))
        vals = np.array([np.max(np.atleast_1d(r.value)) for r in res]).reshape(len(ths), len(phis))
        return vals if n_phi else vals[:, 0]

    thetas = np.linspace(0.0, HALF_PI, n_theta)
    vals = columns(thetas)
    while True:
        coarse = AngleTable(vals)
        n = 2 * len(vals) - 1
        if n > max_theta:
            return coarse
        mids = 0.5 * (thetas[:-1] + thetas[1:])
        new = columns(mids)
        guess = coarse.lookup_angles(mids, phis if n_phi else None)
        fine = np.empty((n,) + vals.shape[1:])
        fine[0::2] = vals
        fine[1::2] = new
        thetas = np.linspace(0.0, HALF_PI, n)
        vals = fine
        if np.max(np.abs(guess - new)) / 8.0 <= tol:
            return AngleTable(vals)
