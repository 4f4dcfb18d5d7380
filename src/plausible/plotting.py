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
    save_figure(fig, path)
    return path


def save_figure(fig, path) -> Path:
    """Save ``fig`` to ``path`` whole or not at all (:func:`plausible.text.replacing`: a
    full disk leaves no 0-byte image) and close it; the format is ``path``'s extension."""
    from .text import replacing

    path = Path(path)
    try:
        with replacing(path) as (tmp,):
            fig.savefig(tmp, format=path.suffix.lstrip(".").lower() or None)
    finally:
        _plt().close(fig)
    return path


def check_image_path(path, what: str = "plot") -> Path:
    """Make sure an image can be written to ``path`` before the work that makes it:
    its extension is a format matplotlib writes and its folder exists and takes
    a new file.  ValueError naming ``what``, the path and the reason otherwise."""
    if not str(path).strip():
        raise ValueError(f"{what}: an empty path; give an image file name (e.g. albedo.png)")
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


def check_new_dir(folder, what: str = "output folder") -> Path:
    """:func:`check_writable_dir` without making anything: ``folder`` exists and takes a
    new file, or it does not exist yet and its nearest existing parent is a folder that
    takes a new file (so that it can be made once the work is done).  For a command that
    validates all its input before it creates its output folder."""
    folder = Path(folder)
    if folder.exists():
        if not folder.is_dir():
            raise ValueError(f"{what}: cannot write into {str(folder)!r} (it is a file, not a folder)")
        return check_writable_dir(folder, what)
    parent = folder.absolute().parent
    while not parent.exists():
        parent = parent.parent
    if not parent.is_dir():
        raise ValueError(f"{what}: cannot write into {str(folder)!r} ({str(parent)!r} is a file, not a folder)")
    check_writable_dir(parent, what)
    return folder


def check_writable_file(path, what: str = "output file") -> Path:
    """ValueError naming ``what`` unless a file can be written at ``path``: not a folder,
    its folder exists and takes a new file, and an existing file opens for appending
    (nothing is written to it).  Before the work that makes the file."""
    path = Path(path)
    if path.is_dir():
        raise ValueError(f"{what} {str(path)!r} is a folder; give a file name")
    check_writable_dir(path.parent, what)
    if path.exists():
        try:
            with open(path, "a", encoding="utf-8"):
                pass
        except OSError as e:
            raise ValueError(f"{what}: cannot write {str(path)!r} ({e.strerror or e})") from None
    return path


def default_thetas(n: int = 46):
    """Incidence angles (radians) from 0 to 89.9 degrees, denser toward grazing."""
    t = np.linspace(0, 1, n)
    deg = 89.9 * (1 - (1 - t) ** 1.5)
    return np.radians(deg)


__all__ = ["check_image_path", "check_new_dir", "check_writable_dir", "check_writable_file", "plot_albedo_curves",
           "default_thetas", "save_figure"]
