"""Write docs/images/convert.png: legacy MTL materials, their conversions to Mitsuba and the rule of thumb.

    PYTHONPATH=src python scripts/convert_figure.py

One row per material of :data:`MTL`: spheres under a light at 30 degrees (the source,
``plausible convert``'s Mitsuba BSDF, the exporters' rule of thumb: ``principled`` with
``base_color = Kd``, dielectric, ``roughness = sqrt(2/(Ns+2))``; Mitsuba through the
adapter), each scaled to the source's brightest pixel, and the albedo curves (source:
accurate integrator; Mitsuba BSDFs: Mitsuba's own sampler), red channel.
"""

from __future__ import annotations

import math
import tempfile
from pathlib import Path

import numpy as np

from plausible.analysis import albedo_curve
from plausible.conversion import convert, read_sources
from plausible.conversion.mitsuba import _load, sampler_albedo
from plausible.fitting.batch_report import render_sphere

MTL = """newmtl plastic
Kd 0.5 0.4 0.3
Ks 0.1 0.1 0.1
Ns 20
illum 2
newmtl glossy-red
Kd 0.5 0.05 0.05
Ks 0.3 0.3 0.3
Ns 100
illum 2
newmtl brushed
Kd 0.05 0.05 0.05
Ks 0.7 0.6 0.4
Ns 8
illum 3
"""
THETAS = np.arange(0.0, 86.0, 5.0)
LIGHT = np.array([math.sin(math.radians(30)), 0.0, math.cos(math.radians(30))])


def rule_of_thumb(kd, ns):
    return {"type": "principled", "base_color": {"type": "rgb", "value": [float(x) for x in kd]},
            "metallic": 0.0, "roughness": math.sqrt(2.0 / (ns + 2.0))}


def main(out="docs/images/convert.png"):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from plausible.conversion.mtl import read_mtl

    with tempfile.TemporaryDirectory() as d:
        path = Path(d) / "legacy.mtl"
        path.write_text(MTL)
        mats, sources, conv = read_mtl(path), read_sources(str(path)), convert(str(path)).items
    fig, axes = plt.subplots(len(mats), 4, figsize=(13, 3.2 * len(mats)))
    for row, (m, s, c) in enumerate(zip(mats, sources, conv)):
        thumb = rule_of_thumb(m.Kd, m.Ns)
        imgs = [render_sphere(s.model, 128, LIGHT), render_sphere(_load(c.params), 128, LIGHT),
                render_sphere(_load(thumb), 128, LIGHT)]
        top = max(float(imgs[0].max()), 1e-6)
        titles = [f"{m.name}: MTL read as\n{s.spec[:48]}...", f"converted: {c.target}",
                  "rule of thumb: principled,\nroughness sqrt(2/(Ns+2))"]
        for ax, img, t in zip(axes[row, :3], imgs, titles):
            ax.imshow(np.clip(img / top, 0, 1) ** (1 / 2.2), cmap="gray", vmin=0, vmax=1)
            ax.set_title(t, fontsize=8)
            ax.axis("off")
        ax = axes[row, 3]
        a_src = np.asarray(albedo_curve(s.model, thetas_deg=THETAS).value).reshape(len(THETAS), -1)[:, 0]
        ax.plot(THETAS, a_src, "k-", label="source (MTL reading)")
        ax.plot(THETAS, sampler_albedo(c.params, THETAS)[:, 0], "C0-", label=f"converted ({c.target})")
        ax.plot(THETAS, sampler_albedo(thumb, THETAS)[:, 0], "C3--", label="rule of thumb")
        ax.set_xlabel("incidence (deg)")
        ax.set_ylabel("albedo (red)")
        ax.set_ylim(0, 1.05)
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=90)
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
