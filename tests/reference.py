"""Independent reference methods shared by the model tests: tensor Gauss-Legendre
quadrature over the hemisphere, a half-vector albedo quadrature for microfacet
lobes, Monte Carlo with a model's own sampler, a fixed-grid chi-square test, and
the contract's consistency checks.  None of them uses :mod:`plausible.analysis`,
so they are a second method to test it and the models against."""

import math

import numpy as np
import pytest
from scipy import special, stats

from plausible.arrays.ops import NP

TWO_PI = 2.0 * math.pi


def unit(v):
    v = np.asarray(v, dtype=np.float64)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def from_angles(theta_deg, phi_deg=0.0):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


def hemisphere_rule(nmu, nphi, mu=(0.0, 1.0), phi=(0.0, TWO_PI)):
    """Gauss-Legendre in ``cos(theta)`` times Gauss-Legendre in ``phi``:
    directions (N, 3) and solid-angle weights (N,)."""
    xm, wm = special.roots_legendre(nmu)
    xp, wp = special.roots_legendre(nphi)
    m = 0.5 * (mu[1] - mu[0]) * xm + 0.5 * (mu[1] + mu[0])
    wm = 0.5 * (mu[1] - mu[0]) * wm
    ph = 0.5 * (phi[1] - phi[0]) * xp + 0.5 * (phi[1] + phi[0])
    wp = 0.5 * (phi[1] - phi[0]) * wp
    M, P = np.meshgrid(m, ph, indexing="ij")
    s = np.sqrt(1.0 - M * M)
    dirs = np.stack([s * np.cos(P), s * np.sin(P), M], axis=-1).reshape(-1, 3)
    return dirs, np.outer(wm, wp).reshape(-1)


def quad_albedo(model, wi, nmu=200, nphi=400):
    dirs, w = hemisphere_rule(nmu, nphi)
    f = model.eval(wi, dirs)
    return float(np.sum(f * dirs[:, 2] * w))


def mc_albedo(model, wi, n=200_000, seed=1):
    u = np.random.default_rng(seed).random((n, 3))
    w = model.sample(wi, u).weight
    return float(w.mean()), float(w.std() / math.sqrt(n))


def mc_albedos(model, wi, n, seed):
    """Monte Carlo albedo with the model's own sampler: (mean, standard error)
    of the channel-mean weight, for each leading index of ``wi`` (k, 3)."""
    wi = np.atleast_2d(wi)[:, None, :]
    u = np.random.default_rng(seed).random((wi.shape[0], n, 3))
    w = model.sample(wi, u).weight
    if w.ndim == 3:
        w = w.mean(axis=-1)
    return w.mean(axis=1), w.std(axis=1, ddof=1) / math.sqrt(n)


def chi2_sampler_pvalue(model, wi, n=100_000, nmu=10, nphi=20, seed=7, sub=12):
    """Chi-square test of ``model.sample`` against ``model.pdf``.

    Cells of equal solid angle (uniform in ``cos(theta)`` and ``phi``), each
    cell's expected count from a ``sub x sub`` Gauss-Legendre rule on the pdf,
    one more cell for samples rejected below the horizon (expected: the mass
    the pdf misses on the hemisphere); cells expecting fewer than 5 are pooled.
    """
    u = np.random.default_rng(seed).random((n, 3))
    s = model.sample(wi, u)
    ok = s.pdf > 0
    wo = s.wo[ok]
    phi = np.mod(np.arctan2(wo[:, 1], wo[:, 0]), TWO_PI)
    mu_edges = np.linspace(0.0, 1.0, nmu + 1)
    phi_edges = np.linspace(0.0, TWO_PI, nphi + 1)
    obs, _, _ = np.histogram2d(wo[:, 2], phi, bins=[mu_edges, phi_edges])
    exp = np.empty((nmu, nphi))
    for i in range(nmu):
        for j in range(nphi):
            d, w = hemisphere_rule(sub, sub, (mu_edges[i], mu_edges[i + 1]),
                                   (phi_edges[j], phi_edges[j + 1]))
            exp[i, j] = np.sum(model.pdf(wi, d) * w)
    obs = np.append(obs.ravel(), n - ok.sum())
    exp = np.append(exp.ravel() * n, n * (1.0 - exp.sum()))
    exp = np.maximum(exp, 0.0)
    small = exp < 5
    if small.any():
        obs = np.append(obs[~small], obs[small].sum())
        exp = np.append(exp[~small], exp[small].sum())
    keep = exp > 0
    assert np.all(obs[~keep] == 0), "samples where the pdf is zero"
    chi2 = float(np.sum((obs[keep] - exp[keep]) ** 2 / exp[keep]))
    return float(stats.chi2.sf(chi2, keep.sum() - 1))


