"""The backend switch (:mod:`plausible.arrays.backend`): the rule that picks NumPy or
Dr.Jit, the same numbers on both over the registry, and a NumPy-only install."""

import math
import os
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import plausible
from conftest import model_cases, random_upper
from plausible.arrays import backend
from plausible.bxdf import BxDF

CASES = model_cases(max_variants=0)

needs_drjit = pytest.mark.skipif(not backend.drjit_available(), reason="Dr.Jit LLVM backend unavailable")


def assert_rel(got, ref, rtol, floor=1e-290):
    """``|got - ref| <= rtol max(|got|, |ref|, floor)`` element-wise.  The floor:
    Dr.Jit's ``exp`` flushes results in the subnormal range (below about 1e-300)
    to zero where NumPy returns a subnormal number (e.g. ``cos^10000`` far from a
    lobe), so values that small agree absolutely, not relatively."""
    got, ref = np.asarray(got), np.asarray(ref)
    assert got.shape == ref.shape
    scale = np.maximum(np.maximum(np.abs(got), np.abs(ref)), floor)
    rel = np.abs(got - ref) / scale
    assert np.all(rel <= rtol), f"max relative difference {rel.max():.3g} > {rtol:g}"


@needs_drjit
@pytest.mark.parametrize("name,kw", CASES)
def test_numpy_and_drjit_front_ends_agree(name, kw, rng):
    m = plausible.make(name, **kw)
    wi, wo, u = random_upper(rng, 3000), random_upper(rng, 3000), rng.random((3000, 3))
    # eval and pdf: the same formulas, transcendental functions within 1e-12 relative
    assert_rel(m.eval(wi, wo, backend="drjit"), m.eval(wi, wo, backend="numpy"), 1e-12)
    assert_rel(m.pdf(wi, wo, backend="drjit"), m.pdf(wi, wo, backend="numpy"), 1e-12)
    assert_rel(m.eval(wi[0], wo, backend="drjit"), m.eval(wi[0], wo, backend="numpy"), 1e-12)
    a, b = m.sample(wi, u, backend="numpy"), m.sample(wi, u, backend="drjit")
    np.testing.assert_allclose(b.wo, a.wo, rtol=0, atol=1e-12)
    # pdf and weight at the sampled direction: a direction that differs in its last
    # bits (sampling inverts pow/exp/atan) changes a cos^n lobe by n times as much
    # relatively (n = 10^4 here), hence 1e-10 rather than 1e-12
    assert_rel(b.pdf, a.pdf, 1e-10)
    assert_rel(b.weight, a.weight, 1e-10)


@needs_drjit
def test_eager_sends_calls_of_eager_min_rows_to_drjit_whatever_ran_before():
    """``eager`` (what ``check`` runs in): a structure not yet compiled goes to Dr.Jit from
    ``EAGER_MIN_ROWS`` pairs, not ``AUTO_MIN_NEW``; smaller calls and explicit requests
    are as outside; and the compiled sampler gives what NumPy's gives."""
    class Fresh(type(plausible.make("ward"))):
        pass

    m = Fresh(alpha_x=0.123, alpha_y=0.234)
    n = backend.EAGER_MIN_ROWS
    assert backend.AUTO_MIN_ROWS <= backend.AUTO_MIN_NEW and n < backend.AUTO_MIN_NEW
    with backend.eager():
        assert backend.choose(n - 1, m, kernel="sample") == "numpy"
        assert backend.choose(n, m, kernel="sample") == "drjit"
        assert backend.choose(n, m, kernel="pdf") == "drjit"
        with backend.use("numpy"):
            assert backend.choose(10 ** 7, m) == "numpy"
    assert backend.choose(backend.AUTO_MIN_ROWS, Fresh(alpha_x=0.2), kernel="eval") == "numpy"
    rng = np.random.default_rng(5)
    wi, u = random_upper(rng, n), rng.random((n, 3))
    with backend.eager(), backend.kernel_log() as log:
        s = m.sample(wi, u)
    assert log["launched"] >= 1
    ref = m.sample(wi, u, backend="numpy")
    np.testing.assert_allclose(s.wo, ref.wo, rtol=0, atol=1e-12)
    assert_rel(s.weight, ref.weight, 1e-10)


