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
