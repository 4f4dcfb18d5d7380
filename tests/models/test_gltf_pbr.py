"""glTF 2.0 metallic-roughness (+ KHR_materials_specular, KHR_materials_anisotropy):
values against the specification's formulas written again here with angles, closed-form
albedos, reciprocity, energy, the sampler (chi-square), Dr.Jit, bad input."""

import math
import re

import numpy as np
import pytest

from reference import (check_drjit, check_reciprocal, check_sampling, chi2_sampler_pvalue,
                       from_angles, hemisphere_rule, quad_albedo)

import plausible
from plausible import warps
from plausible.arrays.ops import NP


def gltf(**kw):
    return plausible.make("gltf-pbr", **kw)


def spec_appendix_b(wi, wo, base, metallic, roughness, separable=False):
    """glTF 2.0 Appendix B "Metal BRDF and Dielectric BRDF", full code, written with
    N.L, N.V, N.H, V.H of unit vectors (independent of the model's frame code);
    ``separable``: the separable Smith G of earlier drafts instead (a wrong model)."""
    n = np.array([0.0, 0.0, 1.0])
    h = (wi + wo) / np.linalg.norm(wi + wo)
    nl, nv, nh, vh = wi @ n, wo @ n, h @ n, wo @ h
    a = roughness ** 2
    d = a * a / (math.pi * (nh * nh * (a * a - 1) + 1) ** 2)
    g = 2 * nl * nv / (nv * math.sqrt(a * a + (1 - a * a) * nl * nl) + nl * math.sqrt(a * a + (1 - a * a) * nv * nv))
    if separable:
        g1 = lambda c: 2 * c / (c + math.sqrt(a * a + (1 - a * a) * c * c))
        g = g1(nl) * g1(nv)
    specular = d * g / (4 * nv * nl)
    fw = (1 - abs(vh)) ** 5
    diffuse = base / math.pi
    dielectric_fresnel = 0.04 + (1 - 0.04) * fw
    dielectric = diffuse * (1 - dielectric_fresnel) + specular * dielectric_fresnel   # mix(a, b, t)
    metal = (base + (1 - base) * fw) * specular
    return dielectric * (1 - metallic) + metal * metallic


PAIRS = [((0.0, 0.0), (30.0, 180.0)), ((20.0, 0.0), (20.0, 180.0)), ((60.0, 10.0), (45.0, 250.0)),
         ((80.0, 0.0), (85.0, 90.0)), ((5.0, 40.0), (70.0, 300.0))]


@pytest.mark.parametrize("base,metallic,roughness", [(0.8, 0.0, 0.5), (0.3, 1.0, 0.2), (0.6, 0.4, 0.9)])
@pytest.mark.parametrize("a,b", PAIRS)
def test_value_is_the_specifications_appendix_b(base, metallic, roughness, a, b):
    wi, wo = from_angles(*a), from_angles(*b)
    m = gltf(base_color=base, metallic=metallic, roughness=roughness)
    assert m.eval(wi, wo) == pytest.approx(spec_appendix_b(wi, wo, base, metallic, roughness), rel=1e-12)


def test_a_wrong_formula_is_told_apart():
    # the comparison can fail: the separable Smith G differs by 0.4 % here, 4e9 times the tolerance
    wi, wo = from_angles(70.0), from_angles(60.0, 180.0)
    got = gltf(base_color=0.8, roughness=0.5).eval(wi, wo)
    wrong = spec_appendix_b(wi, wo, 0.8, 0.0, 0.5, separable=True)
    assert got != pytest.approx(wrong, rel=1e-3)


