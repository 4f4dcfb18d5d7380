"""Peak memory against batch size (NumPy, chunked) and peak RSS of Dr.Jit /
Mitsuba calls (one subprocess per case, ``ru_maxrss`` after the call minus
before it).  The 10^8-direction run is opt-in: ``PLAUSIBLE_BENCH_1E8=1``.

Run a case alone: ``python benchmarks/bench_memory.py CASE N``.
"""

from __future__ import annotations

import json
import os
import resource
import subprocess
import sys

import numpy as np
import pytest

HERE = os.path.dirname(os.path.abspath(__file__))


def _maxrss():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def probe(case: str, n: int) -> dict:
    """Run ``case`` on ``n`` pairs in this process; RSS high-water mark before and after."""
    rng = np.random.default_rng(0)
    if case == "numpy-eval-1wi":
        import plausible

        m = plausible.make("ashikhmin-shirley")
        wo = np.empty((n, 3))
        for s in range(0, n, 1 << 22):   # inputs written in blocks: no temporaries
            e = min(n, s + (1 << 22))
            wo[s:e] = rng.normal(size=(e - s, 3))
            np.abs(wo[s:e, 2], out=wo[s:e, 2])
        before = _maxrss()
        out = m.eval([0.3, 0.0, 0.95], wo)
        return {"before": before, "after": _maxrss(), "inputs": wo.nbytes, "output": out.nbytes}
    import drjit as dr
    import mitsuba as mi

    mi.set_variant("llvm_ad_rgb")
    import plausible.mitsuba as pm

    pm.register("llvm_ad_rgb")
    bsdf = mi.load_dict({"type": case} if case != "roughconductor"
                        else {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1})
    v = rng.normal(size=(3, n)).astype(np.float32)
    v[2] = np.abs(v[2])
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = dr.normalize(mi.Vector3f(v))
    wo = dr.normalize(mi.Vector3f(v[::-1].copy()))
    dr.eval(si, wo)
    before = _maxrss()
    out = bsdf.eval(mi.BSDFContext(), si, wo)
    dr.eval(out)
    dr.sync_thread()
    return {"before": before, "after": _maxrss(), "inputs": 0, "output": 4 * 3 * n}


def run_probe(case, n):
    r = subprocess.run([sys.executable, os.path.join(HERE, "bench_memory.py"), case, str(n)],
                       capture_output=True, text=True, check=True)
    return json.loads(r.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("n", [10**5, 10**6, 4 * 10**6, 16 * 10**6])
def test_numpy_memory_vs_batch(benchmark, n):
    """Traced peak of ``eval`` (colour A-S, one wi against n wo): output + O(CHUNK)."""
    import plausible
    from conftest import record, traced_peak

    m = plausible.make("ashikhmin-shirley", rs=[0.05, 0.3, 0.9])
    rng = np.random.default_rng(1)
    wo = rng.normal(size=(n, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wi = np.array([0.3, 0.0, 0.95])
    peak = traced_peak(lambda: m.eval(wi, wo))
    record(benchmark, "memory", f"numpy eval, n={n:.0e}", backend="numpy", op="eval", n=n,
           peak_bytes=peak, output_bytes=n * 3 * 8)
    benchmark.pedantic(lambda: m.eval(wi, wo), rounds=1, iterations=1)


@pytest.mark.drjit
@pytest.mark.parametrize("case", ["ashikhmin_shirley", "roughconductor"])
def test_mitsuba_eval_rss(benchmark, case):
    """Peak RSS increase of one Mitsuba ``eval`` on 10^6 pairs (own process)."""
    from conftest import record

    r = benchmark.pedantic(lambda: run_probe(case, 10**6), rounds=1, iterations=1)
    record(benchmark, "memory", f"mitsuba eval 1e6 ({case})", backend="mitsuba", op="eval", n=10**6,
           peak_bytes=r["after"] - r["before"], output_bytes=r["output"])


@pytest.mark.skipif(not os.environ.get("PLAUSIBLE_BENCH_1E8"), reason="opt-in: PLAUSIBLE_BENCH_1E8=1")
def test_numpy_1e8(benchmark):
    """10^8 directions through the NumPy ``eval`` (chunked): peak RSS increase of the call."""
    from conftest import record

    n = 10**8
    r = benchmark.pedantic(lambda: run_probe("numpy-eval-1wi", n), rounds=1, iterations=1)
    record(benchmark, "memory", "numpy eval 1e8 (subprocess RSS)", backend="numpy", op="eval", n=n,
           peak_bytes=r["after"] - r["before"], output_bytes=r["output"], input_bytes=r["inputs"])


if __name__ == "__main__":
    print(json.dumps(probe(sys.argv[1], int(sys.argv[2]))))
