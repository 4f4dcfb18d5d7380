"""Mitsuba 3 scene builders and image output for the figures.

Every scene is a ``mi.load_dict`` description built from plausible's plugins
(:mod:`plausible.mitsuba`); nothing here holds a BRDF formula.  Images are
written twice: linear HDR (OpenEXR, the rendered radiance) and tone-mapped
8-bit sRGB PNG for viewing.
"""

from __future__ import annotations

import math
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from ..spectra import luminance  # noqa: F401 - figures call it as scenes.luminance

#: The kinds of Mitsuba variant the figures render with; the device is
#: :func:`plausible.mitsuba.variant.preferred`'s (CUDA where a GPU is found, else LLVM;
#: ``plausible figures --variant``).
RGB = "rgb"
SPECTRAL = "spectral"

#: Gold's colour at normal incidence (linear sRGB of the conductor reflectance
#: of Au from plausible.spectra), used for the "golden" spheres of A-S fig. 3.
GOLD_FALLBACK = (1.0, 0.71, 0.29)


def mitsuba(kind: str = RGB):
    """Set the Mitsuba variant of ``kind`` (:data:`RGB` or :data:`SPECTRAL`, or a full variant name) on the device in
    force (:func:`plausible.mitsuba.variant.preferred`), register plausible's plugins, return ``mi``."""
    import mitsuba as mi

    import plausible.mitsuba as pm
    from plausible.mitsuba.variant import preferred

    pm.register(kind if "_" in kind else preferred(kind))     # a full variant name (a figure restoring one) as it is
    return mi


def gold_rgb() -> tuple:
    """Linear-sRGB normal-incidence reflectance of gold (conductor Fresnel with
    Au's tabulated n, k, reduced to RGB by :mod:`plausible.spectra`)."""
    try:
        from plausible import spectra

        return tuple(float(min(max(x, 0.0), 1.0)) for x in spectra.metal_rgb("Au"))
    except Exception:   # older tables: a fixed gold colour
        return GOLD_FALLBACK


# -- sensors -----------------------------------------------------------------------

def orthographic(mi, width: float, res: int, spp: int, origin=(0, 0, 5), target=(0, 0, 0), up=(0, 1, 0),
                 height: int | None = None):
    """Orthographic camera covering ``[-width, width]`` horizontally (box filter,
    so a pixel is the mean radiance over its footprint)."""
    return {
        "type": "orthographic",
        "to_world": mi.ScalarTransform4f().look_at(origin=list(origin), target=list(target), up=list(up))
        @ mi.ScalarTransform4f().scale([width, width * (height or res) / res, 1.0]),
        "film": {"type": "hdrfilm", "width": res, "height": height or res, "rfilter": {"type": "box"},
                 "pixel_format": "rgb"},
        "sampler": {"type": "independent", "sample_count": spp},
    }


def perspective(mi, origin, target, res: int, spp: int, fov: float = 35.0, up=(0, 0, 1), height=None, crop=None,
                rfilter: str = "gaussian"):
    """A perspective camera (``fov`` degrees across the width); ``crop = (y0, x0, h, w)``
    renders only that window of the film; ``rfilter`` the film's reconstruction filter."""
    film = {"type": "hdrfilm", "width": res, "height": height or res, "rfilter": {"type": rfilter},
            "pixel_format": "rgb"}
    if crop is not None:
        y0, x0, h, w = crop
        film.update(crop_offset_x=x0, crop_offset_y=y0, crop_width=w, crop_height=h)
    return {
        "type": "perspective", "fov": fov,
        "to_world": mi.ScalarTransform4f().look_at(origin=list(origin), target=list(target), up=list(up)),
        "film": film,
        "sampler": {"type": "independent", "sample_count": spp},
    }


# -- scenes ---------------------------------------------------------------------

