"""Measured isotropic BRDFs in the MERL binary format (Matusik et al. 2003).

Layout (the reference reader ``BRDFRead.cpp`` of the MERL database):

* a header of three ``int32``: ``(90, 90, 180)`` -- the resolutions in
  ``theta_h``, ``theta_d`` and ``phi_d``;
* then ``3 * 90 * 90 * 180`` little-endian ``float64``: the red, green and blue
  planes one after the other.  A stored value ``s`` means ``f = s * scale`` with
  ``scale = 1/1500, 1.15/1500, 1.66/1500`` for red, green, blue; a negative
  value marks a cell without a measurement.

A pair ``(wi, wo)`` is looked up through Rusinkiewicz's half/difference angles
(``h = (wi + wo)/|wi + wo|``, ``d`` = ``wi`` rotated by ``-phi_h`` about the
normal and by ``-theta_h`` about the bitangent):

* ``i_h = floor(sqrt(theta_h / (pi/2)) * 90)`` (non-linear: dense near the
  specular peak),
* ``i_d = floor(theta_d / (pi/2) * 90)``,
* ``i_p = floor(phi_d / pi * 180)`` with ``phi_d`` folded into ``[0, pi)`` by
  ``phi_d -> phi_d + pi`` (reciprocity: swapping ``wi`` and ``wo`` adds ``pi``),

each clamped to its range; the flat index is ``i_p + 180 (i_d + 90 i_h)``.
The lookup is **nearest cell** (the reference reader's truncation, no
interpolation).  :func:`tabulate` samples a model at the cell *centres*
(``theta_h = ((i_h + 1/2)/90)^2 pi/2``, ``theta_d = (i_d + 1/2)/90 pi/2``,
``phi_d = (i_p + 1/2)/180 pi``) so that a written table reads back exactly
there.

:class:`MerlBRDF` satisfies the model contract (``eval``, ``pdf``, ``sample``;
sampling is cosine-weighted), so a measured BRDF can be checked, plotted,
fitted and used like any other model.  Its lookup is written against ``ops``
(``ops.table`` / ``ops.gather``), so the Mitsuba plugin ``merl``
(:mod:`plausible.mitsuba`) renders the same table.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from .. import vec, warps
from ..bxdf import BxDF
from ..vec import above

RES = (90, 90, 180)                       # theta_h, theta_d, phi_d
NCELLS = RES[0] * RES[1] * RES[2]
SCALE = np.array([1.0 / 1500.0, 1.15 / 1500.0, 1.66 / 1500.0])
HALF_PI = 0.5 * math.pi


def half_diff(ops, wi, wo):
    """Rusinkiewicz coordinates ``(theta_h, theta_d, phi_d)`` of a pair of unit
    directions given component-wise; ``phi_d`` in ``(-pi, pi]`` (not folded)."""
    h = vec.half_vector(ops, wi, wo)
    theta_h = ops.acos(ops.clip(h[2], -1.0, 1.0))
    rxy2 = h[0] * h[0] + h[1] * h[1]
    pole = rxy2 <= 1e-30
    rxy = ops.sqrt(ops.where(pole, 1.0, rxy2))
    cp = ops.where(pole, 1.0, h[0] / rxy)            # cos(phi_h)
    sp = ops.where(pole, 0.0, h[1] / rxy)            # sin(phi_h)
    ct, st = h[2], ops.sqrt(ops.where(pole, 0.0, rxy2))
    # rotate wi by -phi_h about z, then by -theta_h about y
    x1 = wi[0] * cp + wi[1] * sp
    y1 = -wi[0] * sp + wi[1] * cp
    x2 = x1 * ct - wi[2] * st
    z2 = wi[2] * ct + x1 * st
    theta_d = ops.acos(ops.clip(z2, -1.0, 1.0))
    phi_d = ops.atan2(y1, x2)
    return theta_h, theta_d, phi_d


def cell_index(ops, theta_h, theta_d, phi_d):
    """Flat MERL cell index (as a float holding a whole number) of the angles."""
    ih = ops.floor(ops.sqrt(ops.maximum(theta_h, 0.0) / HALF_PI) * RES[0])
    id_ = ops.floor(theta_d / HALF_PI * RES[1])
    pd = ops.where(phi_d < 0.0, phi_d + math.pi, phi_d)
    ip = ops.floor(pd / math.pi * RES[2])
    ih = ops.clip(ih, 0.0, RES[0] - 1.0)
    id_ = ops.clip(id_, 0.0, RES[1] - 1.0)
    ip = ops.clip(ip, 0.0, RES[2] - 1.0)
    return ip + RES[2] * (id_ + RES[1] * ih)


def cell_centres():
    """Direction pairs ``(wi, wo)``, each of shape ``(90, 90, 180, 3)``, at the
    centres of the cells (``phi_h = 0``)."""
    th = ((np.arange(RES[0]) + 0.5) / RES[0]) ** 2 * HALF_PI
    td = (np.arange(RES[1]) + 0.5) / RES[1] * HALF_PI
    pd = (np.arange(RES[2]) + 0.5) / RES[2] * math.pi
    return from_half_diff(*np.meshgrid(th, td, pd, indexing="ij"))


def from_half_diff(theta_h, theta_d, phi_d, phi_h=0.0):
    """Direction pairs ``(wi, wo)`` (arrays ``(..., 3)``) with Rusinkiewicz
    coordinates ``theta_h, theta_d, phi_d`` and half-vector azimuth ``phi_h``
    (radians): the inverse of :func:`half_diff` (``wi`` is the difference vector
    rotated by ``theta_h`` about ``y``, then by ``phi_h`` about the normal;
    ``wo`` its mirror image about the half vector).  An isotropic table (MERL)
    does not depend on ``phi_h``; an anisotropic model does."""
    TH, TD, PD, PH = np.broadcast_arrays(*(np.asarray(a, dtype=np.float64)
                                           for a in (theta_h, theta_d, phi_d, phi_h)))
    dx, dy, dz = np.sin(TD) * np.cos(PD), np.sin(TD) * np.sin(PD), np.cos(TD)
    ch, sh = np.cos(TH), np.sin(TH)
    wi = np.stack([dx * ch + dz * sh, dy, dz * ch - dx * sh], axis=-1)
    h = np.stack([sh, np.zeros_like(sh), ch], axis=-1)
    wo = 2.0 * np.sum(wi * h, axis=-1, keepdims=True) * h - wi
    cp, sp = np.cos(PH), np.sin(PH)

    def rot(w):          # by phi_h about the normal
        return np.stack([w[..., 0] * cp - w[..., 1] * sp, w[..., 0] * sp + w[..., 1] * cp, w[..., 2]], axis=-1)

    return rot(wi), rot(wo)


#: The golden angle (radians): the half-vector azimuth of the ``k``-th measured
#: pair is ``k`` times it (mod 2 pi), so the azimuths of any run of cells spread
#: evenly over the circle (a Fibonacci-lattice spiral).
GOLDEN_ANGLE = math.pi * (3.0 - math.sqrt(5.0))


class MerlBRDF(BxDF):
    """A measured isotropic BRDF in the MERL layout, looked up nearest-cell.

    ``values`` has shape ``(3, 90, 90, 180)`` and holds ``f`` (already scaled,
    red/green/blue); negative entries mark missing cells, which evaluate to 0
    (see :meth:`missing`).
    """

    PARAMS = ()
    LOBES = frozenset({"diffuse", "glossy"})

    def __init__(self, values, source: str = "table"):
        super().__init__()
        v = np.asarray(values, dtype=np.float64)
        if v.shape != (3,) + RES:
            raise ValueError(f"MERL values must have shape (3, 90, 90, 180), got {v.shape}")
        if not np.all(np.isfinite(v)):
            raise ValueError(f"MERL values must be finite (negative marks a missing cell); "
                             f"{int(np.sum(~np.isfinite(v)))} are NaN or inf")
        self.values = v
        self.source = str(source)
        self.channels = 3
        self._table = np.where(v < 0, 0.0, v).reshape(-1)
        self._missing = (v < 0).reshape(3, -1).any(axis=0)

    def __repr__(self):
        return f"MerlBRDF({self.source!r})"

    def _index(self, ops, wi, wo):
        return cell_index(ops, *half_diff(ops, wi, wo))

    def _backend_table(self, ops):
        """The flat table as the backend's array (made once per backend)."""
        cache = self.__dict__.setdefault("_tables", {})
        key = (ops.name, id(ops))
        if key not in cache:
            cache[key] = ops.table(self._table)
        return cache[key]

    def _f(self, ops, wi, wo, p):
        """The three channels read at the pair's cell.  NumPy: the colour axis of
        the front end is a trailing length-1 axis, so one gather reads all three;
        Dr.Jit: a tuple of three channel arrays (the plugin makes it a colour)."""
        idx = self._index(ops, wi, wo)
        tab = self._backend_table(ops)
        ok = above(ops, wi, wo)
        if ops.name == "numpy":
            return ops.where(ok, ops.gather(tab, idx + NCELLS * np.arange(3)), 0.0)
        return tuple(ops.where(ok, ops.gather(tab, idx + NCELLS * c), 0.0) for c in range(3))

    def _pdf(self, ops, wi, wo, q):
        return ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)

    def _sample(self, ops, wi, u, q):
        return warps.cosine_hemisphere(ops, u[1], u[2])

    def measured_pairs(self, wi, wo):
        """The direction pairs at the centres of the cells that the pairs ``wi``,
        ``wo`` fall in, each cell once (in order of first occurrence): where the
        table was measured.  A fit compares a model with the table there, not at
        arbitrary pairs, a sixth of which (those of
        :func:`plausible.fitting.metrics.sample_pairs`, at whole degrees) lie on
        cell edges, where the nearest-cell value is decided by the last bit.

        The table is isotropic, so a cell's value holds at every half-vector
        azimuth ``phi_h``; the ``k``-th cell is placed at ``phi_h = k`` times
        the golden angle (:data:`GOLDEN_ANGLE`), so the pairs' half vectors
        point along both tangents and in between.  (At ``phi_h = 0`` for all,
        every half vector has ``h_y = 0`` and an anisotropic model's
        ``alpha_y`` is traded freely against its scale.)"""
        from ..directions import as_directions, split
        from ..arrays.ops import NP

        a, b = split(as_directions("wi", wi)), split(as_directions("wo", wo))
        with np.errstate(all="ignore"):
            idx = self._index(NP, a, b).astype(np.int64)
        cells = idx[np.sort(np.unique(idx, return_index=True)[1])]
        ih, rest = np.divmod(cells, RES[1] * RES[2])
        id_, ip = np.divmod(rest, RES[2])
        phi_h = np.mod(np.arange(cells.size) * GOLDEN_ANGLE, 2.0 * math.pi)
        return from_half_diff(((ih + 0.5) / RES[0]) ** 2 * HALF_PI, (id_ + 0.5) / RES[1] * HALF_PI,
                              (ip + 0.5) / RES[2] * math.pi, phi_h)

    def missing(self, wi, wo) -> np.ndarray:
        """Boolean mask: the pair falls in a cell without a measurement."""
        from ..directions import as_directions, split
        from ..arrays.ops import NP

        a, b = split(as_directions("wi", wi)), split(as_directions("wo", wo))
        with np.errstate(all="ignore"):
            idx = self._index(NP, a, b).astype(np.int64)
        return self._missing[idx]


