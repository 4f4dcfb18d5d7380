"""Fit a model's parameters to a target: another model, a table of samples, or a
measured BRDF (MERL), under one of the metrics of :mod:`plausible.fitting.metrics`.

The fit uses only the model contract (``eval``) and the registry (parameter
specifications with their ranges); the albedo comes from
:mod:`plausible.analysis`.  Method:

1. **Free parameters**: every scalar or colour parameter with a numeric default
   that the caller did not fix and that changes ``f`` on the sample set (so
   e.g. Cook-Torrance's conductor ``eta``, ``k`` stay put under Schlick's
   Fresnel).  Choice parameters keep their default or the caller's value.
2. **Bounds and variables**: each parameter's ``[lo, hi]`` from the registry
   (infinite bounds clipped to ``[-1e3, 1e3]``, exponents capped at ``1e5``);
   parameters with ``lo > 0`` and ``hi/lo >= 100`` (roughnesses) are optimised
   as ``ln p``, other non-negative ones with ``hi > 10`` (Phong exponents) as
   ``ln(1 + p)``, the rest linearly.
3. **Multi-start** from the defaults and ``starts - 1`` seeded uniform points in the
   variables, by :func:`optimise` (the one optimiser, :func:`plausible.convert`'s too).
   ``l2-cos`` and ``log``: ``scipy.optimize.least_squares`` on the residual vector
   (:meth:`_Objective._residuals`; the Jacobian from one population of difference points),
   the multi-start ending at the first repeated or exact optimum (:data:`PERFECT`), each
   candidate a copy of the one model built per fit (:func:`candidate`).  An isotropic
   target is fitted with each anisotropic pair tied first (:data:`ANISOTROPY_MARGIN`);
   every metric holds the target's highlight (:data:`plausible.fitting.metrics.HIGHLIGHT_BAND`).
   ``perceptual``: L-BFGS-B (SciPy, finite-difference gradients); a
   parameter set the model rejects (``ValueError``, e.g. ``kd + ks > 1``) costs a
   penalty of ``1e6``.  The ``perceptual`` metric is minimised through its smooth
   log-sum-exp bound at ``beta = 20``, ``200`` and ``2000`` in turn (each from
   the previous optimum).  Every start ends with a bounded Nelder-Mead polish on
   the true figure (L-BFGS-B stalls where a constraint the model enforces by
   ``ValueError`` cuts its line search).  The best point by the true figure wins.
   A start whose first local optimum (``beta = 20`` for ``perceptual``) repeats an
   earlier start's (:data:`MERGE_TOL`) stops there.  Each point of L-BFGS-B is
   evaluated together with its ``n`` forward-difference points, one population
   of candidates in one launch (:meth:`_Objective.many`).
4. **Colours**, for a multi-channel target: all parameters are first fitted to
   the channel mean with colours as scalars, then the colour parameters alone
   are refitted per channel with the others fixed: under ``l2-cos``, where the model
   is linear in its colours, in closed form (:func:`_linear_colours`,
   :func:`plausible.fitting.linear.bounded`), else by
   :func:`optimise`.
5. **Identifiability**: at the solution, the Jacobian of ``ln(f cos + eps)``
   on the sample pairs with respect to the free variables (central
   differences; columns scaled to unit length) is decomposed; a singular
   value below ``1e-6`` of the largest is a flat direction of every
   metric -- a parameter, or a combination (Ward's ``rs / alpha_y`` when no
   half vector leaves the ``x`` axis), that the samples do not constrain.  The
   parameters along it are listed in ``FitResult.unconstrained`` and a
   :class:`UnconstrainedWarning` names them.
6. **Albedo** inside the optimiser: a fixed graded Gauss-Legendre rule per
   incidence angle (:func:`plausible.integrals.quadrature.hemisphere_grid`,
   ``m = 4``, ``levels = 8``; measured against the accurate integrator: 5e-7
   relative for an exponent of 30, 2e-4 for Cook-Torrance ``m = 0.2``, 6e-3 for
   exponents of 10^4, 9e-2 for Ward ``alpha = 0.01``); every **reported** albedo error uses the accurate integrator
   :func:`plausible.analysis.albedo_curve`.
"""

from __future__ import annotations

import copy
import math
import time
import warnings
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from .. import arguments as A
from .. import registry
from ..analysis import albedo_curve, direction
from ..bxdf import BxDF, Params
from ..progress import start
from ..text import fmt
from . import metrics as M
from .targets import Target, as_target, fcos as _fcos

PENALTY = 1e6
EXPONENT_CAP = 1e5


# -- the parameter space ---------------------------------------------------------------

class _Var:
    """One variable of the optimiser: parameter ``p`` in its transform (step 2);
    ``tied``: parameters that take the same value (an isotropic lobe's ``nv`` with ``nu``)."""

    def __init__(self, p, tied=()):
        self.name, self.is_color, self.tied = p.name, p.is_color, tuple(tied)
        lo = -1e3 if p.lo == -math.inf else p.lo
        hi = 1e3 if p.hi == math.inf else p.hi
        if lo > 0 and hi / lo >= 100:
            self.tf = "log"
        elif lo >= 0 and hi > 10:
            self.tf, hi = "log1p", min(hi, EXPONENT_CAP)
        else:
            self.tf = "lin"
        self.lo, self.hi = lo, hi
        self.bounds = (self.fwd(lo), self.fwd(hi))

    def fwd(self, v):
        v = min(max(float(v), self.lo), self.hi)
        return math.log(v) if self.tf == "log" else math.log1p(v) if self.tf == "log1p" else v

    def inv(self, x):
        v = math.exp(x) if self.tf == "log" else math.expm1(x) if self.tf == "log1p" else x
        return min(max(v, self.lo), self.hi)


class _Timeout(Exception):
    pass


class _FastAlbedo:
    """Albedo by a fixed graded rule per incidence angle (smooth in the parameters)."""

    def __init__(self, thetas, peaks_of):
        from ..integrals.quadrature import hemisphere_grid

        self.grids = []
        for t in thetas:
            wi = direction(float(t))
            peaks = [p for fn in peaks_of for p in fn(wi)]
            g = hemisphere_grid(wi, peaks, m=4, levels=8)
            wo = g.wo.reshape(-1, 3)
            self.grids.append((wi, wo, (g.weight.reshape(-1) * wo[:, 2])))
        #: every grid's weights end to end, and where each grid starts in them
        self.weights = np.concatenate([w for _, _, w in self.grids])
        self.starts = np.cumsum([0] + [len(w) for _, _, w in self.grids[:-1]])

    def sums(self, f):
        """The albedo of every grid from ``f`` at all the grids' nodes end to end
        (``(nodes,)`` or ``(nodes, channels)``).  ``np.add.reduceat``, not a dot
        product: NumPy's BLAS threads, woken by a dot of this size, spin on the
        cores the Dr.Jit launches need (measured: a fit's CPU time 10x)."""
        w = self.weights if f.ndim == 1 else self.weights[:, None]
        return np.add.reduceat(w * f, self.starts, axis=0)

    def __call__(self, model):
        return self.sums(np.concatenate([model.eval(wi, wo) for wi, wo, _ in self.grids]))