def test_anisotropic_value_is_the_extensions_formula():
    # KHR_materials_anisotropy: D_GGX_anisotropic and V_GGX_anisotropic of its sample code (without
    # the clamp of V to 1, which never binds here), with t rotated counter-clockwise from the tangent
    strength, rot, rough = 0.7, 0.6, 0.4
    m = gltf(base_color=0.5, metallic=1.0, roughness=rough, anisotropy_strength=strength, anisotropy_rotation=rot)
    at = (rough ** 2) * (1 - strength ** 2) + strength ** 2
    ab = rough ** 2
    t = np.array([math.cos(rot), math.sin(rot), 0.0])
    b = np.cross([0.0, 0.0, 1.0], t)
    for wi, wo in [(from_angles(40, 20), from_angles(50, 230)), (from_angles(10, 100), from_angles(75, 0))]:
        h = (wi + wo) / np.linalg.norm(wi + wo)
        a2 = at * ab
        f = np.array([ab * (t @ h), at * (b @ h), a2 * h[2]])
        w2 = a2 / (f @ f)
        d = a2 * w2 * w2 / math.pi
        v = 0.5 / (wi[2] * np.linalg.norm([at * (t @ wo), ab * (b @ wo), wo[2]])
                   + wo[2] * np.linalg.norm([at * (t @ wi), ab * (b @ wi), wi[2]]))
        fres = 0.5 + 0.5 * (1 - wo @ h) ** 5
        assert m.eval(wi, wo) == pytest.approx(fres * v * d, rel=1e-12)


def test_anisotropy_limits():
    iso = gltf(roughness=0.3)
    wi, wo = from_angles(35, 10), from_angles(60, 200)
    # strength 0 is isotropic whatever the rotation; a half turn changes nothing (D is even)
    assert gltf(roughness=0.3, anisotropy_rotation=1.1).eval(wi, wo) == pytest.approx(iso.eval(wi, wo), rel=1e-13)
    a = gltf(roughness=0.3, anisotropy_strength=0.6, anisotropy_rotation=0.4)
    b = gltf(roughness=0.3, anisotropy_strength=0.6, anisotropy_rotation=0.4 + math.pi / 2)
    # a quarter turn swaps the alphas: the same as wi, wo turned back by a quarter turn
    turn = lambda w: np.array([w[1], -w[0], w[2]])
    assert a.eval(turn(wi), turn(wo)) == pytest.approx(b.eval(wi, wo), rel=1e-12)
    assert abs(a.eval(wi, wo) / iso.eval(wi, wo) - 1) > 0.05


def test_specular_zero_is_lambert():
    # KHR_materials_specular: specular = 0 gives f0 = f90 = 0, a pure diffuse material
    m = gltf(base_color=[0.7, 0.5, 0.2], specular=0.0, roughness=0.2)
    dirs, _ = hemisphere_rule(6, 7)
    np.testing.assert_allclose(m.eval(from_angles(50, 30), dirs), np.tile([0.7, 0.5, 0.2], (len(dirs), 1)) / math.pi,
                               rtol=1e-14)


def test_specular_color_weights_the_diffuse_by_the_largest_channel():
    # fresnel_mix of KHR_materials_specular: layer weighted by F (per channel), base by 1 - max_value(F)
    sc, s, base = np.array([2.0, 0.5, 1.0]), 0.8, np.array([0.6, 0.6, 0.6])
    m = gltf(base_color=base, specular=s, specular_color=sc, roughness=0.5)
    wi, wo = from_angles(30, 0), from_angles(55, 160)
    h = (wi + wo) / np.linalg.norm(wi + wo)
    fw = (1 - wo @ h) ** 5
    f0 = np.minimum(0.04 * sc, 1) * s
    F = f0 + (s - f0) * fw
    spec = gltf(base_color=0.0, metallic=1.0, roughness=0.5).eval(wi, wo) / fw   # Vis D (F = w for base 0)
    expect = F * spec + (1 - F.max()) * base / math.pi
    np.testing.assert_allclose(m.eval(wi, wo), expect, rtol=1e-12)


# -- closed-form albedos ----------------------------------------------------------------

def test_rough_white_metal_at_normal_incidence_reflects_one_minus_ln2():
    # alpha = 1: D = 1/pi, |w~| = 1, Vis = 1 / (2 (1 + cos_o)) at wi = n, so the albedo is
    # int_0^1 mu / (1 + mu) d mu = 1 - ln 2 (single scattering loses the rest)
    m = gltf(base_color=1.0, metallic=1.0, roughness=1.0)
    assert quad_albedo(m, np.array([0.0, 0.0, 1.0]), nmu=64, nphi=4) == pytest.approx(1 - math.log(2), abs=1e-12)


