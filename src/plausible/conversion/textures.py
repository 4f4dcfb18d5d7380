"""The texture files of a conversion's output, made where the target needs them (Pillow).

* **glTF** allows PNG and JPEG images only (glTF 2.0 specification, "Images": ``image/png``,
  ``image/jpeg``; the Khronos validator reports anything else as ``IMAGE_UNRECOGNIZED_FORMAT``, and
  three.js does not load it).  A ``map_Kd`` in another format (``.tga``, ``.bmp``, ``.tif``, ...)
  is written as PNG beside the output (``OUT.TEXTURE.png``) and referenced instead; a file that
  cannot be read is dropped from the material with a warning.
* **Mitsuba** has no texture that scales another, and MTL multiplies ``map_Kd`` by ``Kd``: the
  fitted slot's colour ``c`` times the texture is baked into a PNG beside the output
  (``OUT.MATERIAL.map_Kd.png``), in linear RGB -- each 8-bit texel sRGB-decoded, times ``c``,
  encoded again (Mitsuba decodes an 8-bit ``bitmap`` as sRGB, IEC 61966-2-1) -- so a texel ``T`` of
  the source, whose diffuse albedo is ``Kd T``, renders as ``c T``, ``c`` being what the fit gave for
  ``Kd``.  Where the texture cannot be read, it replaces the colour (the bitmap as the MTL names it)
  and a warning says so.
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import numpy as np

from ..spectra import linear_to_srgb, srgb_to_linear
from .mitsuba import set_entry

__all__ = ["GLTF_FORMATS", "GLTF_TEXTURE_SLOTS", "bake", "prepare", "to_png"]

#: The image suffixes a glTF file may reference (PNG and JPEG).
GLTF_FORMATS = (".png", ".jpg", ".jpeg")
#: The glTF material's texture that an MTL texture becomes in a ``.gltf`` output (a reference to
#: the file as the MTL names it; glTF multiplies ``baseColorTexture`` by ``baseColorFactor``, the
#: fitted colour, as MTL multiplies ``map_Kd`` by ``Kd``).
GLTF_TEXTURE_SLOTS = {"map_Kd": "baseColorTexture"}



def _file(c, name) -> Path:
    name = str(name).replace("\\", "/")
    return Path(name) if c.folder is None or Path(name).is_absolute() else Path(c.folder) / name


def _name_for(c, path: Path) -> str:
    """``path`` as a texture name of ``c`` (relative to its source's folder, as the source's are)."""
    if c.folder is None:
        return str(path.resolve())
    try:
        return Path(os.path.relpath(path.resolve(), c.folder)).as_posix()
    except ValueError:          # another drive (Windows)
        return str(path.resolve())


def _safe(text: str) -> str:
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", str(text)).strip("._") or "texture"


def _load(path: Path) -> np.ndarray:
    """The texels of an image as float RGB in [0, 1] (sRGB-encoded values), ValueError if unreadable."""
    from PIL import Image, UnidentifiedImageError

    try:
        with Image.open(path) as im:
            return np.asarray(im.convert("RGB"), dtype=np.float64) / 255.0
    except (OSError, UnidentifiedImageError) as e:
        raise ValueError(f"cannot read texture {str(path)!r}: {e}") from None


def _save(rgb: np.ndarray, path: Path) -> None:
    from PIL import Image

    from ..text import write_atomic

    buf = io.BytesIO()
    Image.fromarray(np.clip(np.round(rgb * 255.0), 0, 255).astype(np.uint8), "RGB").save(buf, "PNG")
    write_atomic(path, buf.getvalue())


def to_png(src: Path, dst: Path) -> Path:
    """The image ``src`` written as the PNG ``dst`` (RGB, 8 bits); ValueError if ``src`` cannot be read."""
    _save(_load(src), dst)
    return dst


def bake(src: Path, colour, dst: Path) -> Path:
    """The PNG ``dst`` of ``colour`` (linear RGB) times the texture ``src``, in linear RGB (module
    docstring); ValueError if ``src`` cannot be read."""
    lin = srgb_to_linear(_load(src)) * np.broadcast_to(np.asarray(colour, float), (3,))
    _save(linear_to_srgb(np.clip(lin, 0.0, 1.0)), dst)
    return dst


def prepare(conversion, out: Path, suffix: str) -> None:
    """Make the texture files the output ``out`` (of ``suffix``) of ``conversion`` needs, beside it,
    and point the materials at them (module docstring); a texture that cannot be made is a warning of
    its material."""
    out, made = Path(out), {}
    for c in conversion.items:
        if suffix == ".gltf":
            _gltf_images(c, out, made)
        elif c.bakes and isinstance(c.result, dict):
            _bakes(c, out)


def _gltf_images(c, out: Path, made: dict) -> None:
    """``c``'s textures glTF cannot hold written as PNG; ``made``: source file -> PNG of this output
    (a file shared by materials written once; two files of one name in different folders, two PNGs)."""
    for stmt in [s for s in GLTF_TEXTURE_SLOTS if s in c.textures]:
        name = c.textures[stmt]
        if Path(str(name)).suffix.lower() in GLTF_FORMATS:
            continue
        src = _file(c, name).resolve()
        stem = f"{out.stem}.{_safe(Path(str(name).replace(chr(92), '/')).stem)}"
        dst, k = out.parent / f"{stem}.png", 1
        while src not in made and dst in made.values():
            k += 1
            dst = out.parent / f"{stem}-{k}.png"
        try:
            if src not in made:
                made[src] = to_png(src, dst)
            dst = made[src]
        except ValueError as e:
            del c.textures[stmt]
            c.warnings.append(f"{stmt} {name}: glTF allows PNG and JPEG images only, and {e}: dropped")
            continue
        c.textures[stmt] = _name_for(c, dst)
        c.notes.append(f"{stmt} {name}: written as PNG ({dst.name}; glTF allows PNG and JPEG only)")


def _bakes(c, out: Path) -> None:
    root = c.result["bsdf"] if c.result.get("type") == "mask" else c.result
    for slot, (stmt, colour) in c.bakes.items():
        dst = out.parent / f"{out.stem}.{_safe(c.name)}.{stmt}.png"
        try:
            bake(_file(c, c.textures[stmt]), colour, dst)
        except ValueError as e:
            c.warnings.append(f"{stmt} x Kd not baked ({e}): the texture replaces the fitted colour "
                              f"{' '.join(f'{x:.4g}' for x in colour)} of {slot}")
            continue
        set_entry(root, slot, {"type": "bitmap", "filename": _name_for(c, dst)})
