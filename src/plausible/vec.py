"""Component-wise vector helpers shared by every model (one copy of each).

A direction is a 3-tuple ``(x, y, z)`` of scalar-like arrays in the local shading
frame: ``z`` is the normal ``n``, ``x`` the first tangent ``u`` and ``y`` the
second tangent ``v``.
"""

from __future__ import annotations


def dot(a, b):
    """Scalar product ``a . b``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def normalize(ops, a):
    """``a / |a|``; a zero vector stays zero (never NaN)."""
    n2 = dot(a, a)
    inv = ops.where(n2 > 0, 1.0 / ops.sqrt(ops.where(n2 > 0, n2, 1.0)), 0.0)
    return scale(a, inv)


def mirror(a):
    """Mirror direction of ``a`` about the normal ``z``: ``2 (n.a) n - a``."""
    return (-a[0], -a[1], a[2])


def reflect(a, h):
    """Reflection of ``a`` about the unit vector ``h``: ``-a + 2 (a.h) h``
    (Ashikhmin & Shirley 2000, eq. 7 of the journal version)."""
    d = 2.0 * dot(a, h)
    return (d * h[0] - a[0], d * h[1] - a[1], d * h[2] - a[2])


def half_vector(ops, a, b):
    """Normalised half vector ``h = (a + b) / |a + b|``."""
    return normalize(ops, (a[0] + b[0], a[1] + b[1], a[2] + b[2]))


def half_vector_cos(ops, a, b):
    """``(h, a.h)`` for unit vectors ``a`` and ``b``: the half vector
    ``h = (a + b) / |a + b|`` and the cosine of the half angle,
    ``a.h = b.h = |a + b| / 2``.

    The cosine is taken from the length of ``a + b``, not from a dot product:
    at grazing incidence ``a.h`` is a sum of terms of size ``|a|`` that cancel
    to ``|a + b| / 2`` (in float32 the rounding of ``a`` alone, about 6e-8,
    exceeds ``a.h`` once ``|a + b| < 1e-4`` and ``a.h`` comes out with any sign),
    while ``|a + b|`` keeps its relative accuracy.  It is exactly symmetric in
    ``a`` and ``b``, and for ``b = reflect(a, h)`` it is the ``a.h`` the sampler
    used (``a + b = 2 (a.h) h``), so a density and a BRDF that both use it agree
    to rounding at every angle.  A zero ``a + b`` gives ``h = 0`` and ``0``.
    """
    s = (a[0] + b[0], a[1] + b[1], a[2] + b[2])
    n2 = dot(s, s)
    pos = n2 > 0
    n = ops.sqrt(ops.where(pos, n2, 1.0))
    inv = ops.where(pos, 1.0 / n, 0.0)
    return scale(s, inv), ops.where(pos, 0.5 * n, 0.0)


def frame(ops, n):
    """Orthonormal basis ``(s, t)`` completing the unit vector ``n``.

    Branchless construction of Duff et al., "Building an Orthonormal Basis,
    Revisited", JCGT 6(1), 2017.  Continuous except across ``n.z == 0`` with
    ``n`` on the negative side, which is where the sign flips.
    """
    sign = ops.where(n[2] >= 0, 1.0, -1.0)
    a = -1.0 / (sign + n[2])
    b = n[0] * n[1] * a
    s = (1.0 + sign * n[0] * n[0] * a, sign * b, -sign * n[0])
    t = (b, sign + n[1] * n[1] * a, -n[1])
    return s, t


def to_world(local, s, t, n):
    """Express ``local`` given in the basis ``(s, t, n)`` in the shading frame."""
    return (
        local[0] * s[0] + local[1] * t[0] + local[2] * n[0],
        local[0] * s[1] + local[1] * t[1] + local[2] * n[1],
        local[0] * s[2] + local[1] * t[2] + local[2] * n[2],
    )
