"""Direction pairs and comparisons shared by the GLSL export tests."""

from __future__ import annotations

import math

import numpy as np
from conftest import random_upper

#: Relative error allowed against NumPy where f is above ``FLOOR`` of its maximum (float32 shaders).
RTOL = 1e-4
FLOOR = 1e-6


def _unit(v):
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _rotate_towards(w, rng, angles):
    """``w`` (unit rows) turned by ``angles`` (radians) about random perpendicular axes."""
    t = _unit(np.cross(w, _unit(rng.normal(size=w.shape))))
    return _unit(w * np.cos(angles)[:, None] + t * np.sin(angles)[:, None])


def direction_pairs(seed: int = 7, n: int = 4096):
    """``n`` pairs ``(wi, wo)`` as float32 values (the shader's inputs): random
    pairs over the hemisphere (a few below it), grazing ``wi`` and ``wo``
    (``cos`` down to 1e-5), the exact mirror direction, near-mirror pairs
    ``1e-4`` to ``0.3`` rad away (the peak of lobes with exponents up to 1e4)
    and near-normal pairs."""
    rng = np.random.default_rng(seed)
    q = n // 8
    wi, wo = [], []
    wi.append(random_upper(rng, 3 * q)); wo.append(random_upper(rng, 3 * q))            # random
    wo[-1][: q // 8, 2] *= -1.0                                                # some below the horizon
    g = random_upper(rng, q, 1e-5, 0.02)
    wi.append(g); wo.append(random_upper(rng, q))                                   # grazing wi
    wi.append(random_upper(rng, q // 2)); wo.append(random_upper(rng, q // 2, 1e-5, 0.02))  # grazing wo
    m = random_upper(rng, q // 2)
    wi.append(m); wo.append(m * np.array([-1.0, -1.0, 1.0]))                  # the mirror direction
    m = random_upper(rng, 2 * q, 0.05, 1.0)
    ang = np.exp(rng.uniform(math.log(1e-4), math.log(0.3), 2 * q))
    wi.append(m); wo.append(_rotate_towards(m * np.array([-1.0, -1.0, 1.0]), rng, ang))  # near mirror
    k = n - sum(len(a) for a in wi)
    m = random_upper(rng, k, 0.95, 1.0)
    wi.append(m); wo.append(random_upper(rng, k, 0.95, 1.0))                        # near the normal
    wi = np.concatenate(wi).astype(np.float32)
    wo = np.concatenate(wo).astype(np.float32)
    return wi, wo


def relative_errors(got, ref):
    """``|got - ref| / max(|ref|, FLOOR max|ref|)`` per value (the criterion of the
    export tests: relative where f is above ``FLOOR`` of its maximum, absolute
    ``FLOOR max|ref|``-relative below)."""
    ref = np.asarray(ref, dtype=np.float64)
    scale = np.maximum(np.abs(ref), FLOOR * max(float(np.max(np.abs(ref))), 1e-300))
    return np.abs(np.asarray(got, dtype=np.float64) - ref) / scale
