"""Blender (Cycles) from plausible: measure a Cycles material, convert into one.

* :func:`acquire` / :func:`check_material`: virtual acquisition of a Cycles material
  (a sphere, an orthographic camera, a sun of known irradiance, a white furnace;
  :mod:`.acquire`) into a measured BRDF (:class:`plausible.models.merl.MerlBRDF`) and a
  check report (reciprocity from swapped light and camera, energy from the furnace);
* :func:`principled_inputs`, :func:`node_script`, :func:`write_blender`: a plausible
  conversion (the glTF metallic-roughness fit) as a Principled BSDF (GGX), glTF's formula in
  nodes for a dielectric part, or a Lambertian plus Cook-Torrance source as its own lobes,
  written as a ``.blend`` or as a ``.py`` that builds the node tree (:mod:`.principled`);
* :func:`.looks.compare_cycles`, :func:`.looks.check_looks`: a Cycles material rendered in
  the scene of :func:`plausible.compare_looks` beside a source in Mitsuba and scored
  (HDR-FLIP, highlight ratio; :mod:`.looks`).

Blender runs out of process (:mod:`.runner`): ``bpy`` pins ``numpy<2`` and lives in
``.venv-blender``, which ``make setup`` makes.  See docs/blender.md.
"""

from .acquire import ANGLES, Acquisition, acquire, check_acquisition, material_spec
from .runner import BlenderUnavailable, blender_python

__all__ = ["ANGLES", "Acquisition", "BlenderUnavailable", "acquire", "blender_python", "check_acquisition",
           "check_material", "material_spec"]


def check_material(blend=None, material=None, *, principled=None, diffuse=None, script=None, quick=False,
                   tangent=False, progress=None):
    """``plausible check`` of a Cycles material: a material ``material`` of the ``.blend``
    file ``blend`` (or a dict of Principled BSDF inputs, a Diffuse colour, a node script;
    :func:`material_spec`), acquired (:func:`acquire`; ``quick``: 48 px, 5 angles; ``tangent``:
    :func:`.tangent.acquire_tangent`, for an anisotropic material, ``quick`` 48 px, 3 angles x 4
    turns) and checked (:func:`check_acquisition`).  Returns ``(report, acquisition)``."""
    spec = material_spec(blend, material, principled=principled, diffuse=diffuse, script=script)
    name = material or ("principled" if principled is not None else "diffuse" if diffuse is not None else "script")
    if tangent:
        from .tangent import acquire_tangent

        kw = dict(resolution=48, angles=(0, 40, 80), turns=(0, 45, 90, 135)) if quick else {}
        acq = acquire_tangent(spec, name=name, progress=progress, **kw)
        return check_acquisition(acq), acq
    kw = dict(resolution=48, angles=(0, 40, 80, 120, 160)) if quick else {}
    acq = acquire(spec, name=name, progress=progress, **kw)
    return check_acquisition(acq), acq
