"""Mitsuba's names with Mitsuba's meanings (issue 28): ``specular_reflectance``
never stands for Schlick's F0, ``int_ior``/``ext_ior`` and ``alpha`` are
converted where a model has the equivalent, every Mitsuba conductor
``material`` is Mitsuba's own data, and ``to_string`` shows textures."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import dr, interaction, mi, spectrum_np, vec3

import plausible
from plausible.mitsuba import props as P

pytestmark = pytest.mark.drjit

LOAD_ERRORS = (RuntimeError, ValueError)


def test_specular_reflectance_is_refused_where_rs_is_schlicks_f0():
    """A ported roughplastic-style specular_reflectance = 1 would make
    ashikhmin_shirley a mirror (rs = F0 = 1): refused, and the message gives the
    conversion; on Modified Phong it is ks, a factor, as in Mitsuba."""
    for plugin in ("ashikhmin_shirley", "ashikhmin_shirley_specular", "schlick"):
        with pytest.raises(LOAD_ERRORS, match="Schlick's F0.*int_ior"):
            mi.load_dict({"type": plugin, "specular_reflectance": 1.0})
    b = mi.load_dict({"type": "phong", "specular_reflectance": 0.3, "diffuse_reflectance": 0.2})
    assert b.state.values()["ks"] == 0.3


@pytest.mark.parametrize("int_ior,ext_ior", [(1.5, 1.0), (1.33, 1.000277), (None, None)])
def test_int_ior_sets_schlicks_f0(int_ior, ext_ior):
    """int_ior / ext_ior give rs = ((n1 - n2) / (n1 + n2))^2 (Mitsuba's defaults
    1.49 / 1.000277 when only one is given), which equals Mitsuba's own dielectric
    Fresnel reflectance at normal incidence (mi.fresnel)."""
    d = {"type": "ashikhmin_shirley"}
    if int_ior is not None:
        d.update(int_ior=int_ior, ext_ior=ext_ior)
    else:
        d.update(int_ior=1.49)
    rs = mi.load_dict(d).state.values()["rs"]
    n1, n2 = (int_ior or 1.49), (ext_ior or 1.000277)
    want = float(mi.fresnel(mi.Float(1.0), mi.Float(n1 / n2))[0][0])
    assert abs(rs - want) < 1e-6 and rs > 0.01


def test_alpha_sets_the_blinn_exponents():
    """alpha / alpha_u / alpha_v on Ashikhmin-Shirley: n = 2 / alpha^2 - 2 (Walter
    et al. 2007), per axis; a texture or alpha > 1 is refused with the range."""
    v = mi.load_dict({"type": "ashikhmin_shirley", "alpha_u": 0.1, "alpha_v": 0.5}).state.values()
    assert v["nu"] == pytest.approx(198.0) and v["nv"] == pytest.approx(6.0)
    assert mi.load_dict({"type": "reciprocal_blinn", "alpha": 0.2}).state.values()["n"] == pytest.approx(48.0)
    with pytest.raises(LOAD_ERRORS, match="'alpha' must be a number in \\(0, 1\\]"):
        mi.load_dict({"type": "ashikhmin_shirley", "alpha": 1.5})
    with pytest.raises(LOAD_ERRORS, match="'nu' given twice"):
        mi.load_dict({"type": "ashikhmin_shirley", "alpha": 0.2, "nu": 10.0})


def test_the_blinn_exponent_matches_beckmann_near_the_peak():
    """The mapping's claim: the normalised Blinn half-vector density (n + 2)/(2 pi)
    cos^n and Beckmann's of alpha agree near the peak (within 1 % up to theta_h =
    alpha for alpha = 0.1; measured 0.5 %), and part in the tail (40 % apart at
    3 alpha: an approximation, documented as one)."""
    a = 0.1
    n = P.blinn_exponent(a)

    def ratio(th):
        c = np.cos(th)
        return (n + 2) / (2 * np.pi) * c ** n / (np.exp(-np.tan(th) ** 2 / a ** 2) / (np.pi * a * a * c ** 4))

    assert all(abs(ratio(th) - 1) < 0.01 for th in (0.0, a / 2, a))
    assert abs(ratio(3 * a) - 1) > 0.3


def test_every_mitsuba_conductor_is_accepted():
    """Each name of Mitsuba's conductor list loads in Mitsuba's conductor and in
    neumann_metal; an unknown one is refused with the list."""
    for name in P.MITSUBA_CONDUCTORS:
        mi.load_dict({"type": "conductor", "material": name})
        mi.load_dict({"type": "neumann_metal", "material": name})
    assert len(P.MITSUBA_CONDUCTORS) > 60
    with pytest.raises(LOAD_ERRORS, match="'material' must be one of Mitsuba's conductors.*TiN"):
        mi.load_dict({"type": "neumann_metal", "material": "unobtainium"})


@pytest.mark.parametrize("material", ["Au", "gold", "Cu", "Al", "TiN", "W"])
def test_a_conductors_f0_is_mitsubas(material):
    """neumann_metal with material= at normal incidence: eval / c equals the
    reflectance of Mitsuba's own conductor (its sample weight at wi = n), to
    float32 rounding (Au differed by 0.03 with plausible's own table)."""
    c = 5.0
    ours = mi.load_dict({"type": "neumann_metal", "material": material, "n": 30.0, "c": c})
    ref = mi.load_dict({"type": "conductor", "material": P.conductor_name("t", material)})
    si = interaction(np.array([[0.0, 0.0, 1.0]]))
    got = spectrum_np(ours.eval(mi.BSDFContext(), si, mi.Vector3f(0.0, 0.0, 1.0)))[0] / c
    _, w = ref.sample(mi.BSDFContext(), si, mi.Float(0.5), mi.Point2f(0.5, 0.5))
    np.testing.assert_allclose(got, spectrum_np(w)[0], rtol=2e-5)


def test_to_string_shows_textures_not_their_means(tmp_path):
    """A bitmap rd is printed as the bitmap, not as its mean."""
    path = str(tmp_path / "t.png")
    mi.Bitmap(np.full((2, 2, 3), 200, np.uint8), mi.Bitmap.PixelFormat.RGB).write(path)
    b = mi.load_dict({"type": "ashikhmin_shirley", "rd": {"type": "bitmap", "filename": path}, "nu": 10.0})
    text = str(b)
    assert "rd=BitmapTexture('t.png')" in text and "nu=10" in text
    mean = float(np.mean(np.asarray(b.state.textures["rd"].mean())))
    assert f"{mean:.4g}" not in text


class _Lines(mi.Appender):
    """A Mitsuba log appender that keeps the lines."""

    def __init__(self):
        mi.Appender.__init__(self)
        self.lines = []

    def append(self, level, text):
        self.lines.append((level, text))

    def log_progress(self, *args):
        pass


def _load_logged(d):
    log = _Lines()
    logger = mi.logger()
    logger.add_appender(log)
    try:
        mi.load_dict(d)
    finally:
        logger.remove_appender(log)
    return [(lv, t) for lv, t in log.lines if "pumped_up" in t]


def test_pumped_up_announces_its_table_and_the_cache(tmp_path, monkeypatch):
    """A cold pumped_up load says, at Mitsuba's default level (Warn), that it
    computes a table and where it caches it (PLAUSIBLE_CACHE_DIR); the table file
    lands there; a second load in a fresh process memory (same disk cache) reads
    it and says nothing."""
    from plausible.integrals import cache

    monkeypatch.setenv("PLAUSIBLE_CACHE_DIR", str(tmp_path))
    d = {"type": "pumped_up", "base": "reciprocal-phong:ks=1:n=17.25"}
    lines = _load_logged(d)
    warn = [t for lv, t in lines if lv == mi.LogLevel.Warn]
    assert warn and all(str(tmp_path) in t and "PLAUSIBLE_CACHE_DIR" in t for t in warn)
    assert any(p.name.startswith("albedo-") for p in tmp_path.iterdir())
    monkeypatch.setattr(cache, "_TABLES", {})
    assert _load_logged(d) == []
