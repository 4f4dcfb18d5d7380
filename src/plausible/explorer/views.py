"""The data behind each view of the explorer, as library functions (the web
application only serialises them).  Every function takes a model (anything with
the contract of :mod:`plausible.bxdf`) and returns plain lists and floats.

* :func:`model_catalogue` -- every registered model with its parameter specs,
  as the page builds its sliders from them;
* :func:`build` -- a model from a name and JSON parameters (the API's errors);
* :func:`plane` -- ``f cos(theta_o)`` in the plane of incidence (the polar plot);
* :func:`lobe3d` -- ``f cos(theta_o)`` over the hemisphere (the 3-D lobe);
* :func:`half_diff_slice` -- ``f`` over ``theta_h x theta_d`` at ``phi_d = 90``
  degrees (the image slice of Disney's BRDF Explorer);
* :func:`albedo` -- the directional albedo against incidence, with its error
  bound and the angles where it exceeds one (energy gained);
* :func:`verdict` -- :func:`plausible.check` (quick) as JSON;
* :func:`shader` -- the model's GLSL with its parameters as uniforms
  (:mod:`plausible.export`);
* :func:`export` -- spec, Mitsuba dict and XML, GLSL, BRDF Explorer file.
"""

from __future__ import annotations

import json
import math

import numpy as np

from .. import registry
from ..analysis import albedo_curve, direction

#: An albedo counts as energy gained where it exceeds ``1 + ENERGY_TOL`` by more than its error bound.
ENERGY_TOL = 1e-6

#: Parameter kinds that get a slider (scalar) or a colour picker (color).
SLIDER_KINDS = ("scalar", "color")


def _scale(p) -> str:
    """``log`` for exponents and roughnesses spanning decades, else ``linear``."""
    if p.numeric and not p.is_color and p.lo >= 0 and math.isfinite(p.hi) and p.hi >= 100 * max(p.lo, 1.0):
        return "log"
    return "linear"


def _bounds(p, value=None):
    """Slider ends: the parameter's bounds, an infinite one replaced by 10 or 10x the value."""
    d = value if isinstance(value, (int, float)) else p.default if isinstance(p.default, (int, float)) else 1.0
    lo = p.lo if math.isfinite(p.lo) else -max(10.0, 10 * abs(d))
    hi = p.hi if math.isfinite(p.hi) else max(10.0, 10 * abs(d))
    return lo, hi


def param_spec(p, value=None) -> dict:
    """One parameter as the page needs it: ``kind`` is ``scalar`` (a slider),
    ``color`` (a colour picker plus a grey slider), ``choice`` (a menu) or
    ``text`` (anything else, in the command line's value syntax: Lafortune's
    lobes, pumped-up's base); ``default`` is ``value`` (the value the model
    resolved, e.g. Neumann's ``c``) or the spec's default."""
    kind = p.kind if p.kind in SLIDER_KINDS + ("choice",) else "text"
    lo, hi = _bounds(p, value)
    return {"name": p.name, "kind": kind, "doc": p.doc,
            "default": p.to_json(p.default if value is None else value), "lo": lo, "hi": hi,
            "range": p.range_text(), "scale": _scale(p), "integer": bool(p.integer),
            "choices": p.options()}


def model_catalogue() -> list[dict]:
    """Every registered model: name, description, claims, parameter specs (with
    the defaults as the model resolves them); last, the catalogue entries (the
    published materials, parameters ``name`` and ``fit``)."""
    out = []
    for name in registry.names(catalogue=True):
        info = registry.info(name)
        m = info.cls()
        out.append({"name": name, "description": info.description, "reciprocal": info.reciprocal,
                    "energy_conserving": info.energy_conserving,
                    "params": [param_spec(p, m.params[p.name]) for p in info.params]})
    return out


