"""Fits that keep the lobe (issue 40): an isotropic target gets an isotropic lobe, a
parameter at a bound is said aloud, the highlight survives, and the Ashikhmin-Shirley form
with a separate specular scale refits Ngan et al.'s published A-S fits.

The highlight is measured here independently of the fit's own samples and figures: the peak
of ``f cos(theta_o)`` over 3,581 outgoing directions in the plane of incidence (0.05 degree
steps), at incidences 0, 30 and 60 degrees (every lobe here is isotropic: its peak lies in
that plane).  A highlight is kept when the ratio of peaks is within a factor 2 either way
(today's fits lose it by factors of 3 to 50)."""

import importlib
import math
import warnings

import numpy as np
import pytest

import plausible
from plausible.analysis import direction
from plausible.fitting import BoundWarning, fit

FIT = importlib.import_module("plausible.fitting.fit")     # the module (``fit`` is the function)
GOLD = "material:gold-metallic-paint@low2012/smooth-e2"
THETAS = (0.0, 30.0, 60.0)


def peak(model, theta_deg):
    wi = direction(math.radians(theta_deg))
    t = np.radians(np.linspace(-89.5, 89.5, 3581))
    wo = np.stack([np.sin(t), 0.0 * t, np.cos(t)], -1)
    f = np.asarray(model.eval(np.broadcast_to(wi, wo.shape), wo))
    f = f.mean(axis=-1) if f.ndim == 2 else f
    return float(np.max(f * wo[:, 2]))


def ratios(result, source):
    return np.array([peak(result, t) / peak(source, t) for t in THETAS])


def _fit(*args, **kw):
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        r = fit(*args, **kw)
    return r, [w for w in caught if issubclass(w.category, BoundWarning)]


def _at_bound(r):
    """Independently: each free parameter's channels equal to an end of its registry range."""
    out = set()
    for p in r.model.info.params:
        if not p.numeric or p.integer or p.default is None:
            continue
        for i, v in enumerate(np.atleast_1d(np.asarray(r.params[p.name], float))):
            if abs(v - p.lo) <= 1e-9 or abs(v - p.hi) <= 1e-9:
                out.add(p.name if np.ndim(r.params[p.name]) == 0 else f"{p.name}[{i}]")
    return out


def test_isotropic_target_gets_an_isotropic_lobe_and_each_bound_is_warned():
    """The issue's case: A-S fitted to gold-metallic-paint (isotropic) under l2-cos gave
    nu 5.3, nv 0, rd_r = 1, rs_b = 0 silently.  Now nu = nv, and every parameter that ends
    on an end of its range is named in ``at_bounds`` and in one BoundWarning."""
    r, caught = _fit("ashikhmin-shirley", GOLD, "l2-cos")
    assert r.params["nu"] == r.params["nv"] > 0.5
    ends = _at_bound(r)
    assert {s.split(" = ")[0] for s in r.at_bounds} == ends
    if ends:
        assert len(caught) == 1 and all(e in str(caught[0].message) for e in ends)
    assert any("isotropic" in n for n in r.notes)


def test_anisotropic_target_keeps_its_anisotropy():
    r, _ = _fit("ward", "ward:alpha_x=0.1:alpha_y=0.4:rs=0.2:rd=0.3", "l2-cos", starts=1)
    assert r.params["alpha_x"] == pytest.approx(0.1, rel=1e-5)
    assert r.params["alpha_y"] == pytest.approx(0.4, rel=1e-5)


def test_is_isotropic_tells_a_turned_lobe_apart():
    from plausible.fitting.targets import as_target

    assert FIT.is_isotropic(as_target("ward:alpha_x=0.2:alpha_y=0.2", thetas_deg=(0.0, 60.0)))
    assert not FIT.is_isotropic(as_target("ward:alpha_x=0.2:alpha_y=0.21", thetas_deg=(0.0, 60.0)))
    t = as_target("ward:alpha_x=0.2:alpha_y=0.2", thetas_deg=(0.0, 60.0))
    t.model = None                      # a table: nothing to turn, so not known to be isotropic
    assert not FIT.is_isotropic(t)


