"""The Blender side of :mod:`plausible.blender`: a self-contained ``bpy`` script.

It runs in Blender's own interpreter (the ``.venv-blender`` that ``make setup``
makes: ``bpy`` pins ``numpy<2``, so it cannot share plausible's environment), in a
subprocess (a Blender crash does not take plausible down), and imports nothing of
plausible.  Usage::

    python worker.py JOB.json

``JOB.json``: ``{"material": SPEC, "renders": [RENDER, ...], "out": DIR,
"resolution": N, "spp": N, "save_blend": FILE or null}``.

``SPEC`` is one of

* ``{"blend": FILE, "name": NAME}``: a material of a ``.blend`` file (appended);
* ``{"script": FILE}``: a Python file defining ``build(bpy) -> material``
  (what ``plausible convert --to blender --out FILE.py`` writes; with ``"all": true``
  its ``build_all(bpy)``, every material; with ``"name"``, that one of them);
  any spec with ``"untextured": true`` has the links out of its Image Texture nodes
  removed (the uniform material they modulate);
* ``{"principled": {input name: value}}`` (lower-case keys are properties of the
  node: ``"distribution": "GGX"`` or ``"MULTI_GGX"``) or ``{"diffuse": [r, g, b]}``: a node
  tree of one Principled (or Diffuse) BSDF.

Each ``RENDER`` is ``{"kind": "sun", "light": [x, y, z], "camera": [x, y, z]}``
(world directions, unit, pointing away from the sphere; sun irradiance 1 W/m^2
perpendicular to its rays) or ``{"kind": "furnace", "camera": [x, y, z]}`` (a
uniform white world of radiance 1, no lamp).  The scene: a unit sphere at the
origin (a smooth UV sphere of 512 x 256 faces), an orthographic camera of
``ortho_scale`` 2.2 looking at it along ``-camera``, a black world (sun renders),
Cycles on the CPU with the "Standard" view transform, a box pixel filter of
width 0.01 pixel (each sample at the pixel centre, so a pixel is one normal),
no denoiser, one bounce (a convex sphere sees only the light and the world).
Each render writes ``DIR/render_K.npy``: float32 ``(resolution, resolution, 3)``
linear RGB, row 0 at the top of the image.
"""

import json
import math
import os
import sys

import bpy
import numpy as np

ORTHO_SCALE = 2.2
#: Exit status of a job whose input is wrong (a material not in the file): its last line says why.
BAD_INPUT = 3


def _bad_input(argument, why):
    """Stop with :data:`BAD_INPUT`, the last line of stderr ``ARGUMENT<TAB>why`` (the runner's ValueError)."""
    print(f"{argument}\t{why}", file=sys.stderr)
    raise SystemExit(BAD_INPUT)


def _material(spec):
    if "blend" in spec:
        with bpy.data.libraries.load(spec["blend"], link=False) as (src, dst):
            if spec["name"] not in src.materials:
                _bad_input("material", f"{spec['name']!r} is not in {spec['blend']} "
                                       f"(it has {', '.join(src.materials) or 'no materials'})")
            dst.materials = [spec["name"]]
        return dst.materials[0]
    if "script" in spec:
        ns = {"__name__": "plausible_material", "__file__": os.path.abspath(spec["script"])}
        with open(spec["script"]) as fh:
            exec(compile(fh.read(), spec["script"], "exec"), ns)
        if spec.get("all") or spec.get("name"):
            mats = ns["build_all"](bpy)
            return next((m for m in mats if m.name == spec.get("name")), mats[0])
        return ns["build"](bpy)
    mat = bpy.data.materials.new("plausible")
    mat.use_nodes = True
    nodes = mat.node_tree.nodes
    out = next(n for n in nodes if n.type == "OUTPUT_MATERIAL")
    for n in [n for n in nodes if n.name != out.name]:
        nodes.remove(n)
    if "diffuse" in spec:
        b = nodes.new("ShaderNodeBsdfDiffuse")
        b.inputs["Color"].default_value = list(spec["diffuse"]) + [1.0]
        b.inputs["Roughness"].default_value = 0.0
    else:
        b = nodes.new("ShaderNodeBsdfPrincipled")
        for k, v in spec["principled"].items():
            if k.islower():     # a property of the node (distribution, subsurface_method), not an input
                setattr(b, k, v)
            else:
                b.inputs[k].default_value = (list(v) + [1.0]) if isinstance(v, (list, tuple)) and len(v) == 3 else v
    mat.node_tree.links.new(b.outputs[0], out.inputs["Surface"])
    return mat


def _untextured(mat):
    """``mat`` with the links out of its Image Texture nodes removed: each socket they fed
    takes its own default (a Multiply mix its fitted colour, a Bump or Normal Map no
    relief), so the acquisition sees the uniform material the textures modulate."""
    tree = mat.node_tree
    for link in [k for k in tree.links if k.from_node.type == "TEX_IMAGE"]:
        tree.links.remove(link)
    return mat


