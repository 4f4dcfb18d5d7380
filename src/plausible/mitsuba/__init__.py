"""Mitsuba 3 BSDF plugins for every registered :mod:`plausible` model.

``plausible.mitsuba.register()`` adds one plugin per registry entry (generic
over the registry: a model added later appears at once).  A plugin holds no
formula: it converts Mitsuba's ``SurfaceInteraction3f`` / directions into the
component tuples of the model's hooks ``_f``, ``_pdf`` and ``_sample`` and calls
them with :func:`plausible.ops.drjit_ops`.

Conventions (see ``docs/mitsuba.md``):

* directions: Mitsuba's local shading frame is plausible's (``z`` the shading
  normal, ``x`` = ``si.sh_frame.s`` the tangent ``u``, ``y`` = ``sh_frame.t``);
* sampling is driven from ``si.wi`` (the direction the path arrived along, the
  camera side in a path tracer): ``bs.wo`` is the model's ``sample(si.wi, u)``
  with ``u = (sample1, sample2.x, sample2.y)`` and ``pdf`` is the model's
  ``pdf(si.wi, wo)``;
* the BRDF value is ``f(light, view)``: plausible's ``wi`` is the direction
  toward the light.  In ``TransportMode.Radiance`` (path tracing) that is
  Mitsuba's ``wo``; in ``TransportMode.Importance`` it is ``si.wi``.  For a
  reciprocal model the two agree; for ``phong_original`` and ``blinn`` (the
  non-reciprocal baselines, divided by ``cos(theta_light)``) this keeps the
  classic look ``ks c cos^n(alpha)`` under a point light;
* ``eval`` returns ``f * cos(theta_o)`` (Mitsuba's convention, ``wo`` Mitsuba's);
  ``sample`` returns ``weight = f cos(theta_o) / pdf``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import registry, vec
from ..params import ModelInfo

#: Mitsuba-style parameter names accepted by every plugin whose model has one of
#: the candidate parameters (first candidate present wins).
COMMON_ALIASES = {
    "diffuse_reflectance": ("kd", "rd"),
    "specular_reflectance": ("ks", "rs"),
    "exponent": ("n",),
    "reflectance": ("rd", "kd", "ks", "rs"),
}

#: Per-plugin aliases (added to :data:`COMMON_ALIASES`).
PLUGIN_ALIASES = {
    "ashikhmin_shirley": {"specular_reflectance": ("rs",), "diffuse_reflectance": ("rd",)},
    "ward": {"alpha_u": ("alpha_x", "ax", "alpha_u"), "alpha_v": ("alpha_y", "ay", "alpha_v"),
             "alpha": ("alpha",)},
    "cook_torrance": {"alpha": ("m", "alpha", "roughness"), "roughness": ("m", "alpha", "roughness")},
    "neumann_metal": {"alpha_u": ("alpha_x", "ax", "nu"), "alpha_v": ("alpha_y", "ay", "nv")},
}

#: Plugin name -> registry name, where not simply ``name.replace('-', '_')``.
SPECIAL_NAMES = {"phong": "modified-phong", "phong_original": "phong"}


def plugin_names() -> dict:
    """``{plugin name: registry name}`` for every plugin :func:`register` adds."""
    out = {}
    for name in registry.names():
        pname = "phong_original" if name == "phong" else name.replace("-", "_")
        out[pname] = name
    if "modified-phong" in registry.names():
        out["phong"] = "modified-phong"
    return out


def aliases_for(plugin: str, info) -> dict:
    """``{alias: parameter}`` of ``plugin`` (only aliases whose target exists)."""
    names = [p.name for p in info.params]
    table = dict(COMMON_ALIASES)
    table.update(PLUGIN_ALIASES.get(plugin, {}))
    out = {}
    for alias, cands in table.items():
        if alias in names:
            continue
        for c in cands:
            if c in names:
                out[alias] = c
                break
    return out


def parse_structured(text: str):
    """Parse a structured parameter given as a string in XML / ``load_dict``:
    groups separated by ``;``, numbers by commas or spaces.

    ``"-1 -1 1 20 1.75; 1 1 1 5 0.1"`` -> ``[[-1, -1, 1, 20, 1.75], [1, 1, 1, 5, 0.1]]``.
    """
    groups = [g for g in text.split(";") if g.strip()]
    return [[float(x) for x in g.replace(",", " ").split()] for g in groups]


def format_structured(value) -> str:
    """Inverse of :func:`parse_structured` (a list of number tuples -> string)."""
    return "; ".join(" ".join(repr(float(x)) for x in g) for g in value)


def _ensure_variant():
    import mitsuba as mi

    if mi.variant() is None:
        for v in ("llvm_ad_rgb", "scalar_rgb"):
            try:
                mi.set_variant(v)
                return
            except (ImportError, AttributeError, RuntimeError):
                continue
        raise RuntimeError("plausible.mitsuba: no Mitsuba variant could be set")


def _metal_textures(material: str) -> dict:
    """``{"eta": texture, "k": texture}`` of a metal from :mod:`plausible.spectra`.

    Spectral variants: Mitsuba ``irregular`` spectra on the table's wavelengths
    (the Fresnel term then varies per sampled wavelength).  RGB variants: the
    D65-weighted linear sRGB reduction of ``n(lambda)`` and ``k(lambda)``
    (:func:`plausible.spectra.spectrum_to_xyz`, :func:`xyz_to_linear_srgb`).
    """
    import mitsuba as mi

    from .. import spectra

    wl = np.arange(360.0, 831.0, 5.0)
    n, k = spectra.metal_nk(material, wl)
    out = {}
    for name, vals in (("eta", n), ("k", k)):
        if mi.is_spectral:
            out[name] = mi.load_dict({"type": "irregular",
                                      "wavelengths": ", ".join(f"{x:g}" for x in wl),
                                      "values": ", ".join(f"{x:.6g}" for x in vals)})
        else:
            rgb = spectra.xyz_to_linear_srgb(spectra.spectrum_to_xyz(wl, vals))
            out[name] = mi.load_dict({"type": "srgb", "unbounded": True,
                                      "color": mi.ScalarColor3d(*[float(x) for x in rgb])})
    return out


def _channel_mean(c):
    """Mean over the channels of a Mitsuba Spectrum / Color3f (a Float)."""
    n = len(c)
    total = c[0]
    for i in range(1, n):
        total = total + c[i]
    return total * (1.0 / n)


def _is_anisotropic(model) -> bool:
    """Numerically: does ``f`` change when both directions rotate about the normal?"""
    rng = np.random.default_rng(1)
    u = rng.random((64, 2))
    ct = 0.3 + 0.6 * u[:, 0]
    st = np.sqrt(1 - ct * ct)
    ph = 2 * math.pi * u[:, 1]
    wi = np.stack([st * np.cos(ph), st * np.sin(ph), ct], -1)
    wo = np.stack([-wi[:, 0] * 0.9 + 0.1, -wi[:, 1] * 0.9, wi[:, 2]], -1)
    a = 0.7
    rot = np.array([[math.cos(a), -math.sin(a), 0], [math.sin(a), math.cos(a), 0], [0, 0, 1]])
    f0 = model.eval(wi, wo)
    f1 = model.eval(wi @ rot.T, wo @ rot.T)
    return not np.allclose(f0, f1, rtol=1e-9, atol=1e-12 * (1 + np.max(np.abs(f0))))


def make_plugin_class(plugin: str, model_name: str):
    """A ``mitsuba.BSDF`` subclass wrapping the registered model ``model_name``."""
    import drjit as dr
    import mitsuba as mi

    from ..ops import drjit_ops

    info = model_name if isinstance(model_name, ModelInfo) else registry.info(model_name)  # or an unregistered entry
    model_name = info.name
    alias = aliases_for(plugin, info)
    spectral = mi.is_spectral

    class PlausibleBSDF(mi.BSDF):
        INFO = info
        ALIASES = alias
        PLUGIN = plugin

        def __init__(self, props):
            mi.BSDF.__init__(self, props)
            names = [p.name for p in info.params]
            given = {}
            material = props["material"] if "material" in props else None
            if material is not None:
                if not {"eta", "k"} <= set(names):
                    raise ValueError(f"{plugin}: 'material' needs a model with 'eta' and 'k' "
                                     f"parameters ({model_name} has {', '.join(names)})")
                for clash in ("eta", "k"):
                    if clash in props:
                        raise ValueError(f"{plugin}: give either 'material' or {clash!r}, not both")
            for key in props.keys():
                if key == "material":
                    continue
                target = alias.get(key, key)
                if target not in names:
                    raise ValueError(
                        f"{plugin}: unknown parameter {key!r}; allowed: "
                        f"{', '.join(names + sorted(alias))}")
                if target in given:
                    raise ValueError(f"{plugin}: parameter {target!r} given twice (aliases)")
                given[target] = key
            consts = {}   # NumPy-validated constant values (model construction)
            self._tex = {}  # name -> texture (evaluated at si)
            self._const = {}  # name -> Python value passed to hooks as is
            for prm in info.params:
                key = given.get(prm.name)
                if key is None:
                    consts[prm.name] = prm.default
                    self._const[prm.name] = prm.default
                    continue
                raw = props[key]
                if prm.kind == "model":
                    # a nested model spec (pumped_up's base): the model validates it
                    consts[prm.name] = raw
                    self._const[prm.name] = raw
                    continue
                if prm.kind not in ("scalar", "color", "choice"):
                    # structured parameter (e.g. Lafortune's lobes): a string of numbers
                    val = prm.validate(parse_structured(raw) if isinstance(raw, str) else raw, plugin)
                    consts[prm.name] = val
                    self._const[prm.name] = val
                    continue
                if prm.kind == "choice" or isinstance(raw, str):
                    consts[prm.name] = raw
                    self._const[prm.name] = raw
                    continue
                if isinstance(raw, (int, float)) and not isinstance(raw, bool):
                    consts[prm.name] = float(raw)
                    if prm.kind == "color" and spectral:
                        # a grey constant is wavelength-independent: stays a float
                        pass
                    self._const[prm.name] = float(raw)
                    continue
                if prm.kind == "color" and not isinstance(raw, mi.Object) and hasattr(raw, "__len__"):
                    # a plain list / vector of numbers (e.g. from load_dict): an sRGB colour
                    tex = mi.load_dict({"type": "srgb", "color": mi.ScalarColor3d(*[float(x) for x in raw]),
                                        "unbounded": bool(prm.hi > 1.0)})
                elif prm.kind == "color" and prm.hi <= 1.0:
                    tex = props.get_texture(key)
                else:
                    tex = props.get_unbounded_texture(key)
                if tex.is_spatially_varying():
                    # validate the range with the texture's extremes
                    try:  # range check with the texture's maximum where it has one
                        prm.validate(float(np.max(np.asarray(tex.max()))), plugin)
                    except RuntimeError:
                        pass
                    mean = float(np.mean(np.asarray(tex.mean())))
                    consts[prm.name] = min(max(mean, prm.lo), prm.hi)
                else:
                    consts[prm.name] = (np.array(raw, dtype=np.float64).ravel()
                                        if hasattr(raw, "__len__") else float(np.mean(np.asarray(tex.mean()))))
                    if np.ndim(consts[prm.name]) == 1 and consts[prm.name].size == 1:
                        consts[prm.name] = float(consts[prm.name][0])
                self._tex[prm.name] = tex
            if material is not None:
                for k2, tex in _metal_textures(material).items():
                    self._tex[k2] = tex
                    consts[k2] = float(np.mean(np.asarray(tex.mean())))
                if "fresnel" in names and "fresnel" not in given and \
                        "conductor" in info.param("fresnel").choices:
                    consts["fresnel"] = "conductor"
                    self._const["fresnel"] = "conductor"
                    given["fresnel"] = "material"
            # full validation (ranges, cross-parameter constraints) by the model itself
            self.model = info.cls(**{k: v for k, v in consts.items()
                                     if k in given or v is not None})
            # constants as the model resolved them (defaults like c=None included)
            for prm in info.params:
                if prm.name in self._tex:
                    continue
                v = getattr(self.model.p, prm.name)
                if isinstance(v, np.ndarray):
                    v = mi.load_dict({"type": "srgb", "color": mi.ScalarColor3d(*[float(x) for x in v]),
                                      "unbounded": bool(prm.hi > 1.0)})
                    self._tex[prm.name] = v
                else:
                    self._const[prm.name] = v
            self._q_const = dict(vars(self.model.q))
            self._varying = [k for k, t in self._tex.items() if t.is_spatially_varying()]
            self._q_varying = [k for k in self._varying if self._array_safe(k)]
            flags = mi.BSDFFlags.FrontSide
            if model_name == "lambertian":
                flags |= mi.BSDFFlags.DiffuseReflection
                self._sampled_type = mi.BSDFFlags.DiffuseReflection
            else:
                flags |= mi.BSDFFlags.GlossyReflection
                if {"kd", "rd"} & set(names):
                    flags |= mi.BSDFFlags.DiffuseReflection
                self._sampled_type = mi.BSDFFlags.GlossyReflection
            self.anisotropic = _is_anisotropic(self.model)
            if self.anisotropic:
                flags |= mi.BSDFFlags.Anisotropic
            if self._varying:
                flags |= mi.BSDFFlags.SpatiallyVarying
            if not info.reciprocal:
                flags |= mi.BSDFFlags.NonSymmetric
            self.m_flags = flags
            self.m_components = [flags]

        # -- parameters at a surface point ----------------------------------------
        def _array_safe(self, name) -> bool:
            """Can the sampling hooks take a per-point (array) value of ``q.name``?

            A hook may use a Python ``if`` on a sampling parameter (allowed for
            plain floats, e.g. Modified Phong's lobe-choice probability); then
            that parameter is sampled with its texture's mean (still unbiased:
            ``pdf`` and ``sample`` use the same ``q``).  Checked one parameter
            at a time with a dry run on two-element arrays.
            """
            from types import SimpleNamespace

            ops = drjit_ops(mi.Float)
            q = dict(self._q_const)
            q[name] = mi.Float([0.4, 0.6]) * float(self._q_const[name] or 1.0)
            qn = SimpleNamespace(**q)
            w = (mi.Float([0.1, 0.2]), mi.Float([0.0, 0.1]), mi.Float([0.9, 0.95]))
            try:
                self.model._pdf(ops, w, w, qn)
                self.model._sample(ops, w, (w[0], w[1], w[2]), qn)
            except Exception:  # noqa: BLE001 - any failure means "not array-safe"
                mi.Log(mi.LogLevel.Debug,
                       f"{plugin}: sampling uses the mean of texture {name!r} (the model's "
                       f"sampler is not array-safe in it)")
                return False
            return True

        def _p(self, si):
            from types import SimpleNamespace

            vals = dict(self._const)
            for k, tex in self._tex.items():
                prm = info.param(k)
                if prm.kind == "color":
                    vals[k] = tex.eval(si)
                else:
                    # channel mean of eval(), not eval_1(): Mitsuba 3.9's checkerboard
                    # eval_1 swaps its two colours (measured), eval is right
                    vals[k] = _channel_mean(tex.eval(si))
            return SimpleNamespace(**vals)

        def _q(self, si):
            from types import SimpleNamespace

            vals = dict(self._q_const)
            for k in self._q_varying:
                vals[k] = _channel_mean(self._tex[k].eval(si))
            return SimpleNamespace(**vals)

        # -- direction bookkeeping ----------------------------------------------------
        @staticmethod
        def _split(v):
            return (v.x, v.y, v.z)

        def _f_pair(self, ctx, wi_m, wo_m):
            """``(light, view)`` in plausible's order for Mitsuba's ``si.wi``, ``wo``."""
            if ctx.mode == mi.TransportMode.Importance:
                return wi_m, wo_m
            return wo_m, wi_m

        def _value(self, ctx, si, wo_c):
            ops = drjit_ops(mi.Float)
            wi_c = self._split(si.wi)
            light, view = self._f_pair(ctx, wi_c, wo_c)
            f = self.model._f(ops, light, view, self._p(si))
            return mi.Spectrum(f) * dr.maximum(wo_c[2], 0.0)

        # -- the BSDF interface ------------------------------------------------------
        def eval(self, ctx, si, wo, active=True):
            wo_c = self._split(wo)
            v = self._value(ctx, si, wo_c)
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, v, 0.0)

        def pdf(self, ctx, si, wo, active=True):
            ops = drjit_ops(mi.Float)
            pdf = mi.Float(self.model._pdf(ops, self._split(si.wi), self._split(wo), self._q(si)))
            ok = active & (si.wi.z > 0) & (wo.z > 0)
            return dr.select(ok, pdf, 0.0)

        def eval_pdf(self, ctx, si, wo, active=True):
            return self.eval(ctx, si, wo, active), self.pdf(ctx, si, wo, active)

        def sample(self, ctx, si, sample1, sample2, active=True):
            ops = drjit_ops(mi.Float)
            q = self._q(si)
            wi_c = self._split(si.wi)
            wo_c = self.model._sample(ops, wi_c, (mi.Float(sample1), sample2.x, sample2.y), q)
            wo_c = vec.normalize(ops, tuple(mi.Float(c) for c in wo_c))
            wo = mi.Vector3f(wo_c[0], wo_c[1], wo_c[2])
            pdf = mi.Float(self.model._pdf(ops, wi_c, wo_c, q))
            ok = active & (pdf > 0) & (wo.z > 0) & (si.wi.z > 0)
            value = self._value(ctx, si, wo_c)
            bs = dr.zeros(mi.BSDFSample3f)
            bs.wo = wo
            bs.pdf = dr.select(ok, pdf, 0.0)
            bs.eta = 1.0
            bs.sampled_type = mi.UInt32(int(self._sampled_type))
            bs.sampled_component = mi.UInt32(0)
            weight = dr.select(ok, value / dr.select(ok, pdf, 1.0), 0.0)
            return bs, weight

        def traverse(self, callback):
            for k, tex in self._tex.items():
                callback.put(k, tex, mi.ParamFlags.Differentiable)

        def to_string(self):
            return f"{plugin}[plausible model {model_name!r}: {self.model!r}]"

    PlausibleBSDF.__name__ = "Plausible_" + plugin
    PlausibleBSDF.__qualname__ = PlausibleBSDF.__name__
    return PlausibleBSDF


_REGISTERED: dict = {}


def register(variant: str | None = None) -> list:
    """Register a Mitsuba BSDF plugin for every registered plausible model.

    Plugins are registered for the current Mitsuba variant (``variant`` sets it
    first; with none set, ``llvm_ad_rgb`` is tried, then ``scalar_rgb``).  Call
    again after switching variants.  Returns the plugin names.
    """
    import mitsuba as mi

    from . import material

    if variant is not None:
        mi.set_variant(variant)
    _ensure_variant()
    out = []
    classes = _REGISTERED.setdefault(mi.variant(), {})
    for plugin, model in plugin_names().items():
        if plugin not in classes:
            cls = make_plugin_class(plugin, model)
            classes[plugin] = cls
            mi.register_bsdf(plugin, (lambda c: (lambda props: c(props)))(cls))
        out.append(plugin)
    out += material.register_plugin(classes)  # plausible_material (plausible.mitsuba.material)
    return out


__all__ = ["register", "plugin_names", "parse_structured", "format_structured", "aliases_for", "make_plugin_class",
           "COMMON_ALIASES", "PLUGIN_ALIASES"]
