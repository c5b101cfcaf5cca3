"""Shared fixtures: small solid scenes that need no FE, and their models."""
import os

os.environ.setdefault("MPLBACKEND", "Agg")
os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import pytest  # noqa: E402

from study.scene import default_scene  # noqa: E402

SOLID = {"gear2.body.holes": 0, "gear2.body.web_thickness": 17.0}

# 24 teeth, m = 3 mm, small solid bodies: a coarse, fast FE body (about 1 s)
SMALL_PAIR = {"pair.backlash": 0.1}
for _g in (1, 2):
    SMALL_PAIR.update({f"gear{_g}.module": 3.0, f"gear{_g}.teeth": 24, f"gear{_g}.fillet_radius": 0.9,
                       f"gear{_g}.face_width": 20.0, f"gear{_g}.body.rim_height": 4.0,
                       f"gear{_g}.body.web_height": 14.0, f"gear{_g}.body.hub_height": 6.0,
                       f"gear{_g}.body.web_thickness": 20.0, f"gear{_g}.body.holes": 0})


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
