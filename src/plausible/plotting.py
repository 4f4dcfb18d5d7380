"""Plots (matplotlib, headless Agg backend): directional albedo curves
(:func:`albedo_figure`, :func:`plot_albedo_curves`), a lobe in the plane of
incidence on polar axes (:func:`plot_lobe_polar`), a hemisphere map of
``f cos(theta_o)`` (:func:`plot_hemisphere`), and :func:`layout_problems`, which
says what of a figure lies outside its canvas or squeezes its axes.

Every figure is laid out by matplotlib's constrained layout, its legend below the
axes with labels wrapped to the figure's width, so long labels (a fit's target
``material:...@ngan2005/...`` with its parameters) never push the axes aside.
"""

from __future__ import annotations

import math
import tempfile
import textwrap
from pathlib import Path

import numpy as np


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


#: Characters per line of a wrapped legend label or title (the figure is 6.4 inches wide).
WRAP = 72
#: In a linear albedo plot, a curve whose maximum exceeds both this and ``OFF_SCALE`` times
#: every other curve's maximum is drawn off scale (clipped, with a note) unless ``yscale="log"``.
OFF_SCALE_MIN, OFF_SCALE = 2.0, 3.0


def _wrap(text: str, width: int = WRAP, lines: int = 3) -> str:
    """``text`` wrapped to ``width`` characters, at most ``lines`` lines (the rest as "...")."""
    return "\n".join(textwrap.wrap(str(text), width, max_lines=lines, placeholder=" ...")) or str(text)


def _figure(rows: int = 0, polar: bool = False):
    """A constrained-layout figure 6.4 inches wide, taller by the legend's ``rows``.
    Polar axes get fixed margins instead: matplotlib draws a half-disc wedge in the
    middle half of a square box as wide as the disc (constrained layout would fit
    the whole square), so the box overlaps the title and legend bands while the
    half-disc spans 3/4 of the width between them."""
    plt = _plt()
    if not polar:
        fig = plt.figure(figsize=(6.4, 4.2 + 0.16 * rows), dpi=120, layout="constrained")
        return fig, fig.add_subplot()
    side, below, above = 4.8, 0.95 + 0.16 * rows, 0.75     # inches: disc width, legend band, title band
    h = below + side / 2 + above
    centre = below + side / 4                               # the half-disc's middle, from the bottom
    fig = plt.figure(figsize=(6.4, h), dpi=120)
    fig.add_axes(((6.4 - side) / 2 / 6.4, (centre - side / 2) / h, side / 6.4, side / h), projection="polar")
    return fig, fig.axes[0]


def _legend_below(fig, ax, fontsize=8, ncol=1):
    """The axes' legend under them, inside the canvas (constrained layout makes room)."""
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), fontsize=fontsize, ncol=ncol,
                  frameon=False)


def _mean_curve(res) -> np.ndarray:
    v = np.asarray(res.value, dtype=np.float64)
    return v.mean(axis=-1) if v.ndim > 1 else v


def _off_scale(tops: list) -> float | None:
    """The top of a linear y axis that keeps every curve but an outlier readable, or None:
    with two curves or more, one whose maximum exceeds ``OFF_SCALE_MIN`` and ``OFF_SCALE``
    times every other's is clipped at 1.15 times the largest of the others (at least 1.15)."""
    if len(tops) < 2:
        return None
    order = sorted(tops)
    rest = order[-2]
    if order[-1] > OFF_SCALE_MIN and order[-1] > OFF_SCALE * max(rest, 1e-300):
        return 1.15 * max(rest, 1.0)
    return None


def albedo_figure(curves, title="Directional albedo", yscale: str = "linear"):
    """The figure of directional albedo curves: ``curves`` a list of ``(label,
    thetas_rad, AlbedoResult)`` (a colour result is drawn as its channel mean).

    ``yscale``: ``"linear"`` (the default; a curve that dwarfs the others, such as
    the original Phong model's 26 at grazing, is clipped and its legend entry says
    where it peaks) or ``"log"``.  The legend lies below the axes, labels wrapped;
    the dashed line is albedo 1 (energy conservation)."""
    if yscale not in ("linear", "log"):
        raise ValueError(f"yscale must be 'linear' or 'log', got {yscale!r}")
    labels = [_wrap(label) for label, _, _ in curves]
    fig, ax = _figure(sum(lb.count("\n") + 1 for lb in labels))
    values = [_mean_curve(res) for _, _, res in curves]
    top = _off_scale([float(np.nanmax(v)) for v in values]) if yscale == "linear" else None
    for label, (_, th, _), v in zip(labels, curves, values):
        deg = np.degrees(th)
        if top is not None and np.nanmax(v) > top:
            k = int(np.nanargmax(v))
            label += f"\n(off scale: up to {v[k]:.3g} at {deg[k]:.1f} deg; a log axis shows it)"
        ax.plot(deg, v, label=label)
    ax.axhline(1.0, color="0.5", lw=0.8, ls="--")
    ax.set_xlabel("incidence angle (degrees)")
    ax.set_ylabel("directional albedo a(theta)")
    ax.set_xlim(0, 90)
    ax.set_yscale(yscale)
    if top is not None:
        ax.set_ylim(0.0, top)
    ax.set_title(_wrap(title), fontsize=10)
    ax.grid(alpha=0.3)
    _legend_below(fig, ax)
    return fig


