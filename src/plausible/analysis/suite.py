"""Parameter sets used by ``plausible check --all`` and the registry-wide tests:
each model's defaults plus variants at the extremes its parameters declare."""

from __future__ import annotations

from .. import registry


def variants(name: str, max_variants: int = 4) -> list[dict]:
    """Parameter dicts: ``{}`` (defaults), then one parameter at a time set to
    each of its declared extremes (skipping combinations the model refuses)."""
    inf = registry.info(name)
    out = [{}]
    for p in inf.params:
        for v in p.extremes:
            if v != p.default:
                out.append({p.name: v})
    good = []
    for kw in out:
        try:
            inf.cls(**kw)
        except ValueError:
            continue
        good.append(kw)
    return good[:max_variants] if max_variants else good


def model_variants(name: str, max_variants: int = 4):
    inf = registry.info(name)
    return [inf.cls(**kw) for kw in variants(name, max_variants)]


def _check_one(model, quick):
    from .report import check

    try:
        return check(model, quick=quick)
    except Exception as e:  # noqa: BLE001 - one model's failure is reported, the others still run
        return e


def check_many(models, *, quick: bool = False, jobs: int = 1, progress=None) -> list:
    """:func:`plausible.check` of each model of ``models``, in order: a list holding
    each :class:`~plausible.analysis.report.CheckReport`, or the exception its
    check raised (the others still run).  ``jobs`` > 1: that many worker processes
    (spawned; each checks whole models, so every report is the one a single process
    gives, up to the rounding of the backend ``auto`` picks).  ``progress``: a
    :mod:`plausible.progress` factory, ticked after each model."""
    from ..progress import start

    models = list(models)
    tick = start(progress, len(models), "check")
    if jobs <= 1 or len(models) < 2:
        out = []
        for m in models:
            out.append(_check_one(m, quick))
            tick()
        return out
    import multiprocessing as mp
    from concurrent.futures import ProcessPoolExecutor

    out = [None] * len(models)
    with ProcessPoolExecutor(max_workers=jobs, mp_context=mp.get_context("spawn")) as pool:
        futures = {pool.submit(_check_one, m, quick): k for k, m in enumerate(models)}
        from concurrent.futures import as_completed

        for f in as_completed(futures):
            out[futures[f]] = f.result()
            tick()
    return out