def furnace(mi, bsdf: dict, res: int, spp: int, width: float = 1.05):
    """Unit sphere in a constant unit-radiance environment ("furnace", A-S fig. 2),
    seen by an orthographic camera down ``-z``: the pixel at image radius ``r``
    (in sphere radii) sees the surface at incidence ``asin(r)``; ``path`` with
    ``max_depth = 2`` (one bounce: the pixel is the directional albedo)."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 2},
        "sensor": orthographic(mi, width, res, spp),
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })


def checker_plane(scale: float = 20.0, size: float = 12.0, colors=((0.75, 0.75, 0.75), (0.15, 0.15, 0.2)),
                  z: float = -1.0):
    """A texture-mapped Lambertian plane (checkerboard) at height ``z``."""
    import mitsuba as mi

    return {
        "type": "rectangle",
        "to_world": mi.ScalarTransform4f().translate([0, 0, z]) @ mi.ScalarTransform4f().scale(size),
        "bsdf": {"type": "diffuse", "reflectance": {
            "type": "checkerboard", "color0": {"type": "rgb", "value": list(colors[0])},
            "color1": {"type": "rgb", "value": list(colors[1])},
            "to_uv": mi.ScalarTransform4f().scale([scale, scale, 1])}},
    }


#: Radius of the spherical lamps that stand in for point lights (scene units; at the
#: studio's distances of 7-9 units, 4-8 degrees across).
LAMP_RADIUS = 1.0


def lamp(position, intensity, radius: float = LAMP_RADIUS, spectrum: str = "rgb") -> dict:
    """A spherical area light of ``radius`` at ``position`` with the intensity (W/sr,
    seen from afar) of a point light of ``intensity``: radiance ``intensity / (pi r^2)``.

    It replaces a point light in the renders: a point light's highlight on a sharp
    lobe (n = 10^4) is smaller than a pixel, and the light reaching a diffuse surface
    through a sharp lobe (a caustic) can only be found by next-event estimation at
    the glossy vertex, with weights of 10^2-10^3: the isolated hot pixels ("fireflies",
    :func:`hot_pixels`) of the earlier renders (75 in ``as-gold``, max 289).  A lamp
    of finite size is hit by BSDF sampling, which multiple importance sampling then
    weights: unbiased, and no firefly."""
    value = float(intensity) / (math.pi * radius * radius)
    return {"type": "sphere", "center": [float(x) for x in position], "radius": float(radius),
            "emitter": {"type": "area", "radiance": {"type": spectrum, "value": value}}}


#: The studio's sun: the point light it stands for (position, intensity).
STUDIO_SUN = ((4.0, -3.0, 7.0), 90.0)


def studio_lights(sky: float = 0.35, sun=STUDIO_SUN, area=True, sun_distance: float = 3.0,
                  softbox_distance: float = 1.0):
    """Sky (constant environment) + a spherical lamp "sun" + optionally a rectangular
    area light.  The sun gives the irradiance at the origin of a point light of
    intensity ``sun[1]`` at ``sun[0]``, from ``sun_distance`` times as far in the same
    direction (out of the cameras' view), ``sun_distance`` times as large
    (:func:`lamp`, angular radius ``LAMP_RADIUS / |sun[0]|``).  ``softbox_distance``
    moves the area light as far again and scales it as much: the same solid angle and
    irradiance at the origin, out of the view of a distant camera (the sphere grid's
    saw its unlit back, 92 black pixels in the top-left corner)."""
    import mitsuba as mi

    k = float(sun_distance)
    d = {"sky": {"type": "constant", "radiance": {"type": "rgb", "value": sky}},
         "sun": lamp([k * x for x in sun[0]], k * k * sun[1], radius=k * LAMP_RADIUS)}
    if area:
        d["softbox"] = {"type": "rectangle",
                        "to_world": mi.ScalarTransform4f().look_at(origin=[-6.0 * softbox_distance,
                                                                           -2.0 * softbox_distance,
                                                                           9.0 * softbox_distance],
                                                                   target=[0, 0, 0], up=[0, 0, 1])
                        @ mi.ScalarTransform4f().scale(3.0 * softbox_distance),
                        "emitter": {"type": "area", "radiance": {"type": "rgb", "value": 1.5}}}
    return d


def grid_layout(n: int, cols: int = 4, spacing: float = 2.4, camera_elev: float = 55.0) -> tuple:
    """The sphere grid's geometry: the centres of ``n`` unit spheres, ``cols`` per row
    (row-major, the first row at the back), and the camera's origin (looking at the
    origin, up = z, ``GRID_FOV`` degrees across)."""
    rows = math.ceil(n / cols)
    centres = [((c - (cols - 1) / 2) * spacing, ((rows - 1) / 2 - r) * spacing, 0.0)
               for r, c in (divmod(i, cols) for i in range(n))]
    el, dist = math.radians(camera_elev), 2.2 * max(cols, rows) * spacing
    return centres, (0.0, -dist * math.cos(el), dist * math.sin(el))


GRID_FOV = 32.0


def sphere_grid(mi, bsdfs: list, res: int, spp: int, cols: int = 4, spacing: float = 2.4, plane=True,
                lights=None, camera_elev: float = 55.0, crop=None):
    """Spheres of radius 1 on a plane, ``cols`` per row (row-major ``bsdfs``),
    seen from above at ``camera_elev`` degrees (:func:`grid_layout`); ``crop = (y0, x0,
    h, w)`` renders only that window of the film."""
    centres, origin = grid_layout(len(bsdfs), cols, spacing, camera_elev)
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": 6}}
    for i, (b, ctr) in enumerate(zip(bsdfs, centres)):
        d[f"sphere{i}"] = {"type": "sphere", "center": list(ctr), "radius": 1.0, "bsdf": b}
    if plane:
        d["plane"] = checker_plane()
    d.update(lights or studio_lights(softbox_distance=3.0))
    d["sensor"] = perspective(mi, origin=list(origin), target=[0, 0, 0], res=res, spp=spp, fov=GRID_FOV,
                              up=[0, 0, 1], crop=crop)
    return mi.load_dict(d)


def project(points, origin, target, res: int, fov: float, up=(0, 0, 1)) -> np.ndarray:
    """Pixel coordinates ``(x, y)`` (x to the right, y down, pixel centres at +0.5) of
    world ``points`` in the square ``res`` image of :func:`perspective`'s camera (``fov``
    degrees across, looking from ``origin`` at ``target``), and the pixels per scene unit
    at each point's depth: ``(N, 3)`` columns x, y, scale."""
    o = np.asarray(origin, dtype=np.float64)
    fwd = np.asarray(target, dtype=np.float64) - o
    fwd /= np.linalg.norm(fwd)
    right = np.cross(fwd, np.asarray(up, dtype=np.float64))
    right /= np.linalg.norm(right)
    cam_up = np.cross(right, fwd)
    p = np.atleast_2d(np.asarray(points, dtype=np.float64)) - o
    z = p @ fwd
    f = res / 2.0 / math.tan(math.radians(fov) / 2.0)
    return np.stack([res / 2.0 + f * (p @ right) / z, res / 2.0 - f * (p @ cam_up) / z, f / z], axis=-1)


