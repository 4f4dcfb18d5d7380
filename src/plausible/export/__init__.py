"""Export a model as GLSL: a WebGL2/OpenGL function, an ES module for three.js and a
Disney BRDF Explorer file.

The model's own hooks are traced with the symbolic namespace
(:mod:`plausible.symbolic`) and printed by :mod:`plausible.export.glsl`, so a
shader computes the same formula as NumPy and Dr.Jit (to float32 rounding;
``tests/export/test_browser.py`` measures it in a real browser).

* :func:`to_glsl` -- a :class:`GLSLShader`: GLSL ES 3.00 functions
  ``vec3 plausible_f(vec3 wi, vec3 wo)`` (the BRDF without the cosine, local
  frame: ``z`` the normal, ``x`` the tangent ``u``), and where the model samples,
  ``float plausible_pdf(vec3 wi, vec3 wo)`` and
  ``vec3 plausible_sample(vec3 wi, vec3 u, out vec3 weight, out float pdf)``
  (the contract of :mod:`plausible.bxdf`).  Parameters are baked in as constants,
  or with ``uniforms=True`` (or a list of names) declared as uniforms.
* :func:`to_brdf` -- the text of a ``.brdf`` file of Disney's BRDF Explorer
  (``wdas/brdf``): ``analytic``, a ``::begin parameters`` block built from the
  parameter specifications, ``::begin shader`` with
  ``vec3 BRDF(vec3 L, vec3 V, vec3 N, vec3 X, vec3 Y)``, and an ``isFunc``
  section with the importance sampler.  Its loader drops every line that begins
  with ``#`` (so no preprocessor lines) and compiles with ``#version 410``.
* :func:`to_js` -- an ES module for three.js and WebGL2: the GLSL with every
  parameter a uniform and tables as ``R32F`` textures, the uniforms' initial
  values and the textures' texels (``examples/three/index.html`` renders it).

Several exports share one shader with distinct ``prefix`` es: the helpers
(``plausible_pow``, ...) are the same in every export and each is guarded by
``#ifndef``.  Every float the code declares is ``highp``.

What is not a uniform: choices (``fresnel="schlick"``), whole numbers
(``times``), Lafortune's lobe list and pumped-up's base model change the
formula itself, so they are always baked in.  Pumped-up's albedo table (a
function of the base) becomes a ``const float`` array in the shader (or a
texture, ``tables="texture"``; resampled to at most :data:`BRDF_TABLE_LIMIT`
values in a ``.brdf`` file, with the interpolation error stated).
"""

from __future__ import annotations

import copy
import json
import math
import re
from dataclasses import dataclass, field
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from .. import symbolic
from ..bxdf import BxDF
from ..text import fmt
from ..symbolic import SYM
from .glsl import P, Emitter, channels3, helpers, literal

__all__ = ["FORMATS", "GLSLShader", "Uniform", "brdf_tables", "check_prefix", "slider_range", "to_brdf",
           "to_glsl", "to_js", "uniform_params", "write"]

#: Parameter kinds that can be uniforms (others change the formula's structure).
UNIFORM_KINDS = ("scalar", "color")

#: Names the generated functions use for their own arguments.
RESERVED = {"wi", "wo", "u", "weight", "pdf", "L", "V", "N", "X", "Y"}


@dataclass(frozen=True)
class Uniform:
    """A parameter exported as a uniform: GLSL ``name``, ``type`` (``float`` or
    ``vec3``), its current ``value`` and its spec (:class:`~plausible.params.Param`)."""

    name: str
    type: str
    value: tuple
    param: object

    def declaration(self) -> str:
        return f"uniform {P} {self.type} {self.name};"


