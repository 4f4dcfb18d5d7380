"""The CPU of ``plausible.fit`` under ``l2-cos`` against a plain ``scipy.optimize.least_squares``
on the same residuals, in one run (issue 40, docs/benchmarks.md).

The plain fit: the fitted model's parameters (colours as scalars: the channel-mean target), the
registry's bounds, ``least_squares(method="trf")`` with SciPy's own 2-point Jacobian from the
defaults, the residuals of :meth:`plausible.fitting.fit._Objective._residuals` written out here
(``(c - g) / |g|`` and the highlight rows), every evaluation ``plausible.make(...)`` then
``eval`` on NumPy.  ``plausible.fit``: its whole procedure (starts, the isotropic fit first, the
colours per channel, identifiability, the accurate albedo of the result), then with each
Jacobian rule (:data:`plausible.fitting.fit.JACOBIAN`).  Both on one BLAS thread.  The target
(pairs, values, accurate albedo) is built once, outside every timing.

Run: ``PYTHONPATH=src python benchmarks/fitter.py``; prints a Markdown table.  With
``--convert``: the CPU and wall seconds of :func:`plausible.convert` of a few published fits to
Mitsuba and glTF, after one warm-up conversion (Mitsuba imported before).
"""

from __future__ import annotations

import importlib
import math
import time
import warnings

import numpy as np
from scipy.optimize import least_squares
from threadpoolctl import threadpool_limits

import plausible
from plausible import registry
from plausible.fitting import metrics as M
from plausible.fitting.targets import as_target, fcos

F = importlib.import_module("plausible.fitting.fit")

CASES = (("ashikhmin-shirley", "material:gold-metallic-paint@low2012/smooth-e2"),
         ("ward", "material:nickel@ngan2005/ward"),
         ("ashikhmin-shirley-scaled", "material:nickel@ngan2005/ashikhmin-shirley"))


def plain(name, tgt):
    """``least_squares`` on the residuals, plainly: ``(x, l2-cos figure, CPU seconds, evaluations)``."""
    info = registry.info(name)
    g = tgt.fcos.mean(axis=-1) if tgt.fcos.ndim == 2 else tgt.fcos
    wi = np.broadcast_to(tgt.wi, tgt.wo.shape)
    rows, eps, den = M.highlight_rows(wi, g), M.floor(tgt.fcos), math.sqrt(float(np.sum(g * g)))
    ps = [p for p in info.params if p.numeric and not p.integer and p.default is not None]
    lo = np.array([p.lo for p in ps])
    hi = np.array([min(p.hi, F.EXPONENT_CAP) for p in ps])
    count = [0]

    def res(x):
        count[0] += 1
        c = fcos(np.asarray(plausible.make(name, **dict(zip([p.name for p in ps], map(float, x))))
                            .eval(tgt.wi, tgt.wo)), tgt.wo)
        c = c.mean(axis=-1) if c.ndim == 2 else c
        return np.concatenate([(c - g) / den, math.sqrt(M.HIGHLIGHT_WEIGHT) * M.highlight_excess(c, g, rows, eps)])

    t0 = time.process_time()
    r = least_squares(res, np.array([float(np.mean(p.default)) for p in ps]), bounds=(lo, hi), method="trf")
    return r.x, math.sqrt(2 * r.cost), time.process_time() - t0, count[0]


def ours(name, tgt, jacobian):
    F.JACOBIAN = jacobian
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = plausible.fit(name, tgt, "l2-cos")
    return r, time.process_time() - t0


CONVERSIONS = ("material:nickel@ngan2005/ward", "material:alum-bronze@ngan2005/ward",
               "material:gold-metallic-paint@low2012/smooth-e2")


def conversions():
    import mitsuba  # noqa: F401  (imported before the timings)

    plausible.convert("lambertian:rd=0.5", to="mitsuba")
    print("| source | to | chosen | CPU s | wall s |\n|---|---|---|---|---|")
    for spec in CONVERSIONS:
        for to in ("mitsuba", "gltf"):
            t0, c0 = time.time(), time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                c = plausible.convert(spec, to=to)
            print(f"| {spec} | {to} | {c.items[0].target} | {time.process_time() - c0:.1f} | "
                  f"{time.time() - t0:.1f} |", flush=True)


def main():
    import sys

    if "--convert" in sys.argv[1:]:
        return conversions()
    print("| model | target | plain least_squares: CPU s (evaluations), l2-cos | plausible.fit, population "
          "Jacobian: CPU s (evaluations), l2-cos | ratio | plausible.fit, 2-point: CPU s, l2-cos |")
    print("|---|---|---|---|---|---|")
    with threadpool_limits(limits=1, user_api="blas"):
        for name, spec in CASES:
            tgt = as_target(spec)
            ours(name, tgt, "population")          # warm: the kernel cache, imports
            _, e0, t0, n0 = plain(name, tgt)
            r1, t1 = ours(name, tgt, "population")
            r2, t2 = ours(name, tgt, "2-point")
            print(f"| {name} | {spec} | {t0:.2f} ({n0}), {e0:.5g} | {t1:.2f} ({r1.evaluations}), "
                  f"{r1.errors['l2-cos']:.5g} | {t1 / t0:.2f} | {t2:.2f}, {r2.errors['l2-cos']:.5g} |", flush=True)


if __name__ == "__main__":
    main()
