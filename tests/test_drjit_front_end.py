"""The Dr.Jit front end of ``eval``/``pdf``/``sample`` (issue 30): NumPy arrays
enter the kernel raw, and the kernel checks them (finite, non-zero; ``u`` in
[0, 1]) and normalises them (:func:`plausible.directions.unit_lanes`).

The truths: NumPy's :func:`plausible.directions.normalise` (the kernel's unit
vectors must be bitwise its values, so a raw batch gives bitwise the result of
the same batch normalised by NumPy first), NumPy's checks (the same error, the
same message naming the argument, in the same order), and Dr.Jit's kernel
history (one launch, no NumPy pass over the batch)."""

from __future__ import annotations

import numpy as np
import pytest

import plausible
from conftest import random_upper
from plausible import directions as D
from plausible.arrays import backend
from plausible.arrays.ops import NP

needs_drjit = pytest.mark.skipif(not backend.drjit_available(), reason="Dr.Jit LLVM backend unavailable")

#: Scalar and colour, isotropic and anisotropic, a mixture and a single lobe.
SPECS = ["ashikhmin-shirley:nu=10:nv=300:rs=0.05,0.3,0.9:rd=0.5,0.2,0.1", "ward:alpha_x=0.1:alpha_y=0.3",
         "cook-torrance:m=0.2:rs=0.6", "lambertian"]


def raw_batch(rng, n, dtype=np.float64):
    """Upper-hemisphere directions of random lengths, some of them at lengths
    whose ``|w|^2`` over- or underflows (the rescaled rows of ``normalise``)."""
    w = random_upper(rng, n) * rng.uniform(0.3, 3.0, (n, 1))
    if dtype == np.float64:
        w[:7] *= 1e200
        w[7:14] *= 1e-170
    else:
        w[:7] *= 1e30
        w[7:14] *= 1e-30
    return w.astype(dtype)


def test_unit_lanes_is_normalise_and_its_checks():
    """On NumPy arrays (the ops namespace NP), :func:`D.unit_lanes` gives bitwise
    ``normalise``'s vectors and flags exactly the rows NumPy's checks refuse."""
    rng = np.random.default_rng(7)
    a = raw_batch(rng, 400)
    a[20] = [1e-320, 0.0, -2e-320]          # subnormal components, |a|^2 underflows to 0
    a[21] = [0.0, 0.0, 0.0]
    a[22, 1], a[23, 2], a[24, 0] = np.nan, np.inf, -np.inf
    a[25] = [1.0, 1e-9, 0.0]                # unit to UNIT_TOL: kept as given
    with np.errstate(all="ignore"):
        unit, bad = D.unit_lanes(NP, D.split(a))
        ok = ~np.isin(np.arange(len(a)), [21, 22, 23, 24])
        np.testing.assert_array_equal(D.stack(unit)[ok], D.normalise(a[ok]))
    np.testing.assert_array_equal(np.flatnonzero(bad), [21, 22, 23, 24])
    assert D.stack(unit)[25].tolist() == [1.0, 1e-9, 0.0]


@needs_drjit
def test_unit_lanes_on_drjit_mixes_kept_and_normalised_rows():
    """On Dr.Jit, :func:`D.unit_lanes` skips the divisions for packets of unit rows
    (``ops.keep_or``): a batch whose runs of unit rows and of rows to normalise
    (lengths 1 to 64, so packets are all kept, all normalised, or mixed) gives
    bitwise NumPy's ``normalise`` in every row, the unit rows as given."""
    import drjit as dr
    from drjit.llvm import Float64

    from plausible.arrays.ops import drjit_ops

    rng = np.random.default_rng(11)
    a = D.normalise(random_upper(rng, 3000))
    unit = np.abs(D.norm2(a) - 1.0) <= D.UNIT_TOL        # all, before the runs are stretched
    lengths = rng.integers(1, 65, 200)
    a[np.resize(np.repeat(np.arange(len(lengths)) % 2 == 1, lengths), len(a))] *= 2.5
    a[5] *= 1e200
    a[6] *= 1e-170
    ops = drjit_ops(Float64)
    got, bad = D.unit_lanes(ops, tuple(Float64(np.ascontiguousarray(a[:, k])) for k in range(3)))
    dr.eval(got, bad)
    got = np.stack([g.numpy() for g in got], axis=-1)
    np.testing.assert_array_equal(got, D.normalise(a))
    with np.errstate(over="ignore", under="ignore"):
        kept = np.abs(D.norm2(a) - 1.0) <= D.UNIT_TOL
    assert 0 < kept.sum() < len(a) - 100 and np.all(unit[kept])
    np.testing.assert_array_equal(got[kept], a[kept])
    assert not np.any(bad.numpy())


