"""Parameters as kernel data: one compiled Dr.Jit kernel per model *structure*.

A model's parameters are of two sorts:

* **data** -- every float and every float channel array (``is_data``): the
  values that fits, sliders and optimisers change.  The Dr.Jit backend
  (:mod:`plausible.arrays.backend`) hands them to the hooks as kernel *inputs*
  (``dr.opaque`` scalars, channel arrays gathered per lane), never as
  constants folded into the kernel, so the traced kernel is the same for
  every value and Dr.Jit's kernel cache serves it without compiling again;
* **structure** -- everything else: choices (strings), integers, nested
  models, the channel count, and the class itself.  A hook may branch in
  Python on these (``if p.variant == "duer"``); they make up the
  :func:`structure` key, one compiled kernel per key.

A hook must therefore treat data parameters as arrays: ``ops`` functions,
arithmetic and ``ops.where``, not ``math.*``, ``float()`` or a Python ``if``
on a value.  A hook that does not (for example one that takes ``math.log`` of
a parameter) fails on the first data call; the backend then runs that
structure with its parameters as constants, as before this module (one kernel
per parameter set, still correct), so a model registered later works either
way and becomes faster as soon as its hooks are written with ``ops``.

:meth:`plausible.bxdf.BxDF._kernel_view` makes the copy of a model whose data
went through a conversion; a composite model (a :class:`~plausible.models.sum.Sum`,
a pumped-up model holding its base) overrides it to convert what it holds.

>>> import plausible
>>> a = plausible.make("ward", alpha_x=0.1, variant="duer")
>>> structure(a) == structure(plausible.make("ward", alpha_x=0.3, rs=0.2, variant="duer"))
True
>>> structure(a) == structure(plausible.make("ward", variant="balanced"))
False
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np


def is_data(v) -> bool:
    """A float (not an int or a bool) or a 1-D float array (colour channels)."""
    if isinstance(v, np.ndarray):
        return v.ndim <= 1 and v.dtype.kind == "f"
    return isinstance(v, float)


def convert_namespace(ns, convert) -> SimpleNamespace:
    """``ns`` with every data value replaced by ``convert(value)``."""
    return SimpleNamespace(**{k: (convert(v) if is_data(v) else v) for k, v in vars(ns).items()})


def _leaf(v):
    if is_data(v):
        return ("data", np.shape(v))
    if hasattr(v, "_structure"):
        return v._structure()
    try:
        hash(v)
        return v
    except TypeError:
        return repr(v)


def default_structure(model) -> tuple:
    """The class, the channel count, and each parameter: its shape if it is data,
    else its value (a nested model: its own structure)."""
    return (type(model).__module__, type(model).__qualname__, model.channels,
            tuple((k, _leaf(v)) for k, v in model.params.items()))


def structure(model):
    """The structure key of ``model`` (:meth:`~plausible.bxdf.BxDF._structure`):
    equal keys trace to the same kernel whatever the data values."""
    return model._structure()


__all__ = ["convert_namespace", "default_structure", "is_data", "structure"]
