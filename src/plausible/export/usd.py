"""Write ``gltf-pbr`` materials as USD ``UsdPreviewSurface`` materials (usd-core), ``docs/materialx.md``.

References
----------
* Pixar, *UsdPreviewSurface Specification* (2.5): ``diffuseColor``, ``metallic``, ``roughness`` (the
  perceptual roughness, as glTF's), ``ior`` (the dielectric's ``F0 = ((1 - ior)/(1 + ior))^2`` in the
  metallic workflow), ``useSpecularWorkflow`` with ``specularColor`` (the ``F0`` colour, metallic
  unused), ``opacity``, ``emissiveColor``; ``UsdUVTexture`` (``sourceColorSpace`` ``sRGB``, ``scale``
  multiplying the texel) read through ``UsdPrimvarReader_float2`` of the primvar ``st``.

The mapping (:func:`preview_inputs`): ``base_color`` -> ``diffuseColor``, ``metallic``, ``roughness``;
the dielectric ``f0 = min(0.04 sc, 1) s`` of KHR_materials_specular: grey -> ``ior`` of that ``f0``
(metallic workflow); coloured and ``metallic`` 0 -> the specular workflow with ``specularColor = f0``.
What UsdPreviewSurface cannot express: anisotropy (none), a coloured ``f0`` beside a metallic above 0,
the specular factor's ``f90 = s`` (its Fresnel tends to 1 at grazing), transmission (only ``opacity``).
Those are the warnings of :func:`preview_inputs`.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_usd", "preview_inputs", "read_usd_materials", "usd_text"]


def _usd():
    try:
        from pxr import Sdf, Usd, UsdShade
    except ImportError:
        raise ValueError("USD output needs the usd-core package (pip install 'plausible[dcc]' or "
                         "pip install usd-core)") from None
    return Sdf, Usd, UsdShade


def preview_inputs(params, surface: dict | None = None) -> tuple[dict, list]:
    """``(inputs, warnings)``: the ``UsdPreviewSurface`` inputs of one ``gltf-pbr`` material (parameters
    or model) and its ``surface`` (alpha, emissive, transmission, ior), and what the preview surface
    cannot express (module docstring)."""
    from ..models.gltf_pbr import DIELECTRIC_F0, ior_f0
    from .gltf import _model, _surface
    from .materialx import ior_of_f0

    p = _model("material", params).params
    sf = _surface("material", surface)
    rgb = lambda v: [float(x) for x in np.broadcast_to(np.asarray(v, float), (3,))]   # noqa: E731
    out = {"diffuseColor": rgb(p["base_color"]), "metallic": float(p["metallic"]),
           "roughness": float(p["roughness"]), "useSpecularWorkflow": 0}
    warn = []
    base = DIELECTRIC_F0 if "ior" not in sf else float(ior_f0(sf["ior"]))
    f0 = np.minimum(base * np.asarray(rgb(p["specular_color"])), 1.0) * float(p["specular"])
    if np.ptp(f0) <= 1e-12 or p["metallic"] > 0.0:
        out["ior"] = ior_of_f0(float(f0.max()))
        if np.ptp(f0) > 1e-12:
            warn.append(f"UsdPreviewSurface: the coloured dielectric f0 {' '.join(f'{x:.3g}' for x in f0)} beside "
                        f"metallic {p['metallic']:g} is written as the ior of its largest channel")
    else:
        out.update(useSpecularWorkflow=1, specularColor=rgb(f0))
    if p["specular"] not in (0.0, 1.0):
        warn.append(f"UsdPreviewSurface: the specular factor {p['specular']:.3g} scales f0 only (its Fresnel "
                    f"tends to 1 at grazing, glTF's to the factor)")
    if p["anisotropy_strength"] > 0.0:
        warn.append(f"UsdPreviewSurface has no anisotropy: anisotropy_strength {p['anisotropy_strength']:.3g} "
                    f"dropped (the roughness is the glTF roughness, the lobe's narrower axis)")
    if "alpha" in sf:
        out["opacity"] = float(sf["alpha"])
    if "emissive" in sf:
        out["emissiveColor"] = rgb(sf["emissive"])
    if "transmission" in sf:
        warn.append("UsdPreviewSurface has no transmission: the glass is written with opacity "
                    f"{1.0 - float(sf['transmission']):g} and its ior")
        out["opacity"] = 1.0 - float(sf["transmission"])
    return out, warn


def _prim_name(text: str) -> str:
    import re

    s = re.sub(r"[^A-Za-z0-9_]", "_", str(text)) or "material"
    return s if not s[0].isdigit() else "m_" + s


def _texture(Sdf, UsdShade, stage, path, shader, filename, colour):
    """``diffuseColor`` from a ``UsdUVTexture`` of ``filename`` (sRGB), ``scale`` the fitted colour."""
    st = UsdShade.Shader.Define(stage, f"{path}/st")
    st.CreateIdAttr("UsdPrimvarReader_float2")
    st.CreateInput("varname", Sdf.ValueTypeNames.Token).Set("st")
    tex = UsdShade.Shader.Define(stage, f"{path}/map_Kd")
    tex.CreateIdAttr("UsdUVTexture")
    tex.CreateInput("file", Sdf.ValueTypeNames.Asset).Set(str(filename).replace("\\", "/"))
    tex.CreateInput("sourceColorSpace", Sdf.ValueTypeNames.Token).Set("sRGB")
    tex.CreateInput("scale", Sdf.ValueTypeNames.Float4).Set((*colour, 1.0))
    tex.CreateInput("st", Sdf.ValueTypeNames.Float2).ConnectToSource(st.ConnectableAPI(), "result")
    tex.CreateOutput("rgb", Sdf.ValueTypeNames.Float3)
    shader.CreateInput("diffuseColor", Sdf.ValueTypeNames.Color3f).ConnectToSource(tex.ConnectableAPI(), "rgb")


def usd_text(materials: dict, *, textures: dict | None = None, surfaces: dict | None = None) -> str:
    """The ``.usda`` text of ``materials`` (name -> ``gltf-pbr`` parameters or model): a ``/Materials``
    scope with one ``UsdShade.Material`` per material (its prim name the name with characters a prim name
    cannot hold as ``_``), whose surface is a ``UsdPreviewSurface`` of :func:`preview_inputs`;
    ``textures``: ``{material: base colour texture file}``; ``surfaces``: ``{material: surface}``."""
    Sdf, Usd, UsdShade = _usd()
    textures, surfaces = textures or {}, surfaces or {}
    keys = [_prim_name(n) for n in materials]
    if len(set(keys)) < len(keys):
        raise ValueError(f"materials: names {', '.join(map(repr, materials))} collide as USD prim names")
    stage = Usd.Stage.CreateInMemory()
    stage.DefinePrim("/Materials", "Scope")
    types = {"useSpecularWorkflow": Sdf.ValueTypeNames.Int}
    for (name, params), key in zip(materials.items(), keys):
        inputs, _ = preview_inputs(params, surfaces.get(name))
        mat = UsdShade.Material.Define(stage, f"/Materials/{key}")
        mat.GetPrim().SetDocumentation(str(name))        # the name as given
        sh = UsdShade.Shader.Define(stage, f"/Materials/{key}/PreviewSurface")
        sh.CreateIdAttr("UsdPreviewSurface")
        for k, v in inputs.items():
            if k == "diffuseColor" and name in textures:
                _texture(Sdf, UsdShade, stage, f"/Materials/{key}", sh, textures[name], v)
                continue
            t = types.get(k, Sdf.ValueTypeNames.Color3f if isinstance(v, list) else Sdf.ValueTypeNames.Float)
            sh.CreateInput(k, t).Set(tuple(v) if isinstance(v, list) else v)
        mat.CreateSurfaceOutput().ConnectToSource(sh.ConnectableAPI(), "surface")
    return stage.GetRootLayer().ExportToString()


def read_usd_materials(path) -> dict:
    """``{prim name: {input: value}}`` of every ``UsdPreviewSurface`` bound to a material's surface in a
    USD file (colours as lists; a connected input as ``("connected", source prim path)``)."""
    Sdf, Usd, UsdShade = _usd()
    stage = Usd.Stage.Open(str(path))
    if stage is None:
        raise ValueError(f"{path}: not a USD file")
    out = {}
    for prim in stage.Traverse():
        if not prim.IsA(UsdShade.Material):
            continue
        source = UsdShade.Material(prim).GetSurfaceOutput().GetConnectedSources()[0]
        values = {}
        if source:
            sh = UsdShade.Shader(source[0].source.GetPrim())
            values["id"] = str(sh.GetIdAttr().Get())
            for i in sh.GetInputs():
                if i.HasConnectedSource():
                    values[i.GetBaseName()] = ("connected", str(i.GetConnectedSources()[0][0].source.GetPath()))
                else:
                    v = i.Get()
                    values[i.GetBaseName()] = list(v) if hasattr(v, "__len__") else v
        out[prim.GetName()] = values
    return out


#: The UsdPreviewSurface inputs in [0, 1] (Pixar's specification).
UNIT_INPUTS = ("metallic", "roughness", "opacity")


def check_usd(path) -> list[str]:
    """The problems of a USD file of materials: a material whose surface is not a ``UsdPreviewSurface``,
    an input of :data:`UNIT_INPUTS` or a colour channel of ``diffuseColor``/``specularColor`` outside
    [0, 1], an ``ior`` below 1; an empty list: every material is a valid preview surface."""
    problems = []
    for name, v in read_usd_materials(path).items():
        if v.get("id") != "UsdPreviewSurface":
            problems.append(f"material {name!r}: its surface is not a UsdPreviewSurface ({v.get('id')!r})")
            continue
        for k in UNIT_INPUTS + ("diffuseColor", "specularColor"):
            x = v.get(k)
            if x is None or isinstance(x, tuple):
                continue
            if not np.all((np.asarray(x, float) >= 0.0) & (np.asarray(x, float) <= 1.0)):
                problems.append(f"material {name!r}: {k} must be in [0, 1], got {x!r}")
        if isinstance(v.get("ior"), float) and v["ior"] < 1.0:
            problems.append(f"material {name!r}: ior must be at least 1, got {v['ior']!r}")
    return problems
