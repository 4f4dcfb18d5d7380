"""The Mitsuba 3 plugin ``plausible_compensated``: energy compensation of any Mitsuba BSDF.

    {"type": "plausible_compensated", "method": "kulla-conty",
     "bsdf": {"type": "roughconductor", "distribution": "ggx", "alpha": 1.0}}

``bsdf``: the nested BSDF (any reflecting plugin: ``roughconductor``, ``principled``,
``roughplastic``, a plausible plugin); ``method``: ``"kulla-conty"`` (default) or
``"pumping-up"`` (with ``times``, default 1, and ``correction``, default ``"max"``), the
operators of :func:`plausible.compensate`.

At load the nested BSDF is seen through :class:`plausible.analysis.mitsuba_bsdf.MitsubaBSDF`
(radiance mode, front side) and its albedo table is built by plausible's integrator
(:func:`plausible.integrals.cache.albedo_table_of`: announced in Mitsuba's log with its
progress, cached on disk under a key made of the Mitsuba version, the variant and the nested
BSDF's ``str()``, which names the plugin and every parameter).  At a shading point:

* ``eval``: the nested ``eval`` (its ``f cos``, differentiable in its parameters), divided by
  ``g(si.wi, wo)`` (pumping-up), or plus ``F_ms (1 - E(wi)) (1 - E(wo)) / (pi (1 - E_avg)) cos``
  (Kulla-Conty), the tables read with the same Catmull-Rom lookup as the NumPy model
  (:class:`plausible.tables.AngleTable`, on Dr.Jit);
* ``sample``/``pdf``: pumping-up the nested sampler (the weight divided by ``g``); Kulla-Conty
  the mixture of the nested sampler and a cosine lobe with the NumPy model's probability
  (:meth:`plausible.models.kulla_conty.KullaConty.mix`), the weight ``eval / pdf`` of the mixture.

The tables are constants: derivatives flow through the nested BSDF's value, not through the
change of its albedo with its parameters (a table is rebuilt only at load).  The nested BSDF
must be reciprocal (a ``NonSymmetric`` one is refused) and its smooth reflection is what is
compensated; delta lobes (``conductor``) have no albedo to tabulate: a nested BSDF made of
delta lobes only is refused at load with that reason.
"""

from __future__ import annotations

import numpy as np

from .. import progress

PLUGIN = "plausible_compensated"
METHODS = ("kulla-conty", "pumping-up")


def _nested(mi, props):
    names = [k for k in props.keys() if isinstance(props[k], mi.BSDF)]
    if len(names) != 1:
        raise ValueError(f"{PLUGIN}: give exactly one nested BSDF (e.g. 'bsdf': {{'type': "
                         f"'roughconductor'}}), got {len(names)}")
    return props[names[0]]


def build_model(mi, nested, method: str, times: int = 1, correction: str = "max"):
    """The NumPy model of the plugin: :func:`plausible.compensate` of the nested BSDF (its
    tables built here, reported in Mitsuba's log)."""
    from ..analysis.compensation import compensate
    from ..analysis.mitsuba_bsdf import MitsubaBSDF
    from .plugin import mitsuba_progress

    if method not in METHODS:
        raise ValueError(f"{PLUGIN}: parameter 'method' must be one of {', '.join(METHODS)}, got {method!r}")
    flags = int(nested.flags())
    if flags & int(mi.BSDFFlags.Delta) and not flags & int(mi.BSDFFlags.Smooth):
        raise ValueError(f"{PLUGIN}: the nested BSDF {str(nested).splitlines()[0].rstrip('[')} has only delta "
                         f"lobes (a perfect mirror or refraction: it reflects into single directions), so it has "
                         f"no albedo to compensate; nest a rough BSDF instead (roughconductor, roughplastic, "
                         f"principled or a plausible plugin)")
    if flags & int(mi.BSDFFlags.NonSymmetric):
        raise ValueError(f"{PLUGIN}: the nested BSDF {str(nested).splitlines()[0]} is not reciprocal "
                         f"(NonSymmetric); both operators need f(L, V) = f(V, L)")
    with progress.reporting(progress.ambient() or mitsuba_progress(mi, PLUGIN)):
        kw = dict(times=times, correction=correction) if method == "pumping-up" else {}
        return compensate(MitsubaBSDF(nested), method, **kw)


