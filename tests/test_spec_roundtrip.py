"""Specs that round-trip (issue 41, item 2): ``spec()`` of any model, sum or material is a string
that ``plausible.make`` reads back into an equal model, and a sum ``"a + b"`` is a spec wherever a
spec is accepted (``make``, ``eval``, ``albedo``, ``check``, ``fit --target``, Mitsuba's ``to_dict``)."""

import math

import numpy as np
import pytest
from click.testing import CliRunner

import plausible
from plausible.catalogue import fit_sets
from plausible.cli import main
from plausible.models.sum import Sum
from conftest import model_cases, random_upper


def _pairs(seed=7, n=64):
    rng = np.random.default_rng(seed)
    return random_upper(rng, n, 0.05), random_upper(rng, n, 0.05)


def _same(a, b):
    """``b`` is ``a`` again: the same spec and the same values on random pairs."""
    wi, wo = _pairs()
    assert b.spec() == a.spec()
    np.testing.assert_allclose(np.asarray(b.eval(wi, wo)), np.asarray(a.eval(wi, wo)), rtol=1e-12, atol=0)


@pytest.mark.parametrize("name,kw", model_cases())
def test_every_registered_model_reads_back_from_its_spec(name, kw):
    m = plausible.make(name, **kw)
    _same(m, plausible.make(m.spec()))


#: Sums and their terms as (scale, spec), each term built alone in the test.
SUMS = [("lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50",
         [(1.0, "lambertian:rd=0.5"), (1.0, "reciprocal-blinn:ks=0.3:n=50")]),
        ("lambertian:rd=0.2,0.3,0.4 + 0.5,0.25,1 * ward:alpha_x=0.2:alpha_y=0.1",
         [(1.0, "lambertian:rd=0.2,0.3,0.4"), (np.array([0.5, 0.25, 1.0]), "ward:alpha_x=0.2:alpha_y=0.1")]),
        ("0.25 * lambertian + pumped-up:base=[lambertian:rd=0.3 + 0.5 * reciprocal-phong:n=20]",
         [(0.25, "lambertian"), (1.0, "pumped-up:base=[lambertian:rd=0.3 + 0.5 * reciprocal-phong:n=20]")]),
        ("kulla-conty + 0.125 * cook-torrance:m=0.3", [(1.0, "kulla-conty"), (0.125, "cook-torrance:m=0.3")])]


@pytest.mark.parametrize("spec,terms", SUMS, ids=[s for s, _ in SUMS])
def test_a_sum_spec_is_the_sum_of_its_scaled_terms_and_reads_back(spec, terms):
    """Independent truth: the sum's value is each term built alone, times its scale, added."""
    m = plausible.make(spec)
    wi, wo = _pairs()
    total = 0.0
    for scale, part in terms:
        f = np.asarray(plausible.make(part).eval(wi, wo), float)
        total = total + (f[..., None] if f.ndim == 1 and np.ndim(scale) else f) * scale
    np.testing.assert_allclose(np.broadcast_to(np.asarray(m.eval(wi, wo)), np.shape(total)), total, rtol=1e-12)
    _same(m, plausible.make(m.spec()))


def test_a_sum_of_sums_and_a_labelled_sum_read_back():
    inner = Sum([(plausible.make("lambertian", rd=0.4), 0.5), plausible.make("reciprocal-phong", n=30)])
    outer = Sum([(inner, [1.0, 0.5, 0.25]), plausible.make("lambertian", rd=0.1)], name="mine")
    _same(outer, plausible.make(outer.spec()))


FITS = [f.key for f in fit_sets.fits() if f.built]


@pytest.mark.parametrize("fit", FITS)
def test_a_material_reads_back_from_its_spec(fit):
    names = sorted(fit_sets.materials())
    name = names[FITS.index(fit) * 13 % len(names)]          # a different material for each fit set
    m = plausible.material(name, fit)
    assert m.spec() == f"material:{name}@{fit}"
    _same(m, plausible.make(m.spec()))
    s = plausible.make(f"0.5 * {m.spec()} + lambertian:rd=0.1")       # a material inside a sum
    _same(s, plausible.make(s.spec()))


def test_a_sum_is_refused_with_a_message_about_the_sum_not_a_parts_parameters():
    with pytest.raises(ValueError, match="is a sum: give parameters inside its terms") as e:
        plausible.make("lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=50", rd=0.2)
    assert "unknown parameter" not in str(e.value)
    with pytest.raises(ValueError, match=r"scale before ' \* ' must be a number or r,g,b, got 'x'"):
        plausible.make("lambertian + x * lambertian")


def test_albedo_and_eval_take_a_sum_on_the_command_line():
    """Two Lambertian terms: albedo rd1 + s rd2 = 0.5 + 0.5 * 0.5 at every incidence; f = that / pi."""
    spec = "lambertian:rd=0.5 + 0.5 * lambertian:rd=0.5"
    r = CliRunner().invoke(main, ["albedo", spec, "-n", "3"], terminal_width=200)
    assert r.exit_code == 0, r.output
    rows = [ln for ln in r.output.splitlines() if ln.strip().startswith("│ 0.00")]
    assert rows and "0.750000" in rows[0]
    r = CliRunner().invoke(main, ["eval", spec, "--wi", "30,0", "--wo", "40,90", "--json"])
    assert r.exit_code == 0, r.output
    assert f"{0.75 / math.pi:.10f}"[:10] in r.output.replace(" ", "")


def test_check_and_a_fit_target_take_a_sum():
    rep = plausible.check("lambertian:rd=0.5 + 0.5 * lambertian:rd=0.5", quick=True)
    assert rep.passed, rep.verdict
    from plausible.fitting.targets import as_target

    spec = "lambertian:rd=0.1 + 0.5 * material:nickel@ngan2005/ward"       # a '/' is not a path here
    t = as_target(spec)
    wi, wo = _pairs()
    want = 0.1 / math.pi + 0.5 * np.asarray(plausible.material("nickel", "ngan2005/ward").eval(wi, wo))
    np.testing.assert_allclose(np.asarray(plausible.make(spec).eval(wi, wo)), want, rtol=1e-12)
    assert t is not None


def test_mitsubas_to_dict_of_a_sum_and_a_material_loads_and_agrees():
    pytest.importorskip("mitsuba")
    from plausible.analysis.mitsuba_bsdf import MitsubaBSDF, load_bsdf_dict
    from plausible.mitsuba.scene_dict import to_dict
    import plausible.mitsuba as pm

    pm.register()
    wi, wo = _pairs(3, 16)
    for m in (plausible.make("lambertian:rd=0.2,0.3,0.4 + 0.5,0.25,1 * reciprocal-blinn:ks=0.3:n=50"),
              plausible.material("nickel", "ngan2005/ward")):
        d = to_dict(m)
        assert d["type"] in ("plausible_sum", "plausible_material")
        got = np.asarray(MitsubaBSDF(load_bsdf_dict(d)).eval(wi, wo), float)
        np.testing.assert_allclose(got, np.asarray(m.eval(wi, wo)) * 1.0, rtol=2e-5)     # float32 kernels
