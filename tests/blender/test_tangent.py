"""Tangent-resolved acquisition in Cycles (docs/blender.md, "Anisotropic materials"): the tangent
convention against a closed form at two rotations, reciprocity at the same tangent frame, the albedo
over the whole hemisphere, and the checkers fed broken inputs."""

import math

import numpy as np
import pytest

from plausible import registry
from plausible.blender import check_acquisition, material_spec
from plausible.blender.principled import principled_inputs
from plausible.blender.tangent import (_assemble, acquire_tangent, check_isotropy, check_model, pole_rotation,
                                       turned)
from plausible.integrals.albedo import albedo_curve

RD = [0.2, 0.5, 0.9]
SMALL = dict(angles=(0, 40, 80), turns=(0, 45, 90, 135), resolution=48)


def _ggx(rotation):
    """Anisotropic single-scatter GGX, F = 1 (white metal): plausible's glTF model, the closed form."""
    return registry.make("gltf-pbr", base_color=[1, 1, 1], metallic=1.0, roughness=0.5, anisotropy_strength=0.6,
                         anisotropy_rotation=rotation)


@pytest.fixture(scope="module")
def diffuse(blender):
    return acquire_tangent(material_spec(diffuse=RD), spp=16, **SMALL)


@pytest.fixture(scope="module")
def eighth(blender):
    """Principled BSDF, GGX, anisotropic, its tangent turned an eighth of a turn (0.125)."""
    inputs = principled_inputs(_ggx(math.pi / 4).params)
    assert inputs["Anisotropic Rotation"] == pytest.approx(0.125)
    return acquire_tangent(material_spec(principled=inputs), spp=32, **SMALL)


def test_the_spheres_pole_is_turned_into_the_image_plane_at_beta():
    for beta in (0.0, 30.0, 90.0):
        q = pole_rotation(beta)
        assert np.allclose(q @ q.T, np.eye(3)) and np.linalg.det(q) == pytest.approx(1.0)
        b = math.radians(beta)
        assert np.allclose(q[:, 2], [-math.sin(b), math.cos(b), 0.0])


def test_a_diffuse_bsdf_reads_rd_over_pi_in_the_tangent_frame(diffuse):
    assert check_model(diffuse, registry.make("lambertian", rd=RD), tol=2e-3).passed


def test_a_diffuse_bsdfs_table_is_flat_in_phi_and_an_anisotropic_ones_is_not(diffuse, eighth):
    assert check_isotropy(diffuse).passed
    r = check_isotropy(eighth)
    assert not r.passed and r.figure > 0.3


def test_cycles_anisotropic_principled_is_the_ggx_closed_form_at_its_rotation(eighth):
    # the tangent Cycles uses is the radial one of the turned sphere, Anisotropic Rotation turns it
    # counter-clockwise about n (toward n x t), and roughness/anisotropic map as principled_inputs says
    assert check_model(eighth, _ggx(math.pi / 4), tol=0.01).passed


def test_a_wrong_tangent_or_rotation_sign_fails_the_closed_form(eighth):
    assert not check_model(turned(eighth, 45.0), _ggx(math.pi / 4)).passed      # a tangent field turned 45 deg
    assert not check_model(eighth, _ggx(3 * math.pi / 4)).passed                # the rotation's sign mirrored
    assert not check_model(eighth, _ggx(0.0)).passed                            # the rotation ignored


def test_a_quarter_turn_of_the_material_is_a_quarter_turn_of_the_frame(blender, eighth):
    # the same symmetry measured on a second acquisition: the tangent rotated by 0.375 turns in Cycles,
    # read in frames turned by 90 degrees, is the 0.125-turn material
    inputs = dict(principled_inputs(_ggx(math.pi / 4).params), **{"Anisotropic Rotation": 0.375})
    acq = acquire_tangent(material_spec(principled=inputs), spp=32, **dict(SMALL, turns=(0, 90)))
    assert check_model(turned(acq, 90.0), _ggx(math.pi / 4), tol=0.01).passed
    assert not check_model(acq, _ggx(math.pi / 4)).passed


def test_reciprocity_of_an_anisotropic_ggx_is_checked_at_the_same_frame(eighth):
    r = check_acquisition(eighth)["reciprocity"]
    assert r.passed and not r.unresolved and r.details["pairs"] >= 100


