"""A plausible conversion as Blender's Principled BSDF: the inputs, a node script, a ``.blend``.

The fit is the glTF one (:func:`plausible.conversion.convert` with ``to="gltf"``: the
``gltf-pbr`` model's base colour, metallic, roughness, specular, specular colour and
anisotropy fitted to the source).  Blender's Principled BSDF (Blender 4.0 and later,
manual "Principled BSDF"; Cycles ``principled_bsdf``) is the same microfacet
metallic-roughness model, so the fitted values map onto its inputs:

========================  ===========================================================
Principled input          from ``gltf-pbr``
========================  ===========================================================
Base Color                ``base_color`` (linear RGB)
Metallic                  ``metallic``
Roughness                 ``roughness`` (both: GGX ``alpha = roughness^2``); with
                          anisotropy, ``sqrt`` of the geometric mean of glTF's two
                          alphas (below)
IOR                       1.5 (glTF's dielectric: F0 = 0.04)
Specular IOR Level        ``0.5 specular`` (Blender: 0.5 leaves F0 as the IOR gives it,
                          0 removes the reflection, 1 doubles F0; glTF's
                          ``specularFactor`` scales F0 the same way)
Specular Tint             ``specular_color`` (tints the dielectric F0, as glTF's
                          ``specularColorFactor``; on a metal Blender also tints the
                          edge, glTF does not: equal for the white tint the fit gives
                          metals)
Anisotropic               ``(1 - 1/rho) / 0.9`` with ``rho = alpha_t / alpha_b`` of glTF
                          (``alpha_t = mix(alpha, 1, s^2)``, ``alpha_b = alpha``):
                          Cycles' ``alpha_x = alpha / sqrt(1 - 0.9 A)``,
                          ``alpha_y = alpha sqrt(1 - 0.9 A)``, so the ratio is kept up to
                          10 (A = 1) and the geometric mean through Roughness
Anisotropic Rotation      ``anisotropy_rotation / (2 pi)`` (Blender: a fraction of a turn)
========================  ===========================================================

Distribution: **GGX** (single scatter), as ``gltf-pbr``; a new node's default, Multiscatter
GGX, adds the energy of multiple scattering (a rough white metal 1.2x brighter, measured in
compare_looks' scene: FLIP 0.21 against 0.036 for GGX, docs/blender.md).

A material with a dielectric part (``metallic < 1``, ``specular > 0``, isotropic) is written,
by default (``nodes="gltf"``), as **a node tree of glTF's own formula** instead of one
Principled BSDF, because the Principled dielectric's Fresnel is the exact one of its IOR
(at 60 degrees 1.25x Schlick's with F0 = 0.04: the highlight of the 120-degree view 1.25x
the source's) and its diffuse is weighted by the specular layer's albedo.  The tree:

* a **Metallic BSDF** (GGX, Fresnel "F82" with a white edge tint, i.e. Schlick's
  ``F0 + (1 - F0)(1 - cos)^5``) of Base Color ``F0 / specular`` (``F0 = min(0.04
  specular_color, 1) specular``), scaled by ``specular`` (a Mix Shader against nothing):
  glTF's ``F_d specular_brdf`` with ``f90 = specular``;
* plus a **Diffuse BSDF** of colour ``base_color (1 - max(F0))``: glTF's ``(1 - max F_d)``
  at ``V.H = 1`` (Cycles' nodes cannot see ``V.H``; a Schlick weight of ``N.V`` instead
  scored worse: FLIP 0.070-0.078 against 0.039-0.055);
* mixed (Mix Shader, factor ``metallic``) with the metal: a Metallic BSDF (GGX, F82, white
  edge tint) of Base Color ``base_color``.

``nodes="principled"`` writes one Principled BSDF (GGX) instead (what glTF exporters read);
its dielectric scores FLIP 0.06-0.09 with a highlight 1.13-1.25x at 120 degrees.

A source that is itself **a Lambertian plus Cook-Torrance lobes** (Beckmann, Schlick's
Fresnel: Ngan et al.'s published fits; or Blinn's distribution with ``F = rs``: an MTL
``Kd``/``Ks``/``Ns``) is written, where ``nodes="source"`` (the default of
:func:`plausible.blender.convert.convert_to_blender`), **as its own lobes**, without the glTF
fit (:func:`cook_torrance_nodes`): a Diffuse BSDF of ``rd`` plus, per lobe of weight ``w``
(RGB), Schlick's ``w F = w rs + w (1 - rs)(1 - cos)^5`` as two closures of the same
Beckmann lobe (Roughness ``sqrt(m)``: Cycles' ``alpha = roughness^2`` is Beckmann's RMS
slope ``m``): a Glossy BSDF (no Fresnel) of colour ``w rs``, exact per channel, plus a
Metallic BSDF of F0 = 0 (F82, white edge tint: ``(1 - cos)^5``) scaled by the luminance of
``w (1 - rs)`` -- white where the source's grazing rise is coloured (one closure's Fresnel
cannot reach a coloured value below 1 at grazing: F82's is 1 there).  Measured on
gold-metallic-paint: FLIP 0.063 this way, against 0.132 for one Metallic BSDF of F0
``w rs / max(w)`` with its F82 tint matched at 82 degrees and 0.140 with a white tint.
What else differs: Cycles' shadowing is Smith's, the source's the V-groove of Cook and
Torrance.  A lobe with ``F = rs`` (no Fresnel: an MTL's ``Ks``) is the Glossy BSDF alone;
Blinn's distribution ``(n.h)^n`` is written as Beckmann's of the same slope ``m``
(``n = 2/m^2 - 2``, Walter et al. 2007: they agree near the peak).

Textures: an MTL ``map_Kd`` becomes an Image Texture node (colour space sRGB) times
the fitted base colour (a Multiply mix, as MTL and glTF multiply), ``bump`` /
``map_bump`` a Bump node fed by an Image Texture in Non-Color, ``norm`` /
``map_norm`` a Normal Map node (Non-Color); their file names are written relative to
the output file.  What a Principled BSDF cannot express is left out with a note (the
same as the glTF output's).
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from . import runner

__all__ = ["NODES", "OUTPUTS", "blender_material", "cook_torrance_nodes", "principled_inputs", "node_script",
           "write_blender"]

OUTPUTS = (".blend", ".py")
#: How a material with a dielectric part is written (module docstring): glTF's formula as nodes, or one
#: Principled BSDF.
NODES = ("source", "gltf", "principled")
#: MTL texture statements the node script connects, and how: (socket, colour space).
TEXTURE_NODES = {"map_Kd": ("Base Color", "sRGB"), "bump": ("Bump", "Non-Color"), "map_bump": ("Bump", "Non-Color"),
                 "norm": ("Normal Map", "Non-Color"), "map_norm": ("Normal Map", "Non-Color")}


def _rgb(v) -> list:
    return [float(x) for x in np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))]


def principled_inputs(params: dict) -> dict:
    """Principled BSDF inputs (Blender's names) of ``gltf-pbr`` parameters (module docstring)."""
    r = float(params.get("roughness", 1.0))
    s = float(params.get("anisotropy_strength", 0.0))
    out = {"Base Color": _rgb(params.get("base_color", 1.0)), "Metallic": float(params.get("metallic", 1.0)),
           "Roughness": r, "IOR": 1.5, "Specular IOR Level": 0.5 * float(params.get("specular", 1.0)),
           "Specular Tint": _rgb(params.get("specular_color", 1.0)), "distribution": "GGX"}
    if s > 0.0:
        alpha = max(r * r, 1e-8)
        rho = (alpha + (1.0 - alpha) * s * s) / alpha          # glTF: alpha_t = mix(alpha, 1, s^2)
        out["Anisotropic"] = float(min(1.0, (1.0 - 1.0 / rho) / 0.9))
        out["Roughness"] = float(math.sqrt(alpha * math.sqrt(rho)))
        out["Anisotropic Rotation"] = float(params.get("anisotropy_rotation", 0.0)) / (2 * math.pi) % 1.0
    return out


def blender_material(params: dict, nodes: str = "gltf", source=None) -> dict:
    """What the node script builds for ``gltf-pbr`` parameters: the Principled inputs
    (:func:`principled_inputs`) and, where ``nodes`` is ``"gltf"`` and the material has an
    isotropic dielectric part, ``"gltf_nodes"``: the values of glTF's formula as a node tree
    (module docstring), which the script builds in place of the Principled BSDF.  With
    ``nodes="source"``, a ``source`` model that is a Lambertian plus Cook-Torrance lobes is written as
    its own lobes (:func:`cook_torrance_nodes`), any other as ``"gltf"``.
    ValueError naming ``nodes`` for another choice."""
    if nodes not in NODES:
        raise ValueError(f"nodes: one of {', '.join(NODES)}, got {nodes!r}")
    if nodes == "source":
        direct = cook_torrance_nodes(source) if source is not None else None
        if direct is not None:
            return direct
        nodes = "gltf"
    out = principled_inputs(params)
    metallic, spec = float(params.get("metallic", 1.0)), float(params.get("specular", 1.0))
    if nodes == "gltf" and metallic < 1.0 and spec > 0.0 and float(params.get("anisotropy_strength", 0.0)) == 0.0:
        from ..models.gltf_pbr import dielectric_f0

        f0 = dielectric_f0(np, spec, np.asarray(_rgb(params.get("specular_color", 1.0))))
        base = np.asarray(_rgb(params.get("base_color", 1.0)))
        out["gltf_nodes"] = {"base_color": base.tolist(), "metallic": metallic,
                             "roughness": float(params.get("roughness", 1.0)), "specular": spec,
                             "f0_over_specular": (f0 / spec).tolist(),
                             "diffuse": (base * (1.0 - float(f0.max()))).tolist()}
    return out


def cook_torrance_nodes(model) -> dict | None:
    """``{"Base Color": rd, "ct_nodes": {"rd": rd, "lobes": [...]}}``: a Lambertian plus Cook-Torrance lobes
    (a :class:`plausible.Sum`, or one of them alone; Fresnel Schlick's or none, distribution Beckmann's
    or Blinn's) as Cycles nodes (module docstring); None for a model of another form (it takes the
    glTF fit)."""
    from ..models.cook_torrance import CookTorrance
    from ..models.lambert import Lambertian
    from ..models.sum import Sum
    from ..spectra import luminance

    parts = list(zip(model.parts, model.scales)) if isinstance(model, Sum) else [(model, None)]
    rd, lobes = np.zeros(3), []
    for part, scale in parts:
        w = np.broadcast_to(np.asarray(1.0 if scale is None else scale, dtype=float), (3,))
        if isinstance(part, Lambertian):
            rd = rd + w * np.broadcast_to(np.asarray(part.params["rd"], dtype=float), (3,))
            continue
        p = getattr(part, "params", {})
        if not (isinstance(part, CookTorrance) and p.get("distribution") in ("beckmann", "blinn")
                and p.get("fresnel") in ("schlick", "none") and np.all(w >= 0)):
            return None
        rs = np.broadcast_to(np.asarray(p["rs"], dtype=float), (3,))
        lobe = {"roughness": float(min(math.sqrt(float(p["m"])), 1.0))}
        # w F = w rs + w (1 - rs)(1 - cos)^5: a Glossy BSDF (no Fresnel) of colour w rs, exact per channel,
        # plus (Schlick only) the rise (1 - cos)^5 -- a Metallic BSDF of F0 = 0 (F82, white tint) -- scaled
        # by the luminance of w (1 - rs): white, where the source's is coloured
        lobe.update(colour=(w * rs).tolist(),
                    grazing=float(luminance(w * (1.0 - rs))) if p["fresnel"] == "schlick" else 0.0)
        lobes.append(lobe)
    if not lobes:
        return None
    rd = np.clip(rd, 0.0, None).tolist()
    return {"Base Color": rd, "ct_nodes": {"rd": rd, "lobes": lobes}}     # Base Color: what a map_Kd multiplies


def node_script(materials: dict, textures: dict | None = None) -> str:
    """A Python script for Blender that builds each material of ``materials``
    (``{name: Principled inputs}``) with its ``textures`` (``{name: {MTL statement: file}}``,
    :data:`TEXTURE_NODES`): ``build(bpy)`` returns the first material, ``build_all(bpy)``
    all of them; run as a script (``blender --python FILE.py``) it builds them all."""
    return _SCRIPT.replace("MATERIALS = {}", "MATERIALS = " + json.dumps(materials, indent=1)) \
        .replace("TEXTURES = {}", "TEXTURES = " + json.dumps(textures or {}, indent=1)) \
        .replace("TEXTURE_NODES = {}", "TEXTURE_NODES = " + json.dumps(TEXTURE_NODES))


def write_blender(materials: dict, path, textures: dict | None = None) -> Path:
    """Write ``materials`` (``{name: Principled inputs}``) to ``path``: ``.py`` (the node
    script, :func:`node_script`) or ``.blend`` (the script run in Blender, the file saved
    with the materials and no objects).  ValueError naming ``out`` for another suffix."""
    from ..text import write_atomic

    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in OUTPUTS:
        raise ValueError(f"out: a Blender output ends in .blend or .py, got {str(path)!r}")
    text = node_script(materials, textures)
    if suffix == ".py":
        write_atomic(path, text)
        return path
    script = path.with_name(path.name + ".tmp.py")
    script.write_text(text)
    try:
        runner.run_job({"script": str(script), "all": True}, [], resolution=16, spp=1, save_blend=path.resolve())
    finally:
        script.unlink(missing_ok=True)
    return path


_SCRIPT = '''"""Principled BSDF materials written by plausible (convert --to blender).

Run in Blender: ``blender --python THIS.py`` (or exec it in the Text Editor), or
import it and call ``build_all(bpy)``.  The texture files are relative to this file.
"""
import os

MATERIALS = {}
TEXTURES = {}
TEXTURE_NODES = {}
HERE = os.path.dirname(os.path.abspath(__file__)) if "__file__" in globals() else os.getcwd()


def _image(nodes, name, colour_space):
    tex = nodes.new("ShaderNodeTexImage")
    path = name if os.path.isabs(name) else os.path.join(HERE, name)
    import bpy
    tex.image = bpy.data.images.load(path, check_existing=True)
    tex.image.colorspace_settings.name = colour_space
    return tex


def _material(bpy, name, inputs, textures):
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nodes, links = mat.node_tree.nodes, mat.node_tree.links
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL") if any(
        n.type == "OUTPUT_MATERIAL" for n in nodes) else nodes.new("ShaderNodeOutputMaterial")
    for n in [n for n in nodes if n.name != out.name]:
        nodes.remove(n)
    bsdf = nodes.new("ShaderNodeBsdfPrincipled")
    for key, value in inputs.items():
        if key in ("gltf_nodes", "ct_nodes"):
            continue
        if key.islower():             # a property of the node (distribution), not an input
            setattr(bsdf, key, value)
        else:
            bsdf.inputs[key].default_value = list(value) + [1.0] if isinstance(value, list) else value
    if "Anisotropic" in inputs:       # the UV map's tangent, as glTF's anisotropy direction
        tangent = nodes.new("ShaderNodeTangent")
        tangent.direction_type = "UV_MAP"
        links.new(tangent.outputs["Tangent"], bsdf.inputs["Tangent"])
    for stmt, file in textures.items():
        socket, space = TEXTURE_NODES[stmt]
        tex = _image(nodes, file, space)
        if socket == "Base Color":    # MTL and glTF multiply the map by the colour
            mix = nodes.new("ShaderNodeMix")
            mix.data_type, mix.blend_type = "RGBA", "MULTIPLY"
            mix.inputs["Factor"].default_value = 1.0
            mix.inputs[6].default_value = [1.0, 1.0, 1.0, 1.0]    # white where the map is unlinked
            mix.inputs[7].default_value = list(inputs["Base Color"]) + [1.0]
            links.new(tex.outputs["Color"], mix.inputs[6])
            links.new(mix.outputs[2], bsdf.inputs["Base Color"])
        elif socket == "Bump":
            bump = nodes.new("ShaderNodeBump")
            links.new(tex.outputs["Color"], bump.inputs["Height"])
            links.new(bump.outputs["Normal"], bsdf.inputs["Normal"])
        else:
            nm = nodes.new("ShaderNodeNormalMap")
            links.new(tex.outputs["Color"], nm.inputs["Color"])
            links.new(nm.outputs["Normal"], bsdf.inputs["Normal"])
    shader = bsdf.outputs["BSDF"]
    if "ct_nodes" in inputs:          # the source's own lobes (a Lambertian plus Cook-Torrance lobes)
        shader = _ct_tree(nodes, links, inputs["ct_nodes"], bsdf)
        nodes.remove(bsdf)
    elif "gltf_nodes" in inputs:        # glTF's formula in place of the Principled BSDF (its colour links kept)
        shader = _gltf_tree(nodes, links, inputs["gltf_nodes"], bsdf)
        nodes.remove(bsdf)
    links.new(shader, out.inputs["Surface"])
    mat.use_fake_user = True
    return mat


def _metal(nodes, colour, roughness, distribution="GGX", tint=(1.0, 1.0, 1.0)):
    """A Metallic BSDF: Fresnel F82 of F0 = colour (a white edge tint: Schlick's)."""
    m = nodes.new("ShaderNodeBsdfMetallic")
    m.distribution, m.fresnel_type = distribution, "F82"
    m.inputs["Base Color"].default_value = list(colour) + [1.0]
    m.inputs["Edge Tint"].default_value = list(tint) + [1.0]
    m.inputs["Roughness"].default_value = roughness
    return m


def _ct_tree(nodes, links, g, principled):
    """Diffuse BSDF (rd) + per lobe a Glossy BSDF (w rs) + grazing x Metallic BSDF (F0 = 0), Beckmann;
    what fed the Principled BSDF's Base Color (a map_Kd times rd) feeds the diffuse, its Normal all."""
    total = nodes.new("ShaderNodeBsdfDiffuse")
    total.inputs["Color"].default_value = list(g["rd"]) + [1.0]
    total.inputs["Roughness"].default_value = 0.0
    bsdfs = [total]
    for link in list(principled.inputs["Base Color"].links):
        links.new(link.from_socket, total.inputs["Color"])
    for lobe in g["lobes"]:
        glossy = nodes.new("ShaderNodeBsdfGlossy")   # no Fresnel: the constant part w rs
        glossy.distribution = "BECKMANN"
        glossy.inputs["Color"].default_value = list(lobe["colour"]) + [1.0]
        glossy.inputs["Roughness"].default_value = lobe["roughness"]
        parts = [glossy]
        bsdfs.append(glossy)
        if lobe["grazing"] > 0.0:                    # Schlick's rise (1 - cos)^5: F82 of F0 = 0, white tint
            metal = _metal(nodes, (0.0, 0.0, 0.0), lobe["roughness"], "BECKMANN")
            bsdfs.append(metal)
            scaled = nodes.new("ShaderNodeMixShader")    # grazing x the rise (the first input: nothing)
            scaled.inputs["Fac"].default_value = lobe["grazing"]
            links.new(metal.outputs[0], scaled.inputs[2])
            parts.append(scaled)
        for part in parts:
            add = nodes.new("ShaderNodeAddShader")
            links.new(total.outputs[0], add.inputs[0])
            links.new(part.outputs[0], add.inputs[1])
            total = add
    for link in list(principled.inputs["Normal"].links):
        for node in bsdfs:
            links.new(link.from_socket, node.inputs["Normal"])
    return total.outputs[0]


def _gltf_tree(nodes, links, g, principled):
    """mix(F_d specular + (1 - max F0) diffuse, metal, metallic): glTF's material as nodes; what fed the
    Principled BSDF's Base Color and Normal (a texture, a bump) feeds the diffuse, the metal and the normals."""
    spec = _metal(nodes, g["f0_over_specular"], g["roughness"])
    scaled = nodes.new("ShaderNodeMixShader")        # specular x the Metallic BSDF (its first input: nothing)
    scaled.inputs["Fac"].default_value = g["specular"]
    links.new(spec.outputs[0], scaled.inputs[2])
    diffuse = nodes.new("ShaderNodeBsdfDiffuse")
    diffuse.inputs["Color"].default_value = list(g["diffuse"]) + [1.0]
    diffuse.inputs["Roughness"].default_value = 0.0
    dielectric = nodes.new("ShaderNodeAddShader")
    links.new(scaled.outputs[0], dielectric.inputs[0])
    links.new(diffuse.outputs[0], dielectric.inputs[1])
    metal = _metal(nodes, g["base_color"], g["roughness"])
    mix = nodes.new("ShaderNodeMixShader")
    mix.inputs["Fac"].default_value = g["metallic"]
    links.new(dielectric.outputs[0], mix.inputs[1])
    links.new(metal.outputs[0], mix.inputs[2])
    for link in list(principled.inputs["Base Color"].links):    # a map_Kd: the map times each colour
        tint = nodes.new("ShaderNodeMix")
        tint.data_type, tint.blend_type = "RGBA", "MULTIPLY"
        tint.inputs["Factor"].default_value = 1.0
        tint.inputs[7].default_value = [1.0 - max(g["f0_over_specular"]) * g["specular"]] * 3 + [1.0]
        links.new(link.from_socket, tint.inputs[6])
        links.new(tint.outputs[2], diffuse.inputs["Color"])
        links.new(link.from_socket, metal.inputs["Base Color"])
    for link in list(principled.inputs["Normal"].links):
        for node in (spec, diffuse, metal):
            links.new(link.from_socket, node.inputs["Normal"])
    return mix.outputs[0]


def build_all(bpy):
    return [_material(bpy, name, inputs, TEXTURES.get(name, {})) for name, inputs in MATERIALS.items()]


def build(bpy):
    return build_all(bpy)[0]


if __name__ == "__main__":
    import bpy
    build_all(bpy)
'''
