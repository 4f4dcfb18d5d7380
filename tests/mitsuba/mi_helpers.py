"""Shared set-up of the Mitsuba plugin tests (imported by tests/mitsuba/test_*.py)."""

from __future__ import annotations

import os

import numpy as np
import pytest

mi = pytest.importorskip("mitsuba")
dr = pytest.importorskip("drjit")

from plausible.mitsuba import variant as _variants  # noqa: E402

#: The variant the plugin tests run on: $PLAUSIBLE_TEST_VARIANT (scripts/gpu_check.sh runs the
#: suite once per CUDA variant), else the machine's preferred RGB variant (cuda_ad_rgb where a GPU
#: is found, else llvm_ad_rgb), else llvm_ad_rgb.
VARIANT = None
for _v in dict.fromkeys([v for v in (os.environ.get("PLAUSIBLE_TEST_VARIANT"),) if v]
                        + [v for v in _variants.available() if v.endswith("_ad_rgb")][:1] + ["llvm_ad_rgb"]):
    try:
        mi.set_variant(_v)
        VARIANT = _v
        break
    except (ImportError, AttributeError, RuntimeError):
        continue
if VARIANT is None:
    pytest.skip("no Mitsuba JIT variant can be set", allow_module_level=True)
#: The device of :data:`VARIANT`: tolerances that differ there say why (approximate division and
#: square root, flushed denormals and contracted products on CUDA).
ON_CUDA = VARIANT.startswith("cuda")

import plausible  # noqa: E402
import plausible.mitsuba as pm  # noqa: E402
from plausible.params import format_groups  # noqa: E402
from conftest import random_upper  # noqa: E402

PLUGINS = pm.register()
PLUGIN_MODELS = pm.plugin_names()

#: "Moderate" parameters for models whose defaults are too sharp or isotropic
#: for quick float32 / chi-square checks.  Models not listed use their defaults
#: with exponent-like scalars (upper bound >= 1000) capped at 40 (see moderate()).
MODERATE = {
    "ashikhmin-shirley": dict(nu=10.0, nv=60.0, rs=[0.05, 0.1, 0.2], rd=[0.3, 0.4, 0.5]),
    "ashikhmin-shirley-specular": dict(nu=10.0, nv=60.0),
    "modified-phong": dict(kd=[0.3, 0.4, 0.5], ks=[0.3, 0.2, 0.1], n=30.0),
    # roughness 0.1 (the defaults) is a lobe as sharp as n ~ 200: Mitsuba's chi-square
    # harness at its default resolution (res 101, ires 4) gives false failures at 82 deg,
    # as it does for its own roughconductor; moderate roughness here.
    "ward": dict(alpha_x=0.25, alpha_y=0.4, rd=[0.1, 0.2, 0.3], rs=[0.5, 0.6, 0.7]),
    "cook-torrance": dict(m=0.3),
    # tau = 3 um puts the lobe within ~2 degrees of the mirror direction (tau kappa ~ 40):
    # finer than the harness's grid resolves at normal incidence; tau = 1 um, ~6 degrees
    "he-torrance": dict(tau=1.0),
}


def moderate(model_name: str) -> dict:
    """Parameters used by the tests for ``model_name`` (native plausible names)."""
    info = plausible.info(model_name)
    out = {}
    for p in info.params:
        if p.default is None:
            continue
        if p.kind == "scalar" and p.hi >= 1e3 and not p.integer:
            out[p.name] = float(min(p.default, 40.0))
        elif p.kind == "color":
            d = float(np.mean(p.default))
            out[p.name] = [0.6 * d, d, 0.8 * d]
        else:
            out[p.name] = p.default
    if model_name == "lafortune":
        # one Phong-like lobe and one off-specular lobe, exponents 20 and 8
        out["lobes"] = ((-1.0, -1.0, 1.0, 20.0, 1.2), (-0.8, -0.8, 0.5, 8.0, 0.3))
    out.update(MODERATE.get(model_name, {}))
    return out


def to_dict(plugin: str, params: dict) -> dict:
    """A ``mi.load_dict`` description of ``plugin`` with ``params``."""
    d = {"type": plugin}
    for k, v in params.items():
        kind = plausible.info(pm.plugin_names()[plugin]).param(k).kind
        if kind == "model":
            d[k] = v  # a nested model spec string (pumped_up's base)
        elif kind not in ("scalar", "color", "choice"):
            d[k] = format_groups(v)
        elif isinstance(v, (list, tuple, np.ndarray)):
            d[k] = {"type": "rgb", "value": [float(x) for x in v]}
        else:
            d[k] = v
    return d


def upper_dirs(rng, n, zmin=0.05):
    """Random unit vectors with ``z >= zmin`` (:func:`conftest.random_upper`), rounded to
    float32 and normalised again (float32-representable, for the float32 variants)."""
    v = random_upper(rng, n, zmin).astype(np.float32).astype(np.float64)
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def vec3(a):
    return mi.Vector3f(np.ascontiguousarray(a.T, dtype=np.float32))


def interaction(wi):
    si = dr.zeros(mi.SurfaceInteraction3f, len(wi))
    si.wi = vec3(wi)
    return si


def spectrum_np(v):
    """Mitsuba Color3f / Spectrum of width n -> float64 array (n, channels)."""
    return np.array(v, dtype=np.float64).T


@pytest.fixture
def variant(request):
    """Register the plugins in the variant ``request.param`` (indirect parametrisation;
    skipped where the build lacks it); set the suite's variant back afterwards."""
    if request.param not in mi.variants():
        pytest.skip(f"{request.param} not in this Mitsuba build")
    pm.register(request.param)
    try:
        yield request.param
    finally:
        mi.set_variant(VARIANT)


class LogCapture(mi.Appender):
    """Mitsuba's log lines as ``(level, text)`` (add it with ``mi.logger().add_appender``)."""

    def __init__(self):
        super().__init__()
        self.lines = []

    def append(self, level, text):
        self.lines.append((level, text))

    def log_progress(self, *args):
        pass