def _look_at(obj, direction):
    """Place ``obj`` (camera or sun) along ``direction`` looking at the origin: its local
    ``+z`` along ``direction`` (it looks, or shines, along ``-z``), its ``+y`` (the image's
    up) toward world ``+y`` (world ``+x`` when ``direction`` is along ``y``), so a camera
    on ``+z`` has the world's ``x`` to the right and ``y`` up."""
    from mathutils import Matrix
    z = np.asarray(direction, dtype=float)
    z = z / np.linalg.norm(z)
    up = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.999 else np.array([1.0, 0.0, 0.0])
    x = np.cross(up, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    obj.matrix_world = Matrix([[x[0], y[0], z[0], 5 * z[0]], [x[1], y[1], z[1], 5 * z[1]],
                               [x[2], y[2], z[2], 5 * z[2]], [0, 0, 0, 1]])


def _sphere_mesh(segments, rings):
    """A smooth unit UV sphere (poles on z; ``bpy.ops.mesh.primitive_uv_sphere_add``
    takes 15 s at this size, this 0.2 s), with UVs (u along the azimuth) so that a
    tangent (anisotropy) follows the azimuth."""
    th = np.linspace(0.0, math.pi, rings + 1)[1:-1]
    ph = np.linspace(0.0, 2.0 * math.pi, segments, endpoint=False)
    T, P = np.meshgrid(th, ph, indexing="ij")
    v = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    v = np.vstack([v, [[0, 0, 1], [0, 0, -1]]])
    top, bottom = len(v) - 2, len(v) - 1
    idx = lambda r, s: r * segments + (s % segments)      # noqa: E731
    faces = [(top, idx(0, s + 1), idx(0, s)) for s in range(segments)]
    faces += [(idx(r, s), idx(r, s + 1), idx(r + 1, s + 1), idx(r + 1, s))
              for r in range(rings - 3 + 1) for s in range(segments)]
    faces += [(bottom, idx(rings - 2, s), idx(rings - 2, s + 1)) for s in range(segments)]
    mesh = bpy.data.meshes.new("sphere")
    mesh.from_pydata(v.tolist(), [], faces)
    mesh.shade_smooth()
    uv = mesh.uv_layers.new(name="UVMap")
    loops = np.empty(len(mesh.loops), dtype=np.int64)
    mesh.loops.foreach_get("vertex_index", loops)
    p = v[loops]
    u = (np.arctan2(p[:, 1], p[:, 0]) / (2 * math.pi)) % 1.0
    uv.data.foreach_set("uv", np.stack([u, np.arccos(np.clip(p[:, 2], -1, 1)) / math.pi], -1).ravel())
    mesh.validate()
    return mesh


def _scene(job, mat):
    scene = bpy.context.scene
    scene.render.engine = "CYCLES"
    scene.cycles.device = "CPU"
    scene.cycles.samples = int(job["spp"])
    scene.cycles.use_adaptive_sampling = False
    scene.cycles.use_denoising = False
    scene.cycles.max_bounces = 1
    scene.cycles.pixel_filter_type = "BOX"
    scene.cycles.filter_width = 0.01
    scene.cycles.seed = int(job.get("seed", 0))
    scene.render.resolution_x = scene.render.resolution_y = int(job["resolution"])
    scene.render.resolution_percentage = 100
    scene.render.threads_mode = "FIXED"
    scene.render.threads = int(job.get("threads", 1))
    scene.view_settings.view_transform = "Standard"
    scene.view_settings.look = "None"
    scene.view_settings.exposure = 0.0
    scene.view_settings.gamma = 1.0
    scene.render.image_settings.file_format = "OPEN_EXR"
    scene.render.image_settings.color_depth = "32"
    sphere = bpy.data.objects.new("sphere", _sphere_mesh(512, 256))
    scene.collection.objects.link(sphere)
    sphere.data.materials.append(mat)
    cam = bpy.data.objects.new("camera", bpy.data.cameras.new("camera"))
    cam.data.type = "ORTHO"
    cam.data.ortho_scale = ORTHO_SCALE
    scene.collection.objects.link(cam)
    scene.camera = cam
    world = bpy.data.worlds.new("world")
    scene.world = world
    world.use_nodes = True
    sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", type="SUN"))
    sun.data.angle = 0.0
    sun.data.energy = 1.0
    scene.collection.objects.link(sun)
    return scene, cam, sun, world


def _world(world, strength):
    bg = world.node_tree.nodes["Background"]
    bg.inputs["Color"].default_value = (1.0, 1.0, 1.0, 1.0)
    bg.inputs["Strength"].default_value = float(strength)


def _render(scene, path):
    scene.render.filepath = path
    bpy.ops.render.render(write_still=True)
    img = bpy.data.images.load(path)
    w, h = img.size
    px = np.empty(w * h * 4, dtype=np.float32)
    img.pixels.foreach_get(px)
    bpy.data.images.remove(img)
    os.remove(path)
    return px.reshape(h, w, 4)[::-1, :, :3].copy()     # Blender's rows start at the bottom


def main(job_path):
    with open(job_path) as fh:
        job = json.load(fh)
    bpy.ops.wm.read_factory_settings(use_empty=True)
    if "blend" in job["material"] and not os.path.isfile(job["material"]["blend"]):
        _bad_input("blend", f"no such file {job['material']['blend']!r}")
    mat = _material(job["material"])
    if job["material"].get("untextured"):
        _untextured(mat)
    mat.use_fake_user = True
    scene, cam, sun, world = _scene(job, mat)
    for k, r in enumerate(job["renders"]):
        _look_at(cam, r["camera"])
        furnace = r["kind"] == "furnace"
        sun.hide_render = furnace
        _world(world, 1.0 if furnace else 0.0)
        if not furnace:
            _look_at(sun, r["light"])
        np.save(os.path.join(job["out"], f"render_{k}.npy"),
                _render(scene, os.path.join(job["out"], f"render_{k}.exr")))
    if job.get("save_blend"):
        for o in list(bpy.data.objects):
            bpy.data.objects.remove(o)
        bpy.ops.wm.save_as_mainfile(filepath=job["save_blend"])
        bpy.ops.file.make_paths_relative()          # the textures beside the .blend, wherever it goes
        bpy.ops.wm.save_as_mainfile(filepath=job["save_blend"])


if __name__ == "__main__":
    main(sys.argv[1])