# -- results ---------------------------------------------------------------------------

@dataclass
class FitResult:
    """A fit: the model, its parameters, the metric minimised, and the figures of
    every metric (:func:`plausible.fitting.metrics.errors`, albedo by the
    accurate integrator)."""

    model: BxDF
    params: dict
    metric: str
    errors: dict
    target: Target
    evaluations: int = 0
    timed_out: bool = False
    seconds: float = 0.0
    fit_albedo: np.ndarray | None = None
    #: Groups of parameters along a flat direction of the objective at the
    #: solution (step 5 of :mod:`plausible.fitting.fit`): values the target does not decide.
    unconstrained: list = field(default_factory=list)
    #: Parameters (channels) that ended at an end of their range (:func:`at_bounds`); a
    #: :class:`BoundWarning` names them too.
    at_bounds: list = field(default_factory=list)
    #: What the procedure decided (an isotropic target's lobe kept isotropic, or not, and why).
    notes: list = field(default_factory=list)

    def to_dict(self) -> dict:
        """Plain data (JSON): model, metric, parameters, errors, target label."""
        def conv(v):
            return v.tolist() if isinstance(v, np.ndarray) else v
        return {"model": self.model.name, "metric": self.metric, "target": self.target.label,
                "params": {k: conv(v) for k, v in self.params.items()}, "errors": dict(self.errors),
                "evaluations": self.evaluations, "timed_out": self.timed_out, "seconds": self.seconds,
                "unconstrained": [list(g) for g in self.unconstrained], "at_bounds": list(self.at_bounds),
                "notes": list(self.notes)}

    def _repr_html_(self) -> str:
        from ..text import html_table

        rows = [(k, fmt(v, ".5g")) for k, v in self.params.items()]
        rows += [(f"error: {k}", "n/a" if v is None else f"{v:.4g}") for k, v in self.errors.items()]
        rows += [("unconstrained", "; ".join(", ".join(g) for g in self.unconstrained))] if self.unconstrained else []
        return html_table(f"{self.model.name} fitted to {self.target.label} ({self.metric})", ["", "value"], rows)

    def summary(self) -> str:
        ps = ", ".join(f"{k}={fmt(v, '.5g', sep=',')}" for k, v in self.params.items())
        es = ", ".join(f"{k}={v:.4g}" for k, v in self.errors.items() if v is not None)
        return f"{self.model.name} ({self.metric}): {ps}\n  errors: {es}"


# -- the fit ------------------------------------------------------------------------------

def fit(model_name: str, target, metric: str = "perceptual", *, fixed: dict | None = None,
        starts: int = 4, seed: int = 0, time_limit: float | None = None, progress=None,
        thetas_deg=M.THETAS_DEG, target_albedo=None, maxiter: int = 200,
        combine: str = "sum", highlight: float = M.HIGHLIGHT_WEIGHT) -> FitResult:
    """Fit the registered model ``model_name`` to ``target`` under ``metric``.

    ``target``: see :func:`as_target`.  ``fixed``: parameters held at given values
    (choice parameters such as Ward's ``variant`` go here too).  ``starts``:
    number of optimiser starts (the first from the defaults).  ``time_limit``
    (seconds): stop starting/continuing optimisations after this long and
    return the best point found (``timed_out`` is then True).  ``progress``: a
    :mod:`plausible.progress` factory, announced with the number of
    optimisations and ticked after each.  ``combine``: how the perceptual metric
    joins its two maxima, ``"sum"`` (default) or ``"max"``.  ``highlight``: the weight ``w >= 0``
    of the highlight hold, ``w sum excess^2`` added to the figure minimised
    (:func:`plausible.fitting.metrics.highlight_excess`; default
    :data:`plausible.fitting.metrics.HIGHLIGHT_WEIGHT`, 0 the plain metrics as the papers fit them).
    ``thetas_deg``:
    incidence angles of the samples and albedo terms for a model target;
    ``target_albedo = (thetas_deg, values)``: the albedo of a table target.

    The metrics (:mod:`plausible.fitting.metrics`): ``l2-cos`` and ``log`` are
    least squares on ``f cos(theta_o)`` and on its logarithm; ``perceptual`` is
    ``max_k |ln((c_k + eps)/(g_k + eps))| + max_j |ln(a_j / A_j)|``, the maximal
    relative errors of ``f cos`` and of the albedo (Neumann, Neumann &
    Szirmay-Kalos 1999, section 1.1).  Returns a :class:`FitResult`.

    The steps are those of the module docstring.  The fit runs with one BLAS thread
    (``threadpoolctl``): two OpenBLAS threads for a problem of a few variables cost 12
    times the CPU of one (issue 40).
    """
    with one_blas_thread():
        return _fit(model_name, target, metric, fixed, starts, seed, time_limit, progress, thetas_deg,
                    target_albedo, maxiter, combine, highlight)


_CONTROLLER = []


def one_blas_thread():
    """A context manager that holds every BLAS library at one thread (``threadpoolctl``): two
    OpenBLAS threads for a problem of a few variables cost 12 times the CPU of one (issue 40).
    The libraries are listed once per process (``ThreadpoolController``; listing them, as each
    ``threadpool_limits`` call does, reads the process's loaded libraries: 2 ms, 3 % of a small
    fit), after SciPy's optimisers are imported (their BLAS loaded)."""
    from threadpoolctl import ThreadpoolController

    if not _CONTROLLER:
        import scipy.optimize  # noqa: F401  (SciPy's BLAS loaded before the libraries are listed)

        _CONTROLLER.append(ThreadpoolController())
    return _CONTROLLER[0].limit(limits=1, user_api="blas")


