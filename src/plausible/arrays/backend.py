"""Which array library runs the model hooks of the float64 library: NumPy or Dr.Jit.

The NumPy front end (:meth:`plausible.bxdf.BxDF.eval`, ``pdf``, ``sample``) and
the analysis built on it validate their input and shape their output with
NumPy, and hand the arithmetic, the hooks ``_f``, ``_pdf`` and ``_sample``, to
one of two backends of the same formulas (on Dr.Jit, ``eval``/``pdf``/``sample``
check and normalise their raw input inside the kernel: :func:`eval_fused`):

* ``"numpy"`` -- :data:`plausible.arrays.ops.NP`, one temporary array per operation;
* ``"drjit"`` -- :func:`plausible.arrays.ops.drjit_ops` on Dr.Jit's ``Float64`` of the
  device in force (:func:`device`: ``drjit.cuda`` where an NVIDIA GPU and its driver
  are found, else ``drjit.llvm``): the
  hooks are traced once per call into one kernel (float64; all cores on LLVM),
  compiled on first use and then taken from Dr.Jit's kernel cache (in memory,
  and on disk in ``~/.drjit``) whenever the formula's shape and constants are
  the same.  Parameters enter as kernel data, not constants
  (:mod:`plausible.kernel_params`): one kernel per model *structure* serves
  every parameter value; a structure whose hooks need float parameters runs
  with them as constants (one kernel per parameter set).

The rule (see ``docs/backends.md``):

1. the ``backend=`` keyword of ``eval``/``pdf``/``sample``, else the innermost
   :func:`use` block, else the environment variable ``PLAUSIBLE_BACKEND``, else
   ``"auto"``, names the request: ``"auto"``, ``"numpy"``, ``"drjit"``, or one of Dr.Jit's
   devices by name, ``"llvm"`` (the CPU) or ``"cuda"`` (an NVIDIA GPU);
2. ``"auto"`` picks Dr.Jit when it is installed with a working LLVM backend
   and the call has at least :data:`AUTO_MIN_ROWS` direction pairs
   (:data:`AUTO_MIN_NODES` quadrature nodes; :data:`AUTO_MIN_NEW` for a model
   structure not yet compiled in this process; below that, tracing and
   compiling cost more than NumPy's arithmetic), NumPy otherwise;
3. ``"drjit"`` without Dr.Jit raises :class:`ValueError`, and so does ``"llvm"`` or
   ``"cuda"`` where that device does not run; ``"drjit"`` and ``"auto"`` run on CUDA
   where it is available, else on LLVM (:func:`device`): the same kernels, traced from
   the same formulas, with another array type;
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
CHOICES = ("auto", "numpy", "drjit", "llvm", "cuda")
#: Dr.Jit's devices, in the order ``"drjit"`` and ``"auto"`` prefer them.
DEVICES = ("cuda", "llvm")
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
#: Within :func:`eager`, ``auto`` uses Dr.Jit from this many pairs (or nodes), whether
#: or not the model structure has run on Dr.Jit before in this process.
EAGER_MIN_ROWS = 1 << 14

_REQUEST: contextvars.ContextVar = contextvars.ContextVar("plausible_backend", default=None)
#: ``(kernel, kernel_key(model))`` of the models ``auto`` has sent to Dr.Jit (compiled).
_TRACED: set = set()
#: Models whose hooks failed on Dr.Jit (they run on NumPy from then on).
_NUMPY_ONLY: weakref.WeakSet = weakref.WeakSet()
#: Structure keys (:func:`plausible.kernel_params.structure`) whose hooks failed
#: with their parameters as kernel data: they run with constants from then on.
_CONSTANTS: set = set()
#: Whether :func:`eager` is in force.
_EAGER: contextvars.ContextVar = contextvars.ContextVar("plausible_eager", default=False)
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
    """Run the enclosed code with ``backend`` (``"auto"``, ``"numpy"``, ``"drjit"``, ``"llvm"`` or ``"cuda"``)
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


