"""The glTF 2.0 metallic-roughness BRDF, with KHR_materials_specular and
KHR_materials_anisotropy, written from the Khronos specification.

References
----------
* The Khronos 3D Formats Working Group, *glTF 2.0 Specification*, Appendix B
  "BRDF Implementation" (sections "Specular BRDF", "Diffuse BRDF", "Fresnel",
  "Metal BRDF and Dielectric BRDF").
* Khronos, *KHR_materials_specular* (ratified), section "Implementation":
  ``fresnel_mix(f0_color, ior, weight, base, layer)``.
* Khronos, *KHR_materials_anisotropy* (ratified): ``alpha_t = mix(alpha, 1, strength^2)``,
  ``alpha_b = alpha``, Burley's anisotropic distribution in the frame rotated by
  ``anisotropyRotation`` (counter-clockwise from the tangent).
* E. Heitz, "Understanding the masking-shadowing function in microfacet-based
  BRDFs", JCGT 3(2), 2014 (the height-correlated Smith ``G``, eqs. 99 and 86).
* E. Heitz, "Sampling the GGX distribution of visible normals", JCGT 7(4), 2018.

The model, in the specification's notation (``V`` the view, ``L`` the light,
``H`` their half vector; ours are ``wo``, ``wi``, ``h``; ``VdotH = LdotH``)::

    alpha           = roughness^2
    alpha_t         = mix(alpha, 1, anisotropy_strength^2),  alpha_b = alpha
    D               = 1 / (pi alpha_t alpha_b (ht^2/alpha_t^2 + hb^2/alpha_b^2 + hn^2)^2)
    Vis             = chi+(H.L) chi+(H.V) / (2 (|N.V| |L~| + |N.L| |V~|)),
                      |W~| = |(alpha_t W.t, alpha_b W.b, W.n)|      (height-correlated Smith)
    specular_brdf   = Vis D
    fresnel_w       = (1 - |V.H|)^5
    metal_brdf      = specular_brdf (baseColor + (1 - baseColor) fresnel_w)
    f0_d            = min(0.04 specularColor, 1) specular,   f90_d = specular
    F_d             = f0_d + (f90_d - f0_d) fresnel_w       (per channel)
    dielectric_brdf = F_d specular_brdf + (1 - max_value(F_d)) baseColor / pi
    material        = mix(dielectric_brdf, metal_brdf, metallic)

With ``specular = 1``, ``specular_color = 1`` and no anisotropy this is Appendix B
exactly (``f0 = 0.04``, ``dielectric_brdf = mix(diffuse, specular, F)``).  For
isotropic ``alpha`` the visibility is Appendix B's
``1 / (2 (|N.V| sqrt(alpha^2 + (1 - alpha^2)(N.L)^2) + |N.L| sqrt(alpha^2 + (1 - alpha^2)(N.V)^2)))``.
The extension's sample code clamps ``Vis`` to 1 (an approximation); the exact
height-correlated form is used here.

``max_value(F_d) = max(F_d.r, F_d.g, F_d.b)`` couples the channels: since ``F_d``
is linear in ``f0_d`` with a non-negative weight, it equals the Fresnel of
``max(f0_d)``, ``min(0.04 max(specularColor), 1) specular``.  In a spectral
Mitsuba variant the maximum is over the sampled wavelengths.

Energy.  The specification says itself ("Coupling Diffuse and Specular
Reflection") that ``fresnel_mix`` "breaks ... energy conservation": the diffuse
term is weighted by ``1 - F(V.H)`` but the specular term reflects ``F`` of the
mirror direction.  Measured (``tests/models/test_gltf_pbr.py``): a white
dielectric (``base_color = 1``, ``roughness = 0.1``) reflects 1.00 of the light at
normal incidence, 1.20 at 75 degrees and 1.35 at 80.  A metal (``metallic = 1``,
``base_color <= 1``) is a single-scattering GGX conductor: its albedo stays below 1
(it loses the multiple scattering: at ``roughness = 1`` and normal incidence it
reflects ``1 - ln 2 = 0.307``).
So the registry entry says ``energy_conserving=False``.  The model is reciprocal
(``D``, ``Vis`` and every Fresnel term are symmetric in ``V`` and ``L``).

The viewer's behaviour (``viewer="true"``).  Khronos' glTF-Sample-Renderer
(``source/Renderer/shaders/brdf.glsl`` and ``pbr.frag``) departs from the text
in three places; ``viewer="true"`` computes what it shows:

* the dielectric mixes per channel, ``mix(diffuse, specular, F_d)``, so the
  diffuse weight is ``1 - F_d`` per channel instead of ``1 - max_value(F_d)``
  (differs only with a coloured ``specularColor``);
* where anisotropy is on (``anisotropy_strength > 0``; the viewer's
  ``BRDF_specularGGXAnisotropy``) ``Vis`` is clamped to 1 and
* ``alpha_b = clamp(alpha, 0.001, 1)`` there.
The Fresnel weight, ``D`` and ``alpha_t`` are the same.

``KHR_materials_ior`` (``f0 = ((ior - 1)/(ior + 1))^2`` in place of 0.04;
``ior = 0`` means ``f0 = 1``) needs no parameter of its own: with
KHR_materials_specular the dielectric ``f0`` is ``min(F0(ior) specularColor, 1)
specular``, which is exactly this model's with ``specular_color =
min(F0(ior) specularColor, 1) / 0.04`` (:func:`specular_color_of_ior`; at most
25, inside the parameter's range).

Sampling: a one-sample mixture of the specular lobe (GGX visible normals,
Heitz 2018, reflected; ``pdf = D / (2 (wi.z + |wi~|))``) and the diffuse lobe
(cosine-weighted), chosen in proportion to estimates of their albedos at ``wi``.
"""

