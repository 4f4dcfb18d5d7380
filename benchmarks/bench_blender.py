"""Virtual acquisition of a Cycles material (docs/blender.md): one Blender subprocess with the
furnace and two sun renders per light angle, and the MERL table filled from the measured pairs.
Skipped where Blender's interpreter (``.venv-blender``) is absent."""

from __future__ import annotations

import pytest

from conftest import record
from plausible.blender import BlenderUnavailable, acquire, blender_python, material_spec

try:
    blender_python()
except BlenderUnavailable as e:       # pragma: no cover - make setup installs it
    pytest.skip(str(e), allow_module_level=True)

METAL = {"Base Color": [1, 1, 1], "Metallic": 1.0, "Roughness": 0.5}


@pytest.mark.parametrize("res, angles", [(48, (0, 40, 80, 120, 160)), (96, tuple(range(0, 171, 10)))])
def test_acquire_principled(benchmark, res, angles):
    acq = benchmark.pedantic(acquire, args=(material_spec(principled=METAL),),
                             kwargs=dict(resolution=res, angles=angles), rounds=2, iterations=1)
    record(benchmark, "blender", f"acquire a Principled metal, {res} px, {2 * len(angles) + 1} renders",
           backend="cycles-cpu", op="acquire", n=len(acq.f))


def test_fill_merl_table(benchmark):
    acq = acquire(material_spec(principled=METAL), resolution=96)
    benchmark.pedantic(acq.brdf, rounds=2, iterations=1)
    record(benchmark, "blender", f"MERL table (1.46 M cells) from {len(acq.f)} measured pairs", backend="numpy",
           op="table", n=len(acq.f))


@pytest.mark.parametrize("spp", [16, 64])
def test_cycles_looks(benchmark, spp):
    from plausible.blender.looks import cycles_renders

    benchmark.pedantic(cycles_renders, args=(material_spec(principled=dict(METAL, distribution="GGX")),),
                       kwargs=dict(spp=spp), rounds=2, iterations=1)
    record(benchmark, "blender", f"compare_looks' scene in Cycles, 4 views of 64 px, {spp} spp (lamp {16 * spp})",
           backend="cycles-cpu", op="looks", n=8)


@pytest.mark.parametrize("res, angles, turns", [(48, (0, 40, 80), (0, 45, 90, 135)),
                                                (96, (0, 20, 40, 60, 80, 100, 120, 140), (0, 30, 60, 90, 120, 150))])
def test_acquire_tangent(benchmark, res, angles, turns):
    from plausible.blender.tangent import acquire_tangent

    aniso = dict(METAL, Anisotropic=0.6, distribution="GGX")
    acq = benchmark.pedantic(acquire_tangent, args=(material_spec(principled=aniso),),
                             kwargs=dict(resolution=res, angles=angles, turns=turns), rounds=2, iterations=1)
    record(benchmark, "blender", f"tangent-resolved acquisition of an anisotropic metal, {res} px, "
           f"{2 * len(angles) * len(turns) + 1} renders", backend="cycles-cpu", op="acquire", n=len(acq.f))
