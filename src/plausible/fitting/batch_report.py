"""The comparison report of a fitting batch, in the style of Ngan, Durand &
Matusik (EGSR 2005, fig. 4-6): per material, every model's error under every
metric as bars sorted by error, the best model per material, and point-lit
spheres of the target and of each fit side by side.

``write_report(results, out)`` reads the rows of :func:`plausible.fitting.batch.load_results`
(or a results folder) and writes ``out/index.html`` with its PNG images.
"""

from __future__ import annotations

import html
import math
import re
from pathlib import Path

import numpy as np

from .. import registry, vec
from ..arrays.ops import NP
from ..plotting import _plt
from .batch import ERROR_KEYS, load_results
from ..text import write_atomic

#: Direction toward the light of the sphere renders (view along +z).
LIGHT = np.array([-0.45, 0.55, 0.70]) / np.linalg.norm([-0.45, 0.55, 0.70])


def render_sphere(model, size: int = 96, light=LIGHT, rgb: bool = False) -> np.ndarray:
    """Radiance ``f(L, V) cos(theta_L)`` of a unit sphere lit by a directional
    light of unit irradiance (normal incidence), seen orthographically along
    ``-z``: shape ``(size, size)`` (channel mean), or ``(size, size, 3)`` with
    ``rgb`` (a grey model's value in each channel), zero outside the disc.

    At each pixel the shading frame is ``vec.frame`` about the normal, so the
    tangent ``u`` follows that frame (isotropic models do not depend on it).
    """
    c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    inside = r2 < 1.0
    n = np.stack([x[inside], y[inside], np.sqrt(1.0 - r2[inside])], -1)
    nn = (n[:, 0], n[:, 1], n[:, 2])
    s, t = vec.frame(NP, nn)

    def local(d):
        d = np.broadcast_to(d, n.shape)
        dd = (d[:, 0], d[:, 1], d[:, 2])
        return np.stack([vec.dot(dd, s), vec.dot(dd, t), vec.dot(dd, nn)], -1)

    wl, wv = local(light), local(np.array([0.0, 0.0, 1.0]))
    ok = (wl[:, 2] > 1e-6) & (wv[:, 2] > 1e-6)
    img = np.zeros((size, size, 3) if rgb else (size, size))
    vals = np.zeros((len(n), 3) if rgb else len(n))
    if np.any(ok):
        f = np.asarray(model.eval(wl[ok], wv[ok]))
        if rgb:
            f = np.broadcast_to(f[:, None] if f.ndim == 1 else f, (len(f), 3))
            vals[ok] = f * wl[ok, 2][:, None]
        else:
            f = f.mean(axis=-1) if f.ndim == 2 else f
            vals[ok] = f * wl[ok, 2]
    img[inside] = vals
    return img


def _tonemap(img, scale):
    v = np.clip(img / scale, 0.0, None)
    return np.clip(v / (1.0 + v), 0, 1) ** (1 / 2.2)


def _slug(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", text)[:80] or "target"


def _bars(target, rows, path):
    """One panel per metric: each model's error under that metric, sorted."""
    plt = _plt()
    metrics = sorted({r["metric"] for r in rows})
    fig, axes = plt.subplots(1, len(metrics), figsize=(4.2 * len(metrics), 2.8), dpi=110, squeeze=False)
    for ax, metric in zip(axes[0], metrics):
        rs = sorted((r for r in rows if r["metric"] == metric and r["status"] == "ok"
                     and r["errors"].get(metric) is not None), key=lambda r: r["errors"][metric])
        names = [r["model"] for r in rs]
        vals = [r["errors"][metric] for r in rs]
        ax.barh(range(len(rs)), vals, color=[f"C{i % 10}" for i in range(len(rs))])
        ax.set_yticks(range(len(rs)), names, fontsize=7)
        ax.invert_yaxis()
        ax.set_xlabel(f"{metric} error (fitted under {metric})", fontsize=8)
        ax.tick_params(axis="x", labelsize=7)
    fig.suptitle(target, fontsize=8)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)


