"""Fresnel reflectance, shared by every model (one copy of each formula).

All functions take the cosine of the angle between the incident direction and
the microfacet normal (``k.h`` for half-vector models, ``n.k`` otherwise).
"""

from __future__ import annotations


def schlick(ops, cos_theta, r0):
    """Schlick's approximation ``F = R0 + (1 - R0)(1 - cos(theta))^5``.

    C. Schlick, "An inexpensive BRDF model for physically-based rendering",
    Computer Graphics Forum 13(3), 1994; used by Ashikhmin & Shirley 2000 (journal
    eq. 3, tech. report eq. 11).  ``cos_theta`` is clamped to ``[0, 1]``.
    """
    c = ops.minimum(ops.maximum(cos_theta, 0.0), 1.0)
    m = 1.0 - c
    m2 = m * m
    return r0 + (1.0 - r0) * (m2 * m2 * m)


def dielectric_polarized(ops, cos_i, eta):
    """Exact Fresnel reflectances ``(Rs, Rp)`` of a smooth dielectric interface.

    ``eta = n_t / n_i`` is the relative index of refraction (``eta < 1`` when the
    light arrives from the denser side); ``cos_i`` is clamped to ``[0, 1]``.
    Fresnel equations (Born & Wolf, *Principles of Optics*, sec. 1.5.2, eqs. 21):
    with ``cos_t = sqrt(1 - (1 - cos_i^2) / eta^2)``,
    ``rs = (cos_i - eta cos_t) / (cos_i + eta cos_t)``,
    ``rp = (eta cos_i - cos_t) / (eta cos_i + cos_t)``, ``Rs = rs^2``, ``Rp = rp^2``.
    Total internal reflection (``sin^2(theta_t) >= 1``) gives ``Rs = Rp = 1``.
    """
    c = ops.minimum(ops.maximum(cos_i, 0.0), 1.0)
    sin2_t = (1.0 - c * c) / (eta * eta)
    tir = sin2_t >= 1.0
    cos_t = ops.sqrt(ops.maximum(1.0 - sin2_t, 0.0))
    ds = c + eta * cos_t
    dp = eta * c + cos_t
    ok_s = ds > 0
    ok_p = dp > 0
    rs = ops.where(ok_s, (c - eta * cos_t) / ops.where(ok_s, ds, 1.0), 1.0)
    rp = ops.where(ok_p, (eta * c - cos_t) / ops.where(ok_p, dp, 1.0), 1.0)
    return ops.where(tir, 1.0, rs * rs), ops.where(tir, 1.0, rp * rp)


def dielectric(ops, cos_i, eta):
    """Unpolarised exact dielectric reflectance ``(Rs + Rp) / 2``
    (:func:`dielectric_polarized`); 1 under total internal reflection."""
    rs, rp = dielectric_polarized(ops, cos_i, eta)
    return 0.5 * (rs + rp)


def conductor_polarized(ops, cos_i, eta, k):
    """Exact Fresnel reflectances ``(Rs, Rp)`` of a conductor with complex index ``eta + i k``
    (relative to the outside medium), in real arithmetic.

    Standard form (e.g. Glassner, *Principles of Digital Image Synthesis*, 1995,
    sec. 13.4; pbrt-v3 ``FrConductor``): with ``c = cos_i`` and ``s^2 = 1 - c^2``,
    ``t0 = eta^2 - k^2 - s^2``, ``a^2 + b^2 = sqrt(t0^2 + 4 eta^2 k^2)``,
    ``a = sqrt((a^2 + b^2 + t0) / 2)``,
    ``Rs = (a^2 + b^2 + c^2 - 2 a c) / (a^2 + b^2 + c^2 + 2 a c)``,
    ``Rp = Rs (c^2 (a^2 + b^2) + s^4 - 2 a c s^2) / (c^2 (a^2 + b^2) + s^4 + 2 a c s^2)``.
    ``k = 0`` reduces to :func:`dielectric_polarized`; ``cos_i = 0`` gives 1.
    """
    c = ops.minimum(ops.maximum(cos_i, 0.0), 1.0)
    c2 = c * c
    s2 = 1.0 - c2
    n2 = eta * eta
    k2 = k * k
    t0 = n2 - k2 - s2
    a2pb2 = ops.sqrt(t0 * t0 + 4.0 * n2 * k2)
    a = ops.sqrt(ops.maximum(0.5 * (a2pb2 + t0), 0.0))
    t1 = a2pb2 + c2
    t2 = 2.0 * a * c
    ok1 = (t1 + t2) > 0
    rs = ops.where(ok1, (t1 - t2) / ops.where(ok1, t1 + t2, 1.0), 1.0)
    t3 = c2 * a2pb2 + s2 * s2
    t4 = t2 * s2
    ok3 = (t3 + t4) > 0
    rp = rs * ops.where(ok3, (t3 - t4) / ops.where(ok3, t3 + t4, 1.0), 1.0)
    return rs, rp


