"""The symbolic ops namespace: a third backend that records what a hook computes.

Beside :data:`plausible.arrays.ops.NP` (NumPy) and :func:`plausible.arrays.ops.drjit_ops`
(Dr.Jit), :data:`SYM` runs the same formulas on :class:`Expr` values, nodes of
an expression graph, so that the one copy of the math can be printed in another
language (:mod:`plausible.export` prints GLSL).  Nothing in the models changes:
a hook called with ``SYM`` and symbolic directions returns the graph of its
result instead of numbers.

Rules that keep a trace faithful:

* Arithmetic on plain Python numbers is folded at once (in float64), so a
  parameter baked in as a constant leaves only its value in the graph.
* ``where(cond, a, b)`` records both branches (a shader evaluates both too, so
  the guards the formulas already carry for NumPy and Dr.Jit apply unchanged).
* A symbolic value has no truth value: ``if expr:``, ``and``, ``or``, ``min``,
  ``max`` on a traced value raise :class:`SymbolicBranchError` instead of
  silently taking one branch for every input.  The one exception is a branch on
  parameters only (a value built from :func:`param` leaves, never from the
  directions): :func:`trace` runs the hook once per outcome and joins the
  results with ``where`` (both branches, as the shader must do when the
  parameter is a uniform).
* Colour parameters are NumPy object arrays of expressions (one per channel);
  the formulas' broadcasting then yields one expression per channel.
* ``table(values)`` / ``gather(table, index)`` record a constant table and an
  indexed read (the albedo table of :mod:`plausible.models.pumped_up`).

:func:`evaluate` computes a graph with NumPy (float64); the tests use it to
show that the trace equals the NumPy backend for every registered model.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

__all__ = ["Expr", "SYM", "SymbolicBranchError", "Table", "direction", "param", "trace", "evaluate"]


class SymbolicBranchError(TypeError):
    """Python control flow on a traced value (it has no truth value)."""


_NUMBER = (int, float, np.integer, np.floating, bool, np.bool_)


class Table:
    """A 1-D table of float64 constants (``ops.table``), read by ``ops.gather``."""

    __slots__ = ("values", "__weakref__")

    def __init__(self, values):
        self.values = np.ascontiguousarray(values, dtype=np.float64).ravel()


class Expr:
    """A node of an expression graph: ``op`` with ``args`` (nodes or, for the
    leaves ``var`` and ``const``, a name or a float in ``value``).

    ``is_bool`` marks comparisons and their logic; ``deps`` is the set of
    variables the node depends on and ``kinds`` their kinds (``"dir"`` for the
    directions and random numbers, ``"param"`` for parameters)."""

    __slots__ = ("op", "args", "value", "is_bool", "deps", "kinds")
    __array_ufunc__ = None  # NumPy defers to our reflected operators

    def __init__(self, op, args=(), value=None, is_bool=False, kind=None):
        self.op = op
        self.args = tuple(args)
        self.value = value
        self.is_bool = is_bool
        if op == "var":
            self.deps = frozenset((value,))
            self.kinds = frozenset((kind,))
        else:
            ex = [a for a in self.args if isinstance(a, Expr)]
            self.deps = frozenset().union(*(a.deps for a in ex)) if ex else frozenset()
            self.kinds = frozenset().union(*(a.kinds for a in ex)) if ex else frozenset()

    def __repr__(self):
        if self.op == "var":
            return self.value
        if self.op == "const":
            return repr(self.value)
        return f"{self.op}({', '.join(map(repr, self.args))})"

    __hash__ = object.__hash__

    # -- no truth value ------------------------------------------------------------
    def __bool__(self):
        ctx = _BRANCHING[-1] if _BRANCHING else None
        if ctx is None or "dir" in self.kinds:
            what = ("depends on the directions (" + ", ".join(sorted(self.deps)) + ")"
                    if "dir" in self.kinds else
                    "depends on the parameter(s) " + ", ".join(sorted(self.deps)))
            raise SymbolicBranchError(
                f"Python control flow (if/and/or/min/max) on a traced value that {what}: "
                f"a shader cannot take that branch; write it with ops.where")
        return ctx.decide(self)

    def __float__(self):
        raise SymbolicBranchError(f"a traced value ({', '.join(sorted(self.deps)) or 'constant'}) "
                                  f"cannot be converted to a Python float")

    # -- arithmetic -------------------------------------------------------------------
    def __add__(self, o): return _binary("add", self, o)
    def __radd__(self, o): return _binary("add", o, self)
    def __sub__(self, o): return _binary("sub", self, o)
    def __rsub__(self, o): return _binary("sub", o, self)
    def __mul__(self, o): return _binary("mul", self, o)
    def __rmul__(self, o): return _binary("mul", o, self)
    def __truediv__(self, o): return _binary("div", self, o)
    def __rtruediv__(self, o): return _binary("div", o, self)
    def __pow__(self, o): return _binary("pow", self, o)
    def __rpow__(self, o): return _binary("pow", o, self)
    def __neg__(self): return _node("neg", self)
    def __pos__(self): return self
    def __abs__(self): return _node("abs", self)
    # comparisons and logic (boolean nodes)
    def __lt__(self, o): return _binary("lt", self, o)
    def __le__(self, o): return _binary("le", self, o)
    def __gt__(self, o): return _binary("gt", self, o)
    def __ge__(self, o): return _binary("ge", self, o)
    def __eq__(self, o): return _binary("eq", self, o)
    def __ne__(self, o): return _binary("ne", self, o)
    def __and__(self, o): return _binary("and", self, o)
    def __rand__(self, o): return _binary("and", o, self)
    def __or__(self, o): return _binary("or", self, o)
    def __ror__(self, o): return _binary("or", o, self)
    def __invert__(self): return _node("not", self)


def direction(name: str) -> tuple:
    """The components ``(name.x, name.y, name.z)`` of a symbolic direction."""
    return tuple(Expr("var", value=f"{name}.{c}", kind="dir") for c in "xyz")


def param(name: str, channels: int = 0):
    """A parameter leaf; with ``channels`` an object array of ``name.x``, ``name.y``, ..."""
    if not channels:
        return Expr("var", value=name, kind="param")
    return np.array([Expr("var", value=f"{name}.{c}", kind="param") for c in "xyzw"[:channels]],
                    dtype=object).view(Channels)


# -- node construction with constant folding ------------------------------------------

_BOOL_OPS = {"lt", "le", "gt", "ge", "eq", "ne", "and", "or", "not"}

_FOLD = {
    "add": lambda a, b: a + b, "sub": lambda a, b: a - b, "mul": lambda a, b: a * b,
    "div": lambda a, b: np.float64(a) / np.float64(b),
    "pow": lambda a, b: np.power(np.float64(a), np.float64(b)),
    "neg": lambda a: -a, "abs": abs,
    "lt": lambda a, b: a < b, "le": lambda a, b: a <= b, "gt": lambda a, b: a > b,
    "ge": lambda a, b: a >= b, "eq": lambda a, b: a == b, "ne": lambda a, b: a != b,
    "and": lambda a, b: bool(a) and bool(b), "or": lambda a, b: bool(a) or bool(b),
    "not": lambda a: not a,
    "sqrt": np.sqrt, "exp": np.exp, "log": np.log, "log1p": np.log1p, "sin": np.sin,
    "cos": np.cos, "tan": np.tan, "acos": np.arccos, "floor": np.floor,
    "atan2": np.arctan2, "min": np.minimum, "max": np.maximum,
    "power": lambda b, e: np.power(np.float64(b), np.float64(e)) if b > 0 else (1.0 if e == 0 else 0.0),
}


def _fold(op, args):
    with np.errstate(all="ignore"):
        v = _FOLD[op](*args)
    if op in _BOOL_OPS:
        return bool(v)
    return float(v)


class Channels(np.ndarray):
    """An object array of channel values (colours).  NumPy's comparison ufuncs
    cast object results to ``bool``, which would ask an :class:`Expr` for a
    truth value; here comparisons build boolean nodes channel by channel."""

    def _cmp(self, other, op):
        return _elementwise(lambda a, b: _node(op, a, b), (self, other))

    def __lt__(self, o): return self._cmp(o, "lt")
    def __le__(self, o): return self._cmp(o, "le")
    def __gt__(self, o): return self._cmp(o, "gt")
    def __ge__(self, o): return self._cmp(o, "ge")
    def __eq__(self, o): return self._cmp(o, "eq")
    def __ne__(self, o): return self._cmp(o, "ne")
    __hash__ = None


def _obj(a):
    """``a`` as an object array (an :class:`Expr` refuses NumPy's ufuncs otherwise)."""
    if isinstance(a, np.ndarray):
        return a
    out = np.empty((), dtype=object)
    out[()] = a
    return out


def _elementwise(fn, args):
    """``fn`` over the elements of object arrays (colour channels), broadcast."""
    out = np.frompyfunc(fn, len(args), 1)(*(_obj(a) for a in args))
    return np.asarray(out, dtype=object).view(Channels)


def _node(op, *args):
    """A node, or the folded value when no argument is symbolic; object arrays
    (colour channels) are mapped element by element."""
    if any(isinstance(a, np.ndarray) for a in args):
        return _elementwise(lambda *xs: _node(op, *xs), args)
    if not any(isinstance(a, Expr) for a in args):
        return _fold(op, [bool(a) if isinstance(a, (bool, np.bool_)) else float(a) for a in args])
    if op in ("and", "or"):
        # a Python bool on one side decides or vanishes
        for a, b in ((args[0], args[1]), (args[1], args[0])):
            if isinstance(a, (bool, np.bool_)):
                if op == "and":
                    return b if a else False
                return True if a else b
    conv = []
    for a in args:
        if isinstance(a, Expr):
            conv.append(a)
        elif isinstance(a, _NUMBER):
            conv.append(Expr("const", value=float(a)))
        else:
            return NotImplemented
    return Expr(op, conv, is_bool=op in _BOOL_OPS)


def _binary(op, a, b):
    return _node(op, a, b)


def _where(cond, a, b):
    if any(isinstance(x, np.ndarray) for x in (cond, a, b)):
        return _elementwise(_where, (cond, a, b))
    if isinstance(cond, (bool, np.bool_)):
        return a if cond else b
    if not isinstance(cond, Expr):
        raise TypeError(f"where: condition must be a comparison, got {cond!r}")
    if a is b:
        return a
    args = [x if isinstance(x, Expr) else Expr("const", value=float(x)) for x in (a, b)]
    return Expr("where", (cond, *args))


def _fn(op):
    return lambda *args: _node(op, *args)


def _clip(x, lo, hi):
    return _node("min", _node("max", x, lo), hi)


def _gather(tab, index):
    if isinstance(index, np.ndarray):
        return _elementwise(lambda i: _gather(tab, i), (index,))
    if not isinstance(index, Expr):
        return float(tab.values[int(index)])
    return Expr("gather", (index,), value=tab)


SYM = SimpleNamespace(
    name="symbolic",
    sqrt=_fn("sqrt"),
    exp=_fn("exp"),
    log=_fn("log"),
    log1p=_fn("log1p"),
    power=_fn("power"),
    where=_where,
    maximum=_fn("max"),
    minimum=_fn("min"),
    abs=_fn("abs"),
    sin=_fn("sin"),
    cos=_fn("cos"),
    tan=_fn("tan"),
    atan2=_fn("atan2"),
    acos=_fn("acos"),
    floor=_fn("floor"),
    clip=_clip,
    table=Table,
    gather=_gather,
)
"""The symbolic namespace (see the module docstring).  ``power(b, e)`` keeps the
contract of :mod:`plausible.arrays.ops`: defined for ``b >= 0`` with ``0**0 == 1``."""


# -- branches on parameters -------------------------------------------------------------

_BRANCHING: list = []

#: Most outcomes :func:`trace` explores (2**6: six independent parameter branches).
MAX_PATHS = 64


class _Undecided(Exception):
    def __init__(self, cond):
        self.cond = cond


class _Path:
    def __init__(self, decisions):
        self.decisions = decisions
        self.pos = 0

    def decide(self, cond):
        if self.pos < len(self.decisions):
            d = self.decisions[self.pos]
            self.pos += 1
            return d
        raise _Undecided(cond)


def _join(cond, a, b):
    """``where(cond, a, b)`` over nested tuples / arrays of results."""
    if isinstance(a, tuple):
        return tuple(_join(cond, x, y) for x, y in zip(a, b))
    return _where(cond, a, b)


def trace(fn, explore: bool = True):
    """Call ``fn()`` (a hook applied to symbolic inputs) and return its result.

    A Python branch on a value built only from parameters is explored both ways
    (``explore=True``) and the outcomes joined with ``where``; with
    ``explore=False`` it raises :class:`SymbolicBranchError` naming the parameters.
    A branch on anything that depends on the directions always raises.
    """
    if not explore:
        return fn()
    count = [0]

    def run(decisions):
        path = _Path(decisions)
        _BRANCHING.append(path)
        try:
            return fn()
        except _Undecided as u:
            cond = u.cond
        finally:
            _BRANCHING.pop()
        count[0] += 1
        if count[0] > MAX_PATHS:
            raise SymbolicBranchError(f"more than {MAX_PATHS} Python branches on the parameter(s) "
                                      f"{', '.join(sorted(cond.deps))}; bake them in as constants")
        return _join(cond, run(decisions + [True]), run(decisions + [False]))

    return run([])


# -- reading a graph ---------------------------------------------------------------------

_EVAL = {
    **{k: v for k, v in _FOLD.items() if k not in ("div", "pow", "power", "and", "or", "not", "abs")},
    "div": lambda a, b: a / b, "abs": np.abs,
    "pow": np.power,
    "power": lambda b, e: np.where(b > 0, np.power(np.where(b > 0, b, 1.0), e), np.where(e == 0, 1.0, 0.0)),
    "and": np.logical_and, "or": np.logical_or, "not": np.logical_not,
}


def evaluate(root, env: dict):
    """The value of the graph ``root`` (an :class:`Expr`, a number, or a tuple /
    object array of them) with NumPy float64, ``env`` mapping variable names
    (``"wi.x"``, ``"n"``, ``"rs.y"``) to arrays."""
    memo: dict = {}

    def ev(e):
        if not isinstance(e, Expr):
            return e
        k = id(e)
        if k in memo:
            return memo[k]
        if e.op == "var":
            v = np.asarray(env[e.value], dtype=np.float64)
        elif e.op == "const":
            v = np.float64(e.value)
        elif e.op == "where":
            v = np.where(ev(e.args[0]), ev(e.args[1]), ev(e.args[2]))
        elif e.op == "gather":
            v = e.value.values[np.asarray(ev(e.args[0])).astype(np.int64)]
        else:
            v = _EVAL[e.op](*(ev(a) for a in e.args))
        memo[k] = v
        return v

    def walk(x):
        if isinstance(x, tuple):
            return tuple(walk(y) for y in x)
        if isinstance(x, np.ndarray):
            return np.stack(np.broadcast_arrays(*[np.asarray(walk(y), dtype=np.float64)
                                                  for y in x.ravel().tolist()]), axis=-1)
        return ev(x)

    with np.errstate(all="ignore"):
        return walk(root)
