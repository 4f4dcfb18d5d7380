"""The Modified Phong notes' reference scene: a Cornell box with a Modified Phong sphere."""

from __future__ import annotations

import numpy as np

from . import figure
from . import scenes as S


@figure("notes-cornell", "Cornell box with a Modified Phong sphere", "Modified Phong BRDF notes (Mitsuba 0.5 reference)",
        "A reference image: Modified Phong BSDF in Mitsuba 0.5.0 ... When this material is applied to a sphere "
        "within a Cornell Box the output can look like this.", renders=True,
        exponent=30.0, diffuse_reflectance=0.5, specular_reflectance=0.2)
def cornell(ctx, exponent, diffuse_reflectance, specular_reflectance):
    mi = S.mitsuba()
    d = mi.cornell_box()
    for k in [k for k in d if k.startswith(("small-box", "large-box"))]:
        del d[k]
    d["sphere"] = {"type": "sphere", "center": [0.0, -0.5, 0.0], "radius": 0.5,
                   "bsdf": {"type": "phong", "exponent": exponent, "diffuse_reflectance": diffuse_reflectance,
                            "specular_reflectance": specular_reflectance}}
    res = ctx.res(1.0)
    d["sensor"]["film"].update(width=res, height=res)
    d["sensor"]["sampler"]["sample_count"] = ctx.spp(2)
    d["integrator"] = {"type": "path", "max_depth": 8}
    ctx.steps(1)
    img = S.render(mi, mi.load_dict(d), seed=0)
    ctx.tick()
    ctx.image("cornell", img, caption="Mitsuba 3 cornell_box() with the boxes replaced by a 'phong' sphere "
                                      "(Mitsuba 0.5 parameter names)")
    ctx.measure("mean image luminance", float(np.mean(img)))
