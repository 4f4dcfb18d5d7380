"""docs/blender.md's tables: the acquisition validated on Cycles' Diffuse BSDF, then Cycles'
Principled BSDF at a few settings, acquired and checked (reciprocity, energy).

    PYTHONPATH=src python scripts/blender_principled.py > /tmp/blender-tables.md
    PYTHONPATH=src python scripts/blender_principled.py tangent    # the anisotropic tables

About two minutes on two cores (96 px, 16 spp, 18 light angles x 2 and a furnace per material);
``tangent``: the tangent-resolved acquisition (:mod:`plausible.blender.tangent`: 8 angles x 6 turns
x 2 and a furnace per material), about four minutes.
"""

import math
import sys
import time

import numpy as np

from plausible import registry
from plausible.blender import acquire, check_acquisition, material_spec
from plausible.blender.principled import principled_inputs
from plausible.blender.tangent import acquire_tangent, check_isotropy, check_model, turned

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
            rep = check_acquisition(acq)
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


ANISOTROPIC = [
    ("metal, anisotropic (0.4, 0.8)", {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.4,
                                       "Anisotropic": 0.8}),
    ("metal, anisotropic (0.6, 0.5), turned 0.125", {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.6,
                                                     "Anisotropic": 0.5, "Anisotropic Rotation": 0.125}),
    ("dielectric, anisotropic (0.4, 0.8)", {"Base Color": [0.8, 0.8, 0.8], "Metallic": 0.0, "Roughness": 0.4,
                                            "Anisotropic": 0.8}),
]


def _ggx(rotation):
    return registry.make("gltf-pbr", base_color=[1, 1, 1], metallic=1.0, roughness=0.5, anisotropy_strength=0.6,
                         anisotropy_rotation=rotation)


def tangent_validation_rows():
    """The tangent-resolved acquisition against closed forms: Diffuse (rd / pi, flat in phi) and
    anisotropic single-scatter GGX at two rotations, with the wrong frames beside."""
    rd = [0.2, 0.5, 0.9]
    acq = acquire_tangent(material_spec(diffuse=rd), name="diffuse")
    lam, iso = check_model(acq, registry.make("lambertian", rd=rd)), check_isotropy(acq)
    rep = check_acquisition(acq)
    out = [f"| Diffuse (0.2, 0.5, 0.9) | rd / pi | {lam.details['median']:.1e} / {lam.details['p90']:.1e} | "
           f"isotropy {iso.figure:.1e} ({'PASS' if iso.passed else 'FAIL'}) | "
           f"{rep['reciprocity'].details['median']:.1e} / {rep['reciprocity'].figure:.1e} "
           f"({rep['reciprocity'].details['pairs']} pairs) | {acq.seconds:.1f} |"]
    for turn in (0.0, 0.125):
        m = _ggx(2 * math.pi * turn)
        acq = acquire_tangent(material_spec(principled=principled_inputs(m.params)), name=f"ggx {turn}")
        r, rep = check_model(acq, m), check_acquisition(acq)
        wrong = [check_model(turned(acq, 45.0), m).figure, check_model(acq, _ggx(2 * math.pi * (0.5 - turn))).figure]
        out.append(f"| Principled GGX metal, white, roughness {principled_inputs(m.params)['Roughness']:.3f}, "
                   f"anisotropic {principled_inputs(m.params)['Anisotropic']:.3f}, rotation {turn} | gltf-pbr "
                   f"(roughness 0.5, anisotropy 0.6, rotation {turn * 360:.0f} deg) | "
                   f"{r.details['median']:.1e} / {r.details['p90']:.1e} | tangent turned 45 deg: {wrong[0]:.2f}; "
                   f"rotation mirrored: {wrong[1]:.2f} | {rep['reciprocity'].details['median']:.1e} / "
                   f"{rep['reciprocity'].figure:.1e} ({rep['reciprocity'].details['pairs']} pairs) | "
                   f"{acq.seconds:.1f} |")
        print(out[-1], file=sys.stderr)
    return out


def tangent_rows():
    out = []
    for label, p in ANISOTROPIC:
        for dist in ("MULTI_GGX", "GGX"):
            acq = acquire_tangent(material_spec(principled=dict(p, distribution=dist)), name=label)
            rep = check_acquisition(acq)
            r, e = rep["reciprocity"], rep["energy"]
            alb = acq.albedo.mean(1)
            ring = (np.degrees(acq.albedo_theta) > 55) & (np.degrees(acq.albedo_theta) < 65)
            verdict = "PASS" if r.passed else "UNRESOLVED" if r.unresolved else "FAIL"
            out.append(f"| {label} | {dist} | {r.details.get('median', math.nan):.3f} / {r.figure:.3f} "
                       f"({r.details.get('pairs', 0)} pairs, {r.details.get('resolved_share', 0):.0%}) | {verdict} | "
                       f"{alb.min():.3f} - {e.figure:.3f} (at {e.worst['theta_deg']:.0f} deg, phi "
                       f"{e.worst['phi_deg']:.0f} deg, stderr {e.worst['stderr']:.1g}) | "
                       f"{alb[ring].min():.3f} - {alb[ring].max():.3f} | {'PASS' if e.passed else 'FAIL'} | "
                       f"{acq.seconds:.1f} |")
            print(out[-1], file=sys.stderr)
    return out


def tangent_main():
    print("| material | closed form | median / 90th pct of abs(f - closed form) / closed form | wrong frames "
          "(median) | reciprocity median / 95th pct | seconds |")
    print("|---|---|---|---|---|---|")
    print("\n".join(tangent_validation_rows()))
    print()
    print("| Principled BSDF | distribution | reciprocity median / 95th pct | verdict | furnace albedo min - max "
          "(over theta_o, phi_o cells) | albedo over phi_o at theta_o 55-65 deg | energy | seconds |")
    print("|---|---|---|---|---|---|---|---|")
    print("\n".join(tangent_rows()))


if __name__ == "__main__" and sys.argv[1:] == ["tangent"]:
    t0 = time.perf_counter()
    tangent_main()
    print(f"\n(total {time.perf_counter() - t0:.0f} s)")
elif __name__ == "__main__":
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
