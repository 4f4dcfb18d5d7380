"""Conversion of legacy and published materials to the models renderers use today,
with the error measured (``docs/convert.md``).

:func:`convert` reads a *source* -- a model spec (``"modified-phong:kd=0.5"``, a
sum ``"lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50"``), a published fit
``"material:NAME@FIT"``, a Mitsuba BSDF (a dict as ``mi.load_dict`` takes it, a
Mitsuba XML file: every ``<bsdf id=...>``, or a ``.json`` file of such dicts by
name) or a Wavefront ``.mtl`` file (every ``newmtl``; :mod:`.mtl`) -- as
plausible models, and fits a *target* to each:

* ``"mitsuba"``: one of Mitsuba's ``diffuse``, ``roughconductor``,
  ``roughplastic``, ``blendbsdf`` (diffuse + roughconductor), ``blendbsdf-tir``
  (a ``blendbsdf`` of a roughconductor and a diffuse base under a coat of lower index
  than outside, whose albedo falls with incidence), ``principled`` per material, the
  best of the candidates (:func:`.mitsuba.candidates`) by the figure minimised --
  each fitted with the albedo band as a constraint and the rendered highlight held second -- or
  ``"mitsuba:TYPE"`` forced; fitted through Mitsuba's own code (:func:`.mitsuba.fit_family`);
* ``"gltf"``: the glTF 2.0 metallic-roughness material, the registered model
  ``gltf-pbr`` fitted the same way, written by :func:`plausible.export.gltf.write_gltf`
  (refused with a message where that model is not installed);
* ``"materialx"``, ``"usd"``: the glTF fit written as a MaterialX document (an ``open_pbr_surface`` and a
  ``gltf_pbr`` per material, :mod:`plausible.export.materialx`) or a USD file of ``UsdPreviewSurface``
  materials (:mod:`plausible.export.usd`), ``docs/materialx.md``;
* any registered model: :func:`plausible.fit`.

What a reflection model does not hold is converted beside the fit (an MTL's glass as Mitsuba's
``dielectric``/``thindielectric`` or glTF's transmission, its ``d`` as a ``mask`` or glTF's alpha,
its ``Ke`` as glTF's emission), an exactly Lambertian source is written exactly (not fitted), a
candidate that renders other than it evaluates is never chosen (:func:`degenerate`), and a material
that cannot be converted is skipped (:attr:`Conversion.skipped`), the rest converted.

Each :class:`Converted` holds the target's parameters, every fitting metric's
figure, the albedo of source and target at 0, 45 and 75 degrees (the target's
by Mitsuba's own sampler for a Mitsuba target) and warnings where the target
cannot represent the source.  :meth:`Conversion.write` writes ``.json`` (a dict
of Mitsuba dicts by name, for ``mi.load_dict``), ``.xml`` (``<bsdf id=...>``
elements) or ``.gltf``.

>>> import plausible
>>> c = plausible.convert("lambertian:rd=0.5", to="mitsuba")        # doctest: +SKIP
>>> c.items[0].target, c.items[0].params["reflectance"]["value"]      # doctest: +SKIP
('mitsuba:diffuse', [0.5, 0.5, 0.5])
"""

from __future__ import annotations

import json
import math
import os
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import arguments as A

from .mitsuba import CONSERVE_THETAS, PROBE_THETAS, REPORT_THETAS
from .textures import GLTF_TEXTURE_SLOTS, prepare

__all__ = ["Conversion", "Converted", "METALLIC_MARGIN", "OUTPUTS", "Source", "TOLERANCE", "albedo_check",
           "check_output", "convert", "degenerate", "lambertian_albedo", "metallic_decision", "mitsuba_xml",
           "read_sources"]

#: The largest albedo difference (any channel, at each of :data:`REPORT_THETAS`) a
#: conversion of a conserving source is expected to keep; beyond it a warning.
TOLERANCE = 0.05


@dataclass
class Source:
    """One material read from a source: its ``name``, the model (the contract),
    the plausible ``spec`` it was read as, notes of the reading, and textures
    carried by reference (statement -> file)."""

    name: str
    model: object
    spec: str
    notes: list = field(default_factory=list)
    textures: dict = field(default_factory=dict)
    #: The folder the texture file names are relative to (an ``.mtl`` file's own); None: as given.
    folder: str | None = None
    #: What the reading drops or changes that a user must know (the report's warnings).
    warnings: list = field(default_factory=list)
    #: What a reflection model does not hold (:class:`plausible.conversion.mtl.Reading`: glass,
    #: opacity, emission).
    surface: dict = field(default_factory=dict)
    #: Why the material cannot be converted (it is skipped, the rest converted); None: it can.
    refused: str | None = None


@dataclass
class Converted:
    """One conversion (the fields of the ``--json`` report)."""

    name: str
    source: str
    target: str
    params: dict
    errors: dict
    albedo: dict
    warnings: list = field(default_factory=list)
    notes: list = field(default_factory=list)
    textures: dict = field(default_factory=dict)
    #: The target: a Mitsuba dict, or a registered model.
    result: object = None
    #: The folder the texture file names are relative to (the source's; :meth:`Conversion.write`
    #: writes them relative to the output file's folder).
    folder: str | None = None
    #: glTF properties beside the BRDF (:func:`plausible.export.gltf.gltf_material`'s ``surface``:
    #: ``alpha``, ``emissive``, ``transmission``, ``ior``).
    surface: dict = field(default_factory=dict)
    #: Textures to bake into a Mitsuba result (``Kd x map_Kd``): dotted slot -> (statement, the fitted
    #: constant colour the texture multiplies); :meth:`Conversion.write` bakes them beside the output.
    bakes: dict = field(default_factory=dict)
    #: Source and target rendered side by side (:func:`plausible.compare_looks`: FLIP, highlight
    #: ratios); None where they were not rendered (``looks=False``, or a note says why).
    looks: object = None
    #: A Mitsuba target as fitted, before textures replaced its colours (what :attr:`looks` renders).
    fitted: dict | None = None
    #: The registered model fitted where the target is a format written from one (``gltf-pbr`` for
    #: ``gltf``, ``materialx``, ``usd``: :data:`GLTF_SHAPED`); None for a Mitsuba or model target.
    model: str | None = None

    @property
    def label(self) -> str:
        """The target as the report's table shows it: the target asked for, with the model fitted
        where that is another name (``materialx (gltf-pbr fit)``)."""
        return self.target if self.model is None or self.target == "gltf" else f"{self.target} ({self.model} fit)"

    def to_dict(self) -> dict:
        return {"name": self.name, "source": self.source, "target": self.target, "model": self.model,
                "params": self.params,
                "error": self.errors, "albedo": self.albedo, "warnings": self.warnings, "notes": self.notes,
                "textures": self.textures, "surface": self.surface,
                "looks": self.looks.to_dict() if self.looks is not None else None}