def test_at_bounds_names_the_ends_and_only_them():
    info = plausible.registry.info("ashikhmin-shirley")
    vars_ = [FIT._Var(info.param(k)) for k in ("nu", "rs", "rd")]
    got = FIT.at_bounds(vars_, {"nu": 0.0, "rs": np.array([0.3, 1.0, 0.0]), "rd": 0.5})
    assert [s.split(" = ")[0] for s in got] == ["nu", "rs[1]", "rs[2]"]
    assert FIT.at_bounds(vars_, {"nu": 12.0, "rs": np.array([0.3, 0.99, 0.01]), "rd": 0.5}) == []


def test_highlight_rows_are_the_brightest_pair_of_each_incidence_up_to_60_degrees():
    from plausible.fitting import metrics as M

    wi = np.array([[0, 0, 1.0]] * 3 + [[math.sin(1.0), 0, math.cos(1.0)]] * 2 + [[math.sin(1.4), 0, math.cos(1.4)]])
    g = np.array([0.1, 0.7, 0.2, 0.9, 0.3, 5.0])
    assert list(M.highlight_rows(wi, g)) == [1, 3]          # 80 degrees (1.4 rad) is left out
    assert list(M.highlight_rows(wi, [0.1, 0.2, 0.7, 0.3, 0.9, 5.0])) == [2, 4]
    assert list(M.highlight_rows(wi, g, max_theta_deg=85.0)) == [1, 3, 5]


@pytest.mark.parametrize("model", ["ward", "ashikhmin-shirley"])
def test_perceptual_fits_to_gold_metallic_paint_keep_the_highlight(model):
    """Today Ward's perceptual fit had alpha 0.84: its peak a fraction of the paint's."""
    r, _ = _fit(model, GOLD, "perceptual", starts=2)
    q = ratios(r.model, plausible.registry.make_from_spec(GOLD))
    assert np.all((q > 0.5) & (q < 2.0)), q


def test_conversion_to_ashikhmin_shirley_keeps_the_highlight():
    """The docs' conversion returned nu = nv = 0, rs = 0: a matte result."""
    spec = "lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50"
    c = plausible.convert(spec, to="ashikhmin-shirley")
    q = ratios(c.items[0].result, plausible.conversion.read_sources(spec)[0].model)
    assert np.all((q > 0.5) & (q < 2.0)), (q, c.items[0].params)


def test_scaled_form_refits_a_published_ngan_ashikhmin_shirley_fit():
    """Ngan's nickel A-S fit: a Lambertian term plus the A-S lobe with rs = 0.999 times a colour,
    which ``ashikhmin-shirley`` (rs both R0 and scale) cannot express: its highlight is lost.
    The scaled form keeps it, with the published sharpness within 5 %."""
    src = "material:nickel@ngan2005/ashikhmin-shirley"
    r, _ = _fit("ashikhmin-shirley-scaled", src, "l2-cos", starts=2)
    q = ratios(r.model, plausible.registry.make_from_spec(src))
    assert np.all((q > 0.8) & (q < 1.25)), q
    assert r.params["nu"] == r.params["nv"] == pytest.approx(1030.0, rel=0.05)


def test_scaled_form_is_the_paper_model_at_ks_1_and_scales_the_lobe():
    wi, wo = direction(0.5, 0.2), direction(0.7, 3.0)
    base = dict(nu=40.0, nv=90.0, rs=0.3, rd=0.6)
    a = plausible.make("ashikhmin-shirley", **base).eval(wi, wo)
    assert plausible.make("ashikhmin-shirley-scaled", **base).eval(wi, wo) == a
    spec = plausible.make("ashikhmin-shirley", **{**base, "rd": 0.0}).eval(wi, wo)
    # ks = 0.4: 0.4 times the lobe, and the diffuse term under a coating of R0 0.4 rs
    diff = plausible.make("ashikhmin-shirley-diffuse", rs=0.4 * 0.3, rd=0.6).eval(wi, wo)
    got = plausible.make("ashikhmin-shirley-scaled", **base, ks=0.4).eval(wi, wo)
    assert got == pytest.approx(0.4 * spec + diff, rel=1e-13)


