"""A new value of a parameter is kernel data, not code (issue 43): after
``params.update()`` of an ``<rgb>`` colour, ``sample``, ``pdf`` and ``eval`` run
the kernels already compiled (Dr.Jit's kernel history, compared by hash)."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import PLUGIN_MODELS, dr, interaction, mi, upper_dirs, vec3

import plausible

pytestmark = pytest.mark.drjit

#: The two-lobe plugins whose <rgb> colours recompiled on every new value.
TWO_LOBE = {"ashikhmin_shirley": ("rs", "rd"), "modified_phong": ("kd", "ks"), "ward": ("rs", "rd"),
            "gltf_pbr": ("base_color",)}


def colour_params(plugin):
    return [p.name for p in plausible.info(PLUGIN_MODELS[plugin]).params if p.kind == "color" and p.default is not None]


def kernel_hashes(bsdf, wi, wo) -> set:
    """The hashes of the JIT kernels that ``sample``, ``pdf`` and ``eval`` of 64 points launch."""
    ctx, si = mi.BSDFContext(), interaction(wi)
    dr.kernel_history()  # drop what ran before
    n = len(wi)
    bs, w = bsdf.sample(ctx, si, mi.Float(np.linspace(0.01, 0.99, n)), mi.Point2f(np.full((2, n), 0.37)))
    dr.eval(bs.wo, bs.pdf, w, bsdf.pdf(ctx, si, vec3(wo)), bsdf.eval(ctx, si, vec3(wo)))
    return {k["hash"] for k in dr.kernel_history() if k["type"] == dr.KernelType.JIT}


@pytest.fixture
def history():
    old = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    yield
    dr.set_flag(dr.JitFlag.KernelHistory, old)


@pytest.mark.parametrize("plugin", sorted(TWO_LOBE))
def test_a_new_rgb_value_compiles_no_new_kernel(plugin, history):
    """Each colour given as <rgb> (0.2, 0.3, 0.25), then scaled through params.update() (the
    first by 0.9, the second by 0.7, so their ratio changes too):
    the second pass launches only kernels of the first (before issue 43 the lobe-choice
    probability, a mean of the colours, was a literal in the code)."""
    rng = np.random.default_rng(3)
    wi, wo = upper_dirs(rng, 64, 0.2), upper_dirs(rng, 64, 0.2)
    names = TWO_LOBE[plugin]
    assert set(names) <= set(colour_params(plugin))
    bsdf = mi.load_dict({"type": plugin, **{k: {"type": "rgb", "value": [0.2, 0.3, 0.25]} for k in names}})
    first = kernel_hashes(bsdf, wi, wo)
    params = mi.traverse(bsdf)
    for k, scale in zip(names, (0.9, 0.7)):
        params[f"{k}.value"] = params[f"{k}.value"] * scale
    params.update()
    second = kernel_hashes(bsdf, wi, wo)
    assert first and second <= first


def test_he_torrance_compiles_no_new_kernel_for_a_new_wavelength_or_roughness(history):
    """He-Torrance with every colour as <rgb> (wavelength 0.33/0.55/0.44 um, tau 1 um), then
    each colour scaled differently and sigma0 raised: the second pass launches only kernels
    of the first.  Before issue 43 the number of series terms came from the values
    (wavelength x 0.8: 96 -> 128 terms, one new kernel per such value); the plugin sums
    every term (HeTorrance.for_changing_data)."""
    rng = np.random.default_rng(3)
    wi, wo = upper_dirs(rng, 64, 0.2), upper_dirs(rng, 64, 0.2)
    colours = {"wavelength": [0.33, 0.55, 0.44], "eta": [0.9, 1.5, 1.2], "k": [0.1, 0.2, 0.3],
               "rs": [0.6, 1.0, 0.8], "rd": [0.1, 0.2, 0.1]}
    bsdf = mi.load_dict({"type": "he_torrance", "tau": 1.0, "sigma0": 0.18,
                         **{k: {"type": "rgb", "value": v} for k, v in colours.items()}})
    first = kernel_hashes(bsdf, wi, wo)
    params = mi.traverse(bsdf)
    for i, k in enumerate(colours):
        params[f"{k}.value"] = params[f"{k}.value"] * (0.8 - 0.05 * i)
    params["sigma0"] = mi.Float(0.4)
    params.update()
    second = kernel_hashes(bsdf, wi, wo)
    assert first and second <= first
