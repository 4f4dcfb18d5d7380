"""Pearson chi-square goodness-of-fit test of ``sample`` against ``pdf``.

Stages (as in Mitsuba 3's ``mitsuba.chi2.ChiSquareTest``, with the binning and
the integration adapted to sharp lobes).  Stages 1-2 are a *binning*, an object
whose ``cells(model, wi)`` returns the :class:`Cells` (edges and expected
fractions): :class:`AdaptiveBinning` by default, :class:`FixedBinning` for the
naive test; :func:`_histogram` counts the samples in them, :func:`_pool` is
stage 3 and :func:`_statistic` stage 4.

1. **Cells.**  The hemisphere is cut into ``n_theta`` bands in ``theta_o`` and,
   within each band, ``n_phi`` cells in ``phi_o``, at the quantiles of the
   pdf itself (a pilot quadrature): every cell expects about the same number of
   samples, so a lobe of width 10^-2 rad is resolved as finely as a diffuse one
   and the test has power where the samples are.  Below the horizon is one more
   cell: the samples the sampler declares invalid (pdf 0), expected
   ``N (1 - int pdf)`` times.
2. **Expected counts.**  The pdf is integrated over each cell with Gauss-Legendre
   panels whose breakpoints are the cell edges *and* the graded breakpoints of
   :mod:`plausible.integrals.quadrature` (refined toward the lobe), so the
   integral is accurate for exponents of 10^4 at grazing incidence, where a
   fixed grid with a trapezoid or midpoint rule is not (``method="fixed"``
   reproduces that naive test, for comparison).
3. **Pooling.**  Cells expecting fewer than ``min_expected`` samples are pooled;
   a cell with observed samples but zero expectation fails outright.
4. **Statistic.**  Pearson's statistic, ``scipy.special.chdtrc`` (``scipy.stats.chi2.sf``) for the p-value;
   the significance is Sidak-corrected for ``n_tests`` tests:
   ``alpha_1 = 1 - (1 - alpha)^(1 / n_tests)``.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from .. import arguments as A

from ..bxdf import Sample
from ..text import jsonable
from ..integrals.albedo import pdf_phi_sums_many
from ..integrals.quadrature import HALF_PI, hemisphere_grid, lobe_breaks, panel_rule

__all__ = ["AdaptiveBinning", "BINNINGS", "Cells", "Chi2Result", "FixedBinning", "chi2", "chi2_many", "sidak"]


@dataclass
class Chi2Result:
    """Outcome of :func:`chi2`.

    Attributes
    ----------
    passed : bool
        ``p_value >= alpha``.
    p_value : float
        Probability of a statistic at least this large if ``sample`` draws from
        ``pdf`` (0 when samples fell where the pdf integrates to zero).
    statistic : float
        Pearson's ``sum (observed - expected)^2 / expected`` over the pooled cells
        (inf for the zero-cell failure).
    dof : int
        Degrees of freedom: pooled cells - 1 (0 for the zero-cell failure).
    alpha : float
        The per-test significance, Sidak-corrected (:func:`sidak`).
    n_samples : int
        Samples drawn.
    n_cells : int
        Cells compared, after pooling (with the cell of invalid samples).
    wi : list
        The incidence direction (unit vector).
    message : str
        One line: the verdict and its figures, or what failed.
    worst_cells : list of dict
        The cells contributing most to the statistic (at most five), each with
        its ``theta_deg`` and ``phi_deg`` range (or a ``cell`` description),
        ``observed``, ``expected`` and ``contribution``.
    """

    passed: bool
    p_value: float
    statistic: float
    dof: int
    alpha: float
    n_samples: int
    n_cells: int
    wi: list
    message: str
    worst_cells: list = field(default_factory=list)

    def to_dict(self):
        return jsonable(asdict(self))


def sidak(alpha: float, n_tests: int) -> float:
    """Per-test significance keeping the family-wise error at ``alpha``."""
    return 1.0 - (1.0 - alpha) ** (1.0 / max(n_tests, 1))


def _angles_of(wo, phi0):
    theta = np.arccos(np.clip(wo[..., 2], -1, 1))
    phi = np.arctan2(wo[..., 1], wo[..., 0])
    phi = phi0 + np.mod(phi - phi0 + math.pi, 2 * math.pi) - math.pi
    return theta, phi


def _quantile_edges(nodes, mass, lo, hi, k):
    cum = np.cumsum(mass)
    tot = cum[-1] if len(cum) else 0.0
    if tot <= 0:
        return np.linspace(lo, hi, k + 1)
    targets = tot * np.arange(1, k) / k
    inner = nodes[np.minimum(np.searchsorted(cum, targets), len(nodes) - 1)]
    e = np.unique(np.concatenate([[lo], inner, [hi]]))
    return e[np.concatenate([[True], np.diff(e) > 1e-12])]


def _pdf_grid(model, wi, tn, pn):
    st, ct = np.sin(tn), np.cos(tn)
    wo = np.stack(np.broadcast_arrays(st[:, None] * np.cos(pn)[None, :],
                                      st[:, None] * np.sin(pn)[None, :], ct[:, None]), axis=-1)
    return model.pdf(wi, wo)


@dataclass
class Cells:
    """The cells of one test: the ``theta_o`` band edges ``t_edges`` (radians), and
    per band ``(theta_lo, theta_hi, phi_edges, expected)``, ``expected`` the
    integral of the pdf over each cell of the band (a fraction of the samples);
    ``phi_edges`` span ``[phi0 - pi, phi0 + pi]``."""

    t_edges: np.ndarray
    bands: list
    phi0: float


@dataclass(frozen=True)
class AdaptiveBinning:
    """Stages 1-2 of the module docstring: ``n_theta`` bands and ``n_phi`` cells per
    band at the quantiles of the pdf, expected counts by graded Gauss-Legendre
    panels of ``m`` nodes, refined until they settle."""

    n_theta: int = 16
    n_phi: int = 16
    m: int = 8
    #: A band's cell integrals have settled when a refinement changes each by at most
    #: ``settle`` times the mean cell's (plus 1e-12).
    settle: float = 1e-4

    def cells(self, model, wi) -> Cells:
        return self.cells_many(model, [wi])[0]

    def cells_many(self, model, wis) -> list:
        """:meth:`cells` of each incidence of ``wis``, integrated together (every
        refinement step of every incidence in one launch)."""
        return [Cells(*c) for c in _adaptive_cells(model, wis, self.n_theta, self.n_phi, self.m, self.settle)]


@dataclass(frozen=True)
class FixedBinning:
    """The naive test, for comparison: cells uniform in ``(cos theta, phi)``, the pdf
    integrated with an ``ires x ires`` midpoint rule per cell (what a fixed coarse
    grid does; it misses sharp lobes at grazing incidence)."""

    n_theta: int = 16
    n_phi: int = 16
    ires: int = 4

    def cells(self, model, wi) -> Cells:
        return Cells(*_fixed_cells(model, wi, self.n_theta, self.n_phi, self.ires))

    def cells_many(self, model, wis) -> list:
        """:meth:`cells` of each incidence of ``wis``."""
        return [self.cells(model, wi) for wi in wis]


#: The binnings ``chi2(method=...)`` names.
BINNINGS = {"adaptive": AdaptiveBinning, "fixed": FixedBinning}


def _adaptive_cells(model, wis, n_theta, n_phi, m, settle=1e-4):
    """``(t_edges, cells, phi0)`` of each incidence of ``wis`` (stages 1-2): the pilot
    rules' pdf in one call, then every band of every incidence integrated together
    at each refinement step (one launch on Dr.Jit)."""
    pilots = []
    for wi in wis:
        peaks = model.peak_directions(wi)
        # graded breakpoints (refined toward the lobe): the pilot rule, and reused inside every cell
        tb_glob, pb_glob, phi0 = lobe_breaks(wi, peaks)
        pilot = hemisphere_grid(wi, peaks, m=8, theta_breaks=tb_glob, phi_breaks=pb_glob)
        pilots.append((tb_glob, pb_glob, phi0, pilot))
    sizes = [p[3].wo.shape[:2] for p in pilots]
    wo = np.concatenate([p[3].wo.reshape(-1, 3) for p in pilots])
    wi_rows = np.repeat(np.asarray(wis, dtype=np.float64), [a * b for a, b in sizes], axis=0)
    pdfs = np.split(np.asarray(model.pdf(wi_rows, wo)), np.cumsum([a * b for a, b in sizes])[:-1])
    bands, owner, heads = [], [], []   # per band: [ta, tb, phi edges, theta breaks, phi breaks]
    for k, ((tb_glob, pb_glob, phi0, pilot), pdf, shape) in enumerate(zip(pilots, pdfs, sizes)):
        mass = pdf.reshape(shape) * pilot.weight
        phi_lo, phi_hi = phi0 - math.pi, phi0 + math.pi
        t_edges = _quantile_edges(pilot.theta, mass.sum(axis=1), 0.0, HALF_PI, n_theta)
        heads.append((t_edges, phi0, len(bands)))
        for b in range(len(t_edges) - 1):
            ta, tb = t_edges[b], t_edges[b + 1]
            sel = (pilot.theta >= ta) & (pilot.theta < tb) if b < len(t_edges) - 2 else (pilot.theta >= ta)
            p_edges = _quantile_edges(pilot.phi, mass[sel].sum(axis=0), phi_lo, phi_hi, n_phi)
            tbr = np.unique(np.concatenate([[ta, tb], tb_glob[(tb_glob > ta) & (tb_glob < tb)]]))
            pbr = np.unique(np.concatenate([p_edges, pb_glob[(pb_glob > phi_lo) & (pb_glob < phi_hi)]]))
            bands.append([ta, tb, p_edges, tbr, pbr])
            owner.append(k)
    wis = np.asarray(wis, dtype=np.float64)
    expected = _bands_expected(model, wis[owner], bands, m)
    # Refine (midpoints in both angles) until the cell integrals settle: a lobe
    # concentrated along a curve (nu = 0, nv = 10^4) is not a point the graded
    # breakpoints can aim at.  Every band still refining is integrated in one call.
    active = list(range(len(bands)))
    for _ in range(4):
        if not active:
            break
        for b in active:
            bands[b][3], bands[b][4] = _bisect(bands[b][3]), _bisect(bands[b][4])
        fine = _bands_expected(model, wis[[owner[b] for b in active]], [bands[b] for b in active], m)
        still = []
        for b, f in zip(active, fine):
            e = expected[b]
            if not np.all(np.abs(f - e) <= settle * max(e.sum(), 1e-300) / len(e) + 1e-12):
                still.append(b)
            expected[b] = f
        active = still
    out = []
    for k, (t_edges, phi0, first) in enumerate(heads):
        last = heads[k + 1][2] if k + 1 < len(heads) else len(bands)
        cells = [(ta, tb, p_edges, e) for (ta, tb, p_edges, _, _), e in zip(bands[first:last], expected[first:last])]
        out.append((t_edges, cells, phi0))
    return out


def _bisect(b):
    return np.sort(np.concatenate([b, 0.5 * (b[:-1] + b[1:])]))


def _bands_expected(model, wis, bands, m):
    """Integral of the pdf over each cell ``[tbr[0], tbr[-1]] x [p_edges[j], p_edges[j+1]]``
    of every band ``(ta, tb, p_edges, tbr, pbr)``, band ``k`` at incidence ``wis[k]``
    (all bands in one :func:`~plausible.integrals.albedo.pdf_phi_sums_many` call)."""
    rules = [(panel_rule(tbr, m), panel_rule(pbr, m)) for _, _, _, tbr, pbr in bands]
    sums = pdf_phi_sums_many(model, wis, [(tn, tw * np.sin(tn), pn) for (tn, tw), (pn, _) in rules])
    out = []
    for (_, _, p_edges, _, _), (_, (pn, pw)), per_phi in zip(bands, rules, sums):
        idx = np.clip(np.searchsorted(p_edges, pn, side="right") - 1, 0, len(p_edges) - 2)
        out.append(np.bincount(idx, weights=per_phi * pw, minlength=len(p_edges) - 1))
    return out


def _fixed_cells(model, wi, n_theta, n_phi, ires=4):
    """Naive binning for comparison: uniform in (cos(theta), phi), pdf integrated
    with an ``ires x ires`` midpoint rule per cell (what a fixed coarse grid does)."""
    phi0 = 0.0
    zc = np.linspace(1.0, 0.0, n_theta + 1)
    t_edges = np.arccos(zc)
    p_edges = np.linspace(-math.pi, math.pi, n_phi + 1)
    cells = []
    for b in range(n_theta):
        z = zc[b] + (zc[b + 1] - zc[b]) * (np.arange(ires) + 0.5) / ires
        tn = np.arccos(z)
        dz = abs(zc[b + 1] - zc[b]) / ires
        pn = (p_edges[:-1, None] + (p_edges[1:] - p_edges[:-1])[:, None] * (np.arange(ires) + 0.5) / ires).ravel()
        dp = (2 * math.pi / n_phi) / ires
        vals = _pdf_grid(model, wi, tn, pn) * dz * dp
        exp_b = vals.sum(axis=0).reshape(n_phi, ires).sum(axis=1)
        cells.append((t_edges[b], t_edges[b + 1], p_edges, exp_b))
    return t_edges, cells, phi0


#: The most samples one incidence of :func:`chi2_many` draws (about 10 GB of directions and weights).
MAX_SAMPLES = 10 ** 8

def chi2(model, wi, *, n_samples: int = 200_000, n_theta: int = 16, n_phi: int = 16,
         alpha: float = 0.01, n_tests: int = 1, seed: int = 0, min_expected: float = 5.0,
         m: int = 8, method: str = "adaptive", binning=None) -> Chi2Result:
    """Chi-square test that ``model.sample(wi, .)`` draws from ``model.pdf(wi, .)``.

    ``binning``: an object whose ``cells(model, wi)`` gives the :class:`Cells`
    (their edges and expected fractions); default, by ``method``:
    :class:`AdaptiveBinning` (``"adaptive"``) or :class:`FixedBinning`
    (``"fixed"``) with ``n_theta``, ``n_phi`` (and ``m``).  ``n_samples`` draws
    with random numbers from ``seed``; cells expecting fewer than
    ``min_expected`` samples are pooled.  Returns :class:`Chi2Result`;
    ``passed`` is ``p_value >= sidak(alpha, n_tests)``.
    """
    return chi2_many(model, [wi], seeds=[seed], n_samples=n_samples, n_theta=n_theta, n_phi=n_phi,
                     alpha=alpha, n_tests=n_tests, min_expected=min_expected, m=m, method=method,
                     binning=binning)[0]


def chi2_many(model, wis, *, seeds=None, n_samples: int = 200_000, n_theta: int = 16, n_phi: int = 16,
              alpha: float = 0.01, n_tests: int = 1, min_expected: float = 5.0, m: int = 8,
              method: str = "adaptive", binning=None) -> list:
    """:func:`chi2` at each incidence of ``wis`` (``seeds``: one per incidence, default
    ``0, 1, ...``), computed together: the cells of every incidence in one
    refinement (``binning.cells_many`` where the binning has it), every
    incidence's samples in one ``sample`` call.  Each result is the one
    :func:`chi2` gives for that incidence and seed (up to the rounding of the
    backend the larger calls get).  Returns a list of :class:`Chi2Result`."""
    if binning is None:
        if method not in BINNINGS:
            raise ValueError(f"method must be one of {', '.join(map(repr, BINNINGS))}, got {method!r}")
        binning = (AdaptiveBinning(n_theta, n_phi, m) if method == "adaptive"
                   else FixedBinning(n_theta, n_phi))
    # 1e8 samples of one incidence are ~10 GB of directions and weights: beyond, a MemoryError deep inside
    n_samples = A.count("n_samples", n_samples, 1000, MAX_SAMPLES)
    A.count("n_theta", n_theta, 1)
    A.count("n_phi", n_phi, 1)
    A.count("n_tests", n_tests, 1)
    alpha = A.probability("alpha", alpha)
    A.real("min_expected", min_expected, 0.0, open_lo=True)      # a pool below 0 gave a NaN statistic
    wis = [np.asarray(wi, dtype=np.float64) for wi in wis]
    wis = [wi / np.linalg.norm(wi) for wi in wis]
    seeds = list(range(len(wis))) if seeds is None else list(seeds)
    if len(seeds) != len(wis):
        raise ValueError(f"seeds must give one seed per incidence ({len(wis)}), got {len(seeds)}")
    a1 = sidak(alpha, n_tests)
    many = getattr(binning, "cells_many", None)
    cells = many(model, wis) if many is not None else [binning.cells(model, wi) for wi in wis]
    u = np.concatenate([np.random.default_rng(seed).random((n_samples, 3)) for seed in seeds])
    s = model.sample(np.repeat(np.asarray(wis), n_samples, axis=0), u)
    out = []
    for k, (wi, c) in enumerate(zip(wis, cells)):
        b = slice(k * n_samples, (k + 1) * n_samples)
        out.append(_test(c, Sample(s.wo[b], s.weight[b], s.pdf[b]), n_samples, a1, min_expected, wi))
    return out


def _test(cells, s, n_samples, a1, min_expected, wi) -> Chi2Result:
    """Stages 3-4 of one incidence from its cells and samples."""
    bad = int(np.sum(~np.isfinite(s.pdf)))
    obs, exp, desc = _histogram(cells, s, n_samples)
    if bad or not np.all(np.isfinite(exp)):     # a NaN in every comparison reads as a pass: fail it by name
        msg = (f"{bad} of {len(s.pdf)} sampled pdfs are not finite" if bad else
               f"the pdf integrates to a value that is not finite in {int(np.sum(~np.isfinite(exp)))} cell(s)")
        return Chi2Result(False, 0.0, math.inf, 0, a1, n_samples, len(obs), wi.tolist(), msg, [])
    zero = (exp <= 0) & (obs > 0)
    if np.any(zero):      # samples where the pdf integrates to zero: no statistic needed
        k = int(np.argmax(np.where(zero, obs, -1)))
        msg = (f"{int(obs[zero].sum())} samples fell in {int(zero.sum())} cell(s) where the pdf "
               f"integrates to zero, e.g. {desc[k]}")
        return Chi2Result(False, 0.0, math.inf, 0, a1, n_samples, len(obs), wi.tolist(), msg,
                          [dict(desc[k], observed=float(obs[k]), expected=0.0)])
    o, e, d = _pool(obs, exp, desc, min_expected)
    return _statistic(o, e, d, a1, n_samples, wi.tolist())


def _histogram(cells: Cells, s, n_samples):
    """Observed and expected counts per cell (``expected`` scaled to ``n_samples``),
    and a description of each; the last cell holds the invalid samples (pdf 0 or
    below the horizon), expected ``n_samples`` minus every other expectation."""
    valid = (s.pdf > 0) & (s.wo[:, 2] > 0)
    theta, phi = _angles_of(s.wo[valid], cells.phi0)
    t_edges = cells.t_edges
    band = np.clip(np.searchsorted(t_edges, theta, side="right") - 1, 0, len(t_edges) - 2)
    obs, exp, desc = [], [], []
    for b, (ta, tb, p_edges, exp_b) in enumerate(cells.bands):
        idx = np.clip(np.searchsorted(p_edges, phi[band == b], side="right") - 1, 0, len(p_edges) - 2)
        obs.extend(np.bincount(idx, minlength=len(p_edges) - 1).tolist())
        exp.extend((exp_b * n_samples).tolist())
        for j in range(len(p_edges) - 1):
            desc.append(dict(theta_deg=(math.degrees(ta), math.degrees(tb)),
                             phi_deg=(math.degrees(p_edges[j]), math.degrees(p_edges[j + 1]))))
    obs = np.append(np.array(obs, dtype=np.float64), float(n_samples - valid.sum()))
    exp = np.array(exp, dtype=np.float64)
    exp = np.append(exp, max(n_samples - exp.sum(), 0.0))
    desc.append(dict(cell="invalid (below horizon / pdf 0)"))
    return obs, exp, desc


def _pool(obs, exp, desc, min_expected):
    """Stage 3: the cells expecting fewer than ``min_expected`` samples (smallest
    first) pooled into one cell, or, if the pool itself is still too small, into
    the smallest remaining cell.  Returns ``(observed, expected, descriptions)``."""
    order = np.argsort(exp)
    keep = np.ones(len(exp), bool)
    pool_o = pool_e = 0.0
    for k in order:
        if exp[k] >= min_expected:
            break
        pool_o += obs[k]
        pool_e += exp[k]
        keep[k] = False
    o = list(obs[keep])
    e = list(exp[keep])
    d = [desc[k] for k in np.nonzero(keep)[0]]
    if pool_e > 0:
        if pool_e < min_expected and e:
            j = int(np.argmin(e))
            e[j] += pool_e
            o[j] += pool_o
        else:
            o.append(pool_o)
            e.append(pool_e)
            d.append(dict(cell="pooled low-expectation cells"))
    return np.array(o), np.array(e), d


def _statistic(o, e, d, alpha, n_samples, wi) -> Chi2Result:
    """Stage 4: Pearson's statistic over the pooled cells, its p-value
    (``scipy.special.chdtrc``, the function behind ``scipy.stats.chi2.sf``; imported
    here, since ``scipy.stats`` alone takes about a second to import) against
    ``alpha``, and the five worst cells."""
    from scipy.special import chdtrc

    contrib = (o - e) ** 2 / e
    stat = float(contrib.sum())
    dof = max(len(o) - 1, 1)
    p = float(chdtrc(dof, stat))
    top = np.argsort(contrib)[::-1][:5]
    worst = [dict(d[k], observed=float(o[k]), expected=float(e[k]), contribution=float(contrib[k]))
             for k in top]
    passed = p >= alpha
    msg = (f"p = {p:.4g} {'>=' if passed else '<'} alpha = {alpha:.3g} "
           f"(chi2 = {stat:.1f}, dof = {dof}, {len(o)} cells)")
    return Chi2Result(passed, p, stat, dof, alpha, n_samples, len(o), wi, msg, worst)
