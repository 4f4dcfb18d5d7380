"""The error table of ``docs/convert.md``: every published fit converted, resumably.

Each row is :func:`plausible.convert` of ``material:NAME@FIT`` to one target
(``mitsuba``, the family chosen per material, or ``gltf``), with its figures and the
albedo difference at 0, 45 and 75 degrees (the target's by its own sampler).
:func:`run_table` appends each row to a JSON Lines file as soon as it finishes
(one line, flushed), so an interrupted run loses at most the conversions in
flight, and a second run skips every row already there.  The batch engine
(:mod:`plausible.engine`, shared with ``fit-batch`` and ``check --materials``) claims
each conversion, so that two runs on one file share the work and write each row once,
and runs them here, in worker processes or on a Dask scheduler::

    plausible convert-table --out docs/convert-table.jsonl --workers 1     # resumes
    plausible convert-table --out docs/convert-table.jsonl --markdown docs/convert-table.md --limit 0

The order is round robin over the fit sets (the first material of every set, then
the second, ...), each material to every target in turn, so a partial table
covers every fit set alike.
"""

from __future__ import annotations

import json
import time
from functools import lru_cache
from pathlib import Path

import numpy as np

__all__ = ["ISSUE_CASES", "TARGETS", "agreement", "convert_row", "distribution", "distribution_markdown", "family", "jobs", "key", "markdown", "read_rows", "run_table", "sample", "score_row", "summary", "target_of",
           "unwarned", "warning_cell"]

#: The targets of the table.
TARGETS = ("mitsuba", "gltf")


def jobs(targets=TARGETS, per_set: int | None = None, fits=None) -> list[tuple]:
    """``[(to, fit, material), ...]`` for every loadable fit set (or those named in
    ``fits``) and its materials (alphabetical; the first ``per_set`` if given), round
    robin over the fit sets (module docstring)."""
    from .. import catalogue

    loadable = [fs.key for fs in catalogue.fits() if fs.built]
    sets = [k for k in loadable if fits is None or k in fits]
    if fits is not None:
        unknown = sorted(set(fits) - set(sets))
        if unknown:     # the list of all loadable sets (it was the requested ones found: empty for a typo)
            raise ValueError(f"fits: no loadable fit set {', '.join(unknown)}; the loadable ones are "
                             f"{', '.join(loadable)}")
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
                params=c.params, seconds=time.monotonic() - t0, code=code_version(), **_looks_fields(c.looks))


def _looks_fields(looks) -> dict:
    """A row's image scores (:func:`plausible.compare_looks`, source beside target): FLIP, the
    worst and per-angle highlight ratios, and the looks' warnings (empty within the band)."""
    if looks is None:
        return {}
    return dict(flip=looks.flip, highlight_ratio=looks.highlight_ratio, highlight_ratios=list(looks.highlight_ratios),
                looks_warnings=list(looks.warnings))


def target_of(row):
    """What a row's target renders as: its Mitsuba dict (``mitsuba``) or the ``gltf-pbr`` model of
    its parameters (``gltf``)."""
    if row["to"] == "gltf":
        from .. import registry
        from . import GLTF_MODEL

        return registry.make(GLTF_MODEL, **row["params"])
    return row["params"]


def agreement(rows: dict, row) -> dict | None:
    """``row``'s glTF row of the same material with ``agreement``: the Mitsuba and glTF targets
    compared with each other (:func:`plausible.compare_looks`, the Mitsuba target the reference;
    issue 41), once both rows are in ``rows`` with their own image scores; None when there is
    nothing new."""
    if row.get("to") not in ("mitsuba", "gltf") or "error" in row:
        return None
    pair = {to: rows.get(key((to, row["fit"], row["material"]))) for to in ("mitsuba", "gltf")}
    if any(r is None or "error" in r or "flip" not in r for r in pair.values()):
        return None                     # a row missing, failed, or made before the image scores
    if pair["gltf"].get("agreement", {}).get("mitsuba") == pair["mitsuba"]["params"]:
        return None                     # already compared with this Mitsuba target
    from ..mitsuba.looks import compare_looks

    try:
        looks = compare_looks(target_of(pair["mitsuba"]), target_of(pair["gltf"]))
    except (ValueError, ImportError) as e:
        return {**pair["gltf"], "agreement": {"error": str(e), "mitsuba": pair["mitsuba"]["params"]}}
    return {**pair["gltf"], "agreement": dict(flip=looks.flip, highlight_ratio=looks.highlight_ratio,
                                              highlight_ratios=list(looks.highlight_ratios),
                                              mitsuba=pair["mitsuba"]["params"])}


