"""Shared set-up of the benchmark suite (``make bench``; pytest-benchmark).

Not collected by the default test run (``testpaths`` is ``tests``).  Every
benchmark records what the report needs in ``benchmark.extra_info``:
``group`` (a table), ``case`` (a row), ``backend``, ``op``, ``n`` (directions
per call) and, where measured, ``peak_bytes`` (see docs/benchmarks.md) and
``first_call_s`` (Dr.Jit: tracing + kernel compilation or cache load).
``benchmarks/report.py`` turns the JSON into the tables of docs/benchmarks.md.
"""

from __future__ import annotations

import os
import time
import tracemalloc

import numpy as np
import pytest

#: Directions per throughput call (the issue's 10^6 random pairs);
#: ``PLAUSIBLE_BENCH_N`` overrides it for a quick run.
N = int(os.environ.get("PLAUSIBLE_BENCH_N", 1_000_000))
#: Rounds per throughput benchmark (each round is one call on N pairs).
ROUNDS = int(os.environ.get("PLAUSIBLE_BENCH_ROUNDS", 5))


def upper_dirs(rng, n, zmin=0.01):
    """``n`` random unit vectors, uniform on the upper hemisphere with ``z >= zmin``,
    exactly representable in float32 (so both precisions see the same directions)."""
    v = rng.normal(size=(n, 3))
    v[:, 2] = np.maximum(np.abs(v[:, 2]), zmin)
    v = (v / np.linalg.norm(v, axis=1, keepdims=True)).astype(np.float32).astype(np.float64)
    return v / np.linalg.norm(v, axis=1, keepdims=True)


@pytest.fixture(scope="session")
def pairs():
    """``(wi, wo, u)``: N fixed-seed random direction pairs and uniform numbers."""
    rng = np.random.default_rng(2024)
    return upper_dirs(rng, N), upper_dirs(rng, N), rng.random((N, 3))


@pytest.fixture(scope="session")
def mi():
    """Mitsuba 3 in ``llvm_ad_rgb`` with every plausible plugin registered."""
    mitsuba = pytest.importorskip("mitsuba")
    try:
        mitsuba.set_variant("llvm_ad_rgb")
    except (ImportError, AttributeError, RuntimeError) as e:  # pragma: no cover
        pytest.skip(f"no LLVM variant: {e}")
    import plausible.mitsuba as pm

    pm.register("llvm_ad_rgb")
    return mitsuba


def traced_peak(fn):
    """Peak bytes traced by tracemalloc while ``fn()`` runs (NumPy reports its
    buffers to tracemalloc), above what was allocated before the call."""
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        fn()
        return tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()


def first_call(fn):
    """Seconds of one call of ``fn`` (for Dr.Jit, the first call: tracing plus
    compilation, or a load from Dr.Jit's kernel cache)."""
    t0 = time.perf_counter()
    fn()
    return time.perf_counter() - t0


def record(benchmark, group, case, **info):
    benchmark.group = group
    benchmark.extra_info.update(group=group, case=case, **info)
