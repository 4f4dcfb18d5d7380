"""The Mitsuba 3 plugins ``plausible_material`` (a published fit of a MERL material) and
``plausible_sum`` (a sum of models given by its spec, ``{"type": "plausible_sum", "spec": "a + b"}``,
what :func:`plausible.mitsuba.scene_dict.to_dict` writes for a :class:`~plausible.models.sum.Sum`).

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

import numpy as np

from ..catalogue.entry import Material
from ..models.sum import Sum
from ..params import ModelInfo, ModelParam

PLUGIN = Material.OWNER
#: The registry entry ``material`` (:mod:`plausible.catalogue.entry`).
INFO = Material.info
#: The plugin of a sum of models, and its one parameter: the sum's spec (:meth:`Sum.spec`), built
#: by :func:`plausible.make` (no registry entry: a sum is a composition, not a family).
SUM_PLUGIN = "plausible_sum"
SUM_INFO = ModelInfo("sum", Sum, (ModelParam("spec", "lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50.0",
                                             doc="the sum's spec, 'a + SCALE * b'"),),
                     "A sum of models, f = sum_k s_k f_k (plausible.models.sum.Sum), given by its spec.")


def _as_data(mi, model):
    """``model`` with its parts' parameters, scales and lobe probabilities as opaque Dr.Jit values
    (kernel inputs, :mod:`plausible.kernel_params`) instead of constants: the instances of one fitted
    model then trace to the same code, which Dr.Jit compiles once for a scene of many materials (the
    atlas's 100 spheres: one callable, not 100).  A model whose hooks need its values as numbers keeps
    them as constants (``mi.Color3f`` colours)."""
    import drjit as dr

    def convert(v):
        if isinstance(v, np.ndarray):
            return mi.Color3f(*[dr.opaque(mi.Float, float(x)) for x in np.ravel(v)])
        return dr.opaque(mi.Float, float(v))

    try:
        view = model._kernel_view(convert)
        _trace(mi, view)
        return view
    except Exception:  # noqa: BLE001 - hooks that branch on a value: constants, as before
        return model.with_backend_colors(lambda a: mi.Color3f(*[float(x) for x in a]))


def _trace(mi, model):
    """Trace (not run) the hooks on one lane: raises where a hook cannot take data parameters."""
    from ..arrays.ops import drjit_ops

    ops = drjit_ops(mi.Float)
    w = (mi.Float(0.3), mi.Float(0.2), mi.Float(0.9327379053088815))
    model._f(ops, w, w, model.p)
    model._pdf(ops, w, w, model.q)
    model._sample(ops, w, (mi.Float(0.5), mi.Float(0.5), mi.Float(0.5)), model.q)


def make_sum_plugin_class():
    """The plugin ``plausible_sum``: the generic plugin around the model its ``spec`` builds
    (:data:`SUM_INFO`), with the parts' colours as kernel data (as ``plausible_material``)."""
    import mitsuba as mi

    from .plugin import make_plugin_class

    base = make_plugin_class(SUM_PLUGIN, SUM_INFO.name, info=SUM_INFO)

    class PlausibleSum(base):
        def __init__(self, props):
            super().__init__(props)
            self.state.model = _as_data(mi, self.state.model)

        def _model_factory(self, props):
            from ..registry import make_from_spec

            return lambda spec: spec if hasattr(spec, "eval") else make_from_spec(spec)

        def to_string(self):
            return f"{SUM_PLUGIN}[{self.model.spec()}]"

    PlausibleSum.__name__ = PlausibleSum.__qualname__ = "Plausible_" + SUM_PLUGIN
    return PlausibleSum


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
            self.state.model = _as_data(mi, self.state.model)

        def to_string(self):
            return f"{PLUGIN}[{self.model!r}]"

    PlausibleMaterial.__name__ = PlausibleMaterial.__qualname__ = "Plausible_" + PLUGIN
    return PlausibleMaterial


__all__ = ["INFO", "Material", "PLUGIN", "SUM_INFO", "SUM_PLUGIN", "make_material_plugin_class",
           "make_sum_plugin_class"]
