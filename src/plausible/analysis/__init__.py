"""Analysis: albedo, reciprocity, energy, sampling consistency, chi-square, check.

Everything here uses only the model contract (``eval``, ``pdf``, ``sample``
and the optional ``peak_directions`` hint), so it works for any model.
"""

from .albedo import (AlbedoResult, albedo, albedo_curve, albedo_table, albedos, direction, hemispherical_albedo,
                     is_isotropic, pdf_integral, pdf_integrals)
from .checks import PropertyResult, energy, reciprocity, sampling_consistency
from .chi2 import Chi2Result, chi2, sidak
from .report import CheckReport, check

__all__ = ["AlbedoResult", "CheckReport", "Chi2Result", "PropertyResult", "albedo", "albedo_curve", "albedo_table",
           "albedos", "check", "pdf_integrals",
           "chi2", "direction", "energy", "hemispherical_albedo", "is_isotropic", "pdf_integral",
           "reciprocity", "sampling_consistency", "sidak"]