from __future__ import annotations

import math

import numpy as np

from .. import vec, warps
from ..bxdf import BxDF, Lobe
from ..arrays.ops import INV_PI
from ..params import Param
from ..registry import register
from ..vec import HORIZON, above

#: The dielectric reflectance at normal incidence of ``ior = 1.5``: ``((1 - 1.5) / (1 + 1.5))^2``.
DIELECTRIC_F0 = 0.04
#: ``viewer``: the specification's formulas, or glTF-Sample-Renderer's (module docstring).
VIEWER = ("false", "true")
#: glTF-Sample-Renderer's floor on ``alpha_b`` where anisotropy is on (``clamp(alpha, 0.001, 1)``).
VIEWER_ALPHA_B_MIN = 0.001


def ior_f0(ior):
    """``((ior - 1) / (ior + 1))^2`` (KHR_materials_ior, outside ior 1); ``ior = 0``
    is the extension's specular-glossiness mode, an infinite ior: 1."""
    ior = np.asarray(ior, dtype=np.float64)
    return np.where(ior == 0.0, 1.0, ((ior - 1.0) / (ior + 1.0)) ** 2)


def specular_color_of_ior(ior, specular_color=1.0):
    """The ``specular_color`` of this model that gives the dielectric ``f0`` of a
    glTF material with ``KHR_materials_ior.ior`` and
    ``KHR_materials_specular.specularColorFactor`` = ``specular_color``:
    ``min(F0(ior) specular_color, 1) / 0.04`` (exact: both models then compute
    ``min(., 1) specular``, :func:`ior_f0`).  ValueError for an ior that is
    neither 0 nor at least 1."""
    ior = float(ior)
    if not (ior == 0.0 or 1.0 <= ior < math.inf):
        raise ValueError(f"KHR_materials_ior: ior must be 0 or lie in [1, inf), got {ior:g}")
    c = np.asarray(specular_color, dtype=np.float64)
    out = np.minimum(ior_f0(ior) * c, 1.0) / DIELECTRIC_F0
    return float(out) if out.ndim == 0 else out