def render(mi, scene, seed: int = 0, spp: int | None = None) -> np.ndarray:
    """Render ``scene`` -> float64 array (H, W, C); the seed fixes the result."""
    img = mi.render(scene, seed=seed, spp=spp or 0)
    return np.array(img, dtype=np.float64)


# -- output -----------------------------------------------------------------------

def tonemap(img: np.ndarray, exposure: float = 1.0) -> np.ndarray:
    """Linear radiance -> 8-bit sRGB (clipped at 1 after ``exposure``)."""
    x = np.clip(np.nan_to_num(np.asarray(img, dtype=np.float64) * exposure, nan=0.0), 0.0, 1.0)
    s = np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)
    return np.round(s * 255).astype(np.uint8)


@contextmanager
def _pool_of_two():
    """At least two Dr.Jit worker threads within the block: Mitsuba 3.9's OpenEXR writer waits
    forever with one (``plausible figures`` gives each of its worker processes one thread per
    core it shares, :func:`plausible.figures.report.worker_threads`)."""
    import drjit as dr

    n = dr.thread_count()
    if n >= 2:
        yield
        return
    dr.set_thread_count(2)
    try:
        yield
    finally:
        dr.set_thread_count(n)


def write_image(path_stem: Path, img: np.ndarray, exposure: float = 1.0) -> list:
    """Write ``stem.exr`` (linear float32) and ``stem.png`` (sRGB); returns both paths."""
    import mitsuba as mi
    from matplotlib.image import imsave

    path_stem = Path(path_stem)
    img = np.asarray(img, dtype=np.float32)
    if img.ndim == 2:
        img = img[..., None].repeat(3, axis=-1)
    exr = path_stem.with_suffix(".exr")
    with _pool_of_two():
        mi.Bitmap(np.ascontiguousarray(img[..., :3]), pixel_format=mi.Bitmap.PixelFormat.RGB).write(str(exr))
    png = path_stem.with_suffix(".png")
    imsave(png, tonemap(img[..., :3], exposure))
    return [exr, png]


