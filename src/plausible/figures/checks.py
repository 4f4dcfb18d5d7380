"""The plausibility table: :func:`plausible.check` of every registered model."""

from __future__ import annotations

from plausible import registry
from plausible.progress import start, within

from . import figure

QUICK_MODELS = ("lambertian", "modified-phong", "ashikhmin-shirley")


def check_table(models, progress=None):
    """:func:`plausible.check` (quick mode) of each model; returns ``(reports, markdown)``.

    ``progress``: a :mod:`plausible.progress` factory, ticked after each model.
    """
    from plausible.analysis import check

    tick = start(progress, len(models), "checks")
    reports = []
    for m in models:
        reports.append(check(m, quick=True))
        tick()
    lines = ["| model | parameters | claims plausible | reciprocity | energy (max albedo) | sampling | chi2 (p) |",
             "|---|---|---|---|---|---|---|"]
    for m, r in zip(models, reports):
        claims = m.info.reciprocal and m.info.energy_conserving
        cells = [f"{'PASS' if x.passed else 'FAIL'} {x.figure:.4g}" for x in r.results]
        lines.append(f"| {m.name} | {r.params} | {'yes' if claims else 'no'} | " + " | ".join(cells) + " |")
    return reports, "\n".join(lines) + "\n"


@figure("checks", "Plausibility of every model: reciprocity, energy, sampling, chi-square",
        "plausible (all papers)", "Every registered model on its defaults and its declared extreme parameters: "
        "does plausible.check agree with what the model claims (reciprocal, energy conserving)? The "
        "non-reciprocal Phong and Blinn originals are expected to fail what they do not claim.",
        variants="defaults and extremes of every registered model (quick mode: defaults of "
                 + ", ".join(QUICK_MODELS) + ")")
def checks(ctx, variants):
    from plausible.analysis.suite import model_variants

    if ctx.quick:
        models = [registry.make(n) for n in QUICK_MODELS]
    else:
        models = [m for name in registry.names() for m in model_variants(name)]
    ctx.steps(len(models))
    reports, md = check_table(models, progress=within(ctx.tick))
    (ctx.out / "check.md").write_text(md)
    ctx.file("check.md", "the table")
    ctx.json("check", [r.to_dict() for r in reports], "every report")
    for m, r in zip(models, reports):
        rows = "; ".join(f"{x[0]} {x[3]} {x[1]}" for x in r.rows())
        ctx.measure(f"{m.name} {r.params}: agrees with its claims", float(r.as_claimed(m.info)), 1.0, 0.0,
                    note=rows)