def _fit(model_name, target, metric, fixed, starts, seed, time_limit, progress, thetas_deg, target_albedo,
         maxiter, combine, highlight):
    if metric not in M.METRICS:
        raise ValueError(f"metric must be one of {', '.join(M.METRICS)}, got {metric!r}")
    try:
        highlight = float(highlight)
    except (TypeError, ValueError):
        raise ValueError(f"highlight must be a weight >= 0 (0: the plain metric), got {highlight!r}") from None
    if not (math.isfinite(highlight) and highlight >= 0.0):
        raise ValueError(f"highlight must be a finite weight >= 0 (0: the plain metric), got {highlight!r}")
    M.check_combine(combine)
    A.count("starts", starts, 1)
    A.count("seed", seed, 0)                # NumPy's generators take seeds >= 0
    A.count("maxiter", maxiter, 1)
    if time_limit is not None:              # 0: the start, timed out; -1 was taken as 0 and NaN ignored
        A.real("time_limit", time_limit, 0.0)
    A.angles_deg("thetas_deg", thetas_deg, 0.0, 90.0, open_hi=True)
    t0 = time.monotonic()
    info = registry.info(model_name)
    fixed = dict(fixed or {})
    tgt = as_target(target, thetas_deg=thetas_deg, target_albedo=target_albedo)
    proto = info.cls(**fixed)
    problem = _Problem.make(info, proto, tgt, metric, combine, maxiter,
                            None if time_limit is None else t0 + float(time_limit), highlight)
    # 1. free parameters; a parameter whose default is None resolves from the
    # others (neumann-metal's c): leave it out so that it follows them
    base = {k: v for k, v in proto.params.items() if k in fixed or info.param(k).default is not None}
    free = _free_params(info, proto, fixed, problem.values)
    vars_ = [_Var(p) for p in free]
    colour_vars = [v for v in vars_ if v.is_color] if tgt.channels else []
    pairs = _anisotropic_pairs(free) if tgt.derived("isotropic", is_isotropic) else []
    tick = start(progress, starts + bool(pairs) + (tgt.channels if colour_vars else 0), f"fit {model_name}")
    # 2-3. multi-start on the channel mean, colours as scalars (an isotropic target: the lobe isotropic first)
    notes = []
    if pairs:
        params, objectives, note = _fit_isotropic_first(problem, free, pairs, base, starts, seed, tick)
        notes.append(note)
    else:
        params, objectives = _fit_shared(problem, vars_, base, starts, seed, tick)
    # 4. colours per channel
    if colour_vars and not any(o.timed_out for o in objectives):
        params, more = _fit_channels(problem, colour_vars, params, base, tick)
        objectives += more
    params.update({k: v for k, v in base.items() if isinstance(v, np.ndarray) and k in fixed})
    # 5. parameters the samples do not constrain
    flat = unconstrained(problem, vars_, {k: float(np.mean(v)) if isinstance(v, np.ndarray) else v
                                          for k, v in params.items()})
    if flat:
        warnings.warn(f"fit of {model_name} to {tgt.label}: " + "; ".join(_flat_text(g) for g in flat)
                      + " (the samples do not decide them; fix one with fixed={...} or add samples that do)",
                      UnconstrainedWarning, stacklevel=3)
    # 6. every metric's figure, albedo by the accurate integrator; parameters at their bounds said aloud
    model = info.cls(**params)
    out = evaluate_fit(model, tgt, problem.eps, combine, problem.rows)
    bounds = at_bounds(vars_, params)
    if bounds:
        warnings.warn(f"fit of {model_name} to {tgt.label}: " + "; ".join(bounds)
                      + " (the optimum lies on the edge of the range: the model cannot follow the target there, "
                        "or a wider range would fit better)", BoundWarning, stacklevel=3)
    return FitResult(model, {k: model.params[k] for k in model.params}, metric, out["errors"], tgt,
                     sum(o.evaluations for o in objectives), any(o.timed_out for o in objectives),
                     time.monotonic() - t0, out["albedo"], flat, bounds, notes)


#: Parameter pairs of an anisotropic lobe: the exponents or roughnesses along the two tangents.
ANISOTROPIC_PAIRS = (("nu", "nv"), ("alpha_x", "alpha_y"))
#: An isotropic target gets an anisotropic fit only where that lowers the figure minimised
#: by more than this fraction of the isotropic fit's (otherwise the isotropic fit is kept).
ANISOTROPY_MARGIN = 0.05
#: A parameter ends at a bound when its variable is within this fraction of the variable's
#: range of the bound.
BOUND_TOL = 1e-6


def is_isotropic(tgt: Target, turn: float = 0.61) -> bool:
    """Whether ``tgt`` is a model whose ``f`` is unchanged (to 1e-9 relative) when every pair
    turns by ``turn`` radians about the normal; False for a table (nothing to turn)."""
    m = tgt.model
    if m is None:
        return False
    c, s = math.cos(turn), math.sin(turn)
    R = np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])
    wi = np.broadcast_to(tgt.wi, np.shape(tgt.wo))
    f0, f1 = np.asarray(m.eval(wi, tgt.wo)), np.asarray(m.eval(wi @ R.T, tgt.wo @ R.T))
    return bool(np.allclose(f1, f0, rtol=1e-9, atol=1e-12 * float(np.max(np.abs(f0), initial=0.0))))


def _anisotropic_pairs(free) -> list:
    names = {p.name for p in free}
    return [(a, b) for a, b in ANISOTROPIC_PAIRS if a in names and b in names]


def _fit_isotropic_first(problem, free, pairs, base, starts, seed, tick):
    """Steps 2-3 for an isotropic target: the lobe isotropic (each pair of
    :data:`ANISOTROPIC_PAIRS` one variable), then one anisotropic start from there, kept
    only where it lowers the figure by :data:`ANISOTROPY_MARGIN`.  Returns the parameters,
    the objectives and a note saying which was kept and the figures."""
    seconds = {b: a for a, b in pairs}
    iso = [_Var(p, [b for a, b in pairs if a == p.name]) for p in free if p.name not in seconds]
    params, objs = _fit_shared(problem, iso, base, starts, seed, tick)
    for b, a in seconds.items():
        params[b] = params[a]
    iso_value = min(o.best_value for o in objs) if objs else math.inf
    names = ", ".join(f"{a} = {b}" for a, b in pairs)
    if iso_value <= PERFECT:
        tick()
        return params, objs, f"isotropic target: {names}, an exact fit (figure {iso_value:.3g})"
    full = [_Var(p) for p in free]
    obj = _Objective(problem, full, params, None)
    aniso = dict(params)
    try:
        aniso.update(optimise(obj, [[v.fwd(params[v.name]) for v in full]], tick))
    except _Timeout:
        pass
    if obj.best_value < (1.0 - ANISOTROPY_MARGIN) * iso_value:
        return aniso, objs + [obj], (f"anisotropic fit kept: figure {obj.best_value:.4g} against {iso_value:.4g} "
                                     f"with {names} (lower by more than {ANISOTROPY_MARGIN:.0%})")
    return params, objs + [obj], (f"isotropic target: {names} kept (an anisotropic fit reached {obj.best_value:.4g} "
                                  f"against {iso_value:.4g}, not lower by {ANISOTROPY_MARGIN:.0%})")


