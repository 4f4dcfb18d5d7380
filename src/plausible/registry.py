"""The model registry: one entry per model, read by the CLI, the plugins and the tests."""

from __future__ import annotations

import importlib
import pkgutil

from .params import ModelInfo, provide_model_builder

_REGISTRY: dict[str, ModelInfo] = {}
_LOADED = False
#: Builds a sum from its parts, ``[(model, scale or None), ...]``: :class:`plausible.models.sum.Sum`,
#: given by that module as the registry loads it (:func:`provide_sum`; the registry imports no model).
_SUM_BUILDER: list = []


def provide_sum(build) -> None:
    """Give :func:`make_from_spec` the function that builds a sum of parts (``"a + b"``)."""
    _SUM_BUILDER[:] = [build]


def register(name: str, description: str, *, reciprocal: bool = True,
             energy_conserving: bool = True, references: tuple = (), catalogue: bool = False):
    """Class decorator: add a :class:`~plausible.bxdf.BxDF` subclass to the registry.

    ``reciprocal`` / ``energy_conserving`` state what the model *claims*; the
    registry-wide tests assert that :func:`plausible.check` agrees.
    ``catalogue``: an entry of a catalogue of data (``material``), which
    :func:`names` leaves out unless asked.  A class may read its own spec items
    (a classmethod ``from_spec_items(items, **params)``, see :func:`make_from_spec`).
    """

    def deco(cls):
        if name in _REGISTRY and _REGISTRY[name].cls is not cls:
            raise ValueError(f"model name {name!r} registered twice")
        info = ModelInfo(name=name, cls=cls, params=tuple(cls.PARAMS), description=description,
                         reciprocal=reciprocal, energy_conserving=energy_conserving,
                         references=tuple(references), catalogue=catalogue)
        cls.info = info
        _REGISTRY[name] = info
        return cls

    return deco


#: The packages whose modules register entries, imported by name on first use
#: (they import this module to register: the registry imports none of them).
ENTRY_PACKAGES = ("models", "catalogue")


def _load():
    global _LOADED
    if _LOADED:
        return
    for name in ENTRY_PACKAGES:
        pkg = importlib.import_module(f"{__package__}.{name}")
        for mod in pkgutil.iter_modules(pkg.__path__):
            importlib.import_module(f"{pkg.__name__}.{mod.name}")
    _LOADED = True


def names(catalogue: bool = False) -> list[str]:
    """Names of every registered model: plausible's own by module (alphabetical)
    and in the order each module defines them, then any others in registration
    order -- the same list whichever module happened to be imported first.
    ``catalogue``: the catalogue entries (``material``) too, last."""
    _load()
    seq = {n: i for i, n in enumerate(_REGISTRY)}

    def key(n):
        mod = _REGISTRY[n].cls.__module__
        own = mod.startswith("plausible.models.")
        return (not own, mod if own else "", seq[n])

    own = sorted((n for n in _REGISTRY if not _REGISTRY[n].catalogue), key=key)
    return own + sorted((n for n in _REGISTRY if _REGISTRY[n].catalogue), key=key) if catalogue else own


def info(name: str) -> ModelInfo:
    """The registry entry of ``name`` (ValueError listing the names if unknown)."""
    _load()
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        from .text import closest

        close = closest(str(name), _REGISTRY, n=3, cutoff=0.6)
        hint = f" (did you mean {' or '.join(close)}?)" if close else ""
        raise ValueError(f"unknown model {name!r}{hint}; registered models: "
                         f"{', '.join(sorted(_REGISTRY))}") from None


def make(name: str, /, **params):
    """Build the registered model ``name`` with ``params`` (defaults for the rest).
    ``name`` may be a spec, ``"ashikhmin-shirley:nu=10"``, ``"material:NAME@FIT"`` or a sum
    ``"a + b"`` (:func:`make_from_spec`; ``params`` then add to or override the spec's)."""
    if isinstance(name, str) and (":" in name or " + " in name):
        return make_from_spec(name, **params)
    return info(name).cls(**params)


