"""Plots (matplotlib, headless Agg backend)."""

from __future__ import annotations


import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def plot_albedo_curves(curves, path, title="Directional albedo"):
    """``curves``: list of ``(label, thetas_rad, AlbedoResult)``; writes ``path`` (PNG/PDF/SVG)."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.4, 4.2), dpi=120)
    for label, th, res in curves:
        v = np.asarray(res.value)
        if v.ndim > 1:
            v = v.mean(axis=-1)
        ax.plot(np.degrees(th), v, label=label)
    ax.axhline(1.0, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel("incidence angle (degrees)")
    ax.set_ylabel("directional albedo a(theta)")
    ax.set_xlim(0, 90)
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return path


def default_thetas(n: int = 46):
    """Incidence angles (radians) from 0 to 89.9 degrees, denser toward grazing."""
    t = np.linspace(0, 1, n)
    deg = 89.9 * (1 - (1 - t) ** 1.5)
    return np.radians(deg)


__all__ = ["plot_albedo_curves", "default_thetas"]