def test_request_rule_keyword_then_context_then_environment(monkeypatch):
    monkeypatch.setenv(backend.ENV, "numpy")
    assert backend.requested() == "numpy"
    with backend.use("auto"):
        assert backend.requested() == "auto"
        assert backend.requested("numpy") == "numpy"
        with plausible.use_backend("numpy"):
            assert backend.requested() == "numpy"
        assert backend.requested() == "auto"
    monkeypatch.delenv(backend.ENV)
    assert backend.requested() == "auto"


def test_bad_backend_names_are_refused_with_the_choices(monkeypatch):
    m = plausible.make("lambertian")
    with pytest.raises(ValueError, match=r"backend must be one of auto, numpy, drjit, llvm, cuda; got 'metal'"):
        m.eval([0, 0, 1], [0, 0, 1], backend="metal")
    monkeypatch.setenv(backend.ENV, "jax")
    with pytest.raises(ValueError, match=r"PLAUSIBLE_BACKEND must be one of .*got 'jax'"):
        m.eval([0, 0, 1], [0, 0, 1])


@needs_drjit
def test_auto_picks_drjit_for_large_batches_only():
    assert backend.choose(10) == "numpy"
    assert backend.choose(backend.AUTO_MIN_ROWS) == "drjit"
    # a model not yet compiled needs a batch worth the compilation, then less (a class of
    # this test's own: a structure no other test in this process has compiled)
    class Fresh(type(plausible.make("ashikhmin-shirley"))):
        pass

    m = Fresh(nu=12.345, nv=67.89)
    assert backend.choose(backend.AUTO_MIN_ROWS, m) == "numpy"
    assert backend.choose(backend.AUTO_MIN_NEW, m) == "drjit"
    assert backend.choose(backend.AUTO_MIN_ROWS, m) == "drjit"
    # new parameter values of a compiled structure reuse its kernel; a new structure does not
    assert backend.choose(backend.AUTO_MIN_ROWS, Fresh(nu=12.345, nv=67.9)) == "drjit"
    assert backend.choose(backend.AUTO_MIN_ROWS, Fresh(rs=[0.1, 0.2, 0.3])) == "numpy"
    with backend.use("numpy"):
        assert backend.choose(10 ** 7) == "numpy"
    with backend.use("drjit"):
        assert backend.choose(1) == "drjit"
        assert backend.choose(0) == "numpy"      # nothing to trace
        m = plausible.make("lambertian")
        assert m.eval(np.zeros((0, 3)), [0, 0, 1]).shape == (0,)
        assert backend.choose(1, m) == "drjit"  # not marked NumPy-only by the empty call


class _NumpyHooks(BxDF):
    """A model whose hook calls NumPy directly (not written against ``ops``)."""

    def _f(self, ops, wi, wo, p):
        return np.where(np.asarray(wi[2]) > 0, 1.0 / np.pi, 0.0) * np.ones_like(np.asarray(wo[2]))

    def _pdf(self, ops, wi, wo, q):
        return ops.where(wo[2] > 0, wo[2] / np.pi, 0.0)

    def _sample(self, ops, wi, u, q):
        raise NotImplementedError


@needs_drjit
def test_a_model_that_calls_numpy_in_its_hooks_falls_back_to_numpy(rng):
    m = _NumpyHooks()
    wi, wo = random_upper(rng, 50), random_upper(rng, 50)
    np.testing.assert_array_equal(m.eval(wi, wo, backend="drjit"), np.full(50, 1 / np.pi))
    assert backend.choose(10 ** 6, m) == "numpy"          # remembered for later calls
    assert backend.choose(10 ** 6, _NumpyHooks()) == "drjit"  # per model, not per class


BLOCKER = textwrap.dedent("""
    import sys, importlib.abc
    class Block(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name.split(".")[0] in ("drjit", "mitsuba"):
                raise ImportError(f"{name} hidden for this test")
    sys.meta_path.insert(0, Block())
""")