def channel_max(ops, c):
    """``max(c.r, c.g, c.b)`` (KHR_materials_specular's ``max_value``): a number stays
    itself; NumPy and symbolic channel arrays and Dr.Jit colours (the Mitsuba
    plugin's ``Color3f``) are reduced with ``ops.maximum``."""
    if isinstance(c, np.ndarray):
        flat = c.reshape(-1)
        if flat.size <= 1:
            return flat[0] if flat.size == 1 else c
        out = flat[0]
        for x in flat[1:]:
            out = ops.maximum(out, x)
        return out
    if isinstance(c, (int, float)):
        return c
    import drjit as dr  # a Dr.Jit value: a colour has a static size, a Float a dynamic one (-1)

    n = dr.size_v(c)
    if n <= 1:
        return c
    out = c[0]
    for i in range(1, n):
        out = ops.maximum(out, c[i])
    return out


def rotate_to_anisotropy(ops, w, cos_r, sin_r):
    """``w`` in the frame of KHR_materials_anisotropy's direction: the tangent ``u``
    turned counter-clockwise by the rotation (``t = (cos, sin, 0)``,
    ``b = n x t = (-sin, cos, 0)``); ``w.t``, ``w.b``, ``w.n``."""
    return (w[0] * cos_r + w[1] * sin_r, -w[0] * sin_r + w[1] * cos_r, w[2])


def rotate_from_anisotropy(ops, w, cos_r, sin_r):
    """The inverse of :func:`rotate_to_anisotropy`."""
    return (w[0] * cos_r - w[1] * sin_r, w[0] * sin_r + w[1] * cos_r, w[2])


def gltf_alphas(roughness, strength):
    """``(alpha_t, alpha_b) = (mix(r^2, 1, s^2), r^2)`` (glTF Appendix B, ``alpha = roughness^2``;
    KHR_materials_anisotropy, ``directionAlphaRoughness``)."""
    a = roughness * roughness
    return a + (1.0 - a) * strength * strength, a


def smith_visibility(ops, wi, wo, at, ab):
    """``Vis = G / (4 |N.L| |N.V|)`` with the height-correlated Smith ``G`` of GGX:
    ``1 / (2 (wo.z |wi~| + wi.z |wo~|))``, ``|w~| = |(at w.t, ab w.b, w.n)|``
    (glTF Appendix B "Specular BRDF"; Heitz 2014 eq. 99 with ``Lambda`` of eq. 86).
    Directions in the anisotropy frame, both above the horizon; the caller applies
    ``chi+(H.L) chi+(H.V)``."""
    li = warps.ggx_stretched_length(ops, wi, at, ab)
    lo = warps.ggx_stretched_length(ops, wo, at, ab)
    return 0.5 / (wo[2] * li + wi[2] * lo)


def specular_brdf(ops, wi, wo, h, at, ab, vis_max=math.inf):
    """``min(Vis, vis_max) D`` (glTF Appendix B ``specular_brdf(alpha)``; ``vis_max``
    1 for the viewer's anisotropic path, else no cap), zero unless both
    directions are above the horizon; ``h`` their half vector (anisotropy frame)."""
    ok = above(ops, wi, wo)
    wi_s = (wi[0], wi[1], ops.where(ok, wi[2], 1.0))
    wo_s = (wo[0], wo[1], ops.where(ok, wo[2], 1.0))
    vis = ops.minimum(smith_visibility(ops, wi_s, wo_s, at, ab), vis_max)
    return ops.where(ok, vis * warps.ggx_d(ops, h, at, ab), 0.0)


def schlick_f(f0, f90, w):
    """``f0 + (f90 - f0) w``, ``w = (1 - |V.H|)^5`` (glTF Appendix B "Fresnel";
    KHR_materials_specular's ``F90``)."""
    return f0 + (f90 - f0) * w


def fresnel_weight(ops, kh):
    """``(1 - |V.H|)^5`` (glTF Appendix B ``fresnel_w``), ``kh = V.H = L.H``."""
    m = 1.0 - ops.minimum(ops.maximum(kh, 0.0), 1.0)
    m2 = m * m
    return m2 * m2 * m


def dielectric_f0(ops, specular, specular_color):
    """``min(0.04 specularColor, 1) specular`` (KHR_materials_specular, "Implementation")."""
    return ops.minimum(DIELECTRIC_F0 * specular_color, 1.0) * specular


