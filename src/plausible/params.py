"""Parameter specifications and validation.

Every model declares its parameters as :class:`Param` objects; the registry, the
command line (``plausible models``), the Mitsuba plugins and the tests read them.
"""

from __future__ import annotations

import math
import numbers
import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np


@dataclass(frozen=True)
class Param:
    """One model parameter.

    ``kind`` is ``"scalar"`` (a float), ``"color"`` (a float or a trailing
    channel array, e.g. RGB) or ``"choice"`` (one of ``choices``).  ``lo`` and
    ``hi`` bound the value (inclusive); ``extremes`` lists values that the
    ``--all`` checks and the tests try besides the default.
    """

    name: str
    default: Any
    lo: float = -math.inf
    hi: float = math.inf
    kind: str = "scalar"
    doc: str = ""
    extremes: tuple = ()
    choices: tuple = ()
    integer: bool = False

    def range_text(self) -> str:
        if self.kind == "choice":
            return "{" + ", ".join(map(str, self.choices)) + "}"
        lo = "-inf" if self.lo == -math.inf else f"{self.lo:g}"
        hi = "inf" if self.hi == math.inf else f"{self.hi:g}"
        return f"[{lo}, {hi}]"

    def options(self) -> list:
        """The values a choice may take, for menus (:attr:`choices`)."""
        return list(self.choices)

    # -- the kind's conversions (a kind with other values overrides them) ------------
    def parse(self, text: str):
        """The value of the command line's or the explorer's text: a choice as
        written, anything else by :func:`parse_value` (``0.5``, ``r,g,b``, groups)."""
        return text if self.kind == "choice" else parse_value(text.strip())

    def spec_text(self, value) -> str:
        """The value in a model spec (:func:`spec_value`; read back by :meth:`parse`)."""
        return spec_value(value)

    def to_json(self, value):
        """The value as plain JSON (the explorer's sliders and menus): a colour as a
        list, groups of numbers as their ``a,b;c,d;`` text, a number or a string as is."""
        if isinstance(value, np.ndarray):
            return value.tolist()
        if isinstance(value, (list, tuple)):
            if value and isinstance(value[0], (list, tuple)):
                return ";".join(",".join(f"{float(x):g}" for x in g) for g in value) + ";"
            return [float(x) for x in value]
        return value

    def to_mitsuba(self, value):
        """The value in a Mitsuba scene dict (:mod:`plausible.mitsuba.scene_dict`):
        a colour as a float or ``{"type": "rgb", "value": [r, g, b]}``, groups as
        :func:`format_groups` text, a number as a float, a choice as its string."""
        if self.kind == "color":
            arr = np.atleast_1d(np.asarray(value, dtype=np.float64))
            if arr.size == 1:
                return float(arr[0])
            return {"type": "rgb", "value": [float(x) for x in arr]}
        if isinstance(value, (list, tuple)):
            return format_groups(value)
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            return float(value)
        return value

    @property
    def is_color(self) -> bool:
        """A colour: a float or a trailing channel array (a texture in Mitsuba, ``vec3`` in GLSL)."""
        return self.kind == "color"

    @property
    def numeric(self) -> bool:
        """A number or a colour: continuous (unless :attr:`integer`), free in a fit, and
        in Mitsuba a number or a texture (read by :mod:`plausible.mitsuba.props`; any other
        kind's property is read by :meth:`from_mitsuba`)."""
        return self.kind in ("scalar", "color")

    @property
    def nests_model(self) -> bool:
        """A nested model (:class:`ModelParam`), written ``name=[spec]`` in a spec."""
        return False

    # -- Mitsuba: the plugins' properties and ``mi.traverse`` (plausible.mitsuba builds the arrays) --

    def from_mitsuba(self, raw, owner: str = "model"):
        """The value of a Mitsuba property given as a string or a sequence, validated."""
        return self.validate(raw, owner)

    def traversal(self, value):
        """How the value appears in ``mi.traverse``: ``(numbers, integer, differentiable)``,
        or None where it does not (a choice without a fixed list, such as a material
        name: a string).  A choice is its index in :attr:`choices`."""
        if self.kind == "choice":
            return (self.choices.index(value), True, False) if self.choices else None
        if self.integer:
            return int(value), True, False
        return float(value), False, True

    def from_traversal(self, a, template):
        """The value of a traversed array ``a`` (float64, flat; inverse of :meth:`traversal`).
        ``template``: the value before, returned as given when ``a`` holds its float32 rounding."""
        if self.kind == "choice":
            i = int(a[0]) if a.size == 1 else -1
            if not 0 <= i < len(self.choices):
                raise ValueError(f"parameter '{self.name}' must be an index in [0, {len(self.choices) - 1}] "
                                 f"of {self.range_text()}, got {a.tolist()}")
            return self.choices[i]
        if a.size != 1:
            raise ValueError(f"parameter '{self.name}' must be one number, got {a.size} values")
        if template is not None and np.float32(template) == np.float32(a[0]):
            return template  # unchanged: the value as given, not its float32 rounding
        return int(a[0]) if self.integer else float(a[0])

    def validate(self, value, owner: str = "model", channels: tuple = None):
        """Return the value converted (float, or float64 array for colours).

        ``channels``: the channel counts a colour may have (default
        :data:`COLOR_CHANNELS`; a spectral model passes its own, ``BxDF.CHANNELS``).
        Raises :class:`ValueError` naming the parameter and its allowed range.
        """
        where = f"{owner}: parameter '{self.name}'"
        if self.kind == "choice":
            if value not in self.choices:
                raise ValueError(f"{where} must be one of {self.range_text()}, got {value!r}")
            return value
        if isinstance(value, (bool, np.bool_)) or (isinstance(value, (list, tuple)) and
                                                   any(isinstance(x, (bool, np.bool_)) for x in value)):
            raise ValueError(f"{where} must be a number in {self.range_text()}, got {value!r} "
                             f"(a boolean is not a number)")
        if self.kind == "color":
            try:
                arr = np.asarray(value, dtype=np.float64)
            except (TypeError, ValueError):
                raise ValueError(f"{where} must be a number or a list of numbers in "
                                 f"{self.range_text()}, got {value!r}") from None
            if arr.ndim > 1 or arr.size == 0:
                raise ValueError(f"{where} must be a scalar or a 1-D channel array "
                                 f"(e.g. RGB), got shape {arr.shape}")
            channels = COLOR_CHANNELS if channels is None else channels
            if arr.ndim == 1 and arr.size not in channels:
                raise ValueError(f"{where} must have {' or '.join(map(str, channels))} channels "
                                 f"(a number is grey, 3 values RGB), got {arr.size} channels: {value!r}")
            if not np.all(np.isfinite(arr)) or np.any(arr < self.lo) or np.any(arr > self.hi):
                raise ValueError(f"{where} must lie in {self.range_text()}, got {value!r}")
            arr = arr + 0.0     # -0 is 0 (printed so, in the model's repr and spec)
            return float(arr) if arr.ndim == 0 else arr
        try:
            x = float(value)
        except (TypeError, ValueError):
            raise ValueError(f"{where} must be a number in {self.range_text()}, "
                             f"got {value!r}") from None
        if not math.isfinite(x) or x < self.lo or x > self.hi:
            raise ValueError(f"{where} must lie in {self.range_text()}, got {value!r}")
        if self.integer:
            if x != int(x):
                raise ValueError(f"{where} must be an integer in {self.range_text()}, got {value!r}")
            return int(x)
        return x + 0.0      # -0 is 0 (printed so, in the model's repr and spec)