@dataclass
class Conversion:
    """Every material of one source converted to one target."""

    to: str
    metric: str
    items: list
    #: The materials not converted: ``{"name", "skipped": why}`` (a warning each; the command exits 1).
    skipped: list = field(default_factory=list)

    def to_json(self) -> list:
        return [c.to_dict() for c in self.items] + [dict(s) for s in self.skipped]

    def mitsuba_dicts(self, where=None) -> dict:
        """``{name: dict for mi.load_dict}`` (a registered-model target: its plausible plugin,
        loadable after :func:`plausible.mitsuba.register`); ``where``: the folder of the output
        file, every ``bitmap``'s file name relative to it (:func:`texture_path`)."""
        from ..mitsuba.scene_dict import to_dict

        def moved(d, folder):
            if not isinstance(d, dict):
                return d
            if d.get("type") == "bitmap" and "filename" in d:
                return {**d, "filename": texture_path(d["filename"], folder, where)}
            return {k: moved(v, folder) for k, v in d.items()}

        return {c.name: moved(c.result if isinstance(c.result, dict) else to_dict(c.result), c.folder)
                for c in self.items}

    def write(self, path) -> Path:
        """Write the targets to ``path`` by its suffix (:func:`check_output`): ``.json`` (a dict of
        Mitsuba dicts by name), ``.xml`` (a scene fragment of ``<bsdf id=NAME>`` elements) or
        ``.gltf`` (``to="gltf"``).  Written whole or not at all (:func:`plausible.text.write_atomic`):
        an error or Ctrl-C while writing leaves no half-written file.  ValueError naming ``out``
        for a bad suffix, a missing folder or a file that cannot be written."""
        from ..text import write_atomic

        p = Path(path)
        suffix = check_output(p, self.to)
        if not self.items:
            raise ValueError(f"out: no material of the source was converted ({len(self.skipped)} skipped): "
                             f"{str(path)!r} not written")
        prepare(self, p, suffix)        # textures glTF cannot hold as PNG, Kd x map_Kd baked for Mitsuba
        text = self.text(suffix, p.resolve().parent)
        try:
            write_atomic(p, text)
        except OSError as e:
            raise ValueError(f"out: cannot write {str(path)!r}: {e.strerror or e}") from None
        return p

    def text(self, suffix: str, where=None) -> str:
        """The text of the output file of ``suffix`` (``.json``, ``.xml``, ``.gltf``: :meth:`write`),
        texture names relative to the folder ``where`` (None: as the source gives them)."""
        if suffix == ".gltf":
            from ..export.gltf import gltf_document

            return json.dumps(gltf_document({c.name: c.result for c in self.items},
                                            textures=self.gltf_textures(where),
                                            surfaces={c.name: c.surface for c in self.items if c.surface}),
                              indent=1) + "\n"
        if suffix in (".mtlx", ".usda"):
            return self.dcc_text(suffix, where)
        if suffix == ".json":
            return json.dumps(self.mitsuba_dicts(where), indent=2) + "\n"
        if suffix == ".xml":
            return mitsuba_xml(self.mitsuba_dicts(where))
        raise ValueError(f"out: the output file must end in .json, .xml or .gltf{_DCC_SUFFIXES}, got {suffix!r}")

    def dcc_text(self, suffix: str, where=None) -> str:
        """The ``.mtlx`` (:func:`plausible.export.materialx.materialx_text`) or ``.usda``
        (:func:`plausible.export.usd.usd_text`) text of the glTF-shaped results, the base colour
        textures relative to the folder ``where``."""
        textures = {name: slots["baseColorTexture"] for name, slots in self.gltf_textures(where).items()}
        materials = {c.name: c.result for c in self.items}
        surfaces = {c.name: c.surface for c in self.items if c.surface}
        if suffix == ".mtlx":
            from ..export.materialx import materialx_text

            return materialx_text(materials, textures=textures, surfaces=surfaces)
        from ..export.usd import usd_text

        return usd_text(materials, textures=textures, surfaces=surfaces)

    def gltf_textures(self, where=None) -> dict:
        """``{material: {glTF texture slot: file}}`` of the textures a ``.gltf`` file references
        (:data:`GLTF_TEXTURE_SLOTS`: ``map_Kd`` as ``baseColorTexture``); ``where``: the folder
        of the output file, the names relative to it (:func:`texture_path`)."""
        return {c.name: {slot: texture_path(c.textures[stmt], c.folder, where)
                         for stmt, slot in GLTF_TEXTURE_SLOTS.items() if stmt in c.textures}
                for c in self.items if any(stmt in c.textures for stmt in GLTF_TEXTURE_SLOTS)}


def texture_path(name: str, folder, where) -> str:
    """A texture's file ``name`` as written in its source (relative to ``folder``, the
    ``.mtl`` file's) relative to ``where``, the output file's folder, with ``/``
    separators; ``name`` as given (``\\`` as ``/``) when ``folder`` or ``where`` is None or
    the name is absolute.  So the references of an output written anywhere find the files."""
    name = str(name).replace("\\", "/")
    if folder is None or where is None or Path(name).is_absolute():
        return name
    try:
        return Path(os.path.relpath(Path(folder) / name, where)).as_posix()
    except ValueError:          # another drive (Windows): the absolute path
        return (Path(folder) / name).as_posix()


#: The output suffixes :meth:`Conversion.write` writes.
OUTPUTS = (".json", ".xml", ".gltf", ".mtlx", ".usda")
#: Targets fitted as the ``gltf-pbr`` model (and written by their own writer) -> their file's suffix.
GLTF_SHAPED = {"gltf": ".gltf", "materialx": ".mtlx", "usd": ".usda"}
_DCC_SUFFIXES = " (or .mtlx with --to materialx, .usda with --to usd)"


