"""A model as a Mitsuba 3 scene description: the dict ``mi.load_dict`` takes and
the ``<bsdf>`` XML element of a scene file, for the plugins that
:func:`plausible.mitsuba.register` adds.  Pure data: Mitsuba is not imported.

Scalars are floats, colours ``{"type": "rgb", "value": [r, g, b]}`` (``<rgb>``),
choices strings, Lafortune's lobes the ``;``-separated string the plugin parses,
a nested model (pumped-up's base) its spec string.
"""

from __future__ import annotations

from xml.sax.saxutils import quoteattr

from ..bxdf import BxDF


def plugin_name(model: BxDF) -> str:
    """The Mitsuba plugin name of a registered model (``modified-phong`` -> ``phong``)."""
    from . import plugin_names

    for plugin, name in plugin_names().items():
        if name == model.name and not (name == "modified-phong" and plugin != "phong"):
            return plugin
    raise ValueError(f"{model.name!r} has no Mitsuba plugin (is it a registered model?)")


def to_dict(model: BxDF) -> dict:
    """The ``mi.load_dict`` description of ``model`` as a plausible plugin: a published fit
    (``material:NAME@FIT``) as ``plausible_material``, any other sum of models
    (:class:`~plausible.models.sum.Sum`) as ``plausible_sum`` with its spec."""
    spec = model.spec() if hasattr(model, "parts") and hasattr(model, "scales") else None
    from ..catalogue.entry import PREFIX
    from ..catalogue.fit_sets import parse_spec

    if spec is not None and spec.startswith(PREFIX):
        name, fit = parse_spec(spec)
        return {"type": "plausible_material", "name": name, "fit": fit}
    if spec is not None:
        return {"type": "plausible_sum", "spec": spec}
    d = {"type": plugin_name(model)}
    for p in type(model).PARAMS:
        v = model.params[p.name]
        if v is None:
            continue
        d[p.name] = p.to_mitsuba(v)
    return d


def to_xml(model: BxDF, id: str | None = None) -> str:
    """The ``<bsdf>`` element of a Mitsuba 3 scene file for ``model``."""
    d = to_dict(model)
    head = f'<bsdf type={quoteattr(d.pop("type"))}' + (f" id={quoteattr(id)}" if id else "") + ">"
    lines = [head]
    for k, v in d.items():
        if isinstance(v, dict):
            val = ", ".join(f"{x:.9g}" for x in v["value"])
            lines.append(f"    <rgb name={quoteattr(k)} value={quoteattr(val)}/>")
        elif isinstance(v, float):
            lines.append(f"    <float name={quoteattr(k)} value={quoteattr(f'{v:.17g}')}/>")
        else:
            lines.append(f"    <string name={quoteattr(k)} value={quoteattr(str(v))}/>")
    lines.append("</bsdf>")
    return "\n".join(lines) + "\n"


__all__ = ["plugin_name", "to_dict", "to_xml"]