@pytest.mark.parametrize("spec", ["material:alum-bronze@ngan2005/ward", "material:nickel@ngan2005/ashikhmin-shirley"])
def test_published_fits_converted_to_gltf_keep_the_albedo_and_say_what_the_highlight_lost(spec):
    """The issue's case: these conversions to glTF were matte (peaks 0.011-0.018 of the source's
    at 0 and 30 degrees, measured on 6bc24da) without a word.  The albedo is the constraint (within
    0.05 at 0/45/75 deg), and where the head-on highlight as rendered under compare_looks' lamp (Mitsuba,
    independent of the fit) is outside the band, the conversion says it traded the highlight at 0 deg
    away.  (Not the point peak above: a point light's highlight on these lobes is smaller than a pixel,
    docs/looks.md; nickel's glTF dielectric, roughness 0.16 against the source's A-S exponent 1030, renders
    0.77x the source's highlight with a point peak more than 2x its.)"""
    from plausible.mitsuba.looks import HIGHLIGHT_BAND

    c = plausible.convert(spec, to="gltf").items[0]
    assert max(v["max_abs_difference"] for v in c.albedo.values()) <= 0.05
    q = c.looks.highlight_ratios[0]
    if not HIGHLIGHT_BAND[0] <= q <= HIGHLIGHT_BAND[1]:
        (trade,) = [w for w in c.warnings if w.startswith("highlight traded for the albedo")]
        assert ("lost at 0 deg" if q < 1 else "invented at 0 deg") in trade, (q, trade)


def test_candidate_is_the_model_built_again_and_refuses_what_the_model_refuses():
    """``fit.candidate``: a copy of one model with new values evaluates as the class built at
    those values does (bitwise, NumPy), and the model's own constraint between parameters
    still raises (Modified Phong's kd + ks <= 1)."""
    wi, wo = direction(0.4, 0.3), direction(0.6, 2.9)
    for name, values in (("ashikhmin-shirley", dict(nu=30.0, nv=70.0, rs=0.2, rd=0.5)),
                         ("modified-phong", dict(kd=0.3, ks=0.6, n=12.0))):
        proto = plausible.make(name)
        got = FIT.candidate(proto, values)
        assert got.eval(wi, wo) == plausible.make(name, **values).eval(wi, wo)
        assert dict(got.params) == dict(plausible.make(name, **values).params)
    with pytest.raises(ValueError, match="kd"):
        FIT.candidate(plausible.make("modified-phong"), dict(kd=0.6, ks=0.6, n=12.0))


def test_the_highlight_hold_is_an_argument_of_the_fit_not_module_state():
    """Issue 40, item 4: ``fit(..., highlight=w)`` replaces the context manager that set a module
    global.  Measured by the independent peak (``peak``, 3,581 directions): the default hold brings the
    A-S fit's peak at 0 deg nearer the target's than ``highlight=0`` (the plain l2-cos, as the papers fit),
    which in turn has the lower l2-cos figure; and one fit's weight does not leak into the next."""
    target = plausible.make(GOLD)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        plain = fit("ashikhmin-shirley", GOLD, "l2-cos", highlight=0.0)
        held = fit("ashikhmin-shirley", GOLD, "l2-cos")
        again = fit("ashikhmin-shirley", GOLD, "l2-cos", highlight=0.0)
    off = [abs(math.log(peak(r.model, 0.0) / peak(target, 0.0))) for r in (plain, held)]
    assert off[1] < off[0]
    assert plain.errors["l2-cos"] < held.errors["l2-cos"]
    assert again.params["nu"] == plain.params["nu"] and again.errors == plain.errors


@pytest.mark.parametrize("bad", [-1.0, float("nan"), "heavy"])
def test_a_bad_highlight_weight_is_refused_naming_it(bad):
    with pytest.raises(ValueError, match="highlight must be"):
        fit("lambertian", "lambertian:rd=0.5", "l2-cos", highlight=bad)
