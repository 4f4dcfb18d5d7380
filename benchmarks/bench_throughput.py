"""Throughput of ``eval``, ``pdf`` and ``sample`` on N = 10^6 random pairs.

Backends, side by side in one process:

* ``numpy``   -- the NumPy contract ``model.eval/pdf/sample`` on its NumPy backend
  (``backend="numpy"``: float64, one thread);
* ``api-drjit`` -- the same NumPy-facing calls on the Dr.Jit backend
  (``backend="drjit"``: NumPy in, NumPy out, the hooks on ``drjit.llvm.Float64``;
  validation and conversion included);
* ``drjit``   -- the model's hooks ``_f``, ``_pdf``, ``_sample`` (+ ``_pdf``, ``_f``
  for the weight, as the plugin does) on ``mi.Float`` (Dr.Jit LLVM, float32),
  colours as ``mi.Color3f``;
* ``mitsuba`` -- the plausible plugin called through Mitsuba's BSDF interface
  (``bsdf.eval/pdf/sample`` with a ``SurfaceInteraction3f``);
* ``reference`` -- Mitsuba 3's built-in compiled ``roughconductor`` (Beckmann,
  alpha 0.1) through the same interface: the compiled reference of the ratios.

Dr.Jit runs are forced with ``dr.eval`` + ``dr.sync_thread``; each benchmark's
first call (tracing + LLVM compilation or kernel-cache load) is timed once,
separately, before the steady-state rounds.
"""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

import plausible
from conftest import N, ROUNDS, first_call, record, traced_peak

MODELS = plausible.names()
OPS = ("eval", "pdf", "sample")
REFERENCE = {"type": "roughconductor", "distribution": "beckmann", "alpha": 0.1}


def pedantic(benchmark, fn, warm=False):
    benchmark.pedantic(fn, rounds=ROUNDS, iterations=1, warmup_rounds=1 if warm else 0)


# -- NumPy -------------------------------------------------------------------------

@pytest.mark.parametrize("op", OPS)
@pytest.mark.parametrize("name", MODELS)
def test_numpy(benchmark, pairs, name, op):
    m = plausible.make(name)
    wi, wo, u = pairs
    fn = {"eval": lambda: m.eval(wi, wo, backend="numpy"), "pdf": lambda: m.pdf(wi, wo, backend="numpy"),
          "sample": lambda: m.sample(wi, u, backend="numpy")}[op]
    record(benchmark, f"throughput-{op}", name, backend="numpy", op=op, n=N,
           peak_bytes=traced_peak(fn))
    pedantic(benchmark, fn)


@pytest.mark.drjit
@pytest.mark.parametrize("op", OPS)
@pytest.mark.parametrize("name", MODELS)
def test_api_drjit(benchmark, pairs, name, op):
    """The NumPy-facing API on the Dr.Jit float64 backend (what ``auto`` picks for
    these batches when Dr.Jit is installed)."""
    from plausible.arrays import backend

    if not backend.drjit_available():
        pytest.skip("Dr.Jit LLVM backend unavailable")
    m = plausible.make(name)
    wi, wo, u = pairs
    fn = {"eval": lambda: m.eval(wi, wo, backend="drjit"), "pdf": lambda: m.pdf(wi, wo, backend="drjit"),
          "sample": lambda: m.sample(wi, u, backend="drjit")}[op]
    record(benchmark, f"throughput-{op}", name, backend="api-drjit", op=op, n=N, first_call_s=first_call(fn))
    pedantic(benchmark, fn)


# -- Dr.Jit (LLVM) -------------------------------------------------------------------

def dr_inputs(mi, pairs):
    import drjit as dr

    wi, wo, u = pairs
    comp = [tuple(mi.Float(np.ascontiguousarray(a[:, k], dtype=np.float32)) for k in range(3))
            for a in (wi, wo, u)]
    dr.eval(*comp[0], *comp[1], *comp[2])
    return comp


def dr_params(mi, model):
    return SimpleNamespace(**{k: (mi.Color3f(*[float(x) for x in v]) if isinstance(v, np.ndarray) else v)
                              for k, v in vars(model.p).items()})


def dr_run(mi, outs):
    import drjit as dr

    dr.eval(*outs)
    dr.sync_thread()


@pytest.mark.drjit
@pytest.mark.parametrize("op", OPS)
@pytest.mark.parametrize("name", MODELS)
def test_drjit_hooks(benchmark, mi, pairs, name, op):
    import drjit as dr

    from plausible.arrays.ops import drjit_ops

    ops = drjit_ops(mi.Float)
    m = plausible.make(name)
    p, q = dr_params(mi, m), m.q
    wi, wo, u = dr_inputs(mi, pairs)

    def sample():
        w = m._sample(ops, wi, u, q)
        w = tuple(mi.Float(c) for c in w)
        pdf = mi.Float(m._pdf(ops, wi, w, q))
        f = m._f(ops, wi, w, p)
        ok = (pdf > 0) & (w[2] > 0)
        return (*w, pdf, dr.select(ok, f * (w[2] / dr.select(ok, pdf, 1.0)), 0.0))

    fn = {"eval": lambda: dr_run(mi, [m._f(ops, wi, wo, p)]),
          "pdf": lambda: dr_run(mi, [m._pdf(ops, wi, wo, q)]),
          "sample": lambda: dr_run(mi, sample())}[op]
    record(benchmark, f"throughput-{op}", name, backend="drjit", op=op, n=N, first_call_s=first_call(fn))
    pedantic(benchmark, fn)


# -- through Mitsuba's BSDF interface -------------------------------------------------

def mi_setup(mi, pairs):
    import drjit as dr

    wi, wo, u = pairs

    def vec3(a):
        return mi.Vector3f(np.ascontiguousarray(a.T, dtype=np.float32))

    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec3(wi)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    wo_m = vec3(wo)
    s1 = mi.Float(np.ascontiguousarray(u[:, 0], dtype=np.float32))
    s2 = mi.Point2f(np.ascontiguousarray(u[:, 1:].T, dtype=np.float32))
    dr.eval(si, wo_m, s1, s2)
    return mi.BSDFContext(), si, wo_m, s1, s2


def mi_ops(mi, bsdf, pairs):
    ctx, si, wo, s1, s2 = mi_setup(mi, pairs)
    return {"eval": lambda: dr_run(mi, [bsdf.eval(ctx, si, wo)]),
            "pdf": lambda: dr_run(mi, [bsdf.pdf(ctx, si, wo)]),
            "sample": lambda: dr_run(mi, list(bsdf.sample(ctx, si, s1, s2)))}


@pytest.mark.drjit
@pytest.mark.parametrize("op", OPS)
@pytest.mark.parametrize("name", MODELS)
def test_mitsuba_plugin(benchmark, mi, pairs, name, op):
    import plausible.mitsuba as pm

    plugin = {v: k for k, v in pm.plugin_names().items() if k != "phong"}[name]
    fn = mi_ops(mi, mi.load_dict({"type": plugin}), pairs)[op]
    record(benchmark, f"throughput-{op}", name, backend="mitsuba", op=op, n=N, first_call_s=first_call(fn))
    pedantic(benchmark, fn)


@pytest.mark.drjit
@pytest.mark.parametrize("op", OPS)
def test_mitsuba_roughconductor(benchmark, mi, pairs, op):
    fn = mi_ops(mi, mi.load_dict(REFERENCE), pairs)[op]
    record(benchmark, f"throughput-{op}", "roughconductor", backend="reference", op=op, n=N,
           first_call_s=first_call(fn))
    pedantic(benchmark, fn)