@contextlib.contextmanager
def eager():
    """Within this block, ``auto`` sends every call of at least :data:`EAGER_MIN_ROWS`
    pairs (or quadrature nodes) to Dr.Jit, compiling the model structure's kernel if
    this process has not yet (rule 2's :data:`AUTO_MIN_NEW` does not apply): for work
    that makes many calls of that size on one structure, such as
    :func:`plausible.check` (its sampling, guard and chi-square samples, 30,000 to
    200,000 pairs a call), where NumPy's float64 arithmetic costs more than the
    kernels, and the choice then depends on the call alone, not on what ran before.
    An explicit request (``"numpy"``, ``"drjit"``) is obeyed as outside."""
    token = _EAGER.set(True)
    try:
        yield
    finally:
        _EAGER.reset(token)


@lru_cache(maxsize=None)
def device_available(name: str) -> bool:
    """Dr.Jit is importable and its backend ``name`` (``"llvm"``: libLLVM found; ``"cuda"``:
    an NVIDIA GPU with its driver) runs a float64 kernel."""
    try:
        import importlib

        import drjit as dr

        if not dr.has_backend(getattr(dr.JitBackend, name.upper())):
            return False
        x = importlib.import_module(f"drjit.{name}").Float64([1.0, 2.0])
        return float(dr.sum(x * x)[0]) == 5.0
    except Exception:  # noqa: BLE001 - any failure (missing package, no libLLVM, no GPU) means "not available"
        return False


def devices() -> tuple:
    """Dr.Jit's devices that run on this machine, preferred first (a subset of :data:`DEVICES`)."""
    return tuple(d for d in DEVICES if device_available(d))


def drjit_available() -> bool:
    """Dr.Jit runs on at least one device here (LLVM or CUDA)."""
    return bool(devices())


def device(backend: str | None = None) -> str:
    """The Dr.Jit device a Dr.Jit call of the request in force runs on: ``"cuda"`` or
    ``"llvm"`` as asked, else the first of :func:`devices` (CUDA where a GPU is found).
    Raises :class:`ValueError` naming what is missing where the request cannot run."""
    req = requested(backend)
    if req in DEVICES:
        if not device_available(req):
            have = ", ".join(devices()) or "none"
            raise ValueError(f"backend {req!r} was asked for ({ENV} or backend=), but Dr.Jit's {req.upper()} "
                             f"backend does not run on this machine ("
                             + ("no NVIDIA GPU or driver found" if req == "cuda" else "libLLVM not found")
                             + f"; Dr.Jit devices here: {have}); use backend 'auto', 'drjit' or 'numpy'")
        return req
    found = devices()
    if not found:
        raise ValueError(f"backend 'drjit' was asked for ({ENV} or backend=), but Dr.Jit with an LLVM or CUDA "
                         f"backend is not available; install the 'render' extra (pip install "
                         f"'plausible[render]') or use backend 'numpy' or 'auto'")
    return found[0]


def choose(rows: int, model=None, backend: str | None = None, min_rows: int = AUTO_MIN_ROWS,
           kernel: str = "eval") -> str:
    """``"numpy"`` or ``"drjit"`` for a call on ``rows`` direction pairs (see the
    module rule; ``auto`` picks Dr.Jit from ``min_rows``, or :data:`AUTO_MIN_NEW`
    for the first ``kernel`` of a model with these parameters)."""
    req = requested(backend)
    if req == "numpy" or rows == 0 or (model is not None and model in _NUMPY_ONLY):
        return "numpy"
    if req == "drjit" or req in DEVICES:
        device(req)         # raises where the device asked for does not run
        return "drjit"
    key = None if model is None else (kernel, kernel_key(model))
    if _EAGER.get():
        min_rows = min(min_rows, EAGER_MIN_ROWS)
    elif key is not None and key not in _TRACED:
        min_rows = max(min_rows, AUTO_MIN_NEW)
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

def jit_module(backend: str | None = None):
    """``drjit.cuda`` or ``drjit.llvm``: the array types of :func:`device`."""
    import importlib

    return importlib.import_module(f"drjit.{device(backend)}")


