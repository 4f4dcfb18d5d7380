"""Write the error table of docs/convert.md: published fits converted to Mitsuba.

    PYTHONPATH=src python scripts/convert_table.py --per-set 5       # the first 5 materials of each fit set
    PYTHONPATH=src python scripts/convert_table.py --from-json        # rewrite the markdown only

Each row is :func:`plausible.convert` of ``material:NAME@FIT`` to ``mitsuba`` (the
family chosen per material), with the albedo of the result by Mitsuba's own
sampler against the source's at 0, 45 and 75 degrees.  Rows go to
``docs/convert-table.json`` as they finish (a run resumes where it stopped).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np

from plausible import catalogue as library
from plausible.conversion import TOLERANCE, convert

JSON = Path("docs/convert-table.json")
MD = Path("docs/convert-table.md")


def rows(per_set, jobs_done, targets):
    sets = [fs for fs in library.fits() if fs.built]
    for fs, name, to in ((fs, n, t) for fs in sets for n in sorted(library.materials(fs.key))[:per_set]
                         for t in targets):
        spec = f"material:{name}@{fs.key}"
        key = f"{to} {spec}"
        if key in jobs_done:
            continue
        t0 = time.monotonic()
        c = convert(spec, to=to).items[0]
        diffs = [c.albedo[k]["max_abs_difference"] for k in ("0", "45", "75")]
        source_max = max(max(v["source"]) for v in c.albedo.values())
        yield key, dict(to=to, fit=fs.key, material=name, target=c.target, perceptual=c.errors["perceptual"],
                        l2=c.errors["l2-cos"], log=c.errors["log"], albedo_diff=diffs, source_albedo_max=source_max,
                        conserving=not any("not energy conserving" in w for w in c.warnings),
                        seconds=time.monotonic() - t0)


def markdown(data) -> str:
    return "\n".join(_markdown({k: r for k, r in data.items() if r["to"] == to}, to)
                     for to in dict.fromkeys(r["to"] for r in data.values()))


def _markdown(data, to) -> str:
    out = [f"#### every conversion to {to}", "","| fit set | material | target | perceptual | l2-cos | log | albedo diff. 0 / 45 / 75 deg | within 0.05 |",
           "|---|---|---|---|---|---|---|---|"]
    for r in data.values():
        ok = max(r["albedo_diff"]) <= TOLERANCE
        out.append(f"| {r['fit']} | {r['material']} | {r['target'].split(':', 1)[-1]} | {r['perceptual']:.3g} | "
                   f"{r['l2']:.3g} | {r['log']:.3g} | " + " / ".join(f"{d:.3f}" for d in r["albedo_diff"])
                   + f" | {'yes' if ok else ('no' if r['conserving'] else 'no (source not conserving)')} |")
    summary = ["", f"#### to {to}: summary", "", "| fit set | conversions | within 0.05 (conserving sources) | median perceptual | "
               "largest albedo diff. | median seconds |", "|---|---|---|---|---|---|"]
    for fit in dict.fromkeys(r["fit"] for r in data.values()):
        rs = [r for r in data.values() if r["fit"] == fit]
        cons = [r for r in rs if r["conserving"]]
        ok = sum(max(r["albedo_diff"]) <= TOLERANCE for r in cons)
        summary.append(f"| {fit} | {len(rs)} | {ok} / {len(cons)} | {np.median([r['perceptual'] for r in rs]):.3g} | "
                       f"{max(max(r['albedo_diff']) for r in rs):.3f} | {np.median([r['seconds'] for r in rs]):.1f} |")
    return "\n".join(summary[1:] + ["", *out]) + "\n"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--per-set", type=int, default=8, help="materials per fit set (alphabetical)")
    ap.add_argument("--to", default="mitsuba,gltf", help="targets (comma-separated)")
    ap.add_argument("--from-json", action="store_true", help="only rewrite the markdown from the JSON")
    a = ap.parse_args(argv)
    data = json.loads(JSON.read_text()) if JSON.exists() else {}
    if not a.from_json:
        for key, row in rows(a.per_set, data, a.to.split(",")):
            data[key] = row
            JSON.write_text(json.dumps(data, indent=1) + "\n")
            print(key, row["target"], [round(d, 3) for d in row["albedo_diff"]], f"{row['seconds']:.1f} s", flush=True)
    MD.write_text(markdown(data))
    print(f"wrote {MD} ({len(data)} rows)")


if __name__ == "__main__":
    main()