def check_output(path, to: str, source=None) -> str:
    """The suffix of the output ``path`` of a conversion to ``to``, checked before anything is
    converted (the command line calls it first): one of :data:`OUTPUTS`, ``.gltf`` only for
    ``to="gltf"``, its folder an existing directory, and not the file ``source`` being converted
    (a Mitsuba scene converted onto itself lost its comments and other BSDFs).  ValueError naming
    ``out`` otherwise."""
    p = Path(path)
    if source is not None and p.exists() and Path(str(source)).is_file() and p.samefile(str(source)):
        raise ValueError(f"out: {str(path)!r} is the source being converted: write the output to another file "
                         f"(the conversion would replace it)")
    suffix = p.suffix.lower()
    if suffix not in OUTPUTS:
        raise ValueError(f"out: the output file must end in .json, .xml or .gltf{_DCC_SUFFIXES}, got {str(path)!r}")
    if suffix in GLTF_SHAPED.values():
        _gltf_writer()
        want = next(k for k, v in GLTF_SHAPED.items() if v == suffix)
        if str(to).strip() != want:
            what = {"gltf": "glTF", "materialx": "MaterialX", "usd": "USD"}[want]
            raise ValueError(f"out: a {suffix} file holds {what} materials; convert with to={want!r} (this "
                             f"conversion is to {str(to).strip()!r})")
        _dcc_writer(want)
    folder = p.parent if str(p.parent) else Path(".")
    if not folder.is_dir():
        raise ValueError(f"out: the folder of {str(path)!r} does not exist ({str(folder)!r})")
    if p.is_dir():
        raise ValueError(f"out: {str(path)!r} is a directory")
    return suffix


#: The registered model of the glTF 2.0 metallic-roughness BRDF (issue 32's glTF part).
GLTF_MODEL = "gltf-pbr"


def _gltf_writer():
    """``plausible.export.gltf.write_gltf`` when the glTF target is installed, else ValueError."""
    from .. import registry

    try:
        registry.info(GLTF_MODEL)
        from ..export.gltf import write_gltf
    except (ValueError, ImportError):
        raise ValueError(_GLTF_REFUSAL) from None
    return write_gltf


def _dcc_writer(to: str) -> None:
    """ValueError naming the package where the writer of ``to`` (materialx, usd) is not installed."""
    if to == "materialx":
        from ..export.materialx import _mx

        _mx()
    elif to == "usd":
        from ..export.usd import _usd

        _usd()


_GLTF_REFUSAL = ("glTF output is not available yet: the glTF target (the Khronos metallic-roughness BRDF "
                 "and the .gltf writer, plausible.export.gltf) is not installed in this version; "
                 "convert to 'mitsuba' or a registered model")


# -- sources --------------------------------------------------------------------------------------

def read_sources(source) -> list[Source]:
    """The materials of ``source`` (see the module docstring), each a :class:`Source`.
    ValueError for a missing file or a spec that does not build."""
    from .. import registry

    if isinstance(source, dict):
        return [_mitsuba_source(source.get("id", source.get("type", "bsdf")), source)]
    if hasattr(source, "eval") and not isinstance(source, (str, Path)):
        from ..analysis.adapters import as_bxdf

        m = as_bxdf(source)
        return [Source(getattr(m, "label", None) or m.name, m, registry.spec_of(m))]
    if not isinstance(source, (str, Path)):
        raise ValueError(f"source must be a model spec, material:NAME@FIT, a Mitsuba BSDF dict or file, "
                         f"or an .mtl file; got {type(source).__name__}")
    text = str(source).strip()
    suffix = Path(text).suffix.lower()
    if suffix in (".mtl", ".xml", ".json"):
        if not Path(text).is_file():
            raise ValueError(f"source file {text!r} not found")
        if suffix == ".mtl":
            from .mtl import read_mtl, reading

            out = []
            for m in read_mtl(text):
                r = reading(m)
                out.append(Source(m.name, r.model, r.spec, r.notes, m.texture_files, str(Path(text).resolve().parent),
                                  r.warnings, r.surface, r.refused))
            return out
        if suffix == ".xml":
            return _xml_sources(text)
        return _json_sources(text)
    m = registry.make_from_spec(text)         # a sum "a + b" too (registry.split_sum)
    if len(registry.split_sum(text)) > 1:
        return [Source("sum", m, m.spec())]
    spec = registry.spec_of(m)
    return [Source(getattr(m, "label", None) or m.name, m, text if spec == repr(m) else spec)]


def _mitsuba_source(name, d, bsdf=None):
    from ..analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict

    b = MitsubaBSDF(bsdf if bsdf is not None else load_bsdf_dict(d))
    spec = "mitsuba:" + (json.dumps(d, sort_keys=True) if d is not None else b.plugin)
    return Source(str(name), b, spec, ["read through Mitsuba (the adapter plausible.analysis.mitsuba_bsdf)"])


def _json_sources(path):
    try:
        data = json.loads(Path(path).read_text())
    except (OSError, ValueError) as e:
        raise ValueError(f"source {path}: not a JSON file of Mitsuba BSDF dicts ({e})") from None
    if isinstance(data, dict) and "type" in data:
        return [_mitsuba_source(Path(path).stem, data)]
    if not isinstance(data, dict) or not data or not all(isinstance(v, dict) for v in data.values()):
        raise ValueError(f"source {path}: expected a Mitsuba BSDF dict or a dict of them by name")
    return [_mitsuba_source(k, v) for k, v in data.items()]


def _xml_sources(path):
    import xml.etree.ElementTree as ET

    from ..analysis.mitsuba_bsdf import load_bsdf_xml

    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise ValueError(f"source {path}: not an XML file ({e})") from None
    ids = [el.get("id") for el in root.iter("bsdf") if el.get("id")]
    if not ids and root.tag == "bsdf":
        return [_mitsuba_source(Path(path).stem, None, load_bsdf_xml(path))]
    if not ids:
        raise ValueError(f"source {path}: no <bsdf id=...> in the file")
    return [_mitsuba_source(i, None, load_bsdf_xml(path, i)) for i in ids]


# -- the conversion ---------------------------------------------------------------------------------

def _source_albedo(model):
    from ..analysis import albedo_curve

    a = np.asarray(albedo_curve(model, thetas_deg=CONSERVE_THETAS).value, float)
    return np.broadcast_to(a.reshape(len(CONSERVE_THETAS), -1), (len(CONSERVE_THETAS), 3))


def _albedo_report(src_alb, tgt_alb):
    out = {}
    for k, t in enumerate(REPORT_THETAS):
        s = src_alb[CONSERVE_THETAS.index(t)]
        d = tgt_alb[k] - s
        out[f"{t:g}"] = {"source": [float(x) for x in s], "target": [float(x) for x in tgt_alb[k]],
                         "difference": [float(x) for x in d], "max_abs_difference": float(np.max(np.abs(d)))}
    return out


def _conserving(src, src_alb):
    """Warnings if ``src``'s albedo exceeds 1 at a probed incidence."""
    top = float(src_alb.max())
    if top > 1.0 + 1e-3:
        t = CONSERVE_THETAS[int(np.argmax(src_alb.max(axis=1)))]
        return [f"the source is not energy conserving (albedo {top:.3f} at {t:g} degrees): no target of "
                f"albedo <= 1 can represent it; its albedo is matched where it can be"]
    return []


