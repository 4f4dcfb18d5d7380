"""Chunked evaluation of the NumPy contract (``plausible.directions.CHUNK``).

Batches of more than ``CHUNK`` direction pairs are processed ``CHUNK`` pairs at
a time into preallocated outputs.  The truth here is the unchunked evaluation
of the same batch (CHUNK larger than the batch): the results must be *bitwise*
equal, the errors identical, and the peak memory of a chunked batch must not
grow with the batch beyond its outputs.
"""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import plausible
import plausible.directions as bx
from conftest import random_upper

#: Scalar and colour models, isotropic and anisotropic, analytic and tabulated.
MODELS = [
    ("ashikhmin-shirley", dict(nu=10.0, nv=300.0, rs=[0.05, 0.3, 0.9], rd=[0.5, 0.2, 0.1])),
    ("ashikhmin-shirley-specular", dict(nu=50.0, nv=50.0)),
    ("modified-phong", dict(kd=[0.3, 0.4, 0.5], ks=[0.3, 0.2, 0.1], n=30.0)),
    ("ward", {}),
    ("lafortune", {}),
    ("neumann-metal", {}),
    ("phong", {}),
]

SMALL = 1000          # CHUNK used for the equality tests
N = 4 * SMALL + 123   # several chunks and a partial last one


def upper(rng, shape):
    """Random upper-hemisphere directions (:func:`conftest.random_upper`) of non-unit lengths."""
    v = random_upper(rng, int(np.prod(shape))).reshape(shape + (3,))
    return v * rng.uniform(0.5, 2.0, size=shape + (1,))   # non-unit lengths


def run_all(m, wi, wo, u):
    s = m.sample(wi, u)
    s1 = m.sample(wi[0], u)
    return [m.eval(wi, wo), m.pdf(wi, wo), s.wo, s.weight, s.pdf,
            m.eval(wi[0], wo), m.pdf(wo, wi[0]), s1.wo, s1.weight, s1.pdf]


@pytest.mark.parametrize("name,params", MODELS, ids=[m[0] for m in MODELS])
def test_chunked_equals_unchunked(name, params, monkeypatch):
    """eval, pdf and sample (batch against batch, and one wi against a batch) give
    bitwise the same arrays, shapes included, with CHUNK = 1000 as with no chunking."""
    m = plausible.make(name, **params)
    rng = np.random.default_rng(3)
    wi, wo, u = upper(rng, (N,)), upper(rng, (N,)), rng.random((N, 3))
    u[::97] = 1.0  # the closed end of [0, 1]
    ref = run_all(m, wi, wo, u)
    monkeypatch.setattr(bx, "CHUNK", SMALL)
    got = run_all(m, wi, wo, u)
    for r, g in zip(ref, got):
        assert r.shape == g.shape
        np.testing.assert_array_equal(g, r)
    if m.channels:
        assert ref[0].shape == (N, m.channels)


def test_chunked_broadcast_that_cannot_be_flattened_as_a_view(monkeypatch):
    """(A, 1, 3) against (1, B, 3): the broadcast (A, B, 3) is read row block by
    row block (a gather, not a view); the result equals the unchunked one and
    the (A, B, C) reference computed pair by pair."""
    m = plausible.make("ashikhmin-shirley", nu=20.0, nv=200.0, rs=[0.1, 0.2, 0.3])
    rng = np.random.default_rng(5)
    a, b = upper(rng, (70, 1)), upper(rng, (1, 90))
    ref = m.eval(a, b)
    monkeypatch.setattr(bx, "CHUNK", 1000)
    got = m.eval(a, b)
    np.testing.assert_array_equal(got, ref)
    assert got.shape == (70, 90, 3)
    np.testing.assert_array_equal(got[17, 41], m.eval(a[17, 0], b[0, 41]))
    w, uu = plausible.make("ward"), rng.random((1, 90, 3))
    s_chunked = w.sample(a, uu)
    monkeypatch.setattr(bx, "CHUNK", 1 << 20)
    s_whole = w.sample(a, uu)
    assert s_chunked.wo.shape == (70, 90, 3)
    for g, r in zip(s_chunked, s_whole):
        np.testing.assert_array_equal(g, r)


