"""Analysis at the backend ``auto`` picks (Dr.Jit float64 when installed) and, for
the albedo curve and ``check --quick``, on NumPy alone for comparison: a 90-angle
albedo curve (error bound <= 1e-6), ``plausible check`` (quick and full), the
pumped-up 2-D albedo table of an anisotropic base, the perceptual fit of
docs/fitting.md, one small fit, and the first call (trace + compile) with a cold
and a warm Dr.Jit kernel cache.  Peak memory by tracemalloc (one extra call)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile

import numpy as np
import pytest

import plausible
from conftest import record, traced_peak

AS = dict(nu=10.0, nv=100.0, rs=0.05, rd=0.5)   # anisotropic: the harder albedo integral
BACKENDS = ("numpy", "auto")


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name,params", [("ashikhmin-shirley", AS), ("ward", {}),
                                         ("modified-phong", {})],
                         ids=["ashikhmin-shirley", "ward", "modified-phong"])
def test_albedo_curve_90(benchmark, name, params, backend):
    """Directional albedo at 90 incidence angles in [0, 89] degrees, each to an
    error bound of 1e-6 (the default ``tol``); ``max_error`` is the largest bound."""
    m = plausible.make(name, **params)
    thetas = np.radians(np.linspace(0.0, 89.0, 90))
    with plausible.use_backend(backend):
        res = plausible.albedo_curve(m, thetas, tol=1e-6)
        record(benchmark, "analysis", f"albedo curve, 90 angles ({name})", backend=backend, op="albedo",
               n=90, max_error=float(np.max(res.error)),
               peak_bytes=traced_peak(lambda: plausible.albedo_curve(m, thetas, tol=1e-6)))
        benchmark.pedantic(lambda: plausible.albedo_curve(m, thetas, tol=1e-6), rounds=2, iterations=1)


@pytest.mark.parametrize("backend", BACKENDS)
def test_check_quick(benchmark, backend):
    """``plausible.check(model, quick=True)`` of Ashikhmin-Shirley (anisotropic)."""
    m = plausible.make("ashikhmin-shirley", **AS)
    with plausible.use_backend(backend):
        rep = plausible.check(m, quick=True)
        record(benchmark, "analysis", "check --quick (ashikhmin-shirley)", backend=backend, op="check", n=1,
               agrees=bool(rep.passed), peak_bytes=traced_peak(lambda: plausible.check(m, quick=True)))
        benchmark.pedantic(lambda: plausible.check(m, quick=True), rounds=2, iterations=1)


def test_check_full(benchmark):
    """``plausible.check(model)`` (full) of Ashikhmin-Shirley (anisotropic)."""
    m = plausible.make("ashikhmin-shirley", **AS)
    rep = plausible.check(m)
    record(benchmark, "analysis", "check, full (ashikhmin-shirley)", backend="auto", op="check", n=1,
           agrees=bool(rep.passed))
    benchmark.pedantic(lambda: plausible.check(m), rounds=1, iterations=1)


def test_pumped_up_table_2d(benchmark, monkeypatch):
    """The 2-D albedo table (theta x 32 azimuths) of an anisotropic base, built
    from scratch (no disk cache, no memory cache)."""
    from plausible.integrals import cache

    monkeypatch.setenv("PLAUSIBLE_CACHE_DIR", "")
    base = "ashikhmin-shirley-specular:nu=10:nv=200:rs=1"

    def run():
        cache._TABLES.clear()
        return plausible.make("pumped-up", base=base).tables[0]

    tab = run()
    record(benchmark, "analysis", "pumped-up 2-D albedo table (A-S specular nu=10 nv=200)", backend="auto",
           op="table", n=int(tab.values.size), shape=list(tab.values.shape))
    benchmark.pedantic(run, rounds=1, iterations=1)


def test_fit_perceptual(benchmark):
    """The perceptual fit of docs/fitting.md: Ashikhmin-Shirley to Cook-Torrance
    (m = 0.2, rs = 0.9), default starts."""
    def run():
        return plausible.fit("ashikhmin-shirley", "cook-torrance:m=0.2:rs=0.9", metric="perceptual")

    res = run()
    record(benchmark, "analysis", "fit, perceptual (ashikhmin-shirley to cook-torrance, docs/fitting.md)",
           backend="auto", op="fit", n=1, evaluations=int(res.evaluations),
           result=str(res.params), perceptual=float(res.errors.get("perceptual", float("nan"))))
    benchmark.pedantic(run, rounds=1, iterations=1)


def test_fit_one(benchmark):
    """One fit: isotropic Ashikhmin-Shirley (specular term) to Ward (alpha 0.2),
    l2-cos metric, one optimiser start."""
    def run():
        return plausible.fit("ashikhmin-shirley-specular", "ward:alpha_x=0.2:alpha_y=0.2:rd=0:rs=0.5",
                             metric="l2-cos", starts=1, seed=0)

    res = run()
    record(benchmark, "analysis", "fit (ashikhmin-shirley-specular to ward, 1 start)", backend="auto",
           op="fit", n=1, peak_bytes=traced_peak(run), result=str(getattr(res, "params", "")))
    benchmark.pedantic(run, rounds=2, iterations=1)


FIRST_CALL = """
import json, time, numpy as np, plausible
rng = np.random.default_rng(0)
v = rng.normal(size=(2, 10 ** 6, 3)); v[..., 2] = np.abs(v[..., 2])
m = plausible.make("ashikhmin-shirley", nu=10, nv=100)
out = {}
for name, fn in (("eval 10^6", lambda: m.eval(v[0], v[1], backend="drjit")),
                 ("albedo curve 90", lambda: plausible.albedo_curve(m, np.radians(np.arange(90.0))))):
    t0 = time.perf_counter(); fn(); t1 = time.perf_counter(); fn(); t2 = time.perf_counter()
    out[name] = [t1 - t0, t2 - t1]
print(json.dumps(out))
"""


@pytest.mark.drjit
def test_first_call(benchmark):
    """First and second call in a fresh process, with Dr.Jit's on-disk kernel
    cache empty (a new ``HOME``) and then filled by that first process: tracing
    + LLVM compilation, then a cache load, then a warm call."""
    from plausible.arrays import backend

    if not backend.drjit_available():
        pytest.skip("Dr.Jit LLVM backend unavailable")
    res = {}
    with tempfile.TemporaryDirectory() as home:
        env = dict(os.environ, HOME=home, PYTHONPATH=os.pathsep.join(sys.path))
        for label in ("cold disk cache", "warm disk cache"):
            r = subprocess.run([sys.executable, "-c", FIRST_CALL], env=env, capture_output=True, text=True,
                               check=True)
            res[label] = json.loads(r.stdout.strip().splitlines()[-1])
    record(benchmark, "first-call", "A-S nu=10 nv=100: [first, second] call s", backend="api-drjit",
           op="first", n=1, **{k: json.dumps(v) for k, v in res.items()})
    benchmark.pedantic(lambda: None, rounds=1, iterations=1)
