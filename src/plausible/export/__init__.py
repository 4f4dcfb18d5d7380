"""Export a model as GLSL: a WebGL2/OpenGL function, an ES module for three.js and a
Disney BRDF Explorer file.

The model's own hooks are traced with the symbolic namespace
(:mod:`plausible.arrays.symbolic`) and printed by :mod:`plausible.export.glsl`, so a
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

from .brdf_explorer import BRDF_TABLE_LIMIT, brdf_tables, slider_range, to_brdf
from .shader import GLSLShader, Uniform, check_prefix, to_glsl, to_js, uniform_params

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
        from ..text import write_atomic

        write_atomic(path, text)
    return text


__all__ = ["BRDF_TABLE_LIMIT", "FORMATS", "GLSLShader", "Uniform", "brdf_tables", "check_prefix", "slider_range",
           "to_brdf", "to_glsl", "to_js", "uniform_params", "write"]
