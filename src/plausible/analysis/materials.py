"""Which published fits are physically plausible?  ``check`` of every MERL fit.

For each material of each loadable fit set (:mod:`plausible.catalogue`) this
measures

* reciprocity: :func:`plausible.analysis.reciprocity` of the whole model (the
  largest relative asymmetry ``|f(a,b) - f(b,a)| / max|f|`` over pairs of
  stratified directions);
* energy: the directional albedo ``a(theta_i)`` on the grid :data:`THETAS_DEG`,
  its largest value over angles and RGB channels, and where it occurs.

The albedo of a :class:`~plausible.models.sum.Sum` is the sum of its parts'
albedos times their scales (the integral is linear), so each part is integrated
once with :func:`plausible.analysis.albedo` (grey, scale 1) and the scales are
applied after: the same integrator, a third of the work of integrating the RGB
sum.  ``tests/analysis/test_materials.py`` checks that the numbers agree with
``plausible.albedo(plausible.material(...), wi)``.  All fits are isotropic, so
one azimuth suffices.

``plausible check --materials [--fit FIT] [--quick] [--json] [--out DIR]`` runs
:func:`check_fits` and writes the tables of ``docs/materials.md`` with
:func:`write_tables` (``--out docs``).
"""

from __future__ import annotations

import csv
import io
import json
import math
from dataclasses import asdict, dataclass, fields as dataclass_fields
from pathlib import Path

import numpy as np

from ..arrays import backend
from ..arrays.ops import NP
from ..catalogue import fit_set, fits as all_fits, material, materials
from ..integrals.albedo import TOL as ALBEDO_TOL, AlbedoResult, albedos, direction
from ..progress import silent
from ..text import write_all_atomic
from .checks import reciprocity

#: Incidence angles (degrees) of the albedo grid: dense toward grazing, where
#: Ward's and Cook-Torrance's albedos grow.
THETAS_DEG = (0.0, 30.0, 60.0, 75.0, 85.0, 88.0, 89.5, 89.9)
THETAS = THETAS_DEG        # the name before the unit rule (degrees are named _deg)
#: An albedo above ``1 + TOL`` gains energy (the integrator's accuracy is ~2e-5).
TOL = 1e-4
#: Reciprocity verdict: relative asymmetry at most this.
RECIPROCITY_TOL = 1e-9
CHANNELS = "RGB"
#: ``quick``: the albedo's error bound (ten times below the margin :data:`TOL` of
#: the verdict, so no verdict changes) and the reciprocity grid (``n_theta, n_phi``).
QUICK_TOL = 1e-5
QUICK_RECIPROCITY = (8, 16)


@dataclass
class FitCheck:
    """One row: ``material`` in fit set ``fit``.

    ``asymmetry`` the largest relative asymmetry (reciprocity); ``max_albedo`` the
    largest directional albedo over :data:`THETAS_DEG` and channels, at ``theta_deg``
    in channel ``channel``; ``albedo_normal`` the largest channel at normal
    incidence; ``error`` the integrator's error estimate of ``max_albedo``;
    ``curve`` the largest channel's albedo at each angle of ``thetas_deg`` (degrees)."""

    material: str
    fit: str
    asymmetry: float
    max_albedo: float
    theta_deg: float
    channel: str
    albedo_normal: float
    error: float
    thetas_deg: tuple
    curve: tuple

    @property
    def reciprocal(self) -> bool:
        return self.asymmetry <= RECIPROCITY_TOL

    @property
    def gains_energy(self) -> bool:
        return self.max_albedo > 1.0 + TOL

    def to_dict(self):
        d = asdict(self)
        d.update(reciprocal=self.reciprocal, gains_energy=self.gains_energy)
        return d


