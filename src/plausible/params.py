"""Parameter specifications and validation.

Every model declares its parameters as :class:`Param` objects; the registry, the
command line (``plausible models``), the Mitsuba plugins and the tests read them.
"""

from __future__ import annotations

import math
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
        return x


#: Channel counts a colour parameter may have (grey, RGB).
COLOR_CHANNELS = (1, 3)


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
