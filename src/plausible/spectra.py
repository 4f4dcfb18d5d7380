"""Spectral optical constants of metals and their reduction to linear sRGB.

Data (``plausible/data``):

* ``Au_nk.csv``, ``Ag_nk.csv``, ``Cu_nk.csv``, ``Al_nk.csv`` -- wavelength (nm),
  refractive index ``n`` and extinction coefficient ``k`` of gold, silver, copper
  and aluminium, 299-886 nm (55-56 samples, evenly spaced in photon energy).
  Copied unchanged from Mitsuba 3.9.1 (``data/ior/<X>.eta.spd``, ``<X>.k.spd``;
  BSD-3-Clause, (c) Wenzel Jakob), whose files state "data from
  www.luxpop.com database"; the same tables ship with pbrt as its metal spectra.
* ``cie1931_2deg_d65.csv`` -- CIE 1931 2-degree colour matching functions and the
  CIE standard illuminant D65, 360-830 nm at 5 nm (CIE 15:2004; the values are
  those of the CVRL 1 nm table at the 5 nm nodes, as compiled into Mitsuba 3).

Colour pipeline (:func:`spectrum_to_xyz`, :func:`xyz_to_linear_srgb`): a
reflectance spectrum ``R(lambda)`` under an illuminant ``S(lambda)`` (D65 by
default, or ``"E"`` equal energy) gives ``X = sum R S xbar / sum S ybar`` (and
likewise ``Y``, ``Z``) on the 5 nm grid, so the perfect reflector has ``Y = 1``;
XYZ goes to linear sRGB (ITU-R BT.709 primaries, D65 white) with the matrix
derived from the primaries' chromaticities (IEC 61966-2-1).  Under D65 the
perfect reflector maps to RGB (1, 1, 1) up to the tabulation (about 1e-4).
"""

from __future__ import annotations

import csv
from functools import lru_cache
from importlib import resources

import numpy as np

from . import fresnel
from .arrays.ops import NP

#: Metal names and the data file stem of each.
METALS = {"Au": "Au", "gold": "Au", "Ag": "Ag", "silver": "Ag",
          "Cu": "Cu", "copper": "Cu", "Al": "Al", "aluminium": "Al", "aluminum": "Al"}

#: sRGB / BT.709 primaries and the D65 white point as CIE xy chromaticities
#: (IEC 61966-2-1:1999; ITU-R BT.709-6).
SRGB_PRIMARIES_XY = ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06))
D65_WHITE_XY = (0.3127, 0.3290)


def _read_csv(name: str) -> dict[str, np.ndarray]:
    text = resources.files("plausible").joinpath("data", name).read_text()
    rows = [r for r in csv.reader(line for line in text.splitlines()
                                   if line.strip() and not line.startswith("#"))]
    header, body = rows[0], rows[1:]
    data = np.array(body, dtype=np.float64)
    return {h: data[:, i] for i, h in enumerate(header)}


@lru_cache(maxsize=None)
def _metal_table(stem: str):
    t = _read_csv(f"{stem}_nk.csv")
    return t["wavelength_nm"], t["n"], t["k"]


@lru_cache(maxsize=None)
def cie_table():
    """``(wavelength_nm, xbar, ybar, zbar, d65)`` arrays, 360-830 nm at 5 nm."""
    t = _read_csv("cie1931_2deg_d65.csv")
    return t["wavelength_nm"], t["xbar"], t["ybar"], t["zbar"], t["d65"]


def _stem(metal: str) -> str:
    try:
        return METALS[metal]
    except (KeyError, TypeError):
        raise ValueError(f"unknown metal {metal!r}; known: {', '.join(sorted(METALS))}") from None


def metal_nk(metal: str, wavelengths_nm):
    """``(n, k)`` of ``metal`` at ``wavelengths_nm`` (linear interpolation in wavelength).

    ValueError for an unknown metal or a wavelength outside the table.
    """
    wl, n, k = _metal_table(_stem(metal))
    w = np.asarray(wavelengths_nm, dtype=np.float64)
    if np.any(w < wl[0]) or np.any(w > wl[-1]):
        raise ValueError(f"wavelengths must lie in [{wl[0]:g}, {wl[-1]:g}] nm for {metal}")
    return np.interp(w, wl, n), np.interp(w, wl, k)


def metal_reflectance(metal: str, wavelengths_nm, cos_theta=1.0):
    """Unpolarised Fresnel reflectance of ``metal`` (in air) at ``wavelengths_nm``
    (:func:`plausible.fresnel.conductor`); ``cos_theta = 1`` is normal incidence."""
    n, k = metal_nk(metal, wavelengths_nm)
    return fresnel.conductor(NP, np.asarray(cos_theta, dtype=np.float64), n, k)


