"""docs/blender.md's tables: the acquisition validated on Cycles' Diffuse BSDF, then Cycles'
Principled BSDF at a few settings, acquired and checked (reciprocity, energy).

    PYTHONPATH=src python scripts/blender_principled.py > /tmp/blender-tables.md

About two minutes on two cores (96 px, 16 spp, 18 light angles x 2 and a furnace per material).
"""

import math
import sys
import time

import numpy as np

from plausible.blender import acquire, check_acquisition, material_spec

SETTINGS = [
    ("metal, rough (0.5)", {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.5}),
    ("metal, smooth (0.1)", {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.1}),
    ("dielectric, rough (0.5)", {"Base Color": [0.8, 0.8, 0.8], "Metallic": 0.0, "Roughness": 0.5}),
    ("dielectric, smooth (0.1)", {"Base Color": [0.8, 0.8, 0.8], "Metallic": 0.0, "Roughness": 0.1}),
    ("white dielectric, rough (0.5)", {"Base Color": [1, 1, 1], "Metallic": 0.0, "Roughness": 0.5}),
    ("metal, anisotropic (0.4, 0.8)", {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.4,
                                       "Anisotropic": 0.8}),
]


def diffuse_rows():
    rd = np.array([0.2, 0.5, 0.9])
    out = []
    for res in (48, 96):
        acq = acquire(material_spec(diffuse=rd), resolution=res)
        ratio = acq.f * math.pi / rd - 1.0
        th = np.degrees(np.arccos(np.minimum(acq.wi[:, 2], acq.wo[:, 2])))
        rep = check_acquisition(acq)
        out.append(f"| {res} | {len(ratio)} | {np.median(ratio):+.1e} | {np.mean(np.abs(ratio)):.1e} | "
                   f"{np.percentile(np.abs(ratio), 95):.1e} | {np.percentile(np.abs(ratio[th < 60]), 95):.1e} | "
                   f"{np.max(np.abs(acq.albedo - rd)):.1e} | {rep['reciprocity'].details['median']:.1e} / "
                   f"{rep['reciprocity'].figure:.1e} | {acq.seconds:.1f} |")
    return out


def principled_rows():
    out = []
    for label, p in SETTINGS:
        for dist in ("MULTI_GGX", "GGX"):
            acq = acquire(material_spec(principled=dict(p, distribution=dist)), name=label)
            rep = check_acquisition(acq, isotropic="Anisotropic" not in p)
            r, e = rep["reciprocity"], rep["energy"]
            lo = float(acq.albedo.mean(1).min())
            med = r.details.get("median", math.nan)
            verdict = "PASS" if r.passed else "UNRESOLVED" if r.unresolved else "FAIL"
            out.append(f"| {label} | {dist} | {med:.3f} / {r.figure:.3f} ({r.details.get('pairs', 0)} pairs) | "
                       f"{verdict} | {lo:.3f} - {e.figure:.3f} "
                       f"(at {e.worst['theta_deg']:.0f} deg, stderr {e.worst['stderr']:.1g}) | "
                       f"{'PASS' if e.passed else 'FAIL'} | {acq.seconds:.1f} |")
            print(out[-1], file=sys.stderr)
    return out


if __name__ == "__main__":
    t0 = time.perf_counter()
    print("| px | pairs | median f pi/rd - 1 | mean abs | 95th pct abs | 95th pct, theta < 60 | furnace max abs "
          "| reciprocity median / 95th | seconds |")
    print("|---|---|---|---|---|---|---|---|---|")
    print("\n".join(diffuse_rows()))
    print()
    print("| Principled BSDF | distribution | reciprocity median / 95th pct | verdict | furnace albedo min - max "
          "| energy | seconds |")
    print("|---|---|---|---|---|---|---|")
    print("\n".join(principled_rows()))
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")
