"""Which Mitsuba families a source is fitted with (``plausible.conversion.mitsuba.candidates``):
by the albedo its lobes declare diffuse and the rest, at normal incidence (no Mitsuba needed)."""

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
