"""One figure per registered model: its lobe (``f cos theta_o`` in the plane of
incidence) for a few incidence angles, and its directional albedo curve."""

from __future__ import annotations

import math
import textwrap

import numpy as np

from plausible import registry
from plausible.analysis import albedo_curve
from plausible.plotting import default_thetas
from plausible.progress import within

from .core import CURVE_TOL, figure

INCIDENCE = (0.0, 30.0, 60.0, 80.0)


def plane_f(model, theta_i_deg: float, view_deg):
    """``f(wi, wo)`` with ``wi`` at ``theta_i`` (azimuth 0) and ``wo`` at signed
    angles ``view_deg`` in the plane of incidence (mirror at ``-theta_i``), colour
    models reduced to their channel mean; returns ``(f, view angles in radians)``."""
    ti = math.radians(theta_i_deg)
    wi = np.array([math.sin(ti), 0.0, math.cos(ti)])
    v = np.radians(np.asarray(view_deg, dtype=np.float64))
    wo = np.stack([np.sin(v), np.zeros_like(v), np.cos(v)], axis=-1)
    f = np.asarray(model.eval(wi, wo))
    if f.ndim > 1:
        f = f.mean(axis=-1)
    return f, v


def lobe_values(model, theta_i_deg: float, view_deg):
    """``f(wi, wo) cos(theta_o)`` in the plane of incidence (:func:`plane_f`)."""
    f, v = plane_f(model, theta_i_deg, view_deg)
    return f * np.cos(v)


def polar_lobes(ax, view_deg, lobes: dict):
    """Draw ``lobes`` (incidence in degrees -> values at signed viewing angles
    ``view_deg``) on the polar axes ``ax``, each divided by its own peak (so a
    grazing lobe ten times as high does not hide the others; the peak is in the
    legend), the normal up and positive angles (the light's side) on the right:
    the mirror direction, at ``-theta_i``, lies on the left.  Two radial ticks (0.5, 1)."""
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    for t, y in lobes.items():
        y = np.asarray(y, dtype=np.float64)
        peak = float(np.max(y)) if y.size else 0.0
        ax.plot(np.radians(view_deg), y / peak if peak > 0 else y, label=f"theta_i = {t:g} (peak {peak:.3g})")
    ax.set_rmax(1.05)
    ax.set_rticks([0.5, 1.0])
    ax.tick_params(axis="y", labelsize=7)
    ax.set_rlabel_position(90)
    ax.legend(fontsize=7, loc="lower left", bbox_to_anchor=(-0.15, -0.2))


def _lobe_figure(ctx, model_name, incidence):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    m = registry.make(model_name)
    info = registry.info(model_name)
    th = default_thetas(24 if not ctx.quick else 6)
    ctx.steps(len(th))
    alb = albedo_curve(m, th, progress=within(ctx.tick), tol=CURVE_TOL)
    a = np.asarray(alb.value)
    a = a.mean(axis=-1) if a.ndim > 1 else a
    view = np.linspace(-90, 90, 721)
    fig = plt.figure(figsize=(10, 4.4))
    ax = fig.add_subplot(1, 2, 1, projection="polar")
    cols = {"view_deg": view}
    lobes = {}
    for t in incidence:
        lobes[t] = y = lobe_values(m, t, view)
        cols[f"fcos @ theta_i={t:g}"] = y
    polar_lobes(ax, view, lobes)
    ax.set_title(f"{model_name}: f cos(theta_o) / its peak, plane of incidence", fontsize=9)
    ax2 = fig.add_subplot(1, 2, 2)
    ax2.plot(np.degrees(th), a)
    ax2.axhline(1.0, color="0.5", ls="--", lw=0.8)
    ax2.set_xlabel("incidence angle (deg)")
    ax2.set_ylabel("directional albedo")
    ax2.set_xlim(0, 90)
    ax2.grid(alpha=.3)
    ax2.set_title("\n".join(textwrap.wrap(repr(m), 70)), fontsize=7)
    fig.tight_layout()
    ctx.plot("lobe", fig, caption="left: lobe for light at 0, 30, 60, 80 deg, each divided by its own peak "
                                  "(the peak is in the legend), the light on the right of the normal, its "
                                  "mirror direction on the left; right: albedo against incidence")
    ctx.table("lobe", cols)
    ctx.table("albedo", {"theta_deg": np.degrees(th), "albedo": a, "error": np.max(np.atleast_2d(
        np.asarray(alb.error).T), axis=0)})
    ctx.measure("albedo at normal incidence", a[0])
    if info.energy_conserving:
        ctx.measure("max albedo over incidence (claims energy conservation)", float(a.max()),
                    at_most=1.0 + 1e-4, note="1e-4 = the integrator's accuracy")
    else:
        ctx.measure("max albedo over incidence (does not claim energy conservation)", float(a.max()))


for _name in registry.names():
    _info = registry.info(_name)
    figure(f"lobe-{_name}", f"Lobe and albedo: {_name}", "plausible registry", _info.description,
           model_name=_name, incidence=INCIDENCE)(_lobe_figure)