def end_clustered_nodes(a, b, n):
    """Gauss-Legendre on [a, b] through t = (1 - cos(pi s)) / 2 (nodes clustered at both ends)."""
    x, w = np.polynomial.legendre.leggauss(n)
    s = 0.5 * (x + 1.0)
    t = 0.5 * (1.0 - np.cos(np.pi * s))
    return a + (b - a) * t, (b - a) * 0.25 * np.pi * np.sin(np.pi * s) * w


def halfvector_albedo(model, theta_i, width, n=200, tails=8.0):
    """Directional albedo of ``model`` at incidence ``theta_i`` (in the xz plane), integrated over
    the half vector: ``a = int f cos_o 4 (wi.h) d omega_h`` (d omega_o = 4 (wi.h) d omega_h).

    ``theta_h`` runs over ``[0, atan(tails * width)]`` (a Beckmann/Ward lobe of slope ``width``
    carries less than ``exp(-tails^2)`` beyond), split where the horizon starts to cut the
    ``phi`` circle (``theta_h = (pi/2 - theta_i) / 2``); for each ``theta_h`` only the ``phi``
    with ``wo.z > 0`` are integrated (``|phi| < phi*``, closed form), with ``phi = phi* (1 - v^2)``
    so that ``sqrt(cos_o)`` behaviour at the horizon is smooth in ``v``.
    """
    si, ci = math.sin(theta_i), math.cos(theta_i)
    wi = np.array([si, 0.0, ci])
    tmax = math.atan(tails * width)
    tk = 0.5 * (0.5 * math.pi - theta_i)
    cuts = [0.0] + ([tk] if 0 < tk < tmax else []) + [tmax]
    total = 0.0
    v, wv = end_clustered_nodes(0.0, 1.0, n)
    for a, b in zip(cuts[:-1], cuts[1:]):
        th, wt = end_clustered_nodes(a, b, n)
        with np.errstate(all="ignore"):
            cstar = -ci * np.cos(2 * th) / (np.sin(2 * th) * si) if si > 0 else np.full_like(th, -np.inf)
        phs = np.arccos(np.clip(np.nan_to_num(cstar, nan=-1.0, neginf=-1.0), -1.0, 1.0))
        st = np.sin(th)[:, None]
        for sign in (1.0, -1.0):
            phi = sign * phs[:, None] * (1.0 - v[None, :] ** 2)
            jac = phs[:, None] * 2.0 * v[None, :]
            h = np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(th)[:, None]), -1)
            kh = h @ wi
            wo = 2.0 * kh[..., None] * h - wi
            f = model.eval(wi, wo)
            g = f * np.maximum(wo[..., 2], 0.0) * 4.0 * kh * st
            total += np.einsum("i,ij,ij,j->", wt, g, jac, wv)
    return float(total)


def mc_albedo_at(model, theta_i, n=200_000, seed=0):
    """Monte Carlo albedo with the model's own sampler: mean and standard error of the weight."""
    wi = np.array([math.sin(theta_i), 0.0, math.cos(theta_i)])
    u = np.random.default_rng(seed).random((n, 3))
    w = model.sample(wi, u).weight
    return float(w.mean()), float(w.std() / math.sqrt(n))


def check_sampling(model, wi, n=20_000, seed=1):
    """weight == f cos / pdf and pdf(wi, wo) == returned pdf for sampled directions."""
    wi = np.asarray(wi, float) / np.linalg.norm(wi)
    u = np.random.default_rng(seed).random((n, 3))
    s = model.sample(wi, u)
    ok = s.pdf > 0
    assert ok.mean() > 0.5
    pdf = model.pdf(wi, s.wo[ok])
    assert np.allclose(pdf, s.pdf[ok], rtol=1e-10, atol=0)
    f = model.eval(wi, s.wo[ok])
    expect = f * (s.wo[ok, 2] / s.pdf[ok])[(...,) + (None,) * (f.ndim - 1)]
    assert np.allclose(s.weight[ok], expect, rtol=1e-10, atol=1e-300)
    assert np.all(s.weight[~ok] == 0)


