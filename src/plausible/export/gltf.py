"""Write materials of the ``gltf-pbr`` model as a glTF 2.0 file: one UV sphere per material.

References
----------
* The Khronos 3D Formats Working Group, *glTF 2.0 Specification* (sections
  "Buffers and Buffer Views", "Accessors", "Meshes", "Materials"; embedded buffers as
  ``data:application/octet-stream;base64`` URIs).
* Khronos, *KHR_materials_specular* (``specularFactor``, ``specularColorFactor``),
  *KHR_materials_anisotropy* (``anisotropyStrength``, ``anisotropyRotation``; a mesh using
  it MUST have ``NORMAL`` and ``TANGENT`` attributes), *KHR_materials_ior* (``ior``,
  default 1.5; ``f0 = ((ior - 1)/(ior + 1))^2``; 0 means an infinite ior).
* Khronos, *KHR_materials_transmission* (``transmissionFactor``), *KHR_materials_ior* (``ior``),
  *KHR_materials_emissive_strength* (``emissiveStrength``); the core material's ``alphaMode``
  and ``emissiveFactor``: what a material has beside its BRDF (``surface`` of
  :func:`gltf_material`: glass, opacity, emission of an MTL file).

``KHR_materials_ior``: a material given with an ``"ior"`` entry (besides the model's
parameters) is written with the extension and its ``specularColorFactor`` as given; the model
it stands for has ``specular_color = min(F0(ior) specular_color, 1) / 0.04``
(:func:`plausible.models.gltf_pbr.specular_color_of_ior`), the same dielectric ``f0``
exactly.  :func:`read_gltf_materials` reads a file's materials back into models the same way.

The parameters of :mod:`plausible.models.gltf_pbr` are the glTF factors themselves, so a
material is written as it is, with no conversion: ``base_color`` -> ``baseColorFactor``
(alpha 1), ``metallic`` -> ``metallicFactor``, ``roughness`` -> ``roughnessFactor``, and the
extensions only where their values differ from the defaults (an extension at its default
changes nothing; ``extensionsUsed`` lists what the file uses, none is required, so a viewer
without them still shows the base material).

The file: one buffer (positions, normals, tangents of one sphere of radius 1, and its
triangle indices), shared by every mesh; one mesh and one node per material, named after
it, in rows of ``ceil(sqrt(N))`` spheres 2.5 apart along ``+x`` and ``-y``.  A mesh
has ``TANGENT`` where its material is anisotropic (the extension's tangent ``t`` is the
direction of growing azimuth about ``+y``), and ``TEXCOORD_0`` (azimuth and polar angle, 0-1)
where it has a ``baseColorTexture``: an image referenced by a relative URI, not embedded
(``textures`` of :func:`gltf_document`; the Khronos glTF 2.0 specification, "Textures",
"Images": a URI reference, percent-encoded).

>>> from plausible.export.gltf import gltf_document
>>> doc = gltf_document({"gold": {"base_color": [1.0, 0.77, 0.34], "metallic": 1.0, "roughness": 0.3}})
>>> doc["materials"][0]["pbrMetallicRoughness"]["metallicFactor"], doc["asset"]["version"]
(1.0, '2.0')
"""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path

import numpy as np

from .. import registry

__all__ = ["SURFACE", "TEXTURE_SLOTS", "gltf_document", "gltf_material", "image_uri", "material_model",
           "read_gltf_materials", "sphere", "write_gltf"]

#: glTF's numbers for the types the file uses.
_FLOAT, _UNSIGNED_SHORT = 5126, 5123
_ARRAY_BUFFER, _ELEMENT_ARRAY_BUFFER = 34962, 34963
_TRIANGLES = 4
#: Distance between the centres of neighbouring spheres (radius 1).
SPACING = 2.5


def _model(name: str, params):
    """``params`` as a validated ``gltf-pbr`` model (a model given is checked to be one);
    an ``"ior"`` entry folded into ``specular_color`` (module docstring)."""
    from ..models.gltf_pbr import specular_color_of_ior

    cls = registry.info("gltf-pbr").cls
    if isinstance(params, cls):
        return params
    if not isinstance(params, dict):
        raise ValueError(f"material {name!r}: parameters must be a dict of gltf-pbr parameters or a "
                         f"gltf-pbr model, got {type(params).__name__}")
    try:
        if "ior" in params:
            params = dict(params)
            ior = params.pop("ior")
            if isinstance(ior, bool) or not isinstance(ior, (int, float)):
                raise ValueError(f"KHR_materials_ior: ior must be a number, got {ior!r}")
            params["specular_color"] = specular_color_of_ior(ior, params.get("specular_color", 1.0))
        return cls(**params)
    except ValueError as err:
        raise ValueError(f"material {name!r}: {err}") from None


