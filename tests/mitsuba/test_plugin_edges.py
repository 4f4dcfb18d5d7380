"""The float32 plugin at the subnormal edge of issue 27: Ashikhmin-Shirley with
rs = 0 and rd = 1e-39, a float32 subnormal.  Fs + Ad was subnormal, 1/(Fs + Ad)
overflowed and the pdf was NaN.  Dr.Jit's worker threads (large batches) flush
subnormals to zero and the calling thread (small batches) did not, so a batch of
3 saw a diffuse lobe that a batch of 4096 did not; the plugin now flushes a
float32 subnormal parameter itself, and every batch computes with rd = 0."""

import numpy as np
import pytest
from mi_helpers import interaction, mi, to_dict, vec3

import plausible


@pytest.mark.parametrize("n", [3, 5000])
def test_ashikhmin_shirley_plugin_pdf_with_a_subnormal_diffuse_albedo_is_that_of_rd_0(n):
    b = mi.load_dict(to_dict("ashikhmin_shirley", dict(rs=0.0, rd=1e-39, nu=10.0, nv=10.0)))
    wi = np.tile([0.0, 0.0, 1.0], (3, 1))
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.3, -0.4, np.sqrt(0.75)]])
    wi, wo = np.tile(wi, (n // 3 + 1, 1))[:n], np.tile(wo, (n // 3 + 1, 1))[:n]
    pdf = np.array(b.pdf(mi.BSDFContext(), interaction(wi), vec3(wo)), dtype=np.float64)
    assert np.all(np.isfinite(pdf))
    # rd flushed to 0: at normal incidence Fs = 0 and Ad = 0, the specular lobe alone
    ref = plausible.make("ashikhmin-shirley", rs=0.0, rd=0.0, nu=10.0, nv=10.0).pdf(wi, wo)
    np.testing.assert_allclose(pdf, ref, rtol=1e-5)
    # and not the diffuse lobe cos/pi that an unflushed rd gives
    assert np.all(np.abs(pdf - wo[:, 2] / np.pi) > 1e-2)
