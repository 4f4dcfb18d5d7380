"""Looks: two BSDFs compared as a user sees them, rendered side by side in Mitsuba (issue 40).

An albedo that holds at 0, 45 and 75 degrees says nothing of the highlight: a published
Ward fit converted to glTF kept its albedo within 0.05 and lost its highlight (the brightest
pixel 0.02x the source's).  :func:`compare_looks` renders both BSDFs on the same sphere and
scores the pair:

* **the scene** (:func:`render_looks`): a unit sphere seen by :data:`LIGHT_ANGLES` orthographic
  cameras (Mitsuba's ``batch`` sensor, one image per camera side by side), lit

  - by an environment alone (:func:`environment`: a sky brightening toward the zenith over
    a dark ground, with a sharp horizon, so that a sharp lobe shows the horizon and a rough
    one blurs it), and
  - by a distant "point light" alone: a spherical lamp of angular radius :data:`LAMP_DEG` (5 degrees)
    1000 radii away, of the irradiance :data:`IRRADIANCE` a point light would give, at angle ``a``
    from each camera: ``0`` (the light behind the camera: the highlight at the centre, incidence 0),
    ``60``, ``120`` and ``150`` degrees (mirror incidence ``a / 2``: 0, 30, 60 and 75 degrees --
    grazing included).  A true point light's highlight on a sharp lobe is smaller than a pixel and
    found by a pixel's few samples by chance; the lamp's reflection covers a few pixels;

  with the ``path`` integrator, ``max_depth = 2`` (one bounce: a convex sphere has no
  inter-reflection), ``hide_emitters`` (black background), the ``multijitter`` sampler, and
  :data:`LIGHT_SPP` times the samples for the light's image.  The two lightings are rendered
  apart so that the light's peak is measured on its own; the view shown (and scored by FLIP) is
  their sum.  A sum of models (:class:`plausible.Sum`) is rendered part by part and the images
  added with the parts' scales: the render is linear in the BSDF (one bounce), so the sum's image
  is exact; a published fit through the plugin ``plausible_material``.
* **FLIP** (Andersson et al. 2020, 2021; NVIDIA's ``flip-evaluator``, HDR mode, the source as
  the reference, its default 67 pixels per degree): the mean of the per-pixel error over the
  sphere's pixels of each view (environment + light), and the mean over the views
  (:attr:`Looks.flip`).  0 is identical; 1 is the largest difference.
* **highlight ratio**: per light angle, the peak luminance (Rec. 709, :func:`plausible.spectra.luminance`;
  the largest mean over :data:`PEAK_WINDOW` x :data:`PEAK_WINDOW` pixels) of the result's light image
  over the source's (:attr:`Looks.highlight_ratios`); the worst one (farthest from 1 by ``|log r|``)
  is :attr:`Looks.highlight_ratio`.  Outside :data:`HIGHLIGHT_BAND` a warning: "highlight lost"
  below, "highlight invented" above.  Noise (seed to seed): 2-5 % for Ngan et al.'s fits, up to 16 %
  for Löw et al.'s sharpest (exponent 4e4).

Renders of a BSDF are cached in this process (:data:`CACHE_SIZE` entries, keyed by its
Mitsuba dict and the options): a source compared with several results is rendered once.
Defaults (64 x 64 per view, 16 samples per pixel, 256 for the light): about 0.6 CPU-s to render one
BSDF once Dr.Jit has compiled its kernels (a new plugin's first render: about 1 s more), 0.15 s of
FLIP per view (docs/looks.md).

References: P. Andersson, J. Nilsson, T. Akenine-Möller, M. Oskarsson, K. Åström,
M. D. Fairchild, "FLIP: A Difference Evaluator for Alternating Images", Proc. ACM CGIT 3(2),
2020; P. Andersson et al., "Visualizing Errors in Rendered High Dynamic Range Images",
Eurographics 2021 short papers (HDR-FLIP).
"""

from __future__ import annotations