def tabulate(model) -> np.ndarray:
    """Sample ``model.eval`` at the MERL cell centres: array ``(3, 90, 90, 180)``
    of ``f`` (a scalar model fills the three planes alike).  Pairs with a
    direction below the horizon hold the model's value there (0)."""
    wi, wo = cell_centres()
    out = np.empty((3,) + RES)
    for i in range(RES[0]):                       # one theta_h slab at a time (memory)
        f = model.eval(wi[i], wo[i])
        if f.ndim == 2:                           # scalar model
            out[:, i] = f[None]
        elif f.shape[-1] == 3:
            out[:, i] = np.moveaxis(f, -1, 0)
        else:
            raise ValueError(f"MERL tables hold 3 channels; model {model!r} has {f.shape[-1]}")
    return out


def write_merl(path, model_or_values) -> Path:
    """Write a model (tabulated by :func:`tabulate`) or a ``(3, 90, 90, 180)``
    array of ``f`` (negative = missing) as a MERL binary file."""
    v = model_or_values
    if not isinstance(v, np.ndarray):
        v = v.values if isinstance(v, MerlBRDF) else tabulate(v)
    v = np.asarray(v, dtype=np.float64)
    if v.shape != (3,) + RES:
        raise ValueError(f"MERL values must have shape (3, 90, 90, 180), got {v.shape}")
    stored = np.where(v < 0, -1.0, v / SCALE[:, None, None, None])
    path = Path(path)
    with open(path, "wb") as fh:
        np.asarray(RES, dtype="<i4").tofile(fh)
        stored.astype("<f8").tofile(fh)
    return path