def convert(source, to: str = "mitsuba", metric: str = "perceptual", *, starts: int = 2,
            looks: bool = True) -> Conversion:
    """Convert every material of ``source`` to ``to`` under ``metric`` (module docstring).

    ``to``: ``"mitsuba"``, ``"mitsuba:TYPE"`` (``diffuse``, ``roughconductor``,
    ``roughplastic``, ``blendbsdf``, ``blendbsdf-tir``, ``principled``), ``"gltf"``, ``"materialx"``,
    ``"usd"`` (the glTF fit, :data:`GLTF_SHAPED`), or a registered model's name.
    ``metric``: one of :data:`plausible.fitting.metrics.METRICS` (the perceptual
    metric, default, fits lobe and albedo together).  ``starts``: optimiser
    starts of a registered-model fit.  ``looks``: render source and target side by side
    (:func:`plausible.compare_looks`, about a second a material) into :attr:`Converted.looks`, a
    warning where a highlight is lost or invented.  Returns a :class:`Conversion`.
    """
    from ..fitting import metrics as M
    from . import mitsuba as CM

    if metric not in M.METRICS:
        raise ValueError(f"metric must be one of {', '.join(M.METRICS)}, got {metric!r}")
    A.count("starts", starts, 1)            # as plausible.fit (0 was taken)
    to = str(to).strip()
    family = None
    if to in GLTF_SHAPED:
        _gltf_writer()          # refused with a clear message until the glTF target is installed
        _dcc_writer(to)
        family = GLTF_MODEL
    if to.startswith("mitsuba:"):
        family = to.split(":", 1)[1]
        if family not in CM.FAMILIES or family in CM.PLAUSIBLE_TYPES:
            raise ValueError(f"to: Mitsuba target type {family!r} is not fitted; choose one of "
                             f"{', '.join('mitsuba:' + k for k in CM.FAMILIES if k not in CM.PLAUSIBLE_TYPES)} (or 'mitsuba' to let the "
                             f"source choose)")
    elif to != "mitsuba" and to not in GLTF_SHAPED:
        from .. import registry

        try:
            registry.info(to)    # a clear error for an unknown name
        except ValueError as e:  # the targets beside the models (the message listed the models alone)
            raise ValueError(f"to: {e}; or a target: mitsuba, mitsuba:TYPE "
                             f"({', '.join(k for k in CM.FAMILIES if k not in CM.PLAUSIBLE_TYPES)}), "
                             f"{', '.join(GLTF_SHAPED)}") from None
    from threadpoolctl import threadpool_limits

    items, skipped = [], []
    with threadpool_limits(limits=1, user_api="blas"):     # as plausible.fit: a few variables, one thread
        for src in read_sources(source):
            why = src.refused or _refusal(src, to)
            if why:
                skipped.append({"name": src.name, "skipped": why})
                continue
            if "glass" in src.surface:
                items.append(_as_asked(_glass(src, to), to))
                continue
            src_alb = _source_albedo(src.model)
            warn = list(src.warnings) + _conserving(src, src_alb)
            if to.startswith("mitsuba") or to in GLTF_SHAPED:
                c = _to_mitsuba(src, family, metric, src_alb, warn)
            else:
                c = _to_model(src, to, metric, starts, src_alb, warn)
            if looks:
                _add_looks(c, src.model)
            items.append(_as_asked(_dcc_warnings(_with_surface(c, src, to), to), to))
    return Conversion(to, metric, items, skipped)


def _as_asked(c: Converted, to: str) -> Converted:
    """``c`` with the target asked for (``gltf``, ``materialx``, ``usd``) and the model fitted for it
    (``gltf-pbr``) where the target is glTF-shaped (:data:`GLTF_SHAPED`); else ``c`` as it is."""
    if to in GLTF_SHAPED:
        c.target, c.model = to, GLTF_MODEL
    return c


def _refusal(src, to: str):
    """Why ``src`` cannot be converted to ``to`` (None: it can): glass goes to ``mitsuba`` and the glTF-shaped
    targets only (a reflection model, or a Mitsuba family forced, has no transmission)."""
    if "glass" in src.surface and to != "mitsuba" and to not in GLTF_SHAPED:
        return (f"material {src.name!r} is glass (Mitsuba's {src.surface['glass']}): it converts to 'mitsuba' or "
                f"'gltf', not to {to!r} (a reflection model has no transmission): skipped")
    return None


def _glass(src, to: str) -> Converted:
    """Glass as its statements give it (:func:`plausible.conversion.mtl.reading`): Mitsuba's smooth
    ``dielectric``/``thindielectric`` of index ``Ni`` transmitting ``Tf``, or glTF's
    ``KHR_materials_transmission`` (factor 1) with ``KHR_materials_ior`` and ``Tf`` as the base colour
    (glTF tints the transmission by it); not fitted (no error figures, no albedo)."""
    from .. import registry

    sf = src.surface
    notes = list(src.notes) + ["glass: converted by its statements, not fitted (no error figures)"]
    warnings = list(src.warnings)
    for stmt, value in src.textures.items():
        if to in GLTF_SHAPED and stmt in GLTF_TEXTURE_SLOTS:
            notes.append(f"{stmt} {value}: the glass's {GLTF_TEXTURE_SLOTS[stmt]} (glTF tints the transmission by "
                         f"the base colour)")
        else:
            _dropped(stmt, value, "glass is converted by its Ni and Tf", notes, warnings)
    if to in GLTF_SHAPED:
        params = {"base_color": sf["transmittance"], "metallic": 0.0, "roughness": 0.01}
        notes.append("glTF: KHR_materials_transmission 1 and KHR_materials_ior; roughness 0.01 (the model's "
                     "smallest), thin-walled (no KHR_materials_volume: the thickness of a mesh is unknown here)")
        return Converted(src.name, src.spec, "gltf", params, {}, {}, warnings, notes, dict(src.textures),
                         registry.make(GLTF_MODEL, **params), src.folder,
                         {"transmission": 1.0, "ior": float(sf["ior"])})
    d = {"type": sf["glass"], "int_ior": float(sf["ior"]), "ext_ior": 1.0}
    if any(x != 1.0 for x in sf["transmittance"]):
        d["specular_transmittance"] = {"type": "rgb", "value": list(sf["transmittance"])}
    return Converted(src.name, src.spec, f"mitsuba:{sf['glass']}", d, {}, {}, warnings, notes,
                     dict(src.textures), d, src.folder)