@pytest.mark.parametrize("call,message", [
    (lambda m, wi, wo, u: m.eval(wi, wo), "wi must be finite"),
    (lambda m, wi, wo, u: m.pdf(wo, wi), "wi must be non-zero vectors"),
    (lambda m, wi, wo, u: m.pdf(np.where(np.isnan(wi), wi, wo), wi), "wi must be finite"),
    (lambda m, wi, wo, u: m.sample(wi, u), "wi must be finite"),
])
def test_errors_are_those_of_the_whole_batch(call, message, monkeypatch):
    """A NaN in the last chunk of ``wi``, a zero vector in the first chunk of
    ``wo``: the error is the one of the unchunked batch -- all of the first
    argument is checked before the second, and within one argument a NaN
    anywhere is reported before a zero vector anywhere (last case: both in one
    argument, the zero vector in an earlier chunk)."""
    m = plausible.make("modified-phong")
    rng = np.random.default_rng(1)
    wi, wo, u = upper(rng, (N,)), upper(rng, (N,)), rng.random((N, 3))
    wi[-1, 0] = np.nan
    wo[0] = 0.0
    u[0, 1] = 1.5
    with pytest.raises(ValueError, match=message):
        call(m, wi, wo, u)
    monkeypatch.setattr(bx, "CHUNK", SMALL)
    with pytest.raises(ValueError, match=message):
        call(m, wi, wo, u)


def test_errors_in_a_late_chunk_are_found(monkeypatch):
    """Bad values only in the last chunk still raise (zero vector, u outside [0, 1])."""
    monkeypatch.setattr(bx, "CHUNK", SMALL)
    m = plausible.make("lambertian")
    rng = np.random.default_rng(2)
    wi, wo, u = upper(rng, (N,)), upper(rng, (N,)), rng.random((N, 3))
    wo[-1] = 0.0
    with pytest.raises(ValueError, match="wo must be non-zero vectors"):
        m.eval(wi, wo)
    u[-1, 2] = -1e-9
    with pytest.raises(ValueError, match=r"u must lie in \[0, 1\]"):
        m.sample(wi, u)


# -- memory ------------------------------------------------------------------------

MEM_CHUNK = 1 << 14


def peak_bytes(fn):
    """Peak of traced allocations (NumPy reports its buffers to tracemalloc) while
    ``fn()`` runs, above what was allocated before; the result is released after."""
    tracemalloc.start()
    try:
        base = tracemalloc.get_traced_memory()[0]
        tracemalloc.reset_peak()
        out = fn()
        peak = tracemalloc.get_traced_memory()[1] - base
    finally:
        tracemalloc.stop()
    return peak, out


def result_bytes(out):
    return sum(a.nbytes for a in (out if isinstance(out, tuple) else (out,)))


def chunk_overhead_ok(fn_at, n_big, chunk, monkeypatch):
    """Peak of a batch of ``n_big`` pairs with ``CHUNK = chunk`` is at most its
    outputs plus 1.25x the whole peak of one batch of ``chunk`` pairs (the
    temporaries of one chunk)."""
    monkeypatch.setattr(bx, "CHUNK", chunk)
    one, _ = peak_bytes(lambda: fn_at(MEM_CHUNK))
    big, out = peak_bytes(lambda: fn_at(n_big))
    return big <= result_bytes(out) + 1.25 * one, (big, result_bytes(out), one)


def mem_cases():
    rng = np.random.default_rng(4)
    n = 4 * MEM_CHUNK
    wi, wo, u = upper(rng, (n,)), upper(rng, (n,)), rng.random((n, 3))
    a_s = plausible.make("ashikhmin-shirley", nu=10.0, nv=300.0, rs=[0.05, 0.3, 0.9], rd=[0.5, 0.2, 0.1])
    ward = plausible.make("ward")
    return {
        "eval-colour": lambda k: a_s.eval(wi[:k], wo[:k]),
        "pdf": lambda k: ward.pdf(wi[:k], wo[:k]),
        "sample-colour": lambda k: tuple(a_s.sample(wi[:k], u[:k])),
        "eval-one-wi": lambda k: ward.eval(wi[0], wo[:k]),
    }


@pytest.mark.parametrize("case", ["eval-colour", "pdf", "sample-colour", "eval-one-wi"])
def test_peak_memory_is_outputs_plus_one_chunk(case, monkeypatch):
    """N = 4 CHUNK pairs: peak traced memory <= outputs + 1.25 x (peak of one chunk)."""
    fn = mem_cases()[case]
    ok, numbers = chunk_overhead_ok(fn, 4 * MEM_CHUNK, MEM_CHUNK, monkeypatch)
    assert ok, numbers


@pytest.mark.parametrize("case", ["eval-colour", "sample-colour"])
def test_memory_bound_detects_unchunked_evaluation(case, monkeypatch):
    """The same bound fails when chunking is off (CHUNK = N): temporaries grow with N."""
    fn = mem_cases()[case]
    ok, numbers = chunk_overhead_ok(fn, 4 * MEM_CHUNK, 4 * MEM_CHUNK, monkeypatch)
    assert not ok, numbers