def albedo_curve_of_sum(model, thetas_deg=THETAS_DEG, tol: float = ALBEDO_TOL):
    """``(values, errors)`` of shape ``(len(thetas_deg), channels)``: the directional
    albedo of a :class:`~plausible.models.sum.Sum` as ``sum_k s_k a_k(theta)``,
    each part's albedos at every angle refined together
    (:func:`~plausible.integrals.albedo.albedos`) to the error bound ``tol``."""
    ch = model.channels or 1
    vals = np.zeros((len(thetas_deg), ch))
    errs = np.zeros((len(thetas_deg), ch))
    wis = [direction(math.radians(t), 0.0) for t in thetas_deg]
    for part, scale in zip(model.parts, model.scales):
        s = np.ones(ch) if scale is None else np.broadcast_to(np.asarray(scale, dtype=np.float64), (ch,))
        exact = closed_form_albedo(part)
        results = [exact(w) for w in wis] if exact is not None else albedos(part, wis, tol=tol)
        for i, r in enumerate(results):
            v = np.broadcast_to(np.asarray(r.value, dtype=np.float64), (ch,))
            e = np.broadcast_to(np.asarray(r.error, dtype=np.float64), (ch,))
            vals[i] += s * v
            errs[i] += s * e
    return vals, errs


def closed_form_albedo(part):
    """``wi -> AlbedoResult`` (error 0) for a part whose every component declares its
    directional albedo (:attr:`plausible.bxdf.Lobe.albedo`: a diffuse lobe, e.g. the
    Lambertian of every fit, ``a = rd``), the sum of those albedos; None when a
    component declares none (a glossy lobe), which is then integrated.
    (``tests/test_lobes.py`` checks each declared albedo against quadrature.)"""
    lobes = part.components()
    if not lobes or any(lobe.albedo is None for lobe in lobes):
        return None

    def albedo_at(wi):
        if wi[2] <= 0:
            v = 0.0
        else:
            v = sum(np.asarray(lobe.albedo(NP, tuple(float(x) for x in wi), part.p), dtype=np.float64)
                    for lobe in lobes)
        v = np.broadcast_to(np.asarray(v, dtype=np.float64), (part.channels,)).copy() if part.channels \
            else float(v)
        return AlbedoResult(v, np.zeros_like(v) if part.channels else 0.0)

    return albedo_at


def check_fit(name: str, fit: str, thetas_deg=THETAS_DEG, quick: bool = False, albedo_tol=None) -> FitCheck:
    """The :class:`FitCheck` of one material of one fit set."""
    return check_model(material(name, fit), name, fit, thetas_deg, quick=quick, albedo_tol=albedo_tol)


def check_model(model, name: str = "", fit: str = "", thetas_deg=THETAS_DEG, quick: bool = False,
                albedo_tol=None) -> FitCheck:
    """The :class:`FitCheck` of any :class:`~plausible.models.sum.Sum` (``name``
    and ``fit`` only label the row).  ``quick``: albedos to :data:`QUICK_TOL`,
    reciprocity on the :data:`QUICK_RECIPROCITY` grid.  ``albedo_tol``: the albedos'
    error bound alone (default: :data:`QUICK_TOL` when ``quick``, else the
    integrator's default), the reciprocity grid kept."""
    # on the compiled kernels (backend.eager): the 2 x 97,344 pairs of the full grid
    # cost He-Torrance's NumPy series about 0.6 CPU-s a fit
    with backend.eager():
        if quick:
            rec = reciprocity(model, n_theta=QUICK_RECIPROCITY[0], n_phi=QUICK_RECIPROCITY[1])
        else:
            rec = reciprocity(model)
    if albedo_tol is None:
        albedo_tol = QUICK_TOL if quick else ALBEDO_TOL
    vals, errs = albedo_curve_of_sum(model, thetas_deg, albedo_tol)
    i, c = np.unravel_index(int(np.argmax(vals)), vals.shape)
    return FitCheck(name, fit, float(rec.figure), float(vals[i, c]), float(thetas_deg[i]),
                    CHANNELS[c] if vals.shape[1] == 3 else "grey", float(np.max(vals[0])),
                    float(errs[i, c]), tuple(float(t) for t in thetas_deg),
                    tuple(float(x) for x in vals.max(axis=1)))