import json
import math
import time
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from ..spectra import luminance

__all__ = ["HIGHLIGHT_BAND", "IRRADIANCE", "LIGHT_ANGLES", "LampStrip", "Looks", "Renders", "compare_looks", "compare_renders",
           "environment", "mitsuba_parts", "render_looks"]

#: Angles (degrees) between the camera and the point light, one view each: the mirror
#: direction's incidence is half of each (0, 30, 60, 75 degrees).
LIGHT_ANGLES = (0.0, 60.0, 120.0, 150.0)
#: Pixels per side of one view, and samples per pixel.
RES, SPP = 64, 16
SAMPLER = "multijitter"
#: Irradiance of the light (at normal incidence): a white Lambertian facing it has radiance 1
#: (``rd / pi * E``).
IRRADIANCE = math.pi
#: The "point light" is a distant spherical lamp of this angular radius (degrees), at
#: :data:`LAMP_DISTANCE` (100 sphere radii): a true point light's highlight on a sharp lobe is smaller
#: than a pixel, and a pixel's 16 samples find it by chance (the peak of one Löw et al. fit, rendered
#: with two seeds, differed by 0.1-0.97x); the lamp's reflection covers a few pixels and is found by
#: the BSDF's own samples (multiple importance sampling).  Its radiance gives the irradiance
#: ``pi L sin^2(a)`` = :data:`IRRADIANCE` of a point light.
LAMP_DEG, LAMP_DISTANCE = 5.0, 1000.0
#: The light's image takes this many times the samples per pixel (it is cheap: no environment).
LIGHT_SPP = 16
#: The window (pixels) over which a peak is averaged (:meth:`Renders.peaks`).
PEAK_WINDOW = 3
#: The band of the highlight ratio (result / source) kept without a warning: 1/1.5 to 1.5
#: (docs/looks.md: 1.5x is 0.6 stops, a highlight visibly dimmer or brighter side by side; the
#: ratio's noise is 2-5 % seed to seed, 16 % for the sharpest published lobes; today's conversions
#: spread over 0.002-17x).
HIGHLIGHT_BAND = (1.0 / 1.5, 1.5)
#: Peak luminance below which a point-light image counts as black (of :data:`IRRADIANCE` ~ 3):
#: a ratio is taken of the peaks floored at it, so two black images have ratio 1.
PEAK_FLOOR = 1e-4
#: Orthographic half-width of a view (the sphere has radius 1).
HALF_WIDTH = 1.05
#: Renders kept in memory.
CACHE_SIZE = 64

_CACHE: OrderedDict = OrderedDict()


@dataclass(frozen=True)
class Renders:
    """One BSDF's images (linear RGB, float32), the views side by side: ``env`` (H, K*W, 3)
    under the environment, ``light`` (H, K*W, 3) under the point light, K = ``len(angles)``."""

    env: np.ndarray
    light: np.ndarray
    angles: tuple

    def view(self, k: int, which: str = "both") -> np.ndarray:
        """View ``k`` (H, W, 3): ``"env"``, ``"light"`` or ``"both"`` (their sum, what is shown)."""
        w = self.env.shape[1] // len(self.angles)
        sl = slice(k * w, (k + 1) * w)
        if which == "env":
            return self.env[:, sl]
        if which == "light":
            return self.light[:, sl]
        return self.env[:, sl] + self.light[:, sl]

    def peaks(self) -> np.ndarray:
        """The peak of each view's light image: the largest mean luminance over a window of
        :data:`PEAK_WINDOW` x :data:`PEAK_WINDOW` pixels (the highlight's energy near its
        centre, which does not depend on where the pixel grid cuts a highlight of a few pixels)."""
        return _window_max(np.stack([luminance(self.view(k, "light")) for k in range(len(self.angles))]))

    def __add__(self, other):
        return Renders(self.env + other.env, self.light + other.light, self.angles)

    def scaled(self, s):
        s = np.asarray(s, np.float32)
        return Renders(self.env * s, self.light * s, self.angles)


