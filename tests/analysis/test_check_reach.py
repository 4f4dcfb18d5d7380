"""Issue 45, item 7: the verifier's blind spot said plainly.  ``check``'s report states
which directions it examined and what it cannot see; a narrow lobe (1e-3 rad, albedo 0.1)
away from every hint and never drawn by the sampler passes, and the report's statement of
reach excludes it, while a lobe wider than the stated limit is caught."""

import math

import numpy as np
import pytest

from plausible.analysis import check
from plausible.analysis.adapters import CallableBxDF
from plausible.warps import cosine_hemisphere, cosine_hemisphere_pdf
from plausible.arrays.ops import NP

#: the lobe's axis: 40 degrees from the normal, azimuth 130 (no incidence's mirror direction)
D0 = np.array([math.sin(math.radians(40)) * math.cos(math.radians(130)),
               math.sin(math.radians(40)) * math.sin(math.radians(130)), math.cos(math.radians(40))])


def _lambert_and_lobe(width, lobe_albedo=0.1, rd=0.95):
    """``rd / pi`` plus a reciprocal Gaussian lobe about :data:`D0`, ``c (K(wi) + K(wo))``
    with ``K(w) = exp(-(1 - w.D0) / width^2)`` (angular width ``width``), ``c`` such that
    ``c int K cos d omega = lobe_albedo`` (``2 pi width^2 cos(40 deg)`` for a narrow lobe);
    sampled as the Lambertian (the sampler never draws the lobe).  Albedo ``rd + lobe_albedo``
    = 1.05 away from ``D0``: it gains energy."""
    c = lobe_albedo / (2 * math.pi * width ** 2 * D0[2])

    def f(wi, wo):
        return rd / math.pi + c * (np.exp(-(1.0 - wi @ D0) / width ** 2) + np.exp(-(1.0 - wo @ D0) / width ** 2))

    def pdf(wi, wo):
        return cosine_hemisphere_pdf(NP, wo.T)

    def sample(wi, u):
        return np.stack(cosine_hemisphere(NP, u[:, 1], u[:, 2]), axis=-1)

    return CallableBxDF(f, pdf, sample, name=f"lambert+lobe{width:g}")


def test_a_narrow_lobe_away_from_the_hints_passes_and_the_report_says_it_cannot_see_it():
    rep = check(_lambert_and_lobe(1e-3), quick=True)
    assert rep["energy"].passed and rep["reciprocity"].passed        # the blind spot: 1.05 unseen
    reach = rep.reach
    assert reach["blind_rad"] > 1e-3                                  # the lobe is narrower than the stated limit
    for h in reach["hints_at"]["directions"]:                         # and no hint points at it
        assert math.acos(min(1.0, float(np.dot(h, D0)))) > reach["blind_rad"]
    assert "not seen: a lobe narrower than" in reach["text"] and "reach: " in str(rep)
    assert rep.to_dict()["reach"]["blind_rad"] == reach["blind_rad"]


def test_a_lobe_wider_than_the_stated_limit_is_caught():
    rep = check(_lambert_and_lobe(0.15), quick=True)
    assert rep.reach["blind_rad"] < 0.15
    assert not rep["energy"].passed and rep["energy"].figure > 1.02
