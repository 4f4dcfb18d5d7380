"""Checks of the library's own keyword arguments (counts, probabilities, angle lists): a value out of
range is a ValueError naming the argument, the allowed range and the value given, raised where the
function is called, not a NumPy error from deep inside it nor a NaN result (an outside audit of bad
input found ``chi2(min_expected=-1)`` returning NaN and ``check(alpha=1.5)`` a TypeError about
complex numbers).  A model's own parameters are checked by :mod:`plausible.params`."""

from __future__ import annotations

import math
import numbers

__all__ = ["angles_deg", "count", "probability", "real"]


def count(name: str, value, lo: int = 1, hi: int | None = None) -> int:
    """``value`` as a whole number in ``[lo, hi]`` (``hi`` None: no upper end); bools are refused."""
    ok = isinstance(value, numbers.Integral) and not isinstance(value, bool)
    if not ok or value < lo or (hi is not None and value > hi):
        span = f"[{lo}, {hi}]" if hi is not None else f">= {lo}"
        raise ValueError(f"{name} must be a whole number {span}, got {value!r}")
    return int(value)


def real(name: str, value, lo: float = -math.inf, hi: float = math.inf, *, open_lo: bool = False,
         open_hi: bool = False) -> float:
    """``value`` as a finite real number in the interval from ``lo`` to ``hi`` (each end closed unless
    ``open_lo`` / ``open_hi``)."""
    ok = isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(float(value))
    if ok:
        v = float(value)
        ok = (v > lo if open_lo else v >= lo) and (v < hi if open_hi else v <= hi)
    if not ok:
        span = f"{'(' if open_lo else '['}{lo:g}, {hi:g}{')' if open_hi else ']'}"
        raise ValueError(f"{name} must be a finite number in {span}, got {value!r}")
    return float(value)


def probability(name: str, value) -> float:
    """A significance level or other probability strictly between 0 and 1."""
    return real(name, value, 0.0, 1.0, open_lo=True, open_hi=True)


def angles_deg(name: str, values, lo: float = 0.0, hi: float = 90.0, *, open_hi: bool = False) -> tuple:
    """A non-empty sequence of angles in degrees, each in ``[lo, hi]`` (``[lo, hi)`` with ``open_hi``)."""
    try:
        vals = tuple(values)
    except TypeError:
        vals = (values,)
    if not vals:
        raise ValueError(f"{name} must hold at least one angle (degrees in [{lo:g}, {hi:g}]), got {values!r}")
    return tuple(real(f"{name}[{i}] (degrees)", v, lo, hi, open_hi=open_hi) for i, v in enumerate(vals))
