"""The registry entry ``material``: a published fit as a model with two choice
parameters, ``name`` (a MERL material) and ``fit`` (a loadable fit set).

    >>> import plausible
    >>> m = plausible.make("material", name="alum-bronze", fit="ngan2005/ward")
    >>> m.spec()
    'material:alum-bronze@ngan2005/ward'

A catalogue entry (``register(..., catalogue=True)``): :func:`plausible.info`,
:func:`plausible.make` and the explorer know it, :func:`plausible.names` (the
model families every registry-wide test runs over) does not list it.  Its spec
is its own: ``material:NAME@FIT`` or ``material:name=NAME:fit=FIT``
(:meth:`Material.from_spec_items`), read into the plain
:class:`~plausible.models.sum.Sum` of :func:`plausible.material`; the Mitsuba
plugin ``plausible_material`` (:mod:`plausible.mitsuba.material`) renders it.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import SimpleNamespace

from ..bxdf import Params
from ..params import Param
from ..registry import register
from . import fit_sets as F

#: The prefix of a material's spec.
PREFIX = "material:"


@dataclass(frozen=True)
class MaterialNameParam(Param):
    """A material name (``kind="choice"``, checked against the catalogue with the
    closest names suggested; :meth:`options` lists them, read on first use)."""

    kind: str = "choice"

    def range_text(self) -> str:
        return "a material name of plausible.materials() (e.g. alum-bronze)"

    def options(self) -> list:
        return sorted(F.materials())

    def validate(self, value, owner: str = "model"):
        if not isinstance(value, str) or value not in F.materials():
            hint = F.suggest(str(value), F.materials())
            raise ValueError(f"{owner}: parameter '{self.name}' must be {self.range_text()}, "
                             f"got {value!r}{hint}")
        return value


def _fit_param():
    keys = tuple(f.key for f in F.fits() if f.built)
    return Param("fit", F.DEFAULT_FIT, kind="choice", choices=keys,
                 doc="published fit set (plausible materials lists them)")


@register("material", "A published fit of a MERL material (Ngan, Durand & Matusik 2005; Low et al. 2012): "
          "plausible.material(name, fit), a sum of the fitted model's terms.", reciprocal=True,
          energy_conserving=False, references=(F.NGAN, F.LOW, F.SOURCE), catalogue=True)
class Material(F.Sum):
    """``Material(name, fit)``: :func:`plausible.material` as a model with two
    parameters (what the generic plugin and the explorer's menus need)."""

    PARAMS = (MaterialNameParam("name", "alum-bronze", doc="MERL material name"), _fit_param())
    #: The owner named in its errors (the Mitsuba plugin's name, where it is mostly built).
    OWNER = "plausible_material"

    def __init__(self, name: str = "alum-bronze", fit: str = F.DEFAULT_FIT):
        name = self.PARAMS[0].validate(name, self.OWNER)
        fit = self.PARAMS[1].validate(fit, self.OWNER)
        m = F.material(name, fit)
        super().__init__(list(zip(m.parts, m.scales)), name=m.label)
        self._params = Params({"name": name, "fit": fit})
        self.p = SimpleNamespace(**self.params)
        self.q = SimpleNamespace(**self.params)

    def spec(self) -> str:
        return f"{PREFIX}{self.params['name']}@{self.params['fit']}"

    @classmethod
    def from_spec_items(cls, items: list, **extra):
        """The model of the spec ``material:`` + ``":".join(items)``: the
        :class:`~plausible.models.sum.Sum` of :func:`plausible.material`."""
        spec = PREFIX + ":".join(items)
        if extra:
            raise ValueError(f"model spec {spec!r}: a material takes no parameters "
                             f"(got {', '.join(sorted(extra))})")
        return F.from_spec(spec)


__all__ = ["Material", "MaterialNameParam", "PREFIX"]
