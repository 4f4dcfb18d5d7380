"""The plausibility table: :func:`plausible.check` of every registered model."""

from __future__ import annotations

from plausible import registry
from plausible.progress import start, within

from .core import figure

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
        ctx.measure(f"{m.name} {r.params}: agrees with its claims", bool(r.as_claimed(m.info)), True,
                    note=rows)


#: Configurations of the ``mitsuba-builtins`` figure in quick (CI) mode.
QUICK_BUILTINS = ("diffuse", "plastic")


@figure("mitsuba-builtins", "Mitsuba 3's own reflection BSDFs: reciprocity, energy, sampling, chi-square",
        "plausible (issue 15); Mitsuba 3 plugins", "plausible.check on Mitsuba 3's built-in reflection BSDFs through "
        "the Mitsuba adapter (float32, llvm_ad_rgb): which are plausible, which lose energy and how much, which are "
        "not reciprocal, whether a sampler disagrees with its pdf. One number per configuration (the albedo at 60 "
        "degrees) is cross-checked against a Monte-Carlo furnace render in Mitsuba itself. The full table: "
        "docs/mitsuba-builtins.md.", renders=True,
        variants="one of each: diffuse, roughconductor GGX a=0.1, roughplastic, plastic, principled, pplastic, "
                 "blendbsdf (quick mode: " + ", ".join(QUICK_BUILTINS) + "); every configuration (Beckmann/GGX, "
                 "alpha 0.01-1, iso/aniso, sample_visible on/off, ...) in docs/mitsuba-builtins.md")
def mitsuba_builtins(ctx, variants):
    from plausible.analysis.adapters import tolerances
    from plausible.analysis.mitsuba_bsdf import FLOAT32_PRECISION

    from .mitsuba_builtins import CONFIGS, QUICK_CONFIGS, builtin_markdown, builtin_table, plot_albedo, plot_reciprocity

    # the report shows one configuration of each plugin (the full 39-row table takes about 20 minutes:
    # docs/mitsuba-builtins.md, `make mitsuba-builtins`); quick (CI) mode two of them
    configs = [c for c in CONFIGS if c[0] in QUICK_BUILTINS] if ctx.quick else QUICK_CONFIGS
    ctx.steps(len(configs))
    rows = builtin_table(configs, quick=True, spp=ctx.spp(2), progress=lambda total, label="": ctx.tick)
    (ctx.out / "mitsuba-builtins.md").write_text(builtin_markdown(rows))
    ctx.file("mitsuba-builtins.md", "the table (as docs/mitsuba-builtins.md)")
    tol = tolerances(type("Float32", (), dict(precision=FLOAT32_PRECISION))())["reciprocity"]
    ctx.plot("reciprocity", plot_reciprocity(rows, tol), "max relative asymmetry |f(a,b) - f(b,a)| per BSDF")
    ctx.plot("albedo", plot_albedo(rows), "directional albedo against incidence (azimuth 0)")
    ctx.json("rows", [dict(label=r.label, bsdf=r.bsdf, report=r.report) for r in rows], "every report")
    for r in rows:
        ctx.measure(f"{r.label}: albedo at 60 deg, furnace render vs quadrature", r.furnace_60, r.quadrature_60,
                    4 * r.furnace_se + 1e-4, note=f"plausible: {'yes' if r.plausible else 'no'}; "
                                                  + "; ".join(r.notes))
