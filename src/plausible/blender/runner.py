"""Blender out of process: find Blender's interpreter and run :mod:`.worker` in it.

``bpy`` (Blender as a Python module, 5.0.1 for CPython 3.11) pins ``numpy<2``, and
plausible needs numpy 2, so Blender lives in a virtual environment of its own,
``.venv-blender`` (``make setup`` makes it beside ``.venv``), and plausible talks
to it through files: a job in JSON, renders back as ``.npy``.  A crash of Blender
is then an error message here, not a lost session.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

__all__ = ["BlenderUnavailable", "blender_python", "run_job"]

#: The environment variable that names Blender's interpreter (a Python with ``bpy``).
ENV = "PLAUSIBLE_BLENDER_PYTHON"
WORKER = Path(__file__).with_name("worker.py")
#: Seconds a job may take before it is stopped (a render of the tests takes about one).
TIMEOUT = 1800


class BlenderUnavailable(RuntimeError):
    """No interpreter with ``bpy`` was found (the tests skip on it)."""


def _candidates():
    if os.environ.get(ENV):
        yield Path(os.environ[ENV])
        return
    for root in [Path.cwd(), *Path(__file__).resolve().parents]:
        yield root / ".venv-blender" / "bin" / "python"


def blender_python() -> Path:
    """The interpreter that has ``bpy``: ``$PLAUSIBLE_BLENDER_PYTHON``, else the first
    ``.venv-blender/bin/python`` in the working directory or above this package.
    :class:`BlenderUnavailable` (saying how to install it) when there is none."""
    for p in _candidates():
        if p.is_file() and os.access(p, os.X_OK):
            return p
    raise BlenderUnavailable(
        f"Blender is not installed: no {ENV} and no .venv-blender/bin/python here or above "
        f"{Path(__file__).parent}; `make setup` makes .venv-blender (bpy 5.0.1, about 380 MB), or point "
        f"{ENV} at a Python 3.11 with `pip install bpy`")


def run_job(material: dict, renders: list, *, resolution: int, spp: int, seed: int = 0,
            save_blend=None, threads: int | None = None, looks: dict | None = None) -> list:
    """Run one job of :mod:`.worker` (its docstring: ``material``, ``renders``, ``looks``) and
    return the renders as float arrays ``(resolution, resolution, 3)``.
    ValueError naming the argument for a bad input (a material not in its file), RuntimeError
    with Blender's last lines when Blender fails otherwise."""
    py = blender_python()
    threads = threads or min(4, os.cpu_count() or 1)
    out = Path(tempfile.mkdtemp(prefix="plausible-blender-"))
    try:
        job = dict(material=material, renders=renders, out=str(out), resolution=int(resolution), spp=int(spp),
                   seed=int(seed), threads=int(threads), save_blend=str(save_blend) if save_blend else None,
                   looks=looks)
        (out / "job.json").write_text(json.dumps(job))
        p = subprocess.run([str(py), str(WORKER), str(out / "job.json")], capture_output=True, text=True,
                           timeout=TIMEOUT, env={**os.environ, "PYTHONWARNINGS": "ignore"})
        if p.returncode == 3:       # worker.BAD_INPUT: its last line is "ARGUMENT<TAB>why"
            arg, _, why = (p.stderr.strip().splitlines() or ["job\tbad input"])[-1].partition("\t")
            raise ValueError(f"{arg}: {why}")
        if p.returncode != 0:
            tail = "\n".join((p.stdout + p.stderr).strip().splitlines()[-6:])
            raise RuntimeError(f"Blender ({py}) failed with status {p.returncode}:\n{tail}")
        return [np.load(out / f"render_{k}.npy").astype(np.float64) for k in range(len(renders))]
    finally:
        shutil.rmtree(out, ignore_errors=True)


if __name__ == "__main__":    # pragma: no cover - a quick probe: python -m plausible.blender.runner
    print(blender_python(), file=sys.stderr)
