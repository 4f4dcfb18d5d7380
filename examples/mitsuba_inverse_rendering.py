"""Recover Ashikhmin-Shirley parameters from a rendering (inverse rendering).

Renders a reference image of a sphere with known nu, nv, rs, rd, then starts
from other values and runs Adam (mi.ad) through the prb integrator until the
rendering matches.  See docs/mitsuba.md, "Inverse rendering".

    python examples/mitsuba_inverse_rendering.py [--res 24] [--iterations 100]
"""

from __future__ import annotations

import argparse

import mitsuba as mi

TRUTH = {"nu": 50.0, "nv": 400.0, "rs": 0.3, "rd": 0.4}
START = {"nu": 150.0, "nv": 150.0, "rs": 0.15, "rd": 0.6}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--res", type=int, default=24, help="image width and height in pixels")
    ap.add_argument("--spp", type=int, default=4, help="samples per pixel")
    ap.add_argument("--iterations", type=int, default=100)
    ap.add_argument("--lr", type=float, default=0.05, help="Adam's initial learning rate")
    args = ap.parse_args()

    import plausible.mitsuba
    from plausible.mitsuba import inverse

    plausible.mitsuba.register("llvm_ad_rgb")
    reference = mi.render(inverse.sphere_scene({"type": "ashikhmin_shirley", **TRUTH}, args.res, args.spp),
                          seed=0)
    scene = inverse.sphere_scene({"type": "ashikhmin_shirley", **START}, args.res, args.spp)
    result = inverse.fit(scene, reference, START, iterations=args.iterations, lr=args.lr)
    errors = inverse.relative_errors(result.values, TRUTH)
    for k in TRUTH:
        print(f"{k:>3}: start {START[k]:8.3f}  found {result.values[k]:8.3f}  "
              f"true {TRUTH[k]:8.3f}  error {100 * errors[k]:.2f} %")
    print(f"{result.iterations} iterations in {result.seconds:.1f} s; "
          f"final loss {result.history[-1][0]:.3g}")


if __name__ == "__main__":
    main()
