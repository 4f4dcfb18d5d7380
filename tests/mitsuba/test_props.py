"""The plugin machinery's parts, tested alone: the parser of ';'-separated
groups, name resolution, flags from the models' declared lobes, variant set-up."""

from __future__ import annotations

import pytest

from mi_helpers import mi

import plausible
import plausible.bxdf
import plausible.mitsuba as pm
from plausible.mitsuba import plugin as PL
from plausible.mitsuba import props as P
from plausible.params import format_groups, parse_groups, parse_value

pytestmark = pytest.mark.drjit


def test_parse_groups_reads_spaces_commas_and_semicolons():
    assert parse_groups("-1 -1 1 20 1.75; 1,1,1,5,0.1;") == [[-1, -1, 1, 20, 1.75], [1, 1, 1, 5, 0.1]]
    assert parse_groups(format_groups([(0.1, 2.0), (3.0, -4.5)])) == [[0.1, 2.0], [3.0, -4.5]]
    assert parse_value("-1,-1,1,20,1.5;1,1,1,8,0.3") == [[-1, -1, 1, 20, 1.5], [1, 1, 1, 8, 0.3]]


def test_parse_groups_names_a_bad_group():
    with pytest.raises(ValueError, match="got 'a b' in '1 2; a b'"):
        parse_groups("1 2; a b")


def test_given_names_resolves_aliases_and_refuses_unknown_names_and_repeats():
    info = plausible.info("modified-phong")
    alias = P.aliases_for("phong", info)
    assert P.given_names("phong", info, ["exponent", "kd"], alias) == {"n": "exponent", "kd": "kd"}
    with pytest.raises(ValueError, match="unknown parameter 'roughness'; allowed: kd, ks, n, "):
        P.given_names("phong", info, ["roughness"], alias)
    with pytest.raises(ValueError, match="'kd' given twice"):
        P.given_names("phong", info, ["kd", "diffuse_reflectance"], alias)


@pytest.mark.parametrize("name,diffuse,glossy", [
    ("lambertian", True, False), ("ashikhmin-shirley-diffuse", True, False),
    ("modified-phong", True, True), ("ward", True, True), ("cook-torrance", False, True),
    ("reciprocal-phong", False, True)])
def test_flags_follow_the_declared_lobes(name, diffuse, glossy):
    model = plausible.make(name)
    flags, components, sampled = PL.bsdf_flags(mi, model, model.info, varying=False)
    F = mi.BSDFFlags
    assert bool(flags & F.DiffuseReflection) == diffuse and bool(flags & F.GlossyReflection) == glossy
    # one component per lobe, each of one kind: glossy first where both exist
    want = ([F.GlossyReflection] if glossy else []) + ([F.DiffuseReflection] if diffuse else [])
    assert sampled == want
    assert [c & (F.DiffuseReflection | F.GlossyReflection) for c in components] == want


def test_flags_change_with_the_declaration_not_the_name():
    """A Lambertian whose lobe is declared glossy is flagged glossy (the name is not
    read); one that declares no lobes is flagged from its LOBES."""
    info = plausible.info("lambertian")

    class Declared(info.cls):
        def lobes(self):
            return (super().lobes()[0]._replace(kind="glossy"),)

    class Undeclared(info.cls):
        LOBES = frozenset({"glossy"})
        lobes = plausible.bxdf.BxDF.lobes

    for cls in (Declared, Undeclared):
        flags, _, _ = PL.bsdf_flags(mi, cls(), info, varying=False)
        assert flags & mi.BSDFFlags.GlossyReflection and not flags & mi.BSDFFlags.DiffuseReflection


def test_no_variant_error_names_each_reason(monkeypatch):
    def refuse(v):
        raise ImportError(f"no {v} here")

    monkeypatch.setattr(mi, "variant", lambda: None)
    monkeypatch.setattr(mi, "set_variant", refuse)
    with pytest.raises(RuntimeError, match="llvm_ad_rgb: ImportError: no llvm_ad_rgb here; "
                                           "scalar_rgb: ImportError: no scalar_rgb here"):
        pm.ensure_variant()


def test_plugins_load_and_evaluate_in_a_scalar_variant():
    """scalar_rgb (one value per call, Python floats): eval equals the NumPy model;
    mi.traverse holds no Python floats (Mitsuba cannot write them)."""
    import numpy as np

    before = mi.variant()
    try:
        pm.register("scalar_rgb")
        b = mi.load_dict({"type": "ashikhmin_shirley", "nu": 20.0, "nv": 50.0})
        si = mi.SurfaceInteraction3f()
        wi, wo = np.array([0.3, 0.1, 0.9]), np.array([-0.2, -0.15, 0.8])
        wi, wo = wi / np.linalg.norm(wi), wo / np.linalg.norm(wo)
        si.wi = mi.Vector3f(*wi)
        got = np.array(b.eval(mi.BSDFContext(), si, mi.Vector3f(*wo)))
        want = plausible.make("ashikhmin-shirley", nu=20.0, nv=50.0).eval(wo, wi) * wo[2]
        np.testing.assert_allclose(got, want, rtol=1e-5)
        assert len(mi.traverse(b)) == 0
    finally:
        mi.set_variant(before)
