"""Parameter sets used by ``plausible check --all`` and the registry-wide tests:
each model's defaults plus variants at the extremes its parameters declare."""

from __future__ import annotations

from .. import registry


def variants(name: str, max_variants: int = 4) -> list[dict]:
    """Parameter dicts: ``{}`` (defaults), then one parameter at a time set to
    each of its declared extremes (skipping combinations the model refuses)."""
    inf = registry.info(name)
    out = [{}]
    for p in inf.params:
        for v in p.extremes:
            if v != p.default:
                out.append({p.name: v})
    good = []
    for kw in out:
        try:
            inf.cls(**kw)
        except ValueError:
            continue
        good.append(kw)
    return good[:max_variants] if max_variants else good


def model_variants(name: str, max_variants: int = 4):
    inf = registry.info(name)
    return [inf.cls(**kw) for kw in variants(name, max_variants)]
