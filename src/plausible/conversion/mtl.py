"""Wavefront ``.mtl`` files read as plausible models.

A material library (P. Bourke's transcription of the Alias|Wavefront *MTL*
specification, ``paulbourke.net/dataformats/mtl``) holds ``newmtl NAME``
blocks of statements; the ones that describe reflection are ``Kd`` (diffuse
colour), ``Ks`` (specular colour), ``Ns`` (specular exponent, 0-1000) and
``illum`` (the illumination model, 0-10).  The reading (``docs/convert.md``
gives the reasons):

* ``illum 0`` (colour, no lighting) and ``illum 1`` (diffuse): Lambertian,
  ``f = Kd / pi`` (``lambertian:rd=Kd``); a ``Ks`` there is unused by the
  model and noted.
* ``illum 2`` (diffuse and highlight): the specification's colour is
  ``Kd sum_j (N.L_j) I_j + Ks sum_j (N.H_j)^Ns I_j`` -- the highlight has no
  ``N.L``, so as a BRDF (radiance ``f I cos(theta_l)`` per light) it is
  ``Ks (N.H)^Ns / (N.L)``.  The only reciprocal BRDF that agrees with it up to a
  function of the view, ``Ks (N.H)^Ns g(N.V) / (N.L)``, has ``g = k / (N.V)``
  (``g(v) / l = g(l) / v``): ``k Ks (N.H)^Ns / ((N.L)(N.V))``, the microfacet
  form -- Blinn 1977's own, ``D G F / (N.E)`` per unit light, whose ``D1`` is
  ``(N.H)^c`` and which the specification cites (BLIN77).  So the highlight is
  read as ``Ks D(h) G / (4 (N.L)(N.V))`` with ``D`` the normalised Blinn
  distribution ``(Ns + 2) / (2 pi) (N.H)^Ns`` and Blinn's (Torrance-Sparrow's)
  V-groove ``G``, ``F = 1`` (``Ks`` the facets' reflectance): the model
  ``cook-torrance:distribution=blinn:m=sqrt(2/(Ns+2)):rs=Ks:fresnel=none``
  (:func:`plausible.models.cook_torrance.blinn_d`).  Its albedo is at most ``Ks``
  at every incidence (measured for ``Ns`` from 0 to 10^5), so ``Kd + Ks <= 1`` per
  channel conserves energy everywhere; it is nearly flat in incidence, about
  ``Ks`` for ``Ns >= 20`` and less for broad highlights (``0.80 Ks`` at normal
  incidence for ``Ns = 5``, ``0.375 Ks`` for ``Ns = 0``: masking, and facets that
  reflect below the horizon; the usual normalised Blinn-Phong, the same without ``G``, gives
  ``0.50 Ks`` there, and creates energy at grazing incidence: 1.93 ``Ks`` at 75 degrees, 5.74 at 85
  for ``Ns = 0`` -- the reason ``G`` is kept, besides Blinn having it; docs/convert.md).  The reciprocal Blinn lobe ``Ks c(Ns) (N.H)^Ns``
  (no division by the cosines) that an earlier version read falls with
  incidence as ``cos^2(theta)`` for sharp highlights (0.60, 0.32, 0.08 at 0, 45,
  75 degrees for ``Ks = 0.6``, ``Ns = 30``): it drops both ``1/cos`` that the
  specification's missing ``N.L`` and reciprocity put there.
* ``illum 3`` (``illum 2`` plus ray-traced reflection weighted by ``Ks``):
  the same sum: the mirror reflection of ``illum 3`` and its highlight are one
  lobe in a physical reading (the highlight is the blurred reflection of the
  lights; adding a mirror term of weight ``Ks`` besides counts ``Ks`` twice),
  and no Fresnel factor (the specification gives Fresnel to ``illum 5`` and
  ``7`` only).
* ``illum 5`` (reflection with Fresnel, ray trace on): the same lobe with Schlick's Fresnel of
  ``R0 = Ks``; ``illum 8`` (reflection on, ray trace off): the same as 3.
* **Glass** (``illum 4`` and ``9``, "glass on": a thin pane that reflects and transmits without
  refracting; ``illum 6`` and ``7``, "refraction on"): not a reflector, so not fitted:
  :class:`Reading` gives ``surface["glass"]`` (``"thindielectric"`` or ``"dielectric"``), the index
  ``Ni`` (1.5 where it is missing or below 1, warned) and the filter ``Tf`` (the transmittance);
  the conversion writes Mitsuba's ``thindielectric``/``dielectric`` and glTF's
  ``KHR_materials_transmission`` with ``KHR_materials_ior``.  ``illum 10`` (a shadow catcher) has
  no reflection to convert: refused (:attr:`Reading.refused`), the rest of the file converted.
* **Dissolve** ``d`` (or ``Tr = 1 - d``): below 1 on a reflector, ``surface["opacity"]`` (Mitsuba's
  ``mask``, glTF's ``alphaMode BLEND``); ``d 0`` (``Tr 1``), fully transparent, is what several
  exporters write for *opaque* (``Tr`` taken for ``d``): read as opaque, with a warning.  ``map_d``:
  ``surface["opacity_map"]``.  ``Ke`` (emission, not 0): ``surface["emission"]`` (glTF's
  ``emissiveFactor``; Mitsuba has no emitter in a BSDF: a warning).
* **The PBR extension** (``Pr``, ``Pm``; Blender's export): glTF's metallic-roughness BRDF of base
  colour ``Kd`` (:func:`_pbr_spec`); ``Ks``, ``Ns`` and ``illum`` are then not read.
* ``Ka`` (ambient) is not a property of a reflector: ignored with a note.  Every ``map_*`` (and
  ``bump``, ``norm``, ``disp``, ``decal``, ``refl``) is carried by reference: its file name (and
  options) in :attr:`MtlMaterial.textures`, the file name alone (what follows the options, spaces
  kept) in :attr:`MtlMaterial.texture_files`.

Defaults where a statement is missing: ``Kd = Ks = 0``, ``Ns = 0``, ``illum 2`` (each noted);
``Kd`` missing beside a ``map_Kd`` is 1 (the map is the colour: Blender 4 writes no ``Kd`` then).
A bad value raises ValueError naming the file, the line, the material and the statement, with the
allowed range; what real exporters write beside the specification (a title line before the first
``newmtl``, a material defined twice, ``illum 2.0``, ``Ni -1``, ``map_Bump``, the PBR extension's
``Pr``/``Pm``/...) is read with a note or a warning (:func:`read_mtl`).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

__all__ = ["ILLUM", "MtlMaterial", "NS_MAX", "Reading", "as_model", "highlight_spec", "read_mtl", "reading"]

#: The illumination models of the specification, and what each means there.
ILLUM = {0: "colour on, ambient off", 1: "colour on, ambient on (diffuse)",
         2: "highlight on (diffuse + Blinn-Phong highlight)",
         3: "reflection on, ray trace on (illum 2 + mirror reflection)",
         4: "transparency: glass on, reflection: ray trace on",
         5: "reflection: Fresnel on and ray trace on",
         6: "transparency: refraction on, reflection: Fresnel off and ray trace on",
         7: "transparency: refraction on, reflection: Fresnel on and ray trace on",
         8: "reflection on and ray trace off",
         9: "transparency: glass on, reflection: ray trace off",
         10: "casts shadows onto invisible surfaces"}
#: Glass: the Mitsuba BSDF of each transparent illumination model (a pane without refraction:
#: ``thindielectric``; refraction on: ``dielectric``).
GLASS = {4: "thindielectric", 9: "thindielectric", 6: "dielectric", 7: "dielectric"}
#: The index of refraction of glass where ``Ni`` is missing or below 1 (crown glass).
GLASS_IOR = 1.5
#: Largest ``Ns`` read (the range of ``reciprocal-blinn``'s ``n``; the specification's is 0-1000).
NS_MAX = 1e6
#: Statements noted and ignored.
IGNORED = {"Ka": "ambient colour: not a property of a reflector (ignored)",
           "sharpness": "reflection-map sharpness (ignored)"}
TEXTURES = ("bump", "norm", "disp", "decal", "refl")


@dataclass
class MtlMaterial:
    """One ``newmtl`` block: its colours, exponent, illumination model, textures
    (statement -> the rest of its line: options and file name) and notes."""

    name: str
    line: int
    Kd: np.ndarray = field(default_factory=lambda: np.zeros(3))
    Ks: np.ndarray = field(default_factory=lambda: np.zeros(3))
    Ns: float = 0.0
    illum: int = 2
    textures: dict = field(default_factory=dict)
    notes: list = field(default_factory=list)
    given: set = field(default_factory=set)
    #: Optical density (index of refraction), None where not given.
    Ni: float | None = None
    #: Dissolve (opacity, 1 opaque): ``d``, else ``1 - Tr``.
    d: float = 1.0
    #: Emission colour.
    Ke: np.ndarray = field(default_factory=lambda: np.zeros(3))
    #: Transmission filter (the colour glass lets through), None where not given.
    Tf: np.ndarray | None = None
    #: What the reading drops or changes that a user must know (the report's warnings).
    warnings: list = field(default_factory=list)
    #: The dissolve statements as given (``d``, ``Tr``: statement -> value).
    dissolve: dict = field(default_factory=dict)
    #: The PBR extension's statements read (:data:`PBR_READ`: statement -> value).
    pbr: dict = field(default_factory=dict)

    @property
    def texture_files(self) -> dict:
        """Statement -> file name (what follows the statement's options, :func:`texture_file`)."""
        return {k: texture_file(v.split()) for k, v in self.textures.items() if texture_file(v.split())}


#: The options of a texture statement (``map_Kd -s 1 1 1 wood.png``) and how many words each takes
#: (``-o``, ``-s``, ``-t``: one to three numbers), from the specification.
TEXTURE_OPTIONS = {"-blendu": 1, "-blendv": 1, "-bm": 1, "-boost": 1, "-cc": 1, "-clamp": 1, "-imfchan": 1,
                   "-mm": 2, "-o": 3, "-s": 3, "-t": 3, "-texres": 1, "-type": 1,
                   "-colorspace": 1}      # tinyobjloader's (map_Kd -colorspace sRGB wood.png)

#: The statements read, by their lower-case spelling: exporters vary the case (Blender writes
#: ``map_Bump``, some write ``map_kd``), and the reading keys on the specification's spelling.
CANONICAL = {k.lower(): k for k in (
    "newmtl", "Kd", "Ks", "Ka", "Ke", "Ns", "Ni", "Tf", "Tr", "d", "illum", "sharpness",
    "map_Ka", "map_Kd", "map_Ks", "map_Ke", "map_Ns", "map_d", "map_bump", "bump", "norm", "map_norm",
    "disp", "map_disp", "decal", "map_decal", "refl", "map_refl",
    "Pr", "Pm", "Ps", "Pc", "Pcr", "aniso", "anisor", "map_Pr", "map_Pm", "map_Ps")}
#: The physically based extension of MTL (Clara.io's, written by Blender and others): statement ->
#: what it holds.  ``Pr`` and ``Pm`` are read (:data:`PBR_READ`: the material is then glTF's
#: metallic-roughness BRDF, :func:`reading`); the others are warned about, not read.
PBR = {"Pr": "roughness", "Pm": "metallic", "Ps": "sheen", "Pc": "clearcoat thickness",
       "Pcr": "clearcoat roughness", "aniso": "anisotropy", "anisor": "anisotropy rotation"}
PBR_READ = ("Pr", "Pm")
#: The roughness of a PBR material without ``Pr`` or ``Ns`` (Blender's Principled BSDF default).
PBR_ROUGHNESS = 0.5


def _is_number(w) -> bool:
    try:
        float(w)
    except ValueError:
        return False
    return True


def _is_option(w) -> bool:
    return len(w) > 1 and w[0] == "-" and w[1:].isalpha()


def _skip_option(words, i) -> int:
    """The index after the option ``words[i]`` and its arguments (:data:`TEXTURE_OPTIONS`)."""
    n = TEXTURE_OPTIONS.get(words[i].lower())
    i += 1
    if n in (1, 2):
        return i + n
    k = 0          # -o/-s/-t: up to three numbers; an unknown option: the numbers after it
    while i < len(words) and k < (n or len(words)) and _is_number(words[i]):
        i, k = i + 1, k + 1
    if n is None and k == 0 and i < len(words) - 1 and not _is_option(words[i]):
        i += 1     # an unknown option with a word argument (Blender's "-imgchan b"), a name after it
    return i


def _options_only(words) -> bool:
    """``words`` are known options and their arguments, nothing else."""
    i = 0
    while i < len(words):
        if words[i].lower() not in TEXTURE_OPTIONS:
            return False
        i = _skip_option(words, i)
    return i == len(words)


def texture_file(words) -> str:
    """The file name of a texture statement's ``words``: what follows its options
    (:data:`TEXTURE_OPTIONS`), spaces kept (``map_Kd -s 1 1 1 my wood.png`` -> ``my wood.png``);
    ``""`` where nothing follows.  An option not in the table is skipped with the numbers after it (or,
    with none, the one word after it where a name still follows); known options written after the
    name (``bump.jpg -bm 1.5``) are not part of it."""
    i, words = 0, list(words)
    while i < len(words) and _is_option(words[i]):
        i = _skip_option(words, i)
    for j in range(i + 1, len(words)):
        if words[j].lower() in TEXTURE_OPTIONS and _options_only(words[j:]):
            return " ".join(words[i:j])
    return " ".join(words[i:])


def _numbers(where, key, words, lo, hi):
    try:
        vals = [float(w) for w in words]
    except ValueError:
        vals = []
    if not vals or len(vals) not in (1, 3) or not all(math.isfinite(v) and lo <= v <= hi for v in vals):
        raise ValueError(f"{where}: {key} must be one number or three numbers (r g b) in [{lo:g}, {hi:g}], "
                         f"got {' '.join(words)!r}")
    return np.array(vals * 3 if len(vals) == 1 else vals, float)


def _float(words):
    """The one finite number of ``words``, else None."""
    try:
        v = float(words[0]) if len(words) == 1 else math.nan
    except ValueError:
        return None
    return v if math.isfinite(v) else None


def _number(where, key, words, lo, hi) -> float:
    v = _float(words)
    if v is None or not lo <= v <= hi:
        raise ValueError(f"{where}: {key} must be one number in [{lo:g}, {hi:g}], got {' '.join(words)!r}")
    return v


def _illum(where, words):
    x = _float(words)
    n = int(x) if x is not None and x == int(x) else None      # "2" and "2.0" (Tinkercad writes 0.0)
    if n is None:
        raise ValueError(f"{where}: illum must be one integer (0-10), got {' '.join(words)!r}")
    if n not in ILLUM:
        raise ValueError(f"{where}: illum must be one of the specification's illumination models 0-10, got {n}")
    return n


def _statement(cur: MtlMaterial, key: str, words: list, where: str, ln: int) -> None:
    """Read one statement ``key words`` (line ``ln``, ``where`` for errors) into the material ``cur``."""
    if key in ("Kd", "Ks"):
        if words and words[0] in ("spectral", "xyz"):
            raise ValueError(f"{where}: {key} {words[0]} is not read; give {key} as r g b in [0, 1]")
        setattr(cur, key, _numbers(where, key, words, 0.0, 1.0))
    elif key == "Ns":
        cur.Ns = _number(where, "Ns", words, 0.0, NS_MAX)
        if cur.Ns > 1000:
            cur.notes.append(f"Ns = {cur.Ns:g} is above the MTL specification's range 0-1000 (read as given)")
    elif key == "illum":
        cur.illum = _illum(where, words)
    elif key in ("d", "Tr"):
        if words and words[0] == "-halo":
            cur.notes.append(f"{key} -halo: the dissolve's dependence on the view is not read (a constant)")
            words = words[1:]
        cur.dissolve[key] = _number(where, key, words, 0.0, 1.0)
    elif key == "Ni":
        v = _float(words)
        if v is None or v > 10.0:
            raise ValueError(f"{where}: Ni must be one number in [0, 10] (the index of refraction; 0 or "
                             f"below, which exporters write for 'not set', is noted, and glass reads 1.5), "
                             f"got {' '.join(words)!r}")
        cur.Ni = v      # only glass reads it (Reading.surface): below 1 it warns and reads 1.5
        if v <= 0.0:
            cur.notes.append(f"Ni {v:g} is outside the specification's range 0.001-10")
    elif key in PBR_READ:
        cur.pbr[key] = _number(where, key, words, 0.0, 1.0)
    elif key in PBR:    # a zero (no sheen, no coat, no anisotropy) is the BRDF read: a note
        (cur.notes if _float(words) == 0.0 else cur.warnings).append(
            f"{key} {' '.join(words)} (MTL's physically based extension: {PBR[key]}) is not read: a PBR "
            f"material is read as glTF's metallic-roughness BRDF of Kd, Pm and Pr")
    elif key in ("Ke", "Tf"):
        if words and words[0] in ("spectral", "xyz"):
            raise ValueError(f"{where}: {key} {words[0]} is not read; give {key} as r g b")
        setattr(cur, key, _numbers(where, key, words, 0.0, 1e6 if key == "Ke" else 1.0))
    elif key.startswith("map_") or key in TEXTURES:
        if not texture_file(words):
            raise ValueError(f"{where}: {key} needs a file name (after its options), got {' '.join(words)!r}")
        cur.textures[key] = " ".join(words)
    elif key in IGNORED:
        cur.notes.append(f"{key}: {IGNORED[key]}")
    else:
        cur.notes.append(f"line {ln}: statement {key!r} is not read (ignored)")
    cur.given.add(key)


def read_mtl(path) -> list[MtlMaterial]:
    """Every ``newmtl`` of the ``.mtl`` file ``path``, in file order.

    The text: UTF-8, UTF-16 with its byte-order mark, else Windows-1252 or Latin-1 (noted; :func:`_text`).
    ValueError for a missing or unreadable file, a value out of its range (``Kd``, ``Ks`` in
    [0, 1]; ``Ns`` in [0, 1e6]; ``illum`` one of 0-10), or a file with no material.  What
    exporters write that the specification does not have is read with a note or a warning, not
    refused: statements before the first ``newmtl`` (a title line), a second material of one name
    (the first kept), ``illum 2.0``, ``Ni -1``, statements in another case (``map_Bump``), the PBR
    extension's statements (:data:`PBR`: ``Pr`` and ``Pm`` read, :func:`_pbr_spec`; the others warned
    where not zero).
    """
    text, encoding = _text(path)
    out: list[MtlMaterial] = []
    cur = None
    before, again = [], []      # statements before the first newmtl; materials defined again
    for ln, raw in enumerate(re.split(r"\r\n|\r|\n", text), 1):
        s = raw.split("#", 1)[0].strip()
        if not s:
            continue
        key, *words = s.split()
        key = CANONICAL.get(key.lower(), key)
        where = f"{path}:{ln}" + (f" (material {cur.name!r})" if cur else "")
        if key == "newmtl":
            if not words:
                raise ValueError(f"{where}: newmtl needs a name")
            name = " ".join(words)
            cur = MtlMaterial(name, ln)
            first = next((m for m in out if m.name == name), None)
            if first is None:
                out.append(cur)
            else:           # read (its values checked) and set aside
                again.append((first, cur))
            continue
        if cur is None:     # a title line some exporters write (Mineways: "Wavefront OBJ material file")
            before.append((ln, s, key in CANONICAL.values()))
            continue
        _statement(cur, key, words, where, ln)
    if not out:
        raise ValueError(f"MTL file {str(path)!r} defines no material (no newmtl line)")
    for ln, text_, known in before:
        (out[0].warnings if known else out[0].notes).append(
            f"line {ln}: {text_!r} before the first newmtl belongs to no material (not read)")
    for first, later in again:
        first.warnings.append(f"material {first.name!r} is defined again at line {later.line}: that definition is "
                              f"not read (the first is kept, as tinyobjloader does; some loaders keep the last)")
    if encoding != "utf-8":
        for m in out:
            m.notes.append(f"the file is not UTF-8: read as {encoding}")
    for m in out:
        _defaults(m)
    return out


def _defaults(m: MtlMaterial) -> None:
    """The defaults of missing statements (noted) and the dissolve of ``d`` / ``Tr``."""
    if "Kd" not in m.given and "map_Kd" in m.textures:
        m.Kd = np.ones(3)
        m.notes.append("Kd not given beside map_Kd: Kd 1 (MTL multiplies map_Kd by Kd; the map is the colour)")
    for key, default in (("Kd", "0"), ("Ks", "0"), ("Ns", "0"), ("illum", "2")):
        if key not in m.given and not (key == "Kd" and "map_Kd" in m.textures):
            m.notes.append(f"{key} not given: {default}")
    d, tr = m.dissolve.get("d"), m.dissolve.get("Tr")
    if d is not None and tr is not None and abs(d - (1.0 - tr)) > 1e-9:
        m.notes.append(f"d {d:g} and Tr {tr:g} disagree (Tr = 1 - d): d read")
    m.d = d if d is not None else (1.0 - tr if tr is not None else 1.0)
    if m.d == 0.0 and m.illum not in GLASS:          # glass: d is not read (its transparency is the glass)
        said = "d 0" if d is not None else "Tr 1"
        m.warnings.append(f"{said} (fully transparent) read as opaque: exporters write it for opaque materials "
                          f"(Tr taken for d); the material would be invisible")
        m.d = 1.0


def _text(path) -> tuple[str, str]:
    """The text of the file ``path`` and its encoding: UTF-16 where it starts with its byte-order
    mark, else UTF-8 (a byte-order mark skipped), else Windows-1252, else Latin-1 (the encodings of older exporters: every byte is a character, so an
    accented name reads as one); ValueError for a missing or unreadable file, or one with NUL bytes
    (not text).  Lines end at ``\\n``, ``\\r\\n`` or ``\\r`` only (not at Latin-1's NEL, 0x85)."""
    try:
        data = Path(path).read_bytes()
    except FileNotFoundError:
        raise ValueError(f"MTL file {str(path)!r} not found") from None
    except OSError as e:
        raise ValueError(f"MTL file {str(path)!r} cannot be read: {e.strerror or e}") from None
    if data[:2] in (b"\xff\xfe", b"\xfe\xff"):        # a UTF-16 byte-order mark (Windows' "Unicode")
        try:
            return data.decode("utf-16"), "UTF-16"
        except UnicodeDecodeError as e:
            raise ValueError(f"MTL file {str(path)!r} cannot be read as UTF-16 (its byte-order mark): {e}") from None
    if b"\0" in data:
        raise ValueError(f"MTL file {str(path)!r} is not a text file (it holds NUL bytes)")
    for encoding, codec in (("utf-8", "utf-8-sig"), ("Windows-1252", "cp1252"), ("Latin-1", "latin-1")):
        try:
            return data.decode(codec), encoding
        except UnicodeDecodeError:
            continue
    raise AssertionError("Latin-1 decodes every byte")   # pragma: no cover


def _spec_colour(c) -> str:
    return ",".join(repr(float(x)) for x in c)


def highlight_spec(Ks, Ns, fresnel: str = "none") -> str:
    """The spec of MTL's highlight ``Ks``, ``Ns`` as read (module docstring): the
    microfacet model of the normalised Blinn distribution of exponent ``Ns``
    (slope ``m = sqrt(2 / (Ns + 2))``), V-groove masking, no Fresnel (``fresnel="schlick"``:
    Schlick's of ``R0 = Ks``, ``illum 5``)."""
    m = math.sqrt(2.0 / (float(Ns) + 2.0))
    return f"cook-torrance:distribution=blinn:m={m!r}:rs={_spec_colour(Ks)}:fresnel={fresnel}:geometry=vgroove"


#: Texture statements a conversion drops with a note only (the ambient colour is not a property of a
#: reflector); every other texture it drops is a warning (what a user sees changes: the relief, the
#: cut-outs, the decals, the emission, the roughness).
NOTED_TEXTURES = ("map_Ka",)


@dataclass
class Reading:
    """The reading of one material (module docstring): the plausible ``model`` of its reflection
    (a :class:`~plausible.models.sum.Sum`), its ``spec``, ``notes`` and ``warnings``, what a
    reflection model does not hold (``surface``: ``glass`` (the Mitsuba type), ``ior``,
    ``transmittance``, ``opacity``, ``opacity_map``, ``emission``) and, where the material
    cannot be converted, why (``refused``)."""

    model: object
    spec: str
    notes: list
    warnings: list
    surface: dict
    refused: str | None = None


def _surface(m: MtlMaterial, notes: list, warnings: list) -> dict:
    """What the material has beside its reflection (:class:`Reading`)."""
    out = {}
    if m.illum in GLASS:
        out["glass"] = GLASS[m.illum]
        ior = m.Ni if m.Ni is not None and m.Ni > 1.0 else None
        if ior is None:
            said = ("not given" if m.Ni is None else f"{m.Ni:g} (below 1)" if m.Ni < 1.0 else
                    "1 (the index of air: a glass that neither reflects nor refracts, invisible; exporters write it "
                    "for 'not set')")
            warnings.append(f"illum {m.illum} (glass): Ni {said}: the index of glass, {GLASS_IOR:g}, read")
        out["ior"] = ior or GLASS_IOR
        out["transmittance"] = [float(x) for x in (m.Tf if m.Tf is not None else np.ones(3))]
        notes.append(f"illum {m.illum} ({ILLUM[m.illum]}): glass, a smooth {out['glass']} of index {out['ior']:g} "
                     f"transmitting Tf {_spec_colour(out['transmittance'])}; Kd, Ks, Ns and d are not read for it"
                     + ("; MTL's 'Fresnel off' is not followed (a dielectric has Fresnel)" if m.illum == 6 else ""))
        return out
    if m.d < 1.0:
        out["opacity"] = m.d
    if "map_d" in m.texture_files:
        out["opacity_map"] = m.texture_files["map_d"]
    if np.any(m.Ke > 0):
        out["emission"] = [float(x) for x in m.Ke]
    if m.Tf is not None and np.any(m.Tf < 1):
        notes.append("Tf (transmission filter) of an opaque material (illum 0-3, 5, 8): not read")
    return out


def reading(m: MtlMaterial) -> Reading:
    """The :class:`Reading` of ``m`` (module docstring)."""
    from .. import registry
    from ..models.sum import Sum

    notes, warnings = list(m.notes), list(m.warnings)
    parts = []
    if m.pbr and m.illum not in GLASS:
        parts.append(_pbr_spec(m, notes))
    elif m.illum in (0, 1):
        if np.any(m.Ks > 0):
            notes.append(f"illum {m.illum} has no highlight: Ks is unused")
        parts.append(f"lambertian:rd={_spec_colour(m.Kd)}")
        if m.illum == 0:
            notes.append("illum 0 (unlit colour) read as a Lambertian reflector of albedo Kd")
    else:
        if np.any(m.Kd > 0) or not np.any(m.Ks > 0):
            parts.append(f"lambertian:rd={_spec_colour(m.Kd)}")
        if np.any(m.Ks > 0):
            parts.append(highlight_spec(m.Ks, m.Ns, "schlick" if m.illum == 5 else "none"))
        if m.illum in (3, 8):
            notes.append(f"illum {m.illum}: the ray-traced reflection is the Blinn-Phong lobe itself (not added "
                         "twice); no Fresnel (MTL gives Fresnel to illum 5 and 7)")
        if m.illum == 5:
            notes.append("illum 5: the highlight with Schlick's Fresnel of R0 = Ks")
    total = m.Kd + (m.Ks if m.illum >= 2 and not m.pbr else 0.0)
    if np.any(total > 1.0 + 1e-12) and m.illum not in GLASS:
        notes.append(f"Kd + Ks = {_spec_colour(np.round(total, 4))} exceeds 1: energy conservation is not "
                     "guaranteed (it holds only where the highlight reflects less than Ks; the conversion "
                     "measures the albedo)")
    surface = _surface(m, notes, warnings)
    refused = None
    if m.illum == 10:
        refused = (f"illum 10 ({ILLUM[10]}: a shadow catcher, invisible itself) has no reflection to convert: "
                   f"material {m.name!r} skipped")
    models = [registry.make_from_spec(s) for s in parts]
    return Reading(Sum(models, name=m.name), " + ".join(parts), notes, warnings, surface, refused)


def _pbr_spec(m: MtlMaterial, notes: list) -> str:
    """The spec of a material of MTL's PBR extension (``Pr``, ``Pm`` given): glTF's metallic-roughness
    BRDF (``gltf-pbr``) of base colour ``Kd``, metallic ``Pm`` (0 where missing) and roughness ``Pr`` (where
    missing: from ``Ns`` by the Blinn-Beckmann correspondence ``alpha = sqrt(2 / (Ns + 2))``, roughness
    ``sqrt(alpha)``, else :data:`PBR_ROUGHNESS`), as Blender's exporter writes them from its Principled
    BSDF (whose roughness is glTF's)."""
    metallic = m.pbr.get("Pm", 0.0)
    if "Pr" in m.pbr:
        roughness, how = m.pbr["Pr"], "Pr"
    elif "Ns" in m.given:
        roughness, how = math.sqrt(math.sqrt(2.0 / (m.Ns + 2.0))), f"from Ns {m.Ns:g} (alpha = sqrt(2 / (Ns + 2)))"
    else:
        roughness, how = PBR_ROUGHNESS, f"{PBR_ROUGHNESS:g} (no Pr or Ns: Blender's default)"
    if roughness < 0.01:
        roughness, how = 0.01, how + "; raised to the model's smallest, 0.01"
    notes.append(f"the PBR extension (Pr/Pm): glTF's metallic-roughness BRDF of base colour Kd, metallic "
                 f"{metallic:g}{'' if 'Pm' in m.pbr else ' (Pm not given)'}, roughness {roughness:.6g} ({how}); "
                 f"Ks, Ns{'' if m.illum == 10 else f' and illum {m.illum}'} not read")
    return f"gltf-pbr:base_color={_spec_colour(m.Kd)}:metallic={metallic!r}:roughness={roughness!r}"


def as_model(m: MtlMaterial):
    """``(model, spec, notes)`` of :func:`reading` (the reflection of ``m`` as a labelled
    :class:`~plausible.models.sum.Sum`, its spec, the notes of the reading)."""
    r = reading(m)
    return r.model, r.spec, r.notes
