"""The symbolic backend: a trace computes what the NumPy backend computes, and
formulas that a shader cannot follow are refused."""

from __future__ import annotations

import numpy as np
import pytest

import plausible
from plausible.arrays import symbolic
from plausible.analysis.suite import variants
from plausible.export.shader import _symbolic_params, uniform_params
from plausible.models.lambert import Lambertian
from plausible.models.phong import ModifiedPhong
from plausible.arrays.symbolic import SYM, SymbolicBranchError

WI, WO = symbolic.direction("wi"), symbolic.direction("wo")


def _pairs(n=500, seed=2):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=(2, n, 3))
    v[..., 2] = np.abs(v[..., 2])
    v[1, : n // 10, 2] *= -1  # some below the horizon
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _env(wi, wo, m, specs):
    env = {f"{d}.{c}": a[:, k] for d, a in (("wi", wi), ("wo", wo)) for k, c in enumerate("xyz")}
    for s in specs:
        v = np.broadcast_to(m.params[s.name], 3) if s.kind == "color" else m.params[s.name]
        if s.kind == "color":
            env.update({f"{s.name}.{c}": float(v[k]) for k, c in enumerate("xyz")})
        else:
            env[s.name] = float(v)
    return env


CASES = [pytest.param(n, kw, u, id=f"{n}-{kw}-{'uniforms' if u else 'baked'}")
         for n in plausible.names() for kw in variants(n, 2) for u in (False, True)]


@pytest.mark.parametrize("name, kw, uniforms", CASES)
def test_trace_of_f_equals_the_numpy_backend(name, kw, uniforms):
    m = plausible.make(name, **kw)
    specs = uniform_params(m, uniforms)
    p, _ = _symbolic_params(m, specs)
    graph = symbolic.trace(lambda: m._f(SYM, WI, WO, p))
    wi, wo = _pairs()
    got = np.asarray(symbolic.evaluate(graph, _env(wi, wo, m, specs)), dtype=float)
    ref = m.eval(wi, wo)
    if got.ndim == 2 and ref.ndim == 1:  # colour uniforms of a grey model: equal channels
        ref = ref[:, None]
    np.testing.assert_allclose(*np.broadcast_arrays(got, ref), rtol=1e-10, atol=1e-300)


def test_a_python_if_on_a_direction_is_refused():
    with pytest.raises(SymbolicBranchError, match=r"wi\.z"):
        if WI[2] > 0:
            pass


def test_a_model_with_a_python_if_cannot_be_exported():
    """A deliberately broken model: its f branches in Python on wi.z (NumPy would
    fail on arrays too; a trace must not silently export one branch)."""
    class Broken(Lambertian):
        def _f(self, ops, wi, wo, p):
            return p.rd / np.pi if wi[2] > 0 else 0.0

    from plausible.export import to_glsl

    with pytest.raises(ValueError, match=r"_f cannot be exported.*depends on the directions"):
        to_glsl(Broken())


class _BranchingPhong(ModifiedPhong):
    """Modified Phong with its sampling weight as a Python ``if`` on parameters,
    ``ks / (kd + ks) if kd + ks > 0 else 0.5`` (the library's own is an
    ``ops.where`` since parameters became kernel data)."""

    @staticmethod
    def spec_probability(ops, q):
        s = q.kd + q.ks
        return q.ks / s if s > 0 else 0.5


def test_a_branch_on_a_parameter_exports_both_outcomes():
    """A Python if on parameters: as uniforms both outcomes are kept, and the graph
    equals NumPy's pdf on either side of the branch."""
    m = _BranchingPhong()
    specs = uniform_params(m, True)
    _, q = _symbolic_params(m, specs)
    graph = symbolic.trace(lambda: m._pdf(SYM, WI, WO, q))
    wi, wo = _pairs()
    for kd, ks in ((0.5, 0.2), (0.0, 0.0)):
        other = plausible.make("modified-phong", kd=kd, ks=ks)
        got = symbolic.evaluate(graph, _env(wi, wo, other, specs))
        np.testing.assert_allclose(got, other.pdf(wi, wo), rtol=1e-12, atol=1e-300)


def test_a_branch_on_a_parameter_names_it_when_not_explored():
    m = _BranchingPhong()
    _, q = _symbolic_params(m, uniform_params(m, True))
    with pytest.raises(SymbolicBranchError, match=r"parameter\(s\) kd.x, kd.y, kd.z, ks.x"):
        symbolic.trace(lambda: m._pdf(SYM, WI, WO, q), explore=False)


def test_constants_fold_and_where_keeps_both_branches():
    assert SYM.sqrt(4.0) == 2.0 and SYM.power(0.0, 0.0) == 1.0 and SYM.power(-2.0, 3.0) == 0.0
    e = SYM.where(WI[2] > 0.0, 1.0 / WI[2], 0.0)
    assert e.op == "where" and e.args[1].op == "div"
    assert SYM.where(True, WI[0], WI[1]) is WI[0]


def test_a_traced_value_is_not_a_python_float():
    with pytest.raises(SymbolicBranchError):
        float(WI[0] + 1.0)
