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


def _max_abs(a: np.ndarray) -> np.ndarray:
    """The largest ``|component|`` of each row of ``a`` (shape ``(..., 3)``)."""
    return np.maximum(np.maximum(np.abs(a[..., 0]), np.abs(a[..., 1])), np.abs(a[..., 2]))


#: ``|a|^2`` outside ``(_SAFE_LO, _SAFE_HI)`` may have under- or overflowed: those
#: rows are rescaled by their largest component before normalising.
_SAFE_LO, _SAFE_HI = 1e-290, 1e290
#: ``| |a|^2 - 1 |`` up to which a direction counts as unit (about 18 ulp; a
#: normalised vector is within 3 ulp of it).
UNIT_TOL = 4e-15


def _check_block(name: str, b: np.ndarray, check_zero: bool = True):
    with np.errstate(over="ignore", under="ignore"):
        s = norm2(b)
    if not np.all(np.isfinite(s)) and not np.all(np.isfinite(b)):
        raise ValueError(f"{name} must be finite (found NaN or inf)")
    if check_zero:
        z = s == 0  # |b|^2 may underflow for a tiny non-zero b (1e-170): ask its components
        if np.any(z) and np.any(_max_abs(b[z]) == 0):
            raise ValueError(f"{name} must be non-zero vectors (a zero vector has no direction)")
    return s


def check_directions(name: str, a: np.ndarray) -> None:
    """The checks of :func:`as_directions`, in its order (a NaN anywhere before a
    zero vector anywhere), ``CHUNK`` rows at a time (so that checking allocates
    O(CHUNK), not O(N), temporaries)."""
    for b in _blocks(a):
        _check_block(name, b, check_zero=False)
    for b in _blocks(a):
        _check_block(name, b)


def normalise(a: np.ndarray, s: np.ndarray | None = None) -> np.ndarray:
    """``a / |a|`` (``s``: ``norm2(a)`` if already computed).  Rows whose
    ``|a|^2`` under- or overflows (components below 1e-145 or above 1e145) are
    first divided by their largest component, so ``[1e200, 0, 1e200]`` and
    ``[1e-170, 0, 1e-170]`` give the direction of ``[1, 0, 1]``.  Rows already
    unit to rounding (``| |a|^2 - 1 | <= UNIT_TOL``, e.g. a sampled ``wo``) are
    kept as given: normalising twice moves a direction by an ulp, and a density
    that is steep there (a ``cos^n`` lobe with ``n < 1`` near its edge, a
    direction at the horizon threshold) would then differ from the pdf that
    ``sample`` returned for it."""
    with np.errstate(over="ignore", under="ignore", divide="ignore", invalid="ignore"):
        s = norm2(a) if s is None else s
        out = np.where((np.abs(s - 1.0) <= UNIT_TOL)[..., None], a, a / np.sqrt(s)[..., None])
        bad = ~((s > _SAFE_LO) & (s < _SAFE_HI))
        if np.any(bad):
            b = np.broadcast_to(a, out.shape)[bad]
            b = b / _max_abs(b)[..., None]
            out[bad] = b / np.sqrt(norm2(b))[..., None]
    return out


def checked_unit(name: str, a: np.ndarray) -> np.ndarray:
    """:func:`check_directions` and :func:`normalise` in one pass (batches of at
    most ``CHUNK`` rows)."""
    return normalise(a, _check_block(name, a))


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
        bad = ~((b >= 0) & (b <= 1))
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


__all__ = ["CHUNK", "UNIT_TOL", "as_array", "as_directions", "as_unit_interval", "check_directions", "chunked",
           "norm2", "normalise", "prepare", "split", "stack", "unit_fn"]
