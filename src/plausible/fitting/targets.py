"""What a fit is measured against: :class:`Target` (``f cos`` on pairs of
directions, optionally the albedo), built by :func:`as_target` from a model or
spec, a MERL file or a table; the CSV tables of :func:`load_table` and
:func:`save_table` (errors name ``file:line``)."""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .. import registry
from ..analysis import albedo_curve
from ..bxdf import BxDF
from . import metrics as M

@dataclass
class Target:
    """What a fit is measured against: ``fcos`` (f cos(theta_o), shape (N,) or (N, C))
    on pairs ``wi``, ``wo``; optionally the albedo ``albedo`` at ``thetas`` (radians)."""

    wi: np.ndarray
    wo: np.ndarray
    fcos: np.ndarray
    thetas: np.ndarray | None = None
    albedo: np.ndarray | None = None
    model: BxDF | None = None
    label: str = "target"
    peaks: list = field(default_factory=list)

    #: what :meth:`derived` computed, with the fingerprint of the arrays it was computed from
    _memo: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @property
    def channels(self):
        return self.fcos.shape[-1] if self.fcos.ndim == 2 else None

    def derived(self, name: str, fn):
        """``fn(self)``, remembered under ``name`` while the target is unchanged (the same model
        object and the same bytes of ``wi``, ``wo``, ``fcos``: a fingerprint taken at each call,
        about 0.1 ms, so an array changed in place is seen).  What a fit derives from its target
        alone (the highlight rows, whether it is isotropic) is computed once for many fits."""
        mark = (id(self.model),) + tuple(hash(np.ascontiguousarray(a).tobytes()) + hash(np.shape(a))
                                         for a in (self.wi, self.wo, self.fcos))
        hit = self._memo.get(name)
        if hit is None or hit[0] != mark:
            hit = self._memo[name] = (mark, fn(self))
        return hit[1]


def load_table(path):
    """Read a CSV table of samples: columns ``wi_x, wi_y, wi_z, wo_x, wo_y, wo_z,
    f`` (or ``f_r, f_g, f_b``), ``f`` the BRDF without the cosine; one header
    line and ``#`` comments are skipped.  Returns ``(wi, wo, f)``.

    Every value must be a finite number, ``f >= 0`` and no direction a zero
    vector; a row that breaks this, a row with a different number of columns
    than the first, or a file that is not UTF-8 text raises ValueError naming
    the file and line.
    """
    from ..models.merl import not_data

    stand_in = not_data(path)
    if stand_in:
        raise ValueError(stand_in)
    rows, width, header = [], None, False
    try:
        with open(path, encoding="utf-8-sig") as fh:     # (a byte-order mark is not part of the first row)
            for ln, line in enumerate(fh, 1):
                s = line.split("#", 1)[0].strip()
                if not s:
                    continue
                where = f"{path}:{ln}"
                try:
                    row = [float(x) for x in s.replace(";", ",").split(",")]
                except ValueError:
                    if rows or header:
                        raise ValueError(f"{where}: not a row of numbers: {_clip(line.strip())!r}") from None
                    header = True
                    continue
                if width is None:
                    if len(row) not in (7, 9):
                        raise ValueError(f"{where}: expected 7 or 9 columns (wi xyz, wo xyz, f or f_r f_g f_b), "
                                         f"got {len(row)}")
                    width = len(row)
                elif len(row) != width:
                    raise ValueError(f"{where}: {len(row)} columns where the rows above have {width}")
                _check_row(where, row)
                rows.append(row)
    except UnicodeDecodeError as e:
        raise ValueError(f"{path}: not a CSV text table (byte {e.start} is not UTF-8){_binary_note(path)}") from None
    if not rows:
        raise ValueError(f"{path}: no samples")
    a = np.array(rows)
    return a[:, :3], a[:, 3:6], (a[:, 6] if a.shape[1] == 7 else a[:, 6:])


_COLUMNS = ("wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z")
#: Largest BRDF value a table may hold: its square (the least-squares metrics) stays finite.
F_MAX = 1e150


def _check_row(where, row):
    """A table row: finite numbers, non-zero directions, ``f >= 0``."""
    names = _COLUMNS + (("f",) if len(row) == 7 else ("f_r", "f_g", "f_b"))
    for name, v in zip(names, row):
        if not math.isfinite(v):
            raise ValueError(f"{where}: column {name} must be a finite number, got {v}")
    for w, name in ((row[:3], "wi"), (row[3:6], "wo")):
        if not any(w):
            raise ValueError(f"{where}: {name} is the zero vector (a direction needs a non-zero x, y or z)")
    for name, v in zip(names[6:], row[6:]):
        if v < 0:
            raise ValueError(f"{where}: column {name} (the BRDF value) must be >= 0, got {v:g}")
        if v > F_MAX:
            raise ValueError(f"{where}: column {name} (the BRDF value) must lie in [0, {F_MAX:g}] "
                             f"(the metrics square it), got {v:g}")


def _binary_note(path) -> str:
    """For a binary file that is not a table: what its first 12 bytes say as a
    MERL header (``; a MERL file starts with ...``)."""
    from ..models.merl import RES, _header_note

    with open(path, "rb") as fh:
        dims = np.frombuffer(fh.read(12).ljust(12, b"\0"), dtype="<i4")
    if all(0 < int(d) <= 4096 for d in dims):
        return f"; it starts like a MERL file of another resolution: {_header_note(dims)}"
    return f"; a MERL file starts with the header {' '.join(map(str, RES))} (little-endian int32)"


def _clip(text, n=60):
    return text if len(text) <= n else text[:n] + "..."