def _with_surface(c: Converted, src, to: str) -> Converted:
    """``c`` with what its source has beside its reflection (``src.surface``): the opacity ``d`` as
    Mitsuba's ``mask`` around the BSDF or glTF's alpha (``alphaMode BLEND``), ``map_d`` as the
    ``mask``'s opacity texture, the emission ``Ke`` as glTF's ``emissiveFactor``; what the target
    cannot hold is a warning."""
    sf = src.surface
    if not sf:
        return c
    mitsuba = isinstance(c.result, dict)
    if "opacity" in sf or "opacity_map" in sf:
        if mitsuba:
            opacity = ({"type": "bitmap", "filename": sf["opacity_map"], "raw": True} if "opacity_map" in sf
                       else float(sf["opacity"]))
            c.result = c.params = {"type": "mask", "opacity": opacity, "bsdf": c.result}
            c.notes.append(f"Mitsuba mask of opacity {sf.get('opacity_map', sf.get('opacity'))}"
                           + (" (map_d; d is not multiplied in)" if "opacity_map" in sf and "opacity" in sf else ""))
        elif to in GLTF_SHAPED:
            if "opacity" in sf:
                c.surface["alpha"] = float(sf["opacity"])
                c.notes.append(f"d {sf['opacity']:g}: glTF alphaMode BLEND, baseColorFactor alpha {sf['opacity']:g}")
            if "opacity_map" in sf:
                c.warnings.append(f"map_d {sf['opacity_map']}: dropped (glTF reads opacity from the base colour "
                                  f"texture's alpha only)")
        else:
            c.warnings.append(f"the opacity (d {sf.get('opacity', 1.0):g}, map_d {sf.get('opacity_map', '-')}) is "
                              f"dropped: a registered model has none")
    if "emission" in sf:
        ke = sf["emission"]
        if to in GLTF_SHAPED:
            c.surface["emissive"] = list(ke)
            c.notes.append(f"Ke {_colour(ke)}: glTF emissiveFactor" + (" (with KHR_materials_emissive_strength "
                                                                          f"{max(ke):g})" if max(ke) > 1 else ""))
        else:
            c.warnings.append(f"Ke {_colour(ke)} (emission) dropped: a BSDF does not emit; in Mitsuba give the "
                              f"shapes of this material an emitter {{'type': 'area', 'radiance': {{'type': 'rgb', "
                              f"'value': {list(ke)}}}}}")
    return c


def _dcc_warnings(c: Converted, to: str) -> Converted:
    """``c`` with what its target format (materialx: OpenPBR; usd: UsdPreviewSurface) cannot express of
    the fitted glTF material among its warnings (:func:`plausible.export.materialx.open_pbr_inputs`,
    :func:`plausible.export.usd.preview_inputs`; the ``gltf_pbr`` of a ``.mtlx`` is exact)."""
    if to == "materialx":
        from ..export.materialx import open_pbr_inputs as inputs
    elif to == "usd":
        from ..export.usd import preview_inputs as inputs
    else:
        return c
    c.warnings.extend(w for w in inputs(c.result, c.surface)[1] if w not in c.warnings)
    return c


def _colour(c) -> str:
    return " ".join(f"{float(x):g}" for x in c)


def _add_looks(c, source_model):
    """``c.looks``: the source and the fitted target (its constant colours: the fit's; textures
    aside) rendered side by side, the looks' warnings added to ``c.warnings``; a note instead
    where either cannot be rendered (no Mitsuba, a Python callable)."""
    from ..mitsuba.looks import compare_looks

    try:
        c.looks = compare_looks(source_model, c.fitted if c.fitted is not None else c.result)
    except (ValueError, ImportError) as e:
        c.notes.append(f"looks not rendered: {e}")
        return
    c.warnings.extend(c.looks.warnings)


def _to_mitsuba(src, family, metric, src_alb, warn):
    from . import mitsuba as CM

    notes = list(src.notes)
    probe = CM.probe_for(src.model)
    # the source's albedo at the probe's incidences: computed once, with the report's (CONSERVE_THETAS)
    target = CM.source_target(src.model, probe, src_alb[[CONSERVE_THETAS.index(t) for t in CM.PROBE_THETAS]])
    rd = lambertian_albedo(src.model, src_alb)
    if rd is not None and family in (None, "diffuse", GLTF_MODEL):
        family = family or "diffuse"
        r = _exact_diffuse(rd, family, metric, probe, target)
        notes.append(f"a Lambertian source (albedo {_colour(np.round(rd, 6))} at every incidence): "
                     + ("mitsuba:diffuse of that reflectance" if family == "diffuse" else
                        "glTF metallic 0, specular 0 (KHR_materials_specular), base colour that albedo: "
                        "exactly Lambertian"))
    elif family is None:
        r, family = _choose(src, metric, probe, target, src_alb, notes)
    else:
        r = CM.fit_family(src.model, family, metric, probe=probe, target=target, hard=True)
        notes.append(f"fitted with the albedo band as a constraint (within {CM.BAND_HARD} at 0/45/75 deg where "
                     f"the family can), the highlight held second")
        if family == GLTF_MODEL:
            r = metallic_decision(src.model, r, metric, probe, target, notes)
    textures = dict(src.textures)
    warn = list(warn)
    d, bakes = _with_textures(r.dict, family, textures, notes, warn)
    tgt_alb = CM.sampler_albedo(r.dict)
    alb = _albedo_report(src_alb, tgt_alb)
    warn = warn + _albedo_warnings(alb) + _trade_warning(r, alb, family)
    if family in CM.PLAUSIBLE_TYPES:
        from .. import registry

        model = registry.make(family, **CM.model_params(d))
        return Converted(src.name, src.spec, "gltf", CM.model_params(d), r.errors, alb, warn, notes, textures,
                         model, src.folder)
    return Converted(src.name, src.spec, f"mitsuba:{r.family}", d, r.errors, alb, warn, notes, textures, d,
                     src.folder, bakes=bakes, fitted=r.dict)