@dataclass
class Looks:
    """Two BSDFs compared by their renders (:func:`compare_looks`).

    ``flip``: mean HDR-FLIP over the views (each: the mean over the sphere's pixels);
    ``flips``: per view; ``highlight_ratio``: the worst of ``highlight_ratios`` (result's
    peak / source's, per light angle of ``angles``); ``peaks``: ``(source, result)`` peak
    luminances per angle; ``band``: the ratio band; ``warnings``: one per way the highlight
    leaves the band; ``seconds``: the comparison's wall time."""

    flip: float
    flips: tuple
    highlight_ratio: float
    highlight_ratios: tuple
    angles: tuple
    peaks: tuple
    band: tuple = HIGHLIGHT_BAND
    warnings: list = field(default_factory=list)
    seconds: float = 0.0
    source: Renders | None = field(default=None, repr=False)
    result: Renders | None = field(default=None, repr=False)

    @property
    def ok(self) -> bool:
        """No warning: every highlight ratio within the band."""
        return not self.warnings

    def summary(self) -> str:
        """``"FLIP 0.123, highlight x0.02 (0.02 0.05 0.3 0.9 at 0/60/120/150 deg)"``."""
        per = " ".join(f"{r:.3g}" for r in self.highlight_ratios)
        return (f"FLIP {self.flip:.3f}, highlight x{self.highlight_ratio:.3g} ({per} at "
                f"{'/'.join(f'{a:g}' for a in self.angles)} deg)")

    def to_dict(self) -> dict:
        """Plain data (JSON) of the scores."""
        return {"flip": self.flip, "flips": list(self.flips), "highlight_ratio": self.highlight_ratio,
                "highlight_ratios": list(self.highlight_ratios), "angles": list(self.angles),
                "peaks": [list(p) for p in self.peaks], "band": list(self.band), "warnings": list(self.warnings),
                "ok": self.ok, "seconds": self.seconds}


# -- what is rendered --------------------------------------------------------------------------------

def mitsuba_parts(x) -> list:
    """``x`` as ``[(what mi.load_dict takes as a BSDF, scale), ...]``, whose images add up to ``x``'s.

    ``x``: a Mitsuba BSDF dict (``{"type": "diffuse", ...}``) or ``mitsuba.BSDF``; a model spec
    (``"ward:..."``, ``"material:NAME@FIT"``, a sum ``"a + b"``); a registered model (its plausible
    plugin, :func:`plausible.mitsuba.scene_dict.to_dict`); a published fit (the plugin
    ``plausible_material``); a :class:`plausible.Sum` (its parts, each with its scale); a MERL
    table (the ``merl`` plugin); the adapter of a Mitsuba BSDF (its BSDF).  ValueError for
    anything else (a Python callable has no Mitsuba form)."""
    from .. import registry
    from ..bxdf import BxDF
    from ..catalogue.entry import Material
    from ..models.sum import Sum

    if isinstance(x, dict):
        if "type" not in x:
            raise ValueError(f"a Mitsuba BSDF dict needs a 'type'; got {x!r}")
        return [(x, 1.0)]
    if isinstance(x, str):
        text = x.strip()
        if text.startswith("mitsuba:{"):
            return [(json.loads(text.split(":", 1)[1]), 1.0)]
        return [p for s in text.split(" + ") for p in mitsuba_parts(registry.make_from_spec(s.strip()))]
    if isinstance(x, Material):
        return [({"type": Material.OWNER, "name": x.params["name"], "fit": x.params["fit"]}, 1.0)]
    if isinstance(x, Sum):
        fit = _published(x)
        if fit is not None:     # one plugin for every published fit (its parts need not have one)
            return [({"type": Material.OWNER, "name": fit[0], "fit": fit[1]}, 1.0)]
        return [(d, _times(s, k)) for part, s in zip(x.parts, x.scales) for d, k in mitsuba_parts(part)]
    if type(x).__name__ == "MerlBRDF":
        return [({"type": "merl", "filename": str(x.source)}, 1.0)]
    if hasattr(x, "bsdf") and type(x).__name__ == "MitsubaBSDF":
        return [(x.bsdf, 1.0)]
    if isinstance(x, BxDF):
        from .scene_dict import to_dict

        return [(to_dict(x), 1.0)]
    if _is_mitsuba_bsdf(x):
        return [(x, 1.0)]
    raise ValueError(f"cannot render {type(x).__name__} {x!r:.80} in Mitsuba: give a model, a spec, a published "
                     f"fit or a Mitsuba BSDF (dict or object)")