def read_rows(path, problems: list | None = None) -> dict:
    """``{key: row}`` of a table file (a JSON Lines file; a line cut by an interrupt, the
    last one, is ignored; a later row of a key made by other code replaces an earlier one:
    ``--redo``).  A second row of a key made by the same code is a duplicate: dropped, and
    reported in ``problems`` (if given) as ``file:line: reason``."""
    return _Rows(path).update(problems)


class _Rows:
    """The rows of a table file, read incrementally (each :meth:`update` reads only the
    whole lines appended since the last), so a run can ask after each claim whether another
    run wrote the row meanwhile."""

    def __init__(self, path):
        self.path, self.offset, self.line, self.open = Path(path), 0, 0, False
        self.rows, self.lines = {}, {}

    def update(self, problems: list | None = None) -> dict:
        try:
            with open(self.path, "rb") as f:
                f.seek(self.offset)
                data = f.read()
        except FileNotFoundError:
            return self.rows
        end = data.rfind(b"\n") + 1
        if end < len(data) and _row(data[end:]) is not None:
            end = len(data)            # a whole last row lacking only its newline
        skip = int(self.open and data.startswith(b"\n"))     # the newline that ends that row
        chunk = data[skip:end].decode("utf-8", errors="replace")
        self.offset += end
        if end:
            self.open = not data[:end].endswith(b"\n")
        lines = chunk.split("\n") if chunk else []
        if lines and lines[-1] == "":
            lines.pop()
        for text in lines:
            self.line += 1
            r = _row(text.encode())
            if r is None:       # a damaged line (a whole one: a cut last line is not read yet)
                if problems is not None and text.strip():
                    problems.append(f"{self.path}:{self.line}: not a row of this table (not JSON, or no "
                                    f"to/fit/material); ignored (a conversion it held is made again)")
                continue
            k = key(r)
            if k in self.rows and self.rows[k].get("code") == r.get("code"):
                if problems is not None:
                    problems.append(f"{self.path}:{self.line}: a second row of {k} (the first at line "
                                    f"{self.lines[k]}); dropped")
                continue
            self.rows[k], self.lines[k] = r, self.line
        return self.rows


def _row(line: bytes):
    try:
        r = json.loads(line)
    except ValueError:
        return None
    return r if isinstance(r, dict) and {"to", "fit", "material"} <= r.keys() else None


def _guarded(job, row=None):
    """``row(job)`` (default :func:`convert_row`), or a row with the error when it raises."""
    try:
        return (row or convert_row)(job)
    except Exception as e:      # a row that fails is recorded, not fatal to the run
        return _error_row(job, e)


def _error_row(job, e) -> dict:
    to, fit, name = job
    return dict(to=to, fit=fit, material=name, error=f"{type(e).__name__}: {e}")


