"""Array namespaces: the small set of operations every formula is written against.

Each formula in :mod:`plausible` is written once, component-wise (``x, y, z`` of
a direction rather than ``(..., 3)`` arrays), and takes an *ops* namespace as its
first argument.  Two namespaces exist:

* :data:`NP` wraps NumPy (float64 analysis; a plain Python float also passes
  through, which makes scalar doctests trivial);
* :func:`drjit_ops` wraps Dr.Jit (rendering inside Mitsuba 3, LLVM or CUDA).

The namespaces smooth over the differences that bite (measured with Dr.Jit 1.5):

* ``where(cond, a, b)`` is ``np.where`` / ``dr.select`` (same argument order);
  both branches are always evaluated, so formulas guard denominators *before*
  dividing.
* ``power(b, e)`` is defined for ``b >= 0`` only, with ``0**0 == 1``;
  ``dr.power(0, 0)`` is NaN and ``dr.power`` of a negative base is garbage, so
  callers clamp the base with ``maximum(b, 0)``.
* ``table(values)`` turns a 1-D sequence of constants into the backend's
  array and ``gather(table, index)`` reads it at whole-number float indices
  (tabulated functions, e.g. the albedo of :mod:`plausible.models.pumped_up`).
* ``keep_or(keep, c, fn)`` is the components ``c`` where ``keep`` and those of
  ``fn(*c)`` elsewhere: ``where`` for each component, except that Dr.Jit runs
  ``fn`` in a symbolic conditional (``dr.if_stmt``), which its LLVM backend
  skips for every packet of lanes that are all kept (NumPy evaluates ``fn``
  everywhere).  For a rare, costly branch: the normalisation of rows that are
  not unit already (:func:`plausible.directions.unit_lanes`).
* ``log1p`` exists in NumPy but not in Dr.Jit; the Dr.Jit version uses the
  classic compensated formula ``log(u) * x / (u - 1)`` with ``u = 1 + x``.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np

PI = math.pi
INV_PI = 1.0 / math.pi


def _np_power(b, e):
    return np.power(b, e)


def _np_select(cond, a, b):
    return np.where(cond, a, b)


def _np_keep_or(keep, c, fn):
    return tuple(np.where(keep, x, y) for x, y in zip(c, fn(*c)))


def _np_table(values):
    return np.ascontiguousarray(values, dtype=np.float64)


def _np_gather(table, index):
    return table[np.asarray(index).astype(np.int64)]


NP = SimpleNamespace(
    name="numpy",
    sqrt=np.sqrt,
    exp=np.exp,
    log=np.log,
    log1p=np.log1p,
    power=_np_power,
    where=_np_select,
    keep_or=_np_keep_or,
    maximum=np.maximum,
    minimum=np.minimum,
    abs=np.abs,
    sin=np.sin,
    cos=np.cos,
    tan=np.tan,
    atan2=np.arctan2,
    acos=np.arccos,
    floor=np.floor,
    clip=np.clip,
    table=_np_table,
    gather=_np_gather,
)
"""The NumPy namespace (float64)."""

_DR_CACHE: dict[str, SimpleNamespace] = {}


def drjit_ops(float_type=None) -> SimpleNamespace:
    """The Dr.Jit namespace (imported lazily: Dr.Jit is an optional dependency).

    ``float_type`` (e.g. ``drjit.llvm.Float64``, ``drjit.cuda.Float64`` or ``mi.Float``) is the array
    type that ``where`` gives its result when both branches are Python
    numbers (``dr.select`` would otherwise default to single precision).
    """
    key = repr(float_type)
    if key in _DR_CACHE:
        return _DR_CACHE[key]
    import drjit as dr

    def power(b, e):
        # dr.power(0, 0) is NaN: define 0**e as 1 for e == 0 and 0 otherwise.
        pos = b > 0
        safe = dr.select(pos, b, 1.0)
        return dr.select(pos, dr.power(safe, e), dr.select(e == 0, 1.0, 0.0))

    def log1p(x):
        u = 1.0 + x
        d = u - 1.0
        return dr.select(d == 0, x, dr.log(u) * (x / dr.select(d == 0, 1.0, d)))

    def where(cond, a, b):
        if float_type is not None and isinstance(a, (int, float)) and isinstance(b, (int, float)):
            a = float_type(a)
        return dr.select(cond, a, b)

    def keep_or(keep, c, fn):
        # fn only where a lane of the packet is not kept; both branches return the
        # same types (Python numbers would make the merge fail)
        return tuple(dr.if_stmt(tuple(c), ~keep, lambda *a: tuple(fn(*a)), lambda *a: a))

    def table(values):
        # a 1-D table of constants for :func:`gather`, of the namespace's float_type (the device's
        # Float64 of plausible.arrays.backend, or a Mitsuba variant's mi.Float)
        if float_type is None:
            raise ValueError("drjit_ops(float_type): a table needs the array type (e.g. mi.Float)")
        t = float_type
        return t(np.ascontiguousarray(values, dtype=np.float64).ravel())

    def gather(tab, index):
        # ``index`` holds whole numbers as floats (see ``floor``); Dr.Jit needs UInt32
        idx = dr.uint32_array_t(type(index))(index) if not isinstance(index, (int, float)) \
            else int(index)
        return dr.gather(type(tab), tab, idx)

    ns = SimpleNamespace(
        name="drjit",
        sqrt=dr.sqrt,
        exp=dr.exp,
        log=dr.log,
        log1p=log1p,
        power=power,
        where=where,
        keep_or=keep_or,
        maximum=dr.maximum,
        minimum=dr.minimum,
        abs=dr.abs,
        sin=dr.sin,
        cos=dr.cos,
        tan=dr.tan,
        atan2=dr.atan2,
        acos=dr.acos,
        floor=dr.floor,
        clip=dr.clip,
        table=table,
        gather=gather,
    )
    _DR_CACHE[key] = ns
    return ns
