"""The demo job (``make demo``) is now the figures report (:mod:`plausible.figures`):
``python -m plausible.demo --out out`` runs ``plausible figures --out out``.

This module keeps the plausibility table of every registered model
(:func:`check_table`), which the report shows as its ``checks`` figure.
"""

from __future__ import annotations

import argparse


def check_table(models, progress=None):
    """:func:`plausible.check` (quick mode) of each model; returns ``(reports, markdown)``.

    ``progress`` is called with no argument after each model.
    """
    from .analysis import check

    reports = []
    for m in models:
        reports.append(check(m, quick=True))
        if progress:
            progress()
    lines = ["| model | parameters | claims plausible | reciprocity | energy (max albedo) | sampling | chi2 (p) |",
             "|---|---|---|---|---|---|---|"]
    for m, r in zip(models, reports):
        claims = m.info.reciprocal and m.info.energy_conserving
        cells = [f"{'PASS' if x.passed else 'FAIL'} {x.figure:.4g}" for x in r.results]
        lines.append(f"| {m.name} | {r.params} | {'yes' if claims else 'no'} | " + " | ".join(cells) + " |")
    return reports, "\n".join(lines) + "\n"


def main(argv=None):
    from .figures import run

    ap = argparse.ArgumentParser(description="The figures report (same as 'plausible figures').")
    ap.add_argument("--out", default="out", help="output directory")
    ap.add_argument("--quick", action="store_true", help="small images and sample counts")
    a = ap.parse_args(argv)
    run(a.out, quick=a.quick)


if __name__ == "__main__":
    main()