def build(name: str, params: dict | None = None):
    """The model ``name`` with ``params`` as the page sends them (numbers, lists
    of numbers, strings in the command line's syntax).  Raises the model's own
    :class:`ValueError` (parameter, range, value) for anything out of range."""
    info = registry.info(name)
    specs = {p.name: p for p in info.params}
    ps = {}
    for k, v in (params or {}).items():
        if k not in specs:
            raise ValueError(f"{name}: unknown parameter {k!r}; allowed: {', '.join(specs)}")
        ps[k] = specs[k].parse(v) if isinstance(v, str) else v
    return registry.make(name, **ps)


def _mean(model, f):
    """The channel mean of ``model.eval``'s result (unchanged for a grey model)."""
    f = np.asarray(f, dtype=np.float64)
    return f.mean(axis=-1) if getattr(model, "channels", None) else f


def plane(model, theta_i_deg: float, n: int = 181) -> dict:
    """``f cos(theta_o)`` (channel mean) in the plane of incidence, light at
    ``theta_i`` on the ``-x`` side, ``theta_o`` from -90 to 90 degrees (positive:
    the mirror side)."""
    to = np.linspace(-90.0, 90.0, n)
    r = np.radians(np.clip(to, -89.95, 89.95))
    wo = np.stack([np.sin(r), np.zeros_like(r), np.cos(r)], -1)
    wi = direction(math.radians(theta_i_deg), math.pi)
    v = _mean(model, model.eval(wi, wo)) * wo[:, 2]
    return {"theta_o": to.tolist(), "fcos": v.tolist()}


def lobe3d(model, theta_i_deg: float, n_theta: int = 24, n_phi: int = 48) -> dict:
    """``f cos(theta_o)`` (channel mean) on a ``theta x phi`` grid of outgoing
    directions (degrees; the light at ``theta_i``, azimuth 180)."""
    th = np.linspace(0.0, 89.5, n_theta)
    ph = np.linspace(0.0, 360.0, n_phi + 1)
    T, P = np.meshgrid(np.radians(th), np.radians(ph), indexing="ij")
    wo = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    wi = direction(math.radians(theta_i_deg), math.pi)
    v = _mean(model, model.eval(wi, wo)) * wo[..., 2]
    return {"theta": th.tolist(), "phi": ph.tolist(), "fcos": v.tolist()}


def half_diff_slice(model, n: int = 64, phi_d_deg: float = 90.0) -> dict:
    """``f`` (channel mean) over ``theta_h`` (rows) x ``theta_d`` (columns), both
    0..90 degrees at cell centres, ``phi_h = 0`` and ``phi_d`` (Rusinkiewicz
    coordinates, :func:`plausible.models.merl.from_half_diff`)."""
    from ..models.merl import from_half_diff

    a = (np.arange(n) + 0.5) / n * 90.0
    TH, TD = np.meshgrid(np.radians(a), np.radians(a), indexing="ij")
    wi, wo = from_half_diff(TH, TD, np.full_like(TH, math.radians(phi_d_deg)))
    ok = (wi[..., 2] > 0) & (wo[..., 2] > 0)
    f = np.zeros(TH.shape)
    if np.any(ok):
        f[ok] = _mean(model, model.eval(wi[ok], wo[ok]))
    return {"theta_h": a.tolist(), "theta_d": a.tolist(), "f": f.tolist()}


def albedo(model, n: int = 19, phi_deg: float = 0.0) -> dict:
    """Directional albedo at ``n`` incidence angles from 0 to 89.9 degrees with
    its error bound (:func:`plausible.albedo_curve`), per channel, and the angles
    where the largest channel exceeds ``1 + ENERGY_TOL`` by more than its bound."""
    th = np.linspace(0.0, 89.9, n)
    r = albedo_curve(model, np.radians(th), phi=math.radians(phi_deg))
    v = np.asarray(r.value, dtype=np.float64)
    e = np.asarray(r.error, dtype=np.float64)
    vmax = v.max(axis=-1) if v.ndim > 1 else v
    emax = e.max(axis=-1) if e.ndim > 1 else e
    gained = [float(t) for t, a, b in zip(th, vmax, emax) if a - b > 1.0 + ENERGY_TOL]
    return {"theta": th.tolist(), "value": v.tolist(), "error": e.tolist(), "max": vmax.tolist(),
            "energy_gained_at": gained}