def _choose(src, metric, probe, target, src_alb, notes):
    """``(fit, family)``: the best candidate (:func:`.mitsuba.candidates`) by the figure minimised, of
    those that render what they evaluate to (:func:`degenerate`), each fitted with the albedo band as a
    constraint (``hard``: one fit a family, issue 40; before, a fit without it and a refit with it where
    the best missed the band); the choice noted."""
    from . import mitsuba as CM

    families, why = CM.candidates(src.model, src_alb)
    fits = _usable([CM.fit_family(src.model, f, metric, probe=probe, target=target, hard=True) for f in families],
                   probe, notes)
    r = min(fits, key=lambda x: x.figure)
    tried = ", ".join(f"{x.key} {x.figure:.3g} (albedo {x.band:.3f} off)" for x in fits)
    others = [x for x in fits if x.key not in CM.BAND_FAMILIES]
    if r.key in CM.BAND_FAMILIES and others:
        # kept only where the band needs it or the metric's own figure is lower too
        o = min(others, key=lambda x: x.figure)
        if o.band <= CM.BAND_KEEP and o.errors[metric] <= (1.0 + CM.BAND_KEEP_MARGIN) * r.errors[metric]:
            tried += (f"; {o.key} kept: within the band and of a {metric} figure at most "
                      f"{CM.BAND_KEEP_MARGIN:.0%} higher ({o.errors[metric]:.3g} against {r.errors[metric]:.3g})")
            r = o
    notes.append(f"mitsuba:{r.key} chosen: {why}; figure minimised (the albedo band as a constraint, within "
                 f"{CM.BAND_HARD} at 0/45/75 deg where a family can, the highlight held second): {tried}")
    return r, r.key


def lambertian_albedo(model, src_alb, tol: float = 1e-6):
    """The albedo (three channels) of a source that is exactly Lambertian -- every lobe it declares
    diffuse and its albedo that lobe's at every probed incidence, within ``tol`` (an MTL ``illum 0-1``,
    or ``Ks 0``) -- else None."""
    from .mitsuba import diffuse_albedo

    rd = diffuse_albedo(model)
    if not np.all(np.isfinite(rd)) or not np.all(np.abs(np.asarray(src_alb, float) - rd) <= tol):
        return None
    return np.clip(rd, 0.0, 1.0)


def _exact_diffuse(rd, family, metric, probe, target):
    """The exactly Lambertian target of albedo ``rd``: Mitsuba's ``diffuse``, or ``gltf-pbr`` with
    metallic 0 and specular 0 (its dielectric BRDF is then ``base_color / pi``), measured as a fit's
    result is (:func:`.mitsuba.measure`)."""
    from . import mitsuba as CM

    colour = {"type": "rgb", "value": [float(x) for x in rd]}
    d = ({"type": "diffuse", "reflectance": colour} if family == "diffuse" else
         {"type": GLTF_MODEL, "base_color": colour, "metallic": 0.0, "roughness": 1.0, "specular": 0.0})
    return CM.measure(d, family, probe, target, metric)


#: A fractional glTF metallic is kept only where it lowers the image error (HDR-FLIP of the candidate
#: rendered beside the source, :func:`plausible.compare_looks`) by this fraction against the better of
#: metallic 0 and 1 (each fitted with metallic fixed); else that end.  Where nothing can be rendered
#: (no Mitsuba), the figure minimised decides with the same margin.
METALLIC_MARGIN = 0.10


def _image_error(model, r):
    """HDR-FLIP of the glTF candidate ``r`` rendered beside ``model`` (:func:`plausible.compare_looks`);
    None where either cannot be rendered."""
    if model is None:
        return None
    from .. import registry
    from . import mitsuba as CM

    try:
        from ..mitsuba.looks import compare_looks

        return float(compare_looks(model, registry.make(GLTF_MODEL, **CM.model_params(r.dict))).flip)
    except (ValueError, ImportError, TypeError):
        return None


def metallic_decision(model, r, metric, probe, target, notes, margin: float = METALLIC_MARGIN):
    """The glTF material of the lowest image error (:func:`_image_error`; the figure minimised where
    nothing renders) of the ends -- the dielectric with KHR_materials_specular's factors, its lobe
    tinted as the source's (:func:`.mitsuba.gltf_dielectric`, :func:`.mitsuba.lobe_tint`), and the metal
    (metallic 1; the free fit ``r`` where it ended there) -- each fitted; a fractional metallic of ``r`` only where its image error is lower than the better
    end's by ``margin`` (a fraction: a fractional metallic mixes a metal into a dielectric) and by more than
    :data:`IMAGE_NOISE`, and an end that
    needs KHR_materials_specular over one that does not likewise and by more than :data:`IMAGE_NOISE` (a
    tinted dielectric with ``specular`` 1 is a metal's Schlick Fresnel exactly: on a tie the core material,
    which every viewer reads).  An end is
    never kept unjudged: the albedo band as a constraint (:data:`.mitsuba.BAND_HARD`) drove a plastic whose
    reflectance does not rise at grazing (an MTL ``Ks``) to metallic 1, a red plastic made a red metal."""
    from . import mitsuba as CM

    m = float(r.point.get("metallic", r.dict.get("metallic", 0.0)))
    # the free fit at metallic 1 is the metal end; at 0, a point of the dielectric end's grid
    tint = np.ones(3) if target is None else CM.lobe_tint(model, target[1][0])
    ends = [CM.fit_family(model, fam, metric, probe=probe, target=target, hard=r.hard) if fam else r
            for fam in (CM.gltf_dielectric(tint), None if m == 1.0 else CM.gltf_fixed_metallic(1.0))]
    scores = [_image_error(model, x) for x in [r] + ends]
    if all(x is not None for x in scores):
        what, (sr, *se) = "image error (HDR-FLIP beside the source)", scores
    else:
        what, sr, se = "figure minimised", r.figure, [x.figure for x in ends]
    k = int(np.argmin(se))
    core = [i for i, x in enumerate(ends) if not _extended(x)]
    if _extended(ends[k]) and core:     # KHR_materials_specular only where it lowers the score by the margin
        j = min(core, key=lambda i: se[i])
        floor = IMAGE_NOISE if what.startswith("image") else 0.0
        k = k if se[k] <= (1.0 - margin) * se[j] - floor else j
    e = ends[k]
    tried = ", ".join(f"{_gltf_label(x)} {s:.3g}" for x, s in zip(ends, se))
    if m in (0.0, 1.0):
        notes.append(f"{_gltf_label(e)} chosen by the {what}: {tried}")
        return e
    said = f"{what} {sr:.3g} at the fitted metallic {m:.3g}; {tried}"
    if sr <= (1.0 - margin) * se[k] - (IMAGE_NOISE if what.startswith("image") else 0.0):
        notes.append(f"metallic {m:.3g} kept: {said} (at least {margin:.0%} lower than the better end, and by more "
                     f"than the renders' noise)")
        return r
    notes.append(f"{_gltf_label(e)}: {said} (a fractional metallic is kept only where it is more "
                 f"than {margin:.0%} lower)")
    return e


#: A difference of image error (HDR-FLIP) below this is the renders' noise, not a choice: plausible's
#: Lambertian against Mitsuba's ``diffuse`` reads 0.019, 0.024 seed to seed (docs/looks.md); a glTF gold
#: against itself converted read 0.0037 as a metal and 0.0033 as the tinted dielectric equal to it.
IMAGE_NOISE = 0.02


