"""MaterialX's own GLSL ES pixel shader (:func:`plausible.export.materialx.essl_pixel_shader`) made into a
shader of the browser harness (``glsl_webgl.Browser``): one direction pair per pixel.

The generated source is kept as MaterialX writes it, but for its declarations: ``#version`` goes (the
harness writes its own), the vertex inputs (``normalWorld``, ``tangentWorld``, ``positionWorld``), the
view position and the light data become globals that ``main`` fills from the pixel's texels, each public
uniform a ``const`` of its value, and MaterialX's ``main`` is called as ``mx_main``.  The frame: normal
``+z``, tangent ``+x``, the point at the origin, the viewer at ``wo`` (MaterialX's ``V`` is
``normalize(u_viewPosition - positionWorld)``), one directional light of colour 1 and intensity 1
shining along ``-wi``.  MaterialX's reflection closures return ``f cos(theta_i)`` times the light's
intensity (``mx_generalized_schlick_bsdf``: "NdotL is cancelled out"), so the pixel is
``f(wi, wo) cos(theta_i)``.

An image node's texture (``uniform sampler2D``) can be the harness's third input (``in2``: an ``RGBA32F``
texture of the harness's size, read at the pixel's own texel, ``texcoord_0`` its centre): the texel
``k / 255`` is what the GPU gives a shader for the 8-bit value ``k`` of an ``RGBA8`` texture (unsigned
normalised), before any colour space decode, which is the shader's (MaterialX's colour management).
"""

from __future__ import annotations

import re

#: The body of ``main``: ``a`` is wi, ``b`` is wo (``glsl_webgl.MAIN``).
BODY = """normalWorld = vec3(0.0, 0.0, 1.0); tangentWorld = vec3(1.0, 0.0, 0.0); positionWorld = vec3(0.0);
    u_viewPosition = b.xyz; u_numActiveLightSources = 1;
    u_lightData[0].type = 1; u_lightData[0].direction = -a.xyz;
    u_lightData[0].color = vec3(1.0); u_lightData[0].intensity = 1.0;
    mx_main();
    outColor = vec4(out1.rgb, 1.0);"""


def _float(x) -> str:
    s = f"{float(x):.9g}"
    return s if any(c in s for c in ".en") else s + ".0"


def _literal(t: str, v) -> str:
    if t == "int":
        return str(int(v))
    if t == "float":
        return _float(v)
    return f"{t}(" + ", ".join(_float(x) for x in v) + ")"


#: The texture coordinate of the pixel's own texel of ``in2`` (an image read per pixel).
TEXCOORD = "texcoord_0 = (vec2(ij) + 0.5) / vec2(textureSize(in2, 0));\n    "


def harness_shader(source: str, uniforms: dict, image: str | None = None) -> tuple[str, str]:
    """``(code, body)`` for ``Browser.run`` from MaterialX's pixel shader and its uniforms' values;
    ``image``: the sampler uniform (an image node's ``file``) read from the harness's input ``in2``."""
    code = source.replace("#version 300 es", "")
    if image is not None:
        decl = f"uniform sampler2D {image};"
        if decl not in code:
            raise ValueError(f"image: no sampler {image!r} in the shader")
        code = code.replace(decl, f"#define {image} in2")
    code = re.sub(r"^in (\w+) (\w+);", r"\1 \2;", code, flags=re.M)
    code = re.sub(r"^out vec4 out1;", "vec4 out1;", code, flags=re.M)
    for decl in ("vec3 u_viewPosition;", "int u_numActiveLightSources;", "LightData u_lightData[MAX_LIGHT_SOURCES];"):
        code = code.replace("uniform " + decl, decl)

    def const(m):
        t, name = m.group(1), m.group(2)
        return f"const {t} {name} = {_literal(t, uniforms[name])};" if name in uniforms else m.group(0)

    code = re.sub(r"^uniform (int|float|vec3|vec2|vec4) (\w+);", const, code, flags=re.M)
    if "u_refractionTwoSided" in code and "bool u_refractionTwoSided" not in code:
        # used by the transmission's environment lookup, declared by MaterialX's viewer, not by the generator
        code = "const bool u_refractionTwoSided = false;\n" + code
    code = re.sub(r"^void main\(\)", "void mx_main()", code, flags=re.M)
    return code, (TEXCOORD if image is not None else "") + BODY