def _viewer(p) -> bool:
    return getattr(p, "viewer", "false") == "true"


def _frame(ops, wi, wo, p):
    """Both directions in the anisotropy frame, their half vector, ``V.H``, the
    alphas and the cap on ``Vis`` (the viewer's ``alpha_b >= 0.001`` and ``Vis <= 1``
    where anisotropy is on; none for the specification)."""
    c, s = ops.cos(p.anisotropy_rotation), ops.sin(p.anisotropy_rotation)
    wi_r, wo_r = rotate_to_anisotropy(ops, wi, c, s), rotate_to_anisotropy(ops, wo, c, s)
    h, kh = vec.half_vector_cos(ops, wi_r, wo_r)
    at, ab = gltf_alphas(p.roughness, p.anisotropy_strength)
    cap = math.inf
    if _viewer(p):
        aniso = p.anisotropy_strength > 0.0
        ab = ops.where(aniso, ops.maximum(ab, VIEWER_ALPHA_B_MIN), ab)
        cap = ops.where(aniso, 1.0, math.inf)
    return wi_r, wo_r, h, kh, at, ab, cap


def gltf_specular(ops, wi, wo, p):
    """``((1 - metallic) F_d + metallic F_metal) Vis D``: the specular parts of
    ``dielectric_brdf`` and ``metal_brdf`` mixed by ``metallic`` (module docstring)."""
    wi_r, wo_r, h, kh, at, ab, cap = _frame(ops, wi, wo, p)
    w = fresnel_weight(ops, kh)
    f_metal = schlick_f(p.base_color, 1.0, w)
    f_diel = schlick_f(dielectric_f0(ops, p.specular, p.specular_color), p.specular, w)
    weight = (1.0 - p.metallic) * f_diel + p.metallic * f_metal
    return weight * specular_brdf(ops, wi_r, wo_r, h, at, ab, cap)


def _gauss_legendre(n, a, b):
    x, w = np.polynomial.legendre.leggauss(n)
    return [(float(0.5 * (b - a) * xi + 0.5 * (b + a)), float(0.5 * (b - a) * wi)) for xi, wi in zip(x, w)]


#: 10 x 10 Gauss-Legendre nodes in ``(cos theta_o, phi)`` over the half hemisphere ``phi in [0, pi]``
#: (the integrand is even in ``phi``): ``(mu, sin theta_o, cos phi, weight)``.
_FRESNEL_NODES = [(mu, math.sqrt(1.0 - mu * mu), math.cos(ph), wm * wp)
                  for mu, wm in _gauss_legendre(10, 0.0, 1.0) for ph, wp in _gauss_legendre(10, 0.0, math.pi)]


def fresnel_weight_albedo(ops, cos_i):
    """``(1/pi) int (1 - wi.h)^5 cos(theta_o) d omega_o`` over the hemisphere: the
    cosine-weighted mean of ``fresnel_w`` seen by a Lambertian base, so that the
    diffuse lobe's albedo is ``(1 - metallic) baseColor (1 - f0 - (f90 - f0) I)``.
    No closed form (odd powers of ``wi.h = sqrt((1 + wi.wo) / 2)``); the integrand
    is smooth on the hemisphere, and 10 x 10 Gauss-Legendre nodes give it to 2e-8
    up to 75 degrees and 1.1e-7 up to grazing (against 600 x 600 nodes; ``I`` is 8.2e-5 at
    normal incidence, 0.028 at grazing)."""
    s = ops.sqrt(ops.maximum(1.0 - cos_i * cos_i, 0.0))
    total = 0.0
    for mu, st, cp, w in _FRESNEL_NODES:
        x = cos_i * mu + s * (st * cp)
        m = 1.0 - ops.sqrt(ops.maximum(0.5 * (1.0 + x), 0.0))
        m2 = m * m
        total = total + (w * mu) * (m2 * m2 * m)
    return total * (2.0 * INV_PI)