def test_ggx_distribution_is_normalised_against_cos():
    mu, w = hemisphere_rule(400, 400)
    for ax, ay in [(0.3, 0.3), (0.8, 0.2), (0.05, 0.05)]:
        d = warps.ggx_d(NP, (mu[:, 0], mu[:, 1], mu[:, 2]), ax, ay)
        assert np.sum(d * mu[:, 2] * w) == pytest.approx(1.0, abs=1e-10)


# -- energy -----------------------------------------------------------------------------

@pytest.mark.parametrize("roughness", [0.1, 0.5, 1.0])
def test_metal_albedo_stays_below_one(roughness):
    m = gltf(base_color=1.0, metallic=1.0, roughness=roughness)
    for t in (0.0, 45.0, 75.0, 89.0):
        assert plausible.albedo(m, from_angles(t)).value <= 1.0 + 1e-6


def test_white_dielectric_reflects_more_than_it_receives_at_grazing():
    # the specification's own warning (fresnel_mix "breaks ... energy conservation"), measured:
    # 1.20 at 75 degrees, 1.35 at 80 (the registry says energy_conserving=False)
    m = gltf(base_color=1.0, roughness=0.1)
    assert plausible.albedo(m, from_angles(0.0)).value == pytest.approx(1.0, abs=1e-3)
    assert plausible.albedo(m, from_angles(80.0)).value == pytest.approx(1.350, abs=2e-3)
    assert m.info.reciprocal and not m.info.energy_conserving
    assert not plausible.check(m, quick=True)["energy"].passed


# -- sampling ---------------------------------------------------------------------------

SAMPLED = [dict(), dict(metallic=1.0, roughness=0.2), dict(base_color=[0.9, 0.4, 0.1], roughness=0.7,
                                                         metallic=0.3, specular_color=[1.0, 3.0, 0.5]),
           dict(metallic=1.0, roughness=0.3, anisotropy_strength=0.8, anisotropy_rotation=0.9)]


@pytest.mark.parametrize("kw", SAMPLED)
def test_reciprocity_and_sampling_consistency(kw):
    m = gltf(**kw)
    check_reciprocal(m)
    for wi in ([0.0, 0.0, 1.0], [0.6, 0.2, 0.5], [0.99, 0.0, 0.05]):
        check_sampling(m, wi)


@pytest.mark.parametrize("kw", SAMPLED)
@pytest.mark.parametrize("theta", [10.0, 70.0])
def test_chi_square_of_the_sampler(kw, theta):
    assert chi2_sampler_pvalue(gltf(**kw), from_angles(theta, 30.0), n=50_000, sub=40) > 1e-3


def test_chi_square_rejects_a_sampler_of_another_roughness():
    class Wrong(type(gltf())):
        def _pdf(self, ops, wi, wo, q):
            return warps.ggx_visible_reflected_pdf(ops, wi, wo, 0.2, 0.2)

        def _sample(self, ops, wi, u, q):
            return plausible.vec.reflect(wi, warps.ggx_visible_half_vector(ops, wi, 0.3, 0.3, u[1], u[2]))
    assert chi2_sampler_pvalue(Wrong(metallic=1.0), from_angles(30.0), n=50_000) < 1e-6


def test_visible_normal_pdf_integrates_to_the_mass_reflected_above_the_horizon():
    # at normal incidence the visible normals are D cos, and h beyond 45 degrees reflects below the
    # horizon: GGX's P(tan^2 theta_h <= T) = T / (alpha^2 + T) gives int pdf = 1 / (1 + alpha^2)
    dirs, w = hemisphere_rule(300, 300)
    c = (dirs[:, 0], dirs[:, 1], dirs[:, 2])
    for a in (0.1, 0.5):
        total = np.sum(warps.ggx_visible_reflected_pdf(NP, (0.0, 0.0, 1.0), c, a, a) * w)
        assert total == pytest.approx(1.0 / (1.0 + a * a), abs=1e-9)
    for t, ax, ay in [(60.0, 0.5, 0.2), (85.0, 0.3, 0.3)]:
        total = np.sum(warps.ggx_visible_reflected_pdf(NP, tuple(from_angles(t, 20.0)), c, ax, ay) * w)
        assert 0.5 < total <= 1.0 + 1e-6