@needs_drjit
@pytest.mark.parametrize("spec", SPECS, ids=[s.split(":")[0] for s in SPECS])
@pytest.mark.parametrize("dtype", [np.float64, np.float32])
def test_raw_input_gives_the_result_of_numpy_normalised_input(spec, dtype, rng):
    """A raw batch (random lengths, |w|^2 over- and underflowing; float32 too)
    on Dr.Jit: bitwise the result of the same batch normalised by NumPy first,
    for eval, pdf and sample; and within the backend tolerances of the NumPy
    backend (tests/test_backend.py)."""
    m = plausible.registry.make_from_spec(spec)
    wi, wo, u = raw_batch(rng, 2000, dtype), raw_batch(rng, 2000, dtype), rng.random((2000, 3)).astype(dtype)
    ui, uo = (D.normalise(np.asarray(w, dtype=np.float64)) for w in (wi, wo))
    uu = np.asarray(u, dtype=np.float64)
    for got, ref in ((m.eval(wi, wo, backend="drjit"), m.eval(ui, uo, backend="drjit")),
                     (m.pdf(wi, wo, backend="drjit"), m.pdf(ui, uo, backend="drjit")),
                     (m.eval(wi[3], wo, backend="drjit"), m.eval(ui[3], uo, backend="drjit")),
                     *zip(m.sample(wi, u, backend="drjit"), m.sample(ui, uu, backend="drjit"))):
        np.testing.assert_array_equal(got, ref)
    scale = lambda a, b: np.maximum(np.maximum(np.abs(a), np.abs(b)), 1e-290)  # noqa: E731
    for got, ref in ((m.eval(wi, wo, backend="drjit"), m.eval(ui, uo, backend="numpy")),
                     (m.pdf(wi, wo, backend="drjit"), m.pdf(ui, uo, backend="numpy"))):
        assert np.all(np.abs(got - ref) <= 1e-12 * scale(got, ref))


@needs_drjit
@pytest.mark.parametrize("spec,launches", [(SPECS[0], 2), (SPECS[1], 1)], ids=["colour", "scalar"])
def test_one_launch_and_no_numpy_pass(spec, launches, rng, monkeypatch):
    """eval, pdf and sample of a raw batch on Dr.Jit run without NumPy's checks
    or normalisation (they are made to fail here) in one kernel launch each
    (sample of a colour model: two, f per channel in the second)."""
    m = plausible.registry.make_from_spec(spec)
    wi, wo, u = raw_batch(rng, 3000), raw_batch(rng, 3000), rng.random((3000, 3))
    calls = [lambda: m.eval(wi, wo, backend="drjit"), lambda: m.pdf(wi, wo, backend="drjit"),
             lambda: m.sample(wi, u, backend="drjit")]
    for call in calls:
        call()                                 # compiled before counting
    for name in ("prepare", "checked_unit", "check_directions", "normalise", "as_unit_interval"):
        monkeypatch.setattr(D, name, _refused(name))
    counts = []
    for call in calls:
        with backend.kernel_log() as log:
            call()
        counts.append(log["launched"])
    assert counts == [1, 1, launches]
    with pytest.raises(AssertionError, match="NumPy front end"):   # the probe can fail: NumPy's path
        m.eval(wi, wo, backend="numpy")


def _refused(name):
    def refuse(*args, **kwargs):
        raise AssertionError(f"the NumPy front end ran ({name})")
    return refuse


def _message(call):
    try:
        call()
    except ValueError as e:
        return str(e)
    return None


@needs_drjit
def test_bad_input_raises_numpy_errors_in_numpy_order(rng):
    """NaN, infinities, zero vectors and ``u`` outside [0, 1], alone and together:
    on Dr.Jit the same ``ValueError`` as on NumPy, word for word (the argument's
    name; ``wi`` before ``wo``; within one argument a NaN anywhere before a zero
    vector anywhere), never a result."""
    m = plausible.make("ward")
    n = 4000
    wi, wo, u = raw_batch(rng, n), raw_batch(rng, n), rng.random((n, 3))

    def put(a, row, value):
        a = a.copy()
        a[row] = value
        return a

    nan_wi, zero_wi = put(wi, (n - 1, 1), np.nan), put(wi, 5, 0.0)
    both_wi = put(zero_wi, (n - 2, 2), -np.inf)
    zero_wo, inf_wo = put(wo, n - 1, 0.0), put(wo, (0, 0), np.inf)
    cases = [("eval", nan_wi, wo), ("eval", zero_wi, wo), ("pdf", both_wi, wo), ("eval", wi, zero_wo),
             ("pdf", wi, inf_wo), ("eval", zero_wi, inf_wo), ("eval", wi, [0.0, 0.0, 0.0]),
             ("eval", nan_wi, [0.0, 0.0, 0.0]), ("eval", put(raw_batch(rng, n, np.float32), (9, 0), np.nan), raw_batch(rng, n, np.float32)),
             ("sample", nan_wi, u), ("sample", wi, put(u, (n - 1, 2), 1.5)), ("sample", wi, put(u, (3, 0), np.nan)),
             ("sample", zero_wi, put(u, (0, 1), -1e-9)), ("sample", wi, [0.5, 1.5, 0.5]),
             ("eval", nan_wi, wo[:, :2])]
    expected = ["wi must be finite", "wi must be non-zero", "wi must be finite", "wo must be non-zero",
                "wo must be finite", "wi must be non-zero", "wo must be non-zero", "wi must be finite",
                "wi must be finite", "wi must be finite", "u must lie in [0, 1], got 1.5", "u must lie in [0, 1], got nan",
                "wi must be non-zero", "u must lie in [0, 1], got 1.5", "wi must be finite"]
    for (op, a, b), want in zip(cases, expected):
        got = {be: _message(lambda: getattr(m, op)(a, b, backend=be)) for be in ("numpy", "drjit")}
        assert got["drjit"] == got["numpy"] and got["drjit"] is not None and got["drjit"].startswith(want), \
            (op, want, got)