@dataclass
class GLSLShader:
    """The exported functions of one model, in parts a host shader can assemble.

    ``uniforms`` (declarations via :meth:`declarations`), ``tables`` (``const``
    arrays), ``helpers`` (``plausible_pow``, ``plausible_log1p``, ... each in an
    ``#ifndef`` guard; ``helper_names`` the ones used), ``functions``
    and, for ``tables="texture"``, ``textures`` (:class:`~plausible.export.glsl.TableTexture`:
    the texels of each table's ``sampler2D`` uniform)
    (``<prefix>_f`` and, if ``sampling``, ``<prefix>_pdf``, ``<prefix>_sample``);
    ``str(shader)`` is all of it in that order, with a header comment.  No
    ``#version``, no ``precision`` line and no ``main``: those are the host's;
    every float declared is ``highp`` (the formulas need float32 whatever the
    host's default precision).
    """

    model: str
    prefix: str
    uniforms: list
    tables: str
    helpers: str
    functions: str
    sampling: bool
    baked: dict = field(default_factory=dict)
    helper_names: frozenset = frozenset()
    textures: list = field(default_factory=list)

    def declarations(self) -> str:
        return "\n".join(u.declaration() for u in self.uniforms)

    @property
    def text(self) -> str:
        head = (f"// {self.model}, exported by plausible (GLSL ES 3.00 / GLSL 4.10).\n"
                f"// {self.prefix}_f(wi, wo): BRDF value, no cosine; local frame: z = normal, x = tangent u.\n")
        if self.baked:
            head += "// baked in: " + ", ".join(f"{k}={v}" for k, v in self.baked.items()) + "\n"
        parts = [head + self.declarations(), self.tables, self.helpers, self.functions]
        return "\n\n".join(p.strip("\n") for p in parts if p.strip()) + "\n"

    def __str__(self):
        return self.text


def uniform_params(model, uniforms=True) -> list:
    """The parameter specs of ``model`` that become uniforms: every scalar and
    colour parameter for ``True``, none for ``False``, or those named in a list
    (ValueError for a name that is not such a parameter)."""
    specs = [p for p in type(model).PARAMS if p.kind in UNIFORM_KINDS and not p.integer]
    if uniforms is True:
        return specs
    if not uniforms:
        return []
    names = list(uniforms)
    ok = {p.name: p for p in specs}
    bad = [n for n in names if n not in ok]
    if bad:
        raise ValueError(f"{model.name}: cannot make {', '.join(map(repr, bad))} a uniform; "
                         f"parameters that can be uniforms: {', '.join(ok) or 'none'}")
    return [ok[n] for n in names]


def check_prefix(prefix: str, what: str = "prefix") -> str:
    """``prefix`` if it can begin GLSL names (a letter, then letters, digits and
    single underscores; not ``gl_``: GLSL reserves ``gl_`` and ``__``), else
    ValueError naming ``what``."""
    if not (isinstance(prefix, str) and re.fullmatch(r"[A-Za-z][A-Za-z0-9_]*", prefix)
            and "__" not in prefix + "_" and not prefix.startswith("gl_")):
        raise ValueError(f"{what} must be a GLSL name: a letter, then letters, digits and single "
                         f"underscores, not ending in '_' nor beginning with 'gl_' (e.g. 'ward'), got {prefix!r}")
    return prefix


def _symbolic_params(model, specs):
    """``p`` and ``q`` of the hooks with the parameters ``specs`` symbolic."""
    p = dict(vars(model.p))
    q = dict(vars(model.q))
    for spec in specs:
        if spec.kind == "color":
            arr = symbolic.param(spec.name, 3)
            p[spec.name] = arr
            q[spec.name] = (arr[0] + arr[1] + arr[2]) * (1.0 / 3.0)
        else:
            p[spec.name] = q[spec.name] = symbolic.param(spec.name)
    return SimpleNamespace(**p), SimpleNamespace(**q)


def _has_sampling(model) -> bool:
    cls = type(model)
    return cls._pdf is not BxDF._pdf and cls._sample is not BxDF._sample


