"""The one base of the adapters of foreign BSDFs (:class:`~.adapters.CallableBxDF`,
:class:`~.mitsuba_bsdf.MitsubaBSDF`): the contract's ``eval`` and ``pdf`` over
rows of broadcast directions, the foreign function asked only about pairs above
the horizon (zero elsewhere, :data:`~plausible.directions.CHUNK` rows at a time),
and the rows of ``sample``.  A subclass gives ``_value(a, b)`` (``f`` without the
cosine, shape ``(n,)`` or ``(n, channels)``), ``_density(a, b)`` (shape ``(n,)``),
``channels`` and, if it validates directions its own way, ``_directions``.
"""

from __future__ import annotations

import numpy as np

from ..directions import CHUNK, as_directions, as_unit_interval, batch_shape
from ..vec import HORIZON


class ForeignBxDF:
    """Base of the adapters: see the module docstring."""

    channels = None
    #: True where ``_value``/``_density`` only read their rows (then they may be views of the
    #: validated input, not copies); a foreign callable gets writable copies, as from a gather.
    _reads_rows_only = False

    def _directions(self, name: str, w) -> np.ndarray:
        return as_directions(name, w)

    def _tail(self) -> tuple:
        return (self.channels,) if self.channels else ()

    def _rows(self, wi, wo):
        """``(wi rows, wo rows, shape)``: both validated, broadcast and flattened."""
        wi = self._directions("wi", wi)
        wo = self._directions("wo", wo)
        shape = batch_shape(wi=wi, wo=wo)
        return (np.broadcast_to(wi, shape + (3,)).reshape(-1, 3), np.broadcast_to(wo, shape + (3,)).reshape(-1, 3),
                shape)

    def _sample_rows(self, wi, u):
        """``(wi rows, u rows, shape)`` of ``sample``, contiguous."""
        wi = self._directions("wi", wi)
        u = as_unit_interval(u)
        shape = batch_shape(wi=wi, u=u)
        return (np.ascontiguousarray(np.broadcast_to(wi, shape + (3,)).reshape(-1, 3)),
                np.ascontiguousarray(np.broadcast_to(u, shape + (3,)).reshape(-1, 3)), shape)

    def _over_upper(self, fn, a, b, tail):
        """``fn`` on the pairs with both directions above the horizon, zero elsewhere, by chunks."""
        out = np.zeros((len(a),) + tail)
        above = (a[:, 2] > HORIZON) & (b[:, 2] > HORIZON)
        if np.all(above):   # every pair (a quadrature grid): slices, no gather of the rows, no scatter
            rows = np.ascontiguousarray if self._reads_rows_only else np.array   # a callable gets its own copies
            for s in range(0, len(a), CHUNK):
                out[s:s + CHUNK] = fn(rows(a[s:s + CHUNK]), rows(b[s:s + CHUNK]))
            return out
        up = np.nonzero(above)[0]
        for s in range(0, len(up), CHUNK):
            k = up[s:s + CHUNK]
            out[k] = fn(np.ascontiguousarray(a[k]), np.ascontiguousarray(b[k]))
        return out

    def eval(self, wi, wo):
        a, b, shape = self._rows(wi, wo)
        return self._over_upper(self._value, a, b, self._tail()).reshape(shape + self._tail())

    def pdf(self, wi, wo):
        a, b, shape = self._rows(wi, wo)
        return self._over_upper(self._density, a, b, ()).reshape(shape)

    def peak_directions(self, wi):
        """The mirror direction (a foreign BSDF declares no peaks)."""
        return [np.array([-wi[0], -wi[1], wi[2]])]


__all__ = ["ForeignBxDF"]