def run_table(path, targets=TARGETS, *, per_set: int | None = None, fits=None, limit: int | None = None,
              workers: int = 0, on_row=None, redo=(), scheduler: str | None = None, row=None,
              problems: list | None = None, summary: list | None = None, todo_jobs=None,
              make_row=None) -> dict:
    """Convert the :func:`jobs` not yet in ``path`` and append each row as it finishes.

    The batch engine (:func:`plausible.engine.run`) runs them: ``workers``: 0 one after
    another in this process; ``n >= 1`` in ``n`` spawned worker processes (a dead one is
    replaced and its conversion tried once more, then recorded as failed);
    ``scheduler``: the address of a running Dask scheduler instead.  Each conversion is
    claimed (``.FILE.claims`` beside ``path``) just before it starts and the file re-read
    for it, so that runs sharing the file share the work and write each row once.
    ``limit``: at most this many conversions this run.
    ``redo``: targets (``"mitsuba:diffuse"``, ...), fit sets (``"ngan2005/ward"``) or materials
    (``"material:NAME@FIT"``) whose rows made by other code than this (:func:`code_version`) are
    converted again first, in the order of :func:`jobs` (the new row replaces the old one).
    ``row(job)`` (or ``make_row``): the row of a job (default :func:`convert_row`; with workers or a
    scheduler, a module-level function).  ``todo_jobs``: these jobs instead of :func:`jobs` (e.g. a
    :func:`sample`).  A glTF row whose material's Mitsuba row is written too is appended again with
    ``agreement`` (:func:`agreement`: the two targets rendered side by side).  ``on_row(row)`` is called after each row is written.
    ``problems``: duplicated rows are listed here (:func:`read_rows`); ``summary``: the
    engine's :class:`~plausible.engine.RunSummary` is appended to it.  Returns every row of
    ``path``."""
    from functools import partial

    from .. import engine

    row = row or make_row
    if workers < 0:
        raise ValueError(f"workers must be >= 0, got {workers}")
    seen = _Rows(path)
    done = seen.update(problems)
    redo = set(redo)

    def wanted(j):
        r = done[key(j)]
        return bool({r.get("to"), r.get("target"), r.get("fit"), key(j).split(" ", 1)[1]} & redo)

    every = list(todo_jobs) if todo_jobs is not None else jobs(targets, per_set, fits)
    from .mitsuba import FAMILIES

    names = ({j[0] for j in every} | {j[1] for j in every} | {key(j).split(" ", 1)[1] for j in every}
             | {r.get("target") for r in done.values()} | {f"mitsuba:{k}" for k in FAMILIES} | {"gltf"})
    unknown = sorted(redo - names)
    if unknown:     # was ignored: nothing redone, and no word of it
        raise ValueError(f"redo: {', '.join(map(repr, unknown))} names no target, fit set or material "
                         f"(material:NAME@FIT) of this table")
    again = [j for j in every if key(j) in done and wanted(j) and done[key(j)].get("code") != code_version()]
    todo = again + [j for j in every if key(j) not in done]
    if limit is not None:
        todo = todo[:max(0, int(limit))]
    stored = []

    def record(job, r):
        try:
            engine.append_line(path, json.dumps(r))
        except OSError as e:
            raise engine.BatchWriteError(f"cannot write {str(path)!r} ({e.strerror or e}): {len(stored)} rows of "
                                         "this run are stored; free space or fix the permissions and run the "
                                         "same command again to resume") from None
        stored.append(key(r))
        if on_row is not None:
            on_row(r)
        both = agreement(seen.update(), r)      # the glTF row again, with the Mitsuba target beside it
        if both is not None:
            engine.append_line(path, json.dumps(both))

    def written(job):
        r = seen.update().get(key(job))
        return r is not None and (job not in again or r.get("code") == code_version())

    s = engine.run(todo, partial(_guarded, row=row) if row else _guarded, record, key=key, claims=_claims(path),
                   done=written, failed=_error_row, scheduler=scheduler, workers=workers, label="conversions")
    if summary is not None:
        summary.append(s)
    return read_rows(path)


def _claims(path):
    """The claims of a table file: the folder ``.FILE.claims`` beside it (made now, so an
    unwritable place fails before any work)."""
    from .. import engine

    p = Path(path)
    claims = engine.Claims.beside(p, "convert")
    try:
        claims.folder.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise engine.BatchWriteError(f"cannot write beside {str(p)!r} ({e.strerror or e}); nothing was "
                                     "converted") from None
    return claims


def markdown(rows: dict, tolerance: float | None = None) -> str:
    """The table's markdown: per target, a summary per fit set, then every row."""
    from . import TOLERANCE

    tol = TOLERANCE if tolerance is None else tolerance
    good = [r for r in rows.values() if "error" not in r]
    out = []
    for to in sorted(dict.fromkeys(r["to"] for r in good), key=lambda t: (TARGETS + (t,)).index(t)):
        out.append(_markdown([r for r in good if r["to"] == to], to, tol))
    silent = unwarned(good)
    if silent:
        out.append("#### outside the highlight band without their warning\n\n"
                   + "\n".join(f"* {k}: {why}" for k, why in silent) + "\n")
    failed = [r for r in rows.values() if "error" in r]
    if failed:
        out.append("#### failed conversions\n\n" + "\n".join(f"* {key(r)}: {r['error']}" for r in failed) + "\n")
    return "\n".join(out)


def summary(rows, tol) -> list[dict]:
    """Per fit set: conversions, within ``tol`` (of the conserving sources), median
    perceptual, largest albedo difference, median seconds; of the rows with image scores,
    median FLIP and how many have a highlight outside the band (:func:`plausible.compare_looks`)."""
    out = []
    for fit in dict.fromkeys(r["fit"] for r in rows):
        rs = [r for r in rows if r["fit"] == fit]
        cons = [r for r in rs if r["conserving"]]
        looked = [r for r in rs if "flip" in r]
        out.append(dict(fit=fit, n=len(rs), within=sum(max(r["albedo_diff"]) <= tol for r in cons), conserving=len(cons),
                        perceptual=float(np.median([r["perceptual"] for r in rs])),
                        worst=max(max(r["albedo_diff"]) for r in rs),
                        seconds=float(np.median([r["seconds"] for r in rs])),
                        looked=len(looked), flip=float(np.median([r["flip"] for r in looked])) if looked else None,
                        off_band=sum(bool(r["looks_warnings"]) for r in looked)))
    return out


