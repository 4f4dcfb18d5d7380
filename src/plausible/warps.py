"""Sampling warps, kept apart from the models (as in pbrt-v4).

Each warp maps uniform numbers ``u1, u2`` in ``[0, 1)`` to a direction and comes
with its density (per unit solid angle).  Written against an ops namespace, so
the same code runs on NumPy and on Dr.Jit.
"""

from __future__ import annotations

from . import vec
from .vec import HORIZON
from .arrays.ops import INV_PI, PI


def cosine_hemisphere(ops, u1, u2):
    """Cosine-weighted direction about ``z``: ``cos(theta) = sqrt(1 - u1)``.

    Density :func:`cosine_hemisphere_pdf`, ``cos(theta) / pi``.
    """
    r = ops.sqrt(u1)
    phi = 2.0 * PI * u2
    z = ops.sqrt(ops.maximum(1.0 - u1, 0.0))
    return (r * ops.cos(phi), r * ops.sin(phi), z)


def cosine_hemisphere_pdf(ops, w):
    return ops.maximum(w[2], 0.0) * INV_PI


def power_cosine_lobe(ops, n, u1, u2):
    """Direction about ``z`` with density ``(n + 1) / (2 pi) cos^n(theta)``.

    Inverse CDF: ``cos(theta) = u1^(1 / (n + 1))``.  ``n = 0`` gives the uniform
    hemisphere.
    """
    c = ops.power(u1, 1.0 / (n + 1.0))
    s = ops.sqrt(ops.maximum(1.0 - c * c, 0.0))
    phi = 2.0 * PI * u2
    return (s * ops.cos(phi), s * ops.sin(phi), c)


def power_cosine_lobe_pdf(ops, n, cos_theta):
    """``(n + 1) / (2 pi) cos^n(theta)`` for ``cos(theta) > 0``, else zero."""
    c = ops.maximum(cos_theta, 0.0)
    return ops.where(cos_theta > 0, (n + 1.0) / (2.0 * PI) * ops.power(c, n), 0.0)


def power_cosine_lobe_about(ops, axis, n, u1, u2):
    """:func:`power_cosine_lobe` rotated so that its axis is the unit vector ``axis``."""
    local = power_cosine_lobe(ops, n, u1, u2)
    s, t = vec.frame(ops, axis)
    return vec.to_world(local, s, t, axis)


def pow_cos_from_sin2(ops, sin2, e, cos_theta=None):
    """``cos(theta)^e`` computed from ``sin^2(theta)`` as ``exp(e/2 log1p(-sin^2))``.

    Accurate near the pole, where ``cos(theta)`` rounds to 1 and a direct power of
    it loses every digit of the lobe's shape for exponents of 10^4 and more.
    ``sin2 >= 1`` (the horizon) gives 0, or 1 when ``e == 0``.

    Given ``cos_theta`` as well (the cosine of the same angle), angles beyond 45
    degrees (``sin^2 > 1/2``) use ``max(cos_theta, 0)^e`` instead: near the
    horizon ``1 - sin^2`` cancels (in float32, in a shader or Dr.Jit's single
    precision, ``cos = 1e-3`` keeps 2 digits), while the cosine is accurate.
    """
    inside = sin2 < 1.0
    s = ops.where(inside, ops.maximum(sin2, 0.0), 0.0)
    val = ops.exp(0.5 * e * ops.log1p(-s))
    if cos_theta is not None:
        # exp(e log(cos)), not ops.power: Dr.Jit 1.5's power returns -inf when the
        # result underflows (measured: dr.power(0.308849, 604.094))
        pos = cos_theta > 0
        far = ops.exp(e * ops.log(ops.where(pos, cos_theta, 1.0)))
        return ops.where(sin2 > 0.5, ops.where(pos, far, ops.where(e == 0, 1.0, 0.0)), val)
    return ops.where(inside, val, ops.where(e == 0, 1.0, 0.0))


