"""The CPU of ``plausible.fit`` under ``l2-cos`` against a plain ``scipy.optimize.least_squares``
on the same residuals, in one run (issue 40, docs/benchmarks.md).

The plain fit: the fitted model's parameters (colours as scalars: the channel-mean target), the
registry's bounds, ``least_squares(method="trf")`` with SciPy's own 2-point Jacobian from the
defaults, the residuals of :meth:`plausible.fitting.fit._Objective._residuals` written out here
(``(c - g) / |g|`` and the highlight rows), every evaluation ``plausible.make(...)`` then
``eval`` on NumPy.  ``plausible.fit``: its whole procedure (starts, the isotropic fit first, the
colours per channel, identifiability, the accurate albedo of the result).
Both on one BLAS thread.  The target
(pairs, values, accurate albedo) is built once, outside every timing.

Run: ``PYTHONPATH=src python benchmarks/fitter.py [--repeats N] [--before OLD/src]``; prints a
Markdown table of median CPU seconds over ``N`` (default 7) interleaved runs of each; ``--before``
adds ``plausible.fit`` of another checkout's ``src`` measured in a child process of the same run
(the plain fit's column is this process's).  ``--perceptual``: the perceptual fits of
:data:`PERCEPTUAL` instead (median of ``N``, default 7; ``--before`` as above).  With
``--convert``: the CPU and wall seconds of :func:`plausible.convert` of a few published fits to
Mitsuba and glTF, after a warm-up conversion of another fit to each target (its families' kernels compiled).
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


def ours(name, tgt, jacobian, metric="l2-cos"):
    F.JACOBIAN = jacobian
    t0 = time.process_time()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        r = plausible.fit(name, tgt, metric)
    return r, time.process_time() - t0


#: The perceptual fits timed by ``--perceptual`` (no plain baseline: not a sum of squares).
PERCEPTUAL = (("ward", "material:gold-metallic-paint@low2012/smooth-e2"),
              ("ashikhmin-shirley", "material:gold-metallic-paint@low2012/smooth-e2"))


CONVERSIONS = ("material:nickel@ngan2005/ward", "material:alum-bronze@ngan2005/ward",
               "material:gold-metallic-paint@low2012/smooth-e2")
#: The warm-up conversion of :func:`conversions` (not one of :data:`CONVERSIONS`).
WARM_UP = "material:blue-acrylic@ngan2005/ward"


def conversions():
    import mitsuba  # noqa: F401  (imported before the timings)

    # warm-up: a published fit not measured below, to each target, so that the families' kernels are
    # compiled (a Lambertian compiles none of them) and the first row is not the only one paying for it
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for to in ("mitsuba", "gltf"):
            plausible.convert(WARM_UP, to=to)
    print("| source | to | chosen | CPU s | wall s |\n|---|---|---|---|---|")
    for spec in CONVERSIONS:
        for to in ("mitsuba", "gltf"):
            t0, c0 = time.time(), time.process_time()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                c = plausible.convert(spec, to=to)
            print(f"| {spec} | {to} | {c.items[0].target} | {time.process_time() - c0:.1f} | "
                  f"{time.time() - t0:.1f} |", flush=True)


def _median_cpu(fn, repeats):
    """``(last result, median CPU seconds)`` of ``repeats`` calls of ``fn() -> (result, seconds)``."""
    out = [fn() for _ in range(repeats)]
    return out[-1][0], float(np.median([t for _, t in out]))


def before(src, repeats, metric="l2-cos"):
    """The median CPU seconds and evaluations of ``plausible.fit`` under ``metric`` per case,
    measured by the code under ``src`` (another checkout's ``src``) in a child process, one BLAS
    thread."""
    import json
    import os
    import subprocess
    import sys

    env = dict(os.environ, PYTHONPATH=src)
    out = subprocess.run([sys.executable, __file__, "--ours-only", str(repeats), metric], env=env, check=True,
                         capture_output=True, text=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def ours_only(repeats, metric="l2-cos"):
    import json

    res = {}
    with threadpool_limits(limits=1, user_api="blas"):
        for name, spec in (CASES if metric == "l2-cos" else PERCEPTUAL):
            tgt = as_target(spec)
            ours(name, tgt, "population", metric)
            r, t = _median_cpu(lambda: ours(name, tgt, "population", metric), repeats)
            res[name] = (t, r.evaluations, r.errors[metric])
    print(json.dumps(res))


def perceptual(repeats, src):
    """``--perceptual``: the median CPU seconds of the perceptual fits, this checkout's and
    (``--before``) another's."""
    import json
    import io
    from contextlib import redirect_stdout

    buf = io.StringIO()
    with redirect_stdout(buf):
        ours_only(repeats, "perceptual")
    new = json.loads(buf.getvalue().strip().splitlines()[-1])
    old = before(src, repeats, "perceptual") if src else None
    print(f"median CPU s of {repeats} runs each\n| model | target | plausible.fit perceptual: CPU s (evaluations), "
          "figure |" + (" before: CPU s (evaluations), figure |" if old else "") + "\n|---|---|---|" + ("---|" if old else ""))
    for name, spec in PERCEPTUAL:
        t, n, e = new[name]
        row = f"| {name} | {spec} | {t:.2f} ({n}), {e:.6g} |"
        if old:
            t, n, e = old[name]
            row += f" {t:.2f} ({n}), {e:.6g} |"
        print(row)


def main():
    import sys

    args = sys.argv[1:]
    if "--convert" in args:
        return conversions()
    if "--ours-only" in args:
        k = args.index("--ours-only")
        return ours_only(int(args[k + 1]), args[k + 2] if len(args) > k + 2 else "l2-cos")
    repeats = int(args[args.index("--repeats") + 1]) if "--repeats" in args else 7
    if "--perceptual" in args:
        return perceptual(repeats, args[args.index("--before") + 1] if "--before" in args else None)
    old = before(args[args.index("--before") + 1], repeats) if "--before" in args else None
    print(f"median CPU s of {repeats} runs each")
    print("| model | target | plain least_squares: CPU s (evaluations), l2-cos | plausible.fit: CPU s (evaluations), "
          "l2-cos | ratio |" + (" before (--before): CPU s (evaluations), l2-cos | ratio |" if old else ""))
    print("|---|---|---|---|---|" + ("---|---|" if old else ""))
    with threadpool_limits(limits=1, user_api="blas"):
        for name, spec in CASES:
            tgt = as_target(spec)
            ours(name, tgt, "population")          # warm: the kernel cache, imports
            runs = [(plain(name, tgt), ours(name, tgt, "population")) for _ in range(repeats)]   # interleaved
            (_, e0, _, n0), r1 = runs[-1][0], runs[-1][1][0]
            t0 = float(np.median([p[2] for p, _ in runs]))
            t1 = float(np.median([o[1] for _, o in runs]))
            row = (f"| {name} | {spec} | {t0:.3f} ({n0}), {e0:.5g} | {t1:.3f} ({r1.evaluations}), "
                   f"{r1.errors['l2-cos']:.5g} | {t1 / t0:.2f} |")
            if old:
                tb, nb, eb = old[name]
                row += f" {tb:.3f} ({nb}), {eb:.5g} | {tb / t0:.2f} |"
            print(row, flush=True)


if __name__ == "__main__":
    main()
