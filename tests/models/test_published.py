"""Each published fit against an independent evaluation of its formula.

The formulas below are written straight from the definitions of bbm's headers
(``include/bsdfmodel/ngan.h``, ``ward.h``, ``wardduer.h``, ``lafortune.h``,
``ashikhminshirley.h``, ``microfacet.h``, ``ndf/beckmann.h``,
``maskingshadowing/vgroove.h``, ``bbm/fresnel_schlick.h``, ``bbm/fresnel_cook.h``,
``low.h``), with the parameters read from the data file's text by a regular
expression (not by :mod:`plausible.catalogue`'s parser), and evaluated in NumPy
on random directions plus directions near each lobe's peak.
"""

import math
import re
from importlib import resources

import numpy as np
import pytest
from conftest import random_upper

import plausible
from plausible.catalogue.fit_sets import FIT_SETS

PI = math.pi


def raw_line(fit, name):
    """Parameters of ``name`` in ``fit``'s data file: {model: {key: list of floats}}."""
    fs = next(f for f in FIT_SETS if f.key == fit)
    text = resources.files("plausible").joinpath("data", "materials", fs.file).read_text()
    line = next(l for l in text.splitlines() if l.startswith(name + " = "))
    out = {}
    for model, body in re.findall(r"(\w+)\(([^()]*)\)", line):
        out[model] = {k: [float(x) for x in v.strip("[]").split(",")]
                      for k, v in re.findall(r"(\w+) = (\[[^\]]*\]|[-\d.e+]+)", body)}
    return out


def schlick(r0, c):
    return r0 + (1 - r0) * (1 - c) ** 5


def fresnel_cook(eta, c):
    """Cook & Torrance 1982's dielectric Fresnel, as bbm's fresnel_cook.h writes it."""
    g = np.sqrt(np.maximum(eta * eta + c * c - 1, 0))
    a = (g - c) / (g + c)
    b = (c * (g + c) - 1) / (c * (g - c) + 1)
    return 0.5 * a * a * (1 + b * b)


def geometry(wi, wo):
    hv = wi + wo
    h = hv / np.linalg.norm(hv, axis=-1, keepdims=True)
    ci, co, hz = wi[..., 2], wo[..., 2], h[..., 2]
    kh = np.sum(wi * h, axis=-1)
    return hv, h, ci, co, hz, kh


def vgroove(wi, wo, h):
    hz = h[..., 2]
    return np.minimum(1, np.minimum(2 * hz * wi[..., 2] / np.sum(wi * h, -1),
                                    2 * hz * wo[..., 2] / np.sum(wo * h, -1)))


def specular(model, prm, wi, wo):
    """bbm's specular term (no albedo), one model name at a time."""
    hv, h, ci, co, hz, kh = geometry(wi, wo)
    tan2 = (h[..., 0] ** 2 + h[..., 1] ** 2) / hz ** 2
    if model == "NganAshikhminShirley":          # ashikhminshirley.h, isotropic, Schlick(R0)
        n, r0 = prm["sharpness"][0], prm["fresnelReflectance"][0]
        return (n + 1) / (8 * PI) * hz ** n * schlick(r0, kh) / (kh * np.maximum(ci, co))
    if model == "LowAshikhminShirley":           # the same lobe, Cook's Fresnel with an index
        n, eta = prm["sharpness"][0], prm["fresnelReflectance"][0]
        return (n + 1) / (8 * PI) * hz ** n * fresnel_cook(eta, kh) / (kh * np.maximum(ci, co))
    if model == "NganBlinnPhong":                # Ngan et al. 2005: (n+2)/(2 pi) (n.h)^n
        n = prm["sharpness"][0]
        return (n + 2) / (2 * PI) * hz ** n
    if model in ("NganWard", "NganWardDuer"):    # ward.h / wardduer.h with H = in + out
        a = prm["roughness"][0]
        e = np.exp(-(hv[..., 0] ** 2 + hv[..., 1] ** 2) / (a * a) / hv[..., 2] ** 2)
        norm = np.sqrt(ci * co) if model == "NganWard" else ci * co
        return e / (4 * PI * a * a * norm)
    if model == "NganCookTorrance":              # microfacet.h: D G F / pi / (ci co), D with 1/pi
        m, r0 = prm["roughness"][0], prm["eta"][0]
        d = np.exp(-tan2 / (m * m)) / (PI * m * m * hz ** 4)
        return d * vgroove(wi, wo, h) * schlick(r0, kh) / PI / (ci * co)
    if model == "LowCookTorrance":               # cooktorrance.h: D without 1/pi, Cook's Fresnel
        m, eta = prm["roughness"][0], prm["eta"][0]
        d = np.exp(-tan2 / (m * m)) / (m * m * hz ** 4)
        return d * vgroove(wi, wo, h) * fresnel_cook(eta, kh) / PI / (ci * co)
    if model == "NganLafortune":                 # ngan.h: Lafortune * (n+2) / (2 pi max(Cz^2, Cxy^2)^(n/2))
        cxy, cz, n = prm["Cxy"][0], prm["Cz"][0], prm["sharpness"][0]
        dot = cxy * (wi[..., 0] * wo[..., 0] + wi[..., 1] * wo[..., 1]) + cz * wi[..., 2] * wo[..., 2]
        c2 = max(cz * cz, cxy * cxy)
        # in logs: max(Cz^2, Cxy^2)^(n/2) underflows for the sharp fits
        logv = n * np.log(np.maximum(dot, 1e-300)) - 0.5 * n * math.log(c2)
        return np.where(dot > 0, (n + 2) / (2 * PI) * np.exp(logv), 0.0)
    raise AssertionError(model)


