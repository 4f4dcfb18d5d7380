"""Cycles beside Mitsuba, where the user looks: the scene of ``compare_looks`` rendered in both.

:func:`plausible.compare_looks` (:mod:`plausible.mitsuba.looks`) judges a conversion by two
renders of one scene in Mitsuba: a unit sphere, orthographic views at light-camera angles
0, 60, 120 and 150 degrees (mirror incidence 0, 30, 60, 75: grazing included), lit by an
environment (sky ``0.5 + y`` over a dark ground of 0.1, a sharp horizon) and, apart, by a
lamp of angular radius 5 degrees and irradiance ``pi``.  :func:`cycles_renders` renders the
**same scene in Cycles** (the worker's ``looks`` job, :mod:`.worker`): the same sphere
(a smooth 512 x 256 mesh), cameras (orthographic, half-width 1.05, the views side by side),
the same environment map (its rows from :func:`plausible.mitsuba.looks.environment`, an
equirectangular image, bilinear), a sun of the same angular radius and irradiance (Cycles'
sun strength is W/m^2 perpendicular to its rays), a box filter one pixel wide, one bounce,
the background black; the light image at ``LIGHT_SPP`` times the samples, as Mitsuba's.
The images come back as a :class:`plausible.mitsuba.looks.Renders`, and
:func:`compare_cycles` scores a Mitsuba source against a Cycles material with
:func:`plausible.mitsuba.looks.compare_renders` (mean HDR-FLIP over the views and the
highlight ratio: the same functions as ``compare_looks``).

The comparison's floor is measured on a material known exactly on both sides (Cycles'
Diffuse BSDF against Mitsuba's ``diffuse``, f = rd / pi; docs/blender.md):
:func:`check_looks` passes a pair whose FLIP is at most :data:`FLIP_TOL` and whose highlight
ratios are within the band, and fails otherwise (a deliberately wrong material fails:
tests/blender/test_cycles_looks.py).

References: Andersson et al., "FLIP: A Difference Evaluator for Alternating Images", 2020,
and "Visualizing Errors in Rendered High Dynamic Range Images", 2021 (HDR-FLIP); Blender
manual, "Light Objects: Sun" (strength in W/m^2, angle the sun's angular diameter).
"""

from __future__ import annotations

import time
import types

import numpy as np

from ..analysis.checks import PropertyResult
from ..mitsuba import looks as L
from . import runner

__all__ = ["FLIP_TOL", "check_looks", "compare_cycles", "cycles_renders"]

#: Largest mean HDR-FLIP a pair that is the same material on both sides may show: the floor of
#: the comparison (Cycles' Diffuse against Mitsuba's diffuse: 0.027-0.032 at 64 px, 16 spp; 0.012-0.015
#: at 64 spp: the two renderers' Monte Carlo noise under the environment; docs/blender.md), with a margin.
FLIP_TOL = 0.05
#: Columns of the environment map (it is constant along the azimuth).
ENV_WIDTH = 128


def _env_rows(width: int = ENV_WIDTH) -> list:
    """The rows (top first) of :func:`plausible.mitsuba.looks.environment`'s map, from that function."""
    img = L.environment(types.SimpleNamespace(Bitmap=np.asarray), width)
    return [float(v) for v in img[:, 0, 0]]


def cycles_renders(material: dict, *, angles=L.LIGHT_ANGLES, res: int = L.RES, spp: int = L.SPP,
                   seed: int = 0) -> L.Renders:
    """The :class:`~plausible.mitsuba.looks.Renders` of a Cycles ``material`` (a worker spec,
    :func:`plausible.blender.material_spec`) in ``compare_looks``' scene (module docstring):
    ``len(angles)`` views of ``res`` pixels, ``spp`` samples per pixel under the environment and
    ``LIGHT_SPP`` times that under the lamp.  ValueError naming the option for a bad one."""
    L._check_options(angles, res, spp)
    angles = tuple(float(a) for a in angles)
    renders = [{"kind": "look_env", "angle": a} for a in angles] + [{"kind": "look_light", "angle": a} for a in angles]
    look = dict(half_width=L.HALF_WIDTH, env_rows=_env_rows(), env_width=ENV_WIDTH, lamp_deg=L.LAMP_DEG,
                irradiance=L.IRRADIANCE, light_spp=int(spp) * L.LIGHT_SPP)
    imgs = runner.run_job(material, renders, resolution=res, spp=spp, seed=seed, looks=look)
    k = len(angles)
    return L.Renders(np.concatenate(imgs[:k], axis=1).astype(np.float32),
                     np.concatenate(imgs[k:], axis=1).astype(np.float32), angles)


def compare_cycles(source, material: dict, *, angles=L.LIGHT_ANGLES, res: int = L.RES, spp: int = L.SPP,
                   seed: int = 0, band=L.HIGHLIGHT_BAND) -> L.Looks:
    """``source`` (anything ``compare_looks`` reads: a model, a spec, a Mitsuba dict) rendered in
    Mitsuba, the Cycles ``material`` in the same scene, scored by ``compare_looks``' functions
    (the source is FLIP's reference; the highlight ratio is Cycles' peak over Mitsuba's)."""
    t0 = time.perf_counter()
    a = L.render_looks(source, angles=angles, res=res, spp=spp, seed=seed)
    b = cycles_renders(material, angles=angles, res=res, spp=spp, seed=seed)
    looks = L.compare_renders(a, b, band)
    looks.seconds = time.perf_counter() - t0
    return looks


def check_looks(looks: L.Looks, flip_max: float = FLIP_TOL) -> PropertyResult:
    """Whether a Cycles material renders like its Mitsuba source: the mean HDR-FLIP at most
    ``flip_max`` (default :data:`FLIP_TOL`, the comparison's floor with a margin) and every
    highlight ratio within the looks' band.  The worst view and ratio are in ``worst``."""
    if not (isinstance(flip_max, (int, float)) and 0.0 < flip_max <= 1.0):
        raise ValueError(f"flip_max: a mean HDR-FLIP in (0, 1], got {flip_max!r}")
    k = int(np.argmax(looks.flips))
    passed = looks.flip <= flip_max and looks.ok
    bound = f"FLIP <= {flip_max:g}, highlight ratio in {looks.band[0]:.3g}-{looks.band[1]:.3g}"
    worst = {"flip_view_deg": looks.angles[k], "flip_view": looks.flips[k], "highlight_ratio": looks.highlight_ratio}
    return PropertyResult("looks", bool(passed), float(looks.flip), bound, worst,
                          {"flips": list(looks.flips), "highlight_ratios": list(looks.highlight_ratios),
                           "warnings": list(looks.warnings), "summary": looks.summary()})
