"""The model object as a user meets it: read-only parameters, ``replace``,
specs and typos in ``make``, colour channel counts."""

import math
import pickle

import numpy as np
import pytest

import plausible
from plausible.export import to_glsl


def test_parameters_are_read_only_and_eval_keeps_them():
    m = plausible.make("ashikhmin-shirley", nu=10)
    before = m.eval([0, 0.3, 0.9], [0.2, -0.1, 0.95])
    with pytest.raises(TypeError, match="read-only.*replace"):
        m.params["nu"] = 5
    with pytest.raises(TypeError):
        m.params.update(nu=-50)
    with pytest.raises(AttributeError):
        m.params = {"nu": 777}
    assert m.params["nu"] == 10 and "nu=10" in repr(m) and "nu=10" in plausible.registry.spec_of(m)
    assert m.eval([0, 0.3, 0.9], [0.2, -0.1, 0.95]) == before


def test_a_colour_parameter_cannot_be_changed_in_place():
    kd = np.array([0.1, 0.2, 0.3])
    m = plausible.make("modified-phong", kd=kd, ks=0.2)
    with pytest.raises(ValueError, match="read-only"):
        m.params["kd"][0] = 0.9
    kd[0] = 0.9                      # the caller's array is the caller's
    assert m.params["kd"][0] == 0.1


def test_replace_returns_a_new_validated_model():
    m = plausible.make("ashikhmin-shirley", nu=10, nv=100)
    r = m.replace(nu=5)
    wi, wo = [0.3, 0.2, 0.93], [-0.4, 0.1, 0.91]
    assert r.eval(wi, wo) == plausible.make("ashikhmin-shirley", nu=5, nv=100).eval(wi, wo)
    assert r.eval(wi, wo) != m.eval(wi, wo) and m.params["nu"] == 10
    with pytest.raises(ValueError, match="'nu' must lie in"):
        m.replace(nu=-50)
    with pytest.raises(ValueError, match="unknown parameter"):
        m.replace(bogus=1)


def test_replace_derives_a_derived_parameter_again():
    m = plausible.make("neumann-metal", n=100)
    r = m.replace(n=50)
    assert r.params["c"] == pytest.approx((50 + 2) / (2 * math.pi), rel=1e-15)
    # an explicit c stays as given
    assert plausible.make("neumann-metal", n=100, c=1.0).replace(n=50).params["c"] == 1.0


def test_exported_shader_lists_the_values_the_model_uses():
    m = plausible.make("ashikhmin-shirley", nu=10).replace(nu=777)
    assert "nu=777" in to_glsl(m).text and "nu=10" not in to_glsl(m).text


def test_parameters_survive_pickling_and_json():
    m = plausible.make("modified-phong", kd=[0.1, 0.2, 0.3])
    back = pickle.loads(pickle.dumps(m))
    assert np.array_equal(back.params["kd"], [0.1, 0.2, 0.3])
    with pytest.raises(ValueError, match="read-only"):
        back.params["kd"][0] = 0.9                  # still read-only (and so the p the formulas read)
    assert back.p.kd is back.params["kd"]
    assert plausible.text.jsonable(m.params) == {"kd": [0.1, 0.2, 0.3], "ks": 0.2, "n": 30.0}


@pytest.mark.parametrize("bad", [[0.1, 0.2], [0.1, 0.2, 0.3, 0.4]])
def test_colours_have_one_or_three_channels(bad):
    with pytest.raises(ValueError, match=r"'kd' must have 1 or 3 channels.*got %d" % len(bad)):
        plausible.make("modified-phong", kd=bad)
    assert plausible.make("modified-phong", kd=[0.1]).channels == 1
    assert plausible.make("modified-phong", kd=[0.1, 0.2, 0.3]).channels == 3


def test_a_spectral_model_widens_the_channel_rule():
    class Spectral(type(plausible.make("lambertian"))):
        CHANNELS = (1, 3, 4)

    assert Spectral(rd=[0.1, 0.2, 0.3, 0.4]).eval([0, 0, 1], [0, 0, 1]) == pytest.approx(
        np.array([0.1, 0.2, 0.3, 0.4]) / math.pi, rel=1e-15)


# -- units: radians in the library, degrees where a name says _deg -----------------

def test_direction_and_angles_are_inverse_and_in_radians():
    w = plausible.direction(math.radians(60), math.radians(90))
    np.testing.assert_allclose(w, [0.0, math.sin(math.pi / 3), 0.5], atol=1e-15)
    th, ph = plausible.angles(w)
    assert th == pytest.approx(math.pi / 3, rel=1e-14) and ph == pytest.approx(math.pi / 2, rel=1e-14)
    rng = np.random.default_rng(1)
    t, p = rng.uniform(0, math.pi, 50), rng.uniform(-math.pi, math.pi, 50)
    back = plausible.angles(3.0 * plausible.direction(t, p))      # any length
    np.testing.assert_allclose(back[0], t, atol=1e-12)
    np.testing.assert_allclose(back[1], p, atol=1e-12)


def test_degrees_where_radians_are_due_are_refused_with_the_fix():
    m = plausible.make("lambertian", rd=0.5)
    with pytest.raises(ValueError, match=r"radians.*math\.radians\(30\)"):
        plausible.direction(30)
    with pytest.raises(ValueError, match=r"got the number 30.*plausible\.direction"):
        plausible.albedo(m, 30)
    with pytest.raises(ValueError, match=r"\[0, pi/2\] radians, got 30 \(degrees\? pass thetas_deg"):
        plausible.albedo_curve(m, [0, 30, 60])