def reference(fit, name, wi, wo):
    """Lambertian(albedo) / pi + albedo * specular, per RGB channel."""
    terms = raw_line(fit, name)
    out = np.array(terms["Lambertian"]["albedo"]) / PI * np.ones(wi.shape[:-1] + (1,))
    (model, prm), = [(k, v) for k, v in terms.items() if k not in ("Lambertian", "Aggregate")]
    return out + np.array(prm["albedo"]) * specular(model, prm, wi, wo)[..., None]


def directions(rng, n=300):
    """Random pairs on the upper hemisphere, half of them near the mirror
    direction (within ~3 degrees), where the sharp lobes live."""
    wi, wo = random_upper(rng, n, 0.05), random_upper(rng, n, 0.05)
    near = np.stack([-wi[:, 0], -wi[:, 1], wi[:, 2]], -1) + rng.normal(0, 0.03, (n, 3))
    near[:, 2] = np.abs(near[:, 2]) + 0.01
    near /= np.linalg.norm(near, axis=-1, keepdims=True)
    wo = np.where((np.arange(n) % 2 == 0)[:, None], wo, near)
    return wi, wo


#: The He and Löw ABC fit sets have their own comparison with bbm's definitions
#: (tests/models/test_fits_he_low.py, every material).
OWN_TESTS = ("ngan2005/he", "low2012/microfacet-e2", "low2012/smooth-e2")
BUILT = [f.key for f in FIT_SETS if f.built and f.key not in OWN_TESTS]
SAMPLE_MATERIALS = ("alum-bronze", "nickel", "pink-felt", "blue-acrylic", "gold-metallic-paint", "red-fabric")


@pytest.mark.parametrize("fit", BUILT)
def test_every_fit_set_matches_the_formula_of_its_header(fit, rng):
    names = [n for n in SAMPLE_MATERIALS if n in plausible.materials(fit)]
    assert len(names) >= 4
    wi, wo = directions(rng)
    for name in names:
        got = plausible.material(name, fit).eval(wi, wo)
        want = reference(fit, name, wi, wo)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-14, err_msg=f"{name}@{fit}")


def test_ngan_blinn_phong_uses_the_half_vector(rng):
    """Ngan's Blinn-Phong exponent is ~ 2 / alpha^2 of their Ward fit of the same
    material (the half-vector lobe (n.h)^n ~ exp(-n theta_h^2 / 2) against Ward's
    exp(-theta_h^2 / alpha^2)); a mirror-direction lobe would give 1 / (2 alpha^2)."""
    ratios = []
    for name in plausible.materials("ngan2005/blinn-phong"):
        n = raw_line("ngan2005/blinn-phong", name)["NganBlinnPhong"]["sharpness"][0]
        a = raw_line("ngan2005/ward", name)["NganWard"]["roughness"][0]
        if a < 0.45:                             # 0.5 is the fits' upper bound
            ratios.append(n * a * a / 2)
    assert 0.8 < np.median(ratios) < 1.6         # 0.25 for a mirror lobe


def test_each_materials_sampler_is_consistent_with_its_pdf():
    from reference import check_sampling

    for fit in ("ngan2005/lafortune", "low2012/cook-torrance-e2", "ngan2005/blinn-phong"):
        m = plausible.material("gold-metallic-paint", fit)
        for t in (0.0, 50.0, 85.0):
            check_sampling(m, [math.sin(math.radians(t)), 0.0, math.cos(math.radians(t))], n=4000)


@pytest.mark.parametrize("fit", BUILT)
def test_the_published_variants_run_the_same_on_drjit(fit, rng):
    """One math: the material's hooks on Dr.Jit Float64 agree with NumPy (its
    colours converted to the green channel's floats)."""
    from reference import hooks_agree

    m = plausible.material("alum-bronze", fit).with_backend_colors(lambda a: float(a[1]))
    m.channels = None
    wi, wo = directions(rng, 64)
    hooks_agree(m, wi, wo, rng.random((64, 3)), rtol=1e-10, atol=1e-12, rtol_sample=1e-10, atol_sample=1e-12)
