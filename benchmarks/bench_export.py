"""Shader export of a large pumped-up model (docs/export.md): the three formats
of ``plausible export`` for a pumped-up anisotropic base whose albedo table has
the 361 x 32 nodes (12,705 values) of the issue's
``base=ashikhmin-shirley-specular:nu=1:nv=10000``.

The table here is that of ``nu=10, nv=200`` (91 x 32 nodes, built in about
10 s) resampled to 361 x 32: the export's work depends on the table's size,
not on its values, and the base of the issue needs 12 minutes of albedo
integration before anything is exported (``bench_analysis.py`` times table
building).  ``glsl`` writes the table as a ``const float`` array, ``js`` as a
texture's texels, ``brdf`` resamples it to at most 1,200 values (choosing the
grid measures the interpolation error of four candidates)."""

from __future__ import annotations

import copy

import pytest

import plausible
from conftest import record
from plausible.export import to_brdf, to_glsl, to_js

FORMATS = {"glsl": lambda m: to_glsl(m).text, "js": to_js, "brdf": to_brdf}


@pytest.fixture(scope="module")
def large():
    m = plausible.make("pumped-up", base="ashikhmin-shirley-specular:nu=10:nv=200:rs=1")
    big = copy.copy(m)
    big.tables = [m.tables[0].resampled(361, 32)]
    assert big.tables[0].size == 12705
    return big


@pytest.mark.parametrize("fmt", list(FORMATS))
def test_export_large_pumped_up(benchmark, large, fmt):
    text = FORMATS[fmt](large)
    record(benchmark, "export", f"pumped-up, anisotropic base, 12,705 table values, --format {fmt}",
           backend="numpy", op="export", n=1, table_values=large.tables[0].size, chars=len(text))
    benchmark.pedantic(lambda: FORMATS[fmt](large), rounds=3, iterations=1)
