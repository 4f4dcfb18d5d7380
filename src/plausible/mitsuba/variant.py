"""The one variant setter of plausible (its own module, which imports nothing of plausible's but
the array floor's device probe, :func:`plausible.arrays.backend.device_available`: the adapter of
Mitsuba BSDFs, :mod:`plausible.analysis.mitsuba_bsdf`, imports it without importing the plugins,
which import the adapter).

Which device renders: Mitsuba's ``cuda_ad_*`` variants run on an NVIDIA GPU, ``llvm_ad_*`` on
the CPU's cores, ``scalar_*`` one ray at a time.  :func:`preferred` picks the variant of a kind
(``rgb``, ``spectral``, ...) on the device asked for by ``$PLAUSIBLE_VARIANT`` (or
:func:`prefer`; the command line's ``--variant``): ``auto`` (the default) is CUDA where a GPU
and its driver are found and Mitsuba was built with CUDA variants, else LLVM, else scalar.
The same formulas run on every device (the plugins trace them with the variant's array types);
what differs is float32 arithmetic: on CUDA, Dr.Jit emits approximate division and square
root and lets the PTX assembler contract ``a * b + c`` into one rounding (docs/backends.md).
"""

from __future__ import annotations

import os

from ..arrays import backend as _backend

#: The variants :func:`ensure_variant` tries, in order, after :func:`preferred` (``rgb``),
#: when none is set.
VARIANTS = ("llvm_ad_rgb", "scalar_rgb")
#: The environment variable naming the device (or an RGB variant) to render with.
ENV = "PLAUSIBLE_VARIANT"
#: Devices in the order ``auto`` prefers them.
FAMILIES = ("cuda", "llvm", "scalar")


def _name(family: str, kind: str) -> str:
    return f"scalar_{kind}" if family == "scalar" else f"{family}_ad_{kind}"


def available() -> tuple:
    """The Mitsuba variants that can render on this machine: compiled into this Mitsuba and on
    a device that runs here (:func:`plausible.arrays.backend.device_available`: ``cuda_ad_*`` only
    with a GPU; ``scalar_*`` always), preferred device first."""
    try:
        import mitsuba as mi
    except ImportError:
        return ()
    built = set(mi.variants())
    order = {f: i for i, f in enumerate(FAMILIES)}
    fam = [(v, v.split("_")[0]) for v in built]
    return tuple(v for v, f in sorted(fam, key=lambda t: (order.get(t[1], 9), t[0]))
                 if f in order and (f == "scalar" or _backend.device_available(f)))


def prefer(request: str | None):
    """Set the device (``auto``, ``cuda``, ``llvm``, ``scalar``) or the RGB variant (e.g.
    ``cuda_ad_rgb``) that :func:`preferred` answers with, for this process and the processes it
    starts (``$PLAUSIBLE_VARIANT``); None restores ``auto``.  Checked at once (ValueError)."""
    if request is None or request == "auto":
        os.environ.pop(ENV, None)
        return
    family(request)        # raises where it cannot render here
    os.environ[ENV] = request


def family(request: str | None = None) -> str:
    """The device family (``cuda``, ``llvm`` or ``scalar``) of ``request`` (default
    ``$PLAUSIBLE_VARIANT``, else ``auto``); ValueError naming the choices where it cannot render."""
    req = (request if request is not None else os.environ.get(ENV, "") or "auto").strip()
    have = available()
    if req == "auto":
        for f in FAMILIES:
            if _name(f, "rgb") in have:
                return f
        raise ValueError("no Mitsuba variant can render here (is Mitsuba 3 installed? "
                         "pip install 'plausible[render]')")
    f = req.split("_")[0]
    if not is_name(req):
        raise ValueError(f"variant must be auto, cuda, llvm, scalar or a Mitsuba RGB variant name "
                         f"({', '.join(v for v in have if v.endswith('_rgb')) or 'none here'}); got {req!r}")
    if _name(f, "rgb") not in have:
        why = "no NVIDIA GPU or driver found" if f == "cuda" else "not built into this Mitsuba or its device does not run"
        raise ValueError(f"variant {req!r} cannot render on this machine ({why}); variants here: "
                         f"{', '.join(have) or 'none'}")
    return f


def is_name(request: str) -> bool:
    """``request`` names a device (``auto``, ``cuda``, ``llvm``, ``scalar``) or a Mitsuba variant, whether or
    not it renders here (no Mitsuba import: the command line checks ``$PLAUSIBLE_VARIANT`` with it)."""
    req = str(request).strip()
    f = req.split("_")[0]
    return req == "auto" or (f in FAMILIES and (req == f or req in _all_names()))


def _all_names() -> set:
    return {_name(f, k) for f in FAMILIES for k in ("rgb", "mono", "spectral", "mono_polarized",
                                                   "spectral_polarized")}


def preferred(kind: str = "rgb") -> str:
    """The Mitsuba variant of ``kind`` (``rgb``, ``spectral``, ``mono``, ...) on the device in
    force (:func:`family`): ``cuda_ad_rgb`` where a GPU is found, else ``llvm_ad_rgb``, ..."""
    return _name(family(), kind)


def ensure_variant():
    """Import Mitsuba and, when no variant is set, set :func:`preferred` (``rgb``; CUDA first
    where a GPU is found), else the first of :data:`VARIANTS` that loads; return ``mi``.  The
    one variant setter of plausible (the plugins and the adapter of Mitsuba BSDFs,
    :mod:`plausible.analysis.mitsuba_bsdf`); its error lists why each variant failed."""
    import mitsuba as mi

    if mi.variant() is not None:
        return mi
    reasons = []
    try:
        first = (preferred("rgb"),)
    except ValueError as err:
        first, reasons = (), [str(err)]
    for v in dict.fromkeys(first + VARIANTS):
        try:
            mi.set_variant(v)
            return mi
        except (ImportError, AttributeError, RuntimeError) as err:
            reasons.append(f"{v}: {type(err).__name__}: {err}")
    raise RuntimeError("plausible.mitsuba: no Mitsuba variant could be set (" + "; ".join(reasons) + ")")


__all__ = ["ENV", "FAMILIES", "VARIANTS", "available", "ensure_variant", "family", "prefer",
           "preferred"]