def test_numpy_only_install_works_and_refuses_drjit_clearly(tmp_path):
    """Dr.Jit and Mitsuba hidden by an import hook: ``auto`` runs on NumPy (a large
    batch included), the albedo of a Lambertian surface is still its ``kd``, and
    asking for Dr.Jit names the missing extra."""
    script = BLOCKER + textwrap.dedent("""
        import numpy as np, plausible
        from plausible.arrays import backend
        assert not backend.drjit_available()
        m = plausible.make("lambertian", rd=0.4)
        wo = np.tile([0.0, 0.6, 0.8], (backend.AUTO_MIN_ROWS, 1))
        assert np.allclose(m.eval([0, 0, 1], wo), 0.4 / np.pi)
        a = plausible.albedo(m, [0.3, 0.0, 0.9])
        assert abs(a.value - 0.4) <= max(a.error, 1e-12), (a.value, a.error)
        try:
            m.eval([0, 0, 1], wo, backend="drjit")
        except ValueError as e:
            assert "render" in str(e) and "Dr.Jit" in str(e)
        else:
            raise AssertionError("backend='drjit' without Dr.Jit did not raise")
        assert "drjit" not in sys.modules and "mitsuba" not in sys.modules
        print("ok")
    """)
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path), PLAUSIBLE_CACHE_DIR="")
    env.pop(backend.ENV, None)
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120)
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == "ok"


@needs_drjit
@pytest.mark.parametrize("spec", ["ashikhmin-shirley:nu=10:nv=100", "modified-phong:kd=0.2,0.3,0.4:n=30"])
def test_albedo_agrees_on_both_backends_within_its_error_bounds(spec):
    m = plausible.registry.make_from_spec(spec)
    wis = [plausible.analysis.direction(np.radians(t), np.radians(p)) for t, p in ((40, 60), (89.5, 0))]
    with plausible.use_backend("numpy"):
        a = plausible.analysis.albedos(m, wis)
    with plausible.use_backend("drjit"):
        b = plausible.analysis.albedos(m, wis)
    for x, y in zip(a, b):
        assert np.all(np.abs(np.asarray(x.value) - y.value) <= np.asarray(x.error) + y.error)


@needs_drjit
def test_check_report_is_the_same_on_both_backends():
    m = plausible.make("ashikhmin-shirley", nu=10, nv=100)
    with plausible.use_backend("numpy"):
        a = plausible.check(m, quick=True)
    with plausible.use_backend("drjit"):
        b = plausible.check(m, quick=True)
    assert [r.passed for r in a.results] == [r.passed for r in b.results] == [True] * 4
    ea, eb = a["energy"], b["energy"]
    assert abs(ea.figure - eb.figure) <= ea.worst["error"] + eb.worst["error"]
    # the chi-square statistic sees the same samples and cell integrals to 1e-6
    assert b["chi2"].figure == pytest.approx(a["chi2"].figure, rel=1e-3)


#: Modules that ``import plausible`` must not load (each costs 0.1-1 s; the code
#: that needs one imports it where it is used).
HEAVY = ("scipy.stats", "scipy.optimize", "drjit", "mitsuba", "matplotlib", "PIL")


def test_import_plausible_loads_no_heavy_module():
    """``import plausible`` in a fresh process leaves out scipy.stats (about 1 s),
    scipy.optimize, Dr.Jit, Mitsuba and matplotlib; the same probe sees
    ``scipy.stats`` once the script imports it (so it can fail)."""
    probe = "import sys, plausible{}; print(' '.join(m for m in {!r} if m in sys.modules))"
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(sys.path))
    for extra, expect in (("", set()), (", scipy.stats", {"scipy.stats", "scipy.optimize"})):
        r = subprocess.run([sys.executable, "-c", probe.format(extra, HEAVY)], capture_output=True,
                           text=True, env=env, timeout=120)
        assert r.returncode == 0, r.stderr
        assert set(r.stdout.split()) == expect


# -- parameters as kernel data (plausible.kernel_params) -----------------------------------

#: Pairs of models of one structure with different parameter values.
SAME_STRUCTURE = [
    ("ashikhmin-shirley:nu=10:nv=100", "ashikhmin-shirley:nu=20:nv=20:rs=0.3:rd=0.1"),
    ("ward:alpha_x=0.1:rs=0.5:rd=0.2:variant=duer", "ward:alpha_x=0.3:alpha_y=0.05:rs=0.1:rd=0.6:variant=duer"),
    ("modified-phong:kd=0.2,0.3,0.4:ks=0.3:n=30", "modified-phong:kd=0.5,0.1,0.2:ks=0.2:n=7"),
    ("cook-torrance:m=0.2", "cook-torrance:m=0.35:rs=0.7"),
    ("material:alum-bronze@ngan2005/cook-torrance", "material:alumina-oxide@ngan2005/cook-torrance"),
]


