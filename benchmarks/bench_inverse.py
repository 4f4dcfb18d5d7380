"""Inverse rendering with ``<rgb>`` colours (issue 43): a ``prb`` optimisation of a
plugin's two colours against Mitsuba's ``roughplastic`` in the same run (not a test).

    PYTHONPATH=src .venv/bin/python benchmarks/bench_inverse.py [--res 64x48] [--spp 8] [--iters 12]

Scene: a sphere on a diffuse floor under a constant environment and a point light
(as ``bench_render.scene``, with ``prb``).  Each BSDF starts from ``<rgb>`` colours (0.2, 0.3, 0.25)
and (0.5, 0.4, 0.3) and is fitted by ``mi.ad.Adam`` (lr 0.02) to the image of
itself at other colours.  Per iteration (after two warm-up iterations):

* ``iter wall`` / ``iter CPU``: wall and process CPU time of render + backward +
  step + ``params.update(opt)``, the median over the iterations; the BSDFs'
  iterations alternate (the machine is shared); the loop reads the loss each
  iteration, as an optimisation that prints it does, so nothing is left pending;
* ``new kernels``: JIT kernels whose hash Dr.Jit's kernel history had not shown
  before (a compilation, or a load from the on-disk cache of an earlier run),
  summed over the measured iterations; ``kernels/iter`` the JIT kernels launched
  per iteration and ``kernel exec`` their execution time as Dr.Jit's kernel
  history reports it (the rest of the CPU time is tracing, Python, Adam);
* ``update``: ``params[key] = value; params.update()`` alone, on an idle device
  (``dr.sync_thread()`` first), the median of 20; and the same when the previous
  render is still running (Dr.Jit's LLVM backend launches kernels asynchronously;
  reading a value back waits for them).

First, :func:`update_table`: ``params.update()`` alone of one BSDF each (:data:`UPDATES`:
the plugins' colours and numbers, ``roughplastic``/``diffuse`` colours and
``roughconductor``'s alpha for reference), idle, median of 500, in microseconds.
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


class Optimisation:
    """One BSDF's optimisation, run a few iterations at a time (``run``), so that the
    BSDFs' iterations can alternate on a shared machine."""

    def __init__(self, plugin, res, spp):
        self.keys = [f"sphere.bsdf.{n}.value" for n in CASES[plugin] if n is not None]
        self.ref = mi.render(scene(plugin, TARGET, res, spp), spp=4 * spp, seed=999)
        self.scene, self.spp = scene(plugin, START, res, spp), spp
        self.params = mi.traverse(self.scene)
        self.opt = mi.ad.Adam(lr=0.02)
        for k in self.keys:
            self.opt[k] = self.params[k]
        self.params.update(self.opt)
        self.seen, self.it, self.loss = set(), 0, float("nan")
        self.wall, self.cpu, self.new, self.launches, self.exec_ms = [], [], [], [], []

    def run(self, iters, record=True):
        for _ in range(iters):
            dr.kernel_history()
            t0, c0 = time.perf_counter(), time.process_time()
            img = mi.render(self.scene, self.params, spp=self.spp, seed=self.it)
            loss = dr.mean(dr.square(img - self.ref), axis=None)
            dr.backward(loss)
            self.opt.step()
            for k in self.keys:
                self.opt[k] = dr.clip(self.opt[k], 0.0, 0.95)
            self.params.update(self.opt)
            self.loss = float(dr.ravel(loss)[0])
            wall, cpu = time.perf_counter() - t0, time.process_time() - c0
            jit = [k for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT]
            hashes = {k["hash"] for k in jit}
            if record:
                self.wall.append(wall)
                self.cpu.append(cpu)
                self.new.append(len(hashes - self.seen))
                self.launches.append(len(jit))
                self.exec_ms.append(sum(k.get("execution_time", 0.0) for k in jit))
            self.seen |= hashes
            self.it += 1


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