#: Channel counts a colour parameter may have (grey, RGB).
COLOR_CHANNELS = (1, 3)

#: Largest lobe exponent accepted (the same range as the Phong family's ``n``).
N_MAX = 1e6

#: How the lobes are written on the command line (shown by every error of :class:`LobesParam`).
FORMS = ("on the command line -p lobes=cx,cy,cz,n,rho (one lobe), "
         "-p 'lobes=cx,cy,cz,n,rho;cx,cy,cz,n,rho' or -p 'lobes=(cx, cy, cz, n, rho), (cx, cy, cz, n, rho)', "
         "e.g. -p lobes=-1,-1,1,20,1.75")


@dataclass(frozen=True)
class LobesParam(Param):
    """A list of Lafortune lobes ``(cx, cy, cz, n, rho)`` (``kind="lobes"``).

    ``cx, cy, cz`` finite, ``n`` in ``[0, 1e6]``, ``rho >= 0``.  Validated into a
    tuple of 5-tuples of floats; any other input raises :class:`ValueError`
    naming the parameter and these ranges.
    """

    kind: str = "lobes"

    def range_text(self) -> str:
        return (f"a list of (cx, cy, cz, n, rho) tuples with cx, cy, cz finite, "
                f"n in [0, {N_MAX:g}] and rho in [0, inf)")

    def validate(self, value, owner: str = "model"):
        where = f"{owner}: parameter '{self.name}'"
        rng = self.range_text() + "; " + FORMS
        if isinstance(value, str):
            try:    # the command line's forms (plausible.params.parse_groups)
                value = parse_groups(value)
            except ValueError:
                raise ValueError(f"{where} must be {rng}, got {value!r}") from None
        if isinstance(value, bytes) or np.ndim(value) == 0 and not isinstance(value, (list, tuple)):
            raise ValueError(f"{where} must be {rng}, got {value!r}")
        try:
            items = list(value)
        except TypeError:
            raise ValueError(f"{where} must be {rng}, got {value!r}") from None
        if items and all(isinstance(x, numbers.Real) for x in items):
            if len(items) != 5:
                raise ValueError(f"{where}: one lobe is 5 numbers (cx, cy, cz, n, rho), got {len(items)} "
                                 f"numbers {value!r}; {rng}")
            items = [items]     # one lobe given as its five numbers (-p lobes=-1,-1,1,20,1.75)
        out = []
        for i, lobe in enumerate(items):
            try:
                vals = [float(x) for x in lobe]
            except (TypeError, ValueError):
                raise ValueError(f"{where}: lobe {i} must be a tuple of 5 numbers "
                                 f"(cx, cy, cz, n, rho); {rng}; got {lobe!r}") from None
            if len(vals) != 5:
                raise ValueError(f"{where}: lobe {i} must have 5 entries (cx, cy, cz, n, rho), "
                                 f"got {len(vals)}; {rng}")
            cx, cy, cz, n, rho = vals
            if not all(math.isfinite(x) for x in vals):
                raise ValueError(f"{where}: lobe {i} has a NaN or infinite entry; {rng}; got {lobe!r}")
            if not 0.0 <= n <= N_MAX:
                raise ValueError(f"{where}: lobe {i} exponent n must lie in [0, {N_MAX:g}], got {n:g}")
            if rho < 0.0:
                raise ValueError(f"{where}: lobe {i} rho must lie in [0, inf), got {rho:g}")
            out.append((cx, cy, cz, n, rho))
        return tuple(out)

    @property
    def numeric(self) -> bool:
        return False

    def from_mitsuba(self, raw, owner: str = "model"):
        """A string of ``;``-separated groups (:func:`parse_groups`) or a sequence, validated."""
        return self.validate(parse_groups(raw) if isinstance(raw, str) else raw, owner)

    def traversal(self, value):
        """The numbers row by row, not differentiable."""
        return np.asarray(value, dtype=np.float64).ravel(), False, False

    def from_traversal(self, a, template):
        shape = np.shape(template)
        if a.size != int(np.prod(shape)):
            raise ValueError(f"parameter '{self.name}' must keep its {int(np.prod(shape))} numbers "
                             f"(shape {shape}), got {a.size}")
        return [tuple(r) for r in a.reshape(shape)]