@pytest.mark.parametrize("kw", SAMPLED[2:])
def test_numpy_and_drjit_agree(kw):
    m = gltf(**kw)
    check_drjit(m)
    # the kernel of the NumPy front end reads colours one channel per lane; max_value still couples them
    rng = np.random.default_rng(4)
    wi = rng.normal(size=(400, 3)); wi[:, 2] = np.abs(wi[:, 2])
    wo = rng.normal(size=(400, 3)); wo[:, 2] = np.abs(wo[:, 2])
    np.testing.assert_allclose(m.eval(wi, wo, backend="drjit"), m.eval(wi, wo, backend="numpy"), rtol=1e-10)


# -- bad input ------------------------------------------------------------------------

@pytest.mark.parametrize("kw,text", [(dict(roughness=0.0), "'roughness' must lie in [0.01, 1]"),
                                     (dict(metallic=1.5), "'metallic' must lie in [0, 1]"),
                                     (dict(base_color=[0.1, 0.2]), "'base_color' must have 1 or 3 channels"),
                                     (dict(specular_color=-1.0), "'specular_color' must lie in [0, 25]"),
                                     (dict(anisotropy_strength=2.0), "'anisotropy_strength' must lie in [0, 1]")])
def test_bad_parameters_are_named_with_their_range(kw, text):
    with pytest.raises(ValueError, match=re.escape(text)):
        gltf(**kw)


def test_the_shader_trace_takes_max_value_over_the_uniform_channels():
    # exported with uniforms, specular_color is a vec3 the shader reduces itself: the trace must
    # equal NumPy for a colour whose largest channel is not the first
    from plausible.arrays import symbolic
    from plausible.export.shader import _symbolic_params, uniform_params

    m = gltf(base_color=[0.9, 0.5, 0.2], specular=0.7, specular_color=[0.5, 3.0, 1.0], roughness=0.4)
    specs = uniform_params(m, True)
    p, _ = _symbolic_params(m, specs)
    wi_s, wo_s = symbolic.direction("wi"), symbolic.direction("wo")
    graph = symbolic.trace(lambda: m._f(symbolic.SYM, wi_s, wo_s, p))
    rng = np.random.default_rng(5)
    wi, wo = (np.abs(rng.normal(size=(300, 3))) for _ in range(2))
    wi /= np.linalg.norm(wi, axis=1, keepdims=True); wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    env = {f"{d}.{c}": a[:, k] for d, a in (("wi", wi), ("wo", wo)) for k, c in enumerate("xyz")}
    for s in specs:
        v = m.params[s.name]
        env.update({f"{s.name}.{c}": float(np.broadcast_to(v, 3)[k]) for k, c in enumerate("xyz")}
                   if s.kind == "color" else {s.name: float(v)})
    got = np.asarray(symbolic.evaluate(graph, env), dtype=float)
    np.testing.assert_allclose(got, m.eval(wi, wo), rtol=1e-10)
    # the red channel depends on the green one, the largest (a smaller green changes red)
    other = gltf(base_color=[0.9, 0.5, 0.2], specular=0.7, specular_color=[0.5, 1.0, 1.0], roughness=0.4)
    assert np.max(np.abs(other.eval(wi, wo)[:, 0] / m.eval(wi, wo)[:, 0] - 1)) > 1e-3


# -- sweeps (slow) ----------------------------------------------------------------------

@pytest.mark.slow
@pytest.mark.parametrize("roughness", [0.05, 0.2, 0.5, 0.8, 1.0])
@pytest.mark.parametrize("strength", [0.0, 0.5, 1.0])
def test_sweep_metal_albedo_below_one_and_sampler_chi_square(roughness, strength):
    m = gltf(base_color=1.0, metallic=1.0, roughness=roughness, anisotropy_strength=strength,
             anisotropy_rotation=0.5)
    for t in (0.0, 30.0, 60.0, 80.0, 89.0):
        assert plausible.albedo(m, from_angles(t, 40.0)).value <= 1.0 + 1e-6
    if roughness >= 0.2:     # sharper lobes than the 10 x 20 cells of the reference test resolve
        for t in (0.0, 45.0, 80.0):
            assert chi2_sampler_pvalue(m, from_angles(t, 40.0), n=50_000, sub=40) > 1e-4


