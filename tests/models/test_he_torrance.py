"""He, Torrance, Sillion & Greenberg 1991 against a formula written here again from
the paper (with its errata), term by term in angles and explicit vectors:
eq. 76's G with the s and p vectors (not the closed form the model uses), eq. 24-25
with math.erfc, eq. 80 solved by bisection, eq. 78 summed term by term until the
terms vanish, the complex Fresnel factor with Python complex numbers."""

import cmath
import math

import numpy as np
import pytest

import plausible
from plausible import special
from plausible.models import he_torrance as HT
from plausible.arrays.ops import NP


# -- the independent reference -------------------------------------------------------

def _cross(a, b):
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]])


def _unit(a):
    return a / math.sqrt(float(np.dot(a, a)))


def ref_G(wi, wo):
    """Eq. 76 with k_i = -wi, k_r = wo, s = k x n / |k x n|, p = s x k."""
    n = np.array([0.0, 0.0, 1.0])
    ki, kr = -np.asarray(wi, float), np.asarray(wo, float)
    si, sr = _unit(_cross(ki, n)), _unit(_cross(kr, n))
    pi_, pr = _cross(si, ki), _cross(sr, kr)
    v = kr - ki
    c = _cross(kr, ki)
    num = (np.dot(sr, ki) ** 2 + np.dot(pr, ki) ** 2) * (np.dot(si, kr) ** 2 + np.dot(pi_, kr) ** 2)
    return (np.dot(v, v) / v[2]) ** 2 * num / np.dot(c, c) ** 2


def ref_S(theta, sigma0, tau, errata=True):
    """Eqs. 24-25 (errata: exp(-x^2) in Lambda)."""
    if theta == 0:
        return 1.0
    x = tau / (2 * sigma0 * math.tan(theta))
    lam = (math.exp(-x * x) if errata else 1.0) / (2 * math.sqrt(math.pi) * x) - 0.5 * math.erfc(x)
    return (1 - 0.5 * math.erfc(x)) / (lam + 1)


def ref_sigma(ti, tr, sigma0, tau):
    """Eq. 80: sqrt(pi/2) z0 = sigma0/4 (Ki + Kr) exp(-z0^2 / (2 sigma0^2)), by bisection."""
    def K(t):
        return 0.0 if t == 0 else math.tan(t) * math.erfc(tau / (2 * sigma0 * math.tan(t)))
    k = K(ti) + K(tr)
    if k == 0:
        return sigma0
    f = lambda z: math.sqrt(math.pi / 2) * z - sigma0 / 4 * k * math.exp(-z * z / (2 * sigma0 ** 2))  # noqa: E731
    lo, hi = 0.0, sigma0
    while f(hi) < 0:
        hi *= 2
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid) < 0 else (lo, mid)
    z0 = 0.5 * (lo + hi)
    return sigma0 / math.sqrt(1 + z0 ** 2 / sigma0 ** 2)


def ref_sum(g, V):
    """sum_m g^m e^-g / (m! m) e^(-V/m), every term until they are negligible."""
    total, m, peak = 0.0, 1, 0.0
    while True:
        t = math.exp(m * math.log(g) - g - math.lgamma(m + 1) - math.log(m) - V / m)
        total += t
        peak = max(peak, t)
        if m > g + 10 and t < 1e-18 * peak:
            return total
        m += 1


def ref_fresnel(c, n, k):
    """|r_s|^2, |r_p|^2 averaged, with the complex index n + i k (Snell in complex numbers)."""
    N = complex(n, k)
    st = math.sqrt(1 - c * c) / N
    ct = cmath.sqrt(1 - st * st)
    rs = (c - N * ct) / (c + N * ct)
    rp = (N * c - ct) / (N * c + ct)
    return 0.5 * (abs(rs) ** 2 + abs(rp) ** 2)


def ref_dd(wi, wo, sigma0, tau, lam, n, k, variant="westin"):
    """rho_dd = F G S D / (pi cos_i cos_r), eq. 76-80, in angles."""
    ti, tr = math.acos(wi[2]), math.acos(wo[2])
    F = ref_fresnel(math.sqrt((1 + float(np.dot(wi, wo))) / 2), n, k)
    errata = variant != "paper"
    S = ref_S(ti, sigma0, tau, errata) * ref_S(tr, sigma0, tau, errata)
    sig = ref_sigma(ti, tr, sigma0, tau)
    g = (2 * math.pi * sig / lam * (math.cos(ti) + math.cos(tr))) ** 2
    vxy2 = (wi[0] + wo[0]) ** 2 + (wi[1] + wo[1]) ** 2
    if variant == "westin":
        vxy2 *= (2 * math.pi / lam) ** 2
    D = (math.pi * tau / (2 * lam)) ** 2 * ref_sum(g, tau * tau * vxy2 / 4)
    return F * ref_G(wi, wo) * S * D / (math.pi * wi[2] * wo[2])