def _dr():
    import drjit as dr

    from .ops import drjit_ops

    m = jit_module()
    return dr, m.Float64, m.UInt32, drjit_ops(m.Float64)


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

    def raw_vectors(self, a: np.ndarray, check):
        """Components of the raw rows ``a`` (``(rows, 3)``, float32 or float64,
        C-contiguous; neither validated nor normalised) read per lane and converted
        to float64 in the kernel, through ``check(ops, components) -> (components,
        bad)`` (:func:`plausible.directions.unit_lanes`, or the identity with a check
        for ``u``).  ``a`` enters without a copy: Dr.Jit maps contiguous host memory."""
        dr, F = self.dr, self.Float64
        T = F if a.dtype == np.float64 else jit_module().Float32
        flat = T(a.reshape(-1))
        return check(self.ops, tuple(F(dr.gather(T, flat, self.row * 3 + k)) for k in range(3)))

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


def lane_divmod(dr, F, x, d: int):
    """``(x // d, x % d)`` of lane numbers ``x`` (a Float64 array of whole numbers)
    by a whole number ``d``, in float64 arithmetic: exact for fewer than 2^40
    lanes, and a vectorised multiply-floor is much faster than integer
    division, which LLVM does lane by lane.  ``d`` enters as kernel data."""
    q = dr.floor((x + 0.5) * dr.opaque(F, 1.0 / d))
    return q, x - q * dr.opaque(F, float(d))


def data_leaves(model) -> list:
    """The data parameters of ``model`` (the values :func:`kernel_view` converts),
    in the order its ``_kernel_view`` visits them."""
    out = []

    def record(v):
        out.append(v)
        return v

    model._kernel_view(record)
    return out


def _batch_tables(models):
    """The data leaves of ``models`` side by side, one ``(K, size)`` float array per
    leaf; None when the models do not share one structure leaf by leaf (then they
    cannot share a launch)."""
    st = structure_of(models[0])
    if st is None or any(structure_of(m) != st for m in models[1:]):
        return None
    per = [data_leaves(m) for m in models]
    if any(len(p) != len(per[0]) for p in per):
        return None
    tables = []
    for vals in zip(*per):
        shapes = {np.shape(v) for v in vals}
        if len(shapes) != 1:
            return None
        tables.append(np.array([np.asarray(v, dtype=np.float64).reshape(-1) for v in vals]))
    return tables


