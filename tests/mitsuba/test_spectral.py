"""Spectral variant: the same plugins with mi.Spectrum colours, and material="Au"."""

from __future__ import annotations

import numpy as np
import pytest

from mi_helpers import VARIANT, dr, mi

import plausible
import plausible.mitsuba as pm
from plausible import spectra

pytestmark = pytest.mark.drjit

WL = [450.0, 550.0, 650.0, 700.0]


@pytest.fixture
def spectral():
    try:
        pm.register("llvm_ad_spectral")
    except (ImportError, AttributeError, RuntimeError):
        pytest.skip("llvm_ad_spectral variant unavailable")
    try:
        yield
    finally:
        mi.set_variant(VARIANT)


def _si(wi):
    si = dr.zeros(mi.SurfaceInteraction3f, 1)
    si.wi = mi.Vector3f(*[float(x) for x in wi])
    si.wavelengths = mi.Spectrum(*WL)
    return si


def test_spectral_grey_matches_numpy(spectral):
    """A grey Modified Phong in llvm_ad_spectral: every wavelength equals the NumPy value."""
    bsdf = mi.load_dict({"type": "phong", "exponent": 20.0, "diffuse_reflectance": 0.3,
                         "specular_reflectance": 0.4})
    wi = np.array([0.3, 0.1, 0.948683])
    wo = np.array([-0.25, -0.1, 0.963])
    wo /= np.linalg.norm(wo)
    got = np.array(bsdf.eval(mi.BSDFContext(), _si(wi), mi.Vector3f(*[float(x) for x in wo])), dtype=np.float64).ravel()
    want = plausible.make("modified-phong", kd=0.3, ks=0.4, n=20.0).eval(wo, wi) * wo[2]
    np.testing.assert_allclose(got, want, rtol=1e-4)


def test_material_gold_uses_mitsubas_spectral_table(spectral):
    """neumann_metal with material="Au" (fresnel -> conductor): at normal incidence
    eval / c equals the reflectance of Mitsuba's own gold conductor (its sample
    weight at wi = n) at each sampled wavelength, within 1 % of plausible.spectra's
    gold table (a second source), and gold is redder than it is blue."""
    c = 5.0
    bsdf = mi.load_dict({"type": "neumann_metal", "material": "Au", "n": 30.0, "c": c})
    z = np.array([0.0, 0.0, 1.0])
    got = np.array(bsdf.eval(mi.BSDFContext(), _si(z), mi.Vector3f(0.0, 0.0, 1.0)), dtype=np.float64).ravel()
    ref = mi.load_dict({"type": "conductor", "material": "Au"})
    _, w = ref.sample(mi.BSDFContext(), _si(z), mi.Float(0.5), mi.Point2f(0.5, 0.5))
    np.testing.assert_allclose(got / c, np.array(w, dtype=np.float64).ravel(), rtol=2e-5)
    np.testing.assert_allclose(got / c, spectra.metal_reflectance("Au", WL), rtol=1e-2, atol=1e-2)
    assert got[2] > 2 * got[0]