def at_bounds(vars_, params) -> list:
    """``"name = value (its lower/upper bound)"`` for each free parameter (each channel of
    a colour) that ends within :data:`BOUND_TOL` of its range's end (in its variable)."""
    out = []
    for v in vars_:
        vals = np.atleast_1d(np.asarray(params[v.name], float))
        span = v.bounds[1] - v.bounds[0]
        for i, val in enumerate(vals):
            x = v.fwd(val)
            end = ("lower", v.lo) if x - v.bounds[0] <= BOUND_TOL * span else (
                ("upper", v.hi) if v.bounds[1] - x <= BOUND_TOL * span else None)
            if end:
                name = f"{v.name}[{i}]" if len(vals) > 1 else v.name
                out.append(f"{name} = {fmt(float(val), '.6g')} (its {end[0]} bound {end[1]:g})")
    return out


class BoundWarning(UserWarning):
    """A fit ended with a parameter at an end of its range."""


def candidate(proto: BxDF, values: dict) -> BxDF:
    """A model of ``proto``'s class at ``values`` without building it again: a copy of
    ``proto`` with its parameter namespaces replaced (the parameters as data of the one
    model built per fit; the issue measured 3,851 ``Param.validate`` calls in one fit).
    The values come from the optimiser's variables, which :meth:`_Var.inv` keeps inside
    each parameter's range, or from ``proto`` itself, so only the model's own constraints
    between parameters (``_validate``: Modified Phong's ``kd + ks <= 1``) are checked
    (ValueError as from the class).  A model that builds state of its own in ``__init__``
    (a sum, Kulla-Conty's tables) or derives a parameter (Neumann's ``c``) is built by its
    class.  A ``_kernel_view`` of its own is no reason to build: it runs on the copy and
    reads the copy's parameters (glTF's ``specular_color_max``; tests/fitting/test_fit.py
    compares every registered model's copy with a built one)."""
    cls = type(proto)
    if cls.DERIVED or cls.__init__ is not BxDF.__init__:
        return cls(**values)
    m = copy.copy(proto)
    vals = dict(proto.params)
    vals.update(values)
    # the channel count as __init__ counts it (a channel's fit holds scalar colours)
    sizes = {np.size(vals[p.name]) for p in cls.PARAMS if p.is_color and np.ndim(vals[p.name]) == 1}
    m.channels = sizes.pop() if len(sizes) == 1 else None
    m._params = Params(vals)
    m.p = SimpleNamespace(**vals)
    m.q = SimpleNamespace(**{k: (float(np.mean(v)) if isinstance(v, np.ndarray) else v) for k, v in vals.items()})
    m._validate()
    return m


class UnconstrainedWarning(UserWarning):
    """A fit left a parameter (or a combination of parameters) unconstrained."""


def _flat_text(group) -> str:
    if len(group) == 1:
        return f"parameter {group[0]!r} is unconstrained (the objective is flat along it)"
    return (f"parameters {', '.join(map(repr, group))} trade against each other along a flat direction "
            f"of the objective")


#: Step of the Jacobian's central differences (a fraction of each variable's range,
#: in the variables of step 2) and the singular-value ratio below which a direction
#: counts as flat.
JAC_STEP, FLAT_RATIO = 1e-4, 1e-6


def unconstrained(problem, vars_, params) -> list:
    """Step 5: groups of the free variables ``vars_`` along which ``ln(f cos +
    eps)`` on the target's pairs does not change at ``params`` (channel means),
    one group per flat direction: the parameters whose share of that singular
    vector (of the Jacobian with unit columns) is above 0.3.  ``[]`` when every
    direction is constrained."""
    if not vars_:
        return []
    tgt = problem.tgt
    obj = _Objective(problem, vars_, params, None)
    x0 = np.array([v.fwd(params[v.name]) for v in vars_])

    pts = [x0]
    for j, v in enumerate(vars_):
        h = JAC_STEP * (v.bounds[1] - v.bounds[0])
        xp, xm = x0.copy(), x0.copy()
        xp[j] = min(x0[j] + h, v.bounds[1])
        xm[j] = max(x0[j] - h, v.bounds[0])
        pts += [xp, xm]
    models, vals = obj._candidates(pts)          # every point in one launch
    outs = [None if m is None else np.log(_reduce(next(vals)[0], tgt.wo, None) + problem.eps) for m in models]
    f0 = outs[0]
    if f0 is None:
        return []
    cols = []
    for j, v in enumerate(vars_):
        (xp, fp), (xm, fm) = [(x0, f0) if f is None else (x, f) for x, f in zip(pts[1 + 2 * j:3 + 2 * j],
                                                                                 outs[1 + 2 * j:3 + 2 * j])]
        dx = (xp[j] - xm[j]) / (v.bounds[1] - v.bounds[0])
        cols.append((fp - fm) / dx if dx > 0 else np.zeros_like(f0))
    J = np.column_stack(cols)
    norms = np.linalg.norm(J, axis=0)
    top = float(norms.max())
    if top == 0.0:
        return [[v.name for v in vars_]]
    # a column far below the others: that parameter alone; the rest equilibrated
    # (unit columns), so a flat combination shows as a small singular value
    # whatever the parameters' units, with the parameters' shares comparable
    groups = [[v.name] for v, n in zip(vars_, norms) if n <= FLAT_RATIO * top]
    keep = [j for j, n in enumerate(norms) if n > FLAT_RATIO * top]
    _, S, Vt = np.linalg.svd(J[:, keep] / norms[keep], full_matrices=False)
    for s_k, vec in zip(S, Vt):
        if s_k <= FLAT_RATIO * S[0]:
            groups.append([vars_[j].name for j, c in zip(keep, vec) if abs(c) > 0.3])
    return [g for g in groups if g]


class _Values:
    """The evaluation of candidate models for the objective: ``f`` at the
    target's pairs and, with an albedo term, the :class:`_FastAlbedo` sums.

    One :class:`plausible.arrays.backend.PairKernel` over the pairs and the albedo
    nodes concatenated, on the backend of the rule
    (:func:`plausible.arrays.backend.choose` on all of them together): on Dr.Jit
    every evaluation is one launch of one kernel, the parameters kernel data, so
    a whole fit compiles one kernel per model structure; on NumPy the hooks run
    on the validated pairs.  :meth:`many` evaluates a population of candidates
    (the optimiser's finite-difference points) in one launch or one NumPy pass.
    The routes agree to 1e-12 (``tests/fitting/test_fit.py``)."""

    def __init__(self, tgt: Target, fast: _FastAlbedo | None):
        from ..arrays import backend
        from ..directions import as_directions

        self.tgt, self.fast = tgt, fast
        self.shape = np.broadcast_shapes(np.shape(tgt.wi), np.shape(tgt.wo))[:-1]
        wi = np.broadcast_to(as_directions("wi", tgt.wi), self.shape + (3,))
        pairs = [(wi.reshape(-1, 3), np.broadcast_to(as_directions("wo", tgt.wo), wi.shape).reshape(-1, 3))]
        for gwi, gwo, _ in (fast.grids if fast else ()):
            pairs.append((np.broadcast_to(gwi, gwo.shape), gwo))
        self.n0 = len(pairs[0][0])
        total = sum(len(a) for a, _ in pairs)
        self.kernel = backend.PairKernel(np.concatenate([a for a, _ in pairs]),
                                         np.concatenate([b for _, b in pairs]), backend.choose(total, None))

    def _split(self, f):
        out = f[:self.n0].reshape(self.shape + f.shape[1:])
        return out, (self.fast.sums(f[self.n0:]) if self.fast else None)

    def __call__(self, m):
        """``(f at the target's pairs, albedo sums or None)``."""
        return self._split(self.kernel(m))

    def many(self, models) -> list:
        """``[self(m) for m in models]`` in one launch (one NumPy pass)."""
        return [self._split(f) for f in self.kernel.many(models)]


