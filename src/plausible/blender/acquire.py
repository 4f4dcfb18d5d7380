"""Virtual acquisition of a Cycles material: a measured BRDF, as MERL measured real ones.

Geometry (Matusik et al. 2003, "A data-driven reflectance model", done in Cycles):

* a unit sphere at the origin (a smooth UV sphere, 512 x 256 faces, whose sagitta,
  2e-5 of the radius, is far below a pixel), seen by an **orthographic camera** on
  ``+z``: the pixel at image position ``(x, y)`` (in sphere radii) sees the point,
  and the normal, ``n = (x, y, sqrt(1 - x^2 - y^2))``; every sample of a pixel
  lands at its centre (a box filter 0.01 pixel wide), so a pixel is one normal;
* a **sun lamp** of irradiance ``E = 1`` W/m^2 (perpendicular to its rays) from
  ``l = (sin a, 0, cos a)``: the pixel's radiance is ``L = f(wi, wo) E cos(theta_i)``
  with ``wi = l``, ``wo = z`` (light side first, as the issue writes
  ``f(wi, wo) = L / (E cos theta_i)``) in the pixel's frame, a pair of directions
  per pixel. A render at angle ``a`` between light and camera holds the pairs of
  difference angle ``theta_d = a / 2``; renders at :data:`ANGLES` cover the
  isotropic ``(theta_h, theta_d, phi_d)`` domain, one ``theta_d`` slice each;
* **reciprocity** from swapped light and camera: the render at ``-a`` is the
  render at ``a`` with light and camera exchanged and the world turned by ``a``
  about ``y`` (``R``): the pixel at ``R n`` of it sees ``f(wo, wi)`` of the pixel
  at ``n`` (read bilinearly between pixel centres).  The sphere turns with the
  world (its pole on ``y`` in the render at ``a``, turned by ``R`` in its partner),
  so its tangent field does too, and an anisotropic material's swapped pair is at
  the same tangent frame (:mod:`.tangent`);
* **energy** from a **white furnace**: no lamp, a uniform world of radiance 1;
  a pixel's radiance is the directional albedo ``a(wo) = int f(w, wo) cos dw``
  at ``theta_o = acos(n_z)`` (a convex sphere sees only the world), averaged over
  rings of :data:`RING_DEG` with its standard error (the Monte Carlo noise of the
  renderer's sampler: Cycles' Diffuse BSDF samples its cosine exactly and has
  none).

The measured pairs fill a MERL table (:class:`plausible.models.merl.MerlBRDF`, the
model contract): each cell takes the nearest measured pair in
``(sqrt(theta_h), theta_d, phi_d)`` cell units, so ``plausible`` evaluates,
plots, fits and converts the acquisition like any measured material.

References: Matusik, Pfister, Brand, McMillan, "A Data-Driven Reflectance Model",
SIGGRAPH 2003 (the sphere geometry); Blender manual, "Light Objects: Sun"
(strength in W/m^2) and "Principled BSDF".
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from ..analysis.checks import PropertyResult
from ..analysis.report import CheckReport
from ..models import merl
from . import runner

__all__ = ["ANGLES", "Acquisition", "acquire", "check_acquisition", "material_spec"]

#: Angles (degrees) between light and camera of the sun renders: theta_d = a / 2 every 5 degrees.
ANGLES = tuple(range(0, 171, 10))
#: Image size of the renders (the sphere's diameter is 1/1.1 of it).
RESOLUTION = 96
#: Samples per pixel (the sun is a delta light: one sample of a pixel already evaluates f
#: exactly; the furnace's noise falls as 1/sqrt(spp)).
SPP = 16
#: Width (degrees) of a furnace ring.
RING_DEG = 2.5
#: Pairs are kept where theta_i and theta_o are below this (degrees): beyond it a pixel
#: spans more than 5 degrees of normals and the terminator's shading-normal offset
#: (Cycles' shadow terminator fix) darkens the rim.
MAX_THETA_DEG = 75.0
#: Relative difference of f(wi, wo) and f(wo, wi) a reciprocal material keeps through the
#: acquisition (bilinear reading between pixel centres; Diffuse BSDF measured at
#: 1.5e-3 median, docs/blender.md).
RECIPROCITY_TOL = 0.02
#: Largest albedo excess over 1 kept, beyond 3 standard errors of the furnace ring
#: (the white furnace of a Diffuse BSDF of albedo 1 reads 1 to 1e-6, docs/blender.md).
ENERGY_TOL = 1e-3
ORTHO = 2.2


def material_spec(blend=None, material=None, *, principled=None, diffuse=None, script=None) -> dict:
    """The worker's material spec (:mod:`.worker`) of one of: a ``.blend`` file and a
    material name in it; a dict of Principled BSDF inputs (Blender's input names,
    e.g. ``{"Metallic": 1.0, "Roughness": 0.3}``); a Diffuse BSDF colour; a script
    defining ``build(bpy)``.  ValueError naming the argument otherwise."""
    given = [k for k, v in (("blend", blend), ("principled", principled), ("diffuse", diffuse),
                            ("script", script)) if v is not None]
    if len(given) != 1:
        raise ValueError(f"material: give one of blend (with material), principled, diffuse or script; "
                         f"got {', '.join(given) or 'none'}")
    if blend is not None:
        if not material:
            raise ValueError(f"material: name the material of {blend} to acquire")
        return {"blend": str(blend), "name": str(material)}
    if diffuse is not None:
        c = np.broadcast_to(np.asarray(diffuse, dtype=float), (3,))
        if not np.all((c >= 0) & (c <= 1)):
            raise ValueError(f"diffuse: the colour must be in [0, 1], got {diffuse!r}")
        return {"diffuse": c.tolist()}
    if script is not None:
        return {"script": str(script)}
    return {"principled": {str(k): v if isinstance(v, str) else (list(map(float, v)) if np.ndim(v) else float(v))
                           for k, v in principled.items()}}


@dataclass
class Acquisition:
    """What :func:`acquire` measured (all arrays float64, RGB last)."""

    name: str
    #: ``(n, 3)`` light-side and camera-side directions of the measured pairs (local frame)
    wi: np.ndarray
    wo: np.ndarray
    #: ``(n, 3)`` the measured ``f(wi, wo)``
    f: np.ndarray
    #: ``(m,)`` furnace rings' theta_o (radians), ``(m, 3)`` albedo and its standard error
    albedo_theta: np.ndarray
    albedo: np.ndarray
    albedo_stderr: np.ndarray
    #: ``(k, 3)`` f(wi, wo) and f(wo, wi) of the reciprocity pairs; ``(k, 3)`` their theta_i, theta_o
    #: (radians) and the error bound of the bilinear reading of f(wo, wi) (relative, :func:`_curvature`)
    f_ab: np.ndarray
    f_ba: np.ndarray
    recip_thetas: np.ndarray
    resolution: int
    spp: int
    angles: tuple
    seconds: float
    notes: list = field(default_factory=list)
    #: whether the directions are in a known tangent frame (:mod:`.tangent`; a class attribute)
    tangent_frame = False

    def brdf(self) -> merl.MerlBRDF:
        """The measured pairs as a MERL table (nearest measured pair per cell): the model
        contract, for ``check``, ``fit``, ``convert`` and the figures."""
        return merl.MerlBRDF(_fill_table(self.wi, self.wo, self.f), source=f"blender:{self.name}")


def pole_rotation(beta_deg: float = 0.0) -> np.ndarray:
    """The sphere's rotation (world from object) putting its pole (object ``z``, about which
    Cycles' default tangent turns) at ``(-sin b, cos b, 0)``, in the image plane: a quarter turn
    about ``x`` (``z`` to ``y``), then ``b`` about ``z``."""
    b = math.radians(beta_deg)
    rz = np.array([[math.cos(b), -math.sin(b), 0.0], [math.sin(b), math.cos(b), 0.0], [0.0, 0.0, 1.0]])
    rx = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])
    return rz @ rx


def turn_y(a_rad: float) -> np.ndarray:
    """``R``: the turn about ``y`` by ``-a`` (``R (sin a, 0, cos a) = z``, ``R z = (-sin a, 0, cos a)``)."""
    c, s = math.cos(a_rad), math.sin(a_rad)
    return np.array([[c, 0.0, -s], [0.0, 1.0, 0.0], [s, 0.0, c]])


def swapped_renders(angles, sphere: np.ndarray) -> list:
    """Per angle ``a`` of ``angles`` (degrees) the sun render (light at ``a`` in the ``xz`` plane, the
    sphere turned by ``sphere``) and its partner (light at ``-a``, the sphere turned by ``R sphere``:
    the sphere, and its tangent field, turn with the world; module docstring)."""
    out = []
    for a in angles:
        r = math.radians(a)
        out.append({"kind": "sun", "light": [math.sin(r), 0.0, math.cos(r)], "camera": [0, 0, 1],
                    "sphere": sphere.tolist()})
        out.append({"kind": "sun", "light": [-math.sin(r), 0.0, math.cos(r)], "camera": [0, 0, 1],
                    "sphere": (turn_y(r) @ sphere).tolist()})
    return out


def _pixel_normals(res: int):
    """``(res, res, 3)`` normals of the pixel centres (row 0 at the top) and the mask of the sphere."""
    c = ((np.arange(res) + 0.5) / res - 0.5) * ORTHO
    x, y = np.meshgrid(c, -c)
    r2 = x * x + y * y
    z = np.sqrt(np.clip(1.0 - r2, 0.0, 1.0))
    return np.stack([x, y, z], -1), r2 < 1.0


def _bilinear(img, x, y):
    """``img`` read bilinearly at image positions ``x, y`` (sphere radii)."""
    res = img.shape[0]
    u = (x / ORTHO + 0.5) * res - 0.5
    v = (0.5 - y / ORTHO) * res - 0.5
    j0 = np.clip(np.floor(u).astype(int), 0, res - 2)
    i0 = np.clip(np.floor(v).astype(int), 0, res - 2)
    fu, fv = (u - j0)[:, None], (v - i0)[:, None]
    corners = np.stack([img[i0, j0], img[i0, j0 + 1], img[i0 + 1, j0], img[i0 + 1, j0 + 1]])
    value = (1 - fu) * (1 - fv) * corners[0] + fu * (1 - fv) * corners[1] + (1 - fu) * fv * corners[2] \
        + fu * fv * corners[3]
    curv = _curvature(img)
    bound = np.max([curv[i0, j0], curv[i0, j0 + 1], curv[i0 + 1, j0], curv[i0 + 1, j0 + 1]], axis=0)
    return value, bound


def _curvature(img):
    """Bilinear reading's error bound per pixel, relative: ``(|d2/dx2| + |d2/dy2|) / 8`` of the
    image in pixel units (the error of linear interpolation is at most ``h^2 max|f''| / 8``)
    over the pixel's value, the largest channel; infinite at the image's border."""
    p = np.pad(img, ((1, 1), (1, 1), (0, 0)), mode="edge")
    d2 = np.abs(p[1:-1, :-2] - 2 * img + p[1:-1, 2:]) + np.abs(p[:-2, 1:-1] - 2 * img + p[2:, 1:-1])
    with np.errstate(divide="ignore", invalid="ignore"):
        rel = np.where(img > 0, d2 / 8.0 / img, np.where(d2 > 0, np.inf, 0.0))
    return rel.max(-1)


def _local(n, l, v):
    """``wi = l``, ``wo = v`` in the frame of each normal ``n`` (tangent toward ``l``)."""
    cl = n @ l
    t = l[None, :] - cl[:, None] * n
    tn = np.linalg.norm(t, axis=1)
    alt = np.cross(n, [0.0, 1.0, 0.0])          # l along n: any tangent (the BRDF is isotropic)
    t = np.where(tn[:, None] > 1e-9, t / np.maximum(tn, 1e-300)[:, None], alt / np.linalg.norm(alt, axis=1)[:, None])
    b = np.cross(n, t)
    wi = np.stack([t @ l, b @ l, cl], -1)
    wo = np.stack([t @ v, b @ v, n @ v], -1)
    return wi, wo


def _sun_pairs(img, a_deg, normals, mask):
    """The pairs of one sun render at angle ``a_deg``: ``(wi, wo, f)``."""
    a = math.radians(a_deg)
    l, v = np.array([math.sin(a), 0.0, math.cos(a)]), np.array([0.0, 0.0, 1.0])
    n = normals[mask]
    cmin = math.cos(math.radians(MAX_THETA_DEG))
    keep = (n @ l > cmin) & (n[:, 2] > cmin)
    n = n[keep]
    wi, wo = _local(n, l, v)
    return wi, wo, img[mask][keep] / (n @ l)[:, None]


def _swapped(img_a, img_b, a_deg, normals, mask):
    """f(wi, wo) of render ``a_deg`` and f(wo, wi) read from the render at ``-a_deg``."""
    a = math.radians(a_deg)
    n = normals[mask]
    l = np.array([math.sin(a), 0.0, math.cos(a)])
    cmin = math.cos(math.radians(MAX_THETA_DEG))
    keep = (n @ l > cmin) & (n[:, 2] > cmin)
    n, fa = n[keep], img_a[mask][keep] / (n[keep] @ l)[:, None]
    rn = n @ turn_y(a).T                                      # R n: R turns l onto z
    fb, spread = _bilinear(img_b, rn[:, 0], rn[:, 1])
    fb = fb / n[:, 2][:, None]                                # (R n) . l_b = n . z
    th = np.stack([np.arccos(np.clip(n @ l, -1, 1)), np.arccos(np.clip(n[:, 2], -1, 1)), spread], -1)
    return fa, fb, th


def _furnace(img, normals, mask):
    """Ring means of the furnace render: ``theta (m,), albedo (m, 3), stderr (m, 3)``."""
    th = np.degrees(np.arccos(np.clip(normals[mask][:, 2], -1, 1)))
    vals = img[mask]
    edges = np.arange(0.0, MAX_THETA_DEG + 1e-9, RING_DEG)
    out = []
    for lo, hi in zip(edges[:-1], edges[1:]):
        ring = (th >= lo) & (th < hi)
        s = vals[ring]
        if len(s) >= 2:
            out.append((math.radians(th[ring].mean()), s.mean(0), s.std(0, ddof=1) / math.sqrt(len(s))))
    return (np.array([o[0] for o in out]), np.array([o[1] for o in out]), np.array([o[2] for o in out]))


def acquire(spec: dict, *, name: str = "material", angles=ANGLES, resolution: int = RESOLUTION,
            spp: int = SPP, seed: int = 0, progress=None) -> Acquisition:
    """Measure a Cycles material (``spec``: :func:`material_spec`) by virtual acquisition
    (module docstring): one sun render per angle of ``angles`` and its mirror (light and
    camera swapped), one white furnace.  Parameters: ``resolution`` (pixels per side,
    16-2048), ``spp`` (samples per pixel, 1-65536), ``seed``.  Returns :class:`Acquisition`.

    >>> acq = acquire(material_spec(diffuse=0.5), angles=(0, 40), resolution=32)  # doctest: +SKIP
    >>> float(acq.f.mean() * math.pi)                                             # doctest: +SKIP
    0.5
    """
    if not 16 <= int(resolution) <= 2048:
        raise ValueError(f"resolution must be in [16, 2048] pixels, got {resolution!r}")
    if not 1 <= int(spp) <= 65536:
        raise ValueError(f"spp must be in [1, 65536], got {spp!r}")
    angles = tuple(float(a) for a in angles)
    if not angles or not all(0.0 <= a <= 175.0 for a in angles):
        raise ValueError(f"angles must be degrees in [0, 175], got {angles!r}")
    renders = [{"kind": "furnace", "camera": [0, 0, 1], "sphere": pole_rotation().tolist()}]
    renders += swapped_renders(angles, pole_rotation())
    from ..progress import start

    tick = start(progress, 1, f"acquire {name} in Cycles ({len(renders)} renders)")
    t0 = time.perf_counter()
    imgs = runner.run_job(spec, renders, resolution=resolution, spp=spp, seed=seed)
    tick()
    normals, mask = _pixel_normals(int(resolution))
    pairs = [_sun_pairs(imgs[1 + 2 * k], a, normals, mask) for k, a in enumerate(angles)]
    swaps = [_swapped(imgs[1 + 2 * k], imgs[2 + 2 * k], a, normals, mask) for k, a in enumerate(angles) if a > 0]
    th, alb, se = _furnace(imgs[0], normals, mask)
    cat = lambda k, xs: np.concatenate([x[k] for x in xs]) if xs else np.zeros((0, 3))   # noqa: E731
    return Acquisition(name, cat(0, pairs), cat(1, pairs), cat(2, pairs), th, alb, se, cat(0, swaps),
                       cat(1, swaps), cat(2, swaps) if swaps else np.zeros((0, 3)), int(resolution), int(spp),
                       angles, time.perf_counter() - t0)


def _cell_coords(wi, wo):
    """Measured pairs in MERL cell units: ``(i_h, i_d, i_p)`` as continuous numbers."""
    from ..arrays.ops import NP

    th, td, pd = merl.half_diff(NP, wi.T, wo.T)
    pd = np.where(pd < 0, pd + math.pi, pd)
    return np.stack([np.sqrt(np.maximum(th, 0) / merl.HALF_PI) * merl.RES[0], td / merl.HALF_PI * merl.RES[1],
                     pd / math.pi * merl.RES[2]], -1)


def _fill_table(wi, wo, f):
    """A MERL table ``(3, 90, 90, 180)``: each cell the nearest measured pair's ``f``
    (``phi_d`` periodic with period pi, by reciprocity and isotropy, as MERL's fold)."""
    from scipy.spatial import cKDTree

    pts = _cell_coords(wi, wo)
    # phi_d wraps: copies of the pairs one period (180 cells) either side
    rep = np.concatenate([pts + [0, 0, s] for s in (-merl.RES[2], 0, merl.RES[2])])
    tree = cKDTree(rep)
    g = np.stack(np.meshgrid(*(np.arange(r) + 0.5 for r in merl.RES), indexing="ij"), -1).reshape(-1, 3)
    _, k = tree.query(g, workers=1)
    vals = np.tile(f, (3, 1))[k]
    return vals.T.reshape((3,) + merl.RES)


#: A swapped pair is read bilinearly between four pixels; where the reading's error bound
#: (:func:`_curvature`: the image's second differences over 8, relative) exceeds this, a lobe
#: narrower than a few pixels, the pair is left out as unresolved (a quarter of the tolerance).
RESOLVED_SPREAD = 0.005
#: Fewest resolved pairs on which a failure of reciprocity is a verdict (else unresolved).
MIN_RESOLVED = 100


def _reciprocity(acq: Acquisition, tol: float) -> PropertyResult:
    """Relative difference of f(wi, wo) and f(wo, wi) over the swapped pairs where f is
    at least 1e-3 of its largest value and the lobe is resolved (:data:`RESOLVED_SPREAD`);
    passes when the 95th percentile is <= ``tol``; a failure is unresolved when fewer than
    :data:`MIN_RESOLVED` pairs are resolved.  The swapped pair is at the same tangent frame
    (the sphere turns with the world), so an anisotropic material is checked as an isotropic one."""
    fa, fb = acq.f_ab.mean(1), acq.f_ba.mean(1)
    big = np.maximum(fa, fb) > 1e-3 * max(float(np.max(np.maximum(fa, fb), initial=0.0)), 1e-300)
    ok = big & (acq.recip_thetas[:, 2] <= RESOLVED_SPREAD)
    rel = np.abs(fa - fb)[ok] / (0.5 * (fa + fb)[ok])
    if not big.any():
        return PropertyResult("reciprocity", True, math.nan, "not applicable: no swapped pairs (give an angle > 0)",
                              {}, dict(applicable=False, reason="no swapped pairs"))
    share = float(ok.sum() / big.sum())
    if rel.size == 0:
        return PropertyResult("reciprocity", False, math.nan, f"unresolved: no pair resolved at "
                              f"{acq.resolution} px (a lobe narrower than a few pixels)", {},
                              dict(resolved_share=share), unresolved=True)
    p95, med = float(np.percentile(rel, 95)), float(np.median(rel))
    k = int(np.argmax(np.where(ok, np.abs(fa - fb) / np.maximum(0.5 * (fa + fb), 1e-300), -1)))
    worst = dict(theta_i_deg=float(np.degrees(acq.recip_thetas[k, 0])),
                 theta_o_deg=float(np.degrees(acq.recip_thetas[k, 1])), f_ab=float(fa[k]), f_ba=float(fb[k]))
    unresolved = rel.size < MIN_RESOLVED and p95 > tol
    return PropertyResult("reciprocity", p95 <= tol, p95,
                          f"<= {tol:g} (95th percentile of |f(wi,wo) - f(wo,wi)| / mean over {rel.size} swapped "
                          f"pairs resolved at {acq.resolution} px, {share:.0%} of them; median {med:.3g})",
                          worst, dict(median=med, pairs=int(rel.size), resolved_share=share),
                          unresolved=unresolved)


def _energy(acq: Acquisition, tol: float) -> PropertyResult:
    """Largest furnace albedo (any ring, any channel); passes when it is at most
    ``1 + tol + 3`` standard errors of its ring."""
    excess = acq.albedo - (1.0 + tol + 3.0 * acq.albedo_stderr)
    i, c = np.unravel_index(int(np.argmax(acq.albedo)), acq.albedo.shape)
    top = float(acq.albedo[i, c])
    worst = dict(theta_deg=float(np.degrees(acq.albedo_theta[i])), channel="rgb"[c], albedo=top,
                 stderr=float(acq.albedo_stderr[i, c]))
    cells = f"{len(acq.albedo_theta)} rings of {RING_DEG:g} deg"
    if acq.tangent_frame:       # cells of (theta_o, phi_o) in the tangent frame: the whole hemisphere
        worst["phi_deg"] = float(np.degrees(acq.albedo_phi[i]))
        cells = f"{len(acq.albedo_theta)} cells of (theta_o, phi_o) in the tangent frame"
    return PropertyResult("energy", bool(np.all(excess <= 0)), top,
                          f"<= 1 + {tol:g} + 3 standard errors (white furnace, {cells} "
                          f"to {MAX_THETA_DEG:g} deg; largest stderr "
                          f"{float(acq.albedo_stderr.max()):.2g})", worst,
                          dict(albedo=acq.albedo.tolist(), stderr=acq.albedo_stderr.tolist(),
                               theta_deg=np.degrees(acq.albedo_theta).tolist()))


def check_acquisition(acq: Acquisition, *, reciprocity_tol: float = RECIPROCITY_TOL,
                      energy_tol: float = ENERGY_TOL) -> CheckReport:
    """``plausible check`` of an acquired Cycles material: reciprocity from swapped light
    and camera, energy from the white furnace's albedo, angle by angle (what
    :func:`acquire` measured; module docstring), as a :class:`CheckReport`.  The
    sampling and chi-square checks concern a sampler, which an acquisition does not
    have (Cycles samples its own BSDFs): reported not applicable.  An anisotropic material's
    reciprocity is checked (the swapped pair at the same tangent frame); its energy is a ring
    average here, over every ``(theta_o, phi_o)`` cell from :func:`.tangent.acquire_tangent`."""
    from ..analysis.report import not_applicable

    rep = CheckReport(f"blender:{acq.name}", dict(resolution=acq.resolution, spp=acq.spp,
                                                   angles_deg=list(acq.angles)))
    rep.results = [_reciprocity(acq, reciprocity_tol), _energy(acq, energy_tol),
                   not_applicable("sampling", "an acquisition measures values; Cycles keeps its sampler"),
                   not_applicable("chi2", "an acquisition measures values; Cycles keeps its sampler")]
    turns = f" x {len(acq.turns)} turns of a known tangent field" if acq.tangent_frame else ""
    rep.notes.append(f"acquired in Cycles ({len(acq.angles)} light angles x 2{turns} and a white furnace, "
                     f"{acq.resolution} px, {acq.spp} spp, {acq.seconds:.1f} s); {len(acq.f)} measured pairs with "
                     f"theta_i, theta_o <= {MAX_THETA_DEG:g} deg")
    rep.notes += acq.notes
    return rep