def plot_albedo_curves(curves, path, title="Directional albedo", yscale: str = "linear"):
    """Write :func:`albedo_figure` of ``curves`` to ``path`` (PNG/PDF/SVG); returns ``path``."""
    fig = albedo_figure(curves, title, yscale)
    save_figure(fig, path)
    return path


def save_figure(fig, path) -> Path:
    """Save ``fig`` to ``path`` whole (the canvas as laid out, never cropped) or not at all
    (:func:`plausible.text.replacing`: a full disk leaves no 0-byte image) and close it; the
    format is ``path``'s extension."""
    from .text import replacing

    path = Path(path)
    try:
        with replacing(path) as (tmp,):
            fig.savefig(tmp, format=path.suffix.lstrip(".").lower() or None)
    finally:
        _plt().close(fig)
    return path


def _plane_directions(theta_i_deg: float, n: int):
    """``(signed theta_o in radians, wi, wo)`` in the plane of incidence: the light at
    ``theta_i`` on the ``-x`` side, ``theta_o`` from -90 to 90 degrees (positive:
    the mirror side), ``wo = (sin theta_o, 0, cos theta_o)``."""
    from .vec import direction

    to = np.linspace(-math.pi / 2, math.pi / 2, n)
    wo = np.stack([np.sin(to), np.zeros_like(to), np.cos(to)], -1)
    return to, direction(math.radians(theta_i_deg), math.pi), wo


def plot_lobe_polar(model, theta_i_deg=(30.0, 60.0), path=None, n: int = 361, title=None):
    """The lobe in the plane of incidence on polar axes: ``f(wi, wo) cos(theta_o)``
    (channel mean) as the radius against the signed outgoing angle (0 the
    normal, at the top; positive on the mirror side), one curve per incidence angle
    in ``theta_i_deg``, the light's direction drawn as a dotted ray of the same
    colour.  Returns the figure (written to ``path`` too when given).  The radius of
    curve ``k`` is ``fig.axes[0].lines[2 k]``'s data."""
    thetas = np.atleast_1d(np.asarray(theta_i_deg, dtype=np.float64))
    if np.any(~np.isfinite(thetas)) or np.any((thetas < 0) | (thetas >= 90)):
        raise ValueError(f"theta_i_deg must lie in [0, 90) degrees, got {thetas.tolist()}")
    fig, ax = _figure(len(thetas), polar=True)
    top = 0.0
    for k, t in enumerate(thetas):
        to, wi, wo = _plane_directions(float(t), n)
        r = np.asarray(model.eval(wi, wo), dtype=np.float64)
        r = (r.mean(axis=-1) if r.ndim > 1 else r) * wo[:, 2]
        top = max(top, float(np.nanmax(r)))
        ax.plot(to, r, color=f"C{k}", label=f"theta_i = {t:g} deg")
        ax.plot([-math.radians(t)] * 2, [0.0, 1.0], color=f"C{k}", ls=":", lw=1.0)
    for line in ax.lines[1::2]:                 # the light rays reach the largest radius
        line.set_ydata([0.0, 1.05 * top if top > 0 else 1.0])
    ax.set_theta_zero_location("N")
    ax.set_theta_direction(-1)                  # positive angles to the right: the mirror side
    ax.set_thetamin(-90)
    ax.set_thetamax(90)
    # the figure's own title and legend: the polar box reaches into their bands (:func:`_figure`)
    fig.suptitle(_wrap(title or f"{model!r}: f cos(theta_o) in the plane of incidence"), fontsize=9, y=0.985,
                 va="top")
    fig.legend(*ax.get_legend_handles_labels(), loc="lower center", fontsize=8, ncol=min(len(thetas), 3),
               frameon=False)
    if path is not None:
        fig.savefig(path)
    return fig


def hemisphere_grid(n: int):
    """``(x, y, wo, inside)`` of an ``n x n`` map of the hemisphere seen from above
    (orthographic: pixel centres ``(x, y)`` in [-1, 1]^2, ``wo = (x, y,
    sqrt(1 - x^2 - y^2))`` inside the unit disk)."""
    c = (np.arange(n) + 0.5) / n * 2.0 - 1.0
    x, y = np.meshgrid(c, c)
    r2 = x * x + y * y
    inside = r2 < 1.0
    wo = np.stack([x, y, np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))], -1)
    return x, y, wo, inside