def _extended(r) -> bool:
    """Whether the glTF fit ``r`` needs KHR_materials_specular (a factor other than 1)."""
    d = r.dict
    return any(k in d and np.any(np.asarray(d[k], float) != 1.0) for k in ("specular", "specular_color"))


def _gltf_label(r) -> str:
    d = r.dict
    spec = [f"{k} {' '.join(f'{v:.3g}' for v in np.atleast_1d(np.asarray(d[k], float)))}"
            for k in ("specular", "specular_color") if k in d and not isinstance(d[k], dict)]
    return f"metallic {float(d.get('metallic', 0.0)):g}" + (f" ({', '.join(spec)})" if spec else "")


#: Sample side of the check that a candidate renders what it evaluates to (:func:`degenerate`).
DEGENERATE_SIDE = 64


def degenerate(r, probe) -> str | None:
    """Why the fitted candidate ``r`` is never an answer, or None: its value on the probe is NaN,
    or Mitsuba's own sampler gives NaN or an albedo other than its evaluated one (by more than
    0.05 + 10 %) at 0, 45, 75 degrees -- a ``blendbsdf-tir`` whose coat has a zero colour evaluates
    to the conductor's lobe and samples to nothing."""
    from . import mitsuba as CM

    fc, alb = probe.measure(CM._load(r.dict))
    if not (np.all(np.isfinite(fc)) and np.all(np.isfinite(alb))):
        return f"{r.key}: evaluates to NaN"
    rows = [int(np.argmin(np.abs(probe.thetas - math.radians(t)))) for t in REPORT_THETAS]
    want = np.broadcast_to(alb[rows], (len(rows), 3))
    got = CM.sampler_albedo(r.dict, side=DEGENERATE_SIDE)
    if not np.all(np.isfinite(got)):
        return f"{r.key}: its sampler gives NaN"
    if np.any(np.abs(got - want) > 0.05 + 0.1 * want):
        return (f"{r.key}: its sampler's albedo ({_colour(np.round(got.max(axis=1), 3))} at 0/45/75 degrees) is not "
                f"its evaluated one ({_colour(np.round(want.max(axis=1), 3))}): it renders other than it evaluates")
    return None


def _usable(fits, probe, notes):
    """``fits`` without the degenerate ones (:func:`degenerate`, each noted); all of them where none is usable."""
    keep = []
    for f in fits:
        why = degenerate(f, probe)
        if why:
            notes.append(f"candidate rejected: {why}")
        else:
            keep.append(f)
    return keep or fits


#: Which Mitsuba parameter an MTL texture replaces, per family.
TEXTURE_SLOTS = {"map_Kd": {"diffuse": "reflectance", "roughplastic": "diffuse_reflectance",
                            "principled": "base_color", "blendbsdf": "bsdf_0.reflectance",
                            "blendbsdf-tir": "bsdf_0.diffuse_reflectance"},
                 "map_Ks": {"roughconductor": "specular_reflectance", "blendbsdf": "bsdf_1.specular_reflectance",
                            "blendbsdf-tir": "bsdf_1.specular_reflectance"}}


def _dropped(stmt, value, why, notes, warnings):
    """Say that the texture statement ``stmt`` (file ``value``) is dropped, and ``why``: a warning, as a user
    sees it go, or a note for those of :data:`plausible.conversion.mtl.NOTED_TEXTURES`."""
    from .mtl import NOTED_TEXTURES

    (notes if stmt in NOTED_TEXTURES else warnings).append(f"{stmt} {value}: dropped, carried by reference only "
                                                           f"({why})")


def _with_textures(d, family, textures, notes, warn):
    """``(dict, bakes)``: ``d`` with its slots' bitmaps (:data:`TEXTURE_SLOTS`) and the bakes ``Kd x
    map_Kd`` (:attr:`Converted.bakes`: slot -> (statement, fitted colour)); a texture no slot takes is
    a warning (a user sees it go), or noted (:data:`plausible.conversion.mtl.NOTED_TEXTURES`)."""
    import copy

    from . import mitsuba as CM

    def dropped(stmt, where):
        _dropped(stmt, textures[stmt], f"no {where} takes it", notes, warn)

    bakes = {}
    d = copy.deepcopy(d)
    if family == GLTF_MODEL:
        for stmt in textures:
            if stmt in GLTF_TEXTURE_SLOTS:
                notes.append(f"{stmt} {textures[stmt]}: the .gltf material's {GLTF_TEXTURE_SLOTS[stmt]} (times the "
                             f"fitted baseColorFactor, as MTL multiplies {stmt} by Kd; the fit used the constant colour)")
            elif stmt != "map_d":        # map_d: the opacity (_with_surface)
                dropped(stmt, "glTF texture")
        return d, bakes
    for stmt, slots in TEXTURE_SLOTS.items():
        if stmt in textures and family in slots:
            key = slots[family]
            colour = CM.get_entry(d, key)["value"]
            notes.append(f"{stmt} {textures[stmt]}: a bitmap texture of the fitted {key} {_colour(np.round(colour, 4))} "
                         f"times the texture, baked beside the output (as MTL multiplies {stmt} by its colour)")
            CM.set_entry(d, key, {"type": "bitmap", "filename": textures[stmt]})
            bakes[key] = (stmt, [float(x) for x in colour])
    for stmt in textures:
        if (stmt not in TEXTURE_SLOTS or family not in TEXTURE_SLOTS[stmt]) and stmt != "map_d":
            dropped(stmt, f"{family} parameter")
    return d, bakes


#: How far above 1 the target's measured albedo (its sampler's estimate, standard error below
#: 1e-3) may be before the report warns that the target gains energy.
GAIN_TOLERANCE = 5e-3


def _albedo_warnings(alb):
    """A warning naming every incidence where the target is beyond :data:`TOLERANCE`, with
    the difference and both albedos in the channel of the largest difference; and one where
    the target's own albedo exceeds 1 (by more than :data:`GAIN_TOLERANCE`): it gains energy,
    whatever the source (Mitsuba's ``principled`` and glTF's BRDF can, at grazing incidence)."""
    out = []
    gain = [(t, max(v["target"])) for t, v in alb.items() if max(v["target"]) > 1.0 + GAIN_TOLERANCE]
    if gain:
        out.append("the target is not energy conserving: its albedo exceeds 1 at "
                   + ", ".join(f"{t} degrees ({a:.3f})" for t, a in gain))
    bad = [(t, v) for t, v in alb.items() if v["max_abs_difference"] > TOLERANCE]
    if not bad:
        return out

    def one(t, v):
        c = int(np.argmax(np.abs(v["difference"])))
        return (f"{t} degrees ({v['max_abs_difference']:.3f}: source {v['source'][c]:.3f}, target "
                f"{v['target'][c]:.3f} in channel {c})")

    return ["the target's albedo differs from the source's by more than "
            f"{TOLERANCE} at " + ", ".join(one(t, v) for t, v in bad)
            + ": the target family cannot follow the source's albedo curve"] + out