def unwarned(rows, band=None) -> list[tuple[str, str]]:
    """``[(key, why), ...]``: the rows with image scores whose highlight ratio at some light angle lies
    outside ``band`` (default :data:`plausible.mitsuba.looks.HIGHLIGHT_BAND`) and whose
    ``looks_warnings`` do not name it ("highlight lost"/"highlight invented" with that ratio, as
    :func:`plausible.compare_looks` writes them).  Issue 40: every conversion outside the band carries
    its warning; :func:`markdown` lists these rows under their own heading."""
    from ..mitsuba.looks import HIGHLIGHT_BAND

    lo, hi = HIGHLIGHT_BAND if band is None else band
    out = []
    for r in rows:
        if "flip" not in r:
            continue
        said = " ".join(r.get("looks_warnings") or ())
        for ratio in r.get("highlight_ratios") or [r["highlight_ratio"]]:
            word = "lost" if ratio < lo else "invented" if ratio > hi else None
            if word and not (f"highlight {word}" in said and f"{ratio:.3g}x" in said):
                out.append((key(r), f"highlight {word} ({ratio:.3g}x) without its warning"))
    return out


def warning_cell(row) -> str:
    """The table's cell of a row's looks warnings: ``lost 0.364x at 0 deg`` per ratio outside the band,
    ``-`` for none (each taken from the row's ``looks_warnings``, as the conversion printed them)."""
    import re

    parts = []
    for w in row.get("looks_warnings") or ():
        m = re.match(r"highlight (lost|invented): the result's highlight under the light is (.*) \(band", w)
        parts.append(f"{m.group(1)} " + m.group(2).replace(" the source's", "") if m else w)
    return "; ".join(parts) or "-"


def family(row) -> str:
    """The family of a row's target: its Mitsuba type, ``blendbsdf-tir`` for the ``blendbsdf`` whose
    ``bsdf_0`` is the coat of :data:`plausible.conversion.mitsuba.TIR_COAT` (a ``roughplastic``)."""
    name = row["target"].split(":", 1)[-1]
    params = row.get("params") or {}
    if name == "blendbsdf" and isinstance(params.get("bsdf_0"), dict) and params["bsdf_0"].get("type") == "roughplastic":
        return "blendbsdf-tir"
    return name


def _cell(v, fmt_=".3f", prefix=""):
    return "-" if v is None else f"{prefix}{v:{fmt_}}"


def _markdown(rows, to, tol) -> str:
    s = summary(rows, tol)
    lines = [f"#### to {to}: summary", "",
             f"| fit set | conversions | within {tol:g} (conserving sources) | median perceptual | "
             "largest albedo diff. | median FLIP | highlight outside the band | median seconds |",
             "|---|---|---|---|---|---|---|---|"]
    lines += [f"| {r['fit']} | {r['n']} | {r['within']} / {r['conserving']} | {r['perceptual']:.3g} | {r['worst']:.3f} | "
              f"{_cell(r['flip'])} | {r['off_band']} / {r['looked']} | {r['seconds']:.1f} |" for r in s]
    pair = to == "gltf"
    lines += ["", f"#### every conversion to {to}", "",
              f"| fit set | material | target | perceptual | l2-cos | log | albedo diff. 0 / 45 / 75 deg | within {tol:g} | "
              "FLIP | highlight | looks warning | " + ("vs Mitsuba: FLIP / highlight | " if pair else "") + "seconds |",
              "|---|---|---|---|---|---|---|---|---|---|---|" + ("---|" if pair else "") + "---|"]
    for r in sorted(rows, key=lambda r: (r["fit"], r["material"])):
        ok = max(r["albedo_diff"]) <= tol
        agree = r.get("agreement") or {}
        vs = (f"{_cell(agree.get('flip'))} / {_cell(agree.get('highlight_ratio'), '.3g', 'x')} | " if pair else "")
        lines.append(f"| {r['fit']} | {r['material']} | {family(r)} | {r['perceptual']:.3g} | "
                     f"{r['l2']:.3g} | {r['log']:.3g} | " + " / ".join(f"{d:.3f}" for d in r["albedo_diff"])
                     + f" | {'yes' if ok else ('no' if r['conserving'] else 'no (source not conserving)')} | "
                     f"{_cell(r.get('flip'))} | {_cell(r.get('highlight_ratio'), '.3g', 'x')} | "
                     f"{warning_cell(r) if 'flip' in r else '-'} | {vs}{r['seconds']:.1f} |")
    return "\n".join(lines) + "\n"