@pytest.mark.slow
def test_sweep_appendix_b_at_random_pairs():
    rng = np.random.default_rng(11)
    for _ in range(40):
        base, metallic, roughness = rng.uniform(0, 1), rng.uniform(0, 1), rng.uniform(0.05, 1)
        m = gltf(base_color=base, metallic=metallic, roughness=roughness)
        a, b = rng.normal(size=(2, 3))
        wi, wo = np.abs(a) / np.linalg.norm(a), np.abs(b) / np.linalg.norm(b)
        assert m.eval(wi, wo) == pytest.approx(spec_appendix_b(wi, wo, base, metallic, roughness), rel=1e-11)


# -- the viewer's behaviour (glTF-Sample-Renderer) and KHR_materials_ior ----------------------

def sample_renderer(wi, wo, base, metallic, roughness, specular, specular_color, strength):
    """glTF-Sample-Renderer's punctual light (pbr.frag, brdf.glsl), written again here with
    N.L, N.V, N.H, V.H and T, B dot products (rotation 0): per-channel
    ``mix(diffuse, specular, F)``, and where ``strength > 0`` its ``BRDF_specularGGXAnisotropy``
    with ``ab = clamp(alpha, 0.001, 1)`` and ``V`` clamped to [0, 1]."""
    n, t, b = np.array([0.0, 0.0, 1.0]), np.array([1.0, 0.0, 0.0]), np.array([0.0, 1.0, 0.0])
    h = (wi + wo) / np.linalg.norm(wi + wo)
    nl, nv, nh, vh = wi @ n, wo @ n, h @ n, wo @ h
    alpha = roughness ** 2
    if strength > 0:
        at, ab = alpha + (1 - alpha) * strength ** 2, min(max(alpha, 0.001), 1.0)
        a2 = at * ab
        f = np.array([ab * (t @ h), at * (b @ h), a2 * nh])
        d = a2 * (a2 / (f @ f)) ** 2 / math.pi
        v = 0.5 / (nl * np.linalg.norm([at * (t @ wo), ab * (b @ wo), nv])
                   + nv * np.linalg.norm([at * (t @ wi), ab * (b @ wi), nl]))
        v = min(max(v, 0.0), 1.0)
    else:
        d = alpha ** 2 / (math.pi * (nh * nh * (alpha ** 2 - 1) + 1) ** 2)
        v = 0.5 / (nl * math.sqrt(nv * nv * (1 - alpha ** 2) + alpha ** 2)
                   + nv * math.sqrt(nl * nl * (1 - alpha ** 2) + alpha ** 2))
    base, sc = np.broadcast_to(base, (3,)), np.broadcast_to(specular_color, (3,))
    fw = (1 - abs(vh)) ** 5
    f0 = np.minimum(0.04 * sc, 1.0) * specular
    fd = f0 + (specular - f0) * fw                  # F_Schlick(f0_dielectric * specularWeight, f90, VdotH)
    fm = base + (1 - base) * fw
    dielectric = (base / math.pi) * (1 - fd) + (v * d) * fd      # mix per channel
    return dielectric * (1 - metallic) + fm * v * d * metallic


VIEWER_CASES = [([0.6, 0.5, 0.2], 0.3, 0.5, 0.8, [2.0, 0.5, 1.0], 0.0),
                ([0.9, 0.9, 0.9], 1.0, 0.5, 1.0, 1.0, 0.001),
                ([0.4, 0.7, 0.2], 0.5, 0.02, 1.0, [1.5, 1.0, 0.2], 0.6),       # alpha_b = 4e-4 -> 0.001
                ([1.0, 1.0, 1.0], 1.0, 0.1, 1.0, 1.0, 0.3)]


@pytest.mark.parametrize("base,metallic,roughness,specular,sc,strength", VIEWER_CASES)
@pytest.mark.parametrize("a,b", PAIRS + [((88.0, 0.0), (89.0, 180.0)), ((85.0, 90.0), (87.0, 270.0))])
def test_viewer_true_is_the_sample_renderers_formula(base, metallic, roughness, specular, sc, strength, a, b):
    wi, wo = from_angles(*a), from_angles(*b)
    m = gltf(base_color=base, metallic=metallic, roughness=roughness, specular=specular, specular_color=sc,
             anisotropy_strength=strength, viewer="true")
    want = sample_renderer(wi, wo, np.array(base), metallic, roughness, specular, sc, strength)
    np.testing.assert_allclose(m.eval(wi, wo), want, rtol=1e-11)