def _trace(model, hook, *args):
    try:
        return symbolic.trace(lambda: hook(SYM, *args))
    except symbolic.SymbolicBranchError as e:
        raise ValueError(f"{model.name}: {hook.__name__} cannot be exported: {e}") from None


def to_glsl(model, uniforms=False, *, prefix: str = "plausible", sampling: bool = True,
            names=None, tables: str = "const", split_colours=()) -> GLSLShader:
    """Export ``model`` (a :class:`~plausible.bxdf.BxDF`) as GLSL functions.

    Parameters
    ----------
    model : BxDF
        The model with its parameters (their values are the constants, or the
        uniforms' initial values).
    uniforms : bool or list of str
        ``False``: parameters baked in as constants; ``True``: every scalar and
        colour parameter that the formulas read is a uniform named ``<prefix>_<name>`` (``float``, or
        ``vec3`` for a colour); a list: only those.  A Python ``if`` of a hook
        on a uniform parameter is exported as both branches joined by ``?:``.
    prefix : str
        Prefix of the model's global names (functions, tables, uniforms), so
        several models can share one shader; the helpers keep the names
        ``plausible_pow`` etc. in every export, each guarded by ``#ifndef``
        (:func:`plausible.export.glsl.helpers`), and so are defined once.
    sampling : bool
        Also export ``<prefix>_pdf`` and ``<prefix>_sample`` (if the model samples).
    names : callable, optional
        Maps a parameter name to its GLSL name (default ``<prefix>_<name>``).
    tables : str
        How tables (pumped-up's albedo) are stored: ``"const"``, ``const float``
        arrays in the code; ``"texture"``, each a ``uniform highp sampler2D``
        (``R32F``, read with ``texelFetch``) whose texels are in
        ``shader.textures`` (a compile of seconds instead of minutes for the
        12,705 values of an anisotropic base).
    split_colours : sequence of str
        Colour uniforms declared as three ``float`` uniforms ``<name>_r``,
        ``<name>_g``, ``<name>_b`` (for hosts whose colour controls stop at 1).

    Returns
    -------
    GLSLShader
        ``str(shader)`` is a self-contained GLSL ES 3.00 snippet.
    """
    check_prefix(prefix)
    specs = uniform_params(model, uniforms)
    name_of = names or (lambda n: f"{prefix}_{n}")
    for s in specs:
        if name_of(s.name) in RESERVED:
            raise ValueError(f"{model.name}: parameter name {s.name!r} clashes with an argument "
                             f"of the exported functions; pass names= or a prefix")
    p, q = _symbolic_params(model, specs)

    split = set(split_colours)

    def glsl_name(var):
        base, _, comp = var.partition(".")
        if base in ("wi", "wo", "u"):
            return var
        if comp and base in split:
            return f"{name_of(base)}_{'rgb'['xyz'.index(comp)]}"
        return name_of(base) + (f".{comp}" if comp else "")

    em = Emitter(prefix, glsl_name, tables)
    chans = [1] if model.channels is None else [model.channels]
    if chans[0] not in (1, 3):
        raise ValueError(f"{model.name}: GLSL export supports grey or RGB colours, the model has "
                         f"{chans[0]} channels")
    do_sampling = sampling and _has_sampling(model)
    funcs, roots = _functions(model, em, prefix, p, q, do_sampling)
    # a parameter the traced functions never read (eta and k without fresnel='conductor')
    # is no uniform: a slider that does nothing would mislead
    read = {v.partition(".")[0] for r in roots if isinstance(r, symbolic.Expr) for v in r.deps}
    specs = [s for s in specs if s.name in read]
    values = _uniforms(model, specs, name_of, split)
    uni = {s.name for s in specs}
    baked = {k: fmt(v, other=repr) for k, v in model.params.items() if k not in uni}
    return GLSLShader(model=repr(model), prefix=prefix, uniforms=values, tables=em.table_declarations(),
                      helpers=helpers(em.used), functions="\n".join(funcs),
                      sampling=do_sampling, baked=baked, helper_names=frozenset(em.used),
                      textures=em.textures())


