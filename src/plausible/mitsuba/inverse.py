"""Inverse rendering with the plugins: recover BSDF parameters from a reference
image by gradient descent (Adam in ``mi.ad``) through the ``prb`` integrator.

Two steps, each usable alone:

* :func:`sphere_scene` -- a sphere with the BSDF under test, lit by point
  lights, seen by a perspective camera, rendered by ``prb`` (direct light only:
  the image depends on the parameters through ``eval``, and the only noise is
  the pixel jitter);
* :func:`fit` -- Adam on the named parameters of the sphere's BSDF, starting
  from given values, minimising the mean squared difference to a reference
  image.  Exponent-like parameters (upper bound above 100) are optimised in
  ``log`` space, so a step is a relative change whatever their size; each step
  is clamped to the parameter's range, so ``params.update()`` never refuses it.

``examples/mitsuba_inverse_rendering.py`` runs both on Ashikhmin-Shirley;
``docs/mitsuba.md`` gives the measured iterations and times.

Reference: Nimier-David et al., "Mitsuba 2: a retargetable forward and inverse
renderer", SIGGRAPH Asia 2019; Vicini et al., "Path replay backpropagation",
SIGGRAPH 2021 (``prb``).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field

import numpy as np

from . import load_dict


def sphere_scene(bsdf: dict, res: int = 32, spp: int = 4):
    """A unit sphere seen from ``+x`` (its shading tangent ``sh_frame.s`` runs
    around the ``z`` axis, horizontally in the image), lit by two point lights
    that give two highlights; ``prb`` with ``max_depth = 2``.  Loaded by
    :func:`plausible.mitsuba.load_dict` (a plugin not registered in the current
    variant: the error says to call ``register()`` again)."""
    import mitsuba as mi

    return load_dict({
        "type": "scene",
        "integrator": {"type": "prb", "max_depth": 2},
        "sensor": {"type": "perspective", "fov": 35,
                   "to_world": mi.ScalarTransform4f().look_at(origin=[4, 0, 0], target=[0, 0, 0],
                                                              up=[0, 0, 1]),
                   "film": {"type": "hdrfilm", "width": res, "height": res,
                            "rfilter": {"type": "box"}, "pixel_format": "rgb"},
                   "sampler": {"type": "independent", "sample_count": spp}},
        "sphere": {"type": "sphere", "bsdf": bsdf},
        "key": {"type": "point", "position": [4.0, 1.0, 1.0], "intensity": {"type": "rgb", "value": 30.0}},
        "fill": {"type": "point", "position": [3.0, -2.0, -0.5], "intensity": {"type": "rgb", "value": 15.0}},
    })


@dataclass
class FitResult:
    """What :func:`fit` found.

    ``values``: the recovered parameters; ``history``: ``(loss, values)`` per
    iteration; ``iterations`` and ``seconds``: the work it took.
    """

    values: dict
    iterations: int
    seconds: float
    history: list = field(default_factory=list)


def fit(scene, reference, start: dict, *, iterations: int = 100, lr: float = 0.05,
        spp: int | None = None, progress=None) -> FitResult:
    """Adam on the sphere's BSDF parameters ``start`` (``{name: initial value}``;
    names as in ``mi.traverse`` of the plugin) so that ``scene`` renders like
    ``reference`` (an image of the same size).

    Loss: mean squared difference of the images.  Exponent-like parameters are
    optimised as ``log(value)``; every value is clamped to its range after each
    step.  ``progress`` (optional): a factory ``progress(total) -> tick``; ``tick()``
    is called once per iteration.
    """
    import drjit as dr
    import mitsuba as mi

    params = mi.traverse(scene)
    prefix = _bsdf_prefix(params)
    plugin_params = _param_specs(scene)
    opt = mi.ad.Adam(lr=lr)
    logs = {k for k in start if plugin_params[k].hi > 100.0}
    for k, v in start.items():
        opt[k] = mi.Float(math.log(v) if k in logs else v)

    def apply():
        for k in start:
            prm = plugin_params[k]
            x = dr.exp(opt[k]) if k in logs else opt[k]
            params[prefix + k] = dr.clip(x, max(prm.lo, 1e-6 if k in logs else prm.lo), prm.hi)
        params.update()

    tick = progress(iterations) if progress is not None else None
    ref = mi.TensorXf(reference)
    history = []
    t0 = time.perf_counter()
    apply()
    for it in range(iterations):
        opt.set_learning_rate(lr * 0.1 ** (it / iterations))  # decays to lr / 10
        img = mi.render(scene, params, seed=0, spp=spp or 0)
        loss = dr.mean(dr.ravel(dr.square(img - ref)))
        dr.backward(loss)
        opt.step()
        if any(k in logs for k in start):
            for k in logs:  # keep log-exponents within the range
                prm = plugin_params[k]
                opt[k] = dr.clip(opt[k], math.log(max(prm.lo, 1e-6)), math.log(prm.hi))
        apply()
        history.append((float(loss[0]), _values(params, prefix, start)))
        if tick is not None:
            tick()
    return FitResult(_values(params, prefix, start), iterations, time.perf_counter() - t0, history)


def _bsdf_prefix(params) -> str:
    keys = [k for k in params.keys() if ".bsdf." in k]
    if not keys:
        raise ValueError("inverse.fit: the scene has no shape with a BSDF in mi.traverse")
    return keys[0].split(".bsdf.")[0] + ".bsdf."


def _param_specs(scene) -> dict:
    """``{name: Param}`` of the sphere's plausible BSDF."""
    for shape in scene.shapes():
        info = getattr(shape.bsdf(), "INFO", None)
        if info is not None:
            return {p.name: p for p in info.params}
    raise ValueError("inverse.fit: the scene has no plausible BSDF")


def _values(params, prefix, names) -> dict:
    return {k: float(np.array(params[prefix + k])[0]) for k in names}


def relative_errors(found: dict, truth: dict) -> dict:
    """``{name: |found - truth| / |truth|}``."""
    return {k: abs(found[k] - truth[k]) / abs(truth[k]) for k in truth}


__all__ = ["sphere_scene", "fit", "FitResult", "relative_errors"]