def _rgb(v) -> list:
    a = np.broadcast_to(np.asarray(v, dtype=np.float64), (3,))
    return [float(x) for x in a]


#: What a material may have beside its BRDF (``surface`` of :func:`gltf_material`) and its range.
SURFACE = {"alpha": (0.0, 1.0), "emissive": (0.0, float("inf")), "transmission": (0.0, 1.0), "ior": (1.0, 10.0)}


def _surface(name, surface) -> dict:
    """``surface`` checked against :data:`SURFACE` (ValueError naming the material and the key)."""
    surface = dict(surface or {})
    for k, v in surface.items():
        if k not in SURFACE:
            raise ValueError(f"material {name!r}: surface key {k!r} is not written; keys: {', '.join(SURFACE)}")
        lo, hi = SURFACE[k]
        a = np.asarray(v, float)
        if a.size not in (1, 3) or not np.all((a >= lo) & (a <= hi)):
            raise ValueError(f"material {name!r}: surface {k!r} must be in [{lo:g}, {hi:g}], got {v!r}")
    return surface


def _with_surface(mat: dict, ext: dict, sf: dict) -> None:
    """The glTF of ``sf`` (:data:`SURFACE`): ``alpha`` < 1 -> ``alphaMode BLEND`` and the base colour's
    alpha; ``emissive`` -> ``emissiveFactor`` (above 1: divided by its largest channel, which becomes
    ``KHR_materials_emissive_strength``); ``transmission``, ``ior`` -> their extensions."""
    if "alpha" in sf and float(sf["alpha"]) < 1.0:
        mat["pbrMetallicRoughness"]["baseColorFactor"][3] = float(sf["alpha"])
        mat["alphaMode"] = "BLEND"
    if "emissive" in sf:
        e = _rgb(sf["emissive"])
        top = max(e)
        mat["emissiveFactor"] = [x / top for x in e] if top > 1.0 else e
        if top > 1.0:
            ext["KHR_materials_emissive_strength"] = {"emissiveStrength": top}
    if "transmission" in sf:
        ext["KHR_materials_transmission"] = {"transmissionFactor": float(sf["transmission"])}
    if "ior" in sf:
        ext["KHR_materials_ior"] = {"ior": float(sf["ior"])}


def gltf_material(name: str, params, surface: dict | None = None) -> dict:
    """The glTF material object of one ``gltf-pbr`` material (``params``: a dict of its
    parameters or the model) and what it has beside its BRDF (``surface``: :data:`SURFACE`);
    ValueError naming the material and the parameter for bad values."""
    p = _model(name, params).params
    ior = params.get("ior", 1.5) if isinstance(params, dict) else 1.5
    if ior != 1.5:      # the factor as the user gave it, relative to this ior
        p = dict(p, specular_color=params.get("specular_color", 1.0))
    sf = _surface(name, surface)
    mat = {"name": str(name),
           "pbrMetallicRoughness": {"baseColorFactor": _rgb(p["base_color"]) + [1.0],
                                    "metallicFactor": float(p["metallic"]),
                                    "roughnessFactor": float(p["roughness"])}}
    ext = {}
    if p["specular"] != 1.0 or np.any(np.asarray(p["specular_color"]) != 1.0):
        ext["KHR_materials_specular"] = {"specularFactor": float(p["specular"]),
                                         "specularColorFactor": _rgb(p["specular_color"])}
    if p["anisotropy_strength"] != 0.0:
        ext["KHR_materials_anisotropy"] = {"anisotropyStrength": float(p["anisotropy_strength"]),
                                           "anisotropyRotation": float(p["anisotropy_rotation"])}
    if ior != 1.5 and "ior" not in sf:
        ext["KHR_materials_ior"] = {"ior": float(ior)}
    _with_surface(mat, ext, sf)
    if ext:
        mat["extensions"] = ext
    return mat


def material_model(mat: dict):
    """The ``gltf-pbr`` model of one glTF material object (the inverse of
    :func:`gltf_material`): the ``pbrMetallicRoughness`` factors and the
    extensions KHR_materials_specular, KHR_materials_anisotropy and
    KHR_materials_ior (folded into ``specular_color``, exactly), each at its
    default where absent; textures are not read.  ValueError naming the material
    and the parameter for values outside the model's ranges."""
    name = mat.get("name", "material")
    pbr = mat.get("pbrMetallicRoughness", {})
    ext = mat.get("extensions", {})
    spec = ext.get("KHR_materials_specular", {})
    aniso = ext.get("KHR_materials_anisotropy", {})
    params = {"base_color": list(pbr.get("baseColorFactor", [1.0, 1.0, 1.0, 1.0]))[:3],
              "metallic": pbr.get("metallicFactor", 1.0), "roughness": pbr.get("roughnessFactor", 1.0),
              "specular": spec.get("specularFactor", 1.0),
              "specular_color": list(spec.get("specularColorFactor", [1.0, 1.0, 1.0])),
              "anisotropy_strength": aniso.get("anisotropyStrength", 0.0),
              "anisotropy_rotation": aniso.get("anisotropyRotation", 0.0) % math.pi}
    if "KHR_materials_ior" in ext:
        params["ior"] = ext["KHR_materials_ior"].get("ior", 1.5)
    return _model(name, params)


