"""The image scores of docs/convert.md ("The look of a conversion", issue 40): a fixed random sample of
the published fits (plus the cases the issue names) converted to Mitsuba and to glTF, each scored by
``plausible.compare_looks`` against its source, and the two targets of a material against each other.

    # today's conversions: score the rows already in the table (renders only, about a second a row)
    PYTHONPATH=src nice -n 19 python scripts/looks_table.py --rows docs/convert-table.jsonl --label 6bc24da \\
        --out docs/looks-sample.jsonl
    # another code (e.g. after the fitter lands): convert the same sample afresh, then score
    PYTHONPATH=src nice -n 19 python scripts/looks_table.py --label after --out docs/looks-sample-after.jsonl

Rows are appended to ``--out`` as they finish (plausible.conversion.table.run_table): an interrupted run
resumes.  The sample is ``plausible.conversion.table.sample(N, SEED)``: the issue's five cases, then N pairs
(fit set, material) drawn by ``random.Random(SEED)`` from the sorted list of every pair.  Prints the
distribution (one markdown line per target and one for the Mitsuba-glTF pairs) to paste into docs/convert.md.
"""

from __future__ import annotations

import argparse

from plausible.conversion import table


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--rows", help="a convert-table JSONL whose targets to score (default: convert afresh)")
    ap.add_argument("--out", required=True, help="the scores, JSON Lines (resumes)")
    ap.add_argument("--sample", type=int, default=80, help="random pairs besides the issue's cases (default 80)")
    ap.add_argument("--seed", type=int, default=40, help="the sample's seed (default 40, the issue's number)")
    ap.add_argument("--label", default="", help="the code's name in the distribution's first column")
    a = ap.parse_args(argv)
    if a.sample < 0:
        ap.error(f"--sample: a count >= 0, got {a.sample}")
    todo = [(to, fit, name) for fit, name in table.sample(a.sample, a.seed) for to in table.TARGETS]
    make = None
    if a.rows:
        source = table.read_rows(a.rows)
        missing = [table.key(j) for j in todo if table.key(j) not in source]
        if missing:
            ap.error(f"--rows: {len(missing)} rows of the sample are not in {a.rows} (e.g. {missing[0]})")
        make = lambda job: table.score_row(source[table.key(job)])  # noqa: E731
    rows = table.run_table(a.out, todo_jobs=todo, make_row=make,
                           on_row=lambda r: print(table.key(r), r.get("flip"), r.get("highlight_ratio"), flush=True))
    print(table.distribution_markdown(table.distribution([rows[table.key(j)] for j in todo if table.key(j) in rows],
                                                         a.label)))


if __name__ == "__main__":
    main()