def test_albedo_curve_takes_degrees_by_name():
    m = plausible.make("modified-phong", kd=0.3, ks=0.5, n=20)
    with plausible.use_backend("numpy"):        # one backend: the same integrals bit for bit
        a = plausible.albedo_curve(m, thetas_deg=[0, 30, 60], phi_deg=45)
        b = plausible.albedo_curve(m, np.radians([0, 30, 60]), math.radians(45))
    assert np.array_equal(a.value, b.value)
    with pytest.raises(ValueError, match="not both"):
        plausible.albedo_curve(m, [0.1], thetas_deg=[30])


# -- API habits -------------------------------------------------------------------

def test_make_takes_a_spec():
    a = plausible.make("ashikhmin-shirley:nu=10")
    assert a.params["nu"] == 10 and repr(a) == repr(plausible.make("ashikhmin-shirley", nu=10))
    assert plausible.make("ashikhmin-shirley:nu=10", nv=7).params["nv"] == 7
    assert repr(plausible.make("material:nickel@ngan2005/ward")) == repr(plausible.material("nickel", "ngan2005/ward"))


def test_a_typo_in_a_model_name_gets_a_suggestion():
    with pytest.raises(ValueError, match=r"unknown model 'ashikmin-shirley' \(did you mean ashikhmin-shirley"):
        plausible.make("ashikmin-shirley")
    with pytest.raises(ValueError) as e:
        plausible.make("zzzz")
    assert "did you mean" not in str(e.value)


def test_a_nested_spec_without_brackets_gets_the_bracketed_spelling():
    with pytest.raises(ValueError, match=r"square brackets: 'pumped-up:base=\[reciprocal-phong:ks=1:n=20\]:times=2'"):
        plausible.make("pumped-up:base=reciprocal-phong:ks=1:n=20:times=2")


def test_an_albedo_result_computes_as_its_value():
    m = plausible.make("lambertian", rd=0.5)
    a = plausible.albedo(m, [0, 0, 1])
    assert a + 0 == pytest.approx(0.5, rel=1e-12) and sum([a, a]) == pytest.approx(1.0, rel=1e-12)
    assert 2 * a == pytest.approx(1.0, rel=1e-12) and 1 - a == pytest.approx(0.5, rel=1e-12) and a <= 1
    c = plausible.albedo(plausible.make("lambertian", rd=[0.1, 0.2, 0.4]), [0, 0, 1])
    np.testing.assert_allclose(c + 0, [0.1, 0.2, 0.4], rtol=1e-12)
    np.testing.assert_allclose(np.asarray(c), [0.1, 0.2, 0.4], rtol=1e-12)


def test_notebook_html_shows_the_parameters_escaped():
    m = plausible.make("pumped-up", base="reciprocal-phong:n=7")
    html = m._repr_html_()
    assert html.startswith("<table><caption>pumped-up") and "<td>times</td><td>1</td>" in html
    assert "<td>correction</td><td>max</td>" in html
    a = plausible.albedo(plausible.make("lambertian", rd=0.5), [0, 0, 1])
    assert "<td>0.5</td>" in a._repr_html_()
    rep = plausible.check("lambertian:rd=0.5", quick=True)
    assert "<td>reciprocity</td>" in rep._repr_html_() and "PASS" in rep._repr_html_()


@pytest.mark.parametrize("typed,meant", [("ngan2005/as", "ngan2005/ashikhmin-shirley"),
                                         ("ngan2005/ct", "ngan2005/cook-torrance"),
                                         ("ngan2005/bp", "ngan2005/blinn-phong"),
                                         ("low2012/ct", "low2012/cook-torrance-e1")])
def test_an_abbreviated_fit_name_suggests_the_fit_it_abbreviates(typed, meant):
    with pytest.raises(ValueError, match=r"did you mean " + meant):     # listed first
        plausible.make(f"material:nickel@{typed}")


def test_an_abbreviated_model_name_suggests_it_and_unrelated_names_are_not_suggested():
    from plausible.text import closest

    assert closest("as", ["ashikhmin-shirley", "ward", "lambertian"]) == ["ashikhmin-shirley"]
    assert closest("mp", ["modified-phong", "phong"])[0] == "modified-phong"
    assert closest("zz", ["ashikhmin-shirley", "ward"]) == []
    assert closest("ngan2005/as", ["low2012/ashikhmin-shirley-e1"]) == []      # another fit set: no
    with pytest.raises(ValueError, match=r"did you mean ashikhmin-shirley"):
        plausible.make("as")


def test_a_shape_mismatch_names_wi_and_wo():
    m = plausible.make("lambertian")
    a, b = np.tile([0.0, 0.0, 1.0], (5, 1)), np.tile([0.6, 0.0, 0.8], (4, 1))
    for backend in ("numpy", "drjit", None):
        with pytest.raises(ValueError, match=r"wi of shape \(5, 3\) and wo of shape \(4, 3\) do not broadcast"):
            m.eval(a, b, backend=backend)
    with pytest.raises(ValueError, match=r"wi of shape \(5, 3\) and wo of shape \(4, 3\)"):
        m.pdf(a, b)
    with pytest.raises(ValueError, match=r"wi of shape \(5, 3\) and u of shape \(4, 3\)"):
        m.sample(a, np.full((4, 3), 0.5))
    assert m.eval(a, b[0]).shape == (5,)                   # one direction for all still broadcasts