def _published(x):
    """``(name, fit)`` of a :class:`plausible.Sum` that is a published fit as
    :func:`plausible.material` builds it (named ``NAME@FIT``, and equal to that fit), else None."""
    from ..catalogue import fit_sets as F

    name, at, fit = str(getattr(x, "name", "")).partition("@")
    if not at or name not in F.materials() or fit not in {f.key for f in F.fits() if f.built}:
        return None
    ref = F.material(name, fit)
    same = len(ref.parts) == len(x.parts) and all(
        repr(a) == repr(b) and np.array_equal(np.asarray(1.0 if s is None else s), np.asarray(1.0 if t is None else t))
        for a, b, s, t in zip(ref.parts, x.parts, ref.scales, x.scales))
    return (name, fit) if same else None


def _window_max(y: np.ndarray, w: int | None = None):
    """The largest mean of ``y`` over a ``w`` x ``w`` window inside the image: a float for one image
    (H, W), an array of one per image for a stack (..., H, W) (filtered in one call)."""
    from scipy.ndimage import uniform_filter

    w = PEAK_WINDOW if w is None else w
    h = w // 2
    y = np.asarray(y, np.float64)
    size = (1,) * (y.ndim - 2) + (w, w)
    m = uniform_filter(y, size=size, mode="constant")[..., h:-h or None, h:-h or None]
    return float(np.max(m)) if y.ndim == 2 else np.max(m, axis=(-2, -1))


def _times(a, b):
    a = 1.0 if a is None else a
    return np.asarray(a, float) * np.asarray(b, float) if np.ndim(a) or np.ndim(b) else float(a) * float(b)


def _is_mitsuba_bsdf(x) -> bool:
    import sys

    mi = sys.modules.get("mitsuba")
    try:
        return mi is not None and isinstance(x, mi.BSDF)
    except (AttributeError, ImportError):
        return False


def environment(mi, width: int = 128):
    """The environment map (``mi.Bitmap``, latitude-longitude, +y up as Mitsuba's ``envmap``):
    sky radiance ``0.5 + y`` above the horizon (0.5 at the horizon, 1.5 at the zenith), 0.1 below."""
    h = width // 2
    y = np.cos((np.arange(h) + 0.5) / h * math.pi)          # +y component of each row's direction
    row = np.where(y > 0.0, 0.5 + y, 0.1).astype(np.float32)
    img = np.repeat(np.repeat(row[:, None, None], width, axis=1), 3, axis=2)
    return mi.Bitmap(np.ascontiguousarray(img))


def _scene(mi, bsdf, angles, res, spp, light: bool):
    """The sphere with ``bsdf``, the batch of cameras, and either light."""
    sensor = {"type": "batch", "sampler": {"type": SAMPLER, "sample_count": spp},
              "film": {"type": "hdrfilm", "width": res * len(angles), "height": res, "rfilter": {"type": "box"},
                       "pixel_format": "rgb"}}
    for k, a in enumerate(angles):
        a = math.radians(a)
        sensor[f"view_{k}"] = {"type": "orthographic", "to_world": mi.ScalarTransform4f().look_at(
            origin=[5.0 * math.sin(a), 0.0, 5.0 * math.cos(a)], target=[0, 0, 0], up=[0, 1, 0])
            @ mi.ScalarTransform4f().scale([HALF_WIDTH, HALF_WIDTH, 1.0])}
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": 2, "hide_emitters": True}, "sensor": sensor,
         "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf}}
    if light:
        sin_a = math.sin(math.radians(LAMP_DEG))
        d["light"] = {"type": "sphere", "center": [0.0, 0.0, LAMP_DISTANCE], "radius": LAMP_DISTANCE * sin_a,
                      "emitter": {"type": "area", "radiance": {"type": "rgb", "value": IRRADIANCE / (math.pi * sin_a ** 2)}}}
    else:
        d["env"] = {"type": "envmap", "bitmap": environment(mi)}
    return mi.load_dict(d)