def _trade_warning(r, alb, family) -> list:
    """One warning where the fitted target ``r`` (a :class:`.mitsuba.FamilyFit`) keeps its predicted
    highlight (:attr:`.mitsuba.FamilyFit.peak_ratios`) outside compare_looks' band at some light angle:
    the family cannot hold the source's albedo (the fit's constraint, :data:`TOLERANCE` at 0/45/75 deg)
    and its highlight together, and the warning says which is kept and which lost or invented."""
    from ..mitsuba.looks import HIGHLIGHT_BAND, LIGHT_ANGLES

    lo, hi = HIGHLIGHT_BAND
    bad = [(a, q) for a, q in zip(LIGHT_ANGLES, r.peak_ratios) if not lo <= q <= hi]
    if not bad:
        return []
    kept = all(v["max_abs_difference"] <= TOLERANCE for v in alb.values())
    what = ", ".join(f"{'lost' if q < lo else 'invented'} at {a:g} deg ({q:.3g}x the source's)" for a, q in bad)
    return [(f"highlight traded for the albedo: {family} cannot hold both; the albedo kept (within {TOLERANCE} "
             f"at 0/45/75 deg), the highlight " if kept else
             f"highlight and albedo both missed: {family} cannot hold either; the highlight ") + what
            + " (predicted from the fit's bases; compare_looks renders it)"]


def _to_model(src, name, metric, starts, src_alb, warn):
    from ..analysis import albedo_curve
    from ..fitting import fit
    from ..fitting.fit import BoundWarning, UnconstrainedWarning

    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always", UnconstrainedWarning)
        warnings.simplefilter("always", BoundWarning)
        r = fit(name, src.model, metric, starts=starts)
    notes = list(src.notes) + [str(w.message) for w in caught if issubclass(w.category, UnconstrainedWarning)]
    notes += r.notes
    # a parameter at an end of its range: a warning of the conversion (the report's and the command's)
    warn = warn + [str(w.message) for w in caught if issubclass(w.category, BoundWarning)]
    a = np.asarray(albedo_curve(r.model, thetas_deg=REPORT_THETAS).value, float)
    tgt_alb = np.broadcast_to(a.reshape(len(REPORT_THETAS), -1), (len(REPORT_THETAS), 3))
    alb = _albedo_report(src_alb, tgt_alb)
    params = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in r.params.items()}
    from .. import registry

    params = {k: (registry.spec_of(v) if hasattr(v, "eval") else v) for k, v in params.items()}
    return Converted(src.name, src.spec, name, params, dict(r.errors), alb, warn + _albedo_warnings(alb), notes,
                     dict(src.textures), r.model, src.folder)


def albedo_check(source_model, bsdf_dict: dict, tolerance: float = TOLERANCE):
    """``(holds, differences)``: whether the albedo of the Mitsuba BSDF ``bsdf_dict``
    by Mitsuba's own sampler (:func:`.mitsuba.sampler_albedo`) is within ``tolerance``
    (every channel) of ``source_model``'s (accurate integrator) at 0, 45 and 75
    degrees; ``differences`` (3, 3): target minus source per incidence and channel."""
    from ..analysis import albedo_curve
    from .mitsuba import sampler_albedo

    a = np.asarray(albedo_curve(source_model, thetas_deg=REPORT_THETAS).value, float)
    a = np.broadcast_to(a.reshape(len(REPORT_THETAS), -1), (len(REPORT_THETAS), 3))
    d = sampler_albedo(bsdf_dict) - a
    return bool(np.all(np.abs(d) <= tolerance)), d


def mitsuba_xml(dicts: dict) -> str:
    """A Mitsuba 3 scene fragment: one ``<bsdf type=... id=NAME>`` per dict (floats,
    ``<rgb>``, ``<boolean>``, ``<string>``, a ``bitmap`` as a nested ``<texture>``, a
    nested BSDF, ``blendbsdf``'s ``bsdf_0``/``bsdf_1``, as a nested ``<bsdf>``)."""
    lines = ['<scene version="3.0.0">']
    for name, d in dicts.items():
        lines += _xml_element("bsdf", d, f" id={quoteattr(name)}", "    ")
    lines.append("</scene>")
    return "\n".join(lines) + "\n"


def quoteattr(text) -> str:
    """``text`` as a double-quoted XML attribute value (``xml.sax.saxutils.quoteattr``'s escapes
    without its import, which pulls in ``urllib.request``: 78 ms at ``import plausible``)."""
    t = str(text).replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;").replace('"', "&quot;")
    return '"' + t.replace("\n", "&#10;").replace("\r", "&#13;").replace("\t", "&#9;") + '"'


def _xml_element(tag, d, attrs, pad):
    out = [f"{pad}<{tag} type={quoteattr(d['type'])}{attrs}>"]
    for k, v in d.items():
        if k == "type":
            continue
        if isinstance(v, dict) and v.get("type") not in ("rgb", "bitmap"):
            out += _xml_element("bsdf", v, f" name={quoteattr(k)}", pad + "    ")
        else:
            out.append(pad + "    " + _xml_value(k, v))
    out.append(f"{pad}</{tag}>")
    return out


def _xml_value(k, v):
    if isinstance(v, dict) and v.get("type") == "rgb":
        val = ", ".join(f"{x:.9g}" for x in np.broadcast_to(np.asarray(v["value"], float), (3,)))
        return f"<rgb name={quoteattr(k)} value={quoteattr(val)}/>"
    if isinstance(v, dict) and v.get("type") == "bitmap":
        raw = '<boolean name="raw" value="true"/>' if v.get("raw") else ""
        return (f"<texture type=\"bitmap\" name={quoteattr(k)}><string name=\"filename\" "
                f"value={quoteattr(v['filename'])}/>{raw}</texture>")
    if isinstance(v, bool):
        return f"<boolean name={quoteattr(k)} value=\"{str(v).lower()}\"/>"
    if isinstance(v, (int, float)):
        return f"<float name={quoteattr(k)} value={quoteattr(f'{float(v):.17g}')}/>"
    return f"<string name={quoteattr(k)} value={quoteattr(str(v))}/>"
