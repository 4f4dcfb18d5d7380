"""Mitsuba 3 BSDF plugins for every registered :mod:`plausible` model.

``plausible.mitsuba.register()`` adds one plugin per registry entry (generic
over the registry: a model added later appears at once), plus ``merl`` for
measured MERL tables.  A plugin holds no formula: it converts Mitsuba's
``SurfaceInteraction3f`` / directions into the component tuples of the model's
hooks ``_f``, ``_pdf`` and ``_sample`` and calls them with
:func:`plausible.arrays.ops.drjit_ops`.  The parts: :mod:`.props` (properties to
parameters and textures, texture checks) and :mod:`.plugin` (the class factory,
flags, the parameters in ``mi.traverse``).

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

from .. import registry
from .plugin import make_merl_class, make_plugin_class
from .props import COMMON_ALIASES, PLUGIN_ALIASES, aliases_for
from .variant import VARIANTS, ensure_variant


def plugin_names() -> dict:
    """``{plugin name: registry name}`` for every model plugin :func:`register`
    adds: the registry name with ``-`` -> ``_``, except the registry's ``phong``
    (``phong_original``); ``phong`` is Mitsuba 0.5's name of ``modified-phong``."""
    out = {}
    for name in registry.names():
        out["phong_original" if name == "phong" else name.replace("-", "_")] = name
    if "modified-phong" in registry.names():
        out["phong"] = "modified-phong"
    return out


_REGISTERED: dict = {}


def register(variant: str | None = None) -> list:
    """Register a Mitsuba BSDF plugin for every registered plausible model.

    Plugins are registered for the current Mitsuba variant; with none set,
    :func:`plausible.mitsuba.variant.preferred` is tried (``cuda_ad_rgb`` where an NVIDIA GPU
    is found, else ``llvm_ad_rgb``), then ``scalar_rgb``.  ``variant`` is
    ``mi.set_variant(variant)`` first, **and the variant stays set**: Mitsuba
    registers a plugin for the variant that is active, so
    ``register("llvm_ad_spectral")`` makes ``llvm_ad_spectral`` the global
    variant (announced in Mitsuba's log at ``Info`` when it replaces another);
    ``mi.set_variant(old)`` goes back, where the plugins registered before still
    are.  Mitsuba keeps plugins per variant: after ``mi.set_variant(other)``,
    call ``register()`` again, else ``mi.load_dict`` says only ``Plugin
    "lambertian" not found!`` (:func:`load_dict` adds this hint).  Returns the
    plugin names (those of :func:`plugin_names`, then ``merl``,
    ``plausible_material``, ``plausible_sum`` and ``plausible_compensated``).
    """
    import mitsuba as mi

    if variant is not None:
        before = mi.variant()
        mi.set_variant(variant)
        if before is not None and before != variant:
            mi.Log(mi.LogLevel.Info, f"plausible.mitsuba.register: the Mitsuba variant is now {variant!r} "
                                     f"(was {before!r}; mi.set_variant({before!r}) goes back, its plugins "
                                     f"stay registered)")
    ensure_variant()
    classes = _REGISTERED.setdefault(mi.variant(), {})
    made = {plugin: (lambda m=model, p=plugin: make_plugin_class(p, m)) for plugin, model in plugin_names().items()}
    made["merl"] = make_merl_class
    from . import compensated, material

    made[material.PLUGIN] = material.make_material_plugin_class        # plausible_material
    made[material.SUM_PLUGIN] = material.make_sum_plugin_class         # plausible_sum
    made[compensated.PLUGIN] = compensated.make_compensated_class      # plausible_compensated
    for plugin, make in made.items():
        if plugin not in classes:
            cls = classes[plugin] = make()
            mi.register_bsdf(plugin, (lambda c: (lambda props: c(props)))(cls))
    out = list(made)
    return out


def not_registered_hint(err: Exception) -> str | None:
    """The hint for Mitsuba's ``Plugin "NAME" not found!`` when NAME is a plausible plugin
    not registered in the current variant (None for any other error)."""
    import re

    import mitsuba as mi

    found = re.search(r'Plugin "([^"]+)" not found', str(err))
    known = set(plugin_names()) | {"merl", "plausible_material", "plausible_compensated"}
    if found is None or found.group(1) not in known:
        return None
    return (f"plausible.mitsuba: the plugin {found.group(1)!r} is not registered in the variant "
            f"{mi.variant()!r}: Mitsuba keeps plugins per variant, so call plausible.mitsuba.register() "
            f"again after mi.set_variant({mi.variant()!r})")


def load_dict(desc: dict, **kw):
    """``mi.load_dict(desc)``; where it fails because a plausible plugin is not registered
    in the current variant (the variant was switched after :func:`register`), the
    RuntimeError ends with the hint to call :func:`register` again."""
    import mitsuba as mi

    try:
        return mi.load_dict(desc, **kw)
    except RuntimeError as err:
        hint = not_registered_hint(err)
        if hint is None:
            raise
        raise RuntimeError(f"{err}\n{hint}") from None


__all__ = ["VARIANTS", "ensure_variant", "register", "load_dict", "not_registered_hint", "plugin_names", "aliases_for", "make_plugin_class", "make_merl_class",
           "COMMON_ALIASES", "PLUGIN_ALIASES"]
