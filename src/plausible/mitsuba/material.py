"""The Mitsuba 3 plugin ``plausible_material``: a published fit of a MERL material.

    {"type": "plausible_material", "name": "alum-bronze", "fit": "ngan2005/ward"}

``name`` is a material of :func:`plausible.materials`, ``fit`` a loadable fit
set of :func:`plausible.catalogue.fits` (default ``ngan2005/ashikhmin-shirley``).
The plugin is the generic plausible plugin (:func:`plausible.mitsuba.make_plugin_class`)
around :class:`MaterialModel`, a :class:`~plausible.models.sum.Sum` built by
:func:`plausible.material`; no formula lives here.  The fits' colours are RGB,
so the plugin runs in the RGB variants (a spectral variant raises an error that
says so).
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

from .. import catalogue as library
from ..bxdf import Params
from ..params import ModelInfo, Param

PLUGIN = "plausible_material"


@dataclass(frozen=True)
class MaterialNameParam(Param):
    """A material name (``kind="choice"``, checked against the library with the
    closest names suggested)."""

    kind: str = "choice"

    def range_text(self) -> str:
        return "a material name of plausible.materials() (e.g. alum-bronze)"

    def validate(self, value, owner: str = "model"):
        if not isinstance(value, str) or value not in library.materials():
            names = library.materials()
            hint = library.suggest(str(value), names)
            raise ValueError(f"{owner}: parameter '{self.name}' must be {self.range_text()}, "
                             f"got {value!r}{hint}")
        return value


def _fit_param():
    keys = tuple(f.key for f in library.fits() if f.built)
    return Param("fit", library.DEFAULT_FIT, kind="choice", choices=keys,
                 doc="published fit set (plausible materials lists them)")


class MaterialModel(library.Sum):
    """``MaterialModel(name, fit)``: :func:`plausible.material` as a model with
    two parameters (what the generic plugin needs)."""

    PARAMS = (MaterialNameParam("name", "alum-bronze", doc="MERL material name"), _fit_param())

    def __init__(self, name: str = "alum-bronze", fit: str = library.DEFAULT_FIT):
        owner = PLUGIN
        name = self.PARAMS[0].validate(name, owner)
        fit = self.PARAMS[1].validate(fit, owner)
        m = library.material(name, fit)
        super().__init__(list(zip(m.parts, m.scales)), name=m.label)
        self._params = Params({"name": name, "fit": fit})
        self.p = SimpleNamespace(**self.params)
        self.q = SimpleNamespace(**self.params)


INFO = ModelInfo(name="material", cls=MaterialModel, params=MaterialModel.PARAMS,
                 description="a published fit of a MERL material (plausible.material)",
                 reciprocal=True, energy_conserving=False,
                 references=(library.NGAN, library.LOW, library.SOURCE))


def make_material_plugin_class():
    """The plugin class: the generic plugin around :class:`MaterialModel`, with
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


def register_plugin(classes: dict) -> list:
    """Register ``plausible_material`` for the current variant (once; ``classes``
    is :func:`plausible.mitsuba.register`'s per-variant cache).  Returns ``[PLUGIN]``."""
    import mitsuba as mi

    if PLUGIN not in classes:
        cls = make_material_plugin_class()
        classes[PLUGIN] = cls
        mi.register_bsdf(PLUGIN, lambda props: cls(props))
    return [PLUGIN]


__all__ = ["INFO", "MaterialModel", "PLUGIN", "make_material_plugin_class", "register_plugin"]
