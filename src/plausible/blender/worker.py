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
perpendicular to its rays; an optional ``"sphere": 3 x 3`` turns the sphere, world from
object, and with it its tangent field) or ``{"kind": "furnace", "camera": [x, y, z]}`` (a
uniform white world of radiance 1, no lamp).  The scene: a unit sphere at the
origin (a smooth UV sphere of 512 x 256 faces), an orthographic camera of
``ortho_scale`` 2.2 looking at it along ``-camera``, a black world (sun renders),
Cycles on the CPU with the "Standard" view transform, a box pixel filter of
width 0.01 pixel (each sample at the pixel centre, so a pixel is one normal),
no denoiser, one bounce (a convex sphere sees only the light and the world).
Each render writes ``DIR/render_K.npy``: float32 ``(resolution, resolution, 3)``
linear RGB, row 0 at the top of the image.

A job with ``"looks": {...}`` renders instead the scene of ``plausible.compare_looks``
(``plausible.mitsuba.looks``), in Blender's axes: Mitsuba's ``(x, y, z)`` is Blender's
``(x, -z, y)`` (Mitsuba's up, ``+y``, is Blender's ``+z``).  Keys: ``half_width`` (the
orthographic half-width, 1.05), ``env_rows`` (the environment map's rows, top first, each
one radiance; constant along the azimuth), ``env_width``, ``lamp_deg`` (the lamp's angular
radius), ``irradiance`` and ``light_spp``.  Its ``RENDER`` s are ``{"kind": "look_env" or
"look_light", "angle": a}``: the camera at ``a`` degrees from the lamp (Mitsuba's camera at
``5 (sin a, 0, cos a)``, up ``+y``), the unit sphere lit by the environment alone
(``look_env``) or by a sun of angular radius ``lamp_deg`` and strength ``irradiance``
from Mitsuba's ``+z`` alone (``look_light``, at ``light_spp`` samples), the background
transparent (black, as Mitsuba's ``hide_emitters``), a box filter one pixel wide, the
sphere turned so that its pole and UV tangent are those of Mitsuba's sphere (pole on
Mitsuba's ``+z``, tangent ``dp/du`` along the azimuth).
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


def _look_at(obj, direction, up=None):
    """Place ``obj`` (camera or sun) along ``direction`` looking at the origin: its local
    ``+z`` along ``direction`` (it looks, or shines, along ``-z``), its ``+y`` (the image's
    up) toward world ``+y`` (world ``+x`` when ``direction`` is along ``y``), so a camera
    on ``+z`` has the world's ``x`` to the right and ``y`` up."""
    from mathutils import Matrix
    z = np.asarray(direction, dtype=float)
    z = z / np.linalg.norm(z)
    if up is None:
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


def _turn(sphere, rotation):
    """The sphere turned by ``rotation`` (3 x 3, world from object; None: not turned).  The
    sphere is the same, its default tangent (Cycles' radial tangent about the object's ``z``,
    and the UV map's ``dp/du``) turns with it: ``t = Q z x n`` at the normal ``n``."""
    from mathutils import Matrix
    q = np.eye(3) if rotation is None else np.asarray(rotation, dtype=float)
    sphere.matrix_world = Matrix([list(q[0]) + [0.0], list(q[1]) + [0.0], list(q[2]) + [0.0], [0, 0, 0, 1]])


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


def _blender_axes(v):
    """Mitsuba's ``(x, y, z)`` in Blender's axes: ``(x, -z, y)``."""
    return [v[0], -v[2], v[1]]


def _env_image(look):
    """The environment map as a float image (Blender's rows start at the bottom: Mitsuba's last row)."""
    rows = np.asarray(look["env_rows"], dtype=np.float32)[::-1]
    w, h = int(look["env_width"]), len(rows)
    img = bpy.data.images.new("plausible_env", w, h, alpha=False, float_buffer=True)
    img.colorspace_settings.name = "Non-Color"          # the values are scene-linear radiance as they are
    px = np.ones((h, w, 4), dtype=np.float32)
    px[..., :3] = rows[:, None, None]
    img.pixels.foreach_set(px.ravel())
    img.pack()
    return img


def _looks_scene(job, mat):
    """The scene of ``compare_looks`` (module docstring), from the acquisition's scene."""
    look = job["looks"]
    scene, cam, sun, world = _scene(job, mat)
    scene.render.film_transparent = True                # the background black, as Mitsuba's hide_emitters
    scene.cycles.filter_width = 1.0                     # Mitsuba's box filter of radius 0.5 pixel
    scene.cycles.sample_clamp_direct = scene.cycles.sample_clamp_indirect = 0.0
    scene.cycles.light_sampling_threshold = 0.0
    scene.cycles.blur_glossy = 0.0
    scene.render.use_persistent_data = True             # the scene synced once: 0.6 s a render after the first, not 2.5
    cam.data.ortho_scale = 2.0 * float(look["half_width"])
    sphere = scene.objects["sphere"]
    sphere.shadow_terminator_geometry_offset = 0.0      # an analytic sphere in Mitsuba: no terminator fix
    sphere.rotation_euler = (math.pi / 2, 0.0, 0.0)     # its local axes Mitsuba's sphere's: the pole on Mitsuba's
    #                                                     +z, the UV tangent (u along the azimuth) its dp/du
    sun.data.angle = 2.0 * math.radians(float(look["lamp_deg"]))
    sun.data.energy = float(look["irradiance"])
    _look_at(sun, _blender_axes([0.0, 0.0, 1.0]), up=np.array([0.0, 0.0, 1.0]))
    nodes, links = world.node_tree.nodes, world.node_tree.links
    env = nodes.new("ShaderNodeTexEnvironment")
    env.image, env.interpolation, env.projection = _env_image(look), "Linear", "EQUIRECTANGULAR"
    links.new(env.outputs["Color"], nodes["Background"].inputs["Color"])
    world.cycles.sampling_method = "MANUAL"             # importance map at the map's size, built once
    world.cycles.sample_map_resolution = int(look["env_width"])   # (AUTOMATIC: about 2 s a render)
    return scene, cam, sun, world


def _looks(job, mat):
    scene, cam, sun, world = _looks_scene(job, mat)
    look = job["looks"]
    for k, r in enumerate(job["renders"]):
        a = math.radians(float(r["angle"]))
        _look_at(cam, _blender_axes([math.sin(a), 0.0, math.cos(a)]), up=np.array([0.0, 0.0, 1.0]))
        light = r["kind"] == "look_light"
        sun.hide_render = not light
        world.node_tree.nodes["Background"].inputs["Strength"].default_value = 0.0 if light else 1.0
        scene.cycles.samples = int(look["light_spp"]) if light else int(job["spp"])
        scene.cycles.seed = int(job.get("seed", 0)) + k
        np.save(os.path.join(job["out"], f"render_{k}.npy"),
                _render(scene, os.path.join(job["out"], f"render_{k}.exr")))


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
    if job.get("looks"):
        return _looks(job, mat)
    scene, cam, sun, world = _scene(job, mat)
    sphere = scene.objects["sphere"]
    for k, r in enumerate(job["renders"]):
        _turn(sphere, r.get("sphere"))
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