def power_near_one(ops, x, one_minus_x, e):
    """``max(x, 0)^e`` for ``x <= 1``, given also ``1 - x`` computed without cancellation.

    Above ``x = 1/2`` it is ``exp(e log1p(-(1 - x)))``: a lobe ``x^e`` with ``e``
    up to 10^4 peaks where ``x`` rounds to within one unit of 1 (6e-8 in
    float32, a relative error of 6e-4 in ``x^e``), while ``1 - x`` from a
    difference of vectors keeps its digits.  Below, ``exp(e log(x))`` (0 for
    ``x <= 0``, or 1 when ``e == 0``); not ``ops.power``, whose Dr.Jit version
    returns ``-inf`` when the result underflows.
    """
    near = x > 0.5
    v_near = ops.exp(e * ops.log1p(-ops.where(near, ops.minimum(ops.maximum(one_minus_x, 0.0), 0.5), 0.0)))
    pos = x > 0
    v_far = ops.where(pos, ops.exp(e * ops.log(ops.where(pos, x, 1.0))), ops.where(e == 0, 1.0, 0.0))
    return ops.where(near, v_near, v_far)


def anisotropic_exponent(ops, hx, hy, nu, nv):
    """``nu cos^2(phi) + nv sin^2(phi)`` of the half vector, without trigonometry.

    Equals ``(nu hx^2 + nv hy^2) / (1 - hz^2)`` (Ashikhmin & Shirley 2000, tech.
    report eq. 16, journal eq. 4).  At the pole (``hx = hy = 0``) the ratio is
    0/0; any value in ``[min(nu, nv), max(nu, nv)]`` is a valid limit because it
    multiplies ``log(hz) = 0`` there; ``nu`` is returned.
    """
    s = hx * hx + hy * hy
    pos = s > 0
    return ops.where(pos, (nu * hx * hx + nv * hy * hy) / ops.where(pos, s, 1.0), nu)


def anisotropic_half_vector(ops, nu, nv, u1, u2):
    """Half vector with density ``p_h(h) = sqrt((nu+1)(nv+1))/(2 pi) (n.h)^(nu cos^2 phi + nv sin^2 phi)``.

    Ashikhmin & Shirley 2000 (journal eqs. 6, 9, 10; tech. report eqs. 5, 19, 20).
    ``phi = atan(sqrt((nu+1)/(nv+1)) tan(pi xi / 2))`` in the first quadrant,
    computed without ``atan``/``tan``: with ``(c, s) = (cos, sin)(pi xi / 2)``,
    ``cos(phi), sin(phi) = (c, a s) / sqrt(c^2 + a^2 s^2)``.  ``u1`` is split in
    four quarters, one per quadrant; odd quadrants use the mirrored argument
    ``1 - xi`` so that ``phi`` is a continuous, monotone function of ``u1`` over
    ``[0, 2 pi)`` (stratification is preserved; the paper's ``1 - 4(0.5 - u1)``
    gives the same density but a discontinuous map).  Then
    ``cos(theta) = (1 - u2)^(1 / (nu cos^2 phi + nv sin^2 phi + 1))``.
    """
    a = ops.sqrt((nu + 1.0) / (nv + 1.0))
    t = 4.0 * u1
    q1 = (t >= 1.0) & (t < 2.0)
    q2 = (t >= 2.0) & (t < 3.0)
    q3 = t >= 3.0
    frac = t - ops.where(q3, 3.0, ops.where(q2, 2.0, ops.where(q1, 1.0, 0.0)))
    odd = q1 | q3
    xi = ops.where(odd, 1.0 - frac, frac)
    ang = 0.5 * PI * ops.minimum(ops.maximum(xi, 0.0), 1.0)
    c = ops.cos(ang)
    s = a * ops.sin(ang)
    inv = 1.0 / ops.sqrt(c * c + s * s)
    cp = c * inv
    sp = s * inv
    # Quadrant signs: q0 (+,+), q1 (-,+), q2 (-,-), q3 (+,-).
    cp = ops.where(q1 | q2, -cp, cp)
    sp = ops.where(q2 | q3, -sp, sp)
    e = nu * cp * cp + nv * sp * sp
    cos_t = ops.power(ops.maximum(1.0 - u2, 0.0), 1.0 / (e + 1.0))
    sin_t = ops.sqrt(ops.maximum(1.0 - cos_t * cos_t, 0.0))
    return (sin_t * cp, sin_t * sp, cos_t)


def anisotropic_half_vector_pdf(ops, nu, nv, h):
    """``p_h(h)`` of :func:`anisotropic_half_vector` (journal eq. 6), zero for ``h.z <= 0``."""
    return half_vector_lobe_pdf(ops, nu, nv, h, anisotropic_exponent(ops, h[0], h[1], nu, nv))


