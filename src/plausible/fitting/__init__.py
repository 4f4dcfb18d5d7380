"""Fitting a model's parameters to measured data or to another model, with the
least-squares metrics and the perceptual metric of Neumann, Neumann &
Szirmay-Kalos (1999); reading and writing measured BRDFs in the MERL format.
See docs/fitting.md."""

from .fit import BoundWarning, FitResult, UnconstrainedWarning, evaluate_fit, fit
from .targets import Target, as_target, load_table, save_table
from ..models.merl import MerlBRDF, read_merl, tabulate, write_merl
from .metrics import METRICS, errors, objective, sample_pairs

__all__ = ["BoundWarning", "FitResult", "METRICS", "MerlBRDF", "Target", "as_target", "errors", "evaluate_fit",
           "fit", "load_table", "objective", "read_merl", "sample_pairs", "save_table", "tabulate",
           "write_merl"]
