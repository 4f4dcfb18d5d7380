"""Derivatives through the plugins (issue 19): forward- and reverse-mode
derivatives of eval and of a small prb rendering agree with central finite
differences for every continuous parameter of every plugin; no NaN gradient at
the exponents' extremes, at grazing or at the mirror direction."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import PLUGIN_MODELS, dr, interaction, mi, moderate, upper_dirs, vec3

import plausible
from plausible.params import format_groups

pytestmark = pytest.mark.drjit

PLUGIN_LIST = sorted(PLUGIN_MODELS)
REL_STEP = 1e-3
#: a parameter that the value does not depend on (eta and k without the conductor
#: Fresnel factor) has derivative 0, which the finite difference confirms
ALLOW = dr.ADFlag.Default | dr.ADFlag.AllowNoGrad

#: plugins run once more with the conductor Fresnel factor, so that eta and k matter
CONDUCTOR = [p for p in PLUGIN_LIST if "fresnel" in [q.name for q in plausible.info(PLUGIN_MODELS[p]).params]
             and "conductor" in plausible.info(PLUGIN_MODELS[p]).param("fresnel").choices]
CASES = [(p, {}) for p in PLUGIN_LIST] + [(p, {"fresnel": "conductor"}) for p in CONDUCTOR]


def grey_params(plugin):
    """The test parameters with colours as grey numbers (so each is one mi.Float)."""
    name = PLUGIN_MODELS[plugin]
    out = {}
    for k, v in moderate(name).items():
        kind = plausible.info(name).param(k).kind
        if kind == "color" and isinstance(v, (list, tuple, np.ndarray)):
            v = float(np.mean(v))
        out[k] = format_groups(v) if kind == "structured" or k == "lobes" else v
    return out


def continuous_keys(params):
    return [k for k in params.keys() if "." not in k
            and not params.properties[k][3] & mi.ParamFlags.NonDifferentiable]


def step_and_centre(prm, x0):
    """``(h, x)``: a central-difference step and the point, moved inside the range
    so that ``x +- h`` stays valid."""
    h = REL_STEP * max(abs(x0), 1e-2)
    return h, float(np.clip(x0, prm.lo + 2 * h, prm.hi - 2 * h))


def directions(n=256, seed=5):
    rng = np.random.default_rng(seed)
    wi = upper_dirs(rng, n, 0.1)
    wo = upper_dirs(rng, n, 0.1)
    mirror = np.stack([-wi[:, 0], -wi[:, 1], wi[:, 2]], -1)
    wo[: n // 2] = 0.9 * mirror[: n // 2] + 0.1 * wo[: n // 2]   # near the peak
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    return wi, wo


def loss_of(bsdf, wi, wo):
    """Sum over the pairs and channels of eval (a Dr.Jit Float)."""
    v = bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo))
    return dr.sum(v[0] + v[1] + v[2])


def finite_difference(params, key, x, h, loss):
    vals = []
    for s in (+1, -1):
        params[key] = mi.Float(x + s * h)
        params.update()
        vals.append(float(np.sum(np.array(loss(), dtype=np.float64))))
    params[key] = mi.Float(x)
    params.update()
    return (vals[0] - vals[1]) / (2 * h), 0.5 * (abs(vals[0]) + abs(vals[1]))


def ad_derivatives(params, key, x, loss):
    """(forward, reverse) derivative of ``loss`` in ``params[key]`` at ``x``."""
    def traced():      # a fresh input with gradients on, and the loss computed from it
        v = mi.Float(x)
        dr.enable_grad(v)
        params[key] = v
        params.update()
        return v, loss()

    v, out = traced()
    dr.forward(v, flags=ALLOW)
    fwd = float(dr.grad(out)[0])
    v, out = traced()
    dr.backward(out, flags=ALLOW)
    rev = float(dr.grad(v)[0])
    params[key] = mi.Float(x)
    params.update()
    return fwd, rev


def check_derivatives(plugin, params, loss, ad=None):
    info = plausible.info(PLUGIN_MODELS[plugin])
    keys = continuous_keys(params)
    assert keys
    for key in keys:
        prm = info.param(key)
        h, x = step_and_centre(prm, float(np.array(params[key])[0]))
        params[key] = mi.Float(x)
        params.update()
        fd, size = finite_difference(params, key, x, h, loss)
        fwd, rev = (ad or ad_derivatives)(params, key, x, loss)
        tol = 1e-2 * abs(fd) + 1e-3 * size / max(abs(x), 1e-2)
        assert abs(fwd - fd) <= tol and abs(rev - fd) <= tol, (key, x, fd, fwd, rev, tol)


@pytest.mark.parametrize("plugin,extra", CASES, ids=[p + "-" + "-".join(e.values()) for p, e in CASES])
def test_eval_derivatives_match_central_differences(plugin, extra):
    """d/dx of sum(eval) over 256 pairs (half near the mirror direction), for every
    continuous parameter x: forward and reverse mode within 1 % of the central
    difference (step 1e-3 x) plus its float32 rounding (1e-3 sum / x)."""
    bsdf = mi.load_dict({"type": plugin, **grey_params(plugin), **extra})
    wi, wo = directions()
    check_derivatives(plugin, mi.traverse(bsdf), lambda: loss_of(bsdf, wi, wo))


def test_derivative_check_detects_a_wrong_derivative():
    """The comparison above fails for a derivative that is off by 5 %: an eval
    whose exponent enters as n in the value but 1.05 n in the derivative."""
    bsdf = mi.load_dict({"type": "reciprocal_phong", "n": 20.0, "ks": 0.8})
    params = mi.traverse(bsdf)
    wi, wo = directions()
    fd, size = finite_difference(params, "n", 20.0, 0.02, lambda: loss_of(bsdf, wi, wo))
    v = mi.Float(20.0)
    dr.enable_grad(v)
    params["n"] = v * 1.05 - dr.detach(v) * 0.05
    params.update()
    out = loss_of(bsdf, wi, wo)
    dr.backward(out)
    rev = float(dr.grad(v)[0])
    assert abs(rev - fd) > 1e-2 * abs(fd) + 1e-3 * size / 20.0


def extreme_cases(plugin):
    """Parameter sets at the extremes the models declare for their exponents /
    roughness and at the ends of their ranges (each in turn, the rest as in the
    tests)."""
    info = plausible.info(PLUGIN_MODELS[plugin])
    base = grey_params(plugin)
    out = []
    for prm in info.params:
        if prm.kind != "scalar" or prm.integer or prm.default is None:
            continue
        ends = [v for v in (prm.lo, prm.hi) if np.isfinite(v)]
        for v in sorted(set(float(x) for x in prm.extremes) | set(ends)):
            out.append({**base, prm.name: v})
    return out or [base]


def edge_directions():
    """Normal incidence and its mirror, a 60-degree mirror pair, grazing pairs
    (cos = 1e-4) and a pair with one direction on the horizon."""
    t = np.radians(60.0)
    g = np.sqrt(1 - 1e-8)
    wi = np.array([[0, 0, 1], [np.sin(t), 0, np.cos(t)], [g, 0, 1e-4], [g, 0, 1e-4],
                   [0.6, 0.0, 0.8], [0.0, 0.6, 0.8]])
    wo = np.array([[0, 0, 1], [-np.sin(t), 0, np.cos(t)], [-g, 0, 1e-4], [0, g, 1e-4],
                   [-1.0, 0.0, 0.0], [0.0, -0.6, 0.8]])
    return wi, wo


@pytest.mark.parametrize("plugin", PLUGIN_LIST)
def test_no_nan_gradients_at_extremes(plugin):
    """Reverse-mode gradients of eval are finite for every continuous parameter at
    the extremes and range ends of each exponent / roughness, at normal incidence, at the
    mirror direction, at grazing and on the horizon."""
    wi, wo = edge_directions()
    for params_dict in extreme_cases(plugin):
        bsdf = mi.load_dict({"type": plugin, **params_dict})
        params = mi.traverse(bsdf)
        keys = continuous_keys(params)
        vs = {}
        for k in keys:
            vs[k] = mi.Float(np.array(params[k]))
            dr.enable_grad(vs[k])
            params[k] = vs[k]
        params.update()
        v = bsdf.eval(mi.BSDFContext(), interaction(wi), vec3(wo))
        dr.backward(dr.sum(v[0] + v[1] + v[2]), flags=ALLOW)
        for k in keys:
            g = float(dr.grad(vs[k])[0])
            assert np.isfinite(g), (plugin, params_dict, k, g)


# -- through a rendering (prb) ------------------------------------------------------------

def small_scene(bsdf: dict, res: int = 8):
    """A sphere lit by a point light beside a perspective camera, rendered by prb
    (max_depth 2: the image is direct light through eval only, so renders with
    the same seed differ only by the parameters and finite differences are exact
    up to float32)."""
    return mi.load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 30,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[0, 0, 4], target=[0, 0, 0],
                                                              up=[0, 1, 0]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": 2}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "light": {"type": "point", "position": [1.0, 1.5, 3.0], "intensity": {"type": "rgb", "value": 20.0}},
    })


SPP = 2


def render_derivatives(scene, integrator):
    """``(loss, ad)`` for :func:`check_derivatives`: the sum of the image, and its
    forward / reverse derivatives from the integrator's ``render_forward`` /
    ``render_backward`` with the same seed as the primal renders (``mi.render``
    would decorrelate the gradient pass, and the comparison would see its noise)."""
    def loss():
        return dr.sum(dr.ravel(integrator.render(scene, seed=0, spp=SPP)))

    def ad(params, key, x, _loss):
        try:
            return _ad(params, key, x)
        except Exception as err:  # noqa: BLE001 - prb refuses a parameter the image does not depend on
            chain, e = [], err
            while e is not None:
                chain.append(str(e))
                e = e.__cause__ or e.__context__
            if not any("not attached to the AD graph" in c for c in chain):
                raise
            return 0.0, 0.0  # then the finite difference must be 0 as well

    def _ad(params, key, x):
        v = mi.Float(x)
        dr.enable_grad(v)
        params[key] = v
        params.update()
        dr.set_grad(v, 1.0)
        fwd = float(np.sum(np.array(integrator.render_forward(scene, params.params, seed=0, spp=SPP),
                                    dtype=np.float64)))
        v = mi.Float(x)
        dr.enable_grad(v)
        params[key] = v
        params.update()
        img = integrator.render(scene, seed=0, spp=SPP)
        integrator.render_backward(scene, params.params, dr.full(mi.TensorXf, 1.0, img.shape),
                                   seed=0, spp=SPP)
        rev = float(dr.grad(v)[0])
        params[key] = mi.Float(x)
        params.update()
        return fwd, rev

    return loss, ad


def check_render_derivatives(plugin, extra):
    scene = small_scene({"type": plugin, **grey_params(plugin), **extra})
    loss, ad = render_derivatives(scene, scene.integrator())
    check_derivatives(plugin, _BsdfParams(mi.traverse(scene)), loss, ad)


class _BsdfParams:
    """The scene's parameters of the sphere's BSDF under their plugin names."""

    def __init__(self, params):
        self.params = params
        keys = [k for k in params.keys() if ".bsdf." in k]
        self.prefix = keys[0].split(".bsdf.")[0] + ".bsdf."
        self.properties = {k[len(self.prefix):]: params.properties[k] for k in keys}

    def keys(self):
        return list(self.properties)

    def __getitem__(self, k):
        return self.params[self.prefix + k]

    def __setitem__(self, k, v):
        self.params[self.prefix + k] = v

    def update(self):
        self.params.update()


@pytest.mark.parametrize("plugin", ["ashikhmin_shirley"])
def test_render_derivatives_match_central_differences_quick(plugin):
    """d/dx of the sum of an 8x8 prb image (2 spp): forward and reverse mode agree with
    central differences (same seed), for every continuous parameter."""
    check_render_derivatives(plugin, {})


@pytest.mark.slow
@pytest.mark.parametrize("plugin,extra", CASES, ids=[p + "-" + "-".join(e.values()) for p, e in CASES])
def test_render_derivatives_match_central_differences(plugin, extra):
    """As the quick test, for every plugin (and the conductor Fresnel factor)."""
    check_render_derivatives(plugin, extra)
