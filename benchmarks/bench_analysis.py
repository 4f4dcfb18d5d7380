"""Analysis on the NumPy backend: a 90-angle albedo curve, ``plausible check``
(quick) of one model, one fit.  Peak memory by tracemalloc (one extra call)."""

from __future__ import annotations


import numpy as np
import pytest

import plausible
from conftest import record, traced_peak

AS = dict(nu=10.0, nv=100.0, rs=0.05, rd=0.5)   # anisotropic: the harder albedo integral


@pytest.mark.parametrize("name,params", [("ashikhmin-shirley", AS), ("ward", {}),
                                         ("modified-phong", {})],
                         ids=["ashikhmin-shirley", "ward", "modified-phong"])
def test_albedo_curve_90(benchmark, name, params):
    """Directional albedo at 90 incidence angles in [0, 89] degrees (default
    tolerance); ``max_error`` is the curve's largest error bound (target 1e-4)."""
    m = plausible.make(name, **params)
    thetas = np.radians(np.linspace(0.0, 89.0, 90))
    res = plausible.albedo_curve(m, thetas)
    record(benchmark, "analysis", f"albedo curve, 90 angles ({name})", backend="numpy", op="albedo",
           n=90, max_error=float(np.max(res.error)), peak_bytes=traced_peak(lambda: plausible.albedo_curve(m, thetas)))
    benchmark.pedantic(lambda: plausible.albedo_curve(m, thetas), rounds=2, iterations=1)


def test_check_quick(benchmark):
    """``plausible.check(model, quick=True)`` of Ashikhmin-Shirley (anisotropic)."""
    m = plausible.make("ashikhmin-shirley", **AS)
    rep = plausible.check(m, quick=True)
    record(benchmark, "analysis", "check --quick (ashikhmin-shirley)", backend="numpy", op="check", n=1,
           agrees=bool(rep.as_claimed) if hasattr(rep, "as_claimed") else None,
           peak_bytes=traced_peak(lambda: plausible.check(m, quick=True)))
    benchmark.pedantic(lambda: plausible.check(m, quick=True), rounds=2, iterations=1)


def test_fit_one(benchmark):
    """One fit: isotropic Ashikhmin-Shirley (specular term) to Ward (alpha 0.2),
    l2-cos metric, one optimiser start."""
    fitting = pytest.importorskip("plausible.fitting", reason="plausible.fit not available")
    if not hasattr(fitting, "fit"):
        pytest.skip("plausible.fitting.fit not available")

    def run():
        return fitting.fit("ashikhmin-shirley-specular", "ward:alpha_x=0.2:alpha_y=0.2:rd=0:rs=0.5",
                           metric="l2-cos", starts=1, seed=0)

    res = run()
    record(benchmark, "analysis", "fit (ashikhmin-shirley-specular to ward, 1 start)", backend="numpy",
           op="fit", n=1, peak_bytes=traced_peak(run),
           result=str(getattr(res, "params", "")))
    benchmark.pedantic(run, rounds=2, iterations=1)