@dataclass
class _Problem:
    """What every objective of one fit shares: the model class, the target, the
    metric and its settings, the albedo rule (None without an albedo term), the
    evaluation of a candidate (:class:`_Values`) and the deadline
    (``time.monotonic()`` seconds, or None)."""

    info: object
    tgt: Target
    metric: str
    combine: str
    eps: float
    fast: _FastAlbedo | None
    maxiter: int
    deadline: float | None
    values: _Values | None = None
    #: the target's highlight: its brightest pair per incidence (:func:`plausible.fitting.metrics.highlight_rows`)
    rows: np.ndarray | None = None
    #: the weight of the highlight hold (:func:`fit`'s ``highlight``)
    highlight: float = M.HIGHLIGHT_WEIGHT
    #: the model built (and validated) once per fit; every candidate is a copy with new values (:func:`candidate`)
    proto: BxDF | None = None

    @classmethod
    def make(cls, info, proto, tgt, metric, combine, maxiter, deadline, highlight=M.HIGHLIGHT_WEIGHT):
        use_albedo = metric == "perceptual" and tgt.albedo is not None
        fast = _FastAlbedo(tgt.thetas, [proto.peak_directions] + list(tgt.peaks)) if use_albedo else None
        wi = np.broadcast_to(tgt.wi, np.shape(tgt.wo))
        return cls(info, tgt, metric, combine, M.floor(tgt.fcos), fast, maxiter, deadline, _Values(tgt, fast),
                   tgt.derived("highlight_rows", lambda t: M.highlight_rows(wi, t.fcos)), float(highlight), proto)


def _channel(g, c):
    """Channel ``c`` of ``g`` (the channel mean if ``c`` is None)."""
    if g is None:
        return None
    return g.mean(axis=-1) if (c is None and g.ndim == 2) else (g[..., c] if c is not None else g)


class _Objective:
    """The figure minimised over the variables ``vars_`` (the other parameters at
    ``params0``), on channel ``c`` of the target (None: the channel mean).

    Calling it with ``beta`` gives the smooth bound the optimiser descends
    (:func:`plausible.fitting.metrics.objective`); without, the true figure
    (the square of the least-squares figures), and the best point so far is kept
    (``best_x``, ``best_value``).  A parameter set the model rejects costs
    :data:`PENALTY`.  Past the problem's deadline a call raises ``_Timeout`` and
    sets ``timed_out``; ``evaluations`` counts the candidates evaluated before it.
    """

    def __init__(self, problem: _Problem, vars_, params0, c=None):
        self.problem, self.vars, self.params0, self.c = problem, vars_, params0, c
        self.g = _channel(problem.tgt.fcos, c)
        self.A = _channel(problem.tgt.albedo, c) if problem.fast else None
        self.evaluations = 0
        self.timed_out = False
        self.best_value, self.best_x = math.inf, None
        #: ``(step, upper bounds)`` while L-BFGS-B runs (see :meth:`many`), else None
        self.fd = None
        self._cache = {}
        #: candidates the model rejected (its ``_validate``)
        self.rejected = 0

    def model_at(self, x):
        ps = dict(self.params0)
        for v, xi in zip(self.vars, x):
            ps[v.name] = v.inv(xi)
            ps.update(dict.fromkeys(v.tied, ps[v.name]))
        return candidate(self.problem.proto, ps)

    def __call__(self, x, beta=None):
        return self.many([x], beta)[0]

    def many(self, xs, beta=None) -> list:
        """``[self(x, beta) for x in xs]``, the candidates evaluated together
        (:meth:`_Values.many`: one launch, one NumPy pass), the best point kept in
        the order of ``xs``.

        While ``fd`` is set (``(step, upper bounds)``, during L-BFGS-B) a single
        point ``x`` is evaluated together with the forward-difference points
        L-BFGS-B asks for next (``x + step e_j``, ``x - step e_j`` where that
        leaves the bounds: SciPy's rule), which wait in a cache for that request;
        so a point and its gradient are one launch.  ``evaluations`` counts the
        candidates evaluated."""
        pb = self.problem
        if pb.deadline is not None and time.monotonic() > pb.deadline:
            self.timed_out = True
            raise _Timeout
        xs = [np.array(x, float) for x in xs]
        keys = [(beta, x.tobytes()) for x in xs]
        miss = [x for x, k in zip(xs, keys) if k not in self._cache]
        if miss:
            todo = miss + (self._fd_points(miss[0]) if self.fd is not None and len(xs) == 1 else [])
            vals = self._evaluate(todo, beta)
            self.evaluations += len(todo)
            fresh = {(beta, z.tobytes()): v for z, v in zip(todo, vals)}
            out = [fresh[k] if k in fresh else self._cache[k] for k in keys]
            self._cache = fresh
        else:
            out = [self._cache[k] for k in keys]
        if beta is None:
            for x, v in zip(xs, out):
                if v < self.best_value:
                    self.best_value, self.best_x = v, x
        return out

    def _fd_points(self, x):
        step, ub = self.fd
        out = []
        for j in range(len(x)):
            z = x.copy()
            z[j] = x[j] + (step if x[j] + step <= ub[j] else -step)
            out.append(z)
        return out

    def _candidates(self, xs):
        """``(models, values)``: the model at each point (None where the model rejects it) and
        an iterator over the values of those that exist, in order (one launch)."""
        models = []
        for x in xs:
            try:
                models.append(self.model_at(x))
            except ValueError:
                models.append(None)
                self.rejected += 1
        return models, iter(self.problem.values.many([m for m in models if m is not None]))

    def _evaluate(self, xs, beta) -> list:
        models, vals = self._candidates(xs)
        return [PENALTY if m is None else self._value(next(vals), beta) for m in models]

    def _value(self, values, beta):
        pb = self.problem
        if pb.metric in LEAST_SQUARES:
            return float(np.sum(self._residuals(values) ** 2))
        f, alb = values
        cc = _reduce(f, pb.tgt.wo, self.c)
        a = _reduce_alb(alb, self.c) if pb.fast else None
        h = pb.highlight * float(np.sum(M.highlight_excess(cc, self.g, pb.rows, pb.eps) ** 2))
        if beta is None:
            return M.errors(cc, self.g, a, self.A, pb.eps, pb.combine)["perceptual"] + h
        return M.objective(pb.metric, cc, self.g, a, self.A, pb.eps, beta=beta, combine=pb.combine) + h

    def _residuals(self, values) -> np.ndarray:
        """The residual vector of a least-squares metric (:data:`LEAST_SQUARES`), whose sum of
        squares is the figure squared plus the highlight's cost: ``(c - g) / |g|`` (``l2-cos``)
        or ``ln((c + eps)/(g + eps)) / sqrt(N)`` (``log``), then ``sqrt(highlight)`` (the fit's weight) times
        :func:`plausible.fitting.metrics.highlight_excess`."""
        pb = self.problem
        c, g = _reduce(values[0], pb.tgt.wo, self.c), self.g
        if pb.metric == "l2-cos":
            den = float(np.sum(g * g))
            r = (c - g) / math.sqrt(den) if den > 0 else c
        else:
            r = M._lr(c, g, pb.eps) / math.sqrt(c.size)
        h = math.sqrt(pb.highlight) * M.highlight_excess(c, g, pb.rows, pb.eps)
        return np.concatenate([r.reshape(-1), h])

    def residuals_many(self, xs) -> list:
        """:meth:`_residuals` of each candidate of ``xs`` (one launch, :meth:`_Values.many`); a
        rejected candidate's residuals have the sum of squares :data:`PENALTY`.  Counts the
        evaluations, keeps the best point, raises ``_Timeout`` past the deadline."""
        pb = self.problem
        if pb.deadline is not None and time.monotonic() > pb.deadline:
            self.timed_out = True
            raise _Timeout
        models, vals = self._candidates(xs)
        out = [None if m is None else self._residuals(next(vals)) for m in models]
        size = np.size(self.g) + len(pb.rows)      # the residuals: one per pair, one per highlight row
        out = [np.full(size, math.sqrt(PENALTY / size)) if r is None else r for r in out]
        self.evaluations += len(xs)
        for x, r in zip(xs, out):
            v = float(np.sum(r * r))
            if v < self.best_value:
                self.best_value, self.best_x = v, np.array(x, float)
        return out

    def best_params(self, x_default) -> dict:
        """The best point found as parameter values (``x_default`` if none was)."""
        x = self.best_x if self.best_x is not None else np.array(x_default, float)
        return {v.name: v.inv(xi) for v, xi in zip(self.vars, x)}