def read_gltf_materials(path) -> dict:
    """``{name: gltf-pbr model}`` of every material of a ``.gltf`` file (JSON;
    :func:`material_model`); unnamed materials are called ``material N``."""
    doc = json.loads(Path(path).read_text(encoding="utf-8"))
    out = {}
    for k, mat in enumerate(doc.get("materials", [])):
        out[mat.get("name") or f"material {k}"] = material_model(mat)
    return out


def sphere(rings: int = 32, segments: int = 64):
    """A UV sphere of radius 1 about the origin: ``(positions, normals, tangents, indices)``
    as float32 ``(V, 3)``, ``(V, 3)``, ``(V, 4)`` and uint16 ``(T, 3)`` arrays.  Vertex
    ``(i, j)`` at polar angle ``pi i / rings`` from ``+y`` (glTF's up) and azimuth
    ``2 pi j / segments``; the seam column is doubled (``j = segments``).  The tangent
    is the direction of growing azimuth, ``(cos phi, 0, -sin phi)``, with handedness
    ``w = 1``; counter-clockwise triangles seen from outside (glTF's front faces)."""
    if rings < 2 or segments < 3 or (rings + 1) * (segments + 1) > 65535:
        raise ValueError(f"sphere: rings >= 2, segments >= 3 and (rings + 1)(segments + 1) <= 65535 "
                         f"(16-bit indices), got rings={rings}, segments={segments}")
    th = np.linspace(0.0, math.pi, rings + 1)[:, None]
    ph = np.linspace(0.0, 2.0 * math.pi, segments + 1)[None, :]
    st, ct, sp, cp = np.sin(th), np.cos(th), np.sin(ph), np.cos(ph)
    pos = np.stack(np.broadcast_arrays(st * sp, ct, st * cp), -1).reshape(-1, 3)
    tan = np.stack(np.broadcast_arrays(cp, 0.0 * th, -sp, 1.0 + 0.0 * th), -1).reshape(-1, 4)
    i, j = np.meshgrid(np.arange(rings), np.arange(segments), indexing="ij")
    a = i * (segments + 1) + j
    b = a + segments + 1
    quads = np.stack([a, b, a + 1, a + 1, b, b + 1], -1).reshape(-1, 3)
    tris = quads[np.abs(np.cross(pos[quads[:, 1]] - pos[quads[:, 0]],
                                 pos[quads[:, 2]] - pos[quads[:, 0]])).sum(-1) > 1e-12]
    return pos.astype(np.float32), pos.astype(np.float32), tan.astype(np.float32), tris.astype(np.uint16)


def _buffer(arrays):
    """One buffer holding ``arrays`` (each 4-byte aligned), its views and accessors."""
    blob, views, accessors = b"", [], []
    for arr, kind, target in arrays:
        data = np.ascontiguousarray(arr).tobytes()
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": len(data), "target": target})
        acc = {"bufferView": len(views) - 1, "componentType": _UNSIGNED_SHORT if arr.dtype == np.uint16 else _FLOAT,
               "count": int(arr.size if kind == "SCALAR" else len(arr)), "type": kind}
        if kind == "VEC3" and target == _ARRAY_BUFFER and len(accessors) == 0:   # POSITION needs min, max
            acc["min"] = [float(x) for x in arr.min(0)]
            acc["max"] = [float(x) for x in arr.max(0)]
        accessors.append(acc)
        blob += data + b"\0" * (-len(data) % 4)
    uri = "data:application/octet-stream;base64," + base64.b64encode(blob).decode("ascii")
    return {"byteLength": len(blob), "uri": uri}, views, accessors


#: The material textures a file can reference (``textures`` of :func:`gltf_document`).
TEXTURE_SLOTS = ("baseColorTexture",)


def image_uri(filename: str) -> str:
    """A file name as a glTF image URI (a relative URI reference): backslashes as ``/``, and
    characters a URI cannot hold (spaces, ``#``, ``%``, non-ASCII) percent-encoded.

    >>> image_uri(r"tex\\my wood#2.png")
    'tex/my%20wood%232.png'
    """
    from urllib.parse import quote

    name = str(filename).strip().replace("\\", "/")
    if not name:
        raise ValueError("a texture needs a file name")
    return quote(name, safe="/:@!$&'()*+,;=-._~")


