"""The plugins' ``sample()`` returns the ``wo`` whose density it computes, on every device (issue 42).

On an H200 (``cuda_ad_rgb``, ``../shared/gpu/fuzz_cuda.json``) the density that ``sample()``
returned differed from ``pdf()`` at the returned direction by up to 400x at grazing incidence
(ashikhmin_shirley default, cos(theta_i) = 1.1e-7: 98.4 against 39807), where LLVM agrees
bitwise.  The cause, reproduced below from the recorded rows to five digits: ``wo`` was
normalised as ``t * (1 / |t|)``, and the PTX assembler contracts that product into the sum
``wi + wo`` of the half vector (one ``fma``), so the sampling kernel saw the unrounded ``wo``
while ``pdf()`` sees the stored one.  At grazing incidence ``|wi + wo|`` is a few float32 units
of ``wo``, so half an ulp moves the half vector by tenths of a radian.

The check that needs no GPU: in the kernel that Dr.Jit traces for ``sample()``, no float value
that the kernel stores is a product that the same kernel also adds to something (on LLVM,
Dr.Jit emits no contraction; on CUDA ``mul.ftz.f32`` and ``add.ftz.f32`` carry no rounding
modifier, and ptxas may fuse them).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from mi_helpers import PLUGIN_MODELS, dr, mi, moderate, to_dict

from plausible import warps
from plausible.arrays.ops import NP


def contraction_hazards(ir: str) -> list:
    """Names of the float vectors that an LLVM kernel stores and that are ``fmul`` results also
    used by an ``fadd``/``fsub`` of the same kernel (a product a contracting compiler may use
    unrounded there, while the stored value is rounded)."""
    defs = dict(re.findall(r"^\s*(%\w+) = (\w+) ", ir, flags=re.M))
    stored = set(re.findall(r"^\s*store <\d+ x float> (%\w+),", ir, flags=re.M))
    summed = set()
    for a, b in re.findall(r"= f(?:add|sub) <\d+ x float> (%\w+), (%\w+)", ir):
        summed.update((a, b))
    return sorted(v for v in stored if defs.get(v) == "fmul" and v in summed)


def sample_kernel_ir(plugin: str, params: dict, n: int = 64) -> str:
    """The LLVM IR of the kernel that evaluates ``sample()``'s ``wo``, ``pdf`` and weight."""
    bsdf = mi.load_dict(to_dict(plugin, params))
    rng = np.random.default_rng(7)
    si = dr.zeros(mi.SurfaceInteraction3f, n)
    si.wi = mi.Vector3f(0.6, 0.0, 0.8)
    si.sh_frame = mi.Frame3f(mi.Vector3f(0, 0, 1))
    was = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    try:
        bs, w = bsdf.sample(mi.BSDFContext(), si, mi.Float(rng.random(n)),
                            mi.Point2f(mi.Float(rng.random(n)), mi.Float(rng.random(n))))
        dr.eval(bs.wo, bs.pdf, w)
        hist = [h for h in dr.kernel_history() if h["type"] == dr.KernelType.JIT]
    finally:
        dr.set_flag(dr.JitFlag.KernelHistory, was)
    return "\n".join(h["ir"].getvalue() for h in hist)


def test_the_checker_finds_a_stored_product_that_is_also_summed():
    """The hazard as the old ``sample()`` traced it (``wo = t * inv`` stored, then ``wi + wo``)."""
    bad = ("    %f345 = fmul <16 x float> %f318, %f344\n"
           "    store <16 x float> %f345, ptr %f345_p3, align 64\n"
           "    %f573 = fadd <16 x float> %f345, %f7\n")
    assert contraction_hazards(bad) == ["%f345"]
    good = bad.replace("fmul", "fdiv")
    assert contraction_hazards(good) == []
    assert contraction_hazards(bad.replace("%f573 = fadd <16 x float> %f345, %f7", "%f573 = fadd <16 x float> %f9, %f7")) == []


@pytest.mark.skipif(mi.variant() is None or not mi.variant().startswith("llvm"),
                    reason="reads the LLVM IR of the traced kernel")
@pytest.mark.parametrize("plugin", sorted(PLUGIN_MODELS))
def test_sample_stores_no_product_that_it_also_sums(plugin):
    ir = sample_kernel_ir(plugin, moderate(PLUGIN_MODELS[plugin]))
    assert "store <" in ir
    assert contraction_hazards(ir) == []


#: Rows of ``../shared/gpu/fuzz_cuda.json`` (ashikhmin_shirley at its defaults, nu = nv = 100, on
#: cuda_ad_rgb): wi, the stored wo, the density ``sample()`` returned and ``pdf()``'s.  With
#: ``u2 = 0`` the sampled half vector is the normal, so ``t = reflect(wi, n) = (-wi_x, -wi_y, wi_z)``.
CUDA_ROWS = [
    ((-0.6920873522758484, 0.7218137383460999, 1.1089190365964896e-07),
     (0.6920874118804932, -0.7218137979507446, 1.1089191787050368e-07), 98.39350891113281, 39807.10546875),
    ((-0.9248612523078918, 0.38030463457107544, 1.5410518017233699e-07),
     (0.9248613715171814, -0.3803046941757202, 1.541051943831917e-07), 22839.83203125, 4534.72900390625),
]


def _density(s):
    """The A-S (nu = nv = 100) density of ``wo`` at ``s = wi + wo`` (``wi.h = |s|/2``, journal eq. 8)."""
    s = np.asarray(s, dtype=np.float64)
    n = np.linalg.norm(s)
    return warps.anisotropic_half_vector_pdf(NP, 100.0, 100.0, tuple(s / n)) / (2.0 * n)


@pytest.mark.parametrize("wi, wo, pdf_sample, pdf_eval", CUDA_ROWS)
def test_the_cuda_disagreement_is_the_contracted_normalisation(wi, wo, pdf_sample, pdf_eval):
    """``pdf()`` is the density at the stored ``wo``; ``sample()``'s is the density at
    ``wi + t * inv`` rounded once (an fma), with ``inv`` the float32 ``1/|t|`` that rounds
    ``t * inv`` to the stored ``wo``: both reproduced to 1e-5."""
    wi = np.array(wi, np.float32).astype(np.float64)
    wo = np.array(wo, np.float32).astype(np.float64)
    t = np.array([-wi[0], -wi[1], wi[2]])
    inv = [float(np.float32(1.0 + k * 2.0 ** -23)) for k in (-1, 0, 1)]
    inv = [x for x in inv if np.array_equal((t * x).astype(np.float32).astype(np.float64), wo)]
    assert inv, "no float32 1/|t| rounds t * inv to the stored wo"
    assert _density(wi + wo) == pytest.approx(pdf_eval, rel=1e-5)
    fused = (wi + t * inv[0]).astype(np.float32).astype(np.float64)     # one rounding
    assert _density(fused) == pytest.approx(pdf_sample, rel=1e-5)
    assert not np.isclose(pdf_sample, pdf_eval, rtol=0.5)
