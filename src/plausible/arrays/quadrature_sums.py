"""Tensor-product quadrature sums on Dr.Jit: many incidences' rules in one launch
(the kernels of :mod:`plausible.integrals.albedo`; :mod:`plausible.arrays.backend`
is the dispatcher that decides whether they run).
"""

from __future__ import annotations

import numpy as np

from .backend import _dr, _is_jit, _NotJit, aligned, kernel_view


# -- quadrature sums on Dr.Jit ------------------------------------------------------------

#: Largest number of nodes (x channels) of one quadrature launch.
MAX_LANES = 1 << 27


def tensor_sums(model, kind: str, grids, per_phi: bool = False) -> list:
    """Tensor-product quadrature sums of many grids, each at its own incidence, in one
    Dr.Jit launch (more only beyond :data:`MAX_LANES` nodes):

    ``S = sum_ij theta_w[i] phi_w[j] g(wi, wo(theta[i], phi[j]))``

    for each grid ``(wi, theta, theta_w, phi, phi_w, tmin, tmax)`` of ``grids`` (1-D
    arrays of any lengths; ``tmin``, ``tmax`` None or shaped like ``phi``), with ``g = f
    cos(theta_o)`` (``kind="f"``, one sum per channel) or the pdf (``kind="pdf"``) and
    ``wo(theta, phi) = (sin t cos p, sin t sin p, cos t)``.  With ``tmax`` the rule is in
    the half-vector frame of :func:`plausible.integrals.quadrature.half_vector_breaks`:
    ``theta`` holds ``s``, the half vector is at polar angle ``t = tmin + s tmax`` (``tmin``
    0 when None) and azimuth ``phi``, ``wo = 2 (wi.h) h - wi``, and each node's weight is
    multiplied by ``tmax sin(t) 4 (wi.h)`` (``theta_w`` then holds no ``sin``).  Every grid
    of one call is in the same frame.

    One lane per azimuth node (and channel) of every grid sums its grid's polar
    nodes in a loop of the kernel (a symbolic ``drjit.while_loop``, as many
    iterations as the grid has polar nodes): the azimuth's values are read once, the
    polar node's two per iteration, and no grid is padded to another's size.  Every
    size and count enters as data, so the kernel is traced and compiled once per
    model and frame and reused for any grids.  Returns one result per grid: a float,
    or a ``(channels,)`` array for a colour ``f``; with ``per_phi`` (``kind="pdf"`` or a
    scalar ``f``) the sums over ``i`` alone, one per azimuth node."""
    c = (model.channels or 1) if kind == "f" else 1
    if per_phi and c != 1:
        raise ValueError("tensor_sums: per_phi sums are for kind='pdf' or a scalar f")
    zero = np.zeros(c) if model.channels and kind == "f" else 0.0
    out = [np.zeros(len(g[3])) if per_phi else zero for g in grids]
    batches, size = [[]], 0             # grids of each launch, at most MAX_LANES nodes (x channels) each
    for k, g in enumerate(grids):
        n = len(g[1]) * len(g[3]) * c
        if n == 0:
            continue
        if batches[-1] and size + n > MAX_LANES:
            batches.append([])
            size = 0
        batches[-1].append(k)
        size += n
    for batch in filter(None, batches):
        for j, v in zip(batch, _tensor_sums(model, kind, [grids[j] for j in batch], c, per_phi)):
            out[j] = v
    return out


def _tensor_sums(model, kind, grids, c, per_phi):
    """One launch of :func:`tensor_sums`."""
    dr, F, U, ops = _dr()
    half = grids[0][6] is not None
    nt = np.array([len(g[1]) for g in grids])
    npp = np.array([len(g[3]) for g in grids])
    t_off = np.concatenate([[0], np.cumsum(nt)[:-1]])
    # per lane (grid a, azimuth node j, channel): its grid's first polar node, their count,
    # its incidence and its azimuth's values; channel fastest
    cols = int(npp.sum())
    owner = np.repeat(np.arange(len(grids)), npp)

    # Every array enters from NumPy memory aligned to 128 bytes (:func:`~plausible.arrays.backend.aligned`): Dr.Jit maps
    # it without a copy and writes its alignment into the kernel, which would otherwise vary
    # with the address NumPy's allocator gives (a compilation per new call).
    def per_lane(x):
        return F(aligned(np.repeat(x, c) if c > 1 else x, np.float64))

    def per_lane_u(x):
        return U(aligned(np.repeat(x, c) if c > 1 else x, np.uint32))

    phi = np.concatenate([g[3] for g in grids])
    cp, sp = per_lane(np.cos(phi)), per_lane(np.sin(phi))
    wis = np.array([g[0] for g in grids], dtype=np.float64)
    wi = tuple(per_lane(wis[owner, k]) for k in range(3))
    row0, count = per_lane_u(t_off[owner]), per_lane_u(nt[owner])
    chan = U(aligned(np.tile(np.arange(c), cols), np.uint32)) if c > 1 else dr.zeros(U, 1)
    th = np.concatenate([g[1] for g in grids])
    theta = F(aligned(th, np.float64))
    theta_w = F(aligned(np.concatenate([g[2] for g in grids]), np.float64))
    mv = kernel_view(model, dr, F, chan, c)
    if half:   # the half-vector frame: h at (tmin + s tmax, phi), wo its mirror image of wi
        tm = per_lane(np.concatenate([g[6] for g in grids]))
        t0 = per_lane(np.concatenate([np.zeros(len(g[3])) if g[5] is None else g[5] for g in grids]))
    else:
        st_tab, ct_tab = F(aligned(np.sin(th), np.float64)), F(aligned(np.cos(th), np.float64))

    def node(i):
        """``g`` times the polar weight at the lane's azimuth and its grid's polar node ``i``."""
        k = row0 + i
        if half:
            t = dr.gather(F, theta, k) * tm + t0
            st, ct = dr.sincos(t)
            h = (st * cp, st * sp, ct)
            d = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]
            wo = tuple(2.0 * d * hk - wk for hk, wk in zip(h, wi))
            wt = dr.gather(F, theta_w, k) * tm * st * (4.0 * d)
            ct = wo[2]
        else:
            st, ct, wt = (dr.gather(F, x, k) for x in (st_tab, ct_tab, theta_w))
            wo = (st * cp, st * sp, ct)
        if kind == "f":
            g = mv._f(ops, wi, wo, mv.p) * ct
        else:
            g = mv._pdf(ops, wi, wo, mv.q)
        if not (_is_jit(g) or isinstance(g, (int, float))):
            raise _NotJit(type(g).__name__)
        g = F(g)
        if half:    # the contract's zero below the horizon (rounding at the edge s = 1)
            g = dr.select(wo[2] > 0, g, 0.0)
        return g * wt

    lanes = cols * c
    _, acc = dr.while_loop((dr.zeros(U, lanes), dr.zeros(F, lanes)), lambda i, acc: i < count,
                           lambda i, acc: (i + 1, acc + node(i)), labels=("i", "acc"), mode="symbolic")
    v = np.asarray(acc.numpy(), dtype=np.float64).reshape(cols, c) * np.concatenate([g[4] for g in grids])[:, None]
    starts = np.concatenate([[0], np.cumsum(npp)[:-1]])
    if per_phi:
        return [v[a:a + n, 0] for a, n in zip(starts, npp)]
    sums = np.add.reduceat(v, starts, axis=0)
    return [x if model.channels and kind == "f" else float(x[0]) for x in sums]


__all__ = ["MAX_LANES", "tensor_sums"]