def reflected_half_vector(ops, wi, nu, nv, u1, u2):
    """``wo = -wi + 2 (wi.h) h`` with ``h`` from :func:`anisotropic_half_vector`
    (journal eq. 7).  ``nu == nv == n`` samples the Blinn lobe ``(n.h)^n``."""
    h = anisotropic_half_vector(ops, nu, nv, u1, u2)
    return vec.reflect(wi, h)


def reflected_half_vector_pdf(ops, wi, wo, nu, nv):
    """Density of :func:`reflected_half_vector`: ``p_h(h) / (4 (wi.h))``.

    Journal version eq. 8.  (The technical report's eq. 18 prints the fraction
    inverted; the journal version and the change of measure ``d omega_o =
    4 (wi.h) d omega_h`` agree on this form.)
    """
    return reflected_pdf(ops, wi, wo, lambda h: anisotropic_half_vector_pdf(ops, nu, nv, h))


def projected_offset(ops, wi, r, phi):
    """The direction whose projection on the tangent plane is ``d - wi_xy``, with
    ``d = r (cos phi, sin phi)`` (a lobe about the mirror direction in projected
    coordinates); ``(0, 0, -1)`` (invalid) where that point lies outside the unit disc.
    The density of ``wo`` per solid angle is the density of ``d`` per area times
    ``cos(theta_o)``."""
    ox = r * ops.cos(phi) - wi[0]
    oy = r * ops.sin(phi) - wi[1]
    rho2 = ox * ox + oy * oy
    inside = rho2 < 1.0
    oz = ops.sqrt(ops.maximum(1.0 - rho2, 0.0))
    return (ops.where(inside, ox, 0.0), ops.where(inside, oy, 0.0), ops.where(inside, oz, -1.0))


def mixture_weight(ops, a, b):
    """``a / (a + b)`` (the probability of picking the lobe of weight ``a`` beside one of
    weight ``b``), 0.5 where both are zero; by ``ops.where``, not a Python ``if``, so that
    ``a`` and ``b`` may be kernel data (one compiled kernel for every value,
    :mod:`plausible.kernel_params`)."""
    s = a + b
    pos = s > 0
    return ops.where(pos, a / ops.where(pos, s, 1.0), 0.5)


def mixture(ops, choose_a, a, b):
    """Component-wise select between two sampled directions."""
    return (ops.where(choose_a, a[0], b[0]), ops.where(choose_a, a[1], b[1]),
            ops.where(choose_a, a[2], b[2]))


def half_vector_lobe_pdf(ops, nu, nv, h, e):
    """``sqrt((nu+1)(nv+1))/(2 pi) (n.h)^e`` for ``h.z > 0``, else zero, with the
    exponent ``e`` supplied by the caller (journal eq. 6, tech. report eq. 5).

    :func:`anisotropic_half_vector_pdf` passes :func:`anisotropic_exponent`; a
    caller that knows ``nu == nv`` may pass ``nu`` itself (no 0/0, no division).
    ``(n.h)^e`` is taken from ``sin^2`` (:func:`pow_cos_from_sin2`), so ``h = n``
    gives exactly the peak value ``sqrt((nu+1)(nv+1))/(2 pi)``.
    """
    lobe = pow_cos_from_sin2(ops, h[0] * h[0] + h[1] * h[1], e, h[2])
    norm = ops.sqrt((nu + 1.0) * (nv + 1.0)) / (2.0 * PI)
    return ops.where(h[2] > 0, norm * lobe, 0.0)


def beckmann_half_vector(ops, ax, ay, u1, u2):
    """Half vector with density :func:`beckmann_half_vector_pdf` (anisotropic Beckmann
    distribution of normals, ``p_h = D(h) (n.h)``).

    B. Walter, "Notes on the Ward BRDF", Cornell PCG-05-06, 2005 (eqs. 6-7):
    ``phi = atan(ay / ax tan(2 pi u2))`` taken in the quadrant of ``2 pi u2``,
    written without ``atan``/``tan`` as ``(cos, sin)(phi) = (ax cos, ay sin)(2 pi u2) / norm``;
    then ``tan^2(theta) = -log(1 - u1) / (cos^2 phi / ax^2 + sin^2 phi / ay^2)``, where
    the denominator equals ``1 / (ax^2 cos^2 + ay^2 sin^2)(2 pi u2)``.  ``ax == ay == m``
    is the isotropic Beckmann sampler ``tan^2(theta) = -m^2 log(1 - u1)``, ``phi = 2 pi u2``.
    """
    a = 2.0 * PI * u2
    c = ax * ops.cos(a)
    s = ay * ops.sin(a)
    r2 = c * c + s * s
    inv = 1.0 / ops.sqrt(r2)
    tan2 = -ops.log1p(-ops.minimum(u1, 1.0 - 2.0 ** -53)) * r2
    # u1 = 1 (or 1 - 2^-53, which rounds to 1 in float32) gives tan^2 = inf and
    # inf * 0 below; 1e30 is the horizon to 1e-15 (a rejected sample), finite in float32
    tan2 = ops.minimum(tan2, 1e30)
    cos_t = 1.0 / ops.sqrt(1.0 + tan2)
    sin_t = ops.sqrt(tan2) * cos_t
    return (sin_t * c * inv, sin_t * s * inv, cos_t)


