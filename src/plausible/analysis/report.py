"""``check(model)``: every plausibility property in one call, as a report."""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field

import numpy as np

from .adapters import as_bxdf, tolerances
from ..arrays.backend import eager
from ..integrals.albedo import (TOL as ALBEDO_TOL, albedos, direction, is_isotropic, pdf_integrals,
                                quadrature_reach)
from ..progress import start, within
from .. import arguments as A
from ..text import jsonable
from .checks import (ENERGY_THETAS, GUARD_SAMPLES, QUICK_ALBEDO_TOL, PropertyResult, energy, energy_directions,
                     grazing_thetas, reciprocity, sampling_consistency, value_problem)
from .chi2 import MAX_SAMPLES, AdaptiveBinning, chi2_many

#: The chi-square cells of ``check(quick=True)`` have settled when a refinement changes
#: each cell's expected fraction by at most this times the mean cell's
#: (:class:`~plausible.analysis.chi2.AdaptiveBinning`'s ``settle``; 1e-4 in the full check).
#: With the quick check's 50,000 samples and 16 x 16 cells the mean cell expects about 195
#: samples, whose count varies by 14: 1e-3 of the mean is 0.2 samples, 1/70 of that noise.
QUICK_SETTLE = 1e-3

#: Incidences (theta, phi in degrees) of the default chi-square tests.
CHI2_DIRECTIONS = ((0, 0), (45, 0), (80, 0))
CHI2_DIRECTIONS_ANISO = ((0, 0), (45, 0), (45, 60), (80, 30))


@dataclass
class CheckReport:
    """Outcome of :func:`check`: one :class:`PropertyResult` per property."""

    model: str
    params: dict
    results: list = field(default_factory=list)
    #: What the checker could not check, or excluded, and why (adapters' notes).
    notes: list = field(default_factory=list)
    #: Which directions the checks examined and what they cannot see (:func:`reach_of`):
    #: a PASS covers these and no more.
    reach: dict = field(default_factory=dict)

    @property
    def passed(self) -> bool:
        return all(r.passed for r in self.results)

    @property
    def verdict(self) -> str:
        """``PASS``, ``FAIL`` (some property fails) or ``UNRESOLVED`` (none fails, but
        some could not be established: :attr:`PropertyResult.unresolved`)."""
        if self.passed:
            return "PASS"
        return "FAIL" if any(not r.passed and not r.unresolved for r in self.results) else "UNRESOLVED"

    def __getitem__(self, name) -> PropertyResult:
        for r in self.results:
            if r.name == name:
                return r
        raise KeyError(name)

    def to_dict(self):
        """Plain data (JSON).  A check that was not applicable has ``passed`` and
        ``figure`` null (not a pass, not a number); ``counts`` tallies passed,
        failed and not applicable apart."""
        results = []
        for r in self.results:
            d = r.to_dict()
            if not applicable(r):
                d.update(passed=None, figure=None)
            results.append(d)
        n_a = sum(not applicable(r) for r in self.results)
        unresolved = sum(applicable(r) and r.unresolved for r in self.results)
        failed = sum(applicable(r) and not r.passed and not r.unresolved for r in self.results)
        counts = dict(passed=len(self.results) - n_a - failed - unresolved, failed=failed,
                      unresolved=unresolved, not_applicable=n_a)
        return jsonable(dict(model=self.model, params=self.params, passed=self.passed, verdict=self.verdict,
                             counts=counts,
                             results=results, notes=self.notes, reach=self.reach))

    def _repr_html_(self) -> str:
        from ..text import html_table

        return html_table(f"check {self.model}: {self.verdict}",
                          ["property", "figure", "bound", "verdict", "worst case"], self.rows())

    def to_json(self, **kw) -> str:
        return json.dumps(self.to_dict(), **kw)

    def as_claimed(self, info) -> bool:
        """Does the report agree with what the model claims (registry flags)?
        Sampling and chi-square must always pass; reciprocity and energy must
        pass when the model claims them."""
        need = ["sampling", "chi2"] + (["reciprocity"] if info.reciprocal else []) + \
            (["energy"] if info.energy_conserving else [])
        return all(self[n].passed for n in need)

    def rows(self):
        """(property, figure, bound, verdict, worst case) rows for a table."""
        out = []
        for r in self.results:
            w = {k: v for k, v in r.worst.items() if k not in ("wi", "wo", "problems", "cells")}
            worst = ", ".join(f"{k}={_short(v)}" for k, v in list(w.items())[:4])
            if r.worst.get("problems"):
                worst = r.worst["problems"][0] + ("; " + worst if worst else "")
            verdict = "N/A" if not applicable(r) else "PASS" if r.passed else \
                "UNRESOLVED" if r.unresolved else "FAIL"
            out.append((r.name, f"{r.figure:.6g}", r.bound, verdict, worst))
        return out

    def __str__(self):
        lines = [f"check {self.model} {self.params}: {self.verdict}"]
        lines += ["  " + " | ".join(r) for r in self.rows()]
        lines += ["  note: " + n for n in self.notes]
        lines += ["  reach: " + self.reach["text"]] if self.reach else []
        return "\n".join(lines)


