"""Functions of a direction tabulated over the hemisphere, interpolated smoothly.

:class:`AngleTable` holds samples of a function ``a(theta)`` (isotropic) or
``a(theta, phi)`` (anisotropic) of a direction's polar angle ``theta`` and
azimuth ``phi`` on a uniform grid, ``theta_j = j (pi/2) / (N - 1)`` for
``j = 0..N-1`` and ``phi_k = 2 pi k / M`` for ``k = 0..M-1`` (periodic), and
reads it back with Catmull-Rom cubic interpolation (C^1, exact for quadratics,
interpolation error ``O(h^3)``), written once against the ops namespace so the
same lookup runs on NumPy and on Dr.Jit (inside the Mitsuba plugins).

Boundary nodes: below ``theta = 0`` the grid continues through the normal,
``a(-theta, phi) = a(theta, phi + pi)`` (for an isotropic table, ``a(-theta) =
a(theta)``: zero slope at the normal, as for any smooth function of the
direction); beyond the horizon it is extrapolated quadratically.

The table is used by :mod:`plausible.models.pumped_up` for the directional
albedo the operator divides by.
"""

from __future__ import annotations

import math

import numpy as np

HALF_PI = 0.5 * math.pi
TWO_PI = 2.0 * math.pi


def catmull_rom_weights(s):
    """The weights of ``p0..p3`` in the Catmull-Rom cubic through ``p1`` (``s = 0``)
    and ``p2`` (``s = 1``) on a uniform grid (Catmull & Rom 1974; tangents
    ``(p2 - p0)/2`` and ``(p3 - p1)/2``):
    ``((-s^3 + 2s^2 - s), (3s^3 - 5s^2 + 2), (-3s^3 + 4s^2 + s), (s^3 - s^2)) / 2``.
    They sum to 1 and reproduce quadratics exactly."""
    s2 = s * s
    s3 = s2 * s
    return (0.5 * (-s3 + 2.0 * s2 - s), 0.5 * (3.0 * s3 - 5.0 * s2 + 2.0),
            0.5 * (-3.0 * s3 + 4.0 * s2 + s), 0.5 * (s3 - s2))