#: The first line of a Git LFS pointer file (https://github.com/git-lfs/git-lfs/blob/main/docs/spec.md).
LFS_SPEC = b"version https://git-lfs.github.com/spec/"


def not_data(path) -> str | None:
    """What ``path`` is when it is a stand-in for a data file rather than the
    data, as a sentence for an error message, else None: a Git LFS pointer (a
    text file of ~130 bytes whose first line is ``version
    https://git-lfs.github.com/spec/v1``, then ``oid sha256:...`` and ``size N``)
    or a git-annex pointer (a path through ``.git/annex/objects``)."""
    try:
        with open(path, "rb") as fh:
            head = fh.read(1024)
    except OSError:
        return None
    if head.startswith(LFS_SPEC):
        fields = dict(line.split(" ", 1) for line in head.decode("ascii", "replace").splitlines() if " " in line)
        size = fields.get("size", "?").strip()
        return (f"{path}: a Git LFS pointer (the stand-in git keeps for a large file of {size} bytes, "
                f"{fields.get('oid', 'oid ?').strip()}), not the data: fetch the file with `git lfs pull`")
    if b"/annex/objects/" in head and len(head) < 512:
        return f"{path}: a git-annex pointer, not the data: fetch the file with `git annex get`"
    return None


def _header_note(dims) -> str:
    """How a 12-byte header that is not MERL's reads, for an error message."""
    return (f"header dimensions {tuple(int(d) for d in dims)}, expected {RES} (theta_h, theta_d, phi_d "
            f"as little-endian int32)")


