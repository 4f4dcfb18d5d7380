"""The exact text of a model: the one key of every integral remembered or cached.

Two models share a cached albedo table (:mod:`.cache`) or a remembered albedo
(:func:`plausible.integrals.albedo.remembering`) exactly when their texts are
equal, so the text must tell apart any two different parameter values.
``repr(model)`` does not: it prints 6 significant digits (``n=20`` and
``n=20.00004`` read one table before this key).
"""

from __future__ import annotations

import numpy as np

from ..bxdf import BxDF


def exact_text(model) -> str | None:
    """The exact text of ``model``, or None when it has none:

    * a model that names itself (``cache_key()``, e.g. a foreign BSDF held as a model);
    * a model of a registered class: its registry spec (floats by ``repr``,
      :meth:`plausible.bxdf.BxDF.spec`);
    * a sum: its parts and scales;
    * any other object with ``params`` (an unregistered subclass such as the
      published fits' ``CookTorranceWide``, whose ``spec()`` is its 6-digit repr):
      its class and every parameter at full precision;

    and None where a part or a parameter has no exact text."""
    key = getattr(model, "cache_key", None)
    if callable(key):
        return key()
    info = getattr(model, "info", None)
    if info is not None and info.cls is type(model):
        return model.spec()
    if hasattr(model, "parts") and hasattr(model, "scales"):
        parts = [exact_text(m) for m in model.parts]
        scales = [exact_value(s) for s in model.scales]
        if None in parts or None in scales:
            return None
        return "sum(" + ", ".join(f"[{p}]*{s}" for p, s in zip(parts, scales)) + ")"
    params = getattr(model, "params", None)
    if not callable(getattr(params, "items", None)):
        return None
    vals = {k: exact_value(v) for k, v in params.items()}
    if None in vals.values():
        return None
    return f"{type(model).__module__}.{type(model).__qualname__}(" + ", ".join(
        f"{k}={v}" for k, v in vals.items()) + ")"


def exact_value(v) -> str | None:
    """A parameter value as text that tells apart any two different values (None
    for a type it does not know)."""
    if v is None or isinstance(v, (bool, str)):
        return repr(v)
    if isinstance(v, (int, np.integer)):
        return repr(int(v))
    if isinstance(v, (float, np.floating)):
        return repr(float(v))
    if isinstance(v, np.ndarray) and v.dtype.kind in "biuf":
        return f"array{v.shape}" + repr(v.astype(np.float64).ravel().tolist())
    if isinstance(v, (tuple, list)):
        parts = [exact_value(x) for x in v]
        return None if None in parts else "(" + ", ".join(parts) + ")"
    if isinstance(v, BxDF):
        k = exact_text(v)
        return None if k is None else f"[{k}]"
    return None


__all__ = ["exact_text", "exact_value"]