def save_table(path, wi, wo, f):
    """Write samples in the CSV layout of :func:`load_table`."""
    f = np.asarray(f, float)
    cols = ["f"] if f.ndim == 1 else [f"f_{c}" for c in "rgb"[: f.shape[1]]]
    a = np.column_stack([wi, wo, f])
    np.savetxt(path, a, delimiter=",", header=",".join(["wi_x", "wi_y", "wi_z", "wo_x", "wo_y", "wo_z"] + cols),
               comments="", fmt="%.17g")
    return Path(path)


def as_target(target, *, thetas_deg=M.THETAS_DEG, target_albedo=None) -> Target:
    """Build a :class:`Target` from a model (any object with the contract), a
    model spec ``"name:k=v"``, a path (MERL binary or CSV table), or a table
    ``(wi, wo, f)`` / array of shape (N, 7) or (N, 9).

    A model target is sampled on :func:`plausible.fitting.metrics.sample_pairs`
    and its albedo computed accurately at ``thetas_deg``.  A table has no albedo
    unless ``target_albedo = (thetas_deg, values)`` is given.
    """
    if isinstance(target, Target):
        return target
    if isinstance(target, str) and registry.is_spec(target):   # e.g. a published fit, material:NAME@FIT
        return as_target(registry.make_from_spec(target.strip()), thetas_deg=thetas_deg)
    if isinstance(target, (str, Path)):
        p = Path(target)
        if p.is_dir():     # a folder is never a target; a name that is also a model spec is the model
            try:
                return as_target(registry.make_from_spec(str(target)), thetas_deg=thetas_deg)
            except ValueError:
                raise ValueError(f"target {str(target)!r} is a folder; a target is a model spec (name:k=v), "
                                 f"material:NAME@FIT, a MERL .binary file or a CSV table") from None
        if not p.exists() and (p.suffix.lower() in (".csv", ".binary", ".txt") or "/" in str(target)):
            raise ValueError(f"target file {str(target)!r} not found")
        if p.exists():
            from ..models.merl import is_merl_file, read_merl

            if is_merl_file(p):
                return as_target(read_merl(p), thetas_deg=thetas_deg)
            wi, wo, f = load_table(p)
            return _table_target(wi, wo, f, str(p), target_albedo)
        return as_target(registry.make_from_spec(str(target)), thetas_deg=thetas_deg)
    if hasattr(target, "eval") and hasattr(target, "peak_directions"):
        wi, wo = M.sample_pairs(target.peak_directions, thetas_deg=thetas_deg)
        if hasattr(target, "measured_pairs"):   # a table (MERL): compare where it was measured
            wi, wo = target.measured_pairs(wi, wo)
        f = target.eval(wi, wo)
        mask = None
        if hasattr(target, "missing"):
            mask = ~target.missing(wi, wo)
            if not mask.any():
                raise ValueError(f"{target!r}: no measured value at any of the {mask.size} sample pairs "
                                 "(every cell they fall in is marked missing)")
            wi, wo, f = wi[mask], wo[mask], f[mask]
        th = np.radians(np.asarray(thetas_deg, float))
        A = albedo_curve(target, th).value
        return Target(wi, wo, fcos(f, wo), th, np.asarray(A), target, repr(target),
                      [target.peak_directions])
    if isinstance(target, tuple) and len(target) == 3:
        return _table_target(*target, "table", target_albedo)
    a = np.asarray(target, float)
    if a.ndim == 2 and a.shape[1] in (7, 9):
        return _table_target(a[:, :3], a[:, 3:6], a[:, 6] if a.shape[1] == 7 else a[:, 6:], "table",
                             target_albedo)
    raise ValueError("target must be a model, a model spec, a MERL or CSV file, or a table (wi, wo, f)")


def _table_target(wi, wo, f, label, target_albedo):
    from ..directions import as_directions

    try:
        wi, wo = as_directions("wi", wi), as_directions("wo", wo)
    except ValueError as e:
        raise ValueError(f"{label}: {e}") from None
    f = np.asarray(f, float)
    if f.shape[0] != wi.shape[0] or wo.shape[0] != wi.shape[0]:
        raise ValueError(f"{label}: table columns wi, wo, f must have the same number of rows")
    if not np.all(np.isfinite(f)) or np.any(f < 0):
        bad = np.flatnonzero(~(np.isfinite(f) & (f >= 0)).reshape(len(f), -1).all(axis=1))
        raise ValueError(f"{label}: the BRDF values f must be finite and >= 0; {bad.size} rows are not "
                         f"(first: row {bad[0]}, f = {f[bad[0]]})")
    ok = (wi[:, 2] > 0) & (wo[:, 2] > 0)
    if not ok.any():
        raise ValueError(f"{label}: no sample has both wi and wo above the horizon (z > 0); "
                         f"the {len(f)} rows all lie on or below it")
    lost = ~ok & (f.reshape(len(f), -1) > 0).any(axis=1)
    if lost.any():      # dropped (a reflection BRDF is 0 there), but a value there was measured: said, not silent
        k = int(np.argmax(lost))
        warnings.warn(f"{label}: {int(lost.sum())} of {len(f)} rows have a direction on or below the horizon "
                      f"(z <= 0) and f > 0 (first: row {k}, wi = {np.round(wi[k], 6).tolist()}, wo = "
                      f"{np.round(wo[k], 6).tolist()}): dropped, as a reflection BRDF is 0 there", stacklevel=3)
    th = A = None
    if target_albedo is not None:
        th = np.radians(np.asarray(target_albedo[0], float))
        A = np.asarray(target_albedo[1], float)
    return Target(wi[ok], wo[ok], fcos(f[ok], wo[ok]), th, A, None, label, [])


def fcos(f, wo):
    c = wo[:, 2]
    return f * (c[:, None] if f.ndim == 2 else c)


__all__ = ["Target", "as_target", "fcos", "load_table", "save_table"]
