"""The Modified Phong notes' reference scene: a Cornell box with a Modified Phong sphere."""

from __future__ import annotations

import numpy as np

import math

from .core import figure
from . import scenes as S

#: The notes' table of ``evaluate`` tests ("No lets think about other test cases"):
#: ``wi = wo = (0, 0, 1)``, ``n = 10``; (ks, kd, f_r, the notes' f_r as printed, comment).
NOTES_TABLE = ((0.5, 0.5, 7 / (2 * math.pi), "7/(2 pi)", ""),
               (0.0, 0.0, 0.0, "0", "No reflection"),
               (0.0, 1.0, 1 / math.pi, "1/pi", "Only diffuse"),
               (1.0, 0.0, 6 / math.pi, "6/pi", "Only specular"))


def notes_table(ctx):
    """The notes' table with plausible's ``modified-phong`` (float64) and the same model
    as the ``phong`` Mitsuba plugin (plausible's ``modified-phong`` registered under
    Mitsuba 0.5's name, float32) beside each row: checks against the notes' numbers to
    1e-12 and to the notes' own ``abs_error = 0.001``.  The plugin is not an independent
    implementation: tests/figures/test_paper_checks.py compares it with a Mitsuba
    0.5-style Modified Phong written there from the notes, at random directions."""
    import plausible
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    z = np.array([0.0, 0.0, 1.0])
    rows = ["| wi | wo | ks | kd | n | f_r (notes) | plausible | plausible as Mitsuba `phong` (float32) | comment |",
            "|---|---|---|---|---|---|---|---|---|"]
    for ks, kd, want, text, comment in NOTES_TABLE:
        got = float(np.mean(plausible.make("modified-phong", ks=ks, kd=kd, n=10.0).eval(z, z)))
        mi_bsdf = MitsubaBSDF(load_bsdf_dict({"type": "phong", "exponent": 10.0, "diffuse_reflectance": kd,
                                              "specular_reflectance": ks}))
        got_mi = float(np.mean(mi_bsdf.eval(z, z)))
        ctx.measure(f"notes' table, ks = {ks:g}, kd = {kd:g}: plausible f_r(n, n) vs {text}", got, want, 1e-12,
                    note=comment)
        ctx.measure(f"notes' table, ks = {ks:g}, kd = {kd:g}: the same model as the Mitsuba plugin 'phong' "
                    f"(float32) f_r(n, n) vs {text}", got_mi, want, 0.001,
                    note="the notes' abs_error = 0.001; plausible's modified-phong under Mitsuba 0.5's name, not an "
                         "independent implementation")
        rows.append(f"| (0,0,1) | (0,0,1) | {ks:g} | {kd:g} | 10 | {text} = {want:.6g} | {got:.6g} | "
                    f"{got_mi:.6g} | {comment} |")
    (ctx.out / "notes-table.md").write_text("\n".join(rows) + "\n")
    ctx.file("notes-table.md", "the notes' test table with the measured values beside")


def notes_reciprocity(model, pairs: int = 4096, seed: int = 0, abs_error: float = 0.001) -> tuple:
    """The notes' ``checkReciprocity`` and the plain test of reciprocity on ``model``:
    ``pairs`` pairs of directions drawn uniformly on the sphere (the notes'
    ``UniformSampleSphere``); the notes compare ``F(wo, wi) |cos wo|`` with ``F(wi, wo)
    |cos wi|`` to ``abs_error``, which is not Helmholtz reciprocity: a reciprocal BRDF
    fails it wherever ``f`` is large and the two cosines differ.  Returns the fractions
    of pairs that fail the notes' test and the plain ``|f(wi, wo) - f(wo, wi)| <=
    abs_error``."""
    rng = np.random.default_rng(seed)
    z = rng.uniform(-1.0, 1.0, (2, pairs))
    phi = rng.uniform(0.0, 2.0 * math.pi, (2, pairs))
    r = np.sqrt(1.0 - z * z)
    wi, wo = (np.stack([r[k] * np.cos(phi[k]), r[k] * np.sin(phi[k]), z[k]], axis=-1) for k in (0, 1))
    f_io, f_oi = (np.asarray(model.eval(a, b), dtype=np.float64) for a, b in ((wi, wo), (wo, wi)))
    f_io, f_oi = (f.reshape(pairs, -1) for f in (f_io, f_oi))
    notes = np.abs(f_oi * np.abs(wo[:, 2:]) - f_io * np.abs(wi[:, 2:])) > abs_error
    plain = np.abs(f_oi - f_io) > abs_error
    return float(notes.any(axis=-1).mean()), float(plain.any(axis=-1).mean())