def _spec(spec, jitter=0.0):
    m = plausible.registry.make_from_spec(spec)
    if not jitter or not m.params:
        return m
    # values never used before in any process (Dr.Jit's disk cache would know them)
    jitter *= 1.0 + (time.time_ns() % 10 ** 6) * 1e-6
    return type(m)(**{k: (v * (1.0 - jitter) if isinstance(v, float) else v) for k, v in m.params.items()})


def _dirs(seed):
    rng = np.random.default_rng(seed)
    return random_upper(rng, 200), random_upper(rng, 200), rng.random((200, 3))


def _all_kernels(m, seed):
    wi, wo, u = _dirs(seed)
    with plausible.use_backend("drjit"):
        out = [m.eval(wi, wo), m.eval(wi[0], wo), m.pdf(wi, wo), *m.sample(wi, u)]
        out.append(plausible.albedo(m, [0.6, 0.0, 0.8], tol=1e-3).value)
    return out


def test_structure_keys_separate_structure_from_data():
    s = backend.structure_of
    assert s(_spec(SAME_STRUCTURE[1][0])) == s(_spec(SAME_STRUCTURE[1][1]))
    assert s(plausible.make("ward")) != s(plausible.make("ward", variant="balanced"))      # a choice
    assert s(plausible.make("ward")) != s(plausible.make("ward", rs=[1.0, 0.5, 0.2]))      # channels
    assert s(plausible.make("reciprocal-phong")) != s(plausible.make("reciprocal-blinn"))  # the class
    assert s(plausible.make("pumped-up", times=1)) != s(plausible.make("pumped-up", times=2))  # an integer


@needs_drjit
@pytest.mark.parametrize("a,b", SAME_STRUCTURE, ids=[x.split(":")[0] + "-" + x.split(":")[1][:12]
                                                      for x, _ in SAME_STRUCTURE])
def test_new_parameter_values_compile_nothing_and_agree_with_numpy(a, b, rng):
    """Every Dr.Jit kernel (eval, eval with one wi, pdf, sample, the albedo's
    quadrature) compiled for ``a`` serves ``b``: the kernel history shows no
    compilation and no disk-cache load, and ``b`` agrees with NumPy as in
    :func:`test_numpy_and_drjit_front_ends_agree`.  The same probe counts
    compilations when the structure is forced to constants (so it can fail)."""
    _all_kernels(_spec(a), 0)
    mb = _spec(b, jitter=rng.uniform(1e-6, 1e-3))
    with backend.kernel_log() as log:
        got = _all_kernels(mb, 1)
    assert log["launched"] >= 5 and log["compiled"] == 0 and log["loaded"] == 0, log
    wi, wo, u = _dirs(1)
    ref = [mb.eval(wi, wo, backend="numpy"), mb.eval(wi[0], wo, backend="numpy"), mb.pdf(wi, wo, backend="numpy")]
    for g, r in zip(got, ref):
        assert_rel(g, r, 1e-12)
    s = mb.sample(wi, u, backend="numpy")
    np.testing.assert_allclose(got[3], s.wo, rtol=0, atol=1e-12)
    assert_rel(got[4], s.weight, 1e-10)
    assert_rel(got[5], s.pdf, 1e-10)
    mc = _spec(b if "material" not in b else SAME_STRUCTURE[3][1], jitter=rng.uniform(1e-6, 1e-3))
    backend._CONSTANTS.add(backend.structure_of(mc))
    try:
        with backend.kernel_log() as log:
            _all_kernels(mc, 2)
        assert log["compiled"] + log["loaded"] >= 1, log
    finally:
        backend._CONSTANTS.discard(backend.structure_of(mc))


class _MathHooks(BxDF):
    """A model whose hook takes ``math.exp`` of a parameter (not array-safe)."""

    PARAMS = (plausible.bxdf.Param("a", 0.5, 0.0, 1.0),)

    def _f(self, ops, wi, wo, p):
        return ops.where(wo[2] > 0, math.exp(-p.a) * wo[2], 0.0)


