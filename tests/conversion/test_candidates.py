"""Which Mitsuba families a source is fitted with (``plausible.conversion.mitsuba.candidates``):
by the albedo its lobes declare diffuse and the rest, at normal incidence and over the incidences
(a Fresnel rise; no Mitsuba needed)."""

import numpy as np
import pytest

import plausible
from plausible.conversion import read_sources


@pytest.mark.parametrize("spec, families", [
    ("lambertian:rd=0.5", ["diffuse"]),
    ("reciprocal-blinn:ks=0.6:n=20", ["roughconductor"]),
    ("lambertian:rd=0.5 + reciprocal-blinn:ks=0.03:n=20", ["diffuse", "blendbsdf", "roughplastic", "principled"]),
    ("lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=20", ["diffuse", "blendbsdf", "principled"]),
    ("lambertian:rd=0.5 + reciprocal-blinn:ks=0.03,0.01,0.01:n=20", ["diffuse", "blendbsdf", "principled"]),
])
def test_the_candidate_families_follow_the_declared_diffuse_and_specular_albedos(spec, families):
    from plausible.conversion.mitsuba import candidates

    m = read_sources(spec)[0].model
    assert candidates(m, plausible.albedo(m, [0, 0, 1]).value)[0] == families


@pytest.mark.parametrize("spec, families", [
    # Schlick's Fresnel of a dielectric, no diffuse: the albedo rises (0.05 to 0.2 at 80 degrees)
    ("cook-torrance:m=0.05:fresnel=schlick:rs=0.05", ["roughconductor", "roughplastic", "principled"]),
    # the same lobe without Fresnel stays flat: roughconductor alone
    ("cook-torrance:m=0.05:fresnel=none:rs=0.5", ["roughconductor"]),
    # a specular part below 0.01 at normal incidence that rises at grazing: not a diffuse alone
    ("lambertian:rd=0.3 + cook-torrance:m=0.2:fresnel=schlick:rs=0.004",
     ["diffuse", "blendbsdf", "roughplastic", "principled"]),
])
def test_a_fresnel_rise_over_the_incidences_adds_the_families_with_fresnel(spec, families):
    from plausible.analysis import albedo_curve
    from plausible.conversion import CONSERVE_THETAS
    from plausible.conversion.mitsuba import RISE, candidates

    m = read_sources(spec)[0].model
    a = np.asarray(albedo_curve(m, thetas_deg=CONSERVE_THETAS).value).reshape(len(CONSERVE_THETAS), -1)
    assert candidates(m, a)[0] == families
    # at normal incidence alone the rise is unseen (what the rule was before)
    assert (float(np.max(a - a[0])) > RISE) == (candidates(m, a[0])[0] != families)


@pytest.mark.parametrize("spec, falls", [
    # the reciprocal Blinn lobe falls as about cos^2 (0.60 at 0 degrees, 0.08 at 75 for n = 30)
    ("reciprocal-blinn:ks=0.6:n=30", True),
    # Ward's original 1 / sqrt(ci co): about rs cos(theta), 0.66 to 0.18
    ("ward:alpha_x=0.15:rs=0.7", True),
    ("lambertian:rd=0.5 + reciprocal-blinn:ks=0.3:n=20", True),
    # flat to 75 degrees; 0.03 lower at 85 by masking, beyond the band's incidences
    ("cook-torrance:m=0.05:fresnel=none:rs=0.5", False),
    ("lambertian:rd=0.5", False),
])
def test_an_albedo_falling_over_the_bands_incidences_adds_the_family_that_falls(spec, falls):
    from plausible.analysis import albedo_curve
    from plausible.conversion import CONSERVE_THETAS
    from plausible.conversion.mitsuba import FALL, candidates

    m = read_sources(spec)[0].model
    a = np.asarray(albedo_curve(m, thetas_deg=CONSERVE_THETAS).value).reshape(len(CONSERVE_THETAS), -1)
    upto = np.asarray(CONSERVE_THETAS) <= 75.0
    assert (float(np.max(a[0] - a[upto])) > FALL) == falls
    fams, why = candidates(m, a)
    assert ("blendbsdf-tir" in fams) == falls and (("falling by" in why) == falls)
    # the families the rule gave before are all still there, in their order (none of these rises)
    assert [f for f in fams if f != "blendbsdf-tir"] == candidates(m, a[0])[0]
