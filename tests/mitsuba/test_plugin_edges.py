"""The float32 plugin at the subnormal edge of issue 27: Ashikhmin-Shirley with
rs = 0 and rd = 1e-39, a float32 subnormal.  In a small batch (the scalar code
path, which keeps subnormals; a batch of 4096 flushes them) Fs + Ad was
subnormal, 1/(Fs + Ad) overflowed and the pdf was NaN."""

import numpy as np
from mi_helpers import interaction, mi, to_dict, vec3


def test_ashikhmin_shirley_plugin_pdf_with_a_subnormal_diffuse_albedo_is_the_diffuse_lobe():
    b = mi.load_dict(to_dict("ashikhmin_shirley", dict(rs=0.0, rd=1e-39, nu=10.0, nv=10.0)))
    wi = np.tile([0.0, 0.0, 1.0], (3, 1))
    wo = np.array([[0.0, 0.0, 1.0], [0.6, 0.0, 0.8], [0.3, -0.4, np.sqrt(0.75)]])
    pdf = np.array(b.pdf(mi.BSDFContext(), interaction(wi), vec3(wo)), dtype=np.float64)
    # at normal incidence Fs = 0 for rs = 0: for any rd > 0 the diffuse lobe alone, cos / pi
    np.testing.assert_allclose(pdf, wo[:, 2] / np.pi, rtol=1e-5)