def _operator_methods(mi, dr) -> dict:
    """The plugin's own methods: the NumPy model's factors at ``(si.wi, wo)`` on Dr.Jit."""
    from ..arrays.ops import INV_PI, drjit_ops

    def __init__(self, props):
        mi.BSDF.__init__(self, props)
        self.nested = _nested(mi, props)
        self.method = str(props.get("method", "kulla-conty"))
        self.model = build_model(mi, self.nested, self.method, int(props.get("times", 1)),
                                 str(props.get("correction", "max")))
        self.ops = drjit_ops(mi.Float)
        flags = self.nested.flags() | mi.BSDFFlags.FrontSide
        if self.method == "kulla-conty":
            flags = flags | mi.BSDFFlags.DiffuseReflection
            m = self.model
            fms = np.broadcast_to(np.asarray(m.f_ms, dtype=np.float64), (3,))
            scale = fms * (INV_PI / m.loss) if m.loss > 1e-12 else 0.0 * fms
            self.ms = mi.Color3f(*[float(x) for x in scale])
        self.m_flags = flags
        self.m_components = [flags]

    def _split(self, v):
        return (v.x, v.y, v.z)

    def _both_up(self, si, wo):
        return (mi.Frame3f.cos_theta(si.wi) > 0) & (mi.Frame3f.cos_theta(wo) > 0)

    def _g(self, si, wo):
        return self.model.g(self.ops, self._split(si.wi), self._split(wo))

    def _ms(self, si, wo):
        """``F_ms (1 - E(wi)) (1 - E(wo)) / (pi (1 - E_avg)) cos(theta_o)``."""
        m = self.model
        d = m.loss_at(self.ops, self._split(si.wi)) * m.loss_at(self.ops, self._split(wo))
        return self.ms * (d * dr.maximum(mi.Frame3f.cos_theta(wo), 0.0))

    def _value(self, ctx, si, wo, active):
        v = self.nested.eval(ctx, si, wo, active)
        up = self._both_up(si, wo) & active
        if self.method == "pumping-up":
            g = self._g(si, wo)
            return dr.select(up & (g > 0), v / dr.select(g > 0, g, 1.0), 0.0)
        return dr.select(up, v + self._ms(si, wo), 0.0)

    def _pdf(self, ctx, si, wo, active):
        p = self.nested.pdf(ctx, si, wo, active)
        if self.method == "pumping-up":
            return p
        t = self.model.mix(self.ops, self._split(si.wi), self.model.q)
        cos_pdf = dr.select(self._both_up(si, wo), dr.maximum(mi.Frame3f.cos_theta(wo), 0.0) * INV_PI, 0.0)
        return t * cos_pdf + (1.0 - t) * p

    return {k: v for k, v in locals().items() if callable(v) and k not in ("drjit_ops",)}


def _interface_methods(mi, dr) -> dict:
    """Mitsuba's BSDF interface: ``eval``, ``pdf``, ``eval_pdf``, ``sample``, ``traverse``."""

    def eval(self, ctx, si, wo, active=True):
        return self._value(ctx, si, wo, active)

    def pdf(self, ctx, si, wo, active=True):
        return self._pdf(ctx, si, wo, active)

    def eval_pdf(self, ctx, si, wo, active=True):
        return self._value(ctx, si, wo, active), self._pdf(ctx, si, wo, active)

    def sample(self, ctx, si, sample1, sample2, active=True):
        if self.method == "pumping-up":
            bs, w = self.nested.sample(ctx, si, sample1, sample2, active)
            g = self._g(si, bs.wo)
            return bs, dr.select(g > 0, w / dr.select(g > 0, g, 1.0), 0.0)
        t = self.model.mix(self.ops, self._split(si.wi), self.model.q)
        pick_cos = sample1 < t
        u0 = dr.clip((sample1 - t) / (1.0 - t), 0.0, 0.99999994)
        bs, _ = self.nested.sample(ctx, si, u0, sample2, active & ~pick_cos)
        wo = dr.select(pick_cos, mi.warp.square_to_cosine_hemisphere(sample2), bs.wo)
        bs.wo = wo
        bs.eta = dr.select(pick_cos, 1.0, bs.eta)
        bs.sampled_type = dr.select(pick_cos, mi.UInt32(+mi.BSDFFlags.DiffuseReflection), bs.sampled_type)
        bs.sampled_component = dr.select(pick_cos, 0, bs.sampled_component)
        value, pdf = self._value(ctx, si, wo, active), self._pdf(ctx, si, wo, active)
        bs.pdf = pdf
        ok = active & (pdf > 0) & self._both_up(si, wo)
        return bs, dr.select(ok, value / dr.select(pdf > 0, pdf, 1.0), 0.0)

    def traverse(self, callback):
        callback.put("bsdf", self.nested, mi.ParamFlags.Differentiable)

    def parameters_changed(self, keys=[]):  # noqa: B006 - Mitsuba's signature
        pass

    def to_string(self):
        return f"{PLUGIN}[method={self.method}, bsdf={str(self.nested).splitlines()[0]}]"

    return {k: v for k, v in locals().items() if callable(v)}


def make_compensated_class():
    """The plugin class for the current variant."""
    import drjit as dr
    import mitsuba as mi

    ns = {**_operator_methods(mi, dr), **_interface_methods(mi, dr)}
    ns["__qualname__"] = "Plausible_compensated"
    return type("Plausible_compensated", (mi.BSDF,), ns)


__all__ = ["METHODS", "PLUGIN", "build_model", "make_compensated_class"]