class AngleTable:
    """Samples ``values`` of shape ``(N,)`` (a function of ``theta``) or
    ``(N, M)`` (of ``theta`` and ``phi``; ``M`` even), on the grid described in
    the module docstring.  :meth:`lookup` interpolates at directions given as
    component tuples."""

    def __init__(self, values):
        v = np.asarray(values, dtype=np.float64)
        if v.ndim not in (1, 2) or v.shape[0] < 3:
            raise ValueError(f"AngleTable: values must have shape (N,) or (N, M) with N >= 3, got {v.shape}")
        if v.ndim == 2 and (v.shape[1] < 4 or v.shape[1] % 2):
            raise ValueError(f"AngleTable: the azimuth count M must be even and >= 4, got {v.shape[1]}")
        if not np.all(np.isfinite(v)):
            raise ValueError("AngleTable: values must be finite")
        self.values = v
        self.n_theta = v.shape[0]
        self.n_phi = v.shape[1] if v.ndim == 2 else 0
        self.h_theta = HALF_PI / (self.n_theta - 1)
        self._padded = self._pad(v)
        self._backend: dict = {}

    @property
    def isotropic(self) -> bool:
        return self.n_phi == 0

    def thetas(self) -> np.ndarray:
        return np.linspace(0.0, HALF_PI, self.n_theta)

    def phis(self) -> np.ndarray:
        return np.arange(self.n_phi) * (TWO_PI / self.n_phi) if self.n_phi else np.zeros(1)

    @staticmethod
    def _pad(v):
        """Ghost nodes: one before ``theta = 0`` (through the normal) and one past
        the horizon (quadratic extrapolation, which keeps the last interval third order); for 2-D also one column before and two after in
        ``phi`` (periodic)."""
        if v.ndim == 1:
            return np.concatenate([[v[1]], v, [3.0 * (v[-1] - v[-2]) + v[-3]]])
        m = v.shape[1]
        through = np.roll(v[1], -(m // 2))  # a(theta_1, phi + pi)
        rows = np.vstack([through[None, :], v, (3.0 * (v[-1] - v[-2]) + v[-3])[None, :]])
        return np.hstack([rows[:, -1:], rows, rows[:, :2]]).ravel()

    def _table(self, ops):
        key = id(ops)
        if key not in self._backend:
            self._backend[key] = (ops, ops.table(self._padded))
        return self._backend[key][1]

    def lookup_angles(self, thetas, phis=None):
        """NumPy convenience: values at polar angles ``thetas`` (radians), shape
        ``(len(thetas),)``, or ``(len(thetas), len(phis))`` for a 2-D table."""
        from .arrays.ops import NP

        t = np.asarray(thetas, dtype=np.float64)
        if phis is None:
            if not self.isotropic:
                raise ValueError("AngleTable.lookup_angles: a 2-D table needs phis")
            return self.lookup(NP, (np.sin(t), np.zeros_like(t), np.cos(t)))
        t, p = np.meshgrid(t, np.asarray(phis, dtype=np.float64), indexing="ij")
        st = np.sin(t)
        return self.lookup(NP, (st * np.cos(p), st * np.sin(p), np.cos(t)))

    @property
    def size(self) -> int:
        """The number of stored values, ghost nodes included (what a shader holds)."""
        return len(self._padded)

    def resampled(self, n_theta: int, n_phi: int | None = None) -> "AngleTable":
        """The table on a grid of ``n_theta`` (and ``n_phi``) nodes, its values
        this table's interpolation there (a smaller table for hosts that compile
        tables as code; :meth:`difference` says what it costs)."""
        if self.isotropic:
            return AngleTable(self.lookup_angles(np.linspace(0.0, HALF_PI, n_theta)))
        return AngleTable(self.lookup_angles(np.linspace(0.0, HALF_PI, n_theta),
                                             np.arange(n_phi) * (TWO_PI / n_phi)))

    def difference(self, other: "AngleTable") -> float:
        """``max |other - self| / max(|self|, 1e-12)`` over this table's nodes and
        the midpoints between them (in ``theta`` and in ``phi``): the relative
        error of ``other`` read as an approximation of ``self``."""
        t = np.linspace(0.0, HALF_PI, 2 * self.n_theta - 1)
        if self.isotropic:
            a, b = self.lookup_angles(t), other.lookup_angles(t)
        else:
            ph = np.arange(2 * self.n_phi) * (math.pi / self.n_phi)
            a, b = self.lookup_angles(t, ph), other.lookup_angles(t, ph)
        return float(np.max(np.abs(b - a) / np.maximum(np.abs(a), 1e-12)))

    def lookup(self, ops, w):
        """The interpolated value at the directions ``w = (x, y, z)`` (unit vectors;
        ``theta`` is clamped to ``[0, pi/2]``)."""
        tab = self._table(ops)
        z = ops.minimum(ops.maximum(w[2], 0.0), 1.0)
        t = ops.minimum(ops.acos(z) * (1.0 / self.h_theta), float(self.n_theta - 1))
        i = ops.minimum(ops.floor(t), float(self.n_theta - 2))
        s = t - i
        wt = catmull_rom_weights(s)
        if self.isotropic:
            return sum(wt[k] * ops.gather(tab, i + float(k)) for k in range(4))
        m = self.n_phi
        row = float(m + 3)
        phi = ops.atan2(w[1], w[0])
        phi = ops.where(phi < 0.0, phi + TWO_PI, phi)
        tp = phi * (m / TWO_PI)
        j = ops.minimum(ops.floor(tp), float(m - 1))
        r = tp - j
        wp = catmull_rom_weights(r)
        total = 0.0
        for a in range(4):
            base = (i + float(a)) * row + j
            acc = 0.0
            for b in range(4):
                acc = acc + wp[b] * ops.gather(tab, base + float(b))
            total = total + wt[a] * acc
        return total


__all__ = ["AngleTable", "catmull_rom_weights"]