def direction(theta_deg, phi_deg):
    t, p = math.radians(theta_deg), math.radians(phi_deg)
    return np.array([math.sin(t) * math.cos(p), math.sin(t) * math.sin(p), math.cos(t)])


PAIRS = [(10, 0, 25, 180), (30, 0, 30, 180), (45, 20, 60, 170), (60, 0, 10, 90), (75, 0, 80, 180),
         (5, 0, 40, 0), (50, 0, 50, 200), (85, 10, 70, 150), (20, 0, 89, 180), (70, 30, 35, 260)]
SETS = [dict(sigma0=0.18, tau=3.0, wavelength=0.55, eta=1.5, k=0.0),
        dict(sigma0=0.1, tau=1.7, wavelength=0.5, eta=0.2, k=3.0),
        dict(sigma0=0.6, tau=4.0, wavelength=0.6, eta=1.3, k=7.0),          # g up to 160: windowed sum
        dict(sigma0=0.0318, tau=0.3, wavelength=0.444, eta=0.59765, k=5.2337)]


@pytest.mark.parametrize("variant", HT.VARIANTS)
@pytest.mark.parametrize("kw", SETS, ids=["default", "neumann", "rough", "westin-test"])
def test_directional_diffuse_matches_the_paper_formula(kw, variant):
    m = plausible.make("he-torrance", variant=variant, **kw)
    for a, b, c, d in PAIRS:
        wi, wo = direction(a, b), direction(c, d)
        want = ref_dd(wi, wo, kw["sigma0"], kw["tau"], kw["wavelength"], kw["eta"], kw["k"], variant)
        got = float(m.eval(wi, wo))
        assert got == pytest.approx(want, rel=1e-10, abs=1e-300), (a, b, c, d)


def test_the_reference_tells_the_variants_apart():
    """The comparison above can fail: each variant differs from the others' formula."""
    kw = SETS[0]
    wi, wo = direction(60, 0), direction(55, 180)
    vals = {v: ref_dd(wi, wo, kw["sigma0"], kw["tau"], kw["wavelength"], kw["eta"], kw["k"], v)
            for v in HT.VARIANTS}
    for v in HT.VARIANTS:
        got = float(plausible.make("he-torrance", variant=v, **kw).eval(wi, wo))
        for other in HT.VARIANTS:
            if other != v:
                assert abs(got - vals[other]) > 1e-3 * vals[other]


def test_G_of_eq_76_is_the_closed_form():
    """(|v|^2 / v_z)^2 = 16 (k.h)^4 / (c_i + c_r)^2: the brackets of eq. 76 cancel |k_r x k_i|^4."""
    rng = np.random.default_rng(4)
    for _ in range(50):
        wi, wo = (_unit(np.array([*rng.normal(size=2), abs(rng.normal()) + 0.05])) for _ in range(2))
        kh = np.linalg.norm(wi + wo) / 2
        assert 16 * kh ** 4 / (wi[2] + wo[2]) ** 2 == pytest.approx(ref_G(wi, wo), rel=1e-11)


@pytest.mark.parametrize("g", [1e-8, 1e-3, 0.5, 3.0, 17.9, 30.0, 31.8, 60.0, 90.0, 300.0, 2500.0, 4e4])
@pytest.mark.parametrize("V", [0.0, 0.3, 5.0, 80.0])
def test_series_against_term_by_term_sum(g, V):
    got = float(HT.series(NP, np.float64(g), np.float64(V)))
    want = ref_sum(g, V)
    zero = ref_sum(g, 0.0)   # the lobe's value at V = 0 (the documented scale of the error)
    assert abs(got - want) <= 1e-11 * want + 1e-13 * zero


def test_series_with_a_bound_sums_only_what_it_needs():
    n, complete = HT.exact_terms(5.0)
    assert complete and n == 48     # 5 + 12 sqrt(5) + 2 = 33.8, rounded up to a multiple of 16
    g = np.array([1e-4, 0.7, 5.0])
    np.testing.assert_allclose(HT.series(NP, g, 2.0, bound=5.0), HT.series(NP, g, 2.0), rtol=1e-14)
    assert not HT.exact_terms(60.0)[1]


def test_a_series_too_short_would_be_caught():
    """A truncated sum (the 10 terms of Holzschuch & Pacanowski's code) fails the check above at g = 8."""
    g, V = 8.0, 0.3
    ten = sum(math.exp(m * math.log(g) - g - math.lgamma(m + 1) - math.log(m) - V / m) for m in range(1, 11))
    assert abs(ten - ref_sum(g, V)) > 1e-3 * ref_sum(g, V)


