"""The measured-data model MerlBRDF as the Mitsuba plugin 'merl' (issue 19):
the plugin tests of tests/mitsuba/test_plugins.py on a synthetic MERL table."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import interaction, mi, spectrum_np, upper_dirs, vec3

from plausible.models.merl import RES, read_merl, write_merl

pytestmark = pytest.mark.drjit


@pytest.fixture(scope="module")
def merl_file(tmp_path_factory):
    """A table of random values (every cell different, so a wrong cell shows)
    with 1 % of the cells missing (negative)."""
    rng = np.random.default_rng(3)
    v = rng.uniform(0.05, 2.0, (3,) + RES)
    v[:, rng.random(RES) < 0.01] = -1.0
    return write_merl(tmp_path_factory.mktemp("merl") / "random.binary", v)


def test_eval_and_pdf_match_the_numpy_table(merl_file):
    """eval == f(wo, si.wi) cos(theta_o) from the NumPy MerlBRDF, cell for cell, for
    at least 99 % of random pairs (float32 directions may fall in a neighbouring
    cell at a cell edge; a wrong lookup would miss almost every random cell);
    pdf == cos(theta_o) / pi."""
    model = read_merl(merl_file)
    bsdf = mi.load_dict({"type": "merl", "filename": str(merl_file)})
    rng = np.random.default_rng(8)
    wi, wo = upper_dirs(rng, 4096, 0.05), upper_dirs(rng, 4096, 0.05)
    got = spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))
    want = model.eval(wo, wi) * wo[:, 2:3]
    same = np.all(np.isclose(got, want, rtol=1e-5, atol=1e-7), axis=1)
    assert np.mean(same) > 0.99, np.mean(same)
    pdf = np.array(bsdf.pdf(mi.BSDFContext(), interaction(wi), vec3(wo)), dtype=np.float64)
    np.testing.assert_allclose(pdf, wo[:, 2] / np.pi, rtol=1e-5)


def test_a_shifted_table_is_detected(merl_file):
    """The cell comparison above fails for a lookup one theta_d cell off."""
    model = read_merl(merl_file)
    shifted = type(model)(np.roll(model.values, 1, axis=2))
    bsdf = mi.load_dict({"type": "merl", "filename": str(merl_file)})
    rng = np.random.default_rng(8)
    wi, wo = upper_dirs(rng, 1024, 0.05), upper_dirs(rng, 1024, 0.05)
    got = spectrum_np(bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo)))
    same = np.all(np.isclose(got, shifted.eval(wo, wi) * wo[:, 2:3], rtol=1e-5, atol=1e-7), axis=1)
    assert np.mean(same) < 0.2


def test_sample_matches_numpy(merl_file):
    """sample: wo (cosine-weighted), pdf and weight = f cos / pdf as the NumPy model."""
    model = read_merl(merl_file)
    bsdf = mi.load_dict({"type": "merl", "filename": str(merl_file)})
    rng = np.random.default_rng(11)
    wi = upper_dirs(rng, 512, 0.1)
    u = np.clip(rng.random((512, 3)).astype(np.float32).astype(np.float64), 1e-3, 1 - 1e-3)
    ref = model.sample(wi, u)
    bs, w = bsdf.sample(mi.BSDFContext(), interaction(wi), mi.Float(u[:, 0].astype(np.float32)),
                        mi.Point2f(np.ascontiguousarray(u[:, 1:].T, dtype=np.float32)))
    wo = np.array(bs.wo, dtype=np.float64).T
    np.testing.assert_allclose(wo, ref.wo, atol=2e-4)
    np.testing.assert_allclose(np.array(bs.pdf), ref.pdf, rtol=1e-4)
    want = model.eval(wo, wi) * wo[:, 2:3] / ref.pdf[:, None]
    same = np.all(np.isclose(spectrum_np(w), want, rtol=1e-4, atol=1e-6), axis=1)
    assert np.mean(same) > 0.99


def test_chi2(tmp_path):
    """Mitsuba's chi-square harness: sample() is distributed as pdf() says.  (A
    table without missing cells: the harness drops samples of weight 0.)"""
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    path = write_merl(tmp_path / "full.binary", np.random.default_rng(4).uniform(0.05, 2.0, (3,) + RES))
    s, p = BSDFAdapter("merl", {"type": "merl", "filename": str(path)}, wi=[0.5, 0.0, 0.866])
    chi2 = ChiSquareTest(domain=SphericalDomain(), sample_func=s, pdf_func=p, sample_dim=3,
                         sample_count=200_000, res=101, ires=4, seed=3)
    assert chi2.run(significance_level=0.01, quiet=True), chi2.messages


def test_flags_and_errors(merl_file):
    b = mi.load_dict({"type": "merl", "filename": str(merl_file)})
    assert b.flags() & mi.BSDFFlags.GlossyReflection and b.flags() & mi.BSDFFlags.DiffuseReflection
    with pytest.raises((RuntimeError, ValueError), match="merl: the parameter 'filename'"):
        mi.load_dict({"type": "merl"})
    with pytest.raises((RuntimeError, ValueError), match="merl: unknown parameter 'kd'"):
        mi.load_dict({"type": "merl", "filename": str(merl_file), "kd": 0.5})


def test_white_furnace_of_a_tabulated_lambertian(tmp_path):
    """A MERL table of Lambertian rd = 0.7 (plausible.fitting.tabulate) in a unit
    white furnace renders like the lambertian plugin with the same seed (same
    random numbers, same f) within 0.2 % (light samples near the horizon meet
    cells that straddle it, which the table holds as 0: measured 6e-4 at most),
    and its sphere averages 0.7."""
    import plausible
    from plausible.models.merl import tabulate
    from test_render import furnace_scene

    path = write_merl(tmp_path / "lambert.binary", tabulate(plausible.make("lambertian", rd=0.7)))
    merl = np.array(mi.render(furnace_scene({"type": "merl", "filename": str(path)}, 1.1, 16), seed=1))
    lamb = np.array(mi.render(furnace_scene({"type": "lambertian", "rd": 0.7}, 1.1, 16), seed=1))
    c = (np.arange(16) + 0.5) / 16 * 2.2 - 1.1
    inside = np.hypot(c[None, :], c[:, None]) < 0.9
    np.testing.assert_allclose(merl, lamb, rtol=2e-3, atol=1e-6)
    vals = merl[inside].mean(axis=-1)
    assert abs(vals.mean() - 0.7) < 4 * vals.std(ddof=1) / np.sqrt(vals.size)
