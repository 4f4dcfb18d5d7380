"""The one variant setter of plausible (its own module, which imports nothing of plausible's:
the adapter of Mitsuba BSDFs, :mod:`plausible.analysis.mitsuba_bsdf`, imports it without
importing the plugins, which import the adapter)."""

from __future__ import annotations

#: The variants :func:`ensure_variant` tries, in order, when none is set.
VARIANTS = ("llvm_ad_rgb", "scalar_rgb")


def ensure_variant():
    """Import Mitsuba and, when no variant is set, set the first of :data:`VARIANTS`
    that loads; return ``mi``.  The one variant setter of plausible (the plugins
    and the adapter of Mitsuba BSDFs, :mod:`plausible.analysis.mitsuba_bsdf`);
    its error lists why each variant failed."""
    import mitsuba as mi

    if mi.variant() is not None:
        return mi
    reasons = []
    for v in VARIANTS:
        try:
            mi.set_variant(v)
            return mi
        except (ImportError, AttributeError, RuntimeError) as err:
            reasons.append(f"{v}: {type(err).__name__}: {err}")
    raise RuntimeError("plausible.mitsuba: no Mitsuba variant could be set (" + "; ".join(reasons) + ")")


__all__ = ["VARIANTS", "ensure_variant"]