class PairKernel:
    """``f`` of many models at fixed direction pairs: the pairs enter once (unit
    ``(n, 3)`` arrays; the caller validates and normalises them).

    On Dr.Jit (``backend="drjit"``, the default) each call traces ``model._f``
    with the model's parameters as kernel data, so every model of one
    structure runs the same compiled kernel (a fit's objective, a parameter
    sweep).  ``kernel(model)`` is ``model.eval(wi, wo)``: ``(n,)`` or
    ``(n, channels)``; a model whose hooks do not run on Dr.Jit gets NumPy's
    ``model.eval`` (the rule of :func:`run`).  With ``backend="numpy"`` the
    hooks run on NumPy (the pairs are not validated again at each call).

    :meth:`many` evaluates a whole population of models of one structure (an
    optimiser's finite-difference points, a batch of candidates) together: ``K``
    models are ``K x n`` lanes in one Dr.Jit launch, each lane reading its
    model's parameters from a ``K``-row table, or on NumPy one pass with every
    parameter an array of ``K`` rows broadcast against the pairs.  The values
    are those of ``K`` single calls to rounding (``tests/fitting/test_fit.py``:
    1e-12)."""

    def __init__(self, wi: np.ndarray, wo: np.ndarray, backend: str = "drjit"):
        self.wi = np.ascontiguousarray(wi, dtype=np.float64).reshape(-1, 3)
        self.wo = np.ascontiguousarray(wo, dtype=np.float64).reshape(-1, 3)
        if self.wi.shape != self.wo.shape:
            raise ValueError(f"PairKernel: wi and wo must have the same shape, got {wi.shape} and {wo.shape}")
        if backend not in ("numpy", "drjit"):
            raise ValueError(f"PairKernel: backend must be 'numpy' or 'drjit', got {backend!r}")
        self.backend = backend
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

    def _numpy(self, model):
        return model._eval_block(self.wi, self.wo, (self.n,), "numpy")

    def __call__(self, model) -> np.ndarray:
        if self.backend == "numpy":
            return self._numpy(model)
        if model in _NUMPY_ONLY:
            return model.eval(self.wi, self.wo, backend="numpy")
        return run(model, "eval", lambda: model.eval(self.wi, self.wo, backend="numpy"), lambda: self._jit(model))

    def many(self, models) -> list:
        """``[self(m) for m in models]``, the models evaluated together (see the
        class); models that cannot share a pass (different structures, hooks that
        need their parameters as constants or NumPy) are evaluated one by one."""
        models = list(models)
        if len(models) < 2:
            return [self(m) for m in models]
        tables = _batch_tables(models)
        if tables is not None:
            try:
                if self.backend == "numpy":
                    return self._numpy_many(models, tables)
                st = structure_of(models[0])
                if st not in _CONSTANTS and not any(m in _NUMPY_ONLY for m in models):
                    token = _AS_DATA.set(True)
                    try:
                        with _JIT_LOCK:
                            return self._jit_many(models, tables)
                    finally:
                        _AS_DATA.reset(token)
            except (_NotJit, TypeError, AttributeError, ValueError, RuntimeError, IndexError):
                # a hook that branches on a value or calls NumPy on Dr.Jit arrays: one by one
                pass
        return [self(m) for m in models]

    def _shape(self, model, K):
        return (K, self.n) + ((model.channels,) if model.channels else ())

    def _numpy_many(self, models, tables):
        from .ops import NP

        m0, K = models[0], len(models)
        c = m0.channels
        it = iter(tables)

        def convert(v):
            t = next(it)
            if t.shape[1] == 1:         # a float: one value per model
                return t.reshape((K, 1, 1) if c else (K, 1))
            if c and t.shape[1] == c:   # a colour: one row of channels per model
                return t.reshape(K, 1, c)
            if not np.all(t == t[:1]):
                raise _NotJit("a data array that is not a colour differs between the models")
            return v

        view = m0._kernel_view(convert)
        comps = lambda a: tuple(x[:, None] if c else x for x in (a[:, 0], a[:, 1], a[:, 2]))  # noqa: E731
        with np.errstate(all="ignore"):
            f = view._f(NP, comps(self.wi), comps(self.wo), view.p)
        out = np.array(np.broadcast_to(f, self._shape(m0, K)), dtype=np.float64)
        return list(out)

    def _jit_many(self, models, tables):
        dr, F, U, ops = _dr()
        m0, K = models[0], len(models)
        c = m0.channels or 1
        per = self.n * c
        lane = F(dr.arange(U, K * per))
        k, r = lane_divmod(dr, F, lane, per)
        row, chan = lane_divmod(dr, F, r, c) if c > 1 else (r, None)
        k, row = U(k), U(row)
        chan = U(chan) if c > 1 else None
        _, wi1, wo1 = self._block(1)
        wi = tuple(dr.gather(F, x, row) for x in wi1)
        wo = tuple(dr.gather(F, x, row) for x in wo1)
        it = iter(tables)

        def convert(v):
            t = next(it)
            if t.shape[1] == 1:
                return dr.gather(F, F(t.reshape(-1)), k)
            if c > 1 and t.shape[1] == c:
                return dr.gather(F, F(t.reshape(-1)), k * dr.opaque(U, c) + chan)
            if not np.all(t == t[:1]):
                raise _NotJit("a data array that is not a colour differs between the models")
            return v

        view = m0._kernel_view(convert)
        f = view._f(ops, wi, wo, view.p)
        if not _is_jit(f):
            raise _NotJit(type(f).__name__)
        a = np.asarray(F(f).numpy(), dtype=np.float64)
        if a.size != K * per:
            raise _NotJit(f"{a.size} values for {K * per} lanes")
        return list(a.reshape(self._shape(m0, K)))


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


# -- the front end fused into the kernel: raw NumPy input, validation and normalisation on Dr.Jit

#: Lanes of one fused launch stay below this (a ``UInt32`` index of ``rows * reps * 3``).
FUSED_MAX_LANES = (1 << 32) // 3 - 1


def _inputs(L, a: np.ndarray, check):
    """``(components, bad)`` of one input of a fused call: one vector (``(3,)``,
    validated and normalised by the caller) as opaque scalars and ``bad`` None,
    else its raw rows through ``check`` (:meth:`_Lanes.raw_vectors`)."""
    if a.size == 3:
        return L.vectors(a), None
    return L.raw_vectors(a, check)


