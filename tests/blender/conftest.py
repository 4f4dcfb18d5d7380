"""Blender's tests need Blender's interpreter (``.venv-blender``, made by ``make setup``); they
skip, saying so, only where it is absent."""

import pytest

from plausible.blender import BlenderUnavailable, blender_python


@pytest.fixture(scope="session")
def blender():
    try:
        return blender_python()
    except BlenderUnavailable as e:
        pytest.skip(str(e))