#: Two starts have found the same optimum when their first local optima (L-BFGS-B; for
#: ``perceptual`` the one at ``beta = 20``) agree to ``MERGE_TOL`` of every variable's
#: range and their objective values to ``MERGE_RTOL`` relative: the later start stops
#: there (its further steps would repeat the earlier start's to rounding).
MERGE_TOL, MERGE_RTOL = 1e-4, 1e-8
#: Forward-difference step of L-BFGS-B's gradients (in the variables).
FD_STEP = 1e-7


def _lbfgsb(fun: _Objective, x, beta, bounds, **options):
    """L-BFGS-B from ``x`` on ``fun`` at ``beta``, each point evaluated together
    with its finite-difference points (:meth:`_Objective.many`)."""
    from scipy.optimize import minimize

    fun.fd = (FD_STEP, np.array([hi for _, hi in bounds], float))
    try:
        return minimize(lambda z: fun(z, beta), x, method="L-BFGS-B", bounds=bounds,
                        options=dict(eps=FD_STEP, **options))
    finally:
        fun.fd = None


def _same_optimum(found, x, value, spans) -> bool:
    """Whether ``(x, value)`` repeats one of the first optima ``found`` (see :data:`MERGE_TOL`)."""
    return any(np.all(np.abs(x - y) <= MERGE_TOL * spans) and abs(value - w) <= MERGE_RTOL * max(abs(w), 1e-300)
               for y, w in found)


#: A least-squares figure (squared) at or below this is an exact fit (relative RMS 1e-9): no
#: further start, and no anisotropic attempt after an isotropic one.
PERFECT = 1e-18
#: The metrics fitted as least squares of a residual vector (:meth:`_Objective._residuals`).
LEAST_SQUARES = ("l2-cos", "log")
#: How the least-squares Jacobian is taken: ``"population"`` (forward differences of
#: :data:`FD_STEP`, the ``n`` points and the point itself one launch, :meth:`_Values.many`) or
#: ``"2-point"`` (SciPy's own differences, one evaluation at a time); benchmarks/fitter.py
#: measures both (docs/benchmarks.md, issue 40).
JACOBIAN = "population"


def _least_squares(fun: _Objective, x0, bounds):
    """``scipy.optimize.least_squares`` (trust-region reflective, within ``bounds``) on
    :meth:`_Objective.residuals_many` from ``x0``; the Jacobian by :data:`JACOBIAN`."""
    from scipy.optimize import least_squares

    lo, hi = np.array([b[0] for b in bounds], float), np.array([b[1] for b in bounds], float)
    x0 = np.clip(np.asarray(x0, float), lo, hi)
    step, tol = getattr(fun, "fd_step", FD_STEP), getattr(fun, "tol", 1e-12)
    last = {}

    def res(x):
        r = fun.residuals_many([x])[0]
        last["x"], last["r"] = np.array(x, float), r
        return r

    def jac(x):
        x = np.asarray(x, float)
        steps = np.where(x + step <= hi, step, -step)
        pts = [x + s * e for s, e in zip(steps, np.eye(len(x)))]
        if "x" in last and np.array_equal(last["x"], x):
            rs, r0 = fun.residuals_many(pts), last["r"]
        else:
            *rs, r0 = fun.residuals_many(pts + [x])
        return np.column_stack([(r - r0) / s for r, s in zip(rs, steps)])

    return least_squares(res, x0, jac=jac if JACOBIAN == "population" else "2-point", bounds=(lo, hi),
                         method="trf", x_scale="jac", ftol=tol, xtol=tol, gtol=tol,
                         max_nfev=fun.problem.maxiter * (len(x0) + 1))


def _line_polish(fun, bounds, evals: int):
    """The true figure ``fun(x)`` along each variable in turn from the best point so far, by SciPy's bounded
    Brent search of ``evals`` evaluations within ``fun.bracket(k, x)`` (else the variable's bounds): where
    least squares only linearises the figure (:class:`plausible.conversion.mitsuba.AxesObjective`), the
    line searches find the figure's own valley and least squares goes on from there."""
    from scipy.optimize import minimize_scalar

    for k in range(len(bounds)):
        x = np.array(fun.best_x, float)
        lo, hi = fun.bracket(k, x) if hasattr(fun, "bracket") else bounds[k]
        if hi - lo <= 0.0:
            continue

        def along(t, x=x, k=k):
            y = x.copy()
            y[k] = t
            return fun(y)

        minimize_scalar(along, bounds=(lo, hi), method="bounded", options=dict(maxiter=evals, xatol=1e-3))