def _illuminant(name: str, d65):
    if name == "D65":
        return d65
    if name == "E":
        return np.ones_like(d65)
    raise ValueError(f"illuminant must be 'D65' or 'E', got {name!r}")


def spectrum_to_xyz(wavelengths_nm, values, illuminant: str = "D65"):
    """CIE XYZ of a reflectance spectrum ``values`` (last axis along ``wavelengths_nm``).

    The spectrum is linearly interpolated onto the 5 nm CIE grid (zero outside its
    range is not assumed: the grid is restricted to 360-830 nm and the spectrum
    must cover the part of it where it is sampled; outside, its end values are held).
    Normalised so that the perfect reflector has ``Y = 1``.
    """
    wl, xb, yb, zb, d65 = cie_table()
    s = _illuminant(illuminant, d65)
    v = np.asarray(values, dtype=np.float64)
    w = np.asarray(wavelengths_nm, dtype=np.float64)
    r = np.apply_along_axis(lambda a: np.interp(wl, w, a), -1, v) if v.ndim > 1 else np.interp(wl, w, v)
    norm = np.sum(s * yb)
    return np.stack([np.sum(r * s * c, axis=-1) / norm for c in (xb, yb, zb)], axis=-1)


@lru_cache(maxsize=None)
def _rgb_to_xyz_matrix():
    """RGB -> XYZ of the sRGB primaries with the D65 white mapped to Y = 1
    (the standard construction from chromaticities, e.g. CIE 15:2004 / SMPTE RP 177)."""
    def xyz(xy):
        x, y = xy
        return np.array([x / y, 1.0, (1.0 - x - y) / y])

    p = np.stack([xyz(c) for c in SRGB_PRIMARIES_XY], axis=1)
    scale = np.linalg.solve(p, xyz(D65_WHITE_XY))
    return p * scale


def srgb_to_linear(c):
    """The sRGB transfer function undone (IEC 61966-2-1), as Mitsuba's
    ``mi.math.srgb_to_linear``: ``c / 12.92`` up to 0.04045, else
    ``((c + 0.055) / 1.055)^2.4``."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.04045, c / 12.92, np.power((np.maximum(c, 0.04045) + 0.055) / 1.055, 2.4))


def linear_to_srgb(c):
    """The sRGB transfer function (IEC 61966-2-1), the inverse of :func:`srgb_to_linear`:
    ``12.92 c`` up to 0.0031308, else ``1.055 c^(1/2.4) - 0.055``."""
    c = np.asarray(c, dtype=np.float64)
    return np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(np.maximum(c, 0.0031308), 1.0 / 2.4) - 0.055)


def xyz_to_linear_srgb(xyz):
    """Linear sRGB (BT.709 primaries, D65 white) of XYZ values (last axis of size 3)."""
    m = np.linalg.inv(_rgb_to_xyz_matrix())
    return np.asarray(xyz, dtype=np.float64) @ m.T


def metal_rgb(metal: str, cos_theta=1.0, illuminant: str = "D65"):
    """Linear sRGB of the Fresnel reflectance of ``metal`` at ``cos_theta`` (default
    normal incidence) under ``illuminant`` (D65 default), over 360-830 nm.

    Below the table's first wavelength (299-302 nm, i.e. never here) and above its
    last (886 nm) the end values are held; 830 nm lies inside every table."""
    wl = cie_table()[0]
    lo, hi = _metal_table(_stem(metal))[0][[0, -1]]
    w = np.clip(wl, lo, hi)
    r = metal_reflectance(metal, w, cos_theta)
    return xyz_to_linear_srgb(spectrum_to_xyz(wl, r, illuminant))


#: Rec. 709 (sRGB) luminance of linear RGB: the Y row of :func:`_rgb_to_xyz_matrix`, rounded as
#: ITU-R BT.709-6 item 3.2 writes it.
LUMINANCE_WEIGHTS = (0.2126, 0.7152, 0.0722)


def luminance(img) -> np.ndarray:
    """Rec. 709 luminance of linear RGB (last axis; a single channel, or a 2-D array, is its own)."""
    img = np.asarray(img, dtype=np.float64)
    if img.ndim == 2:
        return img
    if img.shape[-1] == 1:
        return img[..., 0]
    return img[..., :3] @ np.array(LUMINANCE_WEIGHTS)