def beckmann_half_vector_pdf(ops, ax, ay, h):
    """``p_h(h) = exp(-((hx/ax)^2 + (hy/ay)^2) / hz^2) / (pi ax ay hz^3)``, zero for ``hz <= 0``.

    Derived from :func:`beckmann_half_vector`: ``phi`` has density
    ``1 / (2 pi ax ay A(phi))`` with ``A = cos^2/ax^2 + sin^2/ay^2``, and given ``phi``,
    ``t = tan^2(theta)`` is exponential with rate ``A``; ``dt = 2 tan / cos^2 d theta``
    and ``d omega = sin d theta d phi`` give the form above (Walter 2005, eq. 9 of the
    Ward notes, is the same density).  It integrates to one over the hemisphere
    (tests/models/test_ward.py checks this numerically).
    """
    hz = h[2]
    ok = hz > 0
    z = ops.where(ok, hz, 1.0)
    e = ((h[0] / ax) ** 2 + (h[1] / ay) ** 2) / (z * z)
    # exp(-e) / hz^3 as one exponential: hz^3 underflows near the horizon in float32
    # (flushed to zero in vectorised code) where exp(-e) is zero too (0/0 otherwise)
    return ops.where(ok, ops.exp(-e - 3.0 * ops.log(z)) / (PI * ax * ay), 0.0)


def beckmann_reflected_pdf(ops, wi, wo, ax, ay):
    """Density of ``wo = reflect(wi, h)`` with ``h`` from :func:`beckmann_half_vector`:
    ``p_h(h) / (4 (wi.h))`` (change of measure ``d omega_o = 4 (wi.h) d omega_h``;
    Walter 2005), zero below the horizon."""
    return reflected_pdf(ops, wi, wo, lambda h: beckmann_half_vector_pdf(ops, ax, ay, h))


def reflected_pdf(ops, wi, wo, half_vector_pdf):
    """Density of ``wo = reflect(wi, h)`` when ``h`` has solid-angle density
    ``half_vector_pdf(h)``: ``p_h(h) / (4 (wi.h))`` with ``h`` the half vector
    of ``wi`` and ``wo`` (the change of measure ``d omega_o = 4 (wi.h) d omega_h``;
    Ashikhmin & Shirley 2000, journal eq. 8).  Zero unless ``wi.h > 0`` and both
    directions are above the horizon (``cos(theta) > HORIZON``, as for ``f`` and
    for the pdf that ``sample`` returns).  Generic in the half-vector distribution
    (used by the Schlick model; :func:`reflected_half_vector_pdf` is the same
    change of measure for the Ashikhmin-Shirley distribution).
    """
    h, kh = vec.half_vector_cos(ops, wi, wo)  # wi.h from |wi + wo| (exact at grazing)
    ok = (kh > 0) & (wo[2] > HORIZON) & (wi[2] > HORIZON)
    return ops.where(ok, half_vector_pdf(h) / (4.0 * ops.where(ok, kh, 1.0)), 0.0)