def check_reciprocal(model, n=2000, seed=2):
    rng = np.random.default_rng(seed)
    a = rng.normal(size=(n, 3)); a[:, 2] = np.abs(a[:, 2]) + 1e-3
    b = rng.normal(size=(n, 3)); b[:, 2] = np.abs(b[:, 2]) + 1e-3
    fa, fb = model.eval(a, b), model.eval(b, a)
    assert np.allclose(fa, fb, rtol=1e-11, atol=1e-300)


def hooks_agree(model, wi, wo, u, *, rtol=1e-12, atol=1e-300, rtol_sample=1e-9, atol_sample=1e-12,
                finite=False):
    """The one-math rule: ``_f`` (per colour channel), ``_pdf`` and ``_sample`` give
    the same numbers on ``drjit.llvm.Float64`` arrays as on NumPy (``finite``: and
    ``_f`` and ``_pdf`` are finite on both).  Skips where Dr.Jit's LLVM backend is
    missing.  Returns the NumPy pdf and sample."""
    try:
        from drjit.llvm import Float64
        Float64(1.0) + 1.0
    except Exception as e:  # pragma: no cover - only where Dr.Jit/LLVM is missing
        pytest.skip(f"Dr.Jit LLVM backend unavailable: {e}")
    from types import SimpleNamespace

    from plausible.arrays.ops import drjit_ops

    ops = drjit_ops(Float64)
    n = len(wi)

    def comp(a):
        return tuple(np.ascontiguousarray(a[:, k]) for k in range(3))

    def dcomp(a):
        return tuple(Float64(x) for x in comp(a))

    for c in range(model.channels or 1):
        pc = SimpleNamespace(**{k: (float(v[c]) if isinstance(v, np.ndarray) else v)
                                for k, v in vars(model.p).items()})
        ref = np.broadcast_to(model._f(NP, comp(wi), comp(wo), pc), (n,))
        got = np.broadcast_to(np.asarray(model._f(ops, dcomp(wi), dcomp(wo), pc), dtype=np.float64), (n,))
        np.testing.assert_allclose(got, ref, rtol=rtol, atol=atol)
        assert not finite or np.all(np.isfinite(ref))
    pdf = np.broadcast_to(model._pdf(NP, comp(wi), comp(wo), model.q), (n,))
    got = np.broadcast_to(np.asarray(model._pdf(ops, dcomp(wi), dcomp(wo), model.q), dtype=np.float64), (n,))
    np.testing.assert_allclose(got, pdf, rtol=rtol, atol=atol)
    assert not finite or np.all(np.isfinite(pdf))
    smp = model._sample(NP, comp(wi), comp(u), model.q)
    got = model._sample(ops, dcomp(wi), dcomp(u), model.q)
    for r, g in zip(smp, got):
        np.testing.assert_allclose(np.broadcast_to(np.asarray(g, dtype=np.float64), (n,)),
                                   np.broadcast_to(r, (n,)), rtol=rtol_sample, atol=atol_sample)
    return pdf, smp


def check_drjit(model, n=500, seed=3):
    """:func:`hooks_agree` on random incidences and directions from the model's sampler."""
    rng = np.random.default_rng(seed)
    wi = rng.normal(size=(n, 3)); wi[:, 2] = np.abs(wi[:, 2])
    wi /= np.linalg.norm(wi, axis=1, keepdims=True)
    u = rng.random((n, 3))
    wo = model.sample(wi, u).wo
    hooks_agree(model, wi, wo, u, rtol=1e-10, atol=1e-12, rtol_sample=1e-10, atol_sample=1e-12)