def work_list(fits=None, names=None) -> list[tuple]:
    """``(material, fit)`` of every material (or ``names``) of every loadable fit
    set (or ``fits``), in table order.  Fit sets that cannot be loaded are
    skipped (see :attr:`plausible.catalogue.FitSet.reason`)."""
    keys = [fit_set(k).key for k in fits] if fits else [f.key for f in all_fits() if f.built]
    out = []
    for key in keys:
        if not fit_set(key).built:
            continue
        avail = materials(key)
        out.extend((name, key) for name in (names if names is not None else avail) if name in avail)
    return out


def _check_task(task, thetas_deg, quick, albedo_tol=None):
    name, key = task
    return check_fit(name, key, thetas_deg, quick, albedo_tol)


def check_fits(fits=None, names=None, *, thetas_deg=THETAS_DEG, progress=None, quick: bool = False,
               jobs: int = 1, albedo_tol=None, scheduler: str | None = None, journal=None,
               summary: list | None = None) -> list[FitCheck]:
    """:func:`check_fit` of every material (or ``names``) of every loadable fit
    set (or ``fits``; see :func:`work_list`; ``albedo_tol`` as in :func:`check_model`), in
    table order.  ``progress``, if given, is called with no argument after each fit.

    The batch engine (:func:`plausible.engine.run`) runs them: ``jobs`` > 1, that many
    spawned worker processes (each keeps its compiled kernels from fit to fit; a dead one
    is replaced and its fit checked once more); ``scheduler``, a running Dask scheduler's
    address instead.  ``journal``: a JSON Lines file where each row is appended as it
    finishes (:func:`read_journal`); rows already there with the same settings are not
    checked again (resume after an interrupt), and each fit is claimed (``.FILE.claims``
    beside it) so that runs sharing the journal share the work.  Rows another run holds
    are missing from the list returned then (compare with :func:`work_list`).
    ``summary``: the engine's :class:`~plausible.engine.RunSummary` is appended to it."""
    from functools import partial

    from .. import engine

    work = work_list(fits, names)
    settings = _settings(thetas_deg, quick, albedo_tol)
    got = read_journal(journal, settings) if journal is not None else {}

    def record(task, row):
        if journal is not None:
            try:
                engine.append_line(journal, json.dumps(dict(row.to_dict(), settings=settings)))
            except OSError as e:
                raise engine.BatchWriteError(f"cannot write {str(journal)!r} ({e.strerror or e}): the rows "
                                             "checked so far are kept there; free space or fix the permissions and "
                                             "run the same command again to resume") from None
        got[task] = row

    claims = None if journal is None else engine.Claims.beside(journal, "check")
    s = engine.run([t for t in work if t not in got], partial(_check_task, thetas_deg=thetas_deg, quick=quick,
                                                             albedo_tol=albedo_tol),
                   record, key=lambda t: json.dumps([t, settings]), claims=claims,
                   done=None if journal is None else lambda t: t in got or t in read_journal(journal, settings),
                   scheduler=scheduler, workers=jobs if jobs > 1 else 0, label="fits", progress=_factory(progress))
    if summary is not None:
        summary.append(s)
    if journal is not None:
        got.update(read_journal(journal, settings))
    return [got[t] for t in work if t in got]


def _factory(progress):
    """A :mod:`plausible.progress` factory whose ticks call ``progress()`` (None: silent)."""
    if progress is None:
        return silent

    def factory(total, label=""):
        def tick(n=1):
            for _ in range(n):
                progress()
        return tick

    return factory


def _settings(thetas_deg, quick, albedo_tol) -> dict:
    """What a journal's row was computed with (a row of other settings is not reused)."""
    from .. import __version__

    return dict(thetas_deg=[float(t) for t in thetas_deg], quick=bool(quick),
                albedo_tol=None if albedo_tol is None else float(albedo_tol), version=__version__)


def read_journal(path, settings: dict | None = None) -> dict:
    """``{(material, fit): FitCheck}`` of the rows of a :func:`check_fits` journal (those
    computed with ``settings``, when given); a line cut by an interrupt is skipped."""
    out = {}
    try:
        text = Path(path).read_text(encoding="utf-8", errors="replace")
    except FileNotFoundError:
        return out
    fields = {f.name for f in dataclass_fields(FitCheck)}
    for line in text.split("\n"):
        try:
            d = json.loads(line)
            if settings is not None and d.get("settings") != settings:
                continue
            row = FitCheck(**{k: (tuple(v) if isinstance(v, list) else v) for k, v in d.items() if k in fields})
        except (ValueError, TypeError, AttributeError):
            continue
        out[(row.material, row.fit)] = row
    return out