def grid_figure(imgs, rows: int, cols: int, labels, row_labels=(), col_labels=(), exposure: float = 1.0,
                title: str = ""):
    """A matplotlib figure showing tone-mapped ``imgs`` (row-major) with a label under each.

    One axes holds every image (each in its own 2.3 x 2.6 inch cell, scaled to fit
    2.2 x 2.05 inches): a hundred subplots (the atlas) cost about 5 CPU-s of axes set-up
    and drawing, one axes with a hundred images a fraction of that."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cw, ch = 2.3, 2.6                       # a cell, inches (the axes' data units)
    left = 0.35 if row_labels else 0.0
    top = (0.45 if title else 0.0) + (0.3 if col_labels else 0.0)
    width, height = left + cw * cols, top + ch * rows
    fig = plt.figure(figsize=(width, height))
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0))
    ax.set_xlim(0.0, width)
    ax.set_ylim(height, 0.0)
    ax.set_axis_off()
    for i, img in enumerate(imgs[:rows * cols]):
        r, c = divmod(i, cols)
        h, w = np.shape(img)[:2]
        s = min(2.2 / w, 2.05 / h)
        x0 = left + c * cw + 0.5 * (cw - w * s)
        y0 = top + r * ch + 0.05
        ax.imshow(tonemap(img, exposure), extent=(x0, x0 + w * s, y0 + h * s, y0), interpolation="nearest")
        ax.add_patch(plt.Rectangle((x0, y0), w * s, h * s, fill=False, linewidth=0.6, edgecolor="0.6"))
        ax.text(left + (c + 0.5) * cw, y0 + h * s + 0.06, labels[i], ha="center", va="top", fontsize=7)
    for r, t in enumerate(row_labels):
        ax.text(0.5 * left, top + (r + 0.45) * ch, t, ha="center", va="center", rotation=90, fontsize=9)
    for c, t in enumerate(col_labels):
        ax.text(left + (c + 0.5) * cw, top - 0.15, t, ha="center", va="bottom", fontsize=9)
    if title:
        ax.text(0.5 * width, 0.1, title, ha="center", va="top", fontsize=10)
    ax.set_aspect("equal")
    return fig


def mosaic(imgs, rows: int, cols: int) -> np.ndarray:
    """Stitch equally sized images (row-major) into one array."""
    h, w, c = imgs[0].shape
    out = np.zeros((rows * h, cols * w, c))
    for i, im in enumerate(imgs):
        r, q = divmod(i, cols)
        out[r * h:(r + 1) * h, q * w:(q + 1) * w] = im
    return out


#: An isolated hot pixel (a firefly): luminance above ``HOT_FACTOR`` x the median of
#: its 3x3 neighbourhood + ``HOT_OFFSET``.
HOT_FACTOR, HOT_OFFSET = 4.0, 0.5


def median3(img: np.ndarray) -> np.ndarray:
    """The median luminance of each pixel's 3x3 neighbourhood (itself included; edges replicated)."""
    y = luminance(img)
    p = np.pad(y, 1, mode="edge")
    h, w = y.shape
    return np.median(np.stack([p[i:i + h, j:j + w] for i in range(3) for j in range(3)]), axis=0)


def hot_pixels(img: np.ndarray, factor: float = HOT_FACTOR, offset: float = HOT_OFFSET,
               isolated: bool = True) -> np.ndarray:
    """Mask of the hot pixels of ``img``: luminance ``> factor * median + offset``,
    the median over the pixel's 3x3 neighbourhood (itself included; edges
    replicated).  With ``isolated`` (the default), only those with at most one of
    their 8 neighbours above the same threshold: a firefly (one pixel, or two
    touching), not the corner of a bright area (a light seen directly, whose corner
    pixel has three bright neighbours in its 3x3 and a dark median)."""
    y = luminance(img)
    p = np.pad(y, 1, mode="edge")
    h, w = y.shape
    stack = np.stack([p[i:i + h, j:j + w] for i in range(3) for j in range(3)])
    thresh = factor * np.median(stack, axis=0) + offset
    hot = y > thresh
    if not isolated:
        return hot
    above = (stack > thresh[None]).sum(axis=0) - hot   # neighbours above this pixel's threshold
    return hot & (above <= 1)