def optimise(fun, x0s, tick) -> dict:
    """Step 3 from each start in ``x0s``, the one optimiser of :func:`fit` and of
    :func:`plausible.convert` (its Mitsuba families' colours,
    :class:`plausible.conversion.mitsuba.ColourObjective`): least squares
    (:func:`_least_squares`, :data:`LEAST_SQUARES` metrics) or, for ``perceptual``,
    L-BFGS-B on the smooth bounds at ``beta = 20, 200, 2000`` then a bounded Nelder-Mead
    polish on the true figure; the multi-start ends once a start repeats an earlier
    start's optimum (:data:`MERGE_TOL`) or fits exactly (:data:`PERFECT`); ``tick()``
    after each start; stop at the deadline.  Returns the best point's parameter values.

    ``fun``, the objective (an :class:`_Objective`, or an adapter with the same
    attributes): ``vars`` (each with ``bounds``), ``problem.metric`` and
    ``problem.maxiter``, ``fun(x)`` the true figure and ``fun(x, beta)`` its smooth
    bound, ``residuals_many(xs)`` (least squares), the best point kept in ``best_x``,
    ``best_value``, ``best_params(x0)``, and ``rejected``, ``timed_out``, ``fd``; optionally
    ``least_squares`` (True: least squares on ``residuals_many`` whatever the metric, the true
    figure kept by ``fun(x)``: :class:`plausible.conversion.mitsuba.AxesObjective`, whose
    residuals linearise ``perceptual``), ``polish`` (evaluations per variable of a bounded line
    search of the true figure from the start, before least squares, :func:`_line_polish`, within
    ``bracket(k, x)`` where given; 0 or absent: none), ``fd_step`` (the Jacobian's difference step, else
    :data:`FD_STEP`) and ``tol`` (least squares' ``ftol``, ``xtol``, ``gtol``; else 1e-12)."""
    from scipy.optimize import minimize

    bounds = [v.bounds for v in fun.vars]
    spans = np.array([hi - lo for lo, hi in bounds], float)
    maxiter = fun.problem.maxiter
    found = []
    for x0 in x0s:
        try:
            x = np.array(x0, float)
            if not getattr(fun, "least_squares", fun.problem.metric != "perceptual"):
                for beta in (20.0, 200.0, 2000.0):
                    r = _lbfgsb(fun, x, beta, bounds, maxiter=maxiter)
                    x = r.x
                    fun(x)
                    if beta == 20.0:
                        if _same_optimum(found, x, float(r.fun), spans):
                            break
                        found.append((x, float(r.fun)))
                else:
                    # derivative-free polish on the true figure (slides along constraints)
                    minimize(fun, x, method="Nelder-Mead", bounds=bounds,
                             options=dict(maxfev=60 * (len(x) + 1), xatol=1e-7, fatol=1e-10))
            else:
                rejected = fun.rejected
                if getattr(fun, "polish", 0):
                    fun(x)                          # the start is the best point so far
                    _line_polish(fun, bounds, fun.polish)
                    x = np.array(fun.best_x, float)
                r = _least_squares(fun, x, bounds)
                value = 2.0 * float(r.cost)
                if _same_optimum(found, r.x, value, spans) or fun.best_value <= PERFECT:
                    for _ in range(len(x0s) - len(found)):
                        tick()      # this start and the ones skipped: the bar completes
                    break           # an optimum found before, or an exact fit: more starts would repeat it
                found.append((r.x, value))
                if fun.rejected > rejected:
                    # derivative-free polish: the trust region stops where a constraint the model
                    # enforces by ValueError (kd + ks <= 1) cuts it
                    minimize(fun, fun.best_x, method="Nelder-Mead", bounds=bounds,
                             options=dict(maxfev=200 * (len(x) + 1), xatol=1e-9, fatol=1e-16))
        except _Timeout:
            pass
        tick()
        if fun.timed_out:
            break
    return fun.best_params(x0s[0])


def _fit_shared(problem, vars_, base, starts, seed, tick):
    """Steps 2-3: every free parameter, colours as scalars (channel means), fitted
    to the channel mean from the defaults and ``starts - 1`` seeded random points.
    Returns the parameters and the objectives used."""
    params = {k: float(np.mean(v)) if isinstance(v, np.ndarray) else v for k, v in base.items()}
    if not vars_:
        tick()
        return params, []
    rng = np.random.default_rng(seed)
    x_def = [v.fwd(params[v.name]) for v in vars_]
    x0s = [x_def] + [[rng.uniform(*v.bounds) for v in vars_] for _ in range(starts - 1)]
    x0s = [_feasible(problem.proto, params, vars_, x, rng) for x in x0s]
    obj = _Objective(problem, vars_, params, None)
    params.update(optimise(obj, x0s, tick))
    return params, [obj]


def _fit_channels(problem, cvars, params, base, tick):
    """Step 4: the colour parameters ``cvars`` refitted on each channel, from the
    shared fit, with the other parameters fixed (fixed colours at this channel's
    value): in closed form where that is exact (:func:`_linear_colours`), else by
    :func:`optimise` from the shared fit.  Returns the parameters with colours and the
    objectives used."""
    C = problem.tgt.channels
    per = {v.name: [] for v in cvars}
    objectives = []
    x_shared = [v.fwd(params[v.name]) for v in cvars]
    basis = {}
    for c in range(C):
        pc = dict(params)
        pc.update({k: float(np.asarray(v)[c]) for k, v in base.items()
                   if isinstance(v, np.ndarray) and v.size == C})
        obj = _Objective(problem, cvars, pc, c)
        objectives.append(obj)
        try:
            x = _linear_colours(obj, x_shared, basis)
        except _Timeout:
            x = None            # past the deadline: optimise() returns at once with the start
        if x is not None:
            tick()
            found = obj.best_params(x)
        else:
            found = optimise(obj, [x_shared], tick)
        for k, val in found.items():
            per[k].append(val)
    params = dict(params)
    params.update({k: np.array(vals) for k, vals in per.items() if len(vals) == C})
    return params, objectives


#: A model is linear in its colour variables (:func:`_linear_colours`) where ``f cos`` at a
#: check point differs from the linear prediction by at most this fraction of its largest value.
LINEAR_TOL = 1e-10