def cornell_scene(mi, exponent, diffuse_reflectance, specular_reflectance, res, spp, integrator):
    """Mitsuba 3's ``cornell_box()`` with the boxes replaced by a ``phong`` sphere (box
    pixel filter, so a pixel is the mean radiance over its footprint and the image
    mean is the film's mean radiance at any resolution)."""
    d = mi.cornell_box()
    for k in [k for k in d if k.startswith(("small-box", "large-box"))]:
        del d[k]
    d["sphere"] = {"type": "sphere", "center": [0.0, -0.5, 0.0], "radius": 0.5,
                   "bsdf": {"type": "phong", "exponent": exponent, "diffuse_reflectance": diffuse_reflectance,
                            "specular_reflectance": specular_reflectance}}
    d["sensor"]["film"].update(width=res, height=res, rfilter={"type": "box"})
    d["sensor"]["sampler"]["sample_count"] = spp
    d["integrator"] = integrator
    return mi.load_dict(d)


#: The two estimators of the Cornell box check (the same path length, 8).
PATH, PTRACER = {"type": "path", "max_depth": 8}, {"type": "ptracer", "max_depth": 8}


def mean_and_se(mi, scene_of, seeds) -> tuple:
    """Mean image luminance over independent renders (one per seed) and its standard error."""
    vals = [float(np.mean(S.luminance(S.render(mi, scene_of(), seed=s)))) for s in seeds]
    return float(np.mean(vals)), float(np.std(vals, ddof=1) / np.sqrt(len(vals))), vals


@figure("notes-cornell", "Cornell box with a Modified Phong sphere", "Modified Phong BRDF notes (Mitsuba 0.5 reference)",
        "A reference image: Modified Phong BSDF in Mitsuba 0.5.0 ... When this material is applied to a sphere "
        "within a Cornell Box the output can look like this.", renders=True,
        exponent=30.0, diffuse_reflectance=0.5, specular_reflectance=0.2)
def cornell(ctx, exponent, diffuse_reflectance, specular_reflectance):
    import plausible

    mi = S.mitsuba()
    notes_table(ctx)
    notes_fail, plain_fail = notes_reciprocity(plausible.make("modified-phong", ks=0.5, kd=0.5, n=10.0))
    ctx.measure("Helmholtz reciprocity of modified-phong (ks = kd = 0.5, n = 10): fraction of 4096 pairs on the "
                "sphere with |f(wi, wo) - f(wo, wi)| > 0.001", plain_fail, at_most=0.0)
    ctx.measure("the notes' checkReciprocity on the same pairs: fraction it rejects (it compares F(wo, wi) |cos wo| "
                "with F(wi, wo) |cos wi|)", notes_fail,
                note="the notes' test multiplies each side by a different |cos|, so it tests the symmetry of f cos, "
                     "not of f: it rejects this reciprocal BRDF wherever f is large and the cosines differ (the "
                     "pairs below the horizon, where f = 0, pass it)")
    params = (exponent, diffuse_reflectance, specular_reflectance)
    res, spp = ctx.res(1.0), ctx.spp(2)
    small, small_spp, seeds = ctx.res(0.15, minimum=24), max(8, ctx.spp(0.25)), range(4)
    ctx.steps(1 + 2 * len(seeds))
    img = S.render(mi, cornell_scene(mi, *params, res, spp, PATH), seed=0)
    ctx.tick()
    ctx.image("cornell", img, caption="Mitsuba 3 cornell_box() with the boxes replaced by a 'phong' sphere "
                                      "(Mitsuba 0.5 parameter names), path tracer")
    # the expected number: the same scene by light tracing (ptracer: paths from the light, connected to the
    # camera), a second estimator of the same image, four seeds; the path tracer's own four at the same budget
    pt, pt_se, _ = mean_and_se(mi, lambda: cornell_scene(mi, *params, small, small_spp, PTRACER), seeds)
    ctx.tick(len(seeds))
    pa, pa_se, _ = mean_and_se(mi, lambda: cornell_scene(mi, *params, small, small_spp, PATH), seeds)
    ctx.tick(len(seeds))
    ctx.measure("mean image luminance, path tracer (4 renders) vs light tracer (4 renders), "
                f"{small} px, {small_spp} spp", pa, pt, 4 * float(np.hypot(pa_se, pt_se)),
                note=f"ptracer {pt:.5f} +- {pt_se:.5f}, path {pa:.5f} +- {pa_se:.5f}; tolerance 4 s.e.")
    # the main render's standard error, scaled from the small ones by the number of samples
    main_se = pa_se * 2.0 * float(np.sqrt(small * small * small_spp / (res * res * spp)))
    ctx.measure("mean image luminance of the render above vs the light tracer's", float(np.mean(S.luminance(img))),
                pt, 4 * float(np.hypot(main_se, pt_se)),
                note=f"tolerance 4 s.e. (the render's {main_se:.2g}, scaled from the small renders by sample count)")
