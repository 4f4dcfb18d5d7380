"""plausible: physically plausible BRDFs under one contract (:mod:`plausible.bxdf`).

Evaluate, sample, check (reciprocity, energy, sampling, chi-square), fit,
export (GLSL, BRDF Explorer, glTF) and render (Mitsuba 3 plugins) every
registered model -- the Phong family, Lafortune, Schlick, Ward, Cook-Torrance,
He-Torrance, Low, albedo pumping-up, ... (:func:`names`) -- the published MERL
fits (:func:`material`), and foreign BSDFs through adapters.  The package's
floors are drawn in ``docs/index.md`` ("Structure").

>>> import plausible
>>> m = plausible.make("modified-phong", kd=0.5, ks=0.5, n=10)
>>> round(float(m.eval([0, 0, 1], [0, 0, 1])), 5)   # 7 / (2 pi)
1.11408
"""

from .analysis import (albedo, albedo_curve, check, chi2, compensate, energy, hemispherical_albedo, reciprocity,
                       sampling_consistency)
from .arrays.backend import use as use_backend
from .bxdf import BxDF, Sample
from .fitting import fit
from .conversion import convert  # (after fitting: it fits)
from .catalogue import material, materials
from .models.sum import Sum
from .mitsuba.looks import Looks, compare_looks
from .registry import info, make, names, register
from .vec import angles, direction

__version__ = "0.1.0"

__all__ = ["BxDF", "Looks", "Sample", "Sum", "albedo", "albedo_curve", "angles", "check", "chi2", "compare_looks", "compensate", "convert", "direction", "energy", "fit",
           "hemispherical_albedo", "info", "make", "material", "materials", "names", "reciprocity", "register",
           "sampling_consistency", "use_backend", "__version__"]