def conductor(ops, cos_i, eta, k):
    """Unpolarised exact conductor reflectance ``(Rs + Rp) / 2`` (:func:`conductor_polarized`).

    At normal incidence it equals ``((eta - 1)^2 + k^2) / ((eta + 1)^2 + k^2)``.
    """
    rs, rp = conductor_polarized(ops, cos_i, eta, k)
    return 0.5 * (rs + rp)


def cook(ops, cos_i, eta):
    """Unpolarised dielectric reflectance in Cook & Torrance's form (ACM TOG 1982, eq. in
    sec. "The Fresnel term"; bbm ``fresnel::cook``):
    ``F = (g - c)^2 / (2 (g + c)^2) (1 + ((c (g + c) - 1) / (c (g - c) + 1))^2)``,
    ``g = sqrt(eta^2 - 1 + c^2)``, with ``eta^2 - 1`` written ``(eta - 1)(eta + 1)`` so that
    ``eta = 1`` gives exactly 0 (``g = c``, also at ``c = 0``); ``g = 0`` under total
    internal reflection (``F = 1``).  Equal to :func:`dielectric` for ``eta >= 1``."""
    c = ops.minimum(ops.maximum(cos_i, 0.0), 1.0)
    g = ops.sqrt(ops.maximum((eta - 1.0) * (eta + 1.0) + c * c, 0.0))
    s = g + c
    ok = s > 0
    a = (g - c) / ops.where(ok, s, 1.0)
    den = c * (g - c) + 1.0
    okb = ops.abs(den) > 0
    b = (c * s - 1.0) / ops.where(okb, den, 1.0)
    # c = g = 0 (grazing, eta <= 1): 1 under total internal reflection (eta < 1), 0 at eta = 1
    grazing = ops.where((eta - 1.0) * (eta + 1.0) + 0.0 * c < 0.0, 1.0, 0.0)
    return ops.where(ok & okb, 0.5 * a * a * (1.0 + b * b), grazing)


#: Fresnel choices shared by the metal models (``fresnel=`` parameter).
FRESNEL_CHOICES = ("none", "schlick", "conductor")


def weight(ops, kind, cos_theta, rs, eta, k):
    """The Fresnel factor a model multiplies its lobe by, by name.

    ``"none"``: the constant ``rs`` (the papers' "Fresnel term is 1", scaled by
    the specular reflectance); ``"schlick"``: :func:`schlick` with ``R0 = rs``;
    ``"conductor"``: :func:`conductor` with index ``eta + i k`` (``rs`` unused).
    ``kind`` is a plain string (a Python branch on a parameter, not on arrays).
    """
    if kind == "none":
        return rs + 0.0 * cos_theta
    if kind == "schlick":
        return schlick(ops, cos_theta, rs)
    if kind == "conductor":
        return conductor(ops, cos_theta, eta, k)
    raise ValueError(f"fresnel must be one of {FRESNEL_CHOICES}, got {kind!r}")