#: An outlier of a render's noise: its two half-sample renders differ by more than ``OUTLIER_SIGMAS`` robust
#: standard deviations of the difference over its ``OUTLIER_WINDOW`` x ``OUTLIER_WINDOW`` neighbourhood.
OUTLIER_SIGMAS, OUTLIER_WINDOW = 5.0, 15


def noise_outliers(a: np.ndarray, b: np.ndarray, sigmas: float = OUTLIER_SIGMAS, window: int = OUTLIER_WINDOW) -> tuple:
    """Outliers of a render's noise, clustered or not, from two independent renders
    ``a`` and ``b`` of the same scene (each with half the samples: their mean is the
    image).  ``d`` = the difference of their luminances; a pixel is an outlier when
    ``|d - median|`` exceeds ``sigmas`` x the robust standard deviation (1.4826 x the
    median absolute deviation) of ``d`` over its ``window`` x ``window`` neighbourhood
    (+ 1e-3).  Gaussian noise has none (5 sigma: 6e-7 a pixel); a feature of the image
    is in both renders and cancels; a caustic's speckle or a sharp lobe's grain is the
    heavy tail of the estimator, in one render, and comes in clusters of 2 or more
    pixels (the renders' gaussian filter spreads a sample over neighbours) that the
    isolated-pixel test (:func:`hot_pixels`) cannot see.  Returns ``(isolated,
    clusters, pixels in clusters)``: 8-connected groups of one pixel, groups of two or
    more, and their pixels."""
    from scipy import ndimage

    d = luminance(a) - luminance(b)
    dev = np.abs(d - ndimage.median_filter(d, size=window, mode="nearest"))
    out = dev > sigmas * 1.4826 * ndimage.median_filter(dev, size=window, mode="nearest") + 1e-3
    labels, n = ndimage.label(out, structure=np.ones((3, 3)))
    sizes = np.bincount(labels.ravel(), minlength=n + 1)[1:]
    return int(np.sum(sizes == 1)), int(np.sum(sizes >= 2)), int(np.sum(sizes[sizes >= 2]))


def into_gamut(img: np.ndarray) -> tuple:
    """Linear sRGB with no negative channel: each pixel with one is mixed with the grey of
    its own luminance, as little as makes its lowest channel 0 (luminance kept, hue
    kept, saturation lowered to the gamut's edge); a pixel of luminance <= 0 becomes
    black.  A spectral render's colour outside the sRGB gamut (gold seen in gold, a
    product of two saturated reflectances) has a negative channel in linear sRGB; no
    reconstruction filter makes it (Mitsuba's gaussian is non-negative).  Returns the
    image and the number of pixels changed."""
    img = np.array(img, dtype=np.float64)
    y = luminance(img)[..., None]
    low = img[..., :3].min(axis=-1, keepdims=True)
    bad = low < 0.0
    t = np.where(bad & (y > 0.0), y / np.where(bad, y - low, 1.0), 1.0)
    img[..., :3] = np.where(bad & (y > 0.0), y + t * (img[..., :3] - y), np.where(bad, 0.0, img[..., :3]))
    return img, int(np.count_nonzero(bad))


def count_hot_pixels(img: np.ndarray, isolated: bool = True) -> int:
    """How many hot pixels :func:`hot_pixels` finds in ``img``."""
    return int(np.count_nonzero(hot_pixels(img, isolated=isolated)))


def radius_map(res: int, width: float) -> np.ndarray:
    """Distance from the image centre (in scene units) of each pixel centre of an
    orthographic ``res`` x ``res`` image covering ``[-width, width]``."""
    x = ((np.arange(res) + 0.5) / res * 2 - 1) * width
    return np.hypot(x[None, :], x[:, None])


def studio(mi, shapes: dict, sensor: dict, plane: bool = True, lights=None, max_depth: int = 6):
    """``shapes`` on the checker plane under :func:`studio_lights`."""
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth}, "sensor": sensor}
    d.update(shapes)
    if plane:
        d["plane"] = checker_plane()
    d.update(lights or studio_lights())
    return mi.load_dict(d)


def rgb(v):
    """A Mitsuba ``rgb`` texture dict from a float or a triple."""
    v = [float(v)] * 3 if np.ndim(v) == 0 else [float(x) for x in v]
    return {"type": "rgb", "value": v}
