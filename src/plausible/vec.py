"""Component-wise vector helpers shared by every model (one copy of each).

A direction is a 3-tuple ``(x, y, z)`` of scalar-like arrays in the local shading
frame: ``z`` is the normal ``n``, ``x`` the first tangent ``u`` and ``y`` the
second tangent ``v``.
"""

from __future__ import annotations

import math

#: Directions with ``cos(theta) <= HORIZON`` count as on the horizon (f = 0).
#: Models that divide by ``cos(theta)`` (original Phong/Blinn, Ward, Cook-Torrance
#: with G = 1) would otherwise overflow for denormal cosines.
HORIZON = 1e-12


def above(ops, wi, wo):
    """Both directions above the horizon (``cos(theta) > HORIZON``)."""
    return (wi[2] > HORIZON) & (wo[2] > HORIZON)


def dot(a, b):
    """Scalar product ``a . b``."""
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


def scale(a, s):
    return (a[0] * s, a[1] * s, a[2] * s)


def normalize(ops, a, divide: bool = False):
    """``a / |a|``; a zero vector stays zero (never NaN).

    ``divide=True`` divides each component by ``|a|`` instead of multiplying it by ``1 / |a|``:
    for a direction that a kernel both returns and goes on using (a BSDF's sampled ``wo``, whose
    density the same kernel computes).  On CUDA the PTX assembler may contract a product into a
    following sum (``fma``, one rounding), so ``wi + wo`` in the sampling kernel would see the
    unrounded ``wo`` while ``pdf()`` sees the stored one; at grazing incidence, where ``|wi + wo|``
    is a few float32 units of ``wo``, that changed the half vector and the density 400-fold
    (measured on an H200, docs/backends.md).  A quotient is never contracted."""
    n2 = dot(a, a)
    pos = n2 > 0
    if divide:
        n = ops.sqrt(ops.where(pos, n2, 1.0))
        return tuple(ops.where(pos, c / n, 0.0) for c in a)
    inv = ops.where(pos, 1.0 / ops.sqrt(ops.where(pos, n2, 1.0)), 0.0)
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


# -- angles <-> directions (NumPy; the library's angles are radians) -----------------

def direction(theta, phi=0.0):
    """Unit vector(s) with polar angle ``theta`` from the normal and azimuth
    ``phi`` from the tangent ``x``, both in **radians** (the unit of every
    library function; degrees only where a name says ``_deg``, and on the
    command line).  Arrays broadcast: shape ``broadcast(theta, phi) + (3,)``.
    Inverse: :func:`angles`.

    ``theta`` must lie in ``[0, pi]``: a larger value is refused as likely
    degrees (write ``math.radians(30)``).

    >>> direction(0.0)
    array([0., 0., 1.])
    """
    import numpy as np

    try:
        t = np.asarray(theta, dtype=np.float64)
        p = np.asarray(phi, dtype=np.float64)
    except (TypeError, ValueError):     # a string, None, a ragged list: NumPy's "could not convert"
        raise ValueError(f"theta and phi must be angles in radians (numbers or arrays of them), got "
                         f"theta={theta!r}, phi={phi!r}") from None
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))):
        raise ValueError(f"theta and phi must be finite angles in radians, got theta={theta!r}, phi={phi!r}")
    if np.any(t < 0) or np.any(t > math.pi):
        bad = float(t[(t < 0) | (t > math.pi)].flat[0])
        hint = f" (degrees? use math.radians({bad:g}) = {math.radians(bad):.6g})" if bad > math.pi else ""
        raise ValueError(f"theta must be a polar angle in radians, within [0, pi], got {bad:g}{hint}")
    s = np.sin(t)
    out = np.stack(np.broadcast_arrays(s * np.cos(p), s * np.sin(p), np.cos(t)), axis=-1)
    return out


def angles(w):
    """``(theta, phi)`` in radians of direction(s) ``w`` (shape ``(..., 3)``, any
    length): ``theta`` in ``[0, pi]`` from the normal, ``phi`` in ``(-pi, pi]``
    from the tangent ``x`` (0 on the normal).  Inverse of :func:`direction`.

    >>> [round(float(a), 12) for a in angles(direction(0.5, 1.0))]
    [0.5, 1.0]
    """
    import numpy as np

    u = np.asarray(w, dtype=np.float64)
    if u.ndim == 0 or u.shape[-1] != 3:
        raise ValueError(f"w must be direction(s) of shape (..., 3), got shape {u.shape}")
    r = np.sqrt(u[..., 0] ** 2 + u[..., 1] ** 2 + u[..., 2] ** 2)
    if not np.all(np.isfinite(r)) or np.any(r == 0):
        raise ValueError("w must be finite, non-zero vectors (a zero vector has no direction)")
    theta = np.arccos(np.clip(u[..., 2] / r, -1.0, 1.0))
    phi = np.arctan2(u[..., 1], u[..., 0])
    if u.ndim == 1:
        return float(theta), float(phi)
    return theta, phi
