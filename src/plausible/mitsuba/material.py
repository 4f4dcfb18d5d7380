"""The Mitsuba 3 plugin ``plausible_material``: a published fit of a MERL material.

    {"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"}

``name`` is a material of :func:`plausible.materials`, ``fit`` a loadable fit
set of :func:`plausible.catalogue.fits` (default ``ngan2005/ashikhmin-shirley``).
The plugin is the generic plausible plugin (:func:`plausible.mitsuba.make_plugin_class`)
around the registry entry ``material`` (:class:`plausible.catalogue.entry.Material`,
a :class:`~plausible.models.sum.Sum` built by :func:`plausible.material`); no
formula lives here.  The fits' colours are RGB,
so the plugin runs in the RGB variants (a spectral variant raises an error that
says so).
"""

from __future__ import annotations

from ..catalogue.entry import Material

PLUGIN = Material.OWNER
#: The registry entry ``material`` (:mod:`plausible.catalogue.entry`).
INFO = Material.info


def make_material_plugin_class():
    """The plugin class: the generic plugin around :class:`Material`, with
    the parts' colours converted to ``mi.Color3f`` for Dr.Jit."""
    import mitsuba as mi

    from .plugin import make_plugin_class

    base = make_plugin_class(PLUGIN, INFO.name, info=INFO)

    class PlausibleMaterial(base):
        def __init__(self, props):
            if mi.is_spectral:
                raise ValueError(f"{PLUGIN}: the published fits are RGB; use an RGB variant "
                                 f"(e.g. llvm_ad_rgb), not {mi.variant()!r}")
            super().__init__(props)
            # the generic plugin keeps its model in its ParamState (plausible.mitsuba.plugin)
            self.state.model = self.state.model.with_backend_colors(lambda a: mi.Color3f(*[float(x) for x in a]))

        def to_string(self):
            return f"{PLUGIN}[{self.model!r}]"

    PlausibleMaterial.__name__ = PlausibleMaterial.__qualname__ = "Plausible_" + PLUGIN
    return PlausibleMaterial


__all__ = ["INFO", "Material", "PLUGIN", "make_material_plugin_class"]
