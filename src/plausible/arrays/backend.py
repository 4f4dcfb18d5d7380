"""Which array library runs the model hooks of the float64 library: NumPy or Dr.Jit.

The NumPy front end (:meth:`plausible.bxdf.BxDF.eval`, ``pdf``, ``sample``) and
the analysis built on it validate their input and shape their output with
NumPy, and hand the arithmetic, the hooks ``_f``, ``_pdf`` and ``_sample``, to
one of two backends of the same formulas:

* ``"numpy"`` -- :data:`plausible.arrays.ops.NP`, one temporary array per operation;
* ``"drjit"`` -- :func:`plausible.arrays.ops.drjit_ops` on ``drjit.llvm.Float64``: the
  hooks are traced once per call into one LLVM kernel (float64, all cores),
  compiled on first use and then taken from Dr.Jit's kernel cache (in memory,
  and on disk in ``~/.drjit``) whenever the formula's shape and constants are
  the same.  Parameters enter as kernel data, not constants
  (:mod:`plausible.kernel_params`): one kernel per model *structure* serves
  every parameter value; a structure whose hooks need float parameters runs
  with them as constants (one kernel per parameter set).

The rule (see ``docs/backends.md``):

1. the ``backend=`` keyword of ``eval``/``pdf``/``sample``, else the innermost
   :func:`use` block, else the environment variable ``PLAUSIBLE_BACKEND``, else
   ``"auto"``, names the request: ``"auto"``, ``"numpy"`` or ``"drjit"``;
2. ``"auto"`` picks Dr.Jit when it is installed with a working LLVM backend
   and the call has at least :data:`AUTO_MIN_ROWS` direction pairs
   (:data:`AUTO_MIN_NODES` quadrature nodes; :data:`AUTO_MIN_NEW` for a model
   structure not yet compiled in this process, in one call or in the calls of
   at least those sizes together; below that, tracing and compiling cost more
   than NumPy's arithmetic), NumPy otherwise;
3. ``"drjit"`` without Dr.Jit raises :class:`ValueError`;
4. a model whose hooks do not run on Dr.Jit arrays (one that calls NumPy
   directly, such as a measured MERL table) runs on NumPy whatever was asked:
   the first failing call is repeated on NumPy and the model is remembered.

Colour models: Dr.Jit runs ``rows x channels`` lanes, each lane one channel of
one pair, with every colour parameter read per lane from a small table: the
same element-wise arithmetic as NumPy's broadcasting of a trailing channel axis.

The kernels of the quadrature rules (many incidences in one launch) are in
:mod:`plausible.arrays.quadrature_sums`; the pair kernels (``eval``, ``pdf``,
``sample`` and the fit's :class:`PairKernel`) are here.
"""

from __future__ import annotations

import threading

import contextlib
import contextvars
import os
import weakref
from functools import lru_cache

import numpy as np

#: The environment variable naming the default request.
ENV = "PLAUSIBLE_BACKEND"
#: Allowed requests.
CHOICES = ("auto", "numpy", "drjit")
#: ``auto`` uses Dr.Jit for ``eval``/``pdf``/``sample`` from this many direction
#: pairs per call.  Measured on the development machine (docs/backends.md): with
#: the kernel compiled, Dr.Jit is as fast as NumPy from about 4,000 pairs and
#: 10x faster from 65,000; a kernel not seen before (a new model or parameter
#: set) costs 30-100 ms to compile once, which NumPy repays only at about 30,000.
AUTO_MIN_ROWS = 1 << 15
#: The same for quadrature (:mod:`plausible.integrals.albedo`): its kernel does
#: not depend on the grid or the incidence, so it is compiled once per model.
AUTO_MIN_NODES = 1 << 14
#: The thresholds above hold once a model structure (:func:`kernel_key`) has run
#: on Dr.Jit in this process; before that ``auto`` asks for this many, where NumPy
#: takes longer than compiling a kernel.
AUTO_MIN_NEW = 1 << 18