#: ``params.update()`` alone, one BSDF each (issue 43, item 2): (label, BSDF dict, key scaled).
UPDATES = [
    ("roughplastic <rgb>", {"type": "roughplastic", "diffuse_reflectance": {"type": "rgb", "value": [0.5, 0.4, 0.3]}},
     "diffuse_reflectance.value"),
    ("diffuse <rgb>", {"type": "diffuse", "reflectance": {"type": "rgb", "value": [0.5, 0.4, 0.3]}},
     "reflectance.value"),
    ("roughconductor alpha", {"type": "roughconductor", "alpha": 0.2}, "alpha.value"),
    ("ashikhmin_shirley rs <rgb>", {"type": "ashikhmin_shirley", "rs": {"type": "rgb", "value": [0.2, 0.3, 0.25]},
                                    "rd": {"type": "rgb", "value": [0.5, 0.4, 0.3]}}, "rs.value"),
    ("modified_phong kd <rgb>", {"type": "modified_phong", "ks": {"type": "rgb", "value": [0.2, 0.3, 0.25]},
                                 "kd": {"type": "rgb", "value": [0.5, 0.4, 0.3]}}, "kd.value"),
    ("ward rd <rgb>", {"type": "ward", "rs": {"type": "rgb", "value": [0.2, 0.3, 0.25]},
                       "rd": {"type": "rgb", "value": [0.5, 0.4, 0.3]}}, "rd.value"),
    ("gltf_pbr base_color <rgb>", {"type": "gltf_pbr", "base_color": {"type": "rgb", "value": [0.2, 0.3, 0.25]}},
     "base_color.value"),
    ("lambertian rd <rgb>", {"type": "lambertian", "rd": {"type": "rgb", "value": [0.5, 0.4, 0.3]}}, "rd.value"),
    ("he_torrance wavelength <rgb>", {"type": "he_torrance", "wavelength": {"type": "rgb", "value": [0.6, 0.5, 0.45]}},
     "wavelength.value"),
    ("ashikhmin_shirley nu", {"type": "ashikhmin_shirley", "nu": 10.0, "nv": 30.0}, "nu"),
    ("ward alpha_x", {"type": "ward", "alpha_x": 0.2, "alpha_y": 0.3}, "alpha_x"),
    ("cook_torrance m", {"type": "cook_torrance", "m": 0.2}, "m"),
]


def update_table(rounds=5, n=100):
    """``params[key] *= 0.999 or 1.0005; params.update()`` on an idle device
    (``dr.sync_thread()`` first), the BSDFs alternating in ``rounds`` rounds of ``n``
    updates each; the median over all, in microseconds."""
    made = []
    for label, d, key in UPDATES:
        params = mi.traverse(mi.load_dict(d))
        made.append((label, params, key, []))
    for _ in range(rounds):
        for label, params, key, times in made:
            for i in range(n):
                params[key] = params[key] * (0.999 if i % 2 else 1.0005)
                dr.sync_thread()
                t0 = time.perf_counter()
                params.update()
                times.append(time.perf_counter() - t0)
    return {label: 1e6 * statistics.median(times) for label, _, _, times in made}


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
    # before the kernel history is switched on: it adds its bookkeeping to every launch
    print("params.update() alone, idle device, median of 500 (us):")
    for label, us in update_table().items():
        print(f"  {label:30s} {us:8.1f}")
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    runs = {plugin: Optimisation(plugin, res, args.spp) for plugin in CASES}
    for r in runs.values():
        r.run(2, record=False)          # warm-up: tracing and compilation of the first values
    for _ in range(args.iters):         # the BSDFs alternate, one iteration each
        for r in runs.values():
            r.run(1)
    print(f"{args.variant}, {res[0]}x{res[1]}, {args.spp} spp, prb, {args.iters} iterations each "
          f"after 2 warm-up, alternating")
    print(f"{'bsdf':20s} {'iter wall (ms)':>15s} {'iter CPU (ms)':>14s} {'kernels/iter':>13s} "
          f"{'kernel exec (ms)':>17s} {'new kernels':>12s} {'final loss':>11s} "
          f"{'update idle (ms)':>17s} {'update after render (ms)':>25s}")
    for plugin, r in runs.items():
        idle, busy = update_cost(plugin, res, args.spp)
        print(f"{plugin:20s} {1e3 * statistics.median(r.wall):15.1f} {1e3 * statistics.median(r.cpu):14.1f} "
              f"{statistics.median(r.launches):13.0f} {statistics.median(r.exec_ms):17.1f} "
              f"{sum(r.new):12d} {r.loss:11.3g} {1e3 * idle:17.2f} {1e3 * busy:25.1f}")


if __name__ == "__main__":
    main()