def _specular_color_max(ops, p):
    # the Mitsuba plugin and the shader reduce the colour; the NumPy kernel view carries it
    scm = getattr(p, "specular_color_max", None)
    return channel_max(ops, p.specular_color) if scm is None else scm


def _diffuse_f0(ops, p):
    """The ``f0`` that weights the diffuse term: ``min(0.04 max(specularColor), 1)
    specular`` (the specification's ``max_value``), or per channel for the viewer."""
    return dielectric_f0(ops, p.specular, p.specular_color if _viewer(p) else _specular_color_max(ops, p))


def gltf_diffuse_albedo(ops, wi, p):
    """``int gltf_diffuse cos d omega_o = (1 - metallic) baseColor (1 - f0m - (f90 - f0m) I(wi.z))``
    with ``f0m = min(0.04 max(specularColor), 1) specular`` (per channel for the
    viewer), ``f90 = specular`` and ``I`` :func:`fresnel_weight_albedo`."""
    f0m = _diffuse_f0(ops, p)
    avg = f0m + (p.specular - f0m) * fresnel_weight_albedo(ops, wi[2])
    return ops.where(wi[2] > HORIZON, (1.0 - p.metallic) * (1.0 - avg) * p.base_color, 0.0)


def gltf_diffuse(ops, wi, wo, p):
    """``(1 - metallic) (1 - max_value(F_d)) baseColor / pi``: the diffuse part of
    ``dielectric_brdf`` (KHR_materials_specular's ``fresnel_mix``; ``1 - F_d`` per
    channel for the viewer), zero below the horizon."""
    kh = vec.half_vector_cos(ops, wi, wo)[1]   # V.H is the same in any frame about n
    f0m = _diffuse_f0(ops, p)
    f_max = schlick_f(f0m, p.specular, fresnel_weight(ops, kh))
    val = (1.0 - p.metallic) * (1.0 - f_max) * p.base_color * INV_PI
    return ops.where(above(ops, wi, wo), val, 0.0)


def _specular_pdf(ops, wi, wo, q):
    c, s = ops.cos(q.anisotropy_rotation), ops.sin(q.anisotropy_rotation)
    at, ab = gltf_alphas(q.roughness, q.anisotropy_strength)
    return warps.ggx_visible_reflected_pdf(ops, rotate_to_anisotropy(ops, wi, c, s),
                                           rotate_to_anisotropy(ops, wo, c, s), at, ab)


def _specular_sample(ops, wi, u, q):
    c, s = ops.cos(q.anisotropy_rotation), ops.sin(q.anisotropy_rotation)
    at, ab = gltf_alphas(q.roughness, q.anisotropy_strength)
    wi_r = rotate_to_anisotropy(ops, wi, c, s)
    h = warps.ggx_visible_half_vector(ops, wi_r, at, ab, u[1], u[2])
    return rotate_from_anisotropy(ops, vec.reflect(wi_r, h), c, s)


def _diffuse_pdf(ops, wi, wo, q):
    return ops.where(above(ops, wi, wo), warps.cosine_hemisphere_pdf(ops, wo), 0.0)


def _diffuse_sample(ops, wi, u, q):
    return warps.cosine_hemisphere(ops, u[1], u[2])


_ROUGHNESS = dict(lo=0.01, hi=1.0)


@register("gltf-pbr",
          "glTF 2.0 metallic-roughness BRDF (Khronos spec Appendix B: GGX D with alpha = roughness^2, "
          "height-correlated Smith, Schlick Fresnel f0 = mix(0.04, base_color, metallic), Lambert "
          "diffuse by fresnel_mix), with KHR_materials_specular and KHR_materials_anisotropy. "
          "fresnel_mix is not energy conserving (the spec says so).",
          reciprocal=True, energy_conserving=False,
          references=("Khronos glTF 2.0 Specification, Appendix B",
                      "Khronos KHR_materials_specular", "Khronos KHR_materials_anisotropy",
                      "Heitz, JCGT 2014", "Heitz, JCGT 2018"))
