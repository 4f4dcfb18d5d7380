"""Cycles beside Mitsuba in compare_looks' scene (docs/blender.md, "The comparison" and "The mapping").

    PYTHONPATH=src python scripts/blender_looks.py floor      # Diffuse vs diffuse: the comparison's floor
    PYTHONPATH=src python scripts/blender_looks.py mapping    # gltf-pbr vs its Principled BSDF, per variant
    PYTHONPATH=src python scripts/blender_looks.py table [source|gltf|principled] [ct|other]
        # convert --to blender, scored (other: Ward and Ashikhmin-Shirley fits, through the glTF fit)
    PYTHONPATH=src python scripts/blender_looks.py mtlx       # convert --to materialx, MaterialX's validate()

Prints a Markdown table per part (FLIP, per view, highlight ratios, seconds)."""

from __future__ import annotations

import sys
import time

from plausible import registry
from plausible.blender import material_spec
from plausible.blender.looks import compare_cycles
from plausible.blender.principled import blender_material, principled_inputs, write_blender

GLTF = {
    "metal, rough (0.6)": dict(base_color=[0.9, 0.9, 0.9], metallic=1.0, roughness=0.6),
    "gold metal (0.35)": dict(base_color=[1.0, 0.78, 0.34], metallic=1.0, roughness=0.35),
    "red dielectric (0.35)": dict(base_color=[0.5, 0.1, 0.1], metallic=0.0, roughness=0.35),
    "red dielectric (0.7)": dict(base_color=[0.5, 0.1, 0.1], metallic=0.0, roughness=0.7),
    "white dielectric (0.2)": dict(base_color=[0.8, 0.8, 0.8], metallic=0.0, roughness=0.2),
}


def variants(params, tmp):
    """The worker's material spec of ``params`` under each candidate mapping."""
    base = principled_inputs(params)
    yield ("Principled, Multiscatter GGX (the node's default)",
           material_spec(principled=dict(base, distribution="MULTI_GGX")))
    yield "Principled, GGX (single scatter)", material_spec(principled=dict(base, distribution="GGX"))
    m = blender_material(params)
    if "gltf_nodes" in m:
        write_blender({"m": m}, tmp / "m.py")
        yield "glTF's formula as nodes (Metallic BSDF F82 + Diffuse x (1 - F0))", {"script": str(tmp / "m.py")}


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


def mapping(spp="64"):
    import tempfile
    from pathlib import Path

    tmp = Path(tempfile.mkdtemp(prefix="c46-map-"))
    print(f"{spp} spp\n")
    print("| gltf-pbr | Principled | FLIP | per view 0/60/120/150 | highlight ratios | seconds |\n"
          "|---|---|---|---|---|---|")
    for name, p in GLTF.items():
        model = registry.make("gltf-pbr", **p)
        for vname, spec in variants(p, tmp):
            t = time.perf_counter()
            lk = compare_cycles(model, spec, spp=int(spp))
            print(row(f"{name} | {vname}", lk, time.perf_counter() - t), flush=True)


MTL = {"wood": "newmtl wood\nKd 0.6 0.4 0.2\nKs 0 0 0\nillum 1\n",
       "red_plastic": "newmtl red_plastic\nKd 0.5 0.1 0.1\nKs 0.04 0.04 0.04\nNs 200\nillum 2\n"}
PUBLISHED = ("gold-metallic-paint@ngan2005/cook-torrance", "red-plastic@ngan2005/cook-torrance",
             "alum-bronze@ngan2005/cook-torrance")
#: Sources no node tree writes as its own lobes: they go through the glTF fit (``table source other``).
OTHER = tuple(f"{m}@ngan2005/{f}" for f in ("ward", "ashikhmin-shirley")
              for m in ("gold-metallic-paint", "red-plastic", "alum-bronze"))


def table(nodes="gltf", which="ct"):
    import tempfile
    from pathlib import Path

    from plausible.blender.convert import convert_to_blender

    print("| source | written | albedo diff. source / fit | FLIP source / fit | highlight vs source (0/60/120/150) "
          "| FLIP glTF fit vs source (Mitsuba) | seconds |\n|---|---|---|---|---|---|---|")
    tmp = Path(tempfile.mkdtemp(prefix="c46-"))
    for label, src in (_sources(tmp) if which == "ct" else [(p, f"material:{p}") for p in OTHER]):
        t = time.perf_counter()
        bc = convert_to_blender(src, tmp / "out.blend", nodes=nodes)
        v = bc.verified[0]
        item = bc.conversion.items[0]
        lk = item.looks.flip if getattr(item, "looks", None) is not None else None
        if lk is None:
            from plausible.mitsuba.looks import compare_looks
            from plausible.conversion import read_sources
            lk = compare_looks(read_sources(src)[0].model, item.result, spp=64).flip
        p = item.result.params
        glTF = f"glTF fit: base ({', '.join(f'{c:.2f}' for c in p['base_color'])}), metallic {p['metallic']:.2f}, " \
            f"roughness {p['roughness']:.2f}"
        what = "source's lobes" if "ct_nodes" in v.inputs else ("glTF nodes, " if "gltf_nodes" in v.inputs
                                                                 else "Principled, ") + glTF
        rat = " / ".join(f"{r:.2f}" for r in v.highlight_ratios)
        fa = "-" if v.fit_albedo_difference is None else f"{v.fit_albedo_difference:.3f}"
        ff = "-" if v.fit_flip is None else f"{v.fit_flip:.3f}"
        print(f"| {label} | {what} | {v.albedo_difference:.3f} / {fa} | {v.flip:.3f} / {ff} | {rat} | {lk:.3f} | "
              f"{time.perf_counter() - t:.0f} |", flush=True)


def _sources(tmp):
    out = []
    for name, text in MTL.items():
        (tmp / f"{name}.mtl").write_text(text)
        out.append((f"MTL {name}", str(tmp / f"{name}.mtl")))
    return out + [(p, f"material:{p}") for p in PUBLISHED]


def mtlx():
    """The same sources through ``plausible convert --to materialx``, each document read back from its file
    and validated by MaterialX (``Document.validate()`` with the standard libraries)."""
    import json
    import tempfile
    from pathlib import Path

    from click.testing import CliRunner

    from plausible.cli import main
    from plausible.export.materialx import check_materialx, read_materialx

    tmp = Path(tempfile.mkdtemp(prefix="c46-mtlx-"))
    print("| source | exit | materials (shaders) | validate() problems |\n|---|---|---|---|")
    for label, src in _sources(tmp):
        out = tmp / "out.mtlx"
        r = CliRunner().invoke(main, ["convert", src, "--to", "materialx", "--out", str(out), "--json"])
        text = out.read_text()
        doc = read_materialx(text)
        shaders = sorted({n.getCategory() for m in doc.getMaterialNodes() for n in
                          __import__("MaterialX").getShaderNodes(m)})
        problems = check_materialx(text)
        print(f"| {label} | {r.exit_code} | {len(doc.getMaterialNodes())} ({', '.join(shaders)}) | "
              f"{len(problems)}{': ' + '; '.join(problems) if problems else ''} |", flush=True)
        json.loads(r.stdout)


if __name__ == "__main__":
    what = sys.argv[1] if len(sys.argv) > 1 else "floor"
    {"floor": floor, "mapping": mapping, "table": table, "mtlx": mtlx}[what](*sys.argv[2:])
