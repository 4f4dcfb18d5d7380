"""Print an expression graph of :mod:`plausible.arrays.symbolic` as GLSL statements.

The printer is the whole of the language knowledge; the formulas come from the
models' hooks, traced once.  What it guarantees:

* each distinct subexpression is computed once (nodes are identified by their
  structure, so equal subexpressions built twice by a formula share one
  temporary), in one ``float``/``bool`` statement of its own;
* every literal is a float (``1.0``, ``1.0e-12``): GLSL ES does not convert ints;
* every float declared is ``highp`` (:data:`P`): the guards and exponents need
  float32 whatever the host's default precision;
* ``where`` becomes ``c ? a : b`` with ``a`` and ``b`` computed before, as
  NumPy and Dr.Jit compute both branches, so the formulas' guards carry over;
* ``power(b, e)`` calls a helper with the contract of :mod:`plausible.arrays.ops`
  (``b <= 0`` gives ``1`` for ``e == 0``, else ``0``; GLSL's ``pow`` is
  undefined for ``b < 0`` and for ``b == 0, e <= 0``), and which for ``b`` near
  1 computes ``exp(e log1p(b - 1))`` so that ``b^e`` keeps its digits for
  exponents of 10^4 in float32;
* ``log1p`` (no GLSL built-in) is a helper exact to float32 rounding near 0,
  ``atan2`` a helper defined at the origin (0, as NumPy), ``acos`` a helper
  through ``atan`` (built-in ``acos`` errs by up to 7e-5 on SwiftShader), and
  ``sin``/``cos`` helpers with their own range reduction and polynomials
  (built-ins err by up to 2e-4 on SwiftShader).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..arrays.symbolic import Expr, Table

_INFIX = {"add": "+", "sub": "-", "mul": "*", "div": "/", "lt": "<", "le": "<=", "gt": ">",
          "ge": ">=", "eq": "==", "ne": "!=", "and": "&&", "or": "||"}
_CALL = {"sqrt": "sqrt", "exp": "exp", "log": "log",
         "floor": "floor", "abs": "abs", "min": "min", "max": "max"}


def literal(x: float) -> str:
    """``x`` as a GLSL float literal (always with a decimal point), negative
    values in parentheses; infinities as bit patterns (GLSL has no ``inf``)."""
    x = float(x)
    if math.isnan(x):
        raise ValueError("a NaN constant cannot be exported (a formula computed NaN from parameters)")
    if math.isinf(x) or abs(x) > 3.4028234663852886e38:
        s = "uintBitsToFloat(0x7F800000u)"
        return s if x > 0 else f"(-{s})"
    r = repr(abs(x))
    if "e" in r:
        mant, exp = r.split("e")
        if "." not in mant:
            mant += ".0"
        r = f"{mant}e{exp}"
    elif "." not in r:
        r += ".0"
    return f"(-{r})" if math.copysign(1.0, x) < 0 else r


#: The namespace of the helper functions, whatever the export's prefix: every
#: export defines them identically, so two exports in one shader share them
#: (each helper is guarded by ``#ifndef PLAUSIBLE_<NAME>``, see :func:`helpers`).
HELPER_PREFIX = "plausible"

#: Precision qualifier of every float the exported code declares (locals,
#: parameters, results, uniforms, tables): the formulas need float32 (exponents
#: of 1e4, guards of 1e-12, clamps of 1e30 lie outside half-float range), so the
#: code asks for highp whatever the host's default precision (GLSL ES 3.00
#: fragment shaders must support highp; desktop GLSL ignores the qualifier).
P = "highp"


def _helper_texts() -> dict:
    """``name -> (helpers it calls, GLSL text)``, in the order they are printed."""
    h = HELPER_PREFIX
    out = {}
    out["log1p"] = ((), f"""{P} float {h}_log1p({P} float x)
{{
    // log(1 + x) to float32 accuracy near 0 (log(1.0 + x) loses the digits of a small x):
    // 2 atanh(z), z = x / (2 + x), by its series for |x| < 0.25 (truncation < 4e-10)
    if (abs(x) < 0.25) {{
        {P} float z = x / (2.0 + x);
        {P} float z2 = z * z;
        return 2.0 * z * (1.0 + z2 * (1.0 / 3.0 + z2 * (0.2 + z2 * (1.0 / 7.0 + z2 * (1.0 / 9.0)))));
    }}
    return log(1.0 + x);
}}
""")
    out["pow"] = (("log1p",), f"""{P} float {h}_pow({P} float b, {P} float e)
{{
    // plausible.arrays.ops.power: defined for b >= 0 with 0^0 = 1 (GLSL pow is undefined for
    // b < 0 and for b == 0, e <= 0); near b = 1 through log1p, so b^e keeps its digits for e ~ 1e4
    if (b <= 0.0) return e == 0.0 ? 1.0 : 0.0;
    {P} float d = b - 1.0;
    if (abs(d) < 0.25) return exp(e * {h}_log1p(d));
    return exp2(e * log2(b));
}}
""")
    out["sincos"] = ((), f"""{P} float {h}_sin_quadrant({P} float x, {P} float shift)
{{
    // sin(x + shift pi/2): x - k pi/2 with pi/2 in three parts (k pi/2 exact for |k| < 2^13),
    // then Taylor polynomials on [-pi/4, pi/4] (truncation < 2e-9); GLSL's sin and cos
    // may err by 2e-4 (SwiftShader)
    {P} float k = floor(x * {literal(2.0 / math.pi)} + 0.5);
    {P} float r = ((x - k * {literal(1.5703125)}) - k * {literal(0.0004837512969970703)}) - k * {literal(7.549790126404332e-08)};
    {P} float r2 = r * r;
    {P} float s = r * (1.0 + r2 * ({literal(-1 / 6)} + r2 * ({literal(1 / 120)} + r2 * ({literal(-1 / 5040)} + r2 * {literal(1 / 362880)}))));
    {P} float c = 1.0 + r2 * (-0.5 + r2 * ({literal(1 / 24)} + r2 * ({literal(-1 / 720)} + r2 * ({literal(1 / 40320)} + r2 * {literal(-1 / 3628800)}))));
    {P} float q = k + shift;
    q -= 4.0 * floor(q * 0.25);  // the quadrant, 0.0 to 3.0 (exact: whole numbers)
    return q == 0.0 ? s : (q == 1.0 ? c : (q == 2.0 ? -s : -c));
}}