def parse_assignments(items) -> dict:
    """``["n=20", "ks=0.9,0.6,0.2"]`` -> ``{"n": 20.0, "ks": [0.9, 0.6, 0.2]}``; a name
    given twice is refused (ValueError naming it)."""
    from .params import parse_value

    out = {}
    for it in items:
        if "=" not in it:
            raise ValueError(f"parameter assignment {it!r} must look like name=value")
        k, v = it.split("=", 1)
        if not k.strip():
            raise ValueError(f"parameter assignment {it!r} has no name before '=' (write name=value, "
                             f"e.g. n=20)")
        if k.strip() in out:    # nu=1:nu=2 took the last value silently
            raise ValueError(f"parameter '{k.strip()}' is given twice ({k.strip()}={out[k.strip()]!r} and "
                             f"{it.strip()}); give each parameter once")
        try:
            out[k.strip()] = parse_value(v)
        except ValueError as e:
            raise ValueError(f"parameter '{k.strip()}': {e}") from None
    return out


#: Deepest nesting of model specs in square brackets (``pumped-up:base=[pumped-up:base=[...]]``):
#: the work of building a nested pumped-up model grows with the cube of the depth (each
#: level tabulates the albedo of the one below), and Python's recursion ends at ~200.
MAX_SPEC_DEPTH = 4


def split_spec(spec: str) -> list[str]:
    """Split ``"name:k=v:k=[name2:k=v]"`` at the colons outside square brackets
    (a bracketed value is a nested spec, e.g. the base of ``pumped-up``); the
    brackets are removed.  At most :data:`MAX_SPEC_DEPTH` levels of brackets."""
    parts, depth, cur = [], 0, ""
    for ch in spec:
        if ch == "[":
            depth += 1
            if depth > MAX_SPEC_DEPTH:
                raise ValueError(f"model spec nests more than {MAX_SPEC_DEPTH} levels of '[...]' "
                                 f"(at most {MAX_SPEC_DEPTH} allowed): {spec[:80]!r}"
                                 + ("..." if len(spec) > 80 else ""))
            if depth == 1:
                continue
        elif ch == "]":
            depth -= 1
            if depth < 0:
                raise ValueError(f"unbalanced ']' in model spec {spec!r}")
            if depth == 0:
                continue
        if ch == ":" and depth == 0:
            parts.append(cur)
            cur = ""
        else:
            cur += ch
    if depth:
        raise ValueError(f"unbalanced '[' in model spec {spec!r}")
    parts.append(cur)
    return parts


def split_sum(spec: str) -> list[str]:
    """The terms of a sum spec ``"a + b + ..."``: split at ``" + "`` outside square brackets
    (a nested model may be a sum: ``pumped-up:base=[a + b]``); one term for a plain spec.

    >>> split_sum("lambertian:rd=0.5 + 0.25 * pumped-up:base=[lambertian + lambertian]")
    ['lambertian:rd=0.5', '0.25 * pumped-up:base=[lambertian + lambertian]']
    """
    terms, cur, depth, i = [], "", 0, 0
    while i < len(spec):
        ch = spec[i]
        depth += (ch == "[") - (ch == "]")
        if depth == 0 and spec.startswith(" + ", i):
            terms.append(cur.strip())
            cur, i = "", i + 3
            continue
        cur += ch
        i += 1
    return terms + [cur.strip()]


def _scaled_term(term: str):
    """``(spec, scale)`` of one term of a sum: ``"SCALE * spec"`` (``SCALE`` a number or ``r,g,b``,
    the part's scale of :class:`~plausible.models.sum.Sum`) or ``"spec"`` (scale None)."""
    head, star, rest = term.partition(" * ")
    if star and "[" not in head:
        try:
            scale = [float(x) for x in head.split(",")]
        except ValueError:
            raise ValueError(f"sum term {term!r}: the scale before ' * ' must be a number or r,g,b, "
                             f"got {head.strip()!r}") from None
        return rest.strip(), (scale[0] if len(scale) == 1 else scale)
    return term, None


