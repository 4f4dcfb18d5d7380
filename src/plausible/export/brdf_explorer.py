"""A model as a Disney BRDF Explorer file (``wdas/brdf``): :func:`to_brdf`, its
parameter sliders and tables (see :mod:`plausible.export` for the format)."""

from __future__ import annotations

import copy
import math

import numpy as np

from ..text import fmt
from .glsl import P, helpers
from .shader import to_glsl

#: Steps of a float slider of BRDF Explorer (its ``FloatVarWidget``: 1000 steps
#: between the parameter line's min and max).
SLIDER_STEPS = 1000

#: The largest slider step, relative to the exported value, that :func:`slider_range`
#: allows where the declared range is too wide for it.
SLIDER_STEP = 0.01

#: The most table values a ``.brdf`` file holds: BRDF Explorer compiles a table
#: as a ``const float`` array in its shaders, which took 9 min on llvmpipe for
#: the 12,705 values of an anisotropic base; larger tables are resampled
#: (:func:`brdf_tables`).
BRDF_TABLE_LIMIT = 1200


def slider_range(spec, value) -> tuple:
    """``(min, max)`` of the slider of a float parameter exported at ``value``.

    The declared range ``[lo, hi]`` when its step (``(hi - lo) / SLIDER_STEPS``)
    is at most ``SLIDER_STEP`` of ``|value|``; otherwise (exponents: ``[0, 1e6]``,
    a step of 1000) ``[lo, 10 |value|]`` within the declared range, a step of at
    most 1 % of the value.  A value of 0 gets ``[lo, lo + 1]``.  Infinite bounds
    are replaced by finite ones the same way.  To reach values beyond the
    slider, export with that value (``-p n=10000``: a slider up to 1e5)."""
    lo, hi = spec.lo, spec.hi
    a = abs(float(value))
    if not math.isfinite(lo):
        lo = min(0.0, -10.0 * a)
    if not math.isfinite(hi) or (hi - lo) / SLIDER_STEPS > SLIDER_STEP * a:
        top = 10.0 * a if a > 0 else lo + 1.0
        short = float(f"{top:.12g}")        # 11.0, not 11.000000000000002
        top = short if short <= top else top
        hi = min(hi, max(top, lo + 1e-6 * max(a, 1.0)))
    return lo, hi


def _num(x: float) -> str:
    return repr(float(x))


def grid_text(t) -> str:
    """``"361 x 32"`` (polar x azimuth nodes) or ``"91"`` (isotropic) of an AngleTable."""
    return f"{t.n_theta} x {t.n_phi}" if t.n_phi else f"{t.n_theta}"


def brdf_tables(model, limit: int = BRDF_TABLE_LIMIT):
    """``(model, notes)``: ``model`` itself when its tables (pumped-up's albedo
    tables, :class:`~plausible.tables.AngleTable`) hold at most ``limit`` values
    each, else a copy whose larger tables are resampled to the grid of at most
    ``limit`` values that best keeps them (azimuth counts 4, 8, 16 or 32, the
    most polar nodes that fit), with one note per table naming both grids and
    the interpolation error of the resampled table (:meth:`AngleTable.difference`)."""
    tabs = getattr(model, "tables", None)
    if not tabs or all(t.size <= limit for t in tabs):
        return model, []
    new, notes = [], []
    for t in tabs:
        if t.size <= limit:
            new.append(t)
            continue
        best = None
        for n_phi in ([0] if t.isotropic else [m for m in (4, 8, 16, 32) if m <= t.n_phi]):
            n_theta = limit // (n_phi + 3) - 2 if n_phi else limit - 2
            if n_theta < 3:
                continue
            c = t.resampled(min(n_theta, t.n_theta), n_phi or None)
            err = t.difference(c)
            if best is None or err < best[0]:
                best = (err, c)
        if best is None:
            least = 5 if t.isotropic else 5 * 7
            raise ValueError(f"a table limit of {limit} values is too small for a table of {grid_text(t)} nodes: "
                             f"it needs at least {least} values (3 polar nodes{'' if t.isotropic else ' x 4 azimuths'})")
        err, c = best
        notes.append(f"albedo table {len(new)} resampled from {grid_text(t)} nodes ({t.size} values) to "
                     f"{grid_text(c)} ({c.size} values): interpolation error at most {_ceil2(err):.2g} relative "
                     f"to the albedo (at the fine nodes and between them), and so to f, which divides by "
                     f"it; plausible export --format glsl or js keeps the full table")
        new.append(c)
    out = copy.copy(model)
    out.tables = new
    return out, notes


