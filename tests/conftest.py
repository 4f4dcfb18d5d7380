import math

import numpy as np
import pytest

import plausible
from plausible.analysis.suite import variants


def all_models():
    return plausible.names()


def model_cases(max_variants=4):
    """(name, params) for every registered model: defaults and declared extremes."""
    return [pytest.param(n, kw, id=f"{n}-{'-'.join(f'{k}={v}' for k, v in kw.items()) or 'default'}")
            for n in plausible.names() for kw in variants(n, max_variants)]


def random_upper(rng, n, zmin=0.0, zmax=1.0):
    """Uniform random directions on the upper hemisphere with ``zmin <= z < zmax``
    (the tests' one generator of random directions: ``z``, then the azimuth)."""
    z = rng.uniform(zmin, zmax, n)
    phi = rng.uniform(0, 2 * math.pi, n)
    s = np.sqrt(1 - z * z)
    return np.stack([s * np.cos(phi), s * np.sin(phi), z], axis=-1)


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


@pytest.fixture
def full_disk(tmp_path):
    """A folder on a small tmpfs (mounted here; skipped where the machine cannot mount
    one) and ``fill()`` / ``free()``: writes to it fail with ENOSPC until ``free()``."""
    import os
    import subprocess
    from types import SimpleNamespace

    root = tmp_path / "tmpfs"
    root.mkdir()
    if os.geteuid() != 0 or subprocess.run(["mount", "-t", "tmpfs", "-o", "size=256k", "tmpfs", str(root)],
                                           capture_output=True).returncode != 0:
        pytest.skip("cannot mount a tmpfs here (needs root)")
    filler = root / ".filler"

    def fill():
        with open(filler, "ab", buffering=0) as fh:
            try:
                while True:
                    fh.write(b"\0" * 4096)
            except OSError:
                pass

    try:
        yield SimpleNamespace(path=root, fill=fill, free=lambda: filler.unlink(missing_ok=True))
    finally:
        subprocess.run(["umount", "-l", str(root)], capture_output=True)


@pytest.fixture
def disk_full_at(monkeypatch):
    """``disk_full_at(name)``: from now on, opening a file whose path holds ``name`` through
    :mod:`plausible.text`'s writers fails with ENOSPC (a disk that fills at that file)."""
    import errno

    import plausible.text

    def install(name):
        real = open

        def full(path, *a, **kw):
            if name in str(path):
                raise OSError(errno.ENOSPC, "No space left on device")
            return real(path, *a, **kw)

        monkeypatch.setattr(plausible.text, "open", full, raising=False)

    return install


@pytest.fixture(scope="session")
def blender():
    """Blender's interpreter (``.venv-blender``, made by ``make setup``); the tests that need it skip,
    saying so, only where it is absent. (Here, not in tests/blender/conftest.py: a second module named
    ``conftest`` would shadow this one for the tests that import its helpers.)"""
    from plausible.blender import BlenderUnavailable, blender_python

    try:
        return blender_python()
    except BlenderUnavailable as e:
        pytest.skip(str(e))