_REQUEST: contextvars.ContextVar = contextvars.ContextVar("plausible_backend", default=None)
#: ``(kernel, kernel_key(model))`` of the models ``auto`` has sent to Dr.Jit (compiled).
_TRACED: set = set()
#: Rows asked of each ``(kernel, kernel_key(model))`` not yet in :data:`_TRACED`, by
#: calls of at least the kernel's minimum (:func:`choose`).
_ASKED: dict = {}
#: Models whose hooks failed on Dr.Jit (they run on NumPy from then on).
_NUMPY_ONLY: weakref.WeakSet = weakref.WeakSet()
#: Structure keys (:func:`plausible.kernel_params.structure`) whose hooks failed
#: with their parameters as kernel data: they run with constants from then on.
_CONSTANTS: set = set()
#: Whether the Dr.Jit call in progress passes parameters as data (set by :func:`run`).
_AS_DATA: contextvars.ContextVar = contextvars.ContextVar("plausible_params_as_data", default=True)


def _checked(name, source: str) -> str:
    if name not in CHOICES:
        raise ValueError(f"{source} must be one of {', '.join(CHOICES)}; got {name!r}")
    return name


def requested(backend: str | None = None) -> str:
    """The request in force: ``backend`` if given, else the innermost :func:`use`,
    else ``$PLAUSIBLE_BACKEND``, else ``"auto"``."""
    if backend is not None:
        return _checked(backend, "backend")
    cur = _REQUEST.get()
    if cur is not None:
        return cur
    env = os.environ.get(ENV)
    if env:
        return _checked(env.strip().lower(), f"environment variable {ENV}")
    return "auto"


@contextlib.contextmanager
def use(backend: str):
    """Run the enclosed code with ``backend`` (``"auto"``, ``"numpy"`` or ``"drjit"``)
    as the request of every ``eval``/``pdf``/``sample`` call, including those
    the analysis makes:

    >>> import plausible
    >>> with plausible.use_backend("numpy"):
    ...     round(float(plausible.make("lambertian", rd=0.5).eval([0, 0, 1], [0, 0, 1])), 6)
    0.159155
    """
    token = _REQUEST.set(_checked(backend, "backend"))
    try:
        yield
    finally:
        _REQUEST.reset(token)


@lru_cache(maxsize=None)
def drjit_available() -> bool:
    """Dr.Jit is importable and its LLVM backend runs (libLLVM found)."""
    try:
        import drjit as dr
        from drjit.llvm import Float64

        if not dr.has_backend(dr.JitBackend.LLVM):
            return False
        x = Float64([1.0, 2.0])
        return float(dr.sum(x * x)[0]) == 5.0
    except Exception:  # noqa: BLE001 - any failure (missing package, no libLLVM) means "not available"
        return False


def choose(rows: int, model=None, backend: str | None = None, min_rows: int = AUTO_MIN_ROWS,
           kernel: str = "eval") -> str:
    """``"numpy"`` or ``"drjit"`` for a call on ``rows`` direction pairs (see the
    module rule; ``auto`` picks Dr.Jit from ``min_rows``, or :data:`AUTO_MIN_NEW`
    for the first ``kernel`` of a model with these parameters)."""
    req = requested(backend)
    if req == "numpy" or rows == 0 or (model is not None and model in _NUMPY_ONLY):
        return "numpy"
    if req == "drjit":
        if not drjit_available():
            raise ValueError(f"backend 'drjit' was asked for ({ENV} or backend=), but Dr.Jit with "
                             f"its LLVM backend is not available; install the 'render' extra "
                             f"(pip install 'plausible[render]') or use backend 'numpy' or 'auto'")
        return "drjit"
    key = None if model is None else (kernel, kernel_key(model))
    if key is not None and key not in _TRACED and rows >= min_rows:
        # a kernel not yet compiled: worth it for one call of AUTO_MIN_NEW rows, or once
        # the calls large enough for a compiled kernel have asked for that many together
        # (a check's 20,000-sample blocks, repeated for each parameter set)
        asked = _ASKED.get(key, 0) + rows
        _ASKED[key] = asked
        min_rows = max(min_rows, AUTO_MIN_NEW - asked + rows)
    if rows >= min_rows and drjit_available():
        if key is not None:
            _TRACED.add(key)
        return "drjit"
    return "numpy"


def structure_of(model):
    """:func:`plausible.kernel_params.structure` of ``model``; None for an object
    that is not a model of this library (it has no ``_structure``)."""
    fn = getattr(model, "_structure", None)
    if fn is None:
        return None
    try:
        return fn()
    except Exception:  # noqa: BLE001 - a model whose parameters do not describe it: no shared kernel
        return None


