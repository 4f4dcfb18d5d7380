"""The catalogue of published materials: the MERL fits of Ngan et al. (2005) and
Löw et al. (2012) as ready models (:mod:`.fit_sets`; ``plausible.material(name, fit)``).

It sits above the models (each fit is a :class:`~plausible.models.sum.Sum` of
model terms) and below every user of models: the CLI, the explorer, the
Mitsuba plugin and the fitting read it, it imports none of them.
"""

from .fit_sets import (DEFAULT_FIT, FIT_SETS, LOW, NGAN, SOURCE, FitSet, Sum, Term, build_term, fit_data, fit_set, fits,
                   from_spec, material, materials, parse_line, parse_spec, spec, suggest, terms)

__all__ = ["DEFAULT_FIT", "FIT_SETS", "FitSet", "LOW", "NGAN", "SOURCE", "Term", "build_term", "fit_data", "fit_set",
           "fits", "from_spec", "material", "materials", "parse_line", "parse_spec", "spec", "suggest", "terms"]