class GltfPBR(BxDF):
    """``mix(dielectric_brdf, metal_brdf, metallic)`` of glTF 2.0 (see the module docstring).

    Parameters are the glTF material's: ``base_color`` (``baseColorFactor``, linear
    RGB), ``metallic`` (``metallicFactor``), ``roughness`` (``roughnessFactor``; at
    least 0.01, as a delta lobe is not a BRDF), ``specular`` and ``specular_color``
    (KHR_materials_specular ``specularFactor``, ``specularColorFactor``),
    ``anisotropy_strength`` and ``anisotropy_rotation`` (KHR_materials_anisotropy,
    radians counter-clockwise from the tangent ``u``).
    """

    LOBES = frozenset({"diffuse", "glossy"})

    PARAMS = (
        Param("base_color", 0.8, 0.0, 1.0, "color", "baseColorFactor (linear RGB)", (0.0, 1.0)),
        Param("metallic", 0.0, 0.0, 1.0, doc="metallicFactor: 0 dielectric, 1 metal", extremes=(1.0,)),
        Param("roughness", 0.5, doc="roughnessFactor (alpha = roughness^2)", extremes=(0.1,),
              **_ROUGHNESS),
        Param("specular", 1.0, 0.0, 1.0, doc="KHR_materials_specular specularFactor (dielectric only)",
              extremes=(0.0,)),
        Param("specular_color", 1.0, 0.0, 25.0, "color",
              "KHR_materials_specular specularColorFactor; f0 = min(0.04 specular_color, 1), "
              "so 25 is the largest that changes anything"),
        Param("anisotropy_strength", 0.0, 0.0, 1.0, doc="KHR_materials_anisotropy anisotropyStrength",
              extremes=(0.8,)),
        # D and Vis are unchanged by a half turn of the frame, so [0, pi] holds every direction
        Param("anisotropy_rotation", 0.0, 0.0, math.pi,
              doc="KHR_materials_anisotropy anisotropyRotation (radians, counter-clockwise from the "
                  "tangent; a half turn changes nothing, so other angles are taken mod pi)"),
        Param("viewer", "false", kind="choice", choices=VIEWER,
              doc="'true': what Khronos' glTF-Sample-Renderer shows (diffuse weight 1 - F per channel; "
                  "where anisotropic, Vis clamped to 1 and alpha_b >= 0.001); 'false': the specification"),
    )

    def lobes(self):
        """The specular lobe (GGX, Fresnel-weighted), then the diffuse one (albedo
        :func:`gltf_diffuse_albedo`)."""
        return (Lobe("glossy", gltf_specular, _specular_pdf, _specular_sample),
                Lobe("diffuse", gltf_diffuse, _diffuse_pdf, _diffuse_sample, gltf_diffuse_albedo))

    def lobe_weights(self, ops, wi, q):
        """Estimates of the two lobes' albedos at ``wi`` (channel means): the Fresnel
        weight at ``n.wi`` for the specular lobe and the rest of ``base_color`` for the
        diffuse one.  Any positive weights give an exact pdf; these make it close to ``f cos``."""
        w = fresnel_weight(ops, wi[2])
        f_diel = schlick_f(dielectric_f0(ops, q.specular, q.specular_color), q.specular, w)
        spec = (1.0 - q.metallic) * f_diel + q.metallic * schlick_f(q.base_color, 1.0, w)
        diff = (1.0 - q.metallic) * (1.0 - f_diel) * q.base_color
        return spec, diff

    def _f(self, ops, wi, wo, p):
        return gltf_specular(ops, wi, wo, p) + gltf_diffuse(ops, wi, wo, p)

    def _kernel_view(self, convert):
        """The NumPy front end's Dr.Jit kernels read a colour one channel per lane, so
        ``max_value`` cannot be taken there: the view carries it, computed here."""
        out = super()._kernel_view(convert)
        out.p.specular_color_max = convert(float(np.max(self.params["specular_color"])))
        return out

    def peak_directions(self, wi):
        return [np.array([-wi[0], -wi[1], wi[2]]), np.array([0.0, 0.0, 1.0])]