def read_merl(path) -> MerlBRDF:
    """Read a MERL binary file into a :class:`MerlBRDF` (ValueError on a bad
    file, a Git LFS or git-annex pointer named as such: :func:`not_data`)."""
    path = Path(path)
    stand_in = not_data(path)
    if stand_in:
        raise ValueError(stand_in)
    with open(path, "rb") as fh:
        dims = np.fromfile(fh, dtype="<i4", count=3)
        if dims.size != 3 or tuple(int(d) for d in dims) != RES:
            raise ValueError(f"{path}: not a MERL BRDF file ({_header_note(dims)})")
        data = np.fromfile(fh, dtype="<f8")
    if data.size != 3 * NCELLS:
        raise ValueError(f"{path}: MERL file holds {data.size} values, expected {3 * NCELLS}")
    data = data.reshape((3,) + RES)
    bad = ~np.isfinite(data)
    if bad.any():
        c, ih, id_, ip = (int(i[0]) for i in np.nonzero(bad))
        raise ValueError(f"{path}: {int(bad.sum())} cells hold NaN or inf (first: {'RGB'[c]} channel, "
                         f"theta_h index {ih}, theta_d index {id_}, phi_d index {ip}); a cell without a "
                         "measurement must hold a negative value")
    if np.all(data < 0):
        raise ValueError(f"{path}: every cell is marked missing (negative): no measurement to use")
    values = np.where(data < 0, -1.0, data * SCALE[:, None, None, None])
    return MerlBRDF(values, source=str(path))


def is_merl_file(path) -> bool:
    """Does ``path`` start with the MERL header ``(90, 90, 180)``?"""
    try:
        with open(path, "rb") as fh:
            dims = np.fromfile(fh, dtype="<i4", count=3)
        return dims.size == 3 and tuple(int(d) for d in dims) == RES
    except OSError:
        return False
