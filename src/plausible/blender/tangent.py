"""Tangent-resolved virtual acquisition: an anisotropic Cycles material measured over
``(theta_i, phi_i, theta_o, phi_o)``, its albedo over the whole hemisphere, its
reciprocity from swapped light and camera.

The isotropic acquisition (:mod:`.acquire`) gives each pixel a normal but no tangent.
Here the sphere carries a **known tangent field**: Cycles' default tangent of an
anisotropic BSDF (an unlinked Tangent socket) is the *radial* tangent about the
object's ``z`` (Cycles ``svm_node_tangent``, ``NODE_TANGENT_RADIAL``, axis Z: the
generated coordinate ``(-y, x, 0)`` turned to world space and projected onto the
tangent plane), and the worker's UV map has ``u`` along the same azimuth, so a
Tangent node of the UV map gives the same field.  On a unit sphere at the origin
whose pole (object ``z``) is at ``p = Q z`` (``Q`` the sphere's rotation), the pixel of
normal ``n`` has

    ``t = (p x n) / |p x n|``,  ``b = n x t``  (a right-handed ``(t, b, n)``).

Geometry (module docstring of :mod:`.acquire` for the camera, sun and furnace):

* **turns**: the sphere's pole in the image plane, ``p = (-sin beta, cos beta, 0)``, at
  each ``beta`` of :data:`TURNS`; the sun in the ``xz`` plane at ``a`` from the camera.
  A render covers two dimensions (the pixels), the angles a third and the turns the
  fourth: at the image's centre the light's azimuth from the tangent is ``-beta``.
  The tangent is singular only at ``n = +-p``, on the silhouette (``theta_o = 90``),
  outside the kept pairs (``theta <= 75`` degrees);
* **reciprocity from swapped light and camera**: the partner of a render (light ``l``,
  sphere ``Q``) is the render of light ``l' = R z`` and sphere ``R Q``, with ``R`` the
  turn about ``y`` by ``-a`` (``R l = z``, ``R z = l'``).  The sphere turns with the
  world, so the tangent field does too (``t(R n) = R t(n)``), and the pixel at ``R n``
  of the partner sees ``f(wo, wi)`` of the pixel ``n`` *in the same tangent frame*
  (read bilinearly; unresolved where the reading is not, as in :mod:`.acquire`);
* **energy**: one white furnace (``beta = 0``); a pixel reads the directional albedo at
  its ``(theta_o, phi_o)`` in the tangent frame, and cells of :data:`RING_DEG` x
  :data:`PHI_DEG` average the pixels, with their standard error: the albedo over the
  whole hemisphere of outgoing directions, not a ring average.

:func:`check_model` compares the measured pairs with a plausible model at the same
``(wi, wo)`` (a closed form or a second method): with the wrong tangent field the
comparison fails (:func:`turned`, the acquisition read with its tangents turned: a
broken input for the tests).  :func:`phi_table` bins ``f`` over
``(theta_h, phi_h, theta_d)``: an isotropic material's table is flat in ``phi_h``.

References: Cycles ``intern/cycles/kernel/svm/tangent.h`` (the radial tangent),
``closure/bsdf_microfacet.h`` and ``svm/closure.h`` (Principled BSDF: ``alpha_x =
r^2 / sqrt(1 - 0.9 A)``, ``alpha_y = r^2 sqrt(1 - 0.9 A)``, the tangent turned about
``n`` by ``2 pi`` times Anisotropic Rotation); Matusik et al. 2003 (the sphere).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..analysis.checks import PropertyResult
from . import runner
from .acquire import (MAX_THETA_DEG, RESOLUTION, SPP, Acquisition, _pixel_normals, _swapped, pole_rotation,
                      swapped_renders)

__all__ = ["ANGLES", "TURNS", "TangentAcquisition", "acquire_tangent", "check_isotropy", "check_model", "phi_table",
           "pole_rotation", "turned"]

#: Angles (degrees) between light and camera of the sun renders (fewer than the isotropic
#: acquisition's: each is rendered at every turn).
ANGLES = (0, 20, 40, 60, 80, 100, 120, 140)
#: Turns ``beta`` (degrees) of the sphere's pole in the image plane.  The tangent field's
#: symmetry ``t -> -t`` under ``beta -> beta + 180`` makes half a turn enough.
TURNS = (0, 30, 60, 90, 120, 150)
#: Furnace cells: theta_o rings of this width (degrees) ...
RING_DEG = 5.0
#: ... times phi_o sectors of this width (degrees, over the full turn; the first ring is one cell).
PHI_DEG = 45.0
#: Fewest pixels of a furnace cell (fewer give no trustworthy standard error).
MIN_CELL = 6


def frames(n: np.ndarray, pole: np.ndarray, turn_deg: float = 0.0):
    """``(t, b)`` of the normals ``n`` (``(k, 3)``) on the sphere of pole ``pole``:
    ``t = p x n`` normalised, ``b = n x t``, both turned by ``turn_deg`` about ``n``
    (0 for Cycles' tangent; another value reads the acquisition in a wrong frame)."""
    t = np.cross(pole, n)
    t /= np.maximum(np.linalg.norm(t, axis=1), 1e-300)[:, None]
    b = np.cross(n, t)
    c, s = math.cos(math.radians(turn_deg)), math.sin(math.radians(turn_deg))
    return c * t + s * b, c * b - s * t


def _local(v, t, b, n):
    """World directions ``v`` (one, or one per row) in the frames ``(t, b, n)``."""
    return np.stack([np.sum(t * v, -1), np.sum(b * v, -1), np.sum(n * v, -1)], -1)


@dataclass
class TangentAcquisition(Acquisition):
    """An :class:`.acquire.Acquisition` whose directions are in the tangent frame (module
    docstring); the furnace in cells of ``(theta_o, phi_o)``: ``albedo_phi`` (radians, the
    cell's mean azimuth from the tangent) beside ``albedo_theta``."""

    tangent_frame = True
    albedo_phi: np.ndarray = field(default_factory=lambda: np.zeros(0))
    turns: tuple = ()
    #: raw renders and per-pair pixel records, to re-read the acquisition in another frame
    raw: dict = field(default_factory=dict, repr=False)

    def brdf(self):
        raise NotImplementedError("a tangent-resolved acquisition is anisotropic: a MERL table cannot hold it; "
                                  "use phi_table() or the pairs (wi, wo, f)")


def _sun_pairs(img, a_deg, pole, normals, mask, turn_deg=0.0):
    """The pairs of one render (light at ``a_deg``, sphere pole ``pole``) in the tangent frame."""
    a = math.radians(a_deg)
    l = np.array([math.sin(a), 0.0, math.cos(a)])
    n = normals[mask]
    cmin = math.cos(math.radians(MAX_THETA_DEG))
    keep = (n @ l > cmin) & (n[:, 2] > cmin)
    n = n[keep]
    t, b = frames(n, pole, turn_deg)
    return _local(l, t, b, n), _local(np.array([0.0, 0.0, 1.0]), t, b, n), img[mask][keep] / (n @ l)[:, None]


def _furnace_cells(img, normals, mask, pole, turn_deg=0.0):
    """Cell means of the furnace: ``theta (m,), phi (m,), albedo (m, 3), stderr (m, 3)`` (``phi``
    NaN for the first ring, one cell around the pole of the tangent frame)."""
    n = normals[mask]
    t, b = frames(n, pole, turn_deg)
    wo = _local(np.array([0.0, 0.0, 1.0]), t, b, n)
    th = np.degrees(np.arccos(np.clip(wo[:, 2], -1, 1)))
    ph = np.degrees(np.arctan2(wo[:, 1], wo[:, 0])) % 360.0
    vals, out = img[mask], []
    for lo in np.arange(0.0, MAX_THETA_DEG - 1e-9, RING_DEG):
        sectors = [(0.0, 360.0)] if lo == 0.0 else [(p, p + PHI_DEG) for p in np.arange(0.0, 360.0 - 1e-9, PHI_DEG)]
        for plo, phi in sectors:        # the first ring one cell: the azimuth is undefined at the pole
            cell = (th >= lo) & (th < lo + RING_DEG) & (ph >= plo) & (ph < phi)
            s = vals[cell]
            if len(s) >= MIN_CELL:
                mid = math.nan if lo == 0.0 else math.radians(ph[cell].mean())
                out.append((math.radians(th[cell].mean()), mid, s.mean(0), s.std(0, ddof=1) / math.sqrt(len(s))))
    return tuple(np.array([o[k] for o in out]) for k in range(4))


def _renders(angles, turns):
    """The job's renders: the furnace, then per turn and angle the render and its swapped partner."""
    out = [{"kind": "furnace", "camera": [0, 0, 1], "sphere": pole_rotation(0.0).tolist()}]
    for beta in turns:
        out += swapped_renders(angles, pole_rotation(beta))
    return out


def _assemble(name, imgs, angles, turns, resolution, spp, seconds, turn_deg=0.0) -> TangentAcquisition:
    """The acquisition of the renders ``imgs`` (:func:`_renders`' order), read with the tangents
    turned by ``turn_deg`` (0: Cycles' frame)."""
    normals, mask = _pixel_normals(int(resolution))
    pairs, swaps = [], []
    for i, beta in enumerate(turns):
        pole = pole_rotation(beta)[:, 2]
        for k, a in enumerate(angles):
            img_a, img_b = imgs[1 + 2 * (i * len(angles) + k)], imgs[2 + 2 * (i * len(angles) + k)]
            pairs.append(_sun_pairs(img_a, a, pole, normals, mask, turn_deg))
            if a > 0:
                swaps.append(_swapped(img_a, img_b, a, normals, mask))
    th, ph, alb, se = _furnace_cells(imgs[0], normals, mask, pole_rotation(0.0)[:, 2], turn_deg)
    cat = lambda k, xs: np.concatenate([x[k] for x in xs]) if xs else np.zeros((0, 3))   # noqa: E731
    return TangentAcquisition(name, cat(0, pairs), cat(1, pairs), cat(2, pairs), th, alb, se, cat(0, swaps),
                              cat(1, swaps), cat(2, swaps), int(resolution), int(spp), tuple(angles), seconds,
                              albedo_phi=ph, turns=tuple(turns),
                              raw=dict(imgs=imgs, turn_deg=turn_deg))


def acquire_tangent(spec: dict, *, name: str = "material", angles=ANGLES, turns=TURNS,
                    resolution: int = RESOLUTION, spp: int = SPP, seed: int = 0,
                    progress=None) -> TangentAcquisition:
    """Measure a Cycles material (``spec``: :func:`.acquire.material_spec`) with a known
    tangent field (module docstring): per turn of ``turns`` and angle of ``angles``, a sun
    render and its swapped partner, and one white furnace.  Parameters: ``resolution``
    (pixels per side, 16-2048), ``spp`` (1-65536), ``angles`` (degrees in [0, 175]),
    ``turns`` (degrees in [0, 180)), ``seed``.  ``2 len(angles) len(turns) + 1`` renders.

    >>> acq = acquire_tangent(material_spec(diffuse=0.5), angles=(0, 60), turns=(0, 90))  # doctest: +SKIP
    """
    if not 16 <= int(resolution) <= 2048:
        raise ValueError(f"resolution must be in [16, 2048] pixels, got {resolution!r}")
    if not 1 <= int(spp) <= 65536:
        raise ValueError(f"spp must be in [1, 65536], got {spp!r}")
    angles, turns = tuple(float(a) for a in angles), tuple(float(b) for b in turns)
    if not angles or not all(0.0 <= a <= 175.0 for a in angles):
        raise ValueError(f"angles must be degrees in [0, 175], got {angles!r}")
    if not turns or not all(0.0 <= b < 180.0 for b in turns):
        raise ValueError(f"turns must be degrees in [0, 180), got {turns!r}")
    from ..progress import start

    renders = _renders(angles, turns)
    tick = start(progress, 1, f"acquire {name} in Cycles, tangent-resolved ({len(renders)} renders)")
    t0 = time.perf_counter()
    imgs = runner.run_job(spec, renders, resolution=resolution, spp=spp, seed=seed)
    tick()
    return _assemble(name, imgs, angles, turns, resolution, spp, time.perf_counter() - t0)


def turned(acq: TangentAcquisition, turn_deg: float) -> TangentAcquisition:
    """The same renders read with every tangent turned by ``turn_deg`` about its normal: a
    wrong tangent convention (a broken input that :func:`check_model` must fail)."""
    return _assemble(acq.name, acq.raw["imgs"], acq.angles, acq.turns, acq.resolution, acq.spp, acq.seconds,
                     turn_deg=float(turn_deg))


def check_model(acq: Acquisition, model, *, tol: float = 0.02, floor: float = 1e-3) -> PropertyResult:
    """The measured ``f(wi, wo)`` against ``model.eval(wi, wo)`` at the same pairs (a closed form
    or a second method): passes when the median of ``|f - f_model| / f_model`` is at most ``tol``,
    over the pairs where the model is at least ``floor`` of its largest value (all channels
    together).  The figure is that median; details the 90th percentile and the pairs."""
    if not 0.0 < float(tol) < 1.0:
        raise ValueError(f"tol must be in (0, 1), got {tol!r}")
    ref = np.asarray(model.eval(acq.wi, acq.wo), dtype=float).reshape(len(acq.f), -1)
    ref = np.broadcast_to(ref, acq.f.shape)
    big = ref > floor * max(float(ref.max(initial=0.0)), 1e-300)
    rel = np.abs(acq.f - ref)[big] / ref[big]
    if rel.size == 0:
        return PropertyResult("model", False, math.nan, "no pairs where the model is above its floor", {}, {},
                              unresolved=True)
    med, p90 = float(np.median(rel)), float(np.percentile(rel, 90))
    return PropertyResult("model", med <= tol, med,
                          f"<= {tol:g} (median |f - model| / model over {rel.size} values; 90th pct {p90:.3g})",
                          {}, dict(median=med, p90=p90, values=int(rel.size)))


def phi_table(acq: Acquisition, *, theta_h_deg=(0, 15, 30, 45, 60), phi_bins: int = 8,
              theta_d_deg=(0, 20, 40, 60)):
    """``f`` binned over ``(theta_h, phi_h, theta_d)`` (the half vector's azimuth from the tangent,
    over the full turn, in ``phi_bins`` sectors): ``(mean (h, p, d, 3), stderr, count)``, NaN in
    empty cells.  An isotropic material's table is flat along ``phi_h`` within its stderr."""
    h = acq.wi + acq.wo
    h /= np.linalg.norm(h, axis=1)[:, None]
    th = np.degrees(np.arccos(np.clip(h[:, 2], -1, 1)))
    ph = np.degrees(np.arctan2(h[:, 1], h[:, 0])) % 360.0
    td = np.degrees(np.arccos(np.clip(np.sum(acq.wi * h, 1), -1, 1)))
    ih = np.digitize(th, theta_h_deg) - 1
    ip = np.minimum((ph / (360.0 / phi_bins)).astype(int), phi_bins - 1)
    idd = np.digitize(td, theta_d_deg) - 1
    shape = (len(theta_h_deg), phi_bins, len(theta_d_deg))
    mean, se, count = np.full(shape + (3,), np.nan), np.full(shape + (3,), np.nan), np.zeros(shape, int)
    for cell in zip(*np.unique(np.stack([ih, ip, idd]), axis=1)):
        sel = (ih == cell[0]) & (ip == cell[1]) & (idd == cell[2])
        count[cell] = sel.sum()
        mean[cell] = acq.f[sel].mean(0)
        if count[cell] > 1:
            se[cell] = acq.f[sel].std(0, ddof=1) / math.sqrt(count[cell])
    return mean, se, count


def check_isotropy(acq: Acquisition, *, tol: float = 0.01, min_count: int = 5) -> PropertyResult:
    """Whether the tangent-resolved table (:func:`phi_table`) is flat along ``phi_h``: in each
    ``(theta_h, theta_d)`` row of cells holding at least ``min_count`` pairs, every cell's mean
    within ``tol`` (relative to the row's median) plus 3 standard errors of that median.  An
    isotropic material (Cycles' Diffuse BSDF: ``f = rd / pi``) passes; an anisotropic one fails.
    The figure is the largest relative excess over the 3 standard errors."""
    if not 0.0 < float(tol) < 1.0:
        raise ValueError(f"tol must be in (0, 1), got {tol!r}")
    mean, se, count = phi_table(acq)
    worst, where = 0.0, {}
    for ih in range(mean.shape[0]):
        for idd in range(mean.shape[2]):
            ok = count[ih, :, idd] >= min_count
            if ok.sum() < 2:
                continue
            row, err = mean[ih, ok, idd], se[ih, ok, idd]
            mid = np.median(row, axis=0)
            excess = (np.abs(row - mid) - 3.0 * np.nan_to_num(err)) / np.maximum(mid, 1e-300)
            k, c = np.unravel_index(int(np.argmax(excess)), excess.shape)
            if excess[k, c] > worst:
                worst = float(excess[k, c])
                where = dict(theta_h_cell=ih, theta_d_cell=idd, phi_h_cell=int(np.flatnonzero(ok)[k]),
                             channel="rgb"[c], cell=float(row[k, c]), row_median=float(mid[c]))
    return PropertyResult("isotropy", worst <= tol, worst,
                          f"<= {tol:g} (every phi_h cell of a (theta_h, theta_d) row within this, relative, "
                          f"of the row's median beyond 3 standard errors)", where, dict(cells=int((count > 0).sum())))