def _ceil2(x: float) -> float:
    """``x`` rounded up to two significant digits (a bound stays a bound)."""
    if x <= 0 or not math.isfinite(x):
        return x
    unit = 10.0 ** (math.floor(math.log10(x)) - 1)
    return math.ceil(x / unit * (1 - 1e-12)) * unit


def to_brdf(model, table_limit: int = BRDF_TABLE_LIMIT) -> str:
    """The text of a Disney BRDF Explorer ``.brdf`` file for ``model``.

    Scalar parameters become ``float name min max default`` sliders
    (:func:`slider_range`), colours in ``[0, 1]`` ``color name r g b``, and
    colours that may exceed 1 (a conductor's ``eta``, ``k``) three sliders
    ``float name_r``, ``name_g``, ``name_b`` (the explorer's colour dialog picks
    only ``[0, 1]`` and stores half floats); everything else is baked in
    (listed in a comment).  Tables over ``table_limit`` values are resampled
    (:func:`brdf_tables`; the file states the interpolation error).
    The shader section holds the traced functions and
    ``vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)``, which expresses ``L``
    and ``V`` in the frame ``(X, Y, N)`` and calls ``plausible_f``; the
    ``isFunc`` section holds ``plausible_pdf`` and ``plausible_sample`` and, in
    world space, ``vec3 sampleBRDF(vec3 V, vec3 u, vec3 N, vec3 X, vec3 Y,
    out vec3 weight, out float pdf)``.
    """
    if isinstance(table_limit, bool) or not isinstance(table_limit, int) or table_limit < 1:
        raise ValueError(f"table_limit must be a positive whole number of table values, got {table_limit!r}")
    model, notes = brdf_tables(model, table_limit)
    wide = [p.name for p in type(model).PARAMS if p.is_color and p.hi > 1.0]
    shader = to_glsl(model, uniforms=True, names=lambda n: n, split_colours=wide)
    params, ranges = [], []
    for u in shader.uniforms:
        if u.type == "vec3":
            params.append(f"color {u.name} " + " ".join(_num(x) for x in u.value))
        else:
            lo, hi = slider_range(u.param, u.value[0])
            params.append(f"float {u.name} {_num(lo)} {_num(hi)} {_num(u.value[0])}")
            if (lo, hi) != (u.param.lo, u.param.hi):
                how = "R,G,B" if u.param.is_color else "VALUE"
                ranges.append(f"# {u.name}: slider {fmt(lo)} to {fmt(hi)} of the declared range "
                              f"[{fmt(u.param.lo)}, {fmt(u.param.hi)}]; for other values export with "
                              f"-p {u.param.name}={how} (the slider then spans up to 10 x the value)")
    f_end = shader.functions.index(f"{P} float {shader.prefix}_pdf(") if shader.sampling else None
    f_part = shader.functions[:f_end] if f_end is not None else shader.functions
    wrapper = """vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)
{
    // L (toward the light) = wi, V (toward the viewer) = wo, in the frame (X, Y, N)
    return plausible_f(vec3(dot(L, X), dot(L, Y), dot(L, N)), vec3(dot(V, X), dot(V, Y), dot(V, N)));
}
"""
    lines = ["analytic", "",
             f"# {shader.model}, exported by plausible (see its docs/export.md)",
             "# Lines beginning with '#' are comments for the BRDF Explorer loader.",
             *(["# baked in: " + ", ".join(f"{k}={v}" for k, v in shader.baked.items())] if shader.baked else []),
             *ranges, *(f"# {n}" for n in notes),
             "", "::begin parameters", *params, "::end parameters", "",
             "::begin shader", *_code_lines("\n\n".join(x for x in (shader.tables, helpers(shader.helper_names, guards=False),
                                                                  f_part, wrapper)
                                                       if x.strip())),
             "::end shader"]
    if shader.sampling:
        is_func = shader.functions[f_end:] + """
vec3 sampleBRDF(vec3 V, vec3 u, vec3 N, vec3 X, vec3 Y, out vec3 weight, out float pdf)
{
    // importance sampling in world space: returns L for the viewer direction V
    vec3 wo = plausible_sample(vec3(dot(V, X), dot(V, Y), dot(V, N)), u, weight, pdf);
    return wo.x * X + wo.y * Y + wo.z * N;
}
"""
        lines += ["", "::begin isFunc", *_code_lines(is_func), "::end isFunc"]
    return "\n".join(lines) + "\n"


def _code_lines(code: str) -> list:
    out = []
    for ln in code.rstrip("\n").split("\n"):
        if ln.lstrip().startswith("#") or ln.strip().startswith("::"):
            raise AssertionError(f"generated GLSL line would be dropped by the .brdf loader: {ln!r}")
        out.append(ln)
    return out
