"""Cycles beside Mitsuba in compare_looks' scene (docs/blender.md, "The comparison" and "The mapping").

    PYTHONPATH=src python scripts/blender_looks.py floor      # Diffuse vs diffuse: the comparison's floor
    PYTHONPATH=src python scripts/blender_looks.py mapping    # gltf-pbr vs its Principled BSDF, per variant

Prints a Markdown table per part (FLIP, per view, highlight ratios, seconds)."""

from __future__ import annotations

import sys
import time

from plausible import registry
from plausible.blender import material_spec
from plausible.blender.looks import compare_cycles
from plausible.blender.principled import principled_inputs

GLTF = {
    "metal, rough (0.6)": dict(base_color=[0.9, 0.9, 0.9], metallic=1.0, roughness=0.6),
    "gold metal (0.35)": dict(base_color=[1.0, 0.78, 0.34], metallic=1.0, roughness=0.35),
    "red dielectric (0.35)": dict(base_color=[0.5, 0.1, 0.1], metallic=0.0, roughness=0.35),
    "red dielectric (0.7)": dict(base_color=[0.5, 0.1, 0.1], metallic=0.0, roughness=0.7),
    "white dielectric (0.2)": dict(base_color=[0.8, 0.8, 0.8], metallic=0.0, roughness=0.2),
}


def variants(params):
    """Principled inputs of ``params`` under each candidate mapping."""
    base = principled_inputs(params)
    yield "MULTI_GGX (the node's default)", dict(base, distribution="MULTI_GGX")
    yield "GGX (single scatter)", dict(base, distribution="GGX")


def row(name, lk, t):
    per = " / ".join(f"{f:.3f}" for f in lk.flips)
    rat = " / ".join(f"{r:.2f}" for r in lk.highlight_ratios)
    return f"| {name} | {lk.flip:.3f} | {per} | {rat} | {t:.0f} |"


def floor(spps=(16, 64)):
    print("| pair | spp | FLIP | per view 0/60/120/150 | highlight ratios | seconds |\n|---|---|---|---|---|---|")
    for rd in ([0.2, 0.5, 0.9], [0.8, 0.8, 0.8]):
        for spp in spps:
            t = time.perf_counter()
            lk = compare_cycles({"type": "diffuse", "reflectance": {"type": "rgb", "value": rd}},
                                material_spec(diffuse=rd), spp=spp)
            print(row(f"Diffuse {rd} | {spp}", lk, time.perf_counter() - t), flush=True)


def mapping():
    print("| gltf-pbr | Principled | FLIP | per view 0/60/120/150 | highlight ratios | seconds |\n"
          "|---|---|---|---|---|---|")
    for name, p in GLTF.items():
        model = registry.make("gltf-pbr", **p)
        for vname, inputs in variants(p):
            t = time.perf_counter()
            lk = compare_cycles(model, material_spec(principled=inputs))
            print(row(f"{name} | {vname}", lk, time.perf_counter() - t), flush=True)


if __name__ == "__main__":
    {"floor": floor, "mapping": mapping}[sys.argv[1] if len(sys.argv) > 1 else "floor"]()
