"""Inverse rendering with ``<rgb>`` colours (issue 43): a ``prb`` optimisation of a
plugin's two colours against Mitsuba's ``roughplastic`` in the same run (not a test).

    PYTHONPATH=src .venv/bin/python benchmarks/bench_inverse.py [--res 64x48] [--spp 8] [--iters 12]

Scene: a sphere on a diffuse floor under a constant environment and a point light
(as ``bench_render.scene``, with ``prb``).  Each BSDF starts from ``<rgb>`` colours (0.2, 0.3, 0.25)
and (0.5, 0.4, 0.3) and is fitted by ``mi.ad.Adam`` (lr 0.02) to the image of
itself at other colours.  Per iteration (after two warm-up iterations):

* ``iter``: wall time of render + backward + step + ``params.update(opt)``, the
  median over the iterations; the loop reads the loss each iteration, as an
  optimisation that prints it does, so nothing is left pending across iterations;
* ``new kernels``: JIT kernels whose hash Dr.Jit's kernel history had not shown
  before (a compilation, or a load from the on-disk cache of an earlier run);
* ``update``: ``params[key] = value; params.update()`` alone, on an idle device
  (``dr.sync_thread()`` first), the median of 20; and the same when the previous
  render is still running (Dr.Jit's LLVM backend launches kernels asynchronously;
  reading a value back waits for them).
"""

from __future__ import annotations

import argparse
import statistics
import time

import drjit as dr
import mitsuba as mi

CASES = {
    "ashikhmin_shirley": ("rs", "rd"),
    "modified_phong": ("ks", "kd"),
    "ward": ("rs", "rd"),
    "gltf_pbr": ("base_color", None),
    "roughplastic": ("specular_reflectance", "diffuse_reflectance"),
}
START = ([0.2, 0.3, 0.25], [0.5, 0.4, 0.3])
TARGET = ([0.1, 0.15, 0.1], [0.3, 0.5, 0.2])


def bsdf_dict(plugin, colours):
    d = {"type": plugin}
    for name, c in zip(CASES[plugin], colours):
        if name is not None:
            d[name] = {"type": "rgb", "value": c}
    return d


def scene(plugin, colours, res, spp):
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 4},
        "sensor": {"type": "perspective", "fov": 40,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, -4, 2], target=[0, 0, 0.3], up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": res[0], "height": res[1]},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "center": [0, 0, 0.5], "radius": 0.5, "bsdf": bsdf_dict(plugin, colours)},
        "floor": {"type": "rectangle", "to_world": mi.ScalarTransform4f().scale([3, 3, 1]), "bsdf": {"type": "diffuse"}},
        "light": {"type": "point", "position": [2, -2, 4], "intensity": {"type": "rgb", "value": 30.0}},
        "env": {"type": "constant", "radiance": {"type": "rgb", "value": 0.2}},
    })


def optimise(plugin, res, spp, iters):
    keys = [f"sphere.bsdf.{n}.value" for n in CASES[plugin] if n is not None]
    ref = mi.render(scene(plugin, TARGET, res, spp), spp=4 * spp, seed=999)
    sc = scene(plugin, START, res, spp)
    params = mi.traverse(sc)
    opt = mi.ad.Adam(lr=0.02)
    for k in keys:
        opt[k] = params[k]
    params.update(opt)
    seen, times, new = set(), [], []
    for it in range(iters + 2):
        dr.kernel_history()
        t0 = time.perf_counter()
        img = mi.render(sc, params, spp=spp, seed=it)
        loss = dr.mean(dr.square(img - ref), axis=None)
        dr.backward(loss)
        opt.step()
        for k in keys:
            opt[k] = dr.clip(opt[k], 0.0, 0.95)
        params.update(opt)
        float(dr.ravel(loss)[0])
        dt = time.perf_counter() - t0
        hashes = {k["hash"] for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT}
        if it >= 2:
            times.append(dt)
            new.append(len(hashes - seen))
        seen |= hashes
    return statistics.median(times), new, float(dr.ravel(loss)[0])


def update_cost(plugin, res, spp, n=20):
    key = f"sphere.bsdf.{CASES[plugin][0]}.value"
    sc = scene(plugin, START, res, spp)
    params = mi.traverse(sc)
    idle, busy = [], []
    for i in range(n):
        dr.sync_thread()
        params[key] = params[key] * 0.99
        t0 = time.perf_counter()
        params.update()
        idle.append(time.perf_counter() - t0)
    for i in range(5):
        img = mi.render(sc, spp=spp, seed=i)
        dr.eval(img)
        params[key] = params[key] * 0.99
        t0 = time.perf_counter()
        params.update()
        busy.append(time.perf_counter() - t0)
        dr.sync_thread()
    return statistics.median(idle), statistics.median(busy)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--res", default="64x48")
    ap.add_argument("--spp", type=int, default=8)
    ap.add_argument("--iters", type=int, default=12)
    ap.add_argument("--variant", default="llvm_ad_rgb")
    args = ap.parse_args()
    res = tuple(int(x) for x in args.res.split("x"))
    mi.set_variant(args.variant)
    import plausible.mitsuba as pm

    pm.register()
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    print(f"{args.variant}, {res[0]}x{res[1]}, {args.spp} spp, prb, {args.iters} iterations after 2 warm-up")
    print(f"{'bsdf':20s} {'iter (ms)':>10s} {'new kernels per iter':>22s} {'final loss':>11s} "
          f"{'update idle (ms)':>17s} {'update after render (ms)':>25s}")
    for plugin in CASES:
        t, new, loss = optimise(plugin, res, args.spp, args.iters)
        idle, busy = update_cost(plugin, res, args.spp)
        print(f"{plugin:20s} {1e3 * t:10.1f} {str(new):>22s} {loss:11.3g} {1e3 * idle:17.2f} {1e3 * busy:25.1f}")


if __name__ == "__main__":
    main()