def _mitsuba():
    """Mitsuba with plausible's plugins registered in an RGB variant (ValueError in another)."""
    from . import register
    from .variant import ensure_variant

    mi = ensure_variant()
    if mi.is_spectral or mi.is_polarized:
        raise ValueError(f"compare_looks renders in an RGB variant (llvm_ad_rgb); Mitsuba is set to "
                         f"{mi.variant()!r}")
    register()
    return mi


def _render_one(bsdf, angles, res, spp, seed) -> Renders:
    mi = _mitsuba()
    key = None
    if isinstance(bsdf, dict):
        try:
            key = (json.dumps(bsdf, sort_keys=True), tuple(angles), res, spp, seed)
        except TypeError:       # a dict holding Mitsuba objects: not cached
            key = None
    if key is not None and key in _CACHE:
        _CACHE.move_to_end(key)
        return _CACHE[key]
    try:
        imgs = [np.array(mi.render(_scene(mi, bsdf, angles, res, spp * (LIGHT_SPP if light else 1), light), seed=seed),
                         dtype=np.float32)[..., :3] for light in (False, True)]
    except Exception as e:  # noqa: BLE001 - Mitsuba's own errors (a bad dict, a plugin's refusal)
        what = bsdf.get("type") if isinstance(bsdf, dict) else type(bsdf).__name__
        raise ValueError(f"rendering {what!r} failed: {str(e).strip().splitlines()[-1]}") from None
    out = Renders(np.nan_to_num(imgs[0]), np.nan_to_num(imgs[1]), tuple(angles))
    if key is not None:
        _CACHE[key] = out
        while len(_CACHE) > CACHE_SIZE:
            _CACHE.popitem(last=False)
    return out


def render_looks(x, *, angles=LIGHT_ANGLES, res: int = RES, spp: int = SPP, seed: int = 0) -> Renders:
    """The :class:`Renders` of ``x`` (anything :func:`mitsuba_parts` reads): each part rendered
    (cached) and the images added with the parts' scales."""
    _check_options(angles, res, spp)
    total = None
    for bsdf, s in mitsuba_parts(x):
        r = _render_one(bsdf, tuple(float(a) for a in angles), int(res), int(spp), int(seed))
        r = r if np.ndim(s) == 0 and float(s) == 1.0 else r.scaled(s)
        total = r if total is None else total + r
    return total


def _check_options(angles, res, spp):
    if not angles or not all(isinstance(a, (int, float)) and 0.0 <= a < 180.0 for a in angles):
        raise ValueError(f"angles: light angles in degrees in [0, 180), at least one; got {angles!r}")
    if not isinstance(res, int) or not 8 <= res <= 1024:
        raise ValueError(f"res: pixels per side of a view, an integer in [8, 1024]; got {res!r}")
    if not isinstance(spp, int) or not 1 <= spp <= 4096:
        raise ValueError(f"spp: samples per pixel, an integer in [1, 4096]; got {spp!r}")


# -- the highlight without a render -------------------------------------------------------------------

#: Directions over the lamp (each with a point of the pixel) of :class:`LampStrip`: 256 put the
#: predicted peak within 1-8 % of the rendered one for the issue's published fits and their conversions.
LAMP_POINTS = 256
#: Rows of a view, about its middle, that :class:`LampStrip` computes: the plane of the camera and the
#: light cuts an isotropic BSDF's image in two mirror halves, and its highlight lies on that plane.
STRIP_ROWS = 4