def _textures(mats, textures):
    """Images, textures and the material indices that need ``TEXCOORD_0``, with each material's
    texture slots filled (one image per distinct file)."""
    textures = textures or {}
    names = [m["name"] for m in mats]
    unknown = [n for n in textures if n not in names]
    if unknown:
        raise ValueError(f"textures: no material named {unknown[0]!r} (materials: {', '.join(names)})")
    images, uris, textured = [], {}, set()
    for k, m in enumerate(mats):
        for slot, filename in (textures.get(m["name"]) or {}).items():
            if slot not in TEXTURE_SLOTS:
                raise ValueError(f"material {m['name']!r}: texture slot {slot!r} is not written; "
                                 f"slots: {', '.join(TEXTURE_SLOTS)}")
            uri = image_uri(filename)
            if uri not in uris:
                uris[uri] = len(images)
                images.append({"uri": uri})
            m["pbrMetallicRoughness"][slot] = {"index": uris[uri], "texCoord": 0}
            textured.add(k)
    return images, textured


def gltf_document(materials: dict, *, rings: int = 32, segments: int = 64, textures: dict | None = None,
                  surfaces: dict | None = None) -> dict:
    """The glTF 2.0 JSON (a dict) of ``materials`` (name -> ``gltf-pbr`` parameters or
    model), one sphere each (see the module docstring).  ``textures``: ``{material:
    {slot: file}}`` (slots :data:`TEXTURE_SLOTS`), each file referenced by a relative URI
    (:func:`image_uri`, not embedded), its material's sphere given ``TEXCOORD_0``
    (``u`` the azimuth, ``v`` the polar angle, both 0-1).  ``surfaces``: ``{material: surface}``
    (:func:`gltf_material`'s, :data:`SURFACE`)."""
    if not isinstance(materials, dict) or not materials:
        raise ValueError(f"materials must be a non-empty dict of name -> gltf-pbr parameters, "
                         f"got {type(materials).__name__} {materials!r:.60}")
    surfaces = surfaces or {}
    mats = [gltf_material(name, params, surfaces.get(name)) for name, params in materials.items()]
    images, textured = _textures(mats, textures)
    pos, nrm, tan, idx = sphere(rings, segments)
    arrays = [(pos, "VEC3", _ARRAY_BUFFER), (nrm, "VEC3", _ARRAY_BUFFER),
              (tan, "VEC4", _ARRAY_BUFFER), (idx, "SCALAR", _ELEMENT_ARRAY_BUFFER)]
    if textured:
        u, v = np.meshgrid(np.linspace(0.0, 1.0, segments + 1), np.linspace(0.0, 1.0, rings + 1))
        arrays.append((np.stack([u.ravel(), v.ravel()], -1).astype(np.float32), "VEC2", _ARRAY_BUFFER))
    buf, views, accessors = _buffer(arrays)

    def prim(m, k):
        # TANGENT only where KHR_materials_anisotropy needs it (the validator reports it unused elsewhere)
        att = {"POSITION": 0, "NORMAL": 1}
        if "KHR_materials_anisotropy" in m.get("extensions", {}):
            att["TANGENT"] = 2
        if k in textured:
            att["TEXCOORD_0"] = 4
        return {"attributes": att, "indices": 3, "material": k, "mode": _TRIANGLES}

    cols = math.ceil(math.sqrt(len(mats)))
    nodes = [{"name": m["name"], "mesh": k,
              "translation": [SPACING * (k % cols), -SPACING * (k // cols), 0.0]} for k, m in enumerate(mats)]
    used = sorted({e for m in mats for e in m.get("extensions", {})})
    doc = {"asset": {"version": "2.0", "generator": "plausible (gltf-pbr)"},
           "scene": 0, "scenes": [{"nodes": list(range(len(mats)))}], "nodes": nodes,
           "meshes": [{"name": m["name"], "primitives": [prim(m, k)]} for k, m in enumerate(mats)],
           "materials": mats, "buffers": [buf], "bufferViews": views, "accessors": accessors}
    if used:
        doc["extensionsUsed"] = used
    if images:
        doc["images"] = images
        doc["textures"] = [{"source": i} for i in range(len(images))]
    return doc


def write_gltf(materials: dict, path, *, rings: int = 32, segments: int = 64, textures: dict | None = None) -> Path:
    """Write ``materials`` (name -> ``gltf-pbr`` parameters or model) to ``path`` as a
    ``.gltf`` file (JSON, buffers embedded, textures referenced: :func:`gltf_document`);
    returns the path.  One sphere per material, each node and mesh named after its material."""
    from ..text import write_atomic

    path = Path(path)
    doc = gltf_document(materials, rings=rings, segments=segments, textures=textures)
    write_atomic(path, json.dumps(doc, indent=1) + "\n")     # whole or not at all
    return path