@needs_drjit
def test_a_hook_that_needs_float_parameters_runs_with_constants(rng):
    """Parameters as data fail for it; the backend runs its structure with
    constants (on Dr.Jit still, not NumPy) and gets NumPy's numbers."""
    m = _MathHooks(a=0.25)
    wi, wo = random_upper(rng, 50), random_upper(rng, 50)
    got = m.eval(wi, wo, backend="drjit")
    assert_rel(got, np.exp(-0.25) * wo[:, 2], 1e-15)
    assert backend.structure_of(m) in backend._CONSTANTS and m not in backend._NUMPY_ONLY
    assert backend.kernel_key(m)[0] == "constants"


def test_aligned_rows_start_on_the_alignment_and_keep_their_values():
    """backend.aligned (the quadrature kernels' inputs, the Mitsuba adapter's components): every
    row contiguous, starting at a multiple of ALIGN bytes, whatever NumPy's allocator gave; the
    values and dtype as asked; a 1-D input stays 1-D."""
    from plausible.arrays.backend import ALIGN, aligned

    rng = np.random.default_rng(3)
    for x, dt in [(np.arange(5.0), np.float64), (np.arange(37), np.uint32), (rng.random((3, 41)), np.float32),
                  (rng.random((3, 1000)), np.float32)]:
        for _ in range(4):                      # several allocations: several starting addresses
            a = aligned(x, dt)
            assert a.dtype == dt and a.shape == x.shape and np.array_equal(a, x.astype(dt))
            assert all(r.ctypes.data % ALIGN == 0 and r.flags.c_contiguous for r in np.atleast_2d(a))


# -- Dr.Jit's devices: LLVM and CUDA (issue 42) ------------------------------------------


def test_drjit_runs_on_the_first_device_found_and_a_named_one_is_obeyed(monkeypatch):
    """``drjit`` and ``auto`` take CUDA where it runs, else LLVM; ``llvm``/``cuda`` are obeyed."""
    monkeypatch.setattr(backend, "devices", lambda: ("cuda", "llvm"))
    monkeypatch.setattr(backend, "device_available", lambda name: True)
    assert backend.device("drjit") == "cuda" and backend.device("auto") == "cuda"
    assert backend.device("llvm") == "llvm"
    monkeypatch.setattr(backend, "devices", lambda: ("llvm",))
    assert backend.device("drjit") == "llvm"


def test_a_device_that_does_not_run_is_refused_with_its_cause(monkeypatch):
    monkeypatch.setattr(backend, "device_available", lambda name: name == "llvm")
    monkeypatch.setattr(backend, "devices", lambda: ("llvm",))
    m = plausible.make("lambertian")
    with pytest.raises(ValueError, match=r"backend 'cuda' .*no NVIDIA GPU or driver found; Dr.Jit devices here: llvm"):
        m.eval([0, 0, 1], [[0, 0, 1]], backend="cuda")
    monkeypatch.setenv(backend.ENV, "cuda")
    with pytest.raises(ValueError, match=r"backend 'cuda'"):
        plausible.albedo(m, [0, 0, 1])


@needs_drjit
@pytest.mark.parametrize("dev", backend.devices())
def test_each_device_of_this_machine_gives_the_numpy_numbers(dev, rng):
    """``backend="llvm"`` / ``"cuda"``, each device this machine has: the NumPy values of eval,
    pdf and a colour model to 1e-12, and the albedo to its error (the same formulas, another
    array type); the kernels run on that device's arrays."""
    m = plausible.make("ashikhmin-shirley", nu=30.0, nv=300.0, rs=[0.05, 0.2, 0.5])
    wi, wo = random_upper(rng, 64, 0.05), random_upper(rng, 64, 0.05)
    for fn in (m.eval, m.pdf):
        assert np.allclose(fn(wi, wo, backend=dev), fn(wi, wo, backend="numpy"), rtol=1e-12, atol=0)
    with backend.use(dev):
        assert backend.jit_module().__name__ == f"drjit.{dev}"
        a = plausible.albedo(m, [0.6, 0.0, 0.8])
    with backend.use("numpy"):
        b = plausible.albedo(m, [0.6, 0.0, 0.8])
    assert np.all(np.abs(np.asarray(a.value) - b.value) <= 2 * np.maximum(a.error, 1e-9))
