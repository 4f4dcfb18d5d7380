"""GLSL of a model: :func:`to_glsl` (a :class:`GLSLShader`) and :func:`to_js`
(an ES module for three.js and WebGL2).  The face :mod:`plausible.export`
describes the formats; the printer is :mod:`plausible.export.glsl`.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field
from types import SimpleNamespace

import numpy as np

from ..arrays import symbolic
from ..bxdf import BxDF
from ..text import fmt
from ..arrays.symbolic import SYM
from .glsl import P, Emitter, channels3, helpers, literal

__all__ = ["GLSLShader", "RESERVED", "UNIFORM_KINDS", "Uniform", "check_prefix", "to_glsl", "to_js", "uniform_params"]

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
        if spec.is_color:
            arr = symbolic.param(spec.name, 3)
            p[spec.name] = arr
            q[spec.name] = (arr[0] + arr[1] + arr[2]) * (1.0 / 3.0)
        else:
            p[spec.name] = q[spec.name] = symbolic.param(spec.name)
    return SimpleNamespace(**p), SimpleNamespace(**q)


def _has_sampling(model) -> bool:
    cls = type(model)
    if cls.lobes is not BxDF.lobes:
        return True     # the mixture of its declared lobes (BxDF._pdf, BxDF._sample)
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
        if s.is_color and s.name in split:
            values.extend(Uniform(f"{name_of(s.name)}_{c}", "float", (float(x),), s)
                          for c, x in zip("rgb", np.broadcast_to(v, 3)))
        elif s.is_color:
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
