"""The table of Mitsuba's built-in BSDFs (figures/mitsuba_builtins.py) on rows with known answers."""

import pytest

from mi_helpers import mi  # noqa: F401  (sets the variant)

from plausible.figures.mitsuba_builtins import CONFIGS, QUICK_CONFIGS, builtin_markdown, builtin_table


def test_white_diffuse_row_is_plausible_with_albedo_one_and_a_matching_furnace():
    (row,) = builtin_table([c for c in CONFIGS if c[0] == "diffuse"], quick=True, spp=16)
    assert row.plausible and row.notes == []
    assert row.max_albedo == pytest.approx(1.0, abs=1e-6) and row.energy_lost < 1e-6   # Lambert: rho = 1
    assert row.quadrature_60 == pytest.approx(1.0, abs=1e-6) and row.furnace_sigma <= 4
    line = builtin_markdown([row]).splitlines()[2]
    assert line.startswith("| diffuse | yes |") and "1.0000 (" in line


def test_configurations_cover_the_issue():
    labels = " ".join(lb for lb, _ in CONFIGS)
    for word in ("diffuse", "beckmann", "ggx", "a=0.01", "a=1", "au=0.05", "sv=off", "nonlinear", "plastic",
                 "principled metallic=0", "principled metallic=1", "spec_tint", "sheen", "pplastic", "blendbsdf"):
        assert word in labels, word
    assert set(lb for lb, _ in QUICK_CONFIGS) <= set(lb for lb, _ in CONFIGS)
