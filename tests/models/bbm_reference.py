"""bbm's definitions of the fitted models, written again here from its headers (P. Peers,
https://github.com/bsdfbenchmark/bbm, commit 9807fb3: include/bsdfmodel/he.h, ngan.h,
lowmicrofacet.h, lowsmooth.h, low.h, include/ndf/low.h, include/bbm/fresnel_cook.h,
maskingshadowing/vgroove.h, backbone wavelength()), step by step as bbm computes them,
its stopping rules and channel coupling included, in plain Python/NumPy.  The tests
compare plausible's models and the loaded fits with these (the fits' own definitions)."""

import math

import numpy as np
from scipy.special import gammaln

WAVELENGTHS = np.array([0.645, 0.526, 0.444])   # bbm Config::wavelength(), micrometres
EPS = np.finfo(float).eps                      # bbm Constants::Epsilon() for double


def cook_fresnel(eta, c):
    """bbm fresnel::cook: g = sqrt(eta^2 + c^2 - 1), 1/2 a^2 (1 + b^2)."""
    g = math.sqrt(max(eta * eta + c * c - 1.0, 0.0))
    if g + c == 0:
        return math.nan            # bbm: 0/0 (eta = 1 at grazing)
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1.0) / (c * (g - c) + 1.0)
    return max(0.5 * a * a * (1.0 + b * b), 0.0)


def _tan(v):
    return math.sqrt(v[0] ** 2 + v[1] ** 2) / v[2]


def nganhe(wi, wo, albedo, roughness, autocorrelation, eta, newton_steps=4, taylor_terms=64,
           threshold=18.0, stop=np.min):
    """bbm::nganhe = scaledmodel(he_base<cook, Errata, Westin, 4, 64, adaptive, 18>): RGB.
    ``stop``: the reduction over the channels in bbm's stopping rule (``hmin``); ``np.max``
    sums every term up to ``taylor_terms`` for every channel (the series without bbm's
    truncation)."""
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    if wi[2] <= 0 or wo[2] <= 0:
        return np.zeros(3)
    s0, tau = roughness, autocorrelation

    def S1(v):
        cot = 1.0 / _tan(v) if _tan(v) > 0 else math.inf
        x = tau * cot / (2.0 * s0)
        e = 0.5 * math.erfc(x)
        lam = 0.5 / math.sqrt(math.pi) / x * math.exp(-x * x) - e   # eq. 25 with the errata
        return (1.0 - e) / (lam + 1.0)

    S = S1(wi) * S1(wo)
    v = wi + wo
    vscale = (np.dot(v, v) / v[2]) ** 2
    kixn2, krxn2 = 1 - wi[2] ** 2, 1 - wo[2] ** 2
    kikr = float(np.dot(-wi, wo))
    sikr = wo[1] * wi[0] - wo[0] * wi[1]
    srki = wi[1] * wo[0] - wi[0] * wo[1]
    pikr = wo[2] + kikr * wi[2]
    prki = wi[2] + kikr * wo[2]
    denom = (1.0 - kikr * kikr) ** 2
    nom = (sikr ** 2 + pikr ** 2) * (srki ** 2 + prki ** 2) / (krxn2 * kixn2)
    G = vscale * nom / denom if denom > EPS else 1.0

    def K(t):
        return t * math.erfc(tau / (2 * s0 * t)) if t > EPS else 0.0
    f0 = (K(_tan(wi)) + K(_tan(wo))) / math.sqrt(8 * math.pi)
    x = f0 if f0 <= 1 else math.sqrt(max(2 * math.log(f0), 0.0))
    for _ in range(newton_steps):
        ex = math.exp(0.5 * x * x)
        val, grad = x * ex - f0, (1 + x * x) * ex
        x -= val / grad if grad > EPS else 0.0
    sigma = s0 / math.sqrt(1 + x * x)

    lam = WAVELENGTHS
    vxy2 = (wi[0] + wo[0]) ** 2 + (wi[1] + wo[1]) ** 2
    g = (2 * math.pi * sigma * (wi[2] + wo[2]) / lam) ** 2
    norm = math.pi ** 2 * 0.25 * tau ** 2 / lam ** 2
    exp_base = vxy2 * tau ** 2 / 4 * (4 * math.pi ** 2 / lam ** 2)
    gmin = float(np.min(g))
    rough, weight = np.zeros(3), 0.0
    if gmin > threshold:
        rough = np.exp(-exp_base / g) / g
        weight = min(max(gmin - threshold, 0.0), 1.0)
    total, gm, last, term = np.zeros(3), np.ones(3), -np.ones(3), np.zeros(3)
    converged = (gmin - 1) > threshold
    m = 1
    if stop is np.max and not converged:     # every term to m = taylor_terms, at once
        ms = np.arange(1, taylor_terms + 1)[:, None]
        logt = ms * np.log(g) - g - gammaln(ms + 1) - np.log(ms) - exp_base / ms
        total, converged = np.exp(logt).sum(axis=0), True
    while m <= taylor_terms and not converged:
        last = term
        gm = gm * g / m
        term = np.exp(-g - exp_base / m) * gm / m
        total = total + term
        converged = (np.min(term) < EPS) and (np.min(term) < np.min(last))
        m += 1
    D = norm * (total + weight * (rough - total))
    F = cook_fresnel(eta, math.sqrt(max((1 + float(np.dot(wi, wo))) / 2, 0.0)))
    return np.asarray(albedo, float) * (F * S * G * D / (math.pi * wi[2] * wo[2]))


def _vgroove(wi, wo, h):
    if np.dot(wi, h) <= 0 or np.dot(wo, h) <= 0:
        return 0.0
    return min(1.0, 2 * h[2] * wi[2] / np.dot(wi, h), 2 * h[2] * wo[2] / np.dot(wo, h))


def lowmicrofacetfit(wi, wo, A, B, C, eta):
    """bbm::lowmicrofacetfit = lowmicrofacet<Cook normalisation>: A D G F / (pi ci co)."""
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    if wi[2] <= 0 or wo[2] <= 0:
        return np.zeros(3)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    D = (1.0 + B * (1.0 - h[2])) ** (-C) if h[2] > 0 else 0.0
    F = cook_fresnel(eta, 0.5 * (np.dot(wi, h) + np.dot(wo, h)))
    return np.asarray(A, float) * (D * _vgroove(wi, wo, h) * F / math.pi / (wi[2] * wo[2]))


def lowsmooth(wi, wo, A, B, C, eta):
    """bbm::lowsmooth: A (1 + B |Ip + Op|^2)^-C cook(eta, sqrt(1 - |Ip - Op|^2 / 4))."""
    wi, wo = np.asarray(wi, float), np.asarray(wo, float)
    if wi[2] < 0 or wo[2] < 0:
        return np.zeros(3)
    dp2 = (wi[0] + wo[0]) ** 2 + (wi[1] + wo[1]) ** 2
    cd = math.sqrt(max(1 - 0.25 * ((wi[0] - wo[0]) ** 2 + (wi[1] - wo[1]) ** 2), 0.0))
    return np.asarray(A, float) * ((1.0 + B * dp2) ** (-C) * cook_fresnel(eta, cd))