def applicable(result) -> bool:
    """False for a check reported as not applicable (the object cannot do what it needs)."""
    return result.details.get("applicable", True) is not False


def not_applicable(name: str, reason: str) -> PropertyResult:
    """A check that was not run: ``passed`` (it found nothing wrong), figure NaN, the reason as bound."""
    return PropertyResult(name, True, math.nan, f"not applicable: {reason}", {}, dict(applicable=False,
                                                                                      reason=reason))


def _short(v):
    if isinstance(v, float):
        return f"{v:.4g}"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k}={_short(x)}" for k, x in v.items()) + "}"
    return str(v)


def check(model, *, alpha: float = 0.001, n_samples: int = 200_000, quick: bool = False,
          progress=None) -> CheckReport:
    """Run reciprocity, energy, sampling consistency and chi-square on ``model``.

    ``model``: a registered model, a model spec string (``"modified-phong:n=20"``),
    a ``mitsuba.BSDF`` or a callable ``f(wi, wo)`` (with optional ``pdf`` and
    ``sample``); :func:`plausible.analysis.adapters.as_bxdf` turns it into the
    contract.  What the object cannot do is reported as not applicable, with the
    reason; the adapter's tolerances (:func:`~plausible.analysis.adapters.tolerances`)
    follow its declared precision; further views it declares (a renderer's
    importance transport, a back side) are checked too, their results named
    ``"reciprocity [importance]"`` and so on.

    The chi-square significance ``alpha`` is family-wise over the tests run here
    (Sidak).  Its default, 0.001, keeps the registry-wide test suite (hundreds
    of chi-square tests) free of chance failures; a broken sampler gives
    p-values below 1e-10.  ``quick`` uses fewer directions and samples.  ``progress``:
    a :mod:`plausible.progress` factory, announced once with every step of every
    property and ticked after each.
    """
    alpha = A.probability("alpha", alpha)
    A.count("n_samples", n_samples, 4000 if quick else 1000, MAX_SAMPLES)     # quick mode's chi-square: a quarter
    model = as_bxdf(model)
    views = [("", model)] + list(model.views() if hasattr(model, "views") else [])
    rep = CheckReport(model.name, jsonable(model.params), notes=list(getattr(model, "notes", [])))
    ticks = _split_progress(progress, len(views))
    for label, m in views:
        with eager():   # the checks' sample, eval and pdf calls on the compiled kernels (see eager)
            sub = _check_one(m, alpha=alpha, n_samples=n_samples, quick=quick, progress=ticks)
        for r in sub.results:
            r.name += f" [{label}]" if label else ""
        rep.results += sub.results
        rep.reach = rep.reach or sub.reach
    if len(views) > 1:
        rep.notes.append("checked separately (they differ): " + ", ".join(lb for lb, _ in views[1:]))
    if hasattr(model, "annotate"):
        model.annotate(rep)
    return rep


def _split_progress(progress, n_views):
    """One announcement for all the views: the first view's total times ``n_views``
    (views check the same grids), then its ticks serve every view."""
    if n_views == 1:
        return progress
    state = {}

    def factory(total, label=""):
        if "tick" not in state:
            state["tick"] = start(progress, total * n_views, label)
        return state["tick"]

    return factory