def _is_model(v) -> bool:
    """A model instance (a :class:`~plausible.bxdf.BxDF`; params lies below the contract)."""
    return hasattr(v, "spec") and hasattr(v, "eval")


#: Builds a model from its registry spec: :func:`plausible.registry.make_from_spec`, given by the
#: registry as it loads (:func:`provide_model_builder`; the registry imports params, so params
#: does not import it, not even inside a function).
_MODEL_BUILDER = []


def provide_model_builder(make) -> None:
    """Give :class:`ModelParam` the function that builds a model from its spec."""
    _MODEL_BUILDER[:] = [make]


def _build_model(spec: str):
    if not _MODEL_BUILDER:
        raise RuntimeError("no model registry loaded (import plausible first)")
    return _MODEL_BUILDER[0](spec)


@dataclass(frozen=True)
class ModelParam(Param):
    """A model given by registry spec (``"reciprocal-phong:n=20:ks=1"``) or as a
    :class:`~plausible.bxdf.BxDF` instance (``kind="model"``).  ``needs``: why the
    owner refuses a base the registry marks as not reciprocal (in its error)."""

    kind: str = "model"
    needs: str = ("pumping-up needs a symmetric BRDF f(L, V) = f(V, L) (its energy proof, eq. 18, "
                  "uses the symmetry)")

    def range_text(self) -> str:
        return "a registered model spec 'name:k=v:...' or a BxDF instance"

    def parse(self, text: str):
        """A spec, with or without its square brackets (``[name:k=v]``)."""
        text = text.strip()
        return text[1:-1] if text.startswith("[") and text.endswith("]") else text

    def to_json(self, value):
        return "[" + value.spec() + "]" if _is_model(value) else value

    def to_mitsuba(self, value):
        return value.spec() if _is_model(value) else value

    def validate(self, value, owner: str = "model"):
        where = f"{owner}: parameter '{self.name}'"
        if _is_model(value):
            model = value
        elif isinstance(value, str):
            try:
                model = _build_model(value)
            except ValueError as e:
                raise ValueError(f"{where}: {e}") from None
        else:
            raise ValueError(f"{where} must be {self.range_text()}, got {value!r}")
        if model.info is not None and not model.info.reciprocal:
            raise ValueError(f"{where}: the base model {model.name!r} is not reciprocal; {self.needs}. "
                             f"Use a reciprocal model, e.g. 'reciprocal-phong'.")
        return model

    @property
    def numeric(self) -> bool:
        return False

    @property
    def nests_model(self) -> bool:
        return True

    def from_mitsuba(self, raw, owner: str = "model"):
        """The spec as given (the model validates it)."""
        return raw

    def traversal(self, value):
        return None     # a nested model spec: a string