def _functions(model, em, prefix, p, q, sampling):
    """``(GLSL functions, traced roots)``: ``<prefix>_f`` and, with ``sampling``,
    ``<prefix>_pdf``, ``<prefix>_sample_direction`` and the sample front end."""
    wi, wo = symbolic.direction("wi"), symbolic.direction("wo")
    f = channels3(_trace(model, model._f, wi, wo, p))
    roots = list(f)
    # wi, wo are unit vectors (the contract's front end normalises; a shader's caller does)
    funcs = [em.function(f"{P} vec3 {prefix}_f({P} vec3 wi, {P} vec3 wo)", f, "vec3({0}, {1}, {2})")]
    if sampling:
        pdf = _trace(model, model._pdf, wi, wo, q)
        roots.append(pdf)
        funcs.append(em.function(f"{P} float {prefix}_pdf({P} vec3 wi, {P} vec3 wo)", [pdf], "{0}"))
        wo_s = _trace(model, model._sample, wi, symbolic.direction("u"), q)
        roots.extend(wo_s)
        funcs.append(em.function(f"{P} vec3 {prefix}_sample_direction({P} vec3 wi, {P} vec3 u)", list(wo_s),
                                 "vec3({0}, {1}, {2})"))
        funcs.append(_sample_front_end(prefix))
    return funcs, roots


def _uniforms(model, specs, name_of, split) -> list:
    """A :class:`Uniform` per parameter of ``specs`` with the model's value
    (a colour of ``split`` as three ``float`` uniforms ``_r``, ``_g``, ``_b``)."""
    values = []
    for s in specs:
        v = model.params[s.name]
        if s.kind == "color" and s.name in split:
            values.extend(Uniform(f"{name_of(s.name)}_{c}", "float", (float(x),), s)
                          for c, x in zip("rgb", np.broadcast_to(v, 3)))
        elif s.kind == "color":
            values.append(Uniform(name_of(s.name), "vec3", tuple(float(x) for x in np.broadcast_to(v, 3)), s))
        else:
            values.append(Uniform(name_of(s.name), "float", (float(v),), s))
    return values


def _sample_front_end(prefix: str) -> str:
    """The contract's ``sample`` (:meth:`plausible.bxdf.BxDF.sample`) around the
    traced direction: normalise ``wo``, its pdf, ``weight = f cos / pdf``, zero
    below the horizon."""
    return f"""{P} vec3 {prefix}_sample({P} vec3 wi, {P} vec3 u, out {P} vec3 weight, out {P} float pdf)
{{
    // wi a unit vector; u in [0, 1)^3: u.x picks a lobe, u.yz drive the warp (plausible.bxdf.BxDF.sample)
    {P} vec3 wo = {prefix}_sample_direction(wi, u);
    {P} float len = length(wo);
    wo = len > 0.0 ? wo / len : vec3(0.0, 0.0, -1.0);
    pdf = {prefix}_pdf(wi, wo);
    bool ok = pdf > 0.0 && wo.z > {literal(1e-12)} && wi.z > {literal(1e-12)};
    weight = ok ? {prefix}_f(wi, wo) * (wo.z / (ok ? pdf : 1.0)) : vec3(0.0);
    pdf = ok ? pdf : 0.0;
    return wo;
}}
"""


# -- Disney BRDF Explorer ---------------------------------------------------------------

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
    wide = [p.name for p in type(model).PARAMS if p.kind == "color" and p.hi > 1.0]
    shader = to_glsl(model, uniforms=True, names=lambda n: n, split_colours=wide)
    params, ranges = [], []
    for u in shader.uniforms:
        if u.type == "vec3":
            params.append(f"color {u.name} " + " ".join(_num(x) for x in u.value))
        else:
            lo, hi = slider_range(u.param, u.value[0])
            params.append(f"float {u.name} {_num(lo)} {_num(hi)} {_num(u.value[0])}")
            if (lo, hi) != (u.param.lo, u.param.hi):
                how = "R,G,B" if u.param.kind == "color" else "VALUE"
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