def plot_hemisphere(model, wi, path=None, n: int = 201, scale: str = "linear", title=None):
    """A map of ``f(wi, wo) cos(theta_o)`` (channel mean) over the hemisphere of
    ``wo``, seen from above (:func:`hemisphere_grid`: ``x`` to the right, ``y`` up;
    the rim is the horizon), with a colour bar; ``wi`` marked by a cross where its
    projection lies.  ``scale``: ``"linear"`` or ``"log"``.  Returns the figure
    (written to ``path`` too when given); the map is ``fig.axes[0].images[0]``'s
    array (NaN outside the disk), row ``j`` at ``y_j``, column ``i`` at ``x_i``."""
    from matplotlib.colors import LogNorm, Normalize

    if scale not in ("linear", "log"):
        raise ValueError(f"scale must be 'linear' or 'log', got {scale!r}")
    wi = np.asarray(wi, dtype=np.float64).reshape(3)
    x, y, wo, inside = hemisphere_grid(n)
    f = np.asarray(model.eval(wi, wo.reshape(-1, 3)), dtype=np.float64)
    f = (f.mean(axis=-1) if f.ndim > 1 else f).reshape(n, n) * wo[..., 2]
    img = np.where(inside, f, np.nan)
    fig, ax = _figure()
    top = float(np.nanmax(img)) if np.any(inside) else 1.0
    norm = (LogNorm(vmin=max(top, 1e-300) * 1e-4, vmax=max(top, 1e-300)) if scale == "log"
            else Normalize(vmin=0.0, vmax=top if top > 0 else 1.0))
    im = ax.imshow(img, origin="lower", extent=(-1, 1, -1, 1), norm=norm, cmap="magma", interpolation="nearest")
    ax.add_patch(_plt().Circle((0, 0), 1.0, fill=False, color="0.5", lw=0.8))
    nrm = wi / np.linalg.norm(wi)
    ax.plot([nrm[0]], [nrm[1]], "x", color="c", ms=8, label="wi (to the light)")
    ax.set_aspect("equal")
    ax.set_xlabel("wo.x")
    ax.set_ylabel("wo.y")
    fig.colorbar(im, ax=ax, label="f cos(theta_o)", shrink=0.9)
    ax.set_title(_wrap(title or f"{model!r}: f cos(theta_o) over the hemisphere", 60), fontsize=9)
    _legend_below(fig, ax)
    if path is not None:
        fig.savefig(path)
    return fig


def layout_problems(fig, min_axes_width: float = 0.5) -> list:
    """What is wrong with the layout of ``fig`` as drawn: texts, legends or
    colour bars reaching outside the canvas, and main axes narrower than
    ``min_axes_width`` of the figure's width.  An empty list is a good layout."""
    fig.canvas.draw()
    r = fig.canvas.get_renderer()
    W, H = fig.bbox.width, fig.bbox.height
    out = []
    main = [a for a in fig.axes if a.get_label() != "<colorbar>"]
    for k, ax in enumerate(main):
        b = ax.get_window_extent(r)
        w = b.width / W
        if ax.name != "rectilinear" or ax.get_aspect() != "auto":   # a disc: its limiting side
            w = max(w, b.height / H)
        if w < min_axes_width:
            out.append(f"axes {k} spans {w:.0%} of the width (< {min_axes_width:.0%})")
    parts = [("title", ax.title) for ax in fig.axes] + [("legend", ax.get_legend()) for ax in fig.axes]
    parts += [("title", fig._suptitle)] + [("legend", lg) for lg in fig.legends]
    parts += [("label", t) for ax in fig.axes for t in (ax.xaxis.label, ax.yaxis.label)]
    for what, artist in parts:
        if artist is None or not artist.get_visible() or (hasattr(artist, "get_text") and not artist.get_text()):
            continue
        b = artist.get_window_extent(r)
        if b.x0 < -0.5 or b.y0 < -0.5 or b.x1 > W + 0.5 or b.y1 > H + 0.5:
            out.append(f"{what} reaches outside the canvas ({b.x0:.0f}..{b.x1:.0f} x {b.y0:.0f}..{b.y1:.0f} "
                       f"of {W:.0f} x {H:.0f} px)")
    return out


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


__all__ = ["albedo_figure", "check_image_path", "check_new_dir", "check_writable_dir", "check_writable_file",
           "default_thetas", "hemisphere_grid", "layout_problems", "plot_albedo_curves", "plot_hemisphere",
           "plot_lobe_polar", "save_figure"]
