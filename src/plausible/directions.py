"""Directions in, arrays out: the validation and chunking of the NumPy front end.

A direction is a float array of shape ``(..., 3)`` in the local shading frame;
:func:`as_directions` checks it (finite, non-zero; the argument's name in every
error) and normalises it (a direction is a direction, whatever its length);
:func:`as_unit_interval` checks the uniform numbers ``u`` of ``sample``.
Batches of more than :data:`CHUNK` rows are checked and evaluated ``CHUNK`` rows
at a time (:func:`chunked`), so memory stays bounded.  The contract
(:mod:`plausible.bxdf`) and the adapters of foreign BSDFs
(:mod:`plausible.analysis.adapters`, :mod:`plausible.analysis.mitsuba_bsdf`)
use these public names.
"""

from __future__ import annotations

import numpy as np

from .arrays.ops import NP
from .text import shorten

#: Largest number of direction pairs evaluated in one NumPy pass; bigger batches
#: are processed in chunks so memory stays bounded.
CHUNK = 1 << 20


def as_array(name: str, w) -> np.ndarray:
    """``w`` as a float64 array of shape ``(..., 3)`` (not normalised)."""
    try:
        a = np.asarray(w, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a float array of shape (..., 3), got {shorten(repr(w))}") from None
    if a.ndim == 0 or a.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), got {a.shape}")
    return a


def _blocks(a: np.ndarray):
    """``a`` of shape ``(..., 3)`` as consecutive ``(<= CHUNK, 3)`` row blocks."""
    rows = a.reshape(-1, 3)
    for s in range(0, max(len(rows), 1), CHUNK):
        yield rows[s:s + CHUNK]


def norm2(a: np.ndarray) -> np.ndarray:
    """``x^2 + y^2 + z^2`` over the last axis, summed left to right: bitwise the
    value of ``np.sum(a * a, axis=-1)`` (a length-3 reduction adds in order),
    without NumPy's slow reduction over a short last axis."""
    x, y, z = a[..., 0], a[..., 1], a[..., 2]
    return x * x + y * y + z * z


#: ``|a|^2`` outside ``(_SAFE_LO, _SAFE_HI)`` may have under- or overflowed: those
#: rows are rescaled by their largest component before normalising.
_SAFE_LO, _SAFE_HI = 1e-290, 1e290
#: ``| |a|^2 - 1 |`` up to which a direction counts as unit (about 18 ulp; a
#: normalised vector is within 3 ulp of it).
UNIT_TOL = 4e-15


def check_block(name: str, b: np.ndarray, check_zero: bool = True):
    """The checks of :func:`check_directions` on one block ``b`` (at most
    :data:`CHUNK` rows): finite and (``check_zero``) non-zero, with the error
    naming ``name``.  Returns ``norm2(b)``, for a caller that normalises next."""
    with np.errstate(over="ignore", under="ignore"):
        s = norm2(b)
    if not np.all(np.isfinite(s)) and not np.all(np.isfinite(b)):
        raise ValueError(f"{name} must be finite (found NaN or inf)")
    if check_zero:
        z = s == 0  # |b|^2 may underflow for a tiny non-zero b (1e-170): ask its components
        if np.any(z) and np.any(max_abs(NP, split(b[z])) == 0):
            raise ValueError(f"{name} must be non-zero vectors (a zero vector has no direction)")
    return s


def check_directions(name: str, a: np.ndarray) -> None:
    """The checks of :func:`as_directions`, in its order (a NaN anywhere before a
    zero vector anywhere), ``CHUNK`` rows at a time (so that checking allocates
    O(CHUNK), not O(N), temporaries)."""
    for b in _blocks(a):
        check_block(name, b, check_zero=False)
    for b in _blocks(a):
        check_block(name, b)


def max_abs(ops, c):
    """The largest ``|component|`` of the components ``c``, against an ops namespace."""
    x, y, z = c
    return ops.maximum(ops.maximum(ops.abs(x), ops.abs(y)), ops.abs(z))


def safe_norm2(s):
    """Whether ``|a|^2 = s`` is free of under- and overflow (:func:`normalise`)."""
    return (s > _SAFE_LO) & (s < _SAFE_HI)


def unit_components(ops, c, s, keep=True):
    """The formula of :func:`normalise`, component-wise against an ops namespace
    (:mod:`plausible.arrays.ops`): each of ``c`` kept where ``keep`` and
    ``| s - 1 | <= UNIT_TOL``, else divided by ``sqrt(s)`` (``s = |c|^2``).  NumPy
    passes ``c = (a,)`` and ``s[..., None]``; :func:`unit_lanes` the three
    components of each lane, bitwise the same values."""
    keep = keep & (ops.abs(s - 1.0) <= UNIT_TOL)
    r = ops.sqrt(s)
    return tuple(ops.where(keep, x, x / r) for x in c)


