"""Render-time ratio: plausible's ``ashikhmin_shirley`` plugin vs Mitsuba's
built-in ``roughconductor`` on the same small scene (not a test).

    .venv/bin/python benchmarks/bench_render.py [--res 128] [--spp 64] [--variant llvm_ad_rgb]

Each BSDF is rendered once to warm the JIT (tracing + LLVM compilation, reported
separately), then ``--repeat`` times; the median of the repeats is compared.
"""

from __future__ import annotations

import argparse
import statistics
import time

import mitsuba as mi
import pytest


def scene(bsdf: dict, res: int, spp: int):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, -4, 2], target=[0, 0, 0.3],
                                                              up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": res, "height": res},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "center": [0, 0, 0.5], "radius": 0.5, "bsdf": bsdf},
        "floor": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([3, 3, 1]),
                  "bsdf": {"type": "diffuse"}},
        "light": {"type": "point", "position": [2, -2, 4], "intensity": {"type": "rgb", "value": 30.0}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })


def timed(sc, repeat: int):
    t0 = time.perf_counter()
    mi.render(sc, seed=0)
    mi.Float(0).numpy()  # make sure the first render finished
    first = time.perf_counter() - t0
    times = []
    for i in range(repeat):
        t0 = time.perf_counter()
        img = mi.render(sc, seed=i + 1)
        img.numpy()
        times.append(time.perf_counter() - t0)
    return first, statistics.median(times)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", type=int, default=128)
    ap.add_argument("--spp", type=int, default=64)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    import plausible.mitsuba as pm

    pm.register(args.variant)
    # comparable lobes: A&S exponent n ~ 2 / alpha^2 - 2 (Beckmann alpha 0.2 -> n = 48)
    a_s = {"type": "ashikhmin_shirley", "nu": 48.0, "nv": 48.0, "rd": 0.0,
           "rs": {"type": "rgb", "value": [0.9, 0.6, 0.3]}}
    rc = {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.2,
          "specular_reflectance": {"type": "rgb", "value": [0.9, 0.6, 0.3]}}
    res = {}
    for name, b in (("ashikhmin_shirley", a_s), ("roughconductor", rc)):
        first, med = timed(scene(b, args.res, args.spp), args.repeat)
        res[name] = med
        print(f"{name:18s} first render (incl. JIT) {first:7.3f} s   median render {med:7.3f} s")
    print(f"variant {args.variant}, {args.res}x{args.res}, {args.spp} spp: "
          f"time ratio ashikhmin_shirley / roughconductor = {res['ashikhmin_shirley'] / res['roughconductor']:.2f}")


if __name__ == "__main__":
    main()


# -- the same comparison as pytest-benchmark tests (``make bench``) ----------------

A_S = {"type": "ashikhmin_shirley", "nu": 48.0, "nv": 48.0, "rd": 0.0,
       "rs": {"type": "rgb", "value": [0.9, 0.6, 0.3]}}
RC = {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.2,
      "specular_reflectance": {"type": "rgb", "value": [0.9, 0.6, 0.3]}}


def furnace_scene(bsdf: dict, res: int = 64, spp: int = 64):
    """A unit sphere in a constant white environment (the white furnace), orthographic view."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "path", "max_depth": 4},
        "sensor": {"type": "orthographic",
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 5], target=[0, 0, 0], up=[0, 1, 0])
                   @ mi.ScalarTransform4f().scale([1.1, 1.1, 1.0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res, "rfilter": {"type": "box"}},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "radius": 1.0, "bsdf": bsdf},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 1.0}},
    })


def _render(sc, seed):
    mi.render(sc, seed=seed).numpy()


@pytest.mark.parametrize("bsdf", ["roughconductor", "ashikhmin_shirley"])
def test_render_scene(benchmark, request, bsdf):
    """The scene above, 128x128, 64 spp, with each BSDF (3 renders after one
    first render that includes tracing and compilation)."""
    request.getfixturevalue("mi")
    from conftest import first_call, record

    sc = scene({"roughconductor": RC, "ashikhmin_shirley": A_S}[bsdf], 128, 64)
    record(benchmark, "render", f"scene 128x128 64spp ({bsdf})", backend="mitsuba", op="render",
           n=128 * 128 * 64, first_call_s=first_call(lambda: _render(sc, 0)))
    benchmark.pedantic(lambda: _render(sc, 1), rounds=3, iterations=1)


def test_furnace_render(benchmark, request):
    """White furnace: Ashikhmin-Shirley plugin on a sphere in a constant white
    environment, 64x64, 64 spp."""
    request.getfixturevalue("mi")
    from conftest import first_call, record

    sc = furnace_scene({"type": "ashikhmin_shirley", "nu": 20.0, "nv": 80.0, "rs": 0.3, "rd": 0.5})
    record(benchmark, "render", "furnace 64x64 64spp (ashikhmin_shirley)", backend="mitsuba", op="render",
           n=64 * 64 * 64, first_call_s=first_call(lambda: _render(sc, 0)))
    benchmark.pedantic(lambda: _render(sc, 1), rounds=3, iterations=1)

