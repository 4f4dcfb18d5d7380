"""The error table of ``docs/convert.md``: every published fit converted, resumably.

Each row is :func:`plausible.convert` of ``material:NAME@FIT`` to one target
(``mitsuba``, the family chosen per material, or ``gltf``), with its figures and the
albedo difference at 0, 45 and 75 degrees (the target's by its own sampler).
:func:`run_table` appends each row to a JSON Lines file as soon as it finishes
(one line, flushed), so an interrupted run loses at most the conversions in
flight, and a second run skips every row already there::

    plausible convert-table --out docs/convert-table.jsonl --workers 1     # resumes
    plausible convert-table --out docs/convert-table.jsonl --markdown docs/convert-table.md --limit 0

The order is round robin over the fit sets (the first material of every set, then
the second, ...), each material to every target in turn, so a partial table
covers every fit set alike.
"""

from __future__ import annotations

import json
import os
import time
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["TARGETS", "convert_row", "family", "jobs", "key", "markdown", "read_rows", "run_table", "summary"]

#: The targets of the table.
TARGETS = ("mitsuba", "gltf")


def jobs(targets=TARGETS, per_set: int | None = None, fits=None) -> list[tuple]:
    """``[(to, fit, material), ...]`` for every loadable fit set (or those named in
    ``fits``) and its materials (alphabetical; the first ``per_set`` if given), round
    robin over the fit sets (module docstring)."""
    from .. import catalogue

    sets = [fs.key for fs in catalogue.fits() if fs.built and (fits is None or fs.key in fits)]
    if fits is not None:
        unknown = sorted(set(fits) - set(sets))
        if unknown:
            raise ValueError(f"fits: no loadable fit set {', '.join(unknown)}; the loadable ones are {', '.join(sets)}")
    names = {k: sorted(catalogue.materials(k))[:per_set] for k in sets}
    out = []
    for i in range(max((len(v) for v in names.values()), default=0)):
        for k in sets:
            if i < len(names[k]):
                out += [(to, k, names[k][i]) for to in targets]
    return out


def key(row_or_job) -> str:
    """The row's identity: ``"TO material:NAME@FIT"``."""
    from .. import catalogue

    if isinstance(row_or_job, dict):
        return f"{row_or_job['to']} {catalogue.spec(row_or_job['material'], row_or_job['fit'])}"
    to, fit, name = row_or_job
    return f"{to} {catalogue.spec(name, fit)}"


@lru_cache(maxsize=None)
def code_version() -> str | None:
    """The git commit of the code that converts (``None`` outside a git checkout)."""
    import subprocess

    try:
        out = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=Path(__file__).parent, capture_output=True,
                             text=True, timeout=10)
    except (OSError, subprocess.SubprocessError):
        return None
    return out.stdout.strip() or None if out.returncode == 0 else None


def convert_row(job) -> dict:
    """One row: the conversion of ``job = (to, fit, material)``, its figures, and the
    commit of the code (:func:`code_version`)."""
    from .. import catalogue
    from . import convert

    to, fit, name = job
    t0 = time.monotonic()
    c = convert(catalogue.spec(name, fit), to=to).items[0]
    diffs = [c.albedo[k]["max_abs_difference"] for k in ("0", "45", "75")]
    return dict(to=to, fit=fit, material=name, target=c.target, perceptual=c.errors["perceptual"],
                l2=c.errors["l2-cos"], log=c.errors["log"], albedo_diff=diffs,
                source_albedo_max=max(max(v["source"]) for v in c.albedo.values()),
                conserving=not any("not energy conserving" in w for w in c.warnings),
                params=c.params, seconds=time.monotonic() - t0, code=code_version())


def read_rows(path) -> dict:
    """``{key: row}`` of a table file (a JSON Lines file; a line cut by an interrupt, the
    last one, is ignored; a later row of a key replaces an earlier one)."""
    p = Path(path)
    out = {}
    if not p.exists():
        return out
    for line in p.read_text().splitlines():
        try:
            r = json.loads(line)
        except ValueError:
            continue
        if isinstance(r, dict) and {"to", "fit", "material"} <= r.keys():
            out[key(r)] = r
    return out


def _append(path, row):
    """One line for ``row``, after a newline if an interrupt left the last line unfinished."""
    p = Path(path)
    cut = False
    if p.exists() and p.stat().st_size:
        with open(p, "rb") as f:
            f.seek(-1, os.SEEK_END)
            cut = f.read(1) != b"\n"
    with open(p, "a") as f:
        f.write(("\n" if cut else "") + json.dumps(row) + "\n")
        f.flush()
        os.fsync(f.fileno())


def _guarded(job):
    try:
        return convert_row(job)
    except Exception as e:      # a row that fails is recorded, not fatal to the run
        to, fit, name = job
        return dict(to=to, fit=fit, material=name, error=f"{type(e).__name__}: {e}")