def verdict(model) -> dict:
    """:func:`plausible.check` in its quick form, as JSON, with the claims."""
    from ..analysis import check

    rep = check(model, quick=True)
    d = json.loads(json.dumps(rep.to_dict(), default=str))
    info = model.info if getattr(model, "info", None) is not None else None
    if info is None or info.catalogue:   # a published material: reciprocal when its terms are, no energy claim
        from types import SimpleNamespace

        info = SimpleNamespace(reciprocal=bool(getattr(model, "reciprocal", False)), energy_conserving=False)
    d["claims"] = {"reciprocal": info.reciprocal, "energy_conserving": info.energy_conserving}
    d["as_claimed"] = bool(rep.as_claimed(info))
    return d


def shader(model, prefix: str = "m0") -> dict:
    """The model's GLSL (GLSL ES 3.00; :func:`plausible.export.to_glsl`) with
    every scalar and colour parameter a uniform, and those uniforms' values."""
    from ..export import to_glsl

    s = to_glsl(model, uniforms=True, prefix=prefix, sampling=False)
    return {"source": s.text, "function": f"{prefix}_f",
            "uniforms": [{"name": u.name, "type": u.type, "value": list(map(float, u.value)),
                          "param": u.param.name} for u in s.uniforms]}


#: Export formats: name -> (file suffix, MIME type).
FORMATS = {"spec": (".txt", "text/plain"), "mitsuba-dict": (".json", "application/json"),
           "mitsuba-xml": (".xml", "application/xml"), "glsl": (".glsl", "text/plain"),
           "brdf": (".brdf", "text/plain")}


def export(model, fmt: str) -> tuple[str, str]:
    """``(file name, text)`` of ``model`` in format ``fmt`` (:data:`FORMATS`)."""
    from ..mitsuba.scene_dict import to_dict, to_xml
    from ..registry import spec_of

    if fmt not in FORMATS:
        raise ValueError(f"export format must be one of {', '.join(FORMATS)}, got {fmt!r}")
    stem = model.name
    if getattr(model.info, "catalogue", False) or (model.info is None and "@" in stem):   # a published material
        return _export_material(model, fmt)
    if fmt == "spec":
        text = spec_of(model) + "\n"
    elif fmt == "mitsuba-dict":
        text = json.dumps(to_dict(model), indent=2) + "\n"
    elif fmt == "mitsuba-xml":
        text = to_xml(model, id=stem)
    else:
        from ..export import to_brdf, to_glsl

        text = str(to_glsl(model)) if fmt == "glsl" else to_brdf(model)
    return stem + FORMATS[fmt][0], text


def _export_material(model, fmt: str) -> tuple[str, str]:
    """A published material: ``material:NAME@FIT``, the ``plausible_material`` plugin,
    or its GLSL / ``.brdf`` (every term baked in)."""
    from ..catalogue.entry import PREFIX

    name, fit = model.name.split("@", 1)
    stem = f"{name}-{fit.replace('/', '-')}"
    d = {"type": "plausible_material", "name": name, "fit": fit}
    if fmt == "spec":
        text = f"{PREFIX}{model.name}\n"
    elif fmt == "mitsuba-dict":
        text = json.dumps(d, indent=2) + "\n"
    elif fmt == "mitsuba-xml":
        text = (f'<bsdf type="plausible_material" id="{name}">\n    <string name="name" value="{name}"/>\n'
                f'    <string name="fit" value="{fit}"/>\n</bsdf>\n')
    else:
        from ..export import to_brdf, to_glsl

        text = str(to_glsl(model)) if fmt == "glsl" else to_brdf(model)
    return stem + FORMATS[fmt][0], text


__all__ = ["FORMATS", "albedo", "build", "export", "half_diff_slice", "lobe3d", "model_catalogue",
           "param_spec", "plane", "shader", "verdict"]
