"""Plots (matplotlib, headless Agg backend)."""

from __future__ import annotations

import tempfile
from pathlib import Path

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


def check_image_path(path, what: str = "plot") -> Path:
    """Make sure an image can be written to ``path`` before the work that makes it:
    its extension is a format matplotlib writes and its folder exists and takes
    a new file.  ValueError naming ``what``, the path and the reason otherwise."""
    path = Path(path)
    from matplotlib.backend_bases import FigureCanvasBase

    fmts = FigureCanvasBase.get_supported_filetypes()
    ext = path.suffix.lower().lstrip(".")
    if ext not in fmts:
        raise ValueError(f"{what} {str(path)!r}: unknown image type {path.suffix or '(no extension)'!r}; "
                         f"use one of {', '.join('.' + f for f in sorted(fmts))}")
    if path.is_dir():
        raise ValueError(f"{what} {str(path)!r} is a folder; give a file name")
    check_writable_dir(path.parent, what)
    return path


def check_writable_dir(folder, what: str = "output folder", create: bool = False) -> Path:
    """ValueError unless ``folder`` exists (or, with ``create``, can be made) and
    a file can be written into it; the message names ``what``, the folder and the
    operating system's reason."""
    folder = Path(folder)
    try:
        if create:
            folder.mkdir(parents=True, exist_ok=True)
        elif not folder.is_dir():
            raise ValueError(f"{what}: folder {str(folder)!r} does not exist")
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as e:
        raise ValueError(f"{what}: cannot write into {str(folder)!r} ({e.strerror or e})") from None
    return folder


def default_thetas(n: int = 46):
    """Incidence angles (radians) from 0 to 89.9 degrees, denser toward grazing."""
    t = np.linspace(0, 1, n)
    deg = 89.9 * (1 - (1 - t) ** 1.5)
    return np.radians(deg)


__all__ = ["check_image_path", "check_writable_dir", "plot_albedo_curves", "default_thetas"]