def test_a_swapped_partner_at_another_tangent_fails_reciprocity(eighth):
    # broken input: each swapped partner taken from the render of the sphere turned 90 degrees further
    imgs, per_turn = list(eighth.raw["imgs"]), 2 * len(eighth.angles)
    broken = list(imgs)
    for i in range(len(eighth.turns)):
        for k in range(len(eighth.angles)):
            j = (i + 2) % len(eighth.turns)
            broken[2 + i * per_turn + 2 * k] = imgs[2 + j * per_turn + 2 * k]
    acq = _assemble("broken", broken, eighth.angles, eighth.turns, eighth.resolution, eighth.spp, 0.0)
    r = check_acquisition(acq)["reciprocity"]
    assert not r.passed and not r.unresolved


def test_the_furnace_gives_the_albedo_over_the_whole_hemisphere(eighth):
    m = _ggx(math.pi / 4)
    ref = np.array([np.asarray(albedo_curve(m, thetas=[t], phi=p).value).reshape(-1)
                    for t, p in zip(eighth.albedo_theta, np.nan_to_num(eighth.albedo_phi))])
    assert np.all(np.abs(eighth.albedo - ref) <= 0.01 + 3 * eighth.albedo_stderr)
    rep = check_acquisition(eighth)["energy"]
    assert rep.passed and "phi_deg" in rep.worst


class TestArguments:
    @pytest.mark.parametrize("kw, name", [(dict(resolution=8), "resolution"), (dict(spp=0), "spp"),
                                          (dict(angles=(190,)), "angles"), (dict(turns=(180,)), "turns")])
    def test_out_of_range_is_refused_naming_the_argument(self, kw, name):
        with pytest.raises(ValueError, match=name):
            acquire_tangent(material_spec(diffuse=0.5), **kw)

    @pytest.mark.parametrize("check", [check_model, check_isotropy])
    def test_a_tolerance_outside_0_1_is_refused(self, diffuse, check):
        args = (diffuse, registry.make("lambertian", rd=RD)) if check is check_model else (diffuse,)
        with pytest.raises(ValueError, match=r"tol must be in \(0, 1\)"):
            check(*args, tol=1.5)

    def test_a_tangent_resolved_acquisition_is_not_a_merl_table(self, diffuse):
        with pytest.raises(NotImplementedError, match="anisotropic"):
            diffuse.brdf()


def test_the_uv_map_tangent_of_a_written_material_is_the_field_the_acquisition_assumes(blender, tmp_path):
    # convert --to blender writes an anisotropic metal with a Tangent node of the UV map: the worker's
    # sphere has u along the azimuth about its pole, the same field as Cycles' default radial tangent
    from plausible.blender.principled import blender_material, write_blender

    m = _ggx(math.pi / 4)
    write_blender({"m": blender_material(m.params)}, tmp_path / "m.py")
    acq = acquire_tangent(material_spec(script=str(tmp_path / "m.py")), spp=16, **dict(SMALL, turns=(0, 90)))
    assert check_model(acq, m, tol=0.01).passed
    assert not check_model(turned(acq, 45.0), m).passed


class TestCheckCommand:
    def test_check_blender_tangent_checks_an_anisotropic_materials_reciprocity(self, blender, tmp_path):
        import json

        from click.testing import CliRunner

        from plausible.blender.principled import blender_material, write_blender
        from plausible.cli import main

        write_blender({"brushed": blender_material(_ggx(math.pi / 4).params)}, tmp_path / "b.blend")
        r = CliRunner().invoke(main, ["check", "--blender", str(tmp_path / "b.blend"), "--material", "brushed",
                                      "--tangent", "--quick", "--json"])
        rep = json.loads(r.stdout)
        assert r.exit_code == 0 and rep["passed"], r.output
        recip = rep["results"][0]
        assert recip["passed"] and recip["details"]["pairs"] >= 100

    def test_tangent_without_blender_exits_2(self):
        from click.testing import CliRunner

        from plausible.cli import main

        r = CliRunner().invoke(main, ["check", "lambertian", "--tangent"])
        assert r.exit_code == 2 and "--tangent chooses the acquisition of --blender" in r.output
