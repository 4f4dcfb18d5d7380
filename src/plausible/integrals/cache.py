"""The integrals a model may be defined by, cached: albedo tables and horizon albedos.

Pumping-up (:mod:`plausible.models.pumped_up`) divides its base by the base's
directional albedo, tabulated once per base with the accurate quadrature
(:func:`plausible.integrals.albedo.albedo_table`) and interpolated with
Catmull-Rom cubics (:class:`plausible.tables.AngleTable`).  A table is cached in
memory (:data:`_TABLES`) and on disk (:func:`table_cache_dir`), keyed by the
exact text of the model (:func:`spec_of`) and a hash of the source that
determines it (the model's module, the integrator, the table code).
"""

from __future__ import annotations

import hashlib
import inspect
import os
from functools import lru_cache
from pathlib import Path

import numpy as np

from .. import tables
from ..progress import start
from ..tables import AngleTable
from .albedo import albedo, albedo_table, is_isotropic
from .keys import exact_text

#: Tables built in this process: key -> AngleTable.
_TABLES: dict = {}


def table_cache_dir() -> Path | None:
    """Where albedo tables are cached on disk: ``$PLAUSIBLE_CACHE_DIR``, else
    ``$XDG_CACHE_HOME/plausible`` or ``~/.cache/plausible``; ``PLAUSIBLE_CACHE_DIR=""``
    turns the disk cache off."""
    env = os.environ.get("PLAUSIBLE_CACHE_DIR")
    if env is not None:
        return Path(env) if env else None
    root = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(root) / "plausible"


def spec_of(model) -> str:
    """The cache key of a model: its exact text (:func:`.keys.exact_text`), else
    its ``repr`` (a model without one; two such models may share a table only
    when their reprs agree)."""
    return exact_text(model) or repr(model)


@lru_cache(maxsize=None)
def _source_hash(cls) -> str:
    """Hash of the source that determines a table: the module of the model class
    ``cls``, the integrator and the table code (read once per class)."""
    h = hashlib.sha1()
    for obj in (cls, albedo_table, tables):
        try:
            h.update(inspect.getsource(inspect.getmodule(obj)).encode())
        except (OSError, TypeError):
            h.update(repr(obj).encode())
    return h.hexdigest()[:16]


def _cached(kind: str, model, compute, wrap=lambda v: v):
    """``wrap(values)`` of the array ``compute()`` for ``model``, cached in memory
    (:data:`_TABLES`) and on disk as ``{kind}-{digest}.npy`` (see :func:`table_cache_dir`)."""
    key = kind + "|" + spec_of(model) + "|" + _source_hash(type(model))
    if key in _TABLES:
        return _TABLES[key]
    digest = hashlib.sha1(key.encode()).hexdigest()
    cache = table_cache_dir()
    # a model that nothing outside this process names (a Python callable) stays in memory
    path = cache / f"{kind}-{digest}.npy" if cache and getattr(model, "disk_cache", True) else None
    out = None
    if path is not None and path.exists():
        try:
            out = wrap(np.load(path))
        except (OSError, ValueError):
            out = None
    if out is None:
        values = compute()
        out = wrap(values)
        if path is not None:
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                tmp = path.with_suffix(f".{os.getpid()}.tmp.npy")
                np.save(tmp, values)
                os.replace(tmp, path)
            except OSError:
                pass
    _TABLES[key] = out
    return out


def albedo_table_of(model, progress=None):
    """The (cached) albedo table of ``model``: memory first, then disk, else integrated
    (reported to ``progress``, a :mod:`plausible.progress` factory; with None, to the
    ambient reporter: the command line's bar)."""
    return _cached("albedo", model, lambda: albedo_table(model, progress=progress).values, AngleTable)


#: ``cos(theta)`` of the two probes of :func:`horizon_albedos`: the table's last
#: node lies 1e-6 rad above the horizon; 1e-9 is as close as the energy check goes.
HORIZON_COS = (1e-6, 1e-9)


def horizon_albedos(model, progress=None) -> np.ndarray:
    """The largest directional albedo of ``model`` over a few azimuths (one for an
    isotropic model, four otherwise) at ``cos(theta)`` = each of :data:`HORIZON_COS`
    (cached like the tables).  ``progress``: a :mod:`plausible.progress` factory,
    told the albedo evaluations when they are computed (none when cached); None:
    the ambient reporter."""
    def compute():
        phis = (0.0,) if is_isotropic(model) else tuple(k * np.pi / 4 for k in range(4))
        tick = start(progress, len(HORIZON_COS) * len(phis), "horizon albedo")
        out = []
        for c in HORIZON_COS:
            s = np.sqrt(1.0 - c * c)
            out.append(max(float(np.max(albedo(model, np.array([s * np.cos(p), s * np.sin(p), c])).value))
                           for p in phis))
            tick(len(phis))
        return np.array(out)

    return _cached("horizon", model, compute)


def albedo_grid_of(model, thetas, phis, tol: float = 1e-6) -> np.ndarray:
    """The largest channel's directional albedo of ``model`` at every polar angle ``thetas``
    and azimuth ``phis`` (radians), shape ``(len(thetas), len(phis))``, integrated to ``tol``
    and cached like the tables (the key holds the angles)."""
    thetas, phis = [float(t) for t in thetas], [float(p) for p in phis]

    def compute():
        from .albedo import albedos, direction

        res = albedos(model, [direction(t, p) for t in thetas for p in phis], tol=tol)
        return np.array([np.max(np.atleast_1d(r.value)) for r in res]).reshape(len(thetas), len(phis))

    kind = "grid-" + hashlib.sha1(repr((thetas, phis, tol)).encode()).hexdigest()[:12]
    return _cached(kind, model, compute)


__all__ = ["HORIZON_COS", "albedo_grid_of", "albedo_table_of", "horizon_albedos", "spec_of", "table_cache_dir"]
