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
    """One launch of :func:`grid_sums`: a lane per ``(incidence a, azimuth node j,
    channel)``, which sums its ``nt`` polar nodes in a loop of the kernel (a symbolic
    ``drjit.while_loop``: the per-azimuth values are read once per lane, and only the
    polar node's two values per iteration); the per-incidence sums over ``j`` are
    NumPy's (pairwise) sums of the lanes read back."""
    A, nt = theta.shape
    npp = phi.shape[1]
    lanes = A * npp * c
    # lane = (a * np + j) * c + chan, split with float64 arithmetic (exact for fewer
    # than 2^40 lanes; a vectorised multiply-floor is much faster than integer
    # division, which LLVM does lane by lane)
    lane = F(dr.arange(U, lanes))

    def divmod_(x, d):
        q = dr.floor((x + 0.5) * dr.opaque(F, 1.0 / d))
        return q, x - q * dr.opaque(F, float(d))

    pt, chan = divmod_(lane, c) if c > 1 else (lane, None)
    a, _ = divmod_(pt, npp)
    pj, a = U(pt), U(a)
    chan = U(chan) if c > 1 else dr.zeros(U, 1)

    def table(x):
        # a single value as an opaque scalar: a one-element array made from NumPy
        # memory enters the kernel with the alignment of its address, which varies,
        # and so would the kernel (two variants to compile)
        x = np.ascontiguousarray(x, dtype=np.float64).ravel()
        return dr.opaque(F, float(x[0])) if x.size == 1 else F(x)

    cp, sp = (dr.gather(F, table(x), pj) for x in (np.cos(phi), np.sin(phi)))
    wi = tuple(dr.gather(F, table(wis[:, k]), a) for k in range(3))
    row0 = a * dr.opaque(U, nt)          # the first polar node of the lane's incidence
    mv = kernel_view(model, dr, F, chan, c)
    if tmax is None:
        tabs = tuple(table(x) for x in (np.sin(theta), np.cos(theta), theta_w))
    else:   # the half-vector frame: h at (tmin + s tmax, phi), wo its mirror image of wi
        tabs = (table(theta), table(theta_w))
        tm = dr.gather(F, table(tmax), pj)
        t0 = dr.gather(F, table(tmin), pj) if tmin is not None else None

    def node(i):
        """``g`` times the polar weight at the lane's azimuth and polar node ``i``."""
        k = row0 + i
        if tmax is None:
            st, ct, wt = (dr.gather(F, x, k) for x in tabs)
            wo = (st * cp, st * sp, ct)
        else:
            t = dr.gather(F, tabs[0], k) * tm
            if t0 is not None:
                t = t + t0
            st, ct = dr.sincos(t)
            h = (st * cp, st * sp, ct)
            d = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]
            wo = tuple(2.0 * d * hk - wk for hk, wk in zip(h, wi))
            wt = dr.gather(F, tabs[1], k) * tm * st * (4.0 * d)
            ct = wo[2]
        if kind == "f":
            g = mv._f(ops, wi, wo, mv.p) * ct
        else:
            g = mv._pdf(ops, wi, wo, mv.q)
        if not (_is_jit(g) or isinstance(g, (int, float))):
            raise _NotJit(type(g).__name__)
        g = F(g)
        if tmax is not None:    # the contract's zero below the horizon (rounding at the edge s = 1)
            g = dr.select(wo[2] > 0, g, 0.0)
        return g * wt

    # Every lane runs the same count of iterations (the rows are padded to nt), and the
    # count is an opaque input: one kernel for every grid size.
    _, acc = dr.while_loop((dr.zeros(U, lanes), dr.zeros(F, lanes)), lambda i, acc: i < dr.opaque(U, nt),
                           lambda i, acc: (i + 1, acc + node(i)), labels=("i", "acc"), mode="symbolic")
    v = np.asarray(acc.numpy(), dtype=np.float64).reshape(A, npp, c) * np.asarray(phi_w)[:, :, None]
    if per_phi:
        return v.reshape(A * npp)
    return v.sum(axis=1).reshape(A * c)


__all__ = ["MAX_LANES", "grid_sums"]