def summary(rows) -> list[dict]:
    """Per fit set: how many fits, how many gain energy, the largest albedo and
    where, the median of the largest albedos, the largest asymmetry."""
    out = []
    for key in dict.fromkeys(r.fit for r in rows):
        rs = [r for r in rows if r.fit == key]
        worst = max(rs, key=lambda r: r.max_albedo)
        out.append(dict(fit=key, n=len(rs), gain=sum(r.gains_energy for r in rs),
                        worst=worst.material, worst_albedo=worst.max_albedo, worst_theta=worst.theta_deg,
                        median=float(np.median([r.max_albedo for r in rs])),
                        asymmetry=max(r.asymmetry for r in rs)))
    return out


def markdown(rows, only_gains: bool = False) -> str:
    """The summary table, then one row per fit (only those gaining energy when
    ``only_gains``)."""
    lines = ["| fit | fits | gain energy | largest albedo (material, angle) | median of the largest albedos "
             "| largest asymmetry |", "|---|---|---|---|---|---|"]
    for s in summary(rows):
        lines.append(f"| {s['fit']} | {s['n']} | {s['gain']} | {s['worst_albedo']:.4f} ({s['worst']}, "
                     f"{s['worst_theta']:g}°) | {s['median']:.4f} | {s['asymmetry']:.1e} |")
    lines += ["", "| material | fit | reciprocal (asymmetry) | largest albedo | at θ_i | channel "
              "| albedo at 0° | gains energy |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        if only_gains and not r.gains_energy:
            continue
        gain = f"yes, +{100 * (r.max_albedo - 1):.1f} %" if r.gains_energy else "no"
        lines.append(f"| {r.material} | {r.fit} | {'yes' if r.reciprocal else 'NO'} ({r.asymmetry:.1e}) | "
                     f"{r.max_albedo:.4f} | {r.theta_deg:g}° | {r.channel} | {r.albedo_normal:.4f} | {gain} |")
    return "\n".join(lines) + "\n"


BEGIN, END = "<!-- table:begin -->", "<!-- table:end -->"


def write_tables(rows, out) -> list[Path]:
    """Write the tables of ``rows`` into the folder ``out``:
    ``materials-table.md`` (the summary and one row per fit), ``materials-table.csv``
    (the same numbers), and the summary with the fits that gain energy between the
    markers :data:`BEGIN` / :data:`END` of ``materials.md`` when it exists there.
    Returns the files written."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    md = out / "materials-table.md"
    files = {md: "# Plausibility of every published MERL fit\n\nGenerated by `plausible check --materials "
                 "--out docs` (see [materials.md](materials.md) for what is measured and how).\n\n"
                 + markdown(rows)}
    cs = out / "materials-table.csv"
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(["material", "fit", "asymmetry", "max_albedo", "theta_deg", "channel", "albedo_normal",
                "error", "gains_energy"])
    for r in rows:
        w.writerow([r.material, r.fit, f"{r.asymmetry:.3e}", f"{r.max_albedo:.6f}", f"{r.theta_deg:g}",
                    r.channel, f"{r.albedo_normal:.6f}", f"{r.error:.2e}", int(r.gains_energy)])
    files[cs] = buf.getvalue()
    doc = out / "materials.md"
    if doc.exists():
        text = doc.read_text()
        if BEGIN in text and END in text:
            head, rest = text.split(BEGIN, 1)
            _, tail = rest.split(END, 1)
            files[doc] = head + BEGIN + "\n" + markdown(rows, only_gains=True) + END + tail
    write_all_atomic(files)     # all or none: a full disk leaves no table without its CSV
    written = list(files)
    return written


__all__ = ["FitCheck", "QUICK_TOL", "THETAS", "THETAS_DEG", "albedo_curve_of_sum", "check_fit", "check_fits",
           "closed_form_albedo",
           "check_model", "markdown", "read_journal", "summary", "work_list", "write_tables"]