def ggx_d(ops, h, ax, ay):
    """The anisotropic GGX / Trowbridge-Reitz distribution of normals,
    ``D(h) = 1 / (pi ax ay ((hx/ax)^2 + (hy/ay)^2 + hz^2)^2)`` for ``hz > 0``, else 0
    (Walter et al., EGSR 2007, eq. 33; Heitz, JCGT 3(2), 2014, eq. 85 for the
    anisotropic form; glTF 2.0 Appendix B and KHR_materials_anisotropy).  For
    ``ax = ay = alpha`` it is the glTF form
    ``alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)``.  ``D(h) (n.h)`` integrates to
    one over the hemisphere.  With ``ax, ay <= 1`` and ``|h| = 1`` the bracket is
    at least 1, so ``D <= 1 / (pi ax ay)`` never overflows.
    """
    s = (h[0] / ax) ** 2 + (h[1] / ay) ** 2 + h[2] * h[2]
    ok = h[2] > 0
    s = ops.where(ok, s, 1.0)
    return ops.where(ok, 1.0 / (PI * ax * ay * s * s), 0.0)


def ggx_stretched_length(ops, w, ax, ay):
    """``|(ax wx, ay wy, wz)|``: ``wz sqrt(1 + tan^2 theta (ax^2 cos^2 phi + ay^2 sin^2 phi))``,
    so that GGX's Smith ``Lambda(w) = (|stretched w| / wz - 1) / 2`` (Heitz 2014, eq. 86)."""
    return ops.sqrt((ax * w[0]) ** 2 + (ay * w[1]) ** 2 + w[2] * w[2])


def ggx_visible_half_vector(ops, wi, ax, ay, u1, u2):
    """A half vector from GGX's distribution of normals visible from ``wi``,
    ``D_wi(h) = G1(wi) max(wi.h, 0) D(h) / wi.z`` (E. Heitz, "Sampling the GGX
    distribution of visible normals", JCGT 7(4), 2018, listing 1): stretch ``wi`` to
    the configuration ``ax = ay = 1``, sample the projected hemisphere (a disc whose
    half is squeezed by ``(1 + cos)/2``), lift the point onto the hemisphere, unstretch.
    ``wi.z`` must be positive (the caller rejects the rest)."""
    vx, vy, vz = ax * wi[0], ay * wi[1], wi[2]
    inv = 1.0 / ops.sqrt(vx * vx + vy * vy + vz * vz)
    vx, vy, vz = vx * inv, vy * inv, vz * inv
    # an orthonormal basis (t1, t2, v); t1 = (1, 0, 0) when v is the normal
    lensq = vx * vx + vy * vy
    pos = lensq > 0
    il = ops.where(pos, 1.0 / ops.sqrt(ops.where(pos, lensq, 1.0)), 0.0)
    t1 = (ops.where(pos, -vy * il, 1.0), ops.where(pos, vx * il, 0.0), 0.0 * vz)
    t2 = (vy * t1[2] - vz * t1[1], vz * t1[0] - vx * t1[2], vx * t1[1] - vy * t1[0])
    # a point of the unit disc, its upper half squeezed toward the v axis
    r = ops.sqrt(u1)
    phi = 2.0 * PI * u2
    p1 = r * ops.cos(phi)
    s = 0.5 * (1.0 + vz)
    p2 = (1.0 - s) * ops.sqrt(ops.maximum(1.0 - p1 * p1, 0.0)) + s * r * ops.sin(phi)
    p3 = ops.sqrt(ops.maximum(1.0 - p1 * p1 - p2 * p2, 0.0))
    nx = p1 * t1[0] + p2 * t2[0] + p3 * vx
    ny = p1 * t1[1] + p2 * t2[1] + p3 * vy
    nz = p1 * t1[2] + p2 * t2[2] + p3 * vz
    return vec.normalize(ops, (ax * nx, ay * ny, ops.maximum(nz, 0.0)))


def ggx_visible_reflected_pdf(ops, wi, wo, ax, ay):
    """Density of ``wo = reflect(wi, h)`` with ``h`` from :func:`ggx_visible_half_vector`:
    ``D_wi(h) / (4 wi.h)`` with ``G1(wi) = 2 wi.z / (wi.z + |stretched wi|)``
    (Heitz 2018, eq. 2 and 17), which simplifies to
    ``D(h) / (2 (wi.z + |stretched wi|))``; zero unless ``wi.h > 0`` and both
    directions are above the horizon."""
    h, kh = vec.half_vector_cos(ops, wi, wo)
    ok = (kh > 0) & (wo[2] > HORIZON) & (wi[2] > HORIZON)
    den = 2.0 * (wi[2] + ggx_stretched_length(ops, wi, ax, ay))
    return ops.where(ok, ggx_d(ops, h, ax, ay) / ops.where(ok, den, 1.0), 0.0)