#: The largest finite float64: ``|x| <= DBL_MAX`` is False for NaN and infinities.
_DBL_MAX = float(np.finfo(np.float64).max)


def unit_lanes(ops, c):
    """:func:`check_directions` and :func:`normalise` for the components ``c`` of one
    direction per lane, against an ops namespace (the Dr.Jit front end's kernels
    run it on raw input): ``(unit components, bad)``, ``bad`` True where a
    component is NaN or infinite or all three are zero (the caller then raises
    NumPy's errors, :func:`prepare`).  One path for every lane: a row whose
    ``|c|^2`` may under- or overflow is divided by its largest component first
    (the others by 1, exactly), as :func:`normalise` does for those rows alone;
    the values are bitwise :func:`normalise`'s.  A row already unit (``| |c|^2 - 1 |
    <= UNIT_TOL``, the common case) is its own result, so the divisions run only
    where one is not (``ops.keep_or``: on Dr.Jit only in packets of lanes that
    hold such a row; in issue 30's profile they were about a third of ``eval``)."""
    x, y, z = c
    s = x * x + y * y + z * z
    unit = ops.keep_or(safe_norm2(s) & (ops.abs(s - 1.0) <= UNIT_TOL), c, lambda *v: _unit_rows(ops, v))
    finite = (ops.abs(x) <= _DBL_MAX) & (ops.abs(y) <= _DBL_MAX) & (ops.abs(z) <= _DBL_MAX)
    return unit, ~finite | ((x == 0) & (y == 0) & (z == 0))


def _unit_rows(ops, c):
    """The normalisation of :func:`unit_lanes` for rows that may not be unit; the
    rescaling by the largest component runs only where ``|c|^2`` under- or
    overflows (``ops.keep_or``; never for float32 input, whose squares stay in range)."""
    x, y, z = c
    s = x * x + y * y + z * z
    safe = safe_norm2(s)
    t = ops.keep_or(safe, c, lambda *v: tuple(q / max_abs(ops, v) for q in v))
    tx, ty, tz = t
    return unit_components(ops, t, ops.where(safe, s, tx * tx + ty * ty + tz * tz), keep=safe)


def outside_unit_interval(x):
    """Where ``x`` is not in ``[0, 1]`` (NaN included): the check of :func:`as_unit_interval`."""
    return ~((x >= 0) & (x <= 1))


def interval_lanes(ops, c):
    """:func:`as_unit_interval`'s check for the components ``c`` of ``u`` per lane
    (as :func:`unit_lanes`): ``(c, bad)``, ``bad`` where a component is outside ``[0, 1]``."""
    x, y, z = c
    return c, outside_unit_interval(x) | outside_unit_interval(y) | outside_unit_interval(z)


def normalise(a: np.ndarray, s: np.ndarray | None = None) -> np.ndarray:
    """``a / |a|`` (``s``: ``norm2(a)`` if already computed).  Rows whose
    ``|a|^2`` under- or overflows (components below 1e-145 or above 1e145) are
    first divided by their largest component, so ``[1e200, 0, 1e200]`` and
    ``[1e-170, 0, 1e-170]`` give the direction of ``[1, 0, 1]``.  Rows already
    unit to rounding (``| |a|^2 - 1 | <= UNIT_TOL``, e.g. a sampled ``wo``) are
    kept as given: normalising twice moves a direction by an ulp, and a density
    that is steep there (a ``cos^n`` lobe with ``n < 1`` near its edge, a
    direction at the horizon threshold) would then differ from the pdf that
    ``sample`` returned for it.  (:func:`unit_components` is the formula, shared
    with the Dr.Jit front end's :func:`unit_lanes`.)"""
    with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
        s = norm2(a) if s is None else s
        out, = unit_components(NP, (a,), s[..., None])
        bad = ~safe_norm2(s)
        if np.any(bad):
            b = np.broadcast_to(a, out.shape)[bad]
            b = b / max_abs(NP, split(b))[..., None]
            out[bad], = unit_components(NP, (b,), norm2(b)[..., None], keep=False)
    return out


def checked_unit(name: str, a: np.ndarray) -> np.ndarray:
    """:func:`check_directions` and :func:`normalise` in one pass (batches of at
    most ``CHUNK`` rows)."""
    return normalise(a, check_block(name, a))