# -- an ES module for three.js and WebGL2 ------------------------------------------------

def to_js(model, prefix: str = "plausible") -> str:
    """The text of an ES module carrying ``model`` for three.js or plain WebGL2
    (``examples/three/index.html`` loads it as ``./brdf.js``):

    * ``glsl``: the functions (:func:`to_glsl`, every parameter a uniform,
      tables as ``sampler2D`` textures);
    * ``functions``: their names (``{f, pdf, sample}``; ``pdf`` and ``sample``
      null if the model does not sample);
    * ``uniforms``: each uniform's initial value, the model's parameter, as an
      array of 1 or 3 numbers (a uniform left unset would read 0);
    * ``textures``: each table as ``{width, height, data}``, ``data`` a
      ``Float32Array`` of ``width x height`` texels (single channel, row by row,
      for an ``R32F`` texture read without filtering: three.js
      ``DataTexture(data, width, height, RedFormat, FloatType)``);
    * ``model``: the model's ``repr``.
    """
    shader = to_glsl(model, uniforms=True, prefix=prefix, tables="texture")
    names = {"f": f"{prefix}_f", "pdf": f"{prefix}_pdf" if shader.sampling else None,
             "sample": f"{prefix}_sample" if shader.sampling else None}
    lines = [f"// {shader.model}, exported by plausible: an ES module for three.js / WebGL2 "
             f"(see docs/export.md and examples/three/index.html).",
             f"export const model = {json.dumps(shader.model)};",
             f"export const glsl = {_js_string(shader.text)};",
             f"export const functions = {json.dumps(names)};",
             "export const uniforms = {"
             + ", ".join(f"{json.dumps(u.name)}: [{', '.join(repr(float(x)) for x in u.value)}]"
                         for u in shader.uniforms) + "};"]
    tex = []
    for t in shader.textures:
        vals = ", ".join(repr(float(x)) for x in t.data)
        tex.append(f"  {json.dumps(t.name)}: {{width: {t.width}, height: {t.height}, "
                   f"data: new Float32Array([{vals}])}}")
    lines.append("export const textures = {" + ("\n" + ",\n".join(tex) + "\n" if tex else "") + "};")
    return "\n".join(lines) + "\n"


def _js_string(text: str) -> str:
    """``text`` as a JavaScript string literal: a template literal (readable, one
    line per line of GLSL) where nothing in it needs escaping, else JSON."""
    if not any(c in text for c in ("`", "\\", "${")):
        return f"`{text}`"
    return json.dumps(text)


FORMATS = ("glsl", "brdf", "js")


def write(model, fmt: str, path, uniforms=False, prefix: str = "plausible",
          table_limit: int = BRDF_TABLE_LIMIT) -> str:
    """Export ``model`` as ``fmt`` (``"glsl"``, ``"brdf"`` or ``"js"``) into ``path``
    (None: no file); returns the text.  ``prefix``: of the GLSL names
    (:func:`to_glsl`, :func:`to_js`; a ``.brdf`` file holds one model);
    ``table_limit``: of a ``.brdf`` file's tables (:func:`to_brdf`)."""
    if fmt == "glsl":
        text = to_glsl(model, uniforms=uniforms, prefix=prefix).text
    elif fmt == "brdf":
        text = to_brdf(model, table_limit=table_limit)
    elif fmt == "js":
        text = to_js(model, prefix=prefix)
    else:
        raise ValueError(f"export format must be one of {', '.join(map(repr, FORMATS))}, got {fmt!r}")
    if path is not None:
        Path(path).write_text(text)
    return text