def _launch(L, values, masks):
    """Evaluate ``values`` (hook results and Python numbers) and the union of the
    bad ``masks`` in one kernel.  Returns ``(jit values, any bad)``."""
    dr = L.dr
    bad = None
    for m in masks:
        if m is not None:
            bad = m if bad is None else bad | m
    jit = [v for v in values if _is_jit(v)]
    dr.eval(*jit, *(() if bad is None else (bad,)))
    return values, bool(bad is not None and np.any(bad.numpy()))


def eval_fused(model, wi: np.ndarray, wo: np.ndarray, shape: tuple, unit) -> tuple:
    """:func:`eval_block` on raw ``wi``, ``wo`` (each one unit vector ``(3,)`` or
    raw rows of ``shape``; float32 or float64, C-contiguous): ``unit`` validates and
    normalises them in the same kernel as ``model._f``
    (:func:`plausible.directions.unit_lanes`).  Returns ``(values, bad)``: ``bad``
    True when a direction was NaN, infinite or zero (``values`` then mean nothing;
    the caller's NumPy checks raise the error)."""
    n = int(np.prod(shape))
    c = model.channels or 1
    L = _Lanes(n, c)
    v = L.view(model)
    (a, bad_a), (b, bad_b) = _inputs(L, wi, unit), _inputs(L, wo, unit)
    (f,), bad = _launch(L, [v._f(L.ops, a, b, v.p)], (bad_a, bad_b))
    return L.numpy(f, n * c).reshape(shape + ((model.channels,) if model.channels else ())), bad


def pdf_fused(model, wi: np.ndarray, wo: np.ndarray, shape: tuple, unit) -> tuple:
    """:func:`pdf_block` on raw input (as :func:`eval_fused`)."""
    n = int(np.prod(shape))
    L = _Lanes(n)
    m = L.view(model)
    (a, bad_a), (b, bad_b) = _inputs(L, wi, unit), _inputs(L, wo, unit)
    (v,), bad = _launch(L, [m._pdf(L.ops, a, b, m.q)], (bad_a, bad_b))
    return L.numpy(v, n).reshape(shape), bad


def sample_block(model, wi: np.ndarray, u: np.ndarray, shape: tuple, horizon: float):
    """``model._sample`` on Dr.Jit with the front end's bookkeeping (see
    :meth:`plausible.bxdf.BxDF._sample_block`, whose steps this repeats in the same
    order): normalise ``wo`` (a zero vector becomes ``(0, 0, -1)``), its pdf, ``f``,
    the validity mask, ``weight = f cos / pdf``.  Returns ``(wo, weight, pdf)``."""
    wi_in = lambda L: (L.vectors(_rows(wi, shape)), None)  # noqa: E731 - the lanes of one input
    u_in = lambda L: (L.vectors(_rows(u, shape)), None)  # noqa: E731
    return _sample(model, shape, horizon, wi_in, u_in)[:3]


def sample_fused(model, wi: np.ndarray, u: np.ndarray, shape: tuple, horizon: float, unit, interval) -> tuple:
    """:func:`sample_block` on raw ``wi`` and ``u`` (as :func:`eval_fused`): ``unit``
    validates and normalises ``wi`` in the kernel, ``interval(ops, components) ->
    (components, bad)`` checks ``u``.  Returns ``(wo, weight, pdf, bad)``."""
    return _sample(model, shape, horizon, lambda L: _inputs(L, wi, unit), lambda L: _inputs(L, u, interval))