def as_directions(name: str, w) -> np.ndarray:
    """Validate and normalise an array of directions of shape ``(..., 3)``."""
    a = as_array(name, w)
    if a.size <= 3 * CHUNK:
        return checked_unit(name, a)
    check_directions(name, a)
    return normalise(a)


def prepare(name: str, w):
    """Validate ``w``; return ``(array, unit)``: normalised (``unit`` True) when it
    has at most ``CHUNK`` rows, else raw (checked by blocks; the caller normalises
    chunk by chunk, so no O(N) normalised copy exists)."""
    a = as_array(name, w)
    if a.size <= 3 * CHUNK:
        return checked_unit(name, a), True
    check_directions(name, a)
    return a, False


def batch_shape(**arrays) -> tuple:
    """The broadcast batch shape (without the last axis of 3) of the named
    direction arrays, or ValueError naming them and their shapes
    (``batch_shape(wi=a, wo=b)``: "wi of shape (5, 3) and wo of shape (4, 3) do
    not broadcast ...")."""
    try:
        return np.broadcast_shapes(*(a.shape for a in arrays.values()))[:-1]
    except ValueError:
        said = " and ".join(f"{k} of shape {tuple(a.shape)}" for k, a in arrays.items())
        raise ValueError(f"{said} do not broadcast: give the same number of directions, or one "
                         f"direction (shape (3,)) for all") from None


def raw_rows(w):
    """``w`` as an array of shape ``(..., 3)`` for a front end that validates and
    normalises inside its kernel: a float32 or float64 array as given (no NumPy
    pass, no float64 copy of float32 input), anything else converted to float64;
    None where that fails or the shape is wrong (:func:`prepare` then raises)."""
    if isinstance(w, np.ndarray) and w.dtype in (np.float32, np.float64):
        a = w
    else:
        try:
            a = np.asarray(w, dtype=np.float64)
        except (TypeError, ValueError):
            return None
    return a if a.ndim > 0 and a.shape[-1] == 3 else None


def unit_fn(unit: bool):
    return (lambda a: a) if unit else normalise


def as_unit_interval(u) -> np.ndarray:
    """``u`` as a float64 array of shape ``(..., 3)`` in ``[0, 1]`` (checked by blocks)."""
    try:
        u = np.asarray(u, dtype=np.float64)
    except (TypeError, ValueError):
        raise ValueError("u must be a float array of shape (..., 3)") from None
    if u.ndim == 0 or u.shape[-1] != 3:
        raise ValueError(f"u must have shape (..., 3), got {u.shape}")
    for b in _blocks(u):
        bad = outside_unit_interval(b)
        if np.any(bad):
            raise ValueError(f"u must lie in [0, 1], got {float(b[bad][0])!r}")
    return u


def _flat_rows(a: np.ndarray, shape: tuple, n: int):
    """A function ``(start, stop) -> rows`` reading ``a`` broadcast to ``shape + (3,)``
    as ``n`` flattened rows, without materialising the broadcast array: a view
    when the broadcast reshapes without a copy, else a gather of just those rows."""
    b = np.broadcast_to(a, shape + (3,))
    try:
        flat = np.reshape(b, (n, 3), copy=False)
        return lambda s, e: flat[s:e]
    except ValueError:
        return lambda s, e: b[np.unravel_index(np.arange(s, e), shape)]


def chunked(shape: tuple, arrays, block, outs):
    """Run ``block(*chunk_arrays, chunk_shape)`` on ``CHUNK``-row slices of the
    flattened broadcast ``arrays`` and write its results into ``outs``
    (preallocated, flattened, one per result).  Peak memory: the outputs plus
    the temporaries of one chunk."""
    n = int(np.prod(shape))
    readers = [_flat_rows(a, shape, n) for a in arrays]
    for s in range(0, n, CHUNK):
        e = min(s + CHUNK, n)
        res = block(*(r(s, e) for r in readers), (e - s,))
        for o, r in zip(outs, res if isinstance(res, tuple) else (res,)):
            o[s:e] = r
        del res, r  # free this chunk's results before the next chunk allocates its own


def split(a):
    return (a[..., 0], a[..., 1], a[..., 2])


def stack(c):
    return np.stack(np.broadcast_arrays(*c), axis=-1)


__all__ = ["CHUNK", "UNIT_TOL", "as_array", "as_directions", "as_unit_interval", "check_block", "check_directions",
           "chunked",
           "interval_lanes", "max_abs", "norm2", "normalise", "outside_unit_interval", "prepare", "raw_rows",
           "safe_norm2", "split", "stack", "unit_components", "unit_fn", "unit_lanes"]