def run_table(path, targets=TARGETS, *, per_set: int | None = None, fits=None, limit: int | None = None,
              workers: int = 0, on_row=None, redo=()) -> dict:
    """Convert the :func:`jobs` not yet in ``path`` and append each row as it finishes.

    ``workers``: 0 runs them one after another in this process; ``n >= 1`` in ``n``
    worker processes.  ``limit``: at most this many conversions this run.
    ``redo``: targets (``"mitsuba:diffuse"``, ...), fit sets (``"ngan2005/ward"``) or materials
    (``"material:NAME@FIT"``) whose rows made by other code than this (:func:`code_version`) are
    converted again first, in the order of :func:`jobs` (the new row replaces the old one).
    ``on_row(row)`` is called after each row is written.  Returns every row of ``path``."""
    if workers < 0:
        raise ValueError(f"workers must be >= 0, got {workers}")
    done = read_rows(path)
    redo = set(redo)
    def wanted(j):
        r = done[key(j)]
        return bool({r.get("target"), r.get("fit"), key(j).split(" ", 1)[1]} & redo)

    again = [j for j in jobs(targets, per_set, fits) if key(j) in done and wanted(j)
             and done[key(j)].get("code") != code_version()]
    todo = again + [j for j in jobs(targets, per_set, fits) if key(j) not in done]
    if limit is not None:
        todo = todo[:max(0, int(limit))]
    Path(path).parent.mkdir(parents=True, exist_ok=True)

    def finish(row):
        _append(path, row)
        if on_row is not None:
            on_row(row)

    if workers == 0 or len(todo) <= 1:
        for j in todo:
            finish(_guarded(j))
    else:
        from concurrent.futures import ProcessPoolExecutor, as_completed

        with ProcessPoolExecutor(max_workers=workers) as ex:
            futs = [ex.submit(_guarded, j) for j in todo]
            for f in as_completed(futs):
                finish(f.result())
    return read_rows(path)


def markdown(rows: dict, tolerance: float | None = None) -> str:
    """The table's markdown: per target, a summary per fit set, then every row."""
    from . import TOLERANCE

    tol = TOLERANCE if tolerance is None else tolerance
    good = [r for r in rows.values() if "error" not in r]
    out = []
    for to in sorted(dict.fromkeys(r["to"] for r in good), key=lambda t: (TARGETS + (t,)).index(t)):
        out.append(_markdown([r for r in good if r["to"] == to], to, tol))
    failed = [r for r in rows.values() if "error" in r]
    if failed:
        out.append("#### failed conversions\n\n" + "\n".join(f"* {key(r)}: {r['error']}" for r in failed) + "\n")
    return "\n".join(out)


def summary(rows, tol) -> list[dict]:
    """Per fit set: conversions, within ``tol`` (of the conserving sources), median
    perceptual, largest albedo difference, median seconds."""
    out = []
    for fit in dict.fromkeys(r["fit"] for r in rows):
        rs = [r for r in rows if r["fit"] == fit]
        cons = [r for r in rs if r["conserving"]]
        out.append(dict(fit=fit, n=len(rs), within=sum(max(r["albedo_diff"]) <= tol for r in cons), conserving=len(cons),
                        perceptual=float(np.median([r["perceptual"] for r in rs])),
                        worst=max(max(r["albedo_diff"]) for r in rs),
                        seconds=float(np.median([r["seconds"] for r in rs]))))
    return out


def family(row) -> str:
    """The family of a row's target: its Mitsuba type, ``blendbsdf-tir`` for the ``blendbsdf`` whose
    ``bsdf_0`` is the coat of :data:`plausible.conversion.mitsuba.TIR_COAT` (a ``roughplastic``)."""
    name = row["target"].split(":", 1)[-1]
    params = row.get("params") or {}
    if name == "blendbsdf" and isinstance(params.get("bsdf_0"), dict) and params["bsdf_0"].get("type") == "roughplastic":
        return "blendbsdf-tir"
    return name


def _markdown(rows, to, tol) -> str:
    s = summary(rows, tol)
    lines = [f"#### to {to}: summary", "",
             f"| fit set | conversions | within {tol:g} (conserving sources) | median perceptual | "
             "largest albedo diff. | median seconds |", "|---|---|---|---|---|---|"]
    lines += [f"| {r['fit']} | {r['n']} | {r['within']} / {r['conserving']} | {r['perceptual']:.3g} | {r['worst']:.3f} | "
              f"{r['seconds']:.1f} |" for r in s]
    lines += ["", f"#### every conversion to {to}", "",
              f"| fit set | material | target | perceptual | l2-cos | log | albedo diff. 0 / 45 / 75 deg | within {tol:g} | seconds |",
              "|---|---|---|---|---|---|---|---|---|"]
    for r in sorted(rows, key=lambda r: (r["fit"], r["material"])):
        ok = max(r["albedo_diff"]) <= tol
        lines.append(f"| {r['fit']} | {r['material']} | {family(r)} | {r['perceptual']:.3g} | "
                     f"{r['l2']:.3g} | {r['log']:.3g} | " + " / ".join(f"{d:.3f}" for d in r["albedo_diff"])
                     + f" | {'yes' if ok else ('no' if r['conserving'] else 'no (source not conserving)')} | "
                     f"{r['seconds']:.1f} |")
    return "\n".join(lines) + "\n"
