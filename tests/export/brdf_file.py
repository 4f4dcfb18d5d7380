"""A reader of Disney BRDF Explorer ``.brdf`` files, following the loader of
``wdas/brdf`` (``BRDFBase::loadBRDF``, ``processParameterLine``,
``BRDFAnalytic::processLineFromSection``, ``loadShaderFromFile``): the first
line's first word is the type (``analytic``); blank lines and lines whose
trimmed text begins with ``#`` are dropped everywhere; ``::begin NAME`` /
``::end NAME`` delimit sections, which do not nest; parameter lines are
``float name min max default``, ``bool name 0|1`` or ``color name r g b``
(anything else fails the load); the other sections keep their lines verbatim.
The loader then declares ``uniform float|bool|vec3 name;`` for each parameter.
"""

from __future__ import annotations


class BRDFFileError(ValueError):
    pass


def parse(text: str) -> dict:
    """``{"type", "params": [(kind, name, values)], "sections": {name: code}}``."""
    lines = text.split("\n")
    kind = lines[0].strip().split(" ")[0] if lines else ""
    if kind not in ("analytic", "bparam"):
        raise BRDFFileError(f"first line must name the type 'analytic', got {lines[0]!r}")
    params, sections, current = [], {}, ""
    for n, line in enumerate(lines[1:], start=2):
        t = line.strip()
        if not t or t.startswith("#"):
            continue
        tok = t.split()
        if tok[0] == "::begin":
            if current:
                raise BRDFFileError(f"line {n}: section {tok[1]!r} begins inside {current!r}")
            current = tok[1]
            sections.setdefault(current, "")
        elif tok[0] == "::end":
            if len(tok) < 2 or tok[1] != current:
                raise BRDFFileError(f"line {n}: '::end' does not close section {current!r}")
            current = ""
        elif current == "parameters":
            if tok[0] == "float" and len(tok) == 5:
                params.append(("float", tok[1], tuple(float(x) for x in tok[2:])))
            elif tok[0] == "color" and len(tok) == 5:
                params.append(("color", tok[1], tuple(float(x) for x in tok[2:])))
            elif tok[0] == "bool" and len(tok) == 3 and tok[2] in ("0", "1"):
                params.append(("bool", tok[1], (float(tok[2]),)))
            else:
                raise BRDFFileError(f"line {n}: not a parameter line: {t!r}")
        elif current:
            sections[current] += line + "\n"
    if current:
        raise BRDFFileError(f"section {current!r} is not closed")
    return {"type": kind, "params": params, "sections": sections}


def uniforms(parsed) -> str:
    """The declarations the loader inserts (``::INSERT_UNIFORMS_HERE::``)."""
    ty = {"float": "float", "bool": "bool", "color": "vec3"}
    order = [p for k in ("float", "bool", "color") for p in parsed["params"] if p[0] == k]
    return "".join(f"uniform {ty[k]} {name};\n" for k, name, _ in order)


def defaults(parsed) -> dict:
    """Each parameter's default value, as the uniforms' values."""
    return {name: [v[2]] if k == "float" else list(v) for k, name, v in parsed["params"]}