def _albedos_of(model, wis, tol) -> list:
    """:func:`~plausible.integrals.albedo.albedos` of ``wis`` to the error bound ``tol``,
    each distinct incidence integrated once (all in one refinement)."""
    keys = [tuple(np.asarray(w, dtype=np.float64)) for w in wis]
    distinct = list(dict.fromkeys(keys))
    res = dict(zip(distinct, albedos(model, [np.array(k) for k in distinct], tol=tol))) if distinct else {}
    return [res[k] for k in keys]


#: Incidence (degrees) at which :func:`reach_of` measures the albedo quadrature's gaps.
REACH_THETA_DEG = 60.0


def reach_of(model, iso: bool, e_dirs, strata: tuple, n_sampling: int) -> dict:
    """What :func:`check` examines and what it cannot see, as data and one sentence.

    Reciprocity compares ``f`` on pairs of ``strata`` (polar x azimuthal) stratified
    directions; energy integrates the albedo at the incidences ``e_dirs`` by the
    quadrature of :mod:`plausible.integrals.albedo`, graded toward the mirror direction,
    the horizon and the model's ``peak_directions`` (and the tangent axes if anisotropic),
    guarded by :data:`~.checks.GUARD_SAMPLES` draws of the model's own sampler, which also
    gives the sampling check's ``n_sampling`` draws per incidence.  Away from those hints
    the quadrature's first rule leaves gaps up to ``blind_rad``
    (:func:`~plausible.integrals.albedo.quadrature_reach` at :data:`REACH_THETA_DEG`):
    a lobe narrower than that, pointed at by no hint and never drawn by the sampler, can
    hold energy that neither method sees, and falls between the reciprocity pairs too
    (issue 45: 1e-3 rad and albedo 0.1 passed both)."""
    wi = direction(math.radians(REACH_THETA_DEG), 0.0)
    blind = quadrature_reach(model, wi, axes=not iso)
    try:
        hints = [np.asarray(p, dtype=np.float64).round(6).tolist() for p in model.peak_directions(wi)]
    except Exception:   # noqa: BLE001  a foreign object without the hint: the mirror direction is the default
        hints = [[-float(wi[0]), -float(wi[1]), float(wi[2])]]
    cell = (90.0 / strata[0], 360.0 / strata[1])
    text = (f"reciprocity on {strata[0] * strata[1]} stratified directions ({cell[0]:.3g} x {cell[1]:.3g} deg "
            f"cells), energy at {len(e_dirs)} incidences by quadrature graded toward the mirror direction, "
            f"the horizon{', the tangent axes' if not iso else ''} and the model's peak hints ({len(hints)} at "
            f"{REACH_THETA_DEG:g} deg), guarded by {GUARD_SAMPLES} draws of its sampler; not seen: a lobe "
            f"narrower than {math.degrees(blind):.2g} deg ({blind:.2g} rad, the quadrature's widest gap away "
            f"from the hints) that no hint points at and the sampler never draws")
    return dict(reciprocity_directions=strata[0] * strata[1], reciprocity_cell_deg=cell,
                energy_incidences_deg=[list(d) for d in e_dirs], hints_at=dict(theta_deg=REACH_THETA_DEG,
                                                                                  directions=hints),
                guard_samples=GUARD_SAMPLES, sampling_samples=n_sampling, blind_rad=blind,
                blind_deg=math.degrees(blind), text=text)