def as_specular_albedo_at_normal(nu, nv, rs):
    """Directional albedo of the Ashikhmin-Shirley specular term at normal incidence, as a
    1-D integral: with ``wi = n``, ``h.k = cos(theta_h) = c``, ``theta_o = 2 theta_h`` and
    ``max(cos i, cos o) = 1``, ``a = sqrt((nu+1)(nv+1))/(8 pi) int c^e F(c) / c cos(2 theta_h)
    4 c dw_h``; the azimuthal integral of ``c^(nu cos^2 + nv sin^2)`` is
    ``2 pi c^((nu+nv)/2) I0((nu-nv)/2 ln c)`` (a Bessel function, scaled as ``i0e``)."""
    from scipy import integrate, special

    def g(t):
        c = math.cos(t)
        a, b = 0.5 * (nu + nv) * math.log(c), abs(0.5 * (nu - nv) * math.log(c))
        fres = rs + (1 - rs) * (1 - c) ** 5
        return math.exp(a + b) * special.i0e(b) * fres * math.cos(2 * t) * math.sin(t)

    pts = [x for x in (1e-4, 1e-3, 1e-2, 0.1) if x < math.pi / 4]
    val = integrate.quad(g, 0.0, math.pi / 4, points=pts, limit=500, epsabs=0, epsrel=1e-11)[0]
    return math.sqrt((nu + 1) * (nv + 1)) / (8 * math.pi) * 4 * 2 * math.pi * val


def as_specular_albedo(nu, nv, wi):
    """Directional albedo of the Ashikhmin-Shirley specular term with ``rs = 1`` (Schlick's
    factor exactly 1) at any incidence ``wi``, from the closed form alone (no model code):
    ``a = int p_h(h) min(1, wo_z / wi_z) d omega_h`` over the half vectors whose mirror image
    ``wo`` of ``wi`` lies above the horizon (``f cos_o d omega_o = p_h / (4 (k.h) max(ci, co))
    co 4 (k.h) d omega_h``), ``p_h = sqrt((nu+1)(nv+1)) / (2 pi) cos(t)^(nu cos^2 phi + nv sin^2 phi)``.

    Nested adaptive Gauss-Kronrod (SciPy ``quad``): for each azimuth ``phi`` of ``h`` the polar
    angle ``t`` runs to the horizon ``pi/4 + delta/2`` with the kink of ``min`` at ``t = delta``
    (``wo_z = R cos(2t - delta)``, ``delta = atan2(sin(theta_i) cos(phi - phi_i), cos(theta_i))``)
    and the lobe's width ``1/sqrt(e)`` as break points; the azimuths are split at the tangent
    axes, the plane of incidence and its normal, each with points 1e-6 to 0.1 away.  Agrees with
    the exact values of issue 45 (mpmath) to 1e-11 and with the other order of integration
    (``t`` outside) to 1e-11 on the issue's cases."""
    from scipy import integrate

    wi = np.asarray(wi, dtype=np.float64) / np.linalg.norm(wi)
    ci, si, phi_i = wi[2], math.hypot(wi[0], wi[1]), math.atan2(wi[1], wi[0])

    def inner(phi):
        e = nu * math.cos(phi) ** 2 + nv * math.sin(phi) ** 2
        r = math.hypot(si * math.cos(phi - phi_i), ci)
        delta = math.atan2(si * math.cos(phi - phi_i), ci)
        tmax = 0.25 * math.pi + 0.5 * delta

        def g(t):
            return math.cos(t) ** e * math.sin(t) * min(1.0, r * math.cos(2 * t - delta) / ci)

        w = 1.0 / math.sqrt(e + 1.0)
        pts = sorted({p for p in (max(delta, 0.0), w, 3 * w, 10 * w, 30 * w) if 0 < p < tmax})
        return integrate.quad(g, 0.0, tmax, points=pts or None, epsabs=1e-15, epsrel=1e-13, limit=1000)[0]

    edges = {0.0, TWO_PI}
    for c in (0.0, 0.5 * math.pi, math.pi, 1.5 * math.pi, phi_i, phi_i + math.pi, phi_i + 0.5 * math.pi,
              phi_i - 0.5 * math.pi):
        for d in (0.0, 1e-6, -1e-6, 1e-4, -1e-4, 1e-3, -1e-3, 1e-2, -1e-2, 0.1, -0.1):
            edges.add((c + d) % TWO_PI)
    edges = sorted(edges)
    total = sum(integrate.quad(inner, a, b, epsabs=1e-15, epsrel=1e-13, limit=500)[0]
                for a, b in zip(edges[:-1], edges[1:]) if b > a)
    return math.sqrt((nu + 1) * (nv + 1)) / (2 * math.pi) * total