def kernel_key(model):
    """What the compiled kernels of ``model`` depend on: its structure when its
    parameters enter as data, else its class and every parameter value."""
    st = structure_of(model)
    if st is not None and st not in _CONSTANTS:
        return ("data", st)
    return ("constants", type(model), repr(model))


#: One Dr.Jit launch at a time across threads: the explorer computes in a worker
#: thread while its caller (a test, a notebook) may compute too, and two threads
#: tracing at once were seen to return integrals of the other thread's parameters
#: (a 3 % error and crude bounds in two full-suite runs; never in one thread).
_JIT_LOCK = threading.RLock()


def run(model, kind: str, numpy_fn, drjit_fn):
    """``drjit_fn()`` with the parameters as kernel data; if the hooks fail that
    way, again with them as constants (and the structure is remembered: it runs
    with constants from then on); if they fail on Dr.Jit arrays at all, remember
    the model as NumPy-only and return ``numpy_fn()``."""
    st = structure_of(model)
    for data in ((True, False) if st is not None and st not in _CONSTANTS else (False,)):
        token = _AS_DATA.set(data)
        try:
            with _JIT_LOCK:
                return drjit_fn()
        except _NotJit:
            pass
        except (TypeError, AttributeError, ValueError, RuntimeError, IndexError):
            # a hook that calls NumPy or ``math`` on Dr.Jit arrays, or ``float()`` of one
            pass
        finally:
            _AS_DATA.reset(token)
        if data:
            _CONSTANTS.add(st)
    _NUMPY_ONLY.add(model)
    return numpy_fn()


class _NotJit(Exception):
    """A hook returned something that is not a Dr.Jit array or a number."""


@contextlib.contextmanager
def kernel_log():
    """Count the Dr.Jit kernels launched inside the block (Dr.Jit's kernel
    history).  Yields a dict filled on exit: ``launched`` (traced kernels run),
    ``compiled`` (neither in Dr.Jit's in-memory cache nor on disk: LLVM
    compiled them), ``loaded`` (from the on-disk cache), ``seconds`` (their
    compile or load time).  Kernels from other threads in that time count too.

    >>> from plausible import backend
    >>> import plausible
    >>> m = plausible.make("ward", alpha_x=0.2)
    >>> _ = m.eval([0, 0, 1], [[0.6, 0, 0.8]], backend="drjit")
    >>> with backend.kernel_log() as log:
    ...     _ = plausible.make("ward", alpha_x=0.3).eval([0, 0, 1], [[0.6, 0, 0.8]], backend="drjit")
    >>> log["compiled"], log["loaded"]
    (0, 0)
    """
    import drjit as dr

    out = dict(launched=0, compiled=0, loaded=0, seconds=0.0)
    was = dr.flag(dr.JitFlag.KernelHistory)
    dr.kernel_history()          # drop what came before
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    try:
        yield out
    finally:
        hist = dr.kernel_history()
        dr.set_flag(dr.JitFlag.KernelHistory, was)
        for e in hist:
            if e.get("type") != dr.KernelType.JIT:
                continue
            out["launched"] += 1
            # a kernel loaded from disk reads cache_hit 1 and cache_disk 1
            if e.get("cache_disk") or not e.get("cache_hit"):
                out["loaded" if e.get("cache_disk") else "compiled"] += 1
                out["seconds"] += (e.get("codegen_time", 0.0) + e.get("backend_time", 0.0)) * 1e-3


# -- Dr.Jit evaluation of the hooks ------------------------------------------------------

def _dr():
    import drjit as dr
    from drjit.llvm import Float64, UInt32

    from .ops import drjit_ops

    return dr, Float64, UInt32, drjit_ops(Float64)