def _check_one(model, *, alpha, n_samples, quick, progress) -> CheckReport:
    """The four checks of one contract (see :func:`check`)."""
    skip = getattr(model, "not_applicable", {})
    tol = tolerances(model)
    iso = getattr(model, "isotropic", None)
    iso = is_isotropic(model) if iso is None else iso
    chi_dirs = CHI2_DIRECTIONS if iso else CHI2_DIRECTIONS_ANISO
    thetas = (0, 30, 60, 80, 89.9) + grazing_thetas((1e-5, 1e-9)) if quick else ENERGY_THETAS
    e_dirs = energy_directions(model, thetas, (0.0,) if iso else None)
    s_thetas = (0, 45, 85) if quick else (0, 30, 60, 80, 89)
    s_phis = (0,) if iso else (0, 45)
    n_s = 20_000 if quick else 50_000
    total = 1 + len(e_dirs) + len(s_thetas) * len(s_phis) + len(chi_dirs)
    tick = start(progress, total, f"check {model.name}")
    rep = CheckReport(model.name, jsonable(model.params))
    if "reciprocity" in skip:
        rep.results.append(not_applicable("reciprocity", skip["reciprocity"]))
    else:
        rep.results.append(reciprocity(model, n_theta=8 if quick else 12, n_phi=16 if quick else 24,
                                       tol=tol["reciprocity"]))
    rep.reach = reach_of(model, iso, e_dirs, (8, 16) if quick else (12, 24), n_s)
    tick()
    # the albedos of the energy and the sampling checks' incidences, integrated together
    e_wis = [direction(math.radians(t), math.radians(p)) for t, p in e_dirs] if "energy" not in skip else []
    s_wis = ([direction(math.radians(t), math.radians(p))
              for p in ((0,) if is_isotropic(model) else s_phis) for t in s_thetas]
             if "sampling" not in skip else [])
    # a value that is no BRDF's (negative, infinite, NaN) fails energy and sampling by name: its albedos
    # would pass a comparison (NaN), take minutes to refine (infinite) or look conserving (negative)
    at_energy = value_problem(model, e_wis)      # tested once: energy is given what it found
    problem = at_energy or value_problem(model, s_wis)
    shared = _albedos_of(model, e_wis + s_wis, QUICK_ALBEDO_TOL if quick else ALBEDO_TOL) if problem is None else None
    if "energy" in skip:
        rep.results.append(not_applicable("energy", skip["energy"]))
        tick(len(e_dirs))
    else:
        rep.results.append(energy(model, thetas_deg=thetas, phis_deg=(0.0,) if iso else None,
                                  progress=within(tick), results=None if shared is None else shared[:len(e_wis)],
                                  problem=at_energy))
    if "sampling" in skip:
        rep.results.append(not_applicable("sampling", skip["sampling"]))
        tick(len(s_thetas) * len(s_phis))
    elif problem is not None:
        rep.results.append(PropertyResult("sampling", False, math.nan, "weight = f cos / pdf", dict(problems=[problem])))
        tick(len(s_thetas) * len(s_phis))
    else:
        rep.results.append(sampling_consistency(
            model, thetas_deg=s_thetas, phis_deg=s_phis, n_samples=n_s, tol=tol["sampling"],
            progress=within(tick), integrals=list(zip(pdf_integrals(model, s_wis), shared[len(e_wis):]))))
    if "chi2" in skip:
        rep.results.append(not_applicable("chi2", skip["chi2"]))
        tick(len(chi_dirs))
        return rep
    # every incidence's test together (cells refined in one launch per step, samples in one call);
    # incidence k draws from seed k, as one chi2 call per incidence does
    tests = chi2_many(model, [direction(math.radians(t), math.radians(p)) for t, p in chi_dirs],
                      seeds=range(len(chi_dirs)), alpha=alpha, n_tests=len(chi_dirs),
                      n_samples=n_samples // (4 if quick else 1),
                      binning=AdaptiveBinning(settle=QUICK_SETTLE) if quick else None)
    results = [(t, p, r) for (t, p), r in zip(chi_dirs, tests)]
    tick(len(chi_dirs))
    worst = min(results, key=lambda x: x[2].p_value)
    rep.results.append(PropertyResult(
        "chi2", all(r.passed for _, _, r in results), worst[2].p_value,
        f">= {worst[2].alpha:.3g} (p-value, Sidak over {len(results)} tests)",
        dict(theta_i_deg=worst[0], phi_i_deg=worst[1], message=worst[2].message,
             cells=worst[2].worst_cells[:3]),
        dict(tests=[dict(theta_deg=t, phi_deg=p, p_value=r.p_value, message=r.message) for t, p, r in results])))
    return rep
