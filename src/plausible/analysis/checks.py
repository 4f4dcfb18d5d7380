"""Plausibility checks on the model contract: reciprocity, energy, sampling.

Each check returns a :class:`PropertyResult` holding the figure measured, the
bound it is compared with, the verdict and the worst case, so a failure says
exactly where the model breaks.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass, field

import numpy as np

from .. import arguments as A
from ..bxdf import Sample
from ..progress import start
from ..text import jsonable
from ..integrals.albedo import albedos, direction, is_isotropic, pdf_integrals

#: ``cos(theta)`` of the incidences between 89.9 degrees and the horizon that every
#: energy check includes: albedos that diverge at grazing incidence (Ward 1992 as
#: ``1/sqrt(cos)``, Cook-Torrance with ``G = 1`` as ``1/cos``, and anything built on
#: them) stay below 1 at 89.9 degrees for smooth lobes and show only here.
GRAZING_COS = (1e-3, 1e-5, 1e-7, 1e-9)


def grazing_thetas(cosines=GRAZING_COS) -> tuple:
    """Polar angles in degrees whose cosines are ``cosines`` (to 1e-7 relative)."""
    return tuple(math.degrees(math.acos(c)) for c in cosines)


#: Incidence angles (degrees) of the default energy grid: dense toward grazing,
#: down to ``cos(theta) = 1e-9`` (:data:`GRAZING_COS`).
ENERGY_THETAS = (0, 10, 20, 30, 40, 50, 60, 70, 75, 80, 85, 88, 89, 89.5, 89.9) + grazing_thetas()
#: Azimuths (degrees) added for anisotropic models.
ENERGY_PHIS = (0, 22.5, 45, 67.5, 90, 135)


@dataclass
class PropertyResult:
    """One verified property: ``figure`` compared with ``bound``."""

    name: str
    passed: bool
    figure: float
    bound: str
    worst: dict = field(default_factory=dict)
    details: dict = field(default_factory=dict)
    #: The figure could not be established (the methods disagree, or a bound is too
    #: wide): neither a pass nor a failure of the model (``passed`` is False).
    unresolved: bool = False

    def to_dict(self):
        return jsonable(asdict(self))


def stratified_directions(n_theta: int, n_phi: int, rng, grazing: bool = True) -> np.ndarray:
    """One random direction in each of ``n_theta x n_phi`` strata of equal
    projected solid angle (``cos^2(theta)`` and ``phi`` uniform), plus, if
    ``grazing``, a ring of directions within 0.1 degree of the horizon."""
    i, j = np.meshgrid(np.arange(n_theta), np.arange(n_phi), indexing="ij")
    a = (i + rng.random(i.shape)) / n_theta
    b = (j + rng.random(j.shape)) / n_phi
    z = np.sqrt(1.0 - a).ravel()
    phi = 2 * math.pi * b.ravel()
    if grazing:
        zg = np.cos(np.radians(90 - rng.uniform(0.001, 0.1, n_phi)))
        z = np.concatenate([z, zg])
        phi = np.concatenate([phi, 2 * math.pi * (np.arange(n_phi) + rng.random(n_phi)) / n_phi])
    s = np.sqrt(np.maximum(1 - z * z, 0))
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


def reciprocity(model, *, n_theta: int = 12, n_phi: int = 24, tol: float = 1e-9,
                seed: int = 1) -> PropertyResult:
    """Max relative asymmetry ``|f(a,b) - f(b,a)| / max(|f(a,b)|, |f(b,a)|)`` over all
    pairs of stratified directions (Helmholtz reciprocity).  Values below
    ``1e-12`` of the largest ``f`` seen are compared absolutely to that floor."""
    A.count("n_theta", n_theta, 1)
    A.count("n_phi", n_phi, 1)
    A.real("tol", tol, 0.0)
    rng = np.random.default_rng(seed)
    d = stratified_directions(n_theta, n_phi, rng)
    a = np.repeat(d, len(d), axis=0)
    b = np.tile(d, (len(d), 1))
    f1 = model.eval(a, b)
    f2 = model.eval(b, a)
    if f1.ndim > 1:
        f1, f2 = f1.max(axis=-1), f2.max(axis=-1)
    floor = 1e-12 * max(float(np.max(np.abs(f1))), 1e-300)
    rel = np.abs(f1 - f2) / np.maximum(np.maximum(np.abs(f1), np.abs(f2)), floor)
    rel = np.where(np.isfinite(rel), rel, np.inf)
    k = int(np.argmax(rel))
    worst = dict(wi=a[k], wo=b[k], f_wi_wo=f1[k], f_wo_wi=f2[k],
                 theta_i_deg=math.degrees(math.acos(a[k][2])), theta_o_deg=math.degrees(math.acos(b[k][2])))
    fig = float(rel[k])
    return PropertyResult("reciprocity", fig <= tol, fig, f"<= {tol:g} (relative asymmetry)", worst,
                          dict(pairs=len(a)))


def energy_directions(model, thetas_deg=ENERGY_THETAS, phis_deg=None):
    if phis_deg is None:
        phis_deg = (0.0,) if is_isotropic(model) else ENERGY_PHIS
    return [(t, p) for p in phis_deg for t in thetas_deg]


#: The error bound to which ``check(quick=True)`` integrates the albedos of its energy and
#: sampling checks: ten times below the energy check's margin ``tol = 1e-4`` (the
#: bound of ``check --materials --quick``, :data:`plausible.analysis.materials.QUICK_TOL`); the full
#: check keeps :data:`plausible.integrals.albedo.TOL`.
QUICK_ALBEDO_TOL = 1e-5

#: Samples per incidence of the sampler's Monte Carlo albedo that guards :func:`energy`.
GUARD_SAMPLES = 1 << 12
#: Standard errors within which the guard and the quadrature agree.
GUARD_SIGMAS = 6.0


def guard_albedos(model, wis, n: int = GUARD_SAMPLES, seed: int = 11):
    """The model's own sampler as a second, independent estimate of the
    directional albedo at each incidence of ``wis``: ``(mean weight, standard
    error)`` (channel mean) from ``n`` samples each, all incidences in one call."""
    wis = np.asarray(wis, dtype=np.float64)
    u = np.random.default_rng(seed).random((len(wis), n, 3))
    s = model.sample(np.repeat(wis[:, None, :], n, axis=1), u)
    w = s.weight if s.weight.ndim == 2 else s.weight.mean(axis=-1)
    w = np.where(np.isfinite(w), w, np.inf)
    return w.mean(axis=1), w.std(axis=1, ddof=1) / math.sqrt(n)


#: :func:`energy`'s ``problem`` when the caller did not test the values.
_UNTESTED = object()


def value_problem(model, wis, seed: int = 5):
    """What makes ``f`` no BRDF, seen at the incidences ``wis`` on stratified outgoing directions
    (:func:`stratified_directions`, 8 x 16 and a grazing ring): a value that is not finite or one below
    zero, as one sentence naming the worst pair; None where every value is finite and non-negative.
    An albedo cannot show either (a negative ``f`` has an albedo below 1; an infinite or NaN one an
    albedo no comparison rejects), so :func:`energy` fails on it first."""
    wis = np.asarray(wis, dtype=np.float64).reshape(-1, 3)
    if not len(wis):
        return None
    wo = stratified_directions(8, 16, np.random.default_rng(seed))
    a, b = np.repeat(wis, len(wo), axis=0), np.tile(wo, (len(wis), 1))
    with np.errstate(all="ignore"):
        f = np.asarray(model.eval(a, b), dtype=np.float64).reshape(len(a), -1)
    finite = np.isfinite(f).all(axis=1)
    if not finite.all():
        k = int(np.argmin(finite))
        return (f"f is not finite ({', '.join(f'{x:g}' for x in f[k])}) at wi = {np.round(a[k], 4).tolist()}, "
                f"wo = {np.round(b[k], 4).tolist()} ({int((~finite).sum())} of {len(a)} pairs): no BRDF")
    low = f.min(axis=1)
    floor = -1e-12 * max(float(np.max(np.abs(f))), 1e-300)     # rounding of an exact 0 is no negative BRDF
    if low.min() < floor:
        k = int(np.argmin(low))
        return (f"f is negative ({low[k]:.6g}) at wi = {np.round(a[k], 4).tolist()}, wo = "
                f"{np.round(b[k], 4).tolist()} ({int((low < floor).sum())} of {len(a)} pairs): no BRDF (a BRDF is "
                f">= 0)")
    return None


def energy(model, *, thetas_deg=ENERGY_THETAS, phis_deg=None, tol: float = 1e-4,
           guard: bool | None = None, progress=None, results=None, problem=_UNTESTED) -> PropertyResult:
    """Max directional albedo over a grid of incidence directions (azimuths too
    for anisotropic models), by default from the normal to ``cos(theta) = 1e-9``;
    passes when ``max a <= 1 + tol``.  ``tol`` matches the
    integrator's accuracy target; each albedo's own error estimate is reported.

    ``guard`` (default: when the model has a sampler) compares each quadrature
    albedo with the model's own sampler (:func:`guard_albedos`, a second,
    independent method).  An incidence is *resolved* when the two agree within
    :data:`GUARD_SIGMAS` standard errors plus the quadrature's bound and that
    bound is at most ``tol``.  The verdict is three-way: **fails** where an albedo
    exceeds ``1 + tol`` by more than its bound and the sampler does not
    contradict it (agrees, or exceeds ``1 + tol`` too); else **unresolved**
    (``passed`` False, ``unresolved`` True) where an unresolved incidence could
    exceed ``1 + tol`` by either estimate; else passes.  So a lobe the quadrature
    cannot resolve is reported as such, not as energy gained.
    ``progress``: a :mod:`plausible.progress` factory, ticked per direction.
    ``results``: the albedos (:func:`~plausible.integrals.albedo.albedos`) of the
    directions of :func:`energy_directions`, if the caller computed them
    (:func:`plausible.check` does, together with the sampling check's); ``problem``: what
    :func:`value_problem` found at those incidences (or more), None for nothing, if the caller
    tested them (:func:`plausible.check` does, once for energy and sampling)."""
    A.angles_deg("thetas_deg", thetas_deg, 0.0, 90.0, open_hi=True)     # 90: no incidence (checked, kept as given)
    A.real("tol", tol, 0.0)
    dirs = energy_directions(model, thetas_deg, phis_deg)
    tick = start(progress, len(dirs), f"energy {model.name}")
    wis = [direction(math.radians(t), math.radians(p)) for t, p in dirs]
    if problem is _UNTESTED:
        problem = value_problem(model, wis)
    if problem is not None:
        tick(len(dirs))
        return PropertyResult("energy", False, math.nan, f"<= 1 + {tol:g} (max directional albedo)",
                              dict(problems=[problem]), dict(grid=[], guard=False, unresolved=0, onset_deg=None))
    res = albedos(model, wis) if results is None else list(results)
    if guard is None:
        guard = callable(getattr(model, "sample", None)) and "sampling" not in getattr(model, "not_applicable", {})
    mcs = guard_albedos(model, wis) if guard else (np.full(len(wis), np.nan), np.full(len(wis), np.nan))
    best = (-math.inf, None, None)
    curve, failed, unresolved = [], [], []
    for (t, p), r, mc, se in zip(dirs, res, *mcs):
        v = float(np.max(r.value))
        e = float(np.max(r.error))
        if not (math.isfinite(v) and math.isfinite(e)):      # f finite on the probes, its integral not
            v, e = math.inf, math.inf
        agree = not guard or abs(float(np.mean(r.value)) - mc) <= GUARD_SIGMAS * se + e + 1e-9
        resolved = agree and e <= tol
        curve.append(dict(theta_deg=t, phi_deg=p, albedo=v, error=e, resolved=resolved,
                          **(dict(sampler=float(mc), sampler_se=float(se)) if guard else {})))
        over_q = v - e > 1.0 + tol
        if over_q and (agree or mc - GUARD_SIGMAS * se > 1.0 + tol):
            failed.append(curve[-1])
        elif not resolved and max(v + e, mc + GUARD_SIGMAS * se if guard else -math.inf) > 1.0 + tol:
            unresolved.append(curve[-1])
        if v > best[0]:
            best = (v, (t, p), e)
        tick()
    fig, (t, p), e = best
    ok = not failed and not unresolved
    worst = dict(theta_i_deg=t, phi_i_deg=p, albedo=fig, error=e)
    if unresolved and not failed:
        u = max(unresolved, key=lambda c: c["albedo"])
        worst = dict(theta_i_deg=u["theta_deg"], phi_i_deg=u["phi_deg"], albedo=u["albedo"], error=u["error"],
                     problems=[f"unresolved: quadrature {u['albedo']:.6g} +- {u['error']:.2g}"
                               + (f" vs sampler {u['sampler']:.6g} +- {u['sampler_se']:.2g}" if guard else "")
                               + f" at theta_i = {u['theta_deg']:g} deg, phi_i = {u['phi_deg']:g} deg"])
    res = PropertyResult("energy", ok, fig, f"<= 1 + {tol:g} (max directional albedo)", worst,
                         dict(grid=curve, guard=guard, unresolved=len(unresolved),
                              onset_deg=next((c["theta_deg"] for c in curve if c["albedo"] > 1 + tol), None)),
                         unresolved=bool(unresolved and not failed))
    return res


#: The figures of :func:`sampling_consistency`, each the maximum over the incidences.
SAMPLING_FIGURES = ("weight_rel_err", "pdf_rel_err", "max_pdf_integral", "max_invalid_fraction",
                    "max_invalid_mismatch_sigma", "max_albedo_mismatch_sigma")


def sampling_consistency(model, *, thetas_deg=(0, 30, 60, 80, 89), phis_deg=(0, 45),
                         n_samples: int = 50_000, seed: int = 3, tol: float = 1e-6,
                         sigmas: float = 5.0, progress=None, integrals=None) -> PropertyResult:
    """Agreement of ``sample`` with ``eval`` and ``pdf`` at several incidences:

    * ``weight == eval * cos / pdf`` (max relative error),
    * ``pdf(wi, sampled wo) == returned pdf`` (max relative error),
    * the fraction of invalid samples (zero weight) and the pdf's integral over
      the hemisphere: ``int pdf <= 1`` and ``int pdf == 1 - invalid fraction``
      within ``sigmas`` binomial standard deviations,
    * Monte Carlo albedo (mean weight) against the deterministic albedo, within
      ``sigmas`` standard errors (a second, independent method).

    ``details`` holds each figure of :data:`SAMPLING_FIGURES` (the maximum over
    the incidences), ``worst`` where each was reached and the first problems.
    ``progress``: a :mod:`plausible.progress` factory, ticked per incidence.
    ``integrals``: the ``(pdf integral, albedo)`` pairs of the incidences (phi outer,
    theta inner), if the caller computed them (:func:`plausible.check` does, with
    the energy check's albedos); else they are computed here.
    """
    A.angles_deg("thetas_deg", thetas_deg, 0.0, 90.0, open_hi=True)
    n_samples = A.count("n_samples", n_samples, 1)
    rng = np.random.default_rng(seed)
    if is_isotropic(model):
        phis_deg = (0,)
    tick = start(progress, len(phis_deg) * len(thetas_deg), f"sampling {model.name}")
    figs = dict.fromkeys(SAMPLING_FIGURES, 0.0)
    worst = {}
    problems = []
    # the deterministic integrals (pdf, albedo) of every incidence, refined together
    wis = [direction(math.radians(t), math.radians(p)) for p in phis_deg for t in thetas_deg]
    if integrals is None:
        integrals = zip(pdf_integrals(model, wis), albedos(model, wis))
    integrals = iter(integrals)
    # every incidence's samples in one call each of sample, eval and pdf (the same random
    # numbers, in the same order, as one draw of n_samples per incidence)
    at_all = iter(_sampling_batches(model, wis, rng.random((len(wis) * n_samples, 3)), n_samples))
    for p in phis_deg:
        for t in thetas_deg:
            here = dict(theta_i_deg=t, phi_i_deg=p)
            at, msgs = _sampling_at(*next(at_all), tol, sigmas, *next(integrals))
            for key, val in at.items():
                if val > figs[key]:
                    figs[key] = float(val)
                    worst[key] = dict(here, value=float(val))
            problems += [f"{m} at {here}" for m in msgs]
            tick()
    fig = max(figs["weight_rel_err"], figs["pdf_rel_err"])
    return PropertyResult("sampling", not problems, fig,
                          f"rel. err <= {tol:g}; int pdf <= 1; MC albedo and invalid fraction within {sigmas:g} sigma",
                          dict(worst, problems=problems[:5]), figs)


def _sampling_batches(model, wis, u, n):
    """``(s, f, pdf)`` of each incidence of ``wis``: ``s = model.sample(wi, u_k)`` with
    ``u_k`` the ``k``-th block of ``n`` rows of ``u``, ``f = model.eval(wi, s.wo)`` and
    ``pdf = model.pdf(wi, s.wo)``, computed for all incidences together (one call of
    each: one launch each on Dr.Jit)."""
    wi_rows = np.repeat(np.asarray(wis, dtype=np.float64), n, axis=0)
    s = model.sample(wi_rows, u)
    f = model.eval(wi_rows, s.wo)
    pdf = model.pdf(wi_rows, s.wo)
    out = []
    for k in range(len(wis)):
        b = slice(k * n, (k + 1) * n)
        out.append((Sample(s.wo[b], s.weight[b], s.pdf[b]), f[b], pdf[b]))
    return out


def _sampling_at(s, f, pdf_wo, tol, sigmas, pint, ref):
    """The figures of :func:`sampling_consistency` at one incidence from its samples
    ``s``, ``f = eval(wi, s.wo)`` and ``pdf_wo = pdf(wi, s.wo)`` (``pint``, ``ref``:
    the pdf integral and the albedo at ``wi``, by quadrature), and a message for
    each that fails."""
    n = len(s.pdf)
    valid = s.pdf > 0
    # the weight the contract promises: f cos / pdf on valid samples, 0 on the others
    cos_over_pdf = np.maximum(s.wo[:, 2], 0) / np.where(valid, s.pdf, 1)
    if f.ndim > 1:                     # colour: one channel axis
        valid_c, cos_over_pdf = valid[:, None], cos_over_pdf[:, None]
    else:
        valid_c = valid
    expect = np.where(valid_c, f * cos_over_pdf, 0)
    werr = np.max(np.abs(s.weight - expect) / np.maximum(np.abs(expect), 1e-12))
    perr = np.max(np.abs(pdf_wo - s.pdf) / np.maximum(np.abs(s.pdf), 1e-12))
    finite = np.all(np.isfinite(s.weight)) and np.all(np.isfinite(s.pdf))
    # invalid fraction against the pdf's missing mass
    inv = 1.0 - valid.mean()
    sig_inv = math.sqrt(max(inv * (1 - inv), 1.0 / n) / n)
    inv_mis = abs((1.0 - pint.value) - inv) / (sig_inv + pint.error)
    # Monte Carlo albedo (mean weight, channel mean) against quadrature
    w = s.weight if s.weight.ndim == 1 else s.weight.mean(axis=-1)
    mc = w.mean()
    se = w.std(ddof=1) / math.sqrt(n)
    refv = float(np.mean(ref.value))
    # floor 1e-3 tol: 1e-9 for float64 models; 1e-7 for float32 renderers (adapters' tol 1e-4),
    # whose constant weights (a diffuse lobe) differ from the quadrature by float32 rounding
    alb_mis = abs(mc - refv) / (se + float(np.mean(ref.error)) + 1e-3 * tol)
    figs = dict(zip(SAMPLING_FIGURES, (werr, perr, pint.value, inv, inv_mis, alb_mis)))
    conds = [
        (werr <= tol, f"weight != eval*cos/pdf (rel. err {werr:.3g})"),
        (perr <= tol, f"pdf(wi, sampled wo) != returned pdf (rel. err {perr:.3g})"),
        (pint.value <= 1 + 1e-4, f"pdf integrates to {pint.value:.6f} > 1"),
        (inv_mis <= sigmas, f"invalid fraction {inv:.4f} vs 1 - int pdf = {1 - pint.value:.4f} "
                            f"({inv_mis:.1f} sigma)"),
        (alb_mis <= sigmas, f"Monte Carlo albedo {mc:.5f} +- {se:.1e} vs quadrature {refv:.5f} "
                            f"({alb_mis:.1f} sigma)"),
        (finite, "non-finite weight or pdf"),
    ]
    return figs, [msg for good, msg in conds if not good]
