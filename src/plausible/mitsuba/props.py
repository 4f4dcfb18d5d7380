"""Mitsuba plugin properties -> model parameters.

A plugin's ``Properties`` hold what the scene gave: numbers, strings, colours,
Mitsuba textures.  This module turns them into what a model takes, and checks
textures as fully as their data allows:

* :func:`given_names` -- which parameter each property sets (aliases resolved,
  unknown and repeated names refused);
* :func:`read_param`: a number (:func:`read_number`) or a texture
  (:func:`read_texture`) where the parameter takes one, else the parameter's
  own reader (``Param.from_mitsuba``: a choice, Lafortune's lobes, a nested
  model spec); :func:`metal_textures` for ``material=``;
* textures: :func:`texture_texels` (every value a bitmap / checkerboard /
  constant texture can take, read from ``mi.traverse``), :func:`check_texture`
  (how many texels leave the parameter's range: as Mitsuba, such a texture is
  clamped into the range at each shading point, with one warning,
  :func:`range_warning`; the same in spectral variants, :func:`spectral_texels`)
  and :func:`check_pointwise` (cross-parameter constraints, e.g. Modified Phong's
  ``kd + ks <= 1``, at every point of a UV grid).  A texture whose values cannot
  be read (a procedural texture) is clamped to the parameter's range per shading
  point too (:func:`texture_range_known` says which).

Every function here takes Mitsuba's module as ``mi`` only where it needs it, so
that the parts that do not render can be read and tested alone.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np

from ..spectra import srgb_to_linear

#: Mitsuba-style parameter names accepted by every plugin whose model has one of
#: the candidate parameters (first candidate present wins).
#: ``specular_reflectance`` goes only to a scale of the specular lobe (``ks``),
#: what it is in Mitsuba (a factor on the lobe, default 1); never to an ``rs``
#: that is Schlick's F0 (:data:`F0_PARAMS`, see :func:`given_names`).
COMMON_ALIASES = {
    "diffuse_reflectance": ("kd", "rd"),
    "specular_reflectance": ("ks",),
    "exponent": ("n",),
    "reflectance": ("rd", "kd", "ks"),
}

#: Per-plugin aliases (added to :data:`COMMON_ALIASES`).  Ward's ``alpha`` is
#: Mitsuba's isotropic roughness: it sets ``alpha_x`` and ``alpha_y`` together
#: (:data:`BOTH`).  Ward's ``rs`` scales its lobe, as Mitsuba 0.5's ``ward``.
PLUGIN_ALIASES = {
    "ashikhmin_shirley": {"diffuse_reflectance": ("rd",)},
    "ward": {"alpha_u": ("alpha_x",), "alpha_v": ("alpha_y",), "alpha": (("alpha_x", "alpha_y"),),
             "specular_reflectance": ("rs",)},
    "cook_torrance": {"alpha": ("m",), "roughness": ("m",)},
}

#: Plugins whose ``rs`` is Schlick's F0 (the reflectance at normal incidence),
#: not a factor: Mitsuba's ``specular_reflectance`` is refused there with the
#: conversion, and ``int_ior`` / ``ext_ior`` set ``rs`` (:data:`CONVERTED`).
F0_PARAMS = {"ashikhmin_shirley": "rs", "ashikhmin_shirley_specular": "rs",
             "ashikhmin_shirley_diffuse": "rs", "schlick": "rs"}


def ior_f0(int_ior: float, ext_ior: float) -> float:
    """Schlick's F0 of a dielectric interface, ``((n_int - n_ext) / (n_int + n_ext))^2``
    (the Fresnel reflectance at normal incidence; Schlick 1994 eq. 24)."""
    return ((int_ior - ext_ior) / (int_ior + ext_ior)) ** 2


def blinn_exponent(alpha: float) -> float:
    """The Blinn-Phong exponent of a Beckmann roughness: ``n = 2 / alpha^2 - 2``
    (Walter et al. 2007, "Microfacet models for refraction", eq. after 33): the
    two half-vector densities agree near the peak.  An approximation; exact only
    in the limit of small ``alpha``."""
    return max(2.0 / (alpha * alpha) - 2.0, 0.0)


#: Mitsuba's names that need a conversion: ``{plugin: {property: (parameters,
#: function of the property's value, range text)}}``.  ``int_ior``/``ext_ior``
#: (defaults as Mitsuba's: 1.49 polypropylene, 1.000277 air) set Schlick's F0;
#: ``alpha``/``alpha_u``/``alpha_v`` set Ashikhmin-Shirley's exponents by
#: :func:`blinn_exponent`.
MITSUBA_IOR = (1.49, 1.000277)
CONVERTED = {
    **{p: {"int_ior": (("rs",), None, "a number > 0"), "ext_ior": (("rs",), None, "a number > 0")}
       for p in F0_PARAMS},
    "ashikhmin_shirley": {"int_ior": (("rs",), None, "a number > 0"), "ext_ior": (("rs",), None, "a number > 0"),
                          "alpha": (("nu", "nv"), blinn_exponent, "a number in (0, 1]"),
                          "alpha_u": (("nu",), blinn_exponent, "a number in (0, 1]"),
                          "alpha_v": (("nv",), blinn_exponent, "a number in (0, 1]")},
    "ashikhmin_shirley_specular": {"int_ior": (("rs",), None, "a number > 0"),
                                   "ext_ior": (("rs",), None, "a number > 0"),
                                   "alpha": (("nu", "nv"), blinn_exponent, "a number in (0, 1]"),
                                   "alpha_u": (("nu",), blinn_exponent, "a number in (0, 1]"),
                                   "alpha_v": (("nv",), blinn_exponent, "a number in (0, 1]")},
    "reciprocal_blinn": {"alpha": (("n",), blinn_exponent, "a number in (0, 1]")},
}


def converted_values(plugin: str, props, keys) -> dict:
    """``{parameter: value}`` from the properties that need a conversion
    (:data:`CONVERTED`); ValueError for a texture or an out-of-range number."""
    table = CONVERTED.get(plugin, {})
    out = {}
    given = [k for k in keys if k in table]
    for key in given:
        raw = props[key]
        lo_ok = isinstance(raw, (int, float)) and not isinstance(raw, bool) and raw > 0
        if not lo_ok or (key.startswith("alpha") and raw > 1.0):
            raise ValueError(f"{plugin}: parameter {key!r} must be {table[key][2]} (converted, "
                             f"see docs/mitsuba.md), got {raw!r}")
    ior = [k for k in given if k in ("int_ior", "ext_ior")]
    if ior:
        i = float(props["int_ior"]) if "int_ior" in ior else MITSUBA_IOR[0]
        e = float(props["ext_ior"]) if "ext_ior" in ior else MITSUBA_IOR[1]
        out["rs"] = ior_f0(i, e)
    for key in given:
        targets, fn, _ = table[key]
        if fn is not None:
            for t in targets:
                out[t] = fn(float(props[key]))
    return out

#: Texture classes whose every value is a texel of their data (bilinear
#: interpolation stays within the texels' range): their range is checked at load.
KNOWN_TEXTURES = ("BitmapTexture", "Checkerboard", "SRGBReflectanceSpectrum", "UniformSpectrum",
                  "D65Spectrum")

#: Largest number of distinct parameter combinations :func:`check_pointwise`
#: builds a model for (beyond it, an evenly spread subset, and a warning).
MAX_POINTS = 20000


def aliases_for(plugin: str, info) -> dict:
    """``{alias: parameter or tuple of parameters}`` of ``plugin`` (only aliases
    whose targets all exist; a native name is never an alias)."""
    names = [p.name for p in info.params]
    table = dict(COMMON_ALIASES)
    table.update(PLUGIN_ALIASES.get(plugin, {}))
    out = {}
    for alias, cands in table.items():
        if alias in names:
            continue
        for c in cands:
            if all(t in names for t in (c if isinstance(c, tuple) else (c,))):
                out[alias] = c
                break
    return out


def given_names(plugin: str, info, keys, alias: dict) -> dict:
    """``{parameter: property key}`` for the property ``keys`` (``material`` aside).

    Raises ValueError for an unknown name (listing the allowed ones) and for a
    parameter set twice through aliases.
    """
    names = [p.name for p in info.params]
    given = {}
    for key in keys:
        if key == "material":
            continue
        target = alias.get(key, key)
        if key == "specular_reflectance" and plugin in F0_PARAMS:
            raise ValueError(f"{plugin}: 'specular_reflectance' is Mitsuba's factor on the Fresnel "
                             f"term (default 1); this model's {F0_PARAMS[plugin]!r} is Schlick's F0, "
                             f"the reflectance at normal incidence (default 0.05; 0.04 for glass). "
                             f"Give {F0_PARAMS[plugin]!r}, or 'int_ior'/'ext_ior' (F0 = ((n1 - n2) / "
                             f"(n1 + n2))^2)")
        for t in (target if isinstance(target, tuple) else (target,)):
            if t not in names:
                raise ValueError(f"{plugin}: unknown parameter {key!r}; allowed: "
                                 f"{', '.join(names + sorted(alias))}")
            if t in given:
                raise ValueError(f"{plugin}: parameter {t!r} given twice "
                                 f"(as {given[t]!r} and {key!r}; aliases)")
            given[t] = key
    return given


def check_material(plugin: str, info, keys) -> None:
    """``material=`` needs a model with ``eta`` and ``k`` and excludes giving them."""
    names = [p.name for p in info.params]
    if not {"eta", "k"} <= set(names):
        raise ValueError(f"{plugin}: 'material' needs a model with 'eta' and 'k' "
                         f"parameters ({info.name} has {', '.join(names)})")
    for clash in ("eta", "k"):
        if clash in keys:
            raise ValueError(f"{plugin}: give either 'material' or {clash!r}, not both")


# -- one reader per kind ------------------------------------------------------------

def read_number(prm, raw, plugin, single: bool = False):
    """A plain number (scalar, or a grey colour): validated, a Python float (int).

    ``single`` (a float32 variant): a float32 subnormal is read as 0.  Dr.Jit's
    LLVM worker threads flush subnormals to zero and the calling thread, which
    runs small batches, does not: with ``rd = 1e-39`` a batch of 3 saw a diffuse
    lobe that a batch of 4096 did not.  Read as 0, every batch agrees."""
    v = prm.validate(float(raw), plugin)
    if single and isinstance(v, float) and 0.0 < abs(v) < np.finfo(np.float32).tiny:
        return 0.0
    return v


def read_texture(mi, prm, props, key, raw):
    """A colour or scalar given as a Mitsuba texture (``<rgb>``, ``bitmap``,
    ``checkerboard``, ...) or as a list of numbers (an sRGB colour)."""
    unbounded = bool(prm.hi > 1.0)
    if prm.is_color and not isinstance(raw, mi.Object) and hasattr(raw, "__len__"):
        return srgb(mi, raw, unbounded)
    if prm.is_color and not unbounded:
        return props.get_texture(key)
    return props.get_unbounded_texture(key)


def srgb(mi, values, unbounded: bool):
    """A constant ``srgb`` texture of three numbers."""
    return mi.load_dict({"type": "srgb", "color": mi.ScalarColor3d(*[float(x) for x in values]),
                         "unbounded": unbounded})


def read_param(mi, prm, props, key, plugin):
    """The value of one given parameter: a Python value or a Mitsuba texture
    (a string or a sequence is the parameter's own to read:
    :meth:`Param.from_mitsuba <plausible.params.Param.from_mitsuba>`)."""
    raw = props[key]
    if not prm.numeric and isinstance(raw, mi.Object):
        # one line, the allowed values last (Mitsuba shows the message's last line)
        given = f" (given as {key!r})" if key != prm.name else ""
        raise ValueError(f"{plugin}: parameter {prm.name!r}{given} takes no texture (got "
                         f"{texture_label(raw)}); it must be {prm.range_text()}")
    if not prm.numeric or isinstance(raw, str):
        return prm.from_mitsuba(raw, plugin)
    if isinstance(raw, (int, float)) and not isinstance(raw, bool):
        return read_number(prm, raw, plugin, single="double" not in mi.variant())
    return read_texture(mi, prm, props, key, raw)


#: The conductor names of Mitsuba 3's ``conductor`` / ``roughconductor``
#: ``material`` (its ``data/ior`` tables; each one loads in Mitsuba 3.9,
#: ``tests/mitsuba/test_conventions.py``); ``"none"`` (a perfect mirror) aside.
MITSUBA_CONDUCTORS = (
    "a-C", "Ag", "Al", "AlAs", "AlAs_palik", "AlSb", "AlSb_palik", "Au", "Be", "Be_palik", "Cr", "CsI",
    "CsI_palik", "Cu", "Cu_palik", "Cu2O", "Cu2O_palik", "CuO", "CuO_palik", "d-C", "d-C_palik", "Hg",
    "Hg_palik", "HgTe", "HgTe_palik", "Ir", "Ir_palik", "K", "K_palik", "Li", "Li_palik", "MgO",
    "MgO_palik", "Mo", "Mo_palik", "Na_palik", "Nb", "Nb_palik", "Ni_palik", "Rh", "Rh_palik", "Se",
    "Se_palik", "SiC", "SiC_palik", "SnTe", "SnTe_palik", "Ta", "Ta_palik", "Te", "Te_palik", "ThF4",
    "ThF4_palik", "TiC", "TiC_palik", "TiN", "TiN_palik", "TiO2", "TiO2_palik", "VC", "VC_palik",
    "V_palik", "VN", "VN_palik", "W")


def conductor_name(plugin: str, material) -> str:
    """Mitsuba's name of a conductor: one of :data:`MITSUBA_CONDUCTORS`, or an
    English name of :data:`plausible.spectra.METALS` (``gold`` -> ``Au``)."""
    from .. import spectra

    name = spectra.METALS.get(material, material) if isinstance(material, str) else material
    if name not in MITSUBA_CONDUCTORS:
        raise ValueError(f"{plugin}: parameter 'material' must be one of Mitsuba's conductors "
                         f"({', '.join(MITSUBA_CONDUCTORS)}) or {', '.join(sorted(set(spectra.METALS) - set(MITSUBA_CONDUCTORS)))}, "
                         f"got {material!r}")
    return name


def metal_textures(mi, material: str, plugin: str = "plugin") -> dict:
    """``{"eta": texture, "k": texture}`` of a conductor, read from Mitsuba itself
    (a ``conductor`` with that ``material``, through ``mi.traverse``), so that the
    plugin's metal is Mitsuba's: its ``irregular`` spectra in spectral variants,
    its RGB reduction of them in RGB and monochrome variants."""
    params = mi.traverse(mi.load_dict({"type": "conductor", "material": conductor_name(plugin, material)}))
    out = {}
    for name in ("eta", "k"):
        if mi.is_spectral:
            wl = np.array(params[f"{name}.wavelengths"], dtype=np.float64).ravel()
            vals = np.array(params[f"{name}.values"], dtype=np.float64).ravel()
            out[name] = mi.load_dict({"type": "irregular",
                                      "wavelengths": ", ".join(f"{x:.9g}" for x in wl),
                                      "values": ", ".join(f"{x:.9g}" for x in vals)})
        else:
            v = np.array(params[f"{name}.value"], dtype=np.float64).ravel()
            out[name] = srgb(mi, np.broadcast_to(v, (3,)) if v.size == 1 else v, True)
    return out


# -- textures: what values they can take ------------------------------------------------

def texture_class(tex) -> str:
    """Mitsuba's class name of a texture (``BitmapTexture``, ``Checkerboard``, ...);
    ``""`` for a texture that cannot print itself (a Python texture without
    ``to_string``)."""
    try:
        return repr(tex).split("[", 1)[0].strip()
    except RuntimeError:
        return ""


def texture_label(tex) -> str:
    """A short printed form of a texture: its class and, where it has one, its
    name (a bitmap's file, a mesh attribute's name), e.g. ``BitmapTexture('wood.jpg')``;
    a constant colour as its value."""
    cls = texture_class(tex) or type(tex).__name__
    try:
        text = repr(tex)
    except RuntimeError:
        text = ""
    constant = cls in ("SRGBReflectanceSpectrum", "UniformSpectrum", "D65Spectrum")
    for key in (("value = ", "value=") if constant else ("name = ",)):
        at = text.find(key)
        if at >= 0:
            val = text[at + len(key):].split("\n", 1)[0].strip().rstrip(",").strip('"')
            if key == "name = ":
                return f"{cls}({val!r})"
            return f"{cls}([{val.strip('[]')}])"
    return cls


def texture_texels(mi, tex):
    """Every value ``tex.eval`` can return, as rows ``(k, channels)`` of float64,
    or None where that cannot be known.

    Known: constant colours, bitmaps (``data``; bilinear interpolation stays in
    the texels' range) and checkerboards of those (``color0``/``color1``), in
    RGB and monochrome variants.  Not known: every other texture (procedural,
    mesh attributes, nested checkerboards) and spectral variants (a texture
    holds spectral coefficients there, not reflectances).
    """
    if mi.is_spectral or texture_class(tex) not in KNOWN_TEXTURES:
        return None
    params = mi.traverse(tex)
    rows = []
    for key in params.keys():
        leaf = key.split(".")[-1]
        if leaf == "to_uv":
            continue
        if leaf not in ("data", "value") or key.count(".") > 1 or \
                (key.count(".") == 1 and key.split(".")[0] not in ("color0", "color1")):
            return None
        a = np.array(params[key])
        if leaf == "data":          # TensorXf / TensorXu8 (height, width, channels)
            a = bitmap_values(a, bitmap_is_raw(tex, key))
            rows.append(a.reshape(-1, a.shape[-1]))
        else:                       # Color3f (3, 1) or Float (1,)
            rows.append(a.astype(np.float64).reshape(1, -1))
    if not rows:
        return None
    width = max(r.shape[1] for r in rows)
    return np.concatenate([np.broadcast_to(r, (len(r), width)) if r.shape[1] == 1 else r
                           for r in rows])


def bitmap_values(data, raw: bool) -> np.ndarray:
    """The values ``eval`` returns at the texels of a bitmap's ``data``: float
    data as stored; 8-bit data (Mitsuba 3.9 keeps PNG and JPEG texels as
    ``TensorXu8``) mapped 0..255 -> [0, 1] and, unless the texture is ``raw``,
    sRGB-decoded (:func:`srgb_to_linear`), as Mitsuba does at each lookup."""
    a = np.asarray(data)
    if a.dtype != np.uint8:
        return a.astype(np.float64)
    a = a.astype(np.float64) / 255.0
    return a if raw else srgb_to_linear(a)


def bitmap_is_raw(tex, key: str) -> bool:
    """Was the bitmap whose ``data`` is ``key`` of ``tex`` (``data``, or
    ``color0.data`` in a checkerboard) loaded ``raw``?  Read from the texture's
    printed form (``raw = 0|1``, Mitsuba 3's ``BitmapTexture::to_string``), the
    only place Python can read it."""
    text = repr(tex)
    prefix = key.rsplit(".", 1)[0] if "." in key else ""
    if prefix:
        at = text.find(f"{prefix} = ")
        text = text[at:] if at >= 0 else ""
    at = text.find("raw = ")
    return at >= 0 and text[at + 6:at + 7] == "1"


def texture_mean(tex):
    """The texture's mean (channel mean, a float), or None where the texture
    has none: Mitsuba's ``mesh_attribute`` (vertex colours) raises
    ``Texture::mean(): not implemented`` (its values live on the mesh)."""
    try:
        return float(np.mean(np.asarray(tex.mean())))
    except RuntimeError:
        return None


#: Constant textures whose one traversed value is what ``eval`` returns (RGB and
#: monochrome variants): :func:`constant_reader` reads them without ``mi.traverse``.
CONSTANT_TEXTURES = ("SRGBReflectanceSpectrum", "UniformSpectrum")


def constant_reader(mi, tex):
    """A function returning the channels of a constant texture (``<rgb>``, ``<float>``)
    as Python floats, reading its traversed ``value`` where it lives now (about 1 us;
    ``mi.traverse`` of the texture takes 12 us), or None for any other texture and in
    spectral variants (a colour holds spectral coefficients there)."""
    import drjit as dr

    if mi.is_spectral or texture_class(tex) not in CONSTANT_TEXTURES:
        return None
    params = mi.traverse(tex)
    if list(params.keys()) != ["value"]:
        return None
    ptr, cpptype, node, _ = params.properties["value"]
    jit = dr.is_jit_v(mi.Float)

    def get():
        return mi.get_property(ptr, cpptype, node) if cpptype is not None else ptr

    depth, size = dr.depth_v(get()), dr.size_v(get())
    if jit and depth == 2 and size == 3:  # Color3f: the common case, without a loop
        def read() -> tuple:
            v = mi.get_property(ptr, cpptype, node) if cpptype is not None else ptr
            return v[0][0], v[1][0], v[2][0]
    elif jit:
        def read() -> tuple:
            v = get()
            return tuple(c[0] for c in v) if depth > 1 else (v[0],)
    else:
        def read() -> tuple:
            v = get()
            return tuple(float(x) for x in v) if depth else (float(v),)
    return read


def texture_varies(tex) -> bool:
    """Does the texture vary over a surface?  ``is_spatially_varying()``, and
    also every texture without a mean: Mitsuba 3.9's ``mesh_attribute`` says
    False although its value changes from vertex to vertex."""
    return bool(tex.is_spatially_varying()) or texture_mean(tex) is None


def texture_range_known(mi, tex) -> bool:
    """Can the texture's values be read at load (:func:`texture_texels`)?"""
    return texture_texels(mi, tex) is not None


class TextureRange(NamedTuple):
    """What :func:`check_texture` found in a texture's values, per texel (a texel: one
    row of :func:`texture_texels`; for a scalar parameter its channel mean)."""

    known: bool       # every value read and inside the range: nothing to clamp
    outside: int      # texels outside the range (0 where none, or none could be read)
    total: int        # texels read (0: the values cannot be read)
    low: float        # the smallest and the largest value read (nan where none)
    high: float


def check_texture(mi, plugin: str, prm, tex) -> TextureRange:
    """The values of ``tex`` against ``prm``'s range.

    As Mitsuba's own BSDFs, a texture whose values leave the model's range is not
    refused: the plugin clamps its value into the range at each shading point, and
    :func:`range_warning` says so once.  The values are read in every variant: the
    texels themselves (:func:`texture_texels`) in RGB and monochrome variants; in
    spectral ones (where a bitmap holds spectral coefficients) the texture evaluated at
    its texel centres over the visible wavelengths (:func:`spectral_texels`), which
    counts what remains outside after Mitsuba's own upsampling (that clamps a bounded
    colour into [0, 1]).  ``known`` is False (clamped per shading point) where anything
    is outside, in spectral variants, and where nothing can be read (a procedural
    texture).  A texel that is not a number (NaN) cannot be clamped: ValueError
    naming the plugin, the parameter, the texture and the count.
    """
    texels, exact = texture_texels(mi, tex), True
    if texels is None and mi.is_spectral:
        texels, exact = spectral_texels(mi, tex), False
    if texels is None or len(texels) == 0:
        return TextureRange(False, 0, 0, float("nan"), float("nan"))
    vals = texels.mean(axis=1) if not prm.is_color else texels
    nan = np.isnan(vals).reshape(len(vals), -1).any(axis=1)
    if np.any(nan):
        raise ValueError(f"{plugin}: parameter '{prm.name}' must lie in {prm.range_text()}; its texture "
                         f"{texture_label(tex)} holds {int(nan.sum())} texel(s) that are not a number (NaN)")
    out = ((vals < prm.lo) | (vals > prm.hi)).reshape(len(vals), -1).any(axis=1)
    return TextureRange(exact and not np.any(out), int(out.sum()), len(out), float(np.min(vals)), float(np.max(vals)))


def range_warning(plugin: str, prm, tex, found: TextureRange, given: str | None = None) -> str | None:
    """The one warning of a texture with values outside ``prm``'s range (None where it has
    none): the plugin, the parameter (and the name the scene gave, ``given``, where that
    differs: Ward's ``alpha``), the range, the texture and how many texels."""
    if not found.outside:
        return None
    name = f"'{prm.name}'" + (f" (given as '{given}')" if given and given != prm.name else "")
    return (f"{plugin}: parameter {name} must lie in {prm.range_text()}; {found.outside} of "
            f"{found.total} texels of its texture {texture_label(tex)} lie outside (values from "
            f"{found.low:g} to {found.high:g}): clamped into the range at each shading point")


#: Wavelengths (nm) at which :func:`spectral_texels` evaluates a texture: Mitsuba's
#: visible range, 360-830 nm, in steps of 10 nm.
SPECTRAL_CHECK_NM = np.arange(360.0, 831.0, 10.0)


def spectral_texels(mi, tex):
    """In a spectral variant: the values of a texture of :data:`KNOWN_TEXTURES` at its texel
    centres (a bitmap's grid at its resolution, capped at 256 x 256 points, 64 x 64 in a
    scalar variant; 8 x 8 for a checkerboard; one point for a constant) at the wavelengths
    :data:`SPECTRAL_CHECK_NM`, rows ``(points, wavelengths)``; None for other textures."""
    import drjit as dr

    if texture_class(tex) not in KNOWN_TEXTURES:
        return None
    params = mi.traverse(tex)
    sizes = [np.array(params[k]).shape[:2] for k in params.keys() if k.split(".")[-1] == "data"]
    res = max(max(s) for s in sizes) if sizes else (8 if tex.is_spatially_varying() else 1)
    res = min(res, 256 if dr.is_array_v(mi.Float) else 64)
    c = (np.arange(res) + 0.5) / res
    u, v = np.meshgrid(c, c, indexing="xy")
    uv = np.stack([u.ravel(), v.ravel()], -1)
    n = dr.size_v(mi.Spectrum)
    cols = []
    for at in range(0, len(SPECTRAL_CHECK_NM), n):
        wl = np.resize(SPECTRAL_CHECK_NM[at:at + n], n)
        cols.append(eval_at_uv(mi, tex, uv, wavelengths=wl))
    return np.concatenate(cols, axis=1)


def uv_grid(mi, textures) -> np.ndarray:
    """UV points ``(m, 2)`` at which :func:`check_pointwise` compares textures:
    the texel centres of the finest bitmap (at least 64 x 64, at most 512 x 512)."""
    res = 32
    for tex in textures:
        for key in mi.traverse(tex).keys():
            if key.split(".")[-1] == "data":
                res = max(res, *np.array(mi.traverse(tex)[key]).shape[:2])
    res = min(2 * res, 512)
    c = (np.arange(res) + 0.5) / res
    u, v = np.meshgrid(c, c, indexing="xy")
    return np.stack([u.ravel(), v.ravel()], -1)


def eval_at_uv(mi, tex, uv: np.ndarray, wavelengths=None) -> np.ndarray:
    """``tex.eval`` at the UV points ``uv`` ``(m, 2)``: array ``(m, channels)``: one
    vectorised interaction, or in a scalar variant (``scalar_rgb``, whose interaction
    holds one point) one call per point (about 10 us each).  ``wavelengths``: those of
    the interaction (a spectral variant), one per channel of ``mi.Spectrum``."""
    import drjit as dr

    if not dr.is_array_v(mi.Float):
        si = dr.zeros(mi.SurfaceInteraction3f)
        if wavelengths is not None:
            si.wavelengths = mi.Spectrum(*[float(w) for w in wavelengths])
        out = []
        for u, v in np.asarray(uv, dtype=np.float64):
            si.uv = mi.Point2f(float(u), float(v))
            out.append(np.atleast_1d(np.array(tex.eval(si), dtype=np.float64)))
        return np.array(out).reshape(len(uv), -1)
    si = dr.zeros(mi.SurfaceInteraction3f, len(uv))
    si.uv = mi.Point2f(np.ascontiguousarray(uv.T, dtype=np.float32))
    if wavelengths is not None:
        si.wavelengths = mi.Spectrum(*[float(w) for w in wavelengths])
    return np.array(tex.eval(si), dtype=np.float64).T


class PointValues(NamedTuple):
    """Parameter values at UV points, for :func:`check_pointwise`."""

    uv: np.ndarray        # (m, 2)
    values: dict          # name -> (m,) scalar or (m, channels) colour


def values_at_uv(mi, info, textures: dict, uv) -> PointValues:
    """Each textured parameter at the points ``uv`` (scalars: channel mean)."""
    vals = {}
    for name, tex in textures.items():
        v = eval_at_uv(mi, tex, uv)
        vals[name] = v.mean(axis=1) if not info.param(name).is_color else v
    return PointValues(uv, vals)


def has_constraints(info) -> bool:
    """Does the model have constraints between parameters (a ``_validate`` of its own),
    which :func:`check_pointwise` checks?"""
    from ..bxdf import BxDF

    return info.cls._validate is not BxDF._validate


def check_pointwise(plugin: str, info, constants: dict, points: PointValues, warn=None) -> int:
    """Cross-parameter constraints at every point: build the model (the NumPy
    one, whose constructor checks them) for each distinct combination of the
    textured values at the points with the constant ``constants``.

    Only for models with constraints between parameters (a ``_validate``
    of their own); more than :data:`MAX_POINTS` distinct combinations are
    thinned to an evenly spread subset (``warn`` is told).  Raises ValueError
    naming the plugin, the UV point and the values there.  Returns the number of
    combinations checked.
    """
    if not has_constraints(info):
        return 0
    names = list(points.values)
    cols = [np.asarray(points.values[n]).reshape(len(points.uv), -1) for n in names]
    table = np.concatenate(cols, axis=1)
    _, first = np.unique(table, axis=0, return_index=True)
    first = np.sort(first)
    if len(first) > MAX_POINTS:
        if warn is not None:
            warn(f"{plugin}: {len(first)} distinct texture combinations; cross-parameter "
                 f"constraints checked at {MAX_POINTS} of them")
        first = first[np.linspace(0, len(first) - 1, MAX_POINTS).astype(int)]
    for i in first:
        params = dict(constants)
        for n in names:
            v = np.asarray(points.values[n])[i]
            params[n] = float(v) if np.ndim(v) == 0 else v
        try:
            info.cls(**params)
        except ValueError as err:
            u, v = points.uv[i]
            shown = ", ".join(f"{n}={_show(params[n])}" for n in names)
            raise ValueError(f"{plugin}: textured parameters break a constraint at uv = "
                             f"({u:.4g}, {v:.4g}) where {shown}: {err}") from None
    return len(first)


def _show(v) -> str:
    if isinstance(v, np.ndarray):
        return "[" + ", ".join(f"{x:.4g}" for x in v) + "]"
    return f"{v:.4g}"


__all__ = ["COMMON_ALIASES", "PLUGIN_ALIASES", "KNOWN_TEXTURES", "aliases_for", "given_names",
           "check_material", "conductor_name", "MITSUBA_CONDUCTORS", "read_param",
           "read_number", "read_texture", "metal_textures", "texture_texels",
           "texture_range_known", "texture_mean", "texture_varies", "srgb_to_linear",
           "bitmap_values", "bitmap_is_raw", "check_texture", "TextureRange", "range_warning", "spectral_texels",
           "SPECTRAL_CHECK_NM", "uv_grid", "values_at_uv", "check_pointwise",
           "has_constraints", "CONSTANT_TEXTURES", "constant_reader",
           "PointValues"]