def test_newton_root_of_the_effective_roughness():
    f0 = np.array([0.0, 1e-12, 1e-3, 0.5, 1.0, 1.6, 3.0, 50.0, 1e5, 1e12])
    y = HT.roughness_root(NP, f0)
    assert y[0] == 0
    np.testing.assert_allclose(y[1:] * np.exp(y[1:] ** 2 / 2), f0[1:], rtol=1e-14)


def test_erfc_and_its_coefficients():
    from numpy.polynomial import chebyshev as C
    from scipy.special import erfcx

    def h(x):
        z = 2 * (1 - x) / (1 + x)
        return np.log(erfcx(z) * (2 + z) / 2)
    c = C.chebinterpolate(lambda x: h(np.clip(x, -1 + 1e-300, 1)), len(special.ERFCX_CHEB) - 1)
    np.testing.assert_allclose(c, special.ERFCX_CHEB, rtol=0, atol=1e-15)
    z = np.concatenate([np.linspace(0, 6, 601), [1e-9, 10, 26, 1e3, 1e8]])
    np.testing.assert_allclose(special.erfcx(NP, z), erfcx(z), rtol=5e-15)
    zz = np.linspace(-5, 5, 401)
    np.testing.assert_allclose(special.erfc(NP, zz), [math.erfc(v) for v in zz], rtol=2e-14)


def test_log_factorial_table_and_stirling():
    m = np.array([0.0, 1, 2, 10, 64, 65, 100, 1e4, 1e7])
    want = [math.lgamma(v + 1) for v in m]
    np.testing.assert_allclose(special.log_factorial(NP, m), want, rtol=1e-15)


def test_no_nan_at_the_normal_at_grazing_and_at_wi_equal_wo():
    for kw in SETS + [dict(sigma0=8.7, tau=100.0), dict(sigma0=1e-4, tau=500.0)]:
        m = plausible.make("he-torrance", **kw)
        cs = [1.0, 1 - 1e-15, 0.5, 1e-3, 1e-6, 1e-9]
        ws = [np.array([math.sqrt(1 - c * c), 0.0, c]) for c in cs]
        ws += [np.array([0, math.sqrt(1 - c * c), c]) for c in cs] + [np.array([0.0, 0.0, 1.0])]
        W = np.array(ws)
        f = m.eval(W[:, None], W[None, :])
        assert np.all(np.isfinite(f)) and np.all(f >= 0)
        d = m.delta_lobes(W)[0][1]
        assert np.all(np.isfinite(d)) and np.all((d >= 0) & (d <= 1))
        # retro-reflection at grazing stays bounded: G S_i S_r D / (c_i c_r) has a limit
        assert np.all(np.diag(f) < 1e6)


def test_delta_lobe_is_fresnel_times_exp_minus_g_times_shadowing():
    kw = SETS[1]
    m = plausible.make("he-torrance", **kw)
    for t in (0.0, 30.0, 70.0, 88.0):
        wi = direction(t, 40)
        (d, w), = m.delta_lobes(wi)
        np.testing.assert_allclose(d, [-wi[0], -wi[1], wi[2]])
        th = math.radians(t)
        sig = ref_sigma(th, th, kw["sigma0"], kw["tau"])
        g = (4 * math.pi * sig * math.cos(th) / kw["wavelength"]) ** 2
        want = ref_fresnel(math.cos(th), kw["eta"], kw["k"]) * math.exp(-g) * ref_S(th, kw["sigma0"], kw["tau"]) ** 2
        assert float(w) == pytest.approx(want, rel=1e-10)


def test_smooth_limit_puts_all_energy_in_the_delta_lobe():
    """sigma0 -> 0: exp(-g) -> 1, S -> 1, rho_dd -> 0; the delta lobe carries F."""
    m = plausible.make("he-torrance", sigma0=1e-4, tau=3.0, fresnel="none", rs=1.0)
    wi = direction(40, 0)
    assert float(m.delta_lobes(wi)[0][1]) == pytest.approx(1.0, abs=1e-5)
    assert float(plausible.albedo(m, wi).value) < 1e-4


def test_rough_beckmann_limit_approaches_the_series():
    """Beckmann's approximation exp(-V/g)/g is the large-g limit of the sum (within ~1/g)."""
    for g in (30.0, 300.0, 3000.0):
        for V in (0.0, 10.0):
            s = ref_sum(g, V)
            assert abs(math.exp(-V / g) / g - s) < 3.0 / g * s


def test_parameters_out_of_range_name_the_parameter():
    with pytest.raises(ValueError, match="'sigma0'"):
        plausible.make("he-torrance", sigma0=-1)
    with pytest.raises(ValueError, match="'variant'"):
        plausible.make("he-torrance", variant="westin-1991")