def _sample(model, shape, horizon, wi_in, u_in):
    """The steps of :func:`sample_block`; ``wi_in(lanes)``, ``u_in(lanes)``: the
    inputs' ``(components, bad)`` read per lane.  One launch (two for a colour
    model: ``f`` per channel lane), every output evaluated together."""
    n = int(np.prod(shape))
    L = _Lanes(n)
    dr, ops = L.dr, L.ops
    (wi_c, bad_wi), (u_c, bad_u) = wi_in(L), u_in(L)
    mv = L.view(model)
    wo_c = mv._sample(ops, wi_c, u_c, mv.q)
    wo_c = tuple(x if _is_jit(x) else L.Float64(float(x)) for x in wo_c)
    if not all(_is_jit(x) for x in wo_c):
        raise _NotJit("sample")
    # the sampled direction, normalised (a zero vector becomes (0, 0, -1))
    x, y, z = wo_c
    nrm = dr.sqrt(x * x + y * y + z * z)
    pos = nrm > 0
    den = dr.select(pos, nrm, 1.0)
    x, y, z = (dr.select(pos, x / den, 0.0), dr.select(pos, y / den, 0.0), dr.select(pos, z / den, -1.0))
    wo_c = (x, y, z)
    # its pdf, the validity mask, cos / pdf
    pdf = mv._pdf(ops, wi_c, wo_c, mv.q)
    ok = (pdf > 1e-250) & (z > horizon) & (wi_c[2] > horizon)
    cos_over_pdf = dr.select(ok, z / dr.select(ok, pdf, 1.0), 0.0)
    pdf = dr.select(ok, pdf, 0.0)
    if model.channels:
        # f per channel lane, in a second launch that reads the first one's rows
        c = model.channels
        cos_over_pdf = dr.select(ok, cos_over_pdf, -1.0)   # -1: not a valid sample (ratios are >= 0)
        (x, y, z, cos_over_pdf, pdf), bad = _launch(L, [x, y, z, cos_over_pdf, pdf], (bad_wi, bad_u))
        C = _Lanes(n, c)
        wo_l = tuple(C.gather_rows(v) for v in (x, y, z))
        cv = C.view(model)
        f = cv._f(ops, wi_in(C)[0], wo_l, cv.p)
        r = C.gather_rows(cos_over_pdf)
        (w,), _ = _launch(C, [dr.select(r >= 0, f * r, 0.0)], ())
        weight = L.numpy(w, n * c).reshape(shape + (c,))
    else:
        f = mv._f(ops, wi_c, wo_c, mv.p)
        (w, x, y, z, pdf), bad = _launch(L, [dr.select(ok, f * cos_over_pdf, 0.0), x, y, z, pdf], (bad_wi, bad_u))
        weight = L.numpy(w, n).reshape(shape)
    wo = np.stack([L.numpy(v, n) for v in (x, y, z)], axis=-1).reshape(shape + (3,))
    return wo, weight, L.numpy(pdf, n).reshape(shape), bad


#: The alignment (bytes) of the arrays :func:`aligned` makes: 16 float64 lanes, the widest packet.
ALIGN = 128


def aligned(x, dtype) -> np.ndarray:
    """``x`` as an array of ``dtype`` whose rows (the last axis; a 1-D ``x`` is one row) are each
    contiguous and start at a multiple of :data:`ALIGN` bytes (a view into a slightly larger
    buffer).  Dr.Jit maps such memory without a copy and writes an input's alignment into the
    kernel: an address NumPy's allocator placed elsewhere would give another kernel for the same
    formula (a compilation per new call)."""
    x = np.asarray(x, dtype=dtype)
    rows = x.reshape(-1, x.shape[-1] if x.ndim else 1)
    k, n = rows.shape
    per = ALIGN // np.dtype(dtype).itemsize
    stride = -(-n // per) * per
    buf = np.empty(k * stride + per, dtype=dtype)
    off = (-buf.ctypes.data % ALIGN) // np.dtype(dtype).itemsize
    out = buf[off:off + k * stride].reshape(k, stride)[:, :n]
    out[...] = rows
    return out[0] if x.ndim <= 1 else out.reshape(x.shape[:-1] + (n,))


__all__ = ["ALIGN", "AUTO_MIN_NEW", "AUTO_MIN_NODES", "AUTO_MIN_ROWS", "CHOICES", "DEVICES", "ENV", "FUSED_MAX_LANES", "PairKernel", "aligned", "choose",
           "data_leaves", "device", "device_available", "devices", "drjit_available", "jit_module", "eval_fused", "kernel_key", "kernel_log", "kernel_view", "lane_divmod",
           "pdf_fused", "requested", "run", "sample_fused", "structure_of", "use"]
