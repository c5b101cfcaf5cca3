"""Shared fixtures: small solid scenes that need no FE, and their models."""
import os

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pytest  # noqa: E402

from study.scene import default_scene  # noqa: E402

SOLID = {"gear2.body.holes": 0, "gear2.body.web_thickness": 17.0}


def solid_scene(**overrides):
    """The paper pair with a solid driven gear (no FE needed), plus overrides."""
    return default_scene().replace(**{**SOLID, **overrides})


@pytest.fixture(scope="session")
def paper_solid_scene():
    return solid_scene()


@pytest.fixture(scope="session")
def paper_solid_model(paper_solid_scene):
    from study.run import build_scene_model
    return build_scene_model(paper_solid_scene)
