"""Plots of a fit: target and fit in the plane of incidence, and their albedo curves."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from ..analysis import albedo_curve, direction
from ..text import jsonable, write_atomic
from ..plotting import _figure, _legend_below, _wrap, default_thetas, plot_albedo_curves, save_figure

PLANE_THETAS_DEG = (0.0, 30.0, 60.0, 75.0)


def _mean(v):
    v = np.asarray(v)
    return v.mean(axis=-1) if v.ndim > 1 else v


def plot_plane(result, path, thetas_deg=PLANE_THETAS_DEG, n: int = 361):
    """``f cos(theta_o)`` of target (solid) and fit (dashed) in the plane of
    incidence, against the signed outgoing angle (negative: the side of the
    light), one colour per incidence angle, log scale; channel means.  A table
    target is drawn as its samples lying in the plane of incidence."""
    fig, ax = _figure((len(thetas_deg) * 2 + 1) // 2 + 1)
    to = np.radians(np.linspace(-89.5, 89.5, n))
    wo = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], -1)
    tgt = result.target
    top = 0.0
    for k, t in enumerate(thetas_deg):
        col = f"C{k}"
        wi = direction(math.radians(t), math.pi)        # light on the -x side
        fc = _mean(result.model.eval(wi, wo)) * wo[:, 2]
        top = max(top, float(np.max(fc)))
        if tgt.model is not None:
            gt = _mean(tgt.model.eval(wi, wo)) * wo[:, 2]
            top = max(top, float(np.max(gt)))
            ax.plot(np.degrees(to), gt, color=col, label=f"target, {t:g} deg")
        ax.plot(np.degrees(to), fc, color=col, ls="--", label=f"fit, {t:g} deg")
    if tgt.model is None:                               # samples in the plane of incidence
        nrm = np.cross(tgt.wi, tgt.wo)
        inplane = np.abs(nrm[:, 0]) < 1e-9
        th = np.degrees(np.arctan2(tgt.wo[:, 0], tgt.wo[:, 2]))
        sign = np.where(tgt.wi[:, 0] > 0, -1.0, 1.0)
        ax.scatter((sign * th)[inplane], _mean(tgt.fcos)[inplane], s=6, color="k", label="target samples")
        top = max(top, float(np.max(_mean(tgt.fcos))))
    ax.set_yscale("log")
    if top > 0:      # four decades below the peak: the fit's floor eps is 1e-3 of the peak
        ax.set_ylim(1e-4 * top, 2 * top)
    ax.set_xlabel("outgoing angle in the plane of incidence (degrees)")
    ax.set_ylabel("f cos(theta_o)")
    ax.set_title(_wrap(f"{result.model.name} fitted ({result.metric}) to {tgt.label}", 90), fontsize=8)
    ax.grid(alpha=0.3)
    _legend_below(fig, ax, fontsize=7, ncol=2)
    return save_figure(fig, path)


def write_plots(result, out_dir, points: int = 24, progress=None) -> list:
    """Write ``plane.png`` (:func:`plot_plane`), ``albedo.png`` (target and fit
    albedo curves, accurate integrator) and ``fit.json`` (parameters and errors)
    into ``out_dir``; returns the paths.  ``progress``: a :mod:`plausible.progress`
    factory (one count per albedo curve)."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    paths = [plot_plane(result, out / "plane.png")]
    th = default_thetas(points)
    curves = []
    if result.target.model is not None:
        curves.append((f"target {result.target.label}", th, albedo_curve(result.target.model, th,
                                                                          progress=progress)))
    curves.append((f"fit {result.model!r}", th, albedo_curve(result.model, th, progress=progress)))
    paths.append(Path(plot_albedo_curves(curves, out / "albedo.png", title="Directional albedo: target and fit")))
    # non-finite numbers as strings ("nan"): bare NaN is not JSON
    write_atomic(out / "fit.json", json.dumps(jsonable(result.to_dict()), indent=1, allow_nan=False))
    paths.append(out / "fit.json")
    return paths