@dataclass
class LampStrip:
    """The light image of the middle rows of each view (:data:`STRIP_ROWS`), computed in NumPy from a
    BSDF's ``f`` instead of rendered, and its peak as :meth:`Renders.peaks` takes it.  At each pixel
    (orthographic view, the camera ``a`` from the lamp, the lamp along +z) the radiance is
    ``(1/K) sum_k f(l_k, v) cos(theta_l_k) L Omega`` over ``K =`` :data:`LAMP_POINTS` directions
    ``l_k`` spread over the lamp's cone (a Fibonacci lattice; ``L = IRRADIANCE / (pi sin^2 LAMP_DEG)``,
    ``Omega = 2 pi (1 - cos LAMP_DEG)``), each paired with a point ``p_k`` of the pixel (the R2
    sequence) whose normal gives the local frame: one sum integrates over the lamp and over the pixel's
    footprint (on the limb a pixel spans 7 degrees of normal at 150 degrees; a point off the sphere
    counts 0, as a pixel on the limb renders).  The peak is the largest mean over :data:`PEAK_WINDOW`
    x :data:`PEAK_WINDOW` pixels of the strip's luminance.  Only the lower half of the strip is
    evaluated and mirrored: an isotropic BSDF's image is symmetric about the plane of camera and light.
    ``wi``, ``wo``: every pair of every view, end to end, in local frames -- a fit evaluates its
    candidates there (:mod:`plausible.conversion.mitsuba`) and calls :meth:`peaks` on the values.
    Measured against the render (``compare_looks``' 64 px, 16 spp, 256 for the light) for the issue's
    published fits and their conversions: within 1-8 % at 256 points (64 points: up to 60 % off for the
    sharpest, chrome@ngan2005/ward at 120-150 degrees), so :data:`LAMP_POINTS` is 256."""

    angles: tuple
    res: int
    wi: np.ndarray
    wo: np.ndarray
    #: per view: ``(the flat position in the (rows, res) strip of each pair's pixel, number of pairs)``
    layout: list
    weight: float
    rows: int = STRIP_ROWS

    @classmethod
    def make(cls, angles=LIGHT_ANGLES, res: int = RES, rows: int = STRIP_ROWS, points: int = LAMP_POINTS):
        # pair k of a pixel: lamp direction k (a Fibonacci lattice over the cone) and a point of the pixel
        # (the R2 sequence), so that one sum integrates over the lamp and the pixel's footprint (on the
        # limb a pixel spans 7 degrees of normal at 150 degrees); points off the sphere count 0
        k = np.arange(points) + 0.5
        cos_a = math.cos(math.radians(LAMP_DEG))
        ct = 1.0 - k / points * (1.0 - cos_a)
        phi = k * math.pi * (3.0 - math.sqrt(5.0))
        lamp = np.stack([np.sqrt(1.0 - ct ** 2) * np.cos(phi), np.sqrt(1.0 - ct ** 2) * np.sin(phi), ct], -1)
        du, dv = (0.5 + k * 0.7548776662466927) % 1.0, (0.5 + k * 0.5698402909980532) % 1.0
        if res % 2 or rows % 2 or not 2 <= rows <= res:
            raise ValueError(f"LampStrip: res and rows must be even, 2 <= rows <= res; got res={res}, rows={rows}")
        # the lower half of the strip; the upper half is its mirror image (the image of an isotropic
        # BSDF is symmetric about the plane of the camera and the light, between the two middle rows)
        mid = np.arange(res // 2, res // 2 + rows // 2)
        R, C = np.meshgrid(mid - mid[0], np.arange(res), indexing="ij")
        X = ((C[..., None] + du) / res * 2.0 - 1.0) * HALF_WIDTH               # (rows, res, points)
        Y = ((mid[:, None, None] + dv) / res * 2.0 - 1.0) * HALF_WIDTH + 0.0 * X
        hit = X ** 2 + Y ** 2 < 1.0
        pix = (R[..., None] * res + C[..., None] + 0 * X.astype(int))[hit]
        L = np.broadcast_to(lamp, X.shape + (3,))[hit]
        X, Y = X[hit], Y[hit]
        WI, WO, layout = [], [], []
        for a in angles:
            a = math.radians(a)
            v = np.array([math.sin(a), 0.0, math.cos(a)])
            right = np.cross([0.0, 1.0, 0.0], v)
            n = X[:, None] * right + Y[:, None] * np.array([0.0, 1.0, 0.0]) + np.sqrt(1.0 - X ** 2 - Y ** 2)[:, None] * v
            t = np.cross(n, [0.0, 1.0, 0.0])
            t /= np.linalg.norm(t, axis=1)[:, None]
            b = np.cross(n, t)
            frame = np.stack([t, b, n], 1)                       # rows: the local axes at each point
            wo, wi = frame @ v, np.einsum("pij,pj->pi", frame, L)
            lit = (wi[:, 2] > 1e-6) & (wo[:, 2] > 1e-6)          # the lamp below a point's horizon: 0
            WO.append(wo[lit])
            WI.append(wi[lit])
            layout.append((pix[lit], int(lit.sum())))
        weight = IRRADIANCE / (math.pi * math.sin(math.radians(LAMP_DEG)) ** 2) * 2.0 * math.pi * (1.0 - cos_a) / points
        return cls(tuple(angles), res, np.concatenate(WI), np.concatenate(WO), layout, weight, rows)

    def images(self, f) -> list:
        """The strip images (rows, res[, C]) of ``f``, the BSDF's values at ``wi``, ``wo`` ((N,) or (N, C))."""
        f = np.asarray(f, float)
        f = f.reshape(len(f), -1)
        out, s = [], 0
        for pix, n in self.layout:
            part = f[s:s + n] * (np.maximum(self.wi[s:s + n, 2], 0.0) * self.weight)[:, None]
            img = np.stack([np.bincount(pix, part[:, c], self.rows // 2 * self.res) for c in range(part.shape[1])], -1)
            img = img.reshape(self.rows // 2, self.res, -1)
            out.append(np.concatenate([img[::-1], img]))
            s += n
        return out

    def peaks(self, f) -> np.ndarray:
        """The peak of each view (luminance of a colour image; a grey one as it is)."""
        return _window_max(np.stack([luminance(im) for im in self.images(f)]))

    def of(self, model) -> np.ndarray:
        """:meth:`peaks` of a contract object (``eval(wi, wo)``)."""
        return self.peaks(model.eval(self.wi, self.wo))


# -- the scores ---------------------------------------------------------------------------------------

def sphere_mask(res: int) -> np.ndarray:
    """The pixels (res, res) whose centre sees the unit sphere in a view."""
    x = ((np.arange(res) + 0.5) / res * 2.0 - 1.0) * HALF_WIDTH
    return np.hypot(x[None, :], x[:, None]) < 1.0


def hdr_flip(reference: np.ndarray, test: np.ndarray, mask: np.ndarray | None = None) -> float:
    """Mean HDR-FLIP error of ``test`` against ``reference`` (linear RGB, H x W x 3) over
    ``mask`` (all pixels if None).  FLIP takes its exposure range from the reference; a black
    reference takes it from the test, and two black images give 0."""
    import flip_evaluator
    from threadpoolctl import threadpool_limits

    ref = np.ascontiguousarray(np.maximum(reference, 0.0), dtype=np.float32)
    tst = np.ascontiguousarray(np.maximum(test, 0.0), dtype=np.float32)
    if not ref.any() and not tst.any():
        return 0.0
    if not ref.any() or np.ptp(luminance(ref)) == 0.0:
        ref, tst = tst, ref
    # one OpenMP thread: flip-evaluator's threads spin against Dr.Jit's (and other processes') for
    # cores; 0.15 s a 64 x 64 view with one, 1-3 s with the default on a shared 2-core machine
    with threadpool_limits(limits=1, user_api="openmp"):
        err = flip_evaluator.evaluate(ref, tst, "HDR", applyMagma=False, computeMeanError=False)[0][..., 0]
    return float(np.mean(err[mask] if mask is not None else err))


def compare_renders(source: Renders, result: Renders, band=HIGHLIGHT_BAND) -> Looks:
    """The :class:`Looks` of two BSDFs' :class:`Renders` (the same angles and size)."""
    if source.env.shape != result.env.shape or source.angles != result.angles:
        raise ValueError(f"renders of different scenes: {source.env.shape} at {source.angles} against "
                         f"{result.env.shape} at {result.angles}")
    lo, hi = float(band[0]), float(band[1])
    if not 0.0 < lo <= 1.0 <= hi:
        raise ValueError(f"band: (low, high) with 0 < low <= 1 <= high; got {band!r}")
    mask = sphere_mask(source.env.shape[0])
    flips = tuple(hdr_flip(source.view(k), result.view(k), mask) for k in range(len(source.angles)))
    ps, pr = source.peaks(), result.peaks()
    ratios = tuple(float(r) for r in np.maximum(pr, PEAK_FLOOR) / np.maximum(ps, PEAK_FLOOR))
    worst = max(ratios, key=lambda r: abs(math.log(r)))
    return Looks(float(np.mean(flips)), flips, worst, ratios, source.angles,
                 tuple((float(a), float(b)) for a, b in zip(ps, pr)), (lo, hi),
                 _warnings(ratios, source.angles, lo, hi), source=source, result=result)


def _warnings(ratios, angles, lo, hi) -> list:
    out = []
    for word, bad in (("lost", [(a, r) for a, r in zip(angles, ratios) if r < lo]),
                      ("invented", [(a, r) for a, r in zip(angles, ratios) if r > hi])):
        if bad:
            out.append(f"highlight {word}: the result's highlight under the light is "
                       + ", ".join(f"{r:.3g}x the source's at {a:g} deg" for a, r in bad)
                       + f" (band {lo:.3g}-{hi:.3g}x)")
    return out


def compare_looks(source, result, *, angles=LIGHT_ANGLES, res: int = RES, spp: int = SPP, seed: int = 0,
                  band=HIGHLIGHT_BAND) -> Looks:
    """Render ``source`` and ``result`` side by side and score the pair (module docstring).

    Parameters
    ----------
    source, result : anything :func:`mitsuba_parts` reads
        A model, a spec string (``"material:alum-bronze@ngan2005/ward"``, ``"a + b"``), a Mitsuba
        BSDF dict or object.  ``source`` is FLIP's reference.
    angles : degrees in [0, 180)
        Angles between camera and point light, one view each (default :data:`LIGHT_ANGLES`).
    res, spp : int
        Pixels per side of a view (8-1024, default 64) and samples per pixel (1-4096, default 16).
    seed : int
        The renders' seed (the same for both: identical BSDFs give identical images).
    band : (low, high)
        Highlight ratios kept without a warning (default :data:`HIGHLIGHT_BAND`, 1/1.5-1.5).

    Returns
    -------
    Looks
        FLIP, highlight ratios, warnings (``.ok`` when there is none).

    >>> import plausible
    >>> looks = plausible.compare_looks("lambertian:rd=0.2", {"type": "diffuse", "reflectance": 0.6})  # doctest: +SKIP
    >>> round(looks.highlight_ratio, 3), looks.warnings[0][:19]                                        # doctest: +SKIP
    (3.0, 'highlight invented:')
    """
    t0 = time.perf_counter()
    a = render_looks(source, angles=angles, res=res, spp=spp, seed=seed)
    b = render_looks(result, angles=angles, res=res, spp=spp, seed=seed)
    looks = compare_renders(a, b, band)
    looks.seconds = time.perf_counter() - t0
    return looks
