"""Tensor-product quadrature sums on Dr.Jit: many incidences' rules in one launch
(the kernels of :mod:`plausible.integrals.albedo`; :mod:`plausible.arrays.backend`
is the dispatcher that decides whether they run).
"""

from __future__ import annotations

import numpy as np

from .backend import _dr, _is_jit, _NotJit, kernel_view


# -- quadrature sums on Dr.Jit ------------------------------------------------------------

#: Largest number of lanes (nodes x channels) of one quadrature launch.
MAX_LANES = 1 << 27


def grid_sums(model, kind: str, wis: np.ndarray, theta, theta_w, phi, phi_w,
              per_phi: bool = False, tmax=None, tmin=None) -> np.ndarray:
    """Tensor-product quadrature sums for many incidences in one Dr.Jit launch:

    ``S[a] = sum_ij theta_w[a, i] phi_w[a, j] g(wis[a], wo(theta[a, i], phi[a, j]))``

    with ``g = f cos(theta_o)`` (``kind="f"``, one sum per channel) or the pdf
    (``kind="pdf"``); ``wo(theta, phi) = (sin t cos p, sin t sin p, cos t)``.  The node
    arrays have one row per incidence, padded with zero weights to a common
    length.  Every size enters the kernel as data (opaque), so the kernel is
    traced and compiled once per model and reused for any grid.  Returns ``(A,)``
    or ``(A, channels)``; with ``per_phi`` (``kind="pdf"`` only) the sums over ``i``
    alone, ``(A, n_phi)``.

    With ``tmax`` (an array shaped like ``phi``) the rule is in the half-vector frame
    of :func:`plausible.integrals.quadrature.half_vector_breaks`: ``theta`` holds
    ``s``, the half vector is at polar angle ``t = s tmax`` and azimuth ``phi``,
    ``wo = 2 (wi.h) h - wi``, and each node's weight is multiplied by
    ``tmax sin(t) 4 (wi.h)`` (``theta_w`` then holds no ``sin``); with ``tmin`` too (shaped
    alike) the polar angle is ``t = tmin + s tmax`` (``tmax`` the span)."""
    dr, F, U, ops = _dr()
    A, nt = theta.shape
    npp = phi.shape[1]
    c = (model.channels or 1) if kind == "f" else 1
    if per_phi and c != 1:
        raise ValueError("grid_sums: per_phi sums are for kind='pdf' or a scalar f")
    per = nt * npp * c
    group = max(1, MAX_LANES // max(per, 1))
    out = []
    for s in range(0, A, group):
        e = min(s + group, A)
        out.append(_grid_sums(dr, F, U, ops, model, kind, wis[s:e], theta[s:e], theta_w[s:e],
                              phi[s:e], phi_w[s:e], c, per_phi, None if tmax is None else tmax[s:e],
                              None if tmin is None else tmin[s:e]))
    res = np.concatenate(out)
    if per_phi:
        return res.reshape(A, npp)
    return res.reshape(A, c) if kind == "f" and model.channels else res


def _grid_sums(dr, F, U, ops, model, kind, wis, theta, theta_w, phi, phi_w, c, per_phi, tmax=None, tmin=None):
    A, nt = theta.shape
    npp = phi.shape[1]
    lanes = A * nt * npp * c
    # lane = ((a * nt + i) * np + j) * c + chan, split with float64 arithmetic (exact
    # for fewer than 2^40 lanes; a vectorised multiply-floor is much faster than
    # integer division, which LLVM does lane by lane)
    lane = F(dr.arange(U, lanes))

    def divmod_(x, d):
        q = dr.floor((x + 0.5) * dr.opaque(F, 1.0 / d))
        return q, x - q * dr.opaque(F, float(d))

    pt, chan = divmod_(lane, c) if c > 1 else (lane, None)
    row, j = divmod_(pt, npp)
    a, i = divmod_(row, nt)
    ti, pj, a = U(row), U(a * dr.opaque(F, float(npp)) + j), U(a)
    chan = U(chan) if c > 1 else dr.zeros(U, 1)
    cc = dr.opaque(U, c)

    def table(x):
        # a single value as an opaque scalar: a one-element array made from NumPy
        # memory enters the kernel with the alignment of its address, which varies,
        # and so would the kernel (two variants to compile)
        a = np.ascontiguousarray(x, dtype=np.float64).ravel()
        return dr.opaque(F, float(a[0])) if a.size == 1 else F(a)

    cp, sp, wp = (dr.gather(F, table(x), pj) for x in (np.cos(phi), np.sin(phi), phi_w))
    wi = tuple(dr.gather(F, table(wis[:, k]), a) for k in range(3))
    if tmax is None:
        st, ct, wt = (dr.gather(F, table(x), ti) for x in (np.sin(theta), np.cos(theta), theta_w))
        wo = (st * cp, st * sp, ct)
    else:   # the half-vector frame: h at (s tmax, phi), wo its mirror image of wi
        tm = dr.gather(F, table(tmax), pj)
        t = dr.gather(F, table(theta), ti) * tm
        if tmin is not None:
            t = t + dr.gather(F, table(tmin), pj)
        st, ct = dr.sincos(t)
        h = (st * cp, st * sp, ct)
        d = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]
        wo = tuple(2.0 * d * hk - wk for hk, wk in zip(h, wi))
        wt = dr.gather(F, table(theta_w), ti) * tm * st * (4.0 * d)
        ct = wo[2]
    mv = kernel_view(model, dr, F, chan, c)
    if kind == "f":
        g = mv._f(ops, wi, wo, mv.p) * ct
    else:
        g = mv._pdf(ops, wi, wo, mv.q)
    if not (_is_jit(g) or isinstance(g, (int, float))):
        raise _NotJit(type(g).__name__)
    if tmax is not None:    # the contract's zero below the horizon (rounding at the edge s = 1)
        g = dr.select(wo[2] > 0, F(g), 0.0)
    v = F(g) * (wt * wp)
    # The reduction mode is named: Dr.Jit's default for a small target on LLVM
    # (``Expand``, a copy per thread) writes the target's size into the kernel, so every
    # new count of sums (incidences, azimuth nodes) compiled a new kernel.  ``Direct``
    # (atomics) suits the per-azimuth sums, whose neighbouring lanes add to different
    # sums; ``Local`` (reduced within a packet first) the per-incidence ones, whose
    # neighbouring lanes add to the same sum.
    if per_phi:
        total = dr.zeros(F, A * npp)
        dr.scatter_reduce(dr.ReduceOp.Add, total, v, pj, mode=dr.ReduceMode.Direct)
    else:
        total = dr.zeros(F, A * c)
        dr.scatter_reduce(dr.ReduceOp.Add, total, v, a * cc + chan, mode=dr.ReduceMode.Local)
    return np.asarray(total.numpy(), dtype=np.float64)


__all__ = ["MAX_LANES", "grid_sums"]