def _spheres(target, rows, path, size):
    """Target and each fitted model (best metric row per model) as spheres."""
    from .targets import as_target

    tgt = as_target(target).model
    if tgt is None:
        return False
    fits = []
    for r in sorted(rows, key=lambda r: (r["model"], r["metric"])):
        if r["status"] != "ok":
            continue
        ps = {k: v for k, v in r["params"].items() if v is not None}
        try:
            fits.append((f"{r['model']}\n({r['metric']})", registry.make(r["model"], **ps)))
        except ValueError:
            continue
    imgs = [("target", render_sphere(tgt, size))] + [(lab, render_sphere(m, size)) for lab, m in fits]
    scale = max(float(np.percentile(imgs[0][1][imgs[0][1] > 0], 99)) if np.any(imgs[0][1] > 0) else 1.0, 1e-6)
    plt = _plt()
    cols = min(len(imgs), 6)
    rws = math.ceil(len(imgs) / cols)
    fig, axes = plt.subplots(rws, cols, figsize=(1.6 * cols, 1.8 * rws), dpi=110, squeeze=False)
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (lab, img) in zip(axes.ravel(), imgs):
        shown = _tonemap(img, scale)
        c = (np.arange(size) + 0.5) / size * 2.0 - 1.0
        x, y = np.meshgrid(c, c)
        shown[x * x + y * y >= 1.0] = 0.3        # grey backdrop: the silhouette stays visible
        ax.imshow(shown, cmap="gray", vmin=0, vmax=1)
        ax.set_title(lab, fontsize=6)
    fig.tight_layout()
    fig.savefig(path)
    plt.close(fig)
    return True


def best_models(rows) -> dict:
    """``{(target, metric): row}``: the row with the smallest error under its own
    metric, per target and metric (failed rows never win)."""
    best = {}
    for r in rows:
        e = r["errors"].get(r["metric"]) if r["status"] == "ok" else None
        if e is None:
            continue
        k = (r["target"], r["metric"])
        if k not in best or e < best[k]["errors"][r["metric"]]:
            best[k] = r
    return best


def write_report(results, out, *, spheres=(), size: int = 96) -> Path:
    """Write ``out/index.html``: the best model per material and metric, a bar
    chart per material, and spheres of target and fits for the targets in
    ``spheres`` (those whose target is a model or a MERL file).

    ``results``: a results folder of :func:`plausible.fitting.batch.fit_batch` or
    its rows (:func:`load_results`)."""
    rows = load_results(results) if isinstance(results, (str, Path)) else list(results)
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    targets = list(dict.fromkeys(r["target"] for r in rows))
    metrics = sorted({r["metric"] for r in rows})
    best = best_models(rows)
    esc = html.escape
    parts = ["<!doctype html><meta charset='utf-8'><title>plausible: fitting batch</title>",
             "<style>body{font-family:sans-serif;margin:2em;max-width:70em}"
             "td,th{padding:2px 8px;border-bottom:1px solid #ddd;font-size:90%}"
             ".failed{color:#b00}</style>",
             "<h1>Fitting batch: comparison</h1>",
             f"<p>{len(targets)} targets, {len({r['model'] for r in rows})} models, {len(metrics)} metrics, "
             f"{len(rows)} fits ({sum(r['status'] != 'ok' for r in rows)} failed). Each error is the figure "
             "of the metric the fit minimised (docs/fitting.md); smaller is better.</p>",
             "<h2>Best model per material</h2><table><tr><th>target</th>"
             + "".join(f"<th>{esc(m)}</th>" for m in metrics) + "</tr>"]
    for t in targets:
        cells = []
        for m in metrics:
            b = best.get((t, m))
            cells.append(f"<td>{esc(b['model'])} ({b['errors'][m]:.4g})</td>" if b else "<td>-</td>")
        parts.append(f"<tr><td>{esc(t)}</td>{''.join(cells)}</tr>")
    parts.append("</table>")
    wanted = set(spheres)
    for t in targets:
        rs = [r for r in rows if r["target"] == t]
        slug = _slug(t)
        parts.append(f"<h2>{esc(t)}</h2>")
        if any(r["status"] == "ok" for r in rs):
            _bars(t, rs, out / f"{slug}-errors.png")
            parts.append(f"<img src='{slug}-errors.png' alt='errors of every model for {esc(t)}'>")
        for r in rs:
            if r["status"] != "ok":
                parts.append(f"<p class='failed'>{esc(r['model'])} / {esc(r['metric'])} failed: "
                             f"{esc(str(r.get('error')))}</p>")
        if t in wanted:
            try:
                if _spheres(t, rs, out / f"{slug}-spheres.png", size):
                    parts.append(f"<p><img src='{slug}-spheres.png' alt='spheres of {esc(t)}'></p>")
                else:
                    parts.append("<p>(no spheres: a table target has no model to render)</p>")
            except ValueError as e:
                parts.append(f"<p class='failed'>spheres not rendered: {esc(str(e))}</p>")
    path = out / "index.html"
    write_atomic(path, "\n".join(parts) + "\n")
    return path


__all__ = ["ERROR_KEYS", "best_models", "render_sphere", "write_report"]
