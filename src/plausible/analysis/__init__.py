"""Analysis: albedo, reciprocity, energy, sampling consistency, chi-square, check.

Everything here uses only the model contract (``eval``, ``pdf``, ``sample``
and the optional ``peak_directions`` hint), so it works for any model; the
adapters (:mod:`.adapters`, :mod:`.mitsuba_bsdf`) bring Mitsuba BSDFs and plain
callables to that contract.
"""

from .adapters import CallableBxDF, as_bxdf
from ..integrals.albedo import (AlbedoResult, albedo, albedo_curve, albedo_table, albedos, direction, hemispherical_albedo,
                     is_isotropic, pdf_integral, pdf_integrals)
from .compensation import compensate
from .checks import PropertyResult, energy, reciprocity, sampling_consistency
from .chi2 import AdaptiveBinning, Chi2Result, FixedBinning, chi2, sidak
from .report import CheckReport, check

__all__ = ["AdaptiveBinning", "AlbedoResult", "CallableBxDF", "CheckReport", "Chi2Result", "FixedBinning",
           "PropertyResult", "albedo", "albedo_curve", "albedo_table", "albedos", "as_bxdf", "check", "chi2",
           "compensate", "direction", "energy", "hemispherical_albedo", "is_isotropic", "pdf_integral", "pdf_integrals",
           "reciprocity", "sampling_consistency", "sidak"]
