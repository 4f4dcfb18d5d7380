"""Write ``gltf-pbr`` materials as a MaterialX document: an ``open_pbr_surface`` and a ``gltf_pbr``
per material, each in its own ``surfacematerial`` (``docs/materialx.md``).

References
----------
* Academy Software Foundation, *OpenPBR Surface specification* 1.1 (``specular_weight`` scales the
  dielectric ``F0``; ``specular_color`` tints the dielectric reflection and is the metal's F82 edge
  tint; ``specular_roughness_anisotropy``: ``alpha_t = r^2 sqrt(2 / (1 + (1 - a)^2))``,
  ``alpha_b = (1 - a) alpha_t``), as MaterialX 1.39 implements it
  (``libraries/bxdf/open_pbr_surface.mtlx``, ``ND_open_pbr_anisotropy``).
* MaterialX 1.39, ``libraries/bxdf/gltf_pbr.mtlx`` (``ND_gltf_pbr_surfaceshader``: the glTF factors
  and the extensions specular, ior, anisotropy, transmission, emissive strength as inputs).
* The Khronos glTF 2.0 specification, Appendix B; KHR_materials_specular, _ior, _anisotropy
  (what :mod:`plausible.models.gltf_pbr` computes).

The ``gltf_pbr`` node takes the model's parameters as they are (``ior`` 1.5, so
``min(F0(ior) specular_color, 1) specular`` is the model's ``f0`` exactly).  The ``open_pbr_surface``
is the mapping :func:`open_pbr_inputs` (its docstring says what is exact and what is not):

==========================  ===========================================================================
glTF (``gltf-pbr``)         OpenPBR
==========================  ===========================================================================
base_color, metallic        base_color, base_metalness (base_weight 1, base_diffuse_roughness 0: Lambert)
roughness, anisotropy       specular_roughness, specular_roughness_anisotropy (alpha_t, alpha_b exact)
anisotropy_rotation         geometry_tangent: the world tangent turned about the normal (``rotate3d``)
f0 = min(0.04 sc, 1) s      specular_ior: ``F0(ior) = max min(0.04 sc, 1)``; specular_weight s; color f0/max f0
metal (F = Schlick(base))   specular_weight 1, specular_color 1 (F82 tint 1 is Schlick's curve)
alpha, emissive, glass      geometry_opacity, emission_color/luminance, transmission_weight/color, ior
==========================  ===========================================================================

A texture (``map_Kd``) is an ``image`` node of colour space ``srgb_texture`` (an 8-bit texture holds
sRGB-encoded values, IEC 61966-2-1) times the fitted colour (a ``multiply``: MTL multiplies ``map_Kd``
by ``Kd``, glTF ``baseColorTexture`` by ``baseColorFactor``), connected to ``base_color`` of both.

:func:`check_materialx` is MaterialX's own ``Document.validate()`` with the standard libraries loaded,
and :func:`essl_pixel_shader` MaterialX's own GLSL ES generator (``tests/export/test_materialx_glsl.py``
runs it in the browser against the model).

>>> doc = materialx_document({"gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3}})
>>> check_materialx(doc)
[]
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MATERIALX_VERSION", "OPEN_PBR_INPUTS", "check_materialx", "essl_pixel_shader", "gltf_pbr_inputs",
           "ior_of_f0", "materialx_document", "materialx_text", "open_pbr_anisotropy", "open_pbr_inputs",
           "read_materialx"]

#: The MaterialX version the documents are written for (the ``materialx`` package of the ``dcc`` extra).
MATERIALX_VERSION = "1.39"
#: The largest ``specular_ior`` written (a dielectric ``f0`` of 1 has an infinite one; F0(399) = 0.99).
IOR_MAX = 399.0
#: The OpenPBR inputs :func:`open_pbr_inputs` writes, with their MaterialX types.
OPEN_PBR_INPUTS = {"base_weight": "float", "base_color": "color3", "base_metalness": "float",
                   "base_diffuse_roughness": "float", "specular_weight": "float", "specular_color": "color3",
                   "specular_roughness": "float", "specular_ior": "float",
                   "specular_roughness_anisotropy": "float", "transmission_weight": "float",
                   "transmission_color": "color3", "geometry_opacity": "float", "emission_color": "color3",
                   "emission_luminance": "float"}


def _mx():
    try:
        import MaterialX as mx
    except ImportError:
        raise ValueError("MaterialX output needs the materialx package (pip install 'plausible[dcc]' or "
                         "pip install materialx)") from None
    return mx


def _rgb(v) -> list:
    return [float(x) for x in np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))]


def ior_of_f0(f0):
    """The index of refraction whose normal-incidence reflectance is ``f0``: ``(1 + sqrt f0) / (1 - sqrt f0)``
    (the inverse of ``((ior - 1)/(ior + 1))^2``), at most :data:`IOR_MAX`; 1 for ``f0 = 0``."""
    s = math.sqrt(min(max(float(f0), 0.0), 1.0))
    return min((1.0 + s) / (1.0 - s), IOR_MAX) if s < 1.0 else IOR_MAX


def open_pbr_anisotropy(roughness: float, strength: float) -> tuple[float, float]:
    """``(specular_roughness, specular_roughness_anisotropy)`` of OpenPBR with the glTF lobe's
    ``alpha_t = mix(r^2, 1, strength^2)`` and ``alpha_b = r^2`` (KHR_materials_anisotropy):
    ``a = 1 - alpha_b / alpha_t`` and ``r_open^2 = alpha_t / sqrt(2 / (1 + (1 - a)^2))`` (the
    OpenPBR specification's ``alpha_t = r^2 sqrt(2 / (1 + (1 - a)^2))``, ``alpha_b = (1 - a) alpha_t``,
    inverted); exact for every glTF value (``alpha_t <= 1``)."""
    ab = float(roughness) ** 2
    at = ab + (1.0 - ab) * float(strength) ** 2
    if at <= 0.0:
        return 0.0, 0.0
    a = 1.0 - ab / at
    return math.sqrt(at / math.sqrt(2.0 / (1.0 + (1.0 - a) ** 2))), a


def _dielectric_specular(p, ior=None):
    """``(specular_ior, specular_weight, specular_color, exact)``: the glTF dielectric
    ``f0_c = min(F0(ior) sc_c, 1) s``, ``f90 = s`` as OpenPBR's: ``F0(specular_ior) = max_c min(F0(ior) sc_c, 1)``,
    ``specular_weight = s`` (OpenPBR scales ``F0`` by it; 0 reflects nothing and leaves the base whole,
    as glTF), ``specular_color = f0_c / max f0`` (the tint of the reflection).  Exact at normal
    incidence; at grazing OpenPBR's reflection tends to ``specular_color`` where glTF's tends to ``s``
    (``exact``: ``s`` is 0 or 1 and ``sc`` grey)."""
    from ..models.gltf_pbr import DIELECTRIC_F0, ior_f0

    base = DIELECTRIC_F0 if ior is None else float(ior_f0(ior))
    sc = np.asarray(_rgb(p["specular_color"]))
    f0 = np.minimum(base * sc, 1.0)          # before the specular factor
    top = float(f0.max())
    s = float(p["specular"])
    tint = f0 / top if top > 0.0 else np.ones(3)
    return ior_of_f0(top), s, _rgb(tint), bool(np.ptp(f0) <= 1e-12 and s in (0.0, 1.0))


def open_pbr_inputs(params, surface: dict | None = None) -> tuple[dict, list]:
    """``(inputs, warnings)``: the ``open_pbr_surface`` inputs (:data:`OPEN_PBR_INPUTS`; a colour as a list
    of 3) of one ``gltf-pbr`` material (parameters or model) and its ``surface``
    (:func:`plausible.export.gltf.gltf_material`'s: alpha, emissive, transmission, ior), and what OpenPBR
    cannot express of it.  The mapping is the module docstring's; ``anisotropy_rotation`` is not an input
    (:func:`materialx_document` turns the tangent)."""
    from .gltf import _model, _surface

    p = _model("material", params).params
    sf = _surface("material", surface)
    out = {"base_weight": 1.0, "base_color": _rgb(p["base_color"]), "base_metalness": float(p["metallic"]),
           "base_diffuse_roughness": 0.0}
    r, a = open_pbr_anisotropy(p["roughness"], p["anisotropy_strength"])
    out["specular_roughness"] = r
    if a > 0.0:
        out["specular_roughness_anisotropy"] = a
    warn = []
    m = float(p["metallic"])
    ior, weight, tint, exact = _dielectric_specular(p, sf.get("ior"))
    if m >= 1.0:
        out.update(specular_weight=1.0, specular_color=[1.0, 1.0, 1.0], specular_ior=1.5)
    else:
        out.update(specular_weight=weight, specular_color=tint, specular_ior=ior)
        if not exact:
            warn.append(f"OpenPBR: KHR_materials_specular (factor {weight:.3g}, f0 colour "
                        f"{' '.join(f'{x:.3g}' for x in tint)}) is exact at normal incidence only: at grazing "
                        f"glTF's reflection tends to the specular factor, OpenPBR's to specular_color")
        if m > 0.0 and (weight != 1.0 or tint != [1.0, 1.0, 1.0]):
            warn.append(f"OpenPBR: metallic {m:g} mixes a metal that specular_weight {weight:.3g} and "
                        f"specular_color (edge tint) scale too (glTF's metal ignores KHR_materials_specular)")
    _open_pbr_surface(out, sf, p)
    return out, warn


def _open_pbr_surface(out: dict, sf: dict, p) -> None:
    """What a material has beside its BRDF (:data:`plausible.export.gltf.SURFACE`) as OpenPBR inputs."""
    if "alpha" in sf:
        out["geometry_opacity"] = float(sf["alpha"])
    if "emissive" in sf:
        e = _rgb(sf["emissive"])
        top = max(e)
        out["emission_color"] = [x / top for x in e] if top > 0.0 else e
        out["emission_luminance"] = top
    if "transmission" in sf:
        out["transmission_weight"] = float(sf["transmission"])
        out["transmission_color"] = _rgb(p["base_color"])


def gltf_pbr_inputs(params, surface: dict | None = None) -> dict:
    """The ``gltf_pbr`` inputs of one ``gltf-pbr`` material and its ``surface``: the model's parameters
    by their glTF names (``ior`` 1.5 and ``specular_color`` as the model holds it, or the glass's ``ior``),
    ``alpha`` with ``alpha_mode`` 2 (BLEND), ``emissive`` and ``emissive_strength``, ``transmission``."""
    from .gltf import _model, _surface

    p = _model("material", params).params
    sf = _surface("material", surface)
    out = {"base_color": _rgb(p["base_color"]), "metallic": float(p["metallic"]),
           "roughness": float(p["roughness"]), "specular": float(p["specular"]),
           "specular_color": _rgb(p["specular_color"]), "ior": float(sf.get("ior", 1.5))}
    if p["anisotropy_strength"] > 0.0:
        out["anisotropy_strength"] = float(p["anisotropy_strength"])
        out["anisotropy_rotation"] = float(p["anisotropy_rotation"])
    if "alpha" in sf and float(sf["alpha"]) < 1.0:
        out.update(alpha=float(sf["alpha"]), alpha_mode=2)
    if "emissive" in sf:
        e = _rgb(sf["emissive"])
        top = max(e)
        out["emissive"] = [x / top for x in e] if top > 1.0 else e
        if top > 1.0:
            out["emissive_strength"] = top
    if "transmission" in sf:
        out["transmission"] = float(sf["transmission"])
    return out


def _set(node, name, value):
    """Input ``name`` of ``node`` set to ``value`` (a list: ``color3``, an int: ``integer``, else ``float``),
    written with 9 significant digits (MaterialX's Python API writes 6; a float32 needs 9)."""
    if isinstance(value, list):
        node.addInput(name, "color3").setValueString(", ".join(f"{float(x):.9g}" for x in value))
    elif isinstance(value, int) and not isinstance(value, bool):
        node.addInput(name, "integer").setValueString(str(value))
    else:
        node.addInput(name, "float").setValueString(f"{float(value):.9g}")


def _texture(mx, doc, name: str, filename: str, colour: list):
    """An ``image`` node of ``filename`` (colour space ``srgb_texture``) times ``colour``: the ``multiply``."""
    img = doc.addNode("image", f"{name}_map_Kd", "color3")
    f = img.addInput("file", "filename")
    f.setValueString(str(filename).replace("\\", "/"))
    f.setColorSpace("srgb_texture")
    mul = doc.addNode("multiply", f"{name}_base_color", "color3")
    mul.addInput("in1", "color3").setConnectedNode(img)
    _set(mul, "in2", colour)
    return mul


def _tangent(mx, doc, name: str, rotation: float):
    """The world tangent turned by ``rotation`` (radians, counter-clockwise seen from the normal, as
    KHR_materials_anisotropy's ``anisotropyRotation``) about the world normal: a ``rotate3d`` node of
    ``amount = -degrees(rotation)``.  MaterialX's ``rotate3d`` turns clockwise seen from its axis
    (``mx_rotate_vector3``: ``v c + (v x axis) s + ...``, the row-vector form of Rodrigues' formula),
    so a counter-clockwise turn is a negative amount, as MaterialX's own ``gltf_pbr`` writes it
    (``libraries/bxdf/gltf_pbr.mtlx``: ``rad_2_deg`` multiplies by -57.29578); measured in the
    browser (``tests/export/test_materialx_glsl.py``: the axis at ``+r``, not ``-r``)."""
    t = doc.addNode("tangent", f"{name}_tangent", "vector3")
    t.setInputValue("space", "world")
    n = doc.addNode("normal", f"{name}_normal", "vector3")
    n.setInputValue("space", "world")
    rot = doc.addNode("rotate3d", f"{name}_rotated_tangent", "vector3")
    rot.addInput("in", "vector3").setConnectedNode(t)
    _set(rot, "amount", -math.degrees(rotation))
    rot.addInput("axis", "vector3").setConnectedNode(n)
    return rot


def _name(text: str) -> str:
    import re

    s = re.sub(r"[^A-Za-z0-9_]", "_", str(text)) or "material"
    return s if not s[0].isdigit() else "m_" + s


def _add_material(mx, doc, name, params, surface, texture):
    """One material's ``open_pbr_surface`` and ``gltf_pbr`` (each with its ``surfacematerial``)."""
    from .gltf import _model

    key = _name(name)
    p = _model(name, params).params
    o_in, warn = open_pbr_inputs(params, surface)
    g_in = gltf_pbr_inputs(params, surface)
    base = _texture(mx, doc, key, texture, _rgb(p["base_color"])) if texture else None
    for node_type, inputs in (("open_pbr_surface", o_in), ("gltf_pbr", g_in)):
        sh = doc.addNode(node_type, f"{key}_{node_type}", "surfaceshader")
        for k, v in inputs.items():
            if k == "base_color" and base is not None:
                sh.addInput("base_color", "color3").setConnectedNode(base)
            else:
                _set(sh, k, v)
        if node_type == "open_pbr_surface" and p["anisotropy_strength"] > 0.0 and p["anisotropy_rotation"] != 0.0:
            sh.addInput("geometry_tangent", "vector3").setConnectedNode(
                _tangent(mx, doc, key, float(p["anisotropy_rotation"])))
        mat = doc.addMaterialNode(f"{key}_{'OpenPBR' if node_type == 'open_pbr_surface' else 'glTF'}", sh)
        mat.setAttribute("uiname", str(name))
    return warn


def materialx_document(materials: dict, *, textures: dict | None = None, surfaces: dict | None = None):
    """A MaterialX document (``MaterialX.Document``) of ``materials`` (name -> ``gltf-pbr`` parameters or
    model): per material ``NAME_open_pbr_surface`` and ``NAME_gltf_pbr`` shaders in the materials
    ``NAME_OpenPBR`` and ``NAME_glTF`` (NAME with characters MaterialX names cannot hold as ``_``;
    ``uiname`` the name as given).  ``textures``: ``{material: file}`` of the base colour texture;
    ``surfaces``: ``{material: surface}`` (:func:`open_pbr_inputs`).  ValueError naming the material and
    parameter for bad values, or naming the missing package."""
    mx = _mx()
    if not isinstance(materials, dict) or not materials:
        raise ValueError(f"materials must be a non-empty dict of name -> gltf-pbr parameters, "
                         f"got {type(materials).__name__}")
    textures, surfaces = textures or {}, surfaces or {}
    keys = [_name(n) for n in materials]
    if len(set(keys)) < len(keys):
        raise ValueError(f"materials: names {', '.join(map(repr, materials))} collide as MaterialX names "
                         f"({', '.join(keys)})")
    doc = mx.createDocument()
    doc.setColorSpace("lin_rec709")
    for name, params in materials.items():
        _add_material(mx, doc, name, params, surfaces.get(name), textures.get(name))
    return doc


def materialx_text(materials: dict, **kw) -> str:
    """The ``.mtlx`` text of :func:`materialx_document`."""
    mx = _mx()
    return mx.writeToXmlString(materialx_document(materials, **kw))


_LIBRARY = None


def _library():
    """MaterialX's standard data libraries (stdlib, pbrlib, bxdf), loaded once."""
    global _LIBRARY
    if _LIBRARY is None:
        mx = _mx()
        lib = mx.createDocument()
        mx.loadLibraries(mx.getDefaultDataLibraryFolders(), mx.getDefaultDataSearchPath(), lib)
        _LIBRARY = lib
    return _LIBRARY


def read_materialx(text: str):
    """A ``.mtlx`` text as a document with MaterialX's standard libraries imported; ValueError where
    MaterialX cannot read it."""
    mx = _mx()
    doc = mx.createDocument()
    try:
        mx.readFromXmlString(doc, text)
    except mx.Exception as e:       # a parse error
        raise ValueError(f"not a MaterialX document: {e}") from None
    doc.setDataLibrary(_library())
    return doc


def check_materialx(doc_or_text) -> list[str]:
    """The problems MaterialX's own ``Document.validate()`` finds in a document (or ``.mtlx`` text), with
    the standard libraries loaded (so every node is checked against its node definition), and a
    material without a surface shader; an empty list: valid."""
    doc = read_materialx(doc_or_text if isinstance(doc_or_text, str) else _mx().writeToXmlString(doc_or_text))
    ok, message = doc.validate()
    problems = [] if ok else [line for line in message.splitlines() if line.strip()]
    mx = _mx()
    for mat in doc.getMaterialNodes():
        if not mx.getShaderNodes(mat):
            problems.append(f"material {mat.getName()!r} has no surface shader")
    return problems


def essl_pixel_shader(doc_or_text, material: str, lights: int = 1) -> tuple[str, dict]:
    """``(source, uniforms)``: the GLSL ES 3.00 pixel shader MaterialX's own generator
    (``EsslShaderGenerator``) writes for ``material`` of a document -- no environment light
    (``SPECULAR_ENVIRONMENT_NONE``), up to ``lights`` directional lights (``ND_directional_light``, light
    type 1, the uniforms ``u_lightData``), image files decoded from their colour space by MaterialX's
    ``DefaultColorManagementSystem`` (``srgb_texture`` -> ``lin_rec709``) -- and its public uniforms'
    values (name -> number or list; an image's ``file`` as its file name)."""
    mx = _mx()
    import MaterialX.PyMaterialXGenGlsl as mx_glsl
    import MaterialX.PyMaterialXGenShader as mx_gen

    doc = read_materialx(doc_or_text if isinstance(doc_or_text, str) else mx.writeToXmlString(doc_or_text))
    node = doc.getChild(material)
    if node is None:
        raise ValueError(f"material {material!r} is not in the document "
                         f"({', '.join(m.getName() for m in doc.getMaterialNodes())})")
    gen = mx_glsl.EsslShaderGenerator.create()
    ctx = mx_gen.GenContext(gen)
    ctx.registerSourceCodeSearchPath(mx.getDefaultDataSearchPath())
    opts = ctx.getOptions()
    opts.hwSpecularEnvironmentMethod = mx_gen.SPECULAR_ENVIRONMENT_NONE
    opts.hwMaxActiveLightSources = int(lights)
    opts.hwShadowMap = False
    # the colour spaces of image files (srgb_texture) decoded to the document's (lin_rec709), as
    # MaterialX's viewer does: without a colour management system the generator ignores them
    cms = mx_gen.DefaultColorManagementSystem.create(gen.getTarget())
    cms.loadLibrary(_library())
    gen.setColorManagementSystem(cms)
    mx_gen.HwShaderGenerator.bindLightShader(_library().getNodeDef("ND_directional_light"), 1, ctx)
    shader = gen.generate(material, node, ctx)
    stage = shader.getStage(mx_gen.PIXEL_STAGE)
    block = stage.getUniformBlock(mx_gen.HW_PUBLIC_UNIFORMS)
    uniforms = {}
    for i in range(block.size()):
        v = block[i]
        if v.getValue() is not None:
            data = v.getValue().getData()
            uniforms[v.getVariable()] = list(data) if hasattr(data, "__len__") and not isinstance(data, str) else data
    return shader.getSourceCode(mx_gen.PIXEL_STAGE), uniforms
