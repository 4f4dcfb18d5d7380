"""Energy compensation (issue 31): pumping-up and Kulla-Conty of GGX ``roughconductor`` and
Cook-Torrance, against the base and the non-reciprocal ``1/E(wi)`` practice."""

from __future__ import annotations

import numpy as np

import plausible

from . import scenes as S
from .core import CURVE_TOL, figure
from .paper_as import _patch_check as patch_check

#: Roughness of the bases (GGX alpha; Beckmann RMS slope m of Cook-Torrance), and in quick mode.
ROUGHNESS, QUICK_ROUGHNESS = (0.3, 0.6, 1.0), (0.6,)
#: Incidences of the albedo curves (degrees).
THETAS = (0, 15, 30, 45, 55, 65, 70, 75, 80, 85, 89)
#: The methods drawn, with their plots' styles; the last has no plugin (a reference).
METHODS = (("base", "-"), ("pumping-up", "--"), ("kulla-conty", "-"), ("incident-albedo", ":"))


def ggx(alpha: float) -> dict:
    return {"type": "roughconductor", "distribution": "ggx", "alpha": float(alpha)}


def cook_torrance(m: float) -> str:
    return f"cook-torrance:m={m!r}:fresnel=none"


def bases(roughness, quick: bool):
    """``(label, kind, base for compensate, {method: plugin dict})`` per base and roughness (GGX
    through the Mitsuba adapter, Cook-Torrance as a registered model; quick mode: Cook-Torrance
    only, whose table takes seconds; the plugin around a Mitsuba BSDF has its own tests)."""
    out = []
    for r in roughness:
        if not quick:
            out.append((f"GGX roughconductor alpha={r:g}", "mitsuba", ggx(r), {
                "base": ggx(r),
                "pumping-up": {"type": "plausible_compensated", "method": "pumping-up", "bsdf": ggx(r)},
                "kulla-conty": {"type": "plausible_compensated", "method": "kulla-conty", "bsdf": ggx(r)}}))
        spec = cook_torrance(r)
        out.append((f"Cook-Torrance m={r:g}", "plausible", spec, {
            "base": {"type": "cook_torrance", "m": float(r), "fresnel": "none"},
            "pumping-up": {"type": "pumped_up", "base": spec},
            "kulla-conty": {"type": "kulla_conty", "base": spec}}))
    return out


def models_of(kind, base):
    """The base and its three compensations as models of the contract."""
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF

    mi = S.mitsuba()
    b = MitsubaBSDF(mi.load_dict(base)) if kind == "mitsuba" else plausible.make(base)
    return {"base": b, **{m: plausible.compensate(b, m) for m, _ in METHODS[1:]}}


@figure("compensation", "Energy compensation of any BSDF: pumping-up and Kulla-Conty",
        "plausible (issue 31); Neumann, Neumann, Szirmay-Kalos 1999, eq. 16, 20; Kulla, Conty 2017 (SIGGRAPH course)",
        "GGX roughconductor (Mitsuba, through the adapter) and Cook-Torrance (Beckmann, V-groove G), Fresnel 1: "
        "albedo against incidence and white-furnace spheres over roughness for the base, pumped up once and "
        "Kulla-Conty's multiple-scattering lobe added; reciprocity measured for each, and for the non-reciprocal "
        "practice of dividing by the albedo at the incidence only (1/E(wi)). Albedo curves to an error bound of 1e-5.",
        renders=True,
        roughness="GGX alpha and Beckmann m 0.3, 0.6, 1.0 (quick mode: Cook-Torrance m = 0.6)")
def compensation(ctx, roughness):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from plausible.mitsuba import register

    mi = S.mitsuba()
    register()
    rough = QUICK_ROUGHNESS if ctx.quick else ROUGHNESS
    cases = bases(rough, ctx.quick)
    ctx.steps(len(cases) * 7)
    res, spp, width = ctx.res(0.3, minimum=24), ctx.spp(), 1.05
    fig, axes = plt.subplots(1, len(cases), figsize=(3.2 * len(cases), 3.2), squeeze=False)
    imgs, labels, rows = [], [], []
    for k, (label, kind, base, plugins) in enumerate(cases):
        models = models_of(kind, base)
        ctx.tick()
        ax = axes[0, k]
        for name, style in METHODS:
            a = np.asarray(plausible.albedo_curve(models[name], thetas_deg=THETAS, tol=CURVE_TOL).value)
            a = a if a.ndim == 1 else a.max(axis=-1)
            ax.plot(THETAS, a, style, label=name)
            ctx.table(f"albedo-{k}-{name}", {"theta_deg": THETAS, "albedo": a}, f"{label}: {name}")
            upto80 = a[np.asarray(THETAS) <= 80]
            if name == "kulla-conty":
                ctx.measure(f"{label}, Kulla-Conty: max |albedo - 1| from 0 to 80 deg", np.max(np.abs(upto80 - 1)),
                            at_most=5e-3)
            else:
                ctx.measure(f"{label}, {name}: max |albedo - 1| from 0 to 80 deg", np.max(np.abs(upto80 - 1)))
            ctx.tick()
        ax.set_title(label, fontsize=8)
        ax.set_xlabel("incidence (deg)")
        ax.set_ylim(0, 1.05)
        for name, _ in METHODS:
            tol = float(getattr(models[name], "precision", 1e-9))   # float32 Mitsuba: 1e-4
            rec = plausible.reciprocity(models[name], n_theta=8, n_phi=16, tol=tol)
            bound = {"at_least": 1e-2} if name == "incident-albedo" else {"at_most": tol}
            ctx.measure(f"{label}, {name}: relative asymmetry", rec.figure, **bound,
                        note="the non-reciprocal practice: expected to fail" if name == "incident-albedo" else "")
            rows.append((label, name, rec.figure))
        for j, name in enumerate(("base", "pumping-up", "kulla-conty")):
            img = S.render(mi, S.furnace(mi, plugins[name], res, spp, width), seed=10 * k + j)
            imgs.append(img)
            c, se, a0 = patch_check(ctx, img, width, models[name], f"{label}, {name}: furnace", res)
            labels.append(f"{label}\n{name}: centre {c:.3f}\u00b1{se:.3f} | albedo {a0:.3f}")
    axes[0, 0].set_ylabel("directional albedo")
    axes[0, 0].legend(fontsize=7)
    fig.tight_layout()
    ctx.plot("albedo", fig, "directional albedo against incidence (azimuth 0), Fresnel 1")
    ctx.image("furnace", S.mosaic(imgs, len(cases), 3),
              caption="white furnace; rows: the bases (GGX, Cook-Torrance per roughness), columns: base, pumped up "
                      "once, Kulla-Conty; background = 1")
    ctx.plot("furnace-labelled", S.grid_figure(imgs, len(cases), 3, labels, title="white furnace"),
             caption="each sphere's centre against plausible.albedo at normal incidence")
    ctx.json("reciprocity", [dict(base=b, method=m, asymmetry=x) for b, m, x in rows],
             "relative asymmetry max |f(a,b) - f(b,a)| / max(f) per base and method")