def _vgroove_wo_kink(ci, r, delta, tmax):
    """Polar angle ``t`` of the half vector in ``(0, tmax)`` where ``2 (n.h)(n.wo) = wo.h`` (the
    V-groove's ``wo`` term reaches 1), by bisection of ``d (4 cos^2 t - 1) - 2 ci cos t``
    (``d = wi.h = r cos(t - delta)``, ``n.wo = 2 d cos t - ci``): ``ci > 0`` at ``t = 0``, ``-d < 0``
    at the horizon."""
    from scipy import optimize

    def g(t):
        d = r * math.cos(t - delta)
        return d * (4.0 * math.cos(t) ** 2 - 1.0) - 2.0 * ci * math.cos(t)

    return optimize.brentq(g, 0.0, tmax, xtol=1e-15, rtol=1e-15)


def ct_vgroove_albedo(m, cos_i):
    """Directional albedo of Cook-Torrance with ``F = 1``, Beckmann ``D`` of slope ``m`` and the
    V-groove ``G`` at incidence ``cos_i`` (isotropic: the incidence's azimuth is 0), from the
    closed forms alone (no model code): ``a = int D(h) G (k.h) / cos_i d omega_h`` over the half
    vectors whose mirror image ``wo`` lies above the horizon (``f cos_o d omega_o =
    D G / (4 ci co) co 4 (k.h) d omega_h``), ``D = exp(-tan^2 t / m^2) / (pi m^2 cos^4 t)``,
    ``G = min(1, 2 cos t co / (k.h), 2 cos t ci / (k.h))``.

    Nested adaptive Gauss-Kronrod (SciPy ``quad``) over the azimuth ``phi`` of ``h`` in
    ``[0, pi]`` (twice: the integrand is even in ``phi``) and, inside, the polar angle ``t`` to
    the horizon ``pi/4 + delta/2``, split at both kinks of ``G`` (the ``wi`` term's at
    ``t = pi/2 - delta`` where ``delta > pi/6``, the ``wo`` term's by bisection) and at the lobe's
    widths ``m, 3 m, 10 m, 30 m``; the azimuths split near the plane of incidence and where the
    ``wi`` term's kink enters the range (``delta = pi/6``: a kink of the inner integral in ``phi``)."""
    from scipy import integrate

    ci = float(cos_i)
    si = math.sqrt(1.0 - ci * ci)

    def inner(phi):
        delta = math.atan2(si * math.cos(phi), ci)
        r = math.hypot(si * math.cos(phi), ci)
        tmax = 0.25 * math.pi + 0.5 * delta

        def g(t):
            c = math.cos(t)
            d = r * math.cos(t - delta)
            co = 2.0 * d * c - ci
            if co <= 0.0 or d <= 0.0:
                return 0.0
            dist = math.exp(-math.tan(t) ** 2 / (m * m)) / (math.pi * m * m * c ** 4)
            geo = min(1.0, 2.0 * c * co / d, 2.0 * c * ci / d)
            return dist * geo * d / ci * math.sin(t)

        kinks = [_vgroove_wo_kink(ci, r, delta, tmax)] + ([0.5 * math.pi - delta] if delta > math.pi / 6 else [])
        pts = sorted({p for p in kinks + [m, 3 * m, 10 * m, 30 * m] if 0.0 < p < tmax})
        return integrate.quad(g, 0.0, tmax, points=pts, epsabs=1e-15, epsrel=1e-13, limit=1000)[0]

    edges = {0.0, math.pi} | {x for d in (1e-4, 1e-3, 1e-2, 0.1, 0.3, 1.0) for x in (d, math.pi - d)}
    if si > math.sqrt(3.0) * ci:        # the azimuth where the wi term's kink enters (delta = pi/6)
        edges.add(math.acos(ci / (math.sqrt(3.0) * si)))
    edges = sorted(edges)
    return 2.0 * sum(integrate.quad(inner, a, b, epsabs=1e-15, epsrel=1e-13, limit=500)[0]
                     for a, b in zip(edges[:-1], edges[1:]))
