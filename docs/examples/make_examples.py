"""Write the example files that docs/fitting.md and docs/mitsuba.md use.

    python docs/examples/make_examples.py [FOLDER]           # samples.csv, scene.xml
    python docs/examples/make_examples.py --merl [FOLDER]    # and paint.binary (33 MB)

FOLDER defaults to this script's folder, where ``samples.csv`` and
``scene.xml`` are shipped (tests/test_docs_examples.py checks that the shipped
copies are what this script writes, and runs every example of the docs).

* ``samples.csv``: "measured" samples of Modified Phong with ``kd = 0.3``,
  ``ks = 0.5``, ``n = 20`` on :func:`plausible.fitting.sample_pairs` at
  incidences 0, 30, 60 and 80 degrees, with 2 % log-normal noise (seed 0), in
  the CSV layout of :func:`plausible.fitting.load_table`.  A fit with ``n``
  fixed at 20 recovers ``kd`` and ``ks`` to about the noise.
* ``scene.xml``: a Mitsuba 3 scene, an Ashikhmin-Shirley sphere on a diffuse
  floor under a sky and a point light, 64 x 64 pixels, 16 samples per pixel.
* ``paint.binary`` (``--merl`` only; not shipped, it is 33 MB): a MERL file of
  an anisotropy-free Ward model with a coloured diffuse part, a stand-in for a
  measured material of the MERL database (read the same way).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

import plausible
from plausible.fitting import sample_pairs, save_table, write_merl

SAMPLES_TRUTH = dict(kd=0.3, ks=0.5, n=20.0)
PAINT = dict(alpha_x=0.2, alpha_y=0.2, rs=0.2, rd=[0.3, 0.2, 0.05])

SCENE = """<scene version="3.0.0">
    <!-- An Ashikhmin-Shirley sphere (the plausible plugin) on a diffuse floor. -->
    <integrator type="path">
        <integer name="max_depth" value="4"/>
    </integrator>
    <sensor type="perspective">
        <float name="fov" value="35"/>
        <transform name="to_world">
            <lookat origin="0, -5, 2" target="0, 0, 0.3" up="0, 0, 1"/>
        </transform>
        <sampler type="independent">
            <integer name="sample_count" value="16"/>
        </sampler>
        <film type="hdrfilm">
            <integer name="width" value="64"/>
            <integer name="height" value="64"/>
        </film>
    </sensor>
    <shape type="sphere">
        <point name="center" value="0, 0, 0.6"/>
        <float name="radius" value="0.6"/>
        <bsdf type="ashikhmin_shirley">
            <float name="nu" value="100"/>
            <float name="nv" value="10"/>
            <rgb name="rs" value="0.9, 0.7, 0.3"/>
            <rgb name="rd" value="0.1, 0.05, 0.02"/>
        </bsdf>
    </shape>
    <shape type="rectangle">
        <transform name="to_world">
            <scale value="4"/>
        </transform>
        <bsdf type="diffuse">
            <rgb name="reflectance" value="0.4, 0.4, 0.4"/>
        </bsdf>
    </shape>
    <emitter type="constant">
        <rgb name="radiance" value="0.3, 0.3, 0.3"/>
    </emitter>
    <emitter type="point">
        <point name="position" value="2, -3, 4"/>
        <rgb name="intensity" value="30, 30, 30"/>
    </emitter>
</scene>
"""


def write_samples(path) -> Path:
    m = plausible.make("modified-phong", **SAMPLES_TRUTH)
    wi, wo = sample_pairs(m.peak_directions, thetas_deg=(0.0, 30.0, 60.0, 80.0))
    noise = np.exp(0.02 * np.random.default_rng(0).standard_normal(len(wi)))
    return save_table(path, wi, wo, m.eval(wi, wo) * noise)


def write_scene(path) -> Path:
    path = Path(path)
    path.write_text(SCENE)
    return path


def write_paint(path) -> Path:
    return write_merl(path, plausible.make("ward", **PAINT))


def main(argv):
    merl = "--merl" in argv
    args = [a for a in argv if a != "--merl"]
    out = Path(args[0]) if args else Path(__file__).resolve().parent
    out.mkdir(parents=True, exist_ok=True)
    paths = [write_samples(out / "samples.csv"), write_scene(out / "scene.xml")]
    if merl:
        paths.append(write_paint(out / "paint.binary"))
    for p in paths:
        print(f"wrote {p}")


if __name__ == "__main__":
    main(sys.argv[1:])