class _Lanes:
    """The Dr.Jit view of one block: ``rows`` pairs, ``reps`` lanes per row
    (``reps`` = channel count for a colour evaluation, else 1)."""

    def __init__(self, rows: int, reps: int = 1):
        dr, self.Float64, self.UInt32, self.ops = _dr()
        self.dr = dr
        self.rows, self.reps = rows, reps
        lane = dr.arange(self.UInt32, rows * reps)
        self.row = lane // reps if reps > 1 else lane
        self.chan = lane % reps if reps > 1 else None

    def vectors(self, a: np.ndarray):
        """Components of ``a`` (``(3,)`` or ``(rows, 3)``) as lane arrays; one vector
        is an opaque scalar (a kernel input, not a constant: the kernel is reused
        for every other vector)."""
        dr, F = self.dr, self.Float64
        if a.size == 3:
            return tuple(dr.opaque(F, float(x)) for x in a.reshape(3))
        flat = F(np.ascontiguousarray(a, dtype=np.float64).reshape(-1))
        return tuple(dr.gather(F, flat, self.row * 3 + k) for k in range(3))

    def gather_rows(self, x):
        """A per-row array (``rows`` lanes) read per lane (``rows x reps``)."""
        if self.reps == 1 or not _is_jit(x):
            return x
        return self.dr.gather(self.Float64, x, self.row)

    def view(self, model):
        """``model`` with its parameters as this block's kernel inputs (see
        :func:`kernel_view`)."""
        return kernel_view(model, self.dr, self.Float64, self.chan, self.reps)

    def numpy(self, x, lanes: int) -> np.ndarray:
        """A hook's result as a NumPy array of ``lanes`` values."""
        if isinstance(x, (int, float, bool, np.bool_)) and not isinstance(x, np.ndarray):
            return np.full(lanes, float(x))
        if not _is_jit(x):
            raise _NotJit(type(x).__name__)
        a = np.asarray(self.Float64(x).numpy(), dtype=np.float64)
        if a.size == 1 and lanes != 1:
            return np.full(lanes, a[0])
        if a.size != lanes:
            raise _NotJit(f"{a.size} values for {lanes} lanes")
        return a


def kernel_view(model, dr, F, chan, reps: int):
    """The copy of ``model`` the Dr.Jit hooks run on (:meth:`plausible.bxdf.BxDF._kernel_view`):
    a channel array of ``reps`` values is read per lane (lane channel ``chan``), and
    with parameters as data (:mod:`plausible.kernel_params`; see :func:`run`) a float
    becomes an opaque kernel input and any other float array a kernel input array."""
    data = _AS_DATA.get()

    def convert(v):
        if isinstance(v, np.ndarray):
            if reps > 1 and v.size == reps:
                return dr.gather(F, F(np.ascontiguousarray(v, dtype=np.float64).ravel()), chan)
            if data and v.size == 1:
                return dr.opaque(F, float(v.reshape(-1)[0]))
            return v
        return dr.opaque(F, float(v)) if data else v

    return model._kernel_view(convert)


class PairKernel:
    """``f`` of many models at fixed direction pairs on Dr.Jit: the pairs enter
    once (unit ``(n, 3)`` arrays; the caller validates and normalises them), and
    each call traces ``model._f`` with the model's parameters as kernel data, so
    every model of one structure runs the same compiled kernel (a fit's
    objective, a parameter sweep).  ``kernel(model)`` is ``model.eval(wi, wo)``:
    ``(n,)`` or ``(n, channels)``; a model whose hooks do not run on Dr.Jit
    gets NumPy's ``model.eval`` (the rule of :func:`run`)."""

    def __init__(self, wi: np.ndarray, wo: np.ndarray):
        self.wi = np.ascontiguousarray(wi, dtype=np.float64).reshape(-1, 3)
        self.wo = np.ascontiguousarray(wo, dtype=np.float64).reshape(-1, 3)
        if self.wi.shape != self.wo.shape:
            raise ValueError(f"PairKernel: wi and wo must have the same shape, got {wi.shape} and {wo.shape}")
        self.n = len(self.wi)
        self._lanes = {}

    def _block(self, reps):
        if reps not in self._lanes:
            L = _Lanes(self.n, reps)
            wi, wo = L.vectors(self.wi), L.vectors(self.wo)
            L.dr.eval(*wi, *wo)
            self._lanes[reps] = (L, wi, wo)
        return self._lanes[reps]

    def _jit(self, model):
        c = model.channels or 1
        L, wi, wo = self._block(c)
        v = L.view(model)
        f = v._f(L.ops, wi, wo, v.p)
        return L.numpy(f, self.n * c).reshape((self.n, c) if model.channels else (self.n,))

    def __call__(self, model) -> np.ndarray:
        if model in _NUMPY_ONLY:
            return model.eval(self.wi, self.wo, backend="numpy")
        return run(model, "eval", lambda: model.eval(self.wi, self.wo, backend="numpy"), lambda: self._jit(model))


def _is_jit(x) -> bool:
    import drjit as dr

    return dr.is_array_v(x)