# -- the image scores of a sample (issue 40; docs/convert.md, "The look of a conversion") ----------------

#: The conversions issue 40 names, always in a sample: highlights lost to glTF (alum-bronze, nickel),
#: a red plastic made a red metal, chrome made copper, and the paint whose perceptual fits lost the lobe.
ISSUE_CASES = (("ngan2005/ward", "alum-bronze"), ("ngan2005/ashikhmin-shirley", "nickel"),
               ("ngan2005/ashikhmin-shirley", "red-specular-plastic"), ("ngan2005/ward", "chrome"),
               ("low2012/smooth-e2", "gold-metallic-paint"))


def sample(n: int, seed: int = 0, include=ISSUE_CASES, fits=None) -> list[tuple]:
    """``[(fit, material), ...]``: ``include`` (those loadable), then ``n`` others drawn without
    replacement by ``random.Random(seed)`` from every (fit set, material) pair of the loadable
    fit sets (or of ``fits``), sorted, so that one seed draws the same sample on any machine."""
    import random

    pairs = sorted({(f, m) for _, f, m in jobs(("x",), None, fits)})
    first = [p for p in include if p in pairs]
    rest = [p for p in pairs if p not in first]
    return first + random.Random(int(seed)).sample(rest, min(int(n), len(rest)))


def score_row(row) -> dict:
    """``row`` (a table row with its target's ``params``) with the image scores of its source,
    ``material:NAME@FIT``, beside its target (:func:`_looks_fields`); a row that has them, or
    failed, as it is."""
    if "error" in row or "flip" in row:
        return row
    from .. import catalogue
    from ..mitsuba.looks import compare_looks

    return {**row, **_looks_fields(compare_looks(catalogue.spec(row["material"], row["fit"]), target_of(row)))}


def distribution(rows, label: str = "") -> list[dict]:
    """Per target, over the rows with image scores: how many, FLIP's 10th/50th/90th percentiles and
    largest, the highlight ratio's smallest, 10th/50th/90th percentiles and largest, how many lost
    (below the band) or invented (above) a highlight, and how many of those carry the warning;
    with ``agreement``, the Mitsuba-glTF pairs the same way (FLIP, ratio glTF / Mitsuba)."""
    from ..mitsuba.looks import HIGHLIGHT_BAND

    lo, hi = HIGHLIGHT_BAND
    out = []
    groups = [(to, [r for r in rows if r.get("to") == to and "flip" in r]) for to in TARGETS]
    groups.append(("mitsuba vs gltf", [r["agreement"] for r in rows if "flip" in r.get("agreement", {})]))
    for to, rs in groups:
        if not rs:
            continue
        flip = np.array([r["flip"] for r in rs])
        ratio = np.array([r["highlight_ratio"] for r in rs])
        warned = sum(bool(r.get("looks_warnings")) for r in rs)
        out.append(dict(label=label, to=to, n=len(rs), flip=[float(np.percentile(flip, q)) for q in (10, 50, 90)]
                        + [float(flip.max())], ratio=[float(ratio.min())] + [float(np.percentile(ratio, q))
                                                                             for q in (10, 50, 90)] + [float(ratio.max())],
                        lost=int(np.sum(ratio < lo)), invented=int(np.sum(ratio > hi)), warned=warned))
    return out


def distribution_markdown(dist) -> str:
    """The rows of :func:`distribution` as the table of docs/convert.md (one line per label and target)."""
    lines = ["| code | target | conversions | FLIP p10 / median / p90 / max | highlight ratio min / p10 / median / "
             "p90 / max | lost (< 1/1.5) | invented (> 1.5) | warned |", "|---|---|---|---|---|---|---|---|"]
    for d in dist:
        lines.append(f"| {d['label']} | {d['to']} | {d['n']} | " + " / ".join(f"{x:.3f}" for x in d["flip"]) + " | "
                     + " / ".join(f"{x:.3g}" for x in d["ratio"]) + f" | {d['lost']} | {d['invented']} | "
                     + (f"{d['warned']} |" if d["to"] != "mitsuba vs gltf" else "- |"))
    return "\n".join(lines) + "\n"