def test_the_viewers_differences_have_the_documented_sizes():
    # Vis clamped to 1 on the anisotropic path: a white metal of roughness 0.5 (the extension present,
    # strength 0.001), the measurement: 0.839 vs 0.553 at 75 deg, 0.901 vs 0.339 at 85 deg
    for theta, spec, viewer in [(75, 0.839, 0.553), (85, 0.901, 0.339)]:
        wi = from_angles(theta, 0)
        got = [float(np.mean(plausible.albedo(gltf(base_color=1.0, metallic=1.0, roughness=0.5,
                                                   anisotropy_strength=0.001, viewer=v), wi).value))
               for v in ("false", "true")]
        assert got == [pytest.approx(spec, abs=6e-4), pytest.approx(viewer, abs=6e-4)]
    # the diffuse weight: 1 - F per channel vs 1 - max F differ by (max f0 - f0_c)(1 - w) specular,
    # 10 % of the diffuse for specularColor (2.5, 1, 1) at normal incidence (f0 0.1 vs 0.04)
    wi = wo = from_angles(0, 0)
    kw = dict(base_color=0.5, roughness=1.0, specular_color=[2.5, 1.0, 1.0])
    diff = gltf(viewer="true", **kw).eval(wi, wo) - gltf(**kw).eval(wi, wo)
    np.testing.assert_allclose(diff / (0.5 / math.pi), [0.0, 0.06, 0.06], atol=1e-12)
    assert gltf(viewer="true", base_color=0.5).eval(wi, wo) == gltf(base_color=0.5).eval(wi, wo)   # grey: same


def test_viewer_true_is_reciprocal_samples_its_lobes_and_agrees_with_drjit():
    m = gltf(base_color=[0.4, 0.7, 0.2], metallic=0.5, roughness=0.3, specular_color=[1.5, 1.0, 0.2],
             anisotropy_strength=0.6, viewer="true")
    check_reciprocal(m)
    check_drjit(m)
    check_sampling(m, from_angles(40, 30))
    # the diffuse lobe's albedo, per channel (1 - f0_c - (f90 - f0_c) I): a smooth material against a rule
    m = gltf(base_color=[0.4, 0.7, 0.2], roughness=1.0, specular_color=[20.0, 1.0, 0.2], viewer="true")
    wi = from_angles(50, 30)
    dirs, w = hemisphere_rule(300, 300)
    quad = (m.eval(wi, dirs) * (dirs[:, 2] * w)[:, None]).sum(0)
    np.testing.assert_allclose(plausible.albedo(m, wi).value, quad, rtol=1e-6)


@pytest.mark.parametrize("ior", [1.0, 1.33, 1.5, 2.42, 0.0])
def test_specular_color_of_ior_gives_the_extensions_f0_exactly(ior):
    from plausible.models.gltf_pbr import specular_color_of_ior

    # KHR_materials_ior + KHR_materials_specular: f0 = min(F0(ior) specularColor, 1) specular, f90 = specular,
    # written into Appendix B's dielectric here
    color, s, base, rough = np.array([1.0, 0.5, 3.0]), 0.9, np.array([0.3, 0.5, 0.7]), 0.4
    F0 = 1.0 if ior == 0 else ((ior - 1) / (ior + 1)) ** 2
    m = gltf(base_color=base, roughness=rough, specular=s, specular_color=specular_color_of_ior(ior, color))
    for a, b in PAIRS:
        wi, wo = from_angles(*a), from_angles(*b)
        h = (wi + wo) / np.linalg.norm(wi + wo)
        fw = (1 - wo @ h) ** 5
        f0 = np.minimum(F0 * color, 1) * s
        F = f0 + (s - f0) * fw
        vd = gltf(base_color=0.0, metallic=1.0, roughness=rough).eval(wi, wo) / fw     # Vis D
        np.testing.assert_allclose(m.eval(wi, wo), F * vd + (1 - F.max()) * base / math.pi, rtol=1e-12)
    with pytest.raises(ValueError, match=r"ior must be 0 or lie in \[1, inf\), got 0.9"):
        specular_color_of_ior(0.9)