@dataclass(frozen=True)
class ModelInfo:
    """A registry entry: everything the CLI, the plugins and the tests need."""

    name: str
    cls: type
    params: tuple
    description: str
    reciprocal: bool = True
    energy_conserving: bool = True
    references: tuple = field(default_factory=tuple)
    #: An entry of a catalogue of data (published materials), not a model family:
    #: not in :func:`plausible.names`, known to :func:`plausible.info` and ``make``.
    catalogue: bool = False

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)


def parse_groups(text: str) -> list:
    """Parse groups of numbers: groups separated by ``;``, numbers within a group
    by commas or spaces (the one parser of structured values, used by the command
    line through :func:`parse_value` and by the Mitsuba plugins' string properties).

    ``"-1 -1 1 20 1.75; 1,1,1,5,0.1"`` -> ``[[-1.0, -1.0, 1.0, 20.0, 1.75], [1.0, 1.0, 1.0, 5.0, 0.1]]``;
    the tuple form ``"(-1, -1, 1, 20, 1.75), (1, 1, 1, 5, 0.1)"`` gives the same.
    A word raises :class:`ValueError` naming the group and the text given.
    """
    groups = _parenthesised(text) if "(" in text or ")" in text else text.split(";")
    out = []
    for g in groups:
        if not g.strip():
            continue
        try:
            out.append([float(x) for x in g.replace(",", " ").split()])
        except ValueError:
            raise ValueError(f"groups of numbers separated by ';' (numbers by commas or spaces) "
                             f"expected, got {g.strip()!r} in {text!r}") from None
    return out


def _parenthesised(text: str) -> list:
    """The groups of ``"(a, b), (c, d)"`` or ``"[(a, b), (c, d)]"`` (the form Python
    and ``plausible models`` print a tuple of tuples in); between the groups only
    commas, semicolons and spaces."""
    body = text.strip()
    if body.startswith("[") and body.endswith("]"):
        body = body[1:-1]
    groups = re.findall(r"\(([^()]*)\)", body)
    rest = re.sub(r"\(([^()]*)\)", " ", body)
    if not groups or rest.strip(" ,;\t"):
        raise ValueError(f"groups of numbers in parentheses, '(a, b, c), (d, e, f)', or separated by ';' "
                         f"expected, got {text!r}")
    return groups


def format_groups(value) -> str:
    """Inverse of :func:`parse_groups` (a list of number tuples -> string)."""
    return "; ".join(" ".join(repr(float(x)) for x in g) for g in value)


def spec_value(v) -> str:
    """A parameter value as spec text that :func:`parse_value` reads back: floats
    exactly (``repr``), colours as ``r,g,b``, groups of tuples as ``a,b;c,d;``, a
    nested model as its own spec in square brackets."""
    if hasattr(v, "spec") and hasattr(v, "eval"):      # a nested model
        return f"[{v.spec()}]"
    if hasattr(v, "tolist"):
        v = v.tolist()
    if isinstance(v, (list, tuple)):
        if any(isinstance(x, (list, tuple)) or hasattr(x, "tolist") for x in v):
            return "".join(spec_value(x) + ";" for x in v)
        return ",".join(spec_value(x) for x in v)
    if isinstance(v, bool) or not isinstance(v, (int, float)):
        return str(v)
    return repr(float(v)) if isinstance(v, float) else str(v)


def parse_value(text: str):
    """Parse a command-line value: ``0.5``, ``0.9,0.6,0.2`` (a colour), groups
    separated by ``;`` (``-1,-1,1,20,1.5;1,1,1,8,0.3``: a list of tuples, e.g.
    Lafortune's lobes; :func:`parse_groups`) or a word."""
    if ";" in text or text.lstrip().startswith(("(", "[(")):
        return parse_groups(text)
    parts = [t.strip() for t in text.split(",")]
    try:
        nums = [float(t) for t in parts]
    except ValueError:
        return text
    return nums[0] if len(nums) == 1 else nums
