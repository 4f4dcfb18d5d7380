"""``plausible convert SOURCE --to blender``: the glTF fit as Principled BSDFs, verified in Cycles.

Each material of the source is fitted as for glTF (:func:`plausible.conversion.convert`,
``to="gltf"``), its parameters mapped onto the Principled BSDF
(:func:`.principled.principled_inputs`), written (:func:`.principled.write_blender`:
``.blend`` or ``.py``), then **read back from the written file and acquired in Cycles**
(:func:`.acquire.acquire`) and compared with the source:

* the **albedo**: the white furnace's ring albedos beside the source's directional
  albedo at the same angles (:func:`plausible.analysis.albedo_curve`), the largest
  difference over the rings and channels (for a reciprocal source the furnace's
  camera-side albedo is the albedo);
* the **look**, where the user looks: the written material rendered **in Cycles** in the
  scene of :func:`plausible.compare_looks` and the source in Mitsuba
  (:func:`.looks.compare_cycles`: mean HDR-FLIP over the views at 0, 60, 120 and 150
  degrees, grazing included, and the highlight ratio, at :data:`LOOK_SPP` samples per
  pixel: the floor of a material known on both sides is FLIP 0.015 there); and the same
  against the fitted ``gltf-pbr`` (the mapping's own error, apart from the glTF fit's), where
  Mitsuba is installed.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .acquire import acquire as _acquire
from .principled import NODES, TEXTURE_NODES, blender_material, write_blender

__all__ = ["BlenderConversion", "Verified", "convert_to_blender"]


@dataclass
class Verified:
    """One written material, acquired in Cycles and compared with its source."""

    name: str
    inputs: dict
    #: largest |furnace albedo - source albedo| over the rings and channels, and where
    albedo_difference: float
    albedo_theta_deg: float
    #: the furnace's largest standard error (the comparison's noise)
    albedo_stderr: float
    #: largest |furnace albedo - albedo of the fitted gltf-pbr model| (the mapping's own error)
    fit_albedo_difference: float | None = None
    #: the look, Cycles against the source in Mitsuba (None: not rendered, :attr:`notes` says why)
    flip: float | None = None
    highlight_ratio: float | None = None
    highlight_ratios: list | None = None
    #: the look, Cycles against the fitted gltf-pbr in Mitsuba (the mapping's own error)
    fit_flip: float | None = None
    fit_highlight_ratio: float | None = None
    notes: list = field(default_factory=list)

    def description(self) -> str:
        """What was written, in a line: the source's lobes, glTF's formula as nodes, or the Principled inputs."""
        def fmt(x):
            return "(" + ", ".join(f"{c:.3g}" for c in x) + ")" if isinstance(x, list) else \
                (f"{x:.3g}" if isinstance(x, float) else str(x))

        if "ct_nodes" in self.inputs:
            g = self.inputs["ct_nodes"]
            lobes = [f"Beckmann r {fmt(b['roughness'])} (Glossy {fmt(b['colour'])}, rise {fmt(b['grazing'])})"
                     for b in g["lobes"]]
            return f"source's lobes: Diffuse {fmt(g['rd'])} + " + " + ".join(lobes)
        g = self.inputs.get("gltf_nodes")
        if g is not None:
            return (f"glTF nodes: base {fmt(g['base_color'])}, metallic {fmt(g['metallic'])}, "
                    f"roughness {fmt(g['roughness'])}, specular {fmt(g['specular'])}")
        return "Principled: " + ", ".join(f"{k} {fmt(x)}" for k, x in self.inputs.items())

    def to_dict(self) -> dict:
        return dict(name=self.name, inputs=self.inputs, albedo_difference=self.albedo_difference,
                    albedo_theta_deg=self.albedo_theta_deg, albedo_stderr=self.albedo_stderr,
                    fit_albedo_difference=self.fit_albedo_difference, flip=self.flip,
                    highlight_ratio=self.highlight_ratio, highlight_ratios=self.highlight_ratios,
                    fit_flip=self.fit_flip, fit_highlight_ratio=self.fit_highlight_ratio, notes=self.notes)


@dataclass
class BlenderConversion:
    """What :func:`convert_to_blender` wrote and measured."""

    path: Path
    conversion: object              # the glTF fit (plausible.conversion.Conversion)
    verified: list                  # [Verified]

    def to_json(self) -> list:
        by = {v.name: v.to_dict() for v in self.verified}
        return [dict(c.to_dict(), target="blender", blender=by.get(c.name)) for c in self.conversion.items] + \
            [dict(s) for s in self.conversion.skipped]


def _textures(conv, where) -> dict:
    from ..conversion import texture_path

    return {c.name: {s: texture_path(c.textures[s], c.folder, where) for s in TEXTURE_NODES if s in c.textures}
            for c in conv.items if any(s in c.textures for s in TEXTURE_NODES)}


def _spec(path: Path, name: str) -> dict:
    """The written material, its textures unlinked (the acquisition measures a uniform material;
    the fit's colour is what a texture multiplies)."""
    return {"blend": str(path), "name": name, "untextured": True} if path.suffix.lower() == ".blend" else \
        {"script": str(path), "name": name, "untextured": True}


#: Samples per pixel of the look comparison (both renderers; the lamp's image 16x that): the floor of
#: Cycles' Diffuse against Mitsuba's diffuse is FLIP 0.015 at 64, 0.032 at 16 (docs/blender.md).
LOOK_SPP = 64


def _albedo_gap(acq, model):
    """Largest |furnace albedo - ``model``'s albedo| over rings and channels, and its theta (degrees)."""
    from ..analysis import albedo_curve

    a = np.asarray(albedo_curve(model, thetas_deg=np.degrees(acq.albedo_theta)).value, float)
    a = np.broadcast_to(a.reshape(len(acq.albedo_theta), -1), acq.albedo.shape)
    d = np.abs(acq.albedo - a)
    k = np.unravel_index(int(np.argmax(d)), d.shape)
    return float(d[k]), float(math.degrees(acq.albedo_theta[k[0]]))


def verify(path, name: str, inputs: dict, source_model, *, fit_model=None, looks: bool = True,
           resolution: int = 64, angles=(0, 30, 60, 90, 120, 150)) -> Verified:
    """Acquire material ``name`` of the written ``path`` and compare it with ``source_model``
    (and with ``fit_model``, the fitted gltf-pbr, if given; module docstring)."""
    acq = _acquire(_spec(Path(path), name), name=name, resolution=resolution, angles=angles)
    gap, theta = _albedo_gap(acq, source_model)
    v = Verified(name, inputs, gap, theta, float(acq.albedo_stderr.max()),
                 _albedo_gap(acq, fit_model)[0] if fit_model is not None else None)
    if looks:
        _looks(v, Path(path), name, source_model, fit_model)
    return v


def _looks(v: Verified, path: Path, name: str, source_model, fit_model) -> None:
    """``v``'s look scores: the written material in Cycles beside the source (and the fit) in Mitsuba."""
    try:
        from .looks import compare_cycles
        from ..mitsuba.looks import compare_renders, render_looks
    except ImportError as e:                               # pragma: no cover - Mitsuba absent
        v.notes.append(f"look not compared: {e}")
        return
    try:
        lk = compare_cycles(source_model, _spec(path, name), spp=LOOK_SPP)
        fit = compare_renders(render_looks(fit_model, spp=LOOK_SPP), lk.result) if fit_model is not None else None
    except (ImportError, ValueError, RuntimeError) as e:
        v.notes.append(f"look not compared: {e}")
        return
    v.flip, v.highlight_ratio, v.highlight_ratios = float(lk.flip), float(lk.highlight_ratio), list(lk.highlight_ratios)
    if fit is not None:
        v.fit_flip, v.fit_highlight_ratio = float(fit.flip), float(fit.highlight_ratio)
    v.notes += list(lk.warnings)


def convert_to_blender(source, out, metric: str = "perceptual", *, verify_looks: bool = True,
                       verify_result: bool = True, nodes: str = "source", progress=None) -> BlenderConversion:
    """Convert every material of ``source`` (what :func:`plausible.conversion.convert` reads:
    an MTL file, a published fit, a model spec) to Principled BSDFs written to ``out``
    (``.blend`` or ``.py``), each verified in Cycles (``verify_result``; the look too where
    ``verify_looks`` and Mitsuba is installed).  ``nodes``: ``"source"`` writes a source that is a
    Lambertian plus Cook-Torrance lobes as its own lobes and any other as ``"gltf"``; ``"gltf"``
    writes the glTF fit, a dielectric part as glTF's formula in nodes; ``"principled"`` the glTF fit
    as one Principled BSDF (:mod:`.principled`).
    ValueError naming ``out`` for a bad suffix, ``nodes`` for another choice."""
    from ..conversion import convert, read_sources
    from ..progress import start

    out = Path(out)
    if out.suffix.lower() not in (".blend", ".py"):
        raise ValueError(f"out: a Blender output ends in .blend or .py, got {str(out)!r}")
    if nodes not in NODES:
        raise ValueError(f"nodes: one of {', '.join(NODES)}, got {nodes!r}")
    if not (out.parent if str(out.parent) else Path(".")).is_dir():
        raise ValueError(f"out: the folder of {str(out)!r} does not exist")
    conv = convert(source, to="gltf", metric=metric, looks=False)
    models = {s.name: s.model for s in read_sources(source)}
    mats = {}
    for c in conv.items:
        if "transmission" in c.surface or not hasattr(c.result, "params"):
            conv.skipped.append({"name": c.name, "skipped": f"{c.name}: glass (transmission) is not written to "
                                 "Blender yet: the writer makes reflecting Principled BSDFs"})
            continue
        mats[c.name] = blender_material(c.result.params, nodes, models.get(c.name))
    conv.items = [c for c in conv.items if c.name in mats]
    if not mats:
        raise ValueError(f"source: nothing to convert in {source!r} "
                         f"({'; '.join(s['skipped'] for s in conv.skipped) or 'no materials'})")
    write_blender(mats, out, _textures(conv, out.parent.resolve()))
    verified = []
    if verify_result:
        fits = {c.name: None if "ct_nodes" in mats[c.name] else c.result for c in conv.items}
        tick = start(progress, len(mats), "verify in Cycles")
        for name, inputs in mats.items():
            verified.append(verify(out, name, inputs, models[name], fit_model=fits[name], looks=verify_looks))
            tick()
    return BlenderConversion(out, conv, verified)