def _rows(a: np.ndarray, shape: tuple) -> np.ndarray:
    """``a`` broadcast to ``shape + (3,)`` as ``(3,)`` (one vector) or ``(rows, 3)``."""
    if a.size == 3:
        return a.reshape(3)
    return np.broadcast_to(a, shape + (3,)).reshape(-1, 3)


def eval_block(model, wi: np.ndarray, wo: np.ndarray, shape: tuple) -> np.ndarray:
    """``model._f`` on Dr.Jit for unit ``wi``, ``wo`` broadcast to ``shape``; NumPy
    array of ``shape`` (plus the channel axis)."""
    n = int(np.prod(shape))
    c = model.channels or 1
    L = _Lanes(n, c)
    v = L.view(model)
    f = v._f(L.ops, L.vectors(_rows(wi, shape)), L.vectors(_rows(wo, shape)), v.p)
    out = L.numpy(f, n * c)
    return out.reshape(shape + ((model.channels,) if model.channels else ()))


def pdf_block(model, wi: np.ndarray, wo: np.ndarray, shape: tuple) -> np.ndarray:
    """``model._pdf`` on Dr.Jit (as :func:`eval_block`; no channel axis)."""
    n = int(np.prod(shape))
    L = _Lanes(n)
    m = L.view(model)
    v = m._pdf(L.ops, L.vectors(_rows(wi, shape)), L.vectors(_rows(wo, shape)), m.q)
    return L.numpy(v, n).reshape(shape)


def sample_block(model, wi: np.ndarray, u: np.ndarray, shape: tuple, horizon: float):
    """``model._sample`` on Dr.Jit with the front end's bookkeeping (see
    :meth:`plausible.bxdf.BxDF._sample_block`, whose steps this repeats in the same
    order): normalise ``wo`` (a zero vector becomes ``(0, 0, -1)``), its pdf, ``f``,
    the validity mask, ``weight = f cos / pdf``.  Returns ``(wo, weight, pdf)``."""
    n = int(np.prod(shape))
    L = _Lanes(n)
    dr, ops = L.dr, L.ops
    wi_c = L.vectors(_rows(wi, shape))
    u_c = L.vectors(_rows(u, shape))
    mv = L.view(model)
    wo_c = mv._sample(ops, wi_c, u_c, mv.q)
    wo_c = tuple(x if _is_jit(x) else L.Float64(float(x)) for x in wo_c)
    if not all(_is_jit(x) for x in wo_c):
        raise _NotJit("sample")
    x, y, z = wo_c
    nrm = dr.sqrt(x * x + y * y + z * z)
    pos = nrm > 0
    den = dr.select(pos, nrm, 1.0)
    x, y, z = (dr.select(pos, x / den, 0.0), dr.select(pos, y / den, 0.0), dr.select(pos, z / den, -1.0))
    wo_c = (x, y, z)
    pdf = mv._pdf(ops, wi_c, wo_c, mv.q)
    ok = (pdf > 1e-250) & (z > horizon) & (wi_c[2] > horizon)
    cos_over_pdf = dr.select(ok, z / dr.select(ok, pdf, 1.0), 0.0)
    pdf = dr.select(ok, pdf, 0.0)
    if model.channels:
        c = model.channels
        dr.eval(x, y, z, cos_over_pdf, pdf)
        C = _Lanes(n, c)
        wo_l = tuple(C.gather_rows(v) for v in (x, y, z))
        wi_l = C.vectors(_rows(wi, shape))
        cv = C.view(model)
        f = cv._f(ops, wi_l, wo_l, cv.p)
        r = C.gather_rows(cos_over_pdf)
        okc = C.gather_rows(dr.select(ok, L.Float64(1.0), L.Float64(0.0))) > 0.5
        weight = L.numpy(dr.select(okc, f * r, 0.0), n * c).reshape(shape + (c,))
    else:
        f = mv._f(ops, wi_c, wo_c, mv.p)
        weight = L.numpy(dr.select(ok, f * cos_over_pdf, 0.0), n).reshape(shape)
    wo = np.stack([L.numpy(v, n) for v in wo_c], axis=-1).reshape(shape + (3,))
    return wo, weight, L.numpy(pdf, n).reshape(shape)


__all__ = ["AUTO_MIN_NEW", "AUTO_MIN_NODES", "AUTO_MIN_ROWS", "CHOICES", "ENV", "PairKernel", "choose", "drjit_available",
           "kernel_key", "kernel_log", "kernel_view", "requested", "run", "structure_of", "use"]
