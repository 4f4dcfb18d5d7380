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
    assert np.array_equal(pickle.loads(pickle.dumps(m)).params["kd"], [0.1, 0.2, 0.3])
    assert plausible.text.jsonable(m.params) == {"kd": [0.1, 0.2, 0.3], "ks": 0.2, "n": 30.0}


@pytest.mark.parametrize("bad", [[0.1, 0.2], [0.1, 0.2, 0.3, 0.4]])
def test_colours_have_one_or_three_channels(bad):
    with pytest.raises(ValueError, match=r"'kd' must have 1 or 3 channel\(s\).*got %d" % len(bad)):
        plausible.make("modified-phong", kd=bad)
    assert plausible.make("modified-phong", kd=[0.1]).channels == 1
    assert plausible.make("modified-phong", kd=[0.1, 0.2, 0.3]).channels == 3


def test_a_spectral_model_widens_the_channel_rule():
    class Spectral(type(plausible.make("lambertian"))):
        CHANNELS = (1, 3, 4)

    assert Spectral(rd=[0.1, 0.2, 0.3, 0.4]).eval([0, 0, 1], [0, 0, 1]) == pytest.approx(
        np.array([0.1, 0.2, 0.3, 0.4]) / math.pi, rel=1e-15)