def _colour_basis(obj, x0):
    """``(c0, B)`` with ``c(x) = c0 + B x`` (``f cos`` on the pairs, this objective's channel)
    where the model is linear in the variables ``x`` of ``obj`` (every one untransformed), else
    None: ``B``'s columns from one step per variable from ``x0`` (half-way to its farther
    bound), checked at a third point that moves them all (0.6 of each step); every candidate a
    model accepts, in one launch."""
    if any(v.tf != "lin" for v in obj.vars):
        return None
    lo = np.array([v.bounds[0] for v in obj.vars])
    hi = np.array([v.bounds[1] for v in obj.vars])
    x0 = np.clip(np.asarray(x0, float), lo, hi)
    d = np.where(x0 - lo >= hi - x0, 0.5 * (lo - x0), 0.5 * (hi - x0))
    if np.any(d == 0.0):
        return None
    pts = [x0] + [x0 + dk * e for dk, e in zip(d, np.eye(len(x0)))] + [x0 + 0.6 * d]
    models, vals = obj._candidates(pts)
    obj.evaluations += len(pts)
    if any(m is None for m in models):
        return None
    cs = [_reduce(v[0], obj.problem.tgt.wo, obj.c).reshape(-1) for v in vals]
    B = np.column_stack([(ck - cs[0]) / dk for ck, dk in zip(cs[1:-1], d)])
    c0 = cs[0] - B @ x0
    scale = max(float(np.max(np.abs(np.concatenate(cs)))), 1e-300)
    if np.max(np.abs(c0 + B @ pts[-1] - cs[-1])) > LINEAR_TOL * scale:
        return None
    return c0, B


def _linear_colours(obj, x_shared, basis):
    """The colour step of ``l2-cos`` in closed form, where exact: the model linear in its colour
    variables (:func:`_colour_basis`: Ward's ``rd``, ``rs``; the basis computed once for every
    channel that shares the other parameters, kept in ``basis``), so the figure is a linear least
    squares within the variables' bounds, solved by SciPy's BVLS (an active-set method: the
    exact optimum).  Kept only where the model accepts the solution and its highlight lies inside
    the band (:func:`plausible.fitting.metrics.highlight_excess` zero: the highlight term, never
    negative, adds nothing, so the optimum of the sum) or has no weight (``highlight=0``); then
    ``obj`` holds it as its best point.
    Returns the variables, or None (the iterative fit decides)."""
    pb = obj.problem
    if pb.metric != "l2-cos" or not obj.vars:
        return None
    from .linear import bounded

    names = {v.name for v in obj.vars}
    key = tuple(sorted((k, repr(v)) for k, v in obj.params0.items() if k not in names))
    if key not in basis:
        basis[key] = _colour_basis(obj, x_shared)
    if basis[key] is None:
        return None
    c0, B = basis[key]
    g = np.asarray(obj.g, float).reshape(-1)
    den = math.sqrt(float(np.sum(g * g)))
    if den == 0.0:
        return None
    lo, hi = [np.array([v.bounds[k] for v in obj.vars]) for k in (0, 1)]
    x = bounded(B / den, (g - c0) / den, lo, hi)
    if pb.highlight > 0.0 and np.any(M.highlight_excess(c0 + B @ x, g, pb.rows, pb.eps) != 0.0):
        return None
    rejected = obj.rejected
    obj.residuals_many([x])              # the model at the solution: accepted, and kept as the best point
    return x if obj.rejected == rejected else None


def _reduce(f, wo, c):
    f = _fcos(f, wo)
    if f.ndim == 2:
        return f.mean(axis=-1) if c is None else f[:, c]
    return f


def _reduce_alb(a, c):
    if a.ndim == 2:
        return a.mean(axis=-1) if c is None else a[:, c]
    return a


def _feasible(proto, params, vars_, x, rng, tries=50):
    """``x``, or a seeded uniform point in the variables where the model rejects ``x``
    (its constraints between parameters, :func:`candidate`); ``x`` after ``tries``."""
    for _ in range(tries):
        ps = dict(params)
        ps.update({v.name: v.inv(xi) for v, xi in zip(vars_, x)})
        try:
            candidate(proto, ps)
            return list(x)
        except ValueError:
            x = [rng.uniform(*v.bounds) for v in vars_]
    return list(x)


def _free_params(info, proto, fixed, values):
    """Numeric parameters not fixed by the caller that change f on the sample set: each moved
    to 0.37 and 0.73 of its variable's range, every such model evaluated in one launch
    (``values``, the fit's :class:`_Values`)."""
    probes, models = [], [proto]
    for p in info.params:
        if p.name in fixed or not p.numeric or p.integer or p.default is None:
            continue
        v = _Var(p)
        for frac in (0.37, 0.73):
            ps = dict(proto.params)
            ps[p.name] = v.inv(v.bounds[0] + frac * (v.bounds[1] - v.bounds[0]))
            try:
                models.append(candidate(proto, ps))
                probes.append(p)
            except ValueError:
                continue
    ref, *alts = [f for f, _ in values.many(models)]
    out = []
    for p, alt in zip(probes, alts):
        if p not in out and not np.allclose(alt, ref, rtol=1e-12, atol=0):
            out.append(p)
    return [p for p in info.params if p in out]


def evaluate_fit(model, target, eps=None, combine: str = "sum", rows=None) -> dict:
    """Every metric's figure of ``model`` against ``target`` (albedo by the
    accurate integrator :func:`plausible.analysis.albedo_curve`).

    Returns
    -------
    dict with two keys:

    ``"errors"``
        the dict of :func:`plausible.fitting.metrics.errors`: ``l2-cos``,
        ``log``, ``perceptual``, ``fcos_max`` (``E_f``) and ``albedo_max``
        (``E_a``; None, and ``perceptual`` the ``fcos`` figure alone, when the
        target has no albedo), and ``highlight`` (how far the fit's brightest value per
        incidence lies outside the band around the target's, in log units: 0 within it);
    ``"albedo"``
        the model's directional albedo at the target's ``thetas`` (an array,
        channel-averaged to the target's shape), or None without a target albedo.

    ``rows``: the target's highlight (:func:`plausible.fitting.metrics.highlight_rows`), if known.

    Example: ``evaluate_fit(fit.model, "material:nickel@ngan2005/ward")["errors"]["log"]``."""
    tgt = as_target(target)
    if rows is None:
        rows = M.highlight_rows(np.broadcast_to(tgt.wi, np.shape(tgt.wo)), tgt.fcos)
    f = _fcos(model.eval(tgt.wi, tgt.wo), tgt.wo)
    g = tgt.fcos
    if f.ndim < g.ndim:
        f = np.broadcast_to(f[:, None], g.shape)
    elif f.ndim > g.ndim:
        f = f.mean(axis=-1)
    a = A = None
    if tgt.albedo is not None:
        a = np.asarray(albedo_curve(model, tgt.thetas).value)
        A = tgt.albedo
        if a.ndim < A.ndim:
            a = np.broadcast_to(a[:, None], A.shape)
        elif a.ndim > A.ndim:
            a = a.mean(axis=-1)
    return {"errors": M.errors(f, g, a, A, eps, combine, rows), "albedo": a}