def _make_sum(spec: str, terms: list, extra: dict):
    """The :class:`~plausible.models.sum.Sum` of the terms of ``spec`` (:func:`split_sum`)."""
    if extra:
        raise ValueError(f"model spec {spec!r} is a sum: give parameters inside its terms, not beside it "
                         f"(got {', '.join(sorted(extra))})")
    if any(not t for t in terms):
        raise ValueError(f"model spec {spec!r}: every term of a sum 'a + b' needs a model spec (an empty term)")
    parts = [_scaled_term(t) for t in terms]
    return _SUM_BUILDER[0]([(make_from_spec(s), k) for s, k in parts])


def spec_of(model) -> str:
    """The spec string of a model, ``"name:k=v:..."``, that :func:`make_from_spec`
    reads back into an equal model (:meth:`plausible.bxdf.BxDF.spec`); anything
    else gives its ``repr``.

    >>> spec_of(make("pumped-up"))
    'pumped-up:base=[reciprocal-phong:ks=1.0:n=20.0]:correction=max:times=1:fresnel=none:rs=1.0:eta=0.2:k=3.0'
    """
    spec = getattr(model, "spec", None)
    return spec() if callable(spec) else repr(model)


def is_spec(text: str) -> bool:
    """Whether ``text`` reads as the spec of a registered entry that takes its own
    spec items (``material:NAME@FIT``, whose fit key holds a '/', is not a path), or a sum
    ``"a + b"`` whose terms each name a registered entry."""
    terms = split_sum(text.strip())
    if len(terms) > 1:              # a sum: every term a registered entry's spec
        _load()
        try:
            return all(split_spec(_scaled_term(t)[0])[0].strip() in _REGISTRY for t in terms)
        except ValueError:
            return False
    try:
        name = split_spec(text.strip())[0].strip() if ":" in text else ""
    except ValueError:              # unbalanced brackets: not a spec
        return False
    _load()
    return hasattr(getattr(_REGISTRY.get(name), "cls", None), "from_spec_items")


def make_from_spec(spec: str, **extra):
    """Build a model from ``"name"`` or ``"name:k=v:k=v"`` (colours as ``r,g,b``;
    a nested model spec in square brackets, ``"pumped-up:base=[reciprocal-phong:n=20]"``).
    An entry whose class reads its own spec items (``from_spec_items``) gets them:
    a published fit of a real material, ``"material:NAME@FIT"``
    (:class:`plausible.catalogue.entry.Material`).  A sum ``"a + b"`` (terms :func:`split_sum`, each
    ``spec`` or ``SCALE * spec``) is the :class:`~plausible.models.sum.Sum` of its terms, what
    :meth:`~plausible.models.sum.Sum.spec` writes."""
    _load()
    terms = split_sum(spec)
    if len(terms) > 1:
        return _make_sum(spec, terms, extra)
    name, *assign = split_spec(spec)
    reader = getattr(getattr(_REGISTRY.get(name.strip()), "cls", None), "from_spec_items", None)
    if reader is not None:
        return reader([a.strip() for a in assign], **extra)
    params = parse_assignments(assign)
    params.update(extra)
    try:
        return info(name.strip()).cls(**params)
    except ValueError as e:
        hint = "" if "[" in spec else _bracket_hint(name.strip(), assign)
        if hint:
            raise ValueError(f"{e}. A nested model's parameters go in square brackets: {hint!r}") from None
        raise


def _bracket_hint(name: str, assign: list) -> str:
    """The spec with brackets where a model-valued parameter (pumped-up's
    ``base``) is followed by parameters the outer model does not have:
    ``pumped-up:base=reciprocal-phong:ks=1:n=20`` -> ``pumped-up:base=[reciprocal-phong:ks=1:n=20]``
    ("" when there is no such parameter)."""
    try:
        inf = info(name)
    except ValueError:
        return ""
    own = {p.name for p in inf.params}
    nested_kind = {p.name for p in inf.params if p.nests_model}
    keys = [a.split("=", 1)[0].strip() for a in assign]
    for i, k in enumerate(keys):
        if k in nested_kind:
            j = i + 1
            while j < len(keys) and keys[j] not in own:
                j += 1
            if j > i + 1:
                inner = ":".join([assign[i].split("=", 1)[1]] + assign[i + 1:j])
                return ":".join([name, *assign[:i], f"{k}=[{inner}]", *assign[j:]])
    return ""


provide_model_builder(make_from_spec)