{P} float {h}_sin({P} float x)
{{
    return {h}_sin_quadrant(x, 0.0);
}}

{P} float {h}_cos({P} float x)
{{
    return {h}_sin_quadrant(x, 1.0);
}}
""")
    out["acos"] = ((), f"""{P} float {h}_acos({P} float x)
{{
    // acos(x) as atan(sqrt((1 - x)(1 + x)), x): GLSL's acos may err by 7e-5 near 0 (SwiftShader)
    return atan(sqrt((1.0 - x) * (1.0 + x)), x);
}}
""")
    out["atan2"] = ((), f"""{P} float {h}_atan2({P} float y, {P} float x)
{{
    // atan(y, x) is undefined at the origin; NumPy's arctan2 gives 0 there
    return (x == 0.0 && y == 0.0) ? 0.0 : atan(y, x);
}}
""")
    return out


_HELPERS = _helper_texts()


def helpers(used: set, guards: bool = True) -> str:
    """The helper functions ``used`` needs (``pow``, ``log1p``, ``sincos``, ``acos``,
    ``atan2``, and the helpers they call), in order.  ``guards``: each wrapped in
    ``#ifndef PLAUSIBLE_<NAME>`` / ``#define`` / ``#endif``, so that several
    exports pasted into one shader define each helper once (the helpers are the
    same text in every export); without, for hosts that drop preprocessor lines
    (BRDF Explorer's loader)."""
    need = set(used)
    for name in list(need):
        need.update(_HELPERS[name][0])
    out = []
    for name, (_, text) in _HELPERS.items():
        if name in need:
            if guards:
                macro = f"{HELPER_PREFIX.upper()}_{name.upper()}"
                text = f"#ifndef {macro}\n#define {macro}\n{text}#endif\n"
            out.append(text)
    return "\n".join(out)


#: Widest table texture (WebGL2 guarantees 2048 texels a side).
MAX_TEXTURE_WIDTH = 1024


def texture_width(n: int) -> int:
    """Width of the texture holding a table of ``n`` values (row by row)."""
    return min(n, MAX_TEXTURE_WIDTH)


@dataclass(frozen=True)
class TableTexture:
    """A table as a texture: ``width x height`` single-channel float32 texels
    (``R32F``; read with ``texelFetch``, no filtering), ``data`` row by row, the
    last row padded with zeros; ``name`` is its ``sampler2D`` uniform."""

    name: str
    width: int
    height: int
    data: np.ndarray


class Emitter:
    """Prints graphs as GLSL statements, one temporary per distinct node.

    ``names`` maps a variable of the graph (``"wi.x"``, ``"n"``, ``"rs.y"``) to
    its GLSL text; ``prefix`` names the tables (the helpers are
    :data:`HELPER_PREFIX`'s).  One emitter may
    print several functions (:meth:`function`); the helpers and tables they
    use accumulate in :attr:`used` and :attr:`tables`.
    """

    def __init__(self, prefix: str, names, tables: str = "const"):
        if tables not in ("const", "texture"):
            raise ValueError(f"tables must be 'const' or 'texture', got {tables!r}")
        self.prefix = prefix
        self.names = names
        self.table_kind = tables
        self.used: set = set()
        self.tables: dict = {}  # id(Table) -> (name, Table)

    def table_name(self, tab: Table) -> str:
        if id(tab) not in self.tables:
            self.tables[id(tab)] = (f"{self.prefix}_table{len(self.tables)}", tab)
        return self.tables[id(tab)][0]

    def table_declarations(self) -> str:
        """The tables: ``const`` arrays, or (``tables="texture"``) a ``sampler2D``
        uniform and its reader ``<name>_at(i)`` each (:meth:`textures` holds the texels)."""
        out = []
        for name, tab in self.tables.values():
            n = len(tab.values)
            if self.table_kind == "const":
                vals = ", ".join(literal(v) for v in tab.values)
                out.append(f"const {P} float {name}[{n}] = float[{n}]({vals});")
                continue
            w = texture_width(n)
            out.append(f"""uniform {P} sampler2D {name};  // {n} values in a {w} x {-(-n // w)} R32F texture, row by row
{P} float {name}_at({P} float i)
{{
    {P} int k = int(i);
    return texelFetch({name}, ivec2(k % {w}, k / {w}), 0).r;
}}""")
        return "\n".join(out)

    def textures(self) -> list:
        """``TableTexture`` s of the tables (``tables="texture"``), else ``[]``."""
        if self.table_kind != "texture":
            return []
        out = []
        for name, tab in self.tables.values():
            n = len(tab.values)
            w = texture_width(n)
            h = -(-n // w)
            data = np.zeros(w * h, dtype=np.float32)
            data[:n] = tab.values
            out.append(TableTexture(name, w, h, data))
        return out

    def statements(self, roots):
        """GLSL statements computing ``roots`` (nodes or numbers) and the text of each root."""
        lines: list = []
        key_of: dict = {}    # id(node) -> number of its structural key
        text_of: dict = {}   # structural key number -> GLSL text (temporary, literal or name)
        number: dict = {}    # structural key (children as numbers) -> its number: a key is
        # never a nested tuple, whose hash would cost the size of the whole subtree (exponential
        # for a recurrence such as Clenshaw's, where each node uses the two before it)

        def key(e):
            return key_of[id(e)]

        def visit(root):
            if not isinstance(root, Expr):
                return literal(root)
            stack = [(root, False)]
            while stack:
                e, ready = stack.pop()
                if id(e) in key_of:
                    continue
                if not ready:
                    stack.append((e, True))
                    stack.extend((a, False) for a in e.args if id(a) not in key_of)
                    continue
                if e.op == "var":
                    k = ("var", e.value)
                    text = self.names(e.value)
                elif e.op == "const":
                    k = ("const", float(e.value).hex())
                    text = literal(e.value)
                else:
                    k = (e.op, tuple(key(a) for a in e.args),
                         id(e.value) if isinstance(e.value, Table) else None)
                    text = None
                k = number.setdefault(k, len(number))
                key_of[id(e)] = k
                if k in text_of:
                    continue
                if text is None:
                    text = f"t{len(lines)}"
                    ty = "bool" if e.is_bool else f"{P} float"
                    lines.append(f"{ty} {text} = {self.expression(e, [text_of[key(a)] for a in e.args])};")
                text_of[k] = text
            return text_of[key(root)]

        return lines, [visit(r) for r in roots]

    def expression(self, e: Expr, a: list) -> str:
        op = e.op
        h = HELPER_PREFIX
        if op in _INFIX:
            return f"{a[0]} {_INFIX[op]} {a[1]}"
        if op in _CALL:
            return f"{_CALL[op]}({', '.join(a)})"
        if op == "neg":
            return f"-{a[0]}"
        if op == "not":
            return f"!{a[0]}"
        if op == "where":
            return f"{a[0]} ? {a[1]} : {a[2]}"
        if op == "pow":  # Python's ** : small whole exponents are products (any base)
            ex = e.args[1]
            if ex.op == "const" and ex.value in (0.0, 1.0, 2.0, 3.0, 4.0):
                n = int(ex.value)
                return " * ".join([a[0]] * n) if n else "1.0"
            self.used.add("pow")
            return f"{h}_pow({a[0]}, {a[1]})"
        if op == "power":
            self.used.add("pow")
            return f"{h}_pow({a[0]}, {a[1]})"
        if op == "log1p":
            self.used.add("log1p")
            return f"{h}_log1p({a[0]})"
        if op in ("sin", "cos"):
            self.used.add("sincos")
            return f"{h}_{op}({a[0]})"
        if op == "tan":
            self.used.add("sincos")
            return f"{h}_sin({a[0]}) / {h}_cos({a[0]})"
        if op == "acos":
            self.used.add("acos")
            return f"{h}_acos({a[0]})"
        if op == "atan2":
            self.used.add("atan2")
            return f"{h}_atan2({a[0]}, {a[1]})"
        if op == "gather":
            if self.table_kind == "texture":
                return f"{self.table_name(e.value)}_at({a[0]})"
            return f"{self.table_name(e.value)}[int({a[0]})]"
        raise ValueError(f"GLSL export: no translation of the operation {op!r}")

    def function(self, signature: str, roots, ret: str, prologue=(), epilogue=()) -> str:
        """A GLSL function ``signature`` that computes ``roots`` and returns
        ``ret.format(*texts)``."""
        lines, texts = self.statements(roots)
        body = list(prologue) + lines + list(epilogue) + [f"return {ret.format(*texts)};"]
        return signature + "\n{\n" + "".join(f"    {ln}\n" for ln in body) + "}\n"


def channels3(value) -> list:
    """A result as three channel values (a grey value is repeated)."""
    if isinstance(value, np.ndarray):
        vals = value.ravel().tolist()
        if len(vals) == 1:
            return vals * 3
        if len(vals) != 3:
            raise ValueError(f"GLSL export supports grey or RGB colours (3 channels), got {len(vals)} channels")
        return vals
    return [value] * 3
