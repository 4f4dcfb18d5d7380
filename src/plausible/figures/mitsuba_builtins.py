"""Mitsuba 3's own reflection BSDFs under :func:`plausible.check`: the measured table.

:func:`builtin_table` checks each configuration of :data:`CONFIGS` through the
Mitsuba adapter (:mod:`plausible.analysis.mitsuba_bsdf`) and cross-checks one
number per configuration against an independent computation: the directional
albedo at 60 degrees as a Monte-Carlo furnace render in Mitsuba itself
(:func:`furnace_albedo`: a flat patch under a unit constant environment, one
bounce, Mitsuba's path integrator with its own emitter and BSDF sampling and
MIS), against the adapter's quadrature (smooth albedo plus delta reflectance).
:func:`builtin_markdown` writes the table of ``docs/mitsuba-builtins.md``
(``scripts/mitsuba_builtins.py``); the ``mitsuba-builtins`` figure of the
report (:mod:`plausible.figures.checks`) plots it.

Conductors are white (``material = "none"``: Fresnel 1) and diffuse bases white,
so ``1 - albedo`` is the energy a single-scattering model loses (no multiple
scattering between microfacets).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["CONFIGS", "QUICK_CONFIGS", "BuiltinRow", "builtin_table", "builtin_markdown", "furnace_albedo",
           "plot_reciprocity", "plot_albedo"]

WHITE = {"type": "rgb", "value": 1.0}


def _configs():
    out = [("diffuse", {"type": "diffuse", "reflectance": WHITE})]
    for dist in ("beckmann", "ggx"):
        for alpha in (0.01, 0.1, 0.3, 0.6, 1.0):
            for sv in (True, False):
                out.append((f"roughconductor {dist} a={alpha:g}{'' if sv else ' sv=off'}",
                            {"type": "roughconductor", "distribution": dist, "alpha": alpha, "sample_visible": sv}))
        for sv in (True, False):
            out.append((f"roughconductor {dist} au=0.05 av=0.3{'' if sv else ' sv=off'}",
                        {"type": "roughconductor", "distribution": dist, "alpha_u": 0.05, "alpha_v": 0.3,
                         "sample_visible": sv}))
    for nl in (False, True):
        out.append((f"roughplastic a=0.1{' nonlinear' if nl else ''}",
                    {"type": "roughplastic", "alpha": 0.1, "nonlinear": nl, "diffuse_reflectance": WHITE}))
    out.append(("roughplastic ggx a=0.4", {"type": "roughplastic", "distribution": "ggx", "alpha": 0.4,
                                            "diffuse_reflectance": WHITE}))
    out.append(("plastic", {"type": "plastic", "diffuse_reflectance": WHITE}))
    for metallic in (0.0, 1.0):
        for rough in (0.1, 0.5, 1.0):
            out.append((f"principled metallic={metallic:g} r={rough:g}",
                        {"type": "principled", "base_color": WHITE, "metallic": metallic, "roughness": rough}))
    out.append(("principled spec_tint=1 (base 0.8,0.3,0.2)",
                {"type": "principled", "base_color": {"type": "rgb", "value": [0.8, 0.3, 0.2]}, "spec_tint": 1.0}))
    out.append(("principled sheen=1", {"type": "principled", "base_color": WHITE, "sheen": 1.0}))
    out.append(("pplastic a=0.1", {"type": "pplastic", "alpha": 0.1, "diffuse_reflectance": WHITE}))
    out.append(("blendbsdf 0.5 diffuse + roughconductor a=0.2",
                {"type": "blendbsdf", "weight": 0.5, "bsdf_0": {"type": "diffuse", "reflectance": WHITE},
                 "bsdf_1": {"type": "roughconductor", "alpha": 0.2}}))
    return out


#: ``(label, mi.load_dict description)`` of every configuration of the table.
CONFIGS = _configs()
#: The subset of the quick (CI) run: one of each plugin.
QUICK_CONFIGS = [c for c in CONFIGS if c[0] in (
    "diffuse", "roughconductor ggx a=0.1", "roughplastic a=0.1", "plastic", "principled metallic=0 r=0.5",
    "pplastic a=0.1", "blendbsdf 0.5 diffuse + roughconductor a=0.2")]

#: Incidence (degrees) of the furnace cross-check.
FURNACE_THETA = 60.0


def furnace_albedo(bsdf: dict, theta_deg: float = FURNACE_THETA, res: int = 16, spp: int = 256,
                   seed: int = 0) -> tuple:
    """Directional albedo seen from ``theta_deg`` (azimuth 0, along the tangent ``+x``),
    rendered by Mitsuba: a 20 x 20 rectangle (normal ``+z``, tangent ``+x``) under a
    constant unit environment, an orthographic camera of width 0.2 looking at its
    centre, ``path`` with ``max_depth = 2`` (one bounce).  Every pixel estimates
    ``int f(l, v) cos(theta_l) dl`` (plus delta lobes) with ``v`` the camera direction,
    i.e. the albedo of the adapter's radiance-mode contract at ``wi = v``.
    Returns ``(channel mean, its standard error from the pixels' spread)``.
    """
    from .scenes import mitsuba, orthographic, render

    mi = mitsuba()
    t = math.radians(theta_deg)
    origin = (5 * math.sin(t), 0.0, 5 * math.cos(t))
    scene = mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": orthographic(mi, 0.1, res, spp, origin=origin, target=(0, 0, 0), up=(0, 1, 0)),
        "plane": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([10.0, 10.0, 1.0]), "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })
    px = render(mi, scene, seed=seed).reshape(-1, 3).mean(axis=1)
    return float(px.mean()), float(px.std(ddof=1) / math.sqrt(len(px)))


@dataclass
class BuiltinRow:
    """One configuration: its report (``to_dict``) and the numbers of the table."""

    label: str
    bsdf: dict
    report: dict
    plausible: bool
    reciprocity: float
    max_albedo: float
    max_at: tuple
    min_albedo: float
    min_at: tuple
    sampling_ok: bool
    sampling_figure: float
    chi2_p: float
    delta_max: float | None
    delta_at: tuple | None
    quadrature_60: float
    furnace_60: float
    furnace_se: float
    notes: list = field(default_factory=list)

    @property
    def furnace_sigma(self) -> float:
        return abs(self.furnace_60 - self.quadrature_60) / (self.furnace_se + 1e-4)

    @property
    def energy_lost(self) -> float:
        return max(0.0, 1.0 - self.min_albedo)


def _row(label, d, spp, quick):
    from plausible.analysis import albedo, check, direction
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    b = MitsubaBSDF(load_bsdf_dict(d), params={k: v for k, v in d.items() if k != "type"}, name=d["type"])
    rep = check(b, quick=quick)
    names = [r.name for r in rep.results]
    grid = rep["energy"].details.get("grid", [])
    mx = max(grid, key=lambda g: g["albedo"])
    # what is lost: of the whole reflectance (smooth albedo + delta lobes, where there are any)
    total = [dict(g, albedo=g["total"]) for g in rep["energy+delta"].details["grid"]] if "energy+delta" in names \
        else grid
    mn = min(total, key=lambda g: g["albedo"])
    wi = direction(math.radians(FURNACE_THETA))
    quad = float(np.mean(albedo(b, wi).value)) + float(np.mean(b.delta_reflectance(wi)))
    fur, se = furnace_albedo(d, spp=spp)
    return BuiltinRow(
        label, d, rep.to_dict(), rep.passed, rep["reciprocity"].figure, mx["albedo"], (mx["theta_deg"], mx["phi_deg"]),
        mn["albedo"], (mn["theta_deg"], mn["phi_deg"]), rep["sampling"].passed, rep["sampling"].figure,
        rep["chi2"].figure, rep["energy+delta"].figure if "energy+delta" in names else None,
        (rep["energy+delta"].worst["theta_i_deg"], rep["energy+delta"].worst["phi_i_deg"]) if "energy+delta" in names
        else None, quad, fur, se, [_failure(r) for r in rep.results if not r.passed])


def _failure(r) -> str:
    """One line saying how a check failed: its figure, bound and where."""
    where = ", ".join(f"{k}={v:g}" for k, v in r.worst.items() if k in ("theta_i_deg", "phi_i_deg")
                      and isinstance(v, (int, float)))
    text = f"{r.name} {r.figure:.4g} (bound {r.bound}{'; at ' + where if where else ''})"
    if r.worst.get("problems"):
        text += ": " + r.worst["problems"][0]
    return text


def builtin_table(configs=None, *, quick: bool = False, spp: int = 256, progress=None) -> list:
    """:class:`BuiltinRow` for each ``(label, dict)`` of ``configs`` (default
    :data:`CONFIGS`): :func:`plausible.check` through the Mitsuba adapter, and the
    furnace cross-check.  ``progress(total)`` returns a function called after each row."""
    configs = CONFIGS if configs is None else configs
    tick = progress(len(configs)) if progress else None
    rows = []
    for label, d in configs:
        rows.append(_row(label, d, spp, quick))
        if tick:
            tick()
    return rows


def builtin_markdown(rows) -> str:
    """The table of ``docs/mitsuba-builtins.md``."""
    head = ("| BSDF | plausible | reciprocity (max rel. asymmetry) | max albedo (at theta, phi) | "
            "energy lost (1 - min albedo incl. delta, at theta) | sampling (max rel. err) | chi2 min p | "
            "albedo 60 deg: quadrature / furnace render (sigma) |\n|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        alb = f"{r.max_albedo:.4f} ({r.max_at[0]:g}, {r.max_at[1]:g})"
        if r.delta_max is not None:
            alb += f"; +delta {r.delta_max:.4f}"
        lines.append(
            f"| {r.label} | {'yes' if r.plausible else '**no**'} | {r.reciprocity:.2g} | {alb} | "
            f"{r.energy_lost:.4f} ({r.min_at[0]:g}) | {'ok' if r.sampling_ok else '**FAIL**'} "
            f"{r.sampling_figure:.2g} | {r.chi2_p:.3g} | {r.quadrature_60:.4f} / {r.furnace_60:.4f} "
            f"({r.furnace_sigma:.1f}) |")
    return "\n".join(lines) + "\n"


def plot_reciprocity(rows, tol: float):
    """Bar chart of each configuration's reciprocity figure (log scale) with the tolerance."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(8, 0.22 * len(rows) + 1.2))
    y = np.arange(len(rows))
    v = np.array([max(r.reciprocity, 1e-10) for r in rows])
    ax.barh(y, v, color=["tab:green" if x <= tol else "tab:red" for x in v])
    ax.axvline(tol, color="k", ls="--", lw=1, label=f"tolerance {tol:g} (float32)")
    ax.axvline(2.0 ** -24, color="gray", ls=":", lw=1, label="float32 rounding 2^-24")
    ax.set_xscale("log")
    ax.set_yticks(y, [r.label for r in rows], fontsize=7)
    ax.invert_yaxis()
    ax.set_xlabel("max |f(a,b) - f(b,a)| / max(f)")
    ax.legend(fontsize=7)
    fig.tight_layout()
    return fig


def plot_albedo(rows):
    """Directional albedo against incidence (the energy grid at azimuth 0) of each configuration;
    with delta lobes, the smooth albedo plus their reflectance (dashed)."""
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(9, 6))
    for r in rows:
        res = {x["name"]: x for x in r.report["results"]}
        if "energy+delta" in res:   # the whole reflectance: smooth albedo + delta lobes
            g = [dict(x, albedo=x["total"]) for x in res["energy+delta"]["details"]["grid"]]
        else:
            g = res["energy"]["details"].get("grid", [])
        g = [x for x in g if x["phi_deg"] == 0]
        ax.plot([x["theta_deg"] for x in g], [x["albedo"] for x in g], lw=1,
                ls="--" if "energy+delta" in res else "-",
                label=r.label + (" (smooth + delta)" if "energy+delta" in res else ""))
    ax.axhline(1.0, color="k", lw=0.8)
    ax.set_xlabel("incidence theta (deg)")
    ax.set_ylabel("directional albedo (max channel)")
    ax.legend(fontsize=5, ncol=2)
    fig.tight_layout()
    return fig
