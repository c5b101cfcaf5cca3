"""The graded gear-body mesh against the fine one (the reference): tooth stiffness and fillet stress.

The graded mesh coarsens the tooth cores and the rim under the roots, where the displacement
field is smooth; the outline and the fillets keep their sizes. Measured on every tooth of four
bodies (benchmarks/bench_fe.py --grading): stiffness within 0.12 %, fillet stress within 1 %.
Here a sample of teeth of the paper's solid gear and of a lightened one (12 holes in a 6 mm web
on a 5 mm rim, the thinnest of the standard sensitivity study), at the default outline size.
"""
import numpy as np
import pytest

from solver.fe import body as fe
from solver.fe.mesh import mesh_body
from study.inputs.gearsetup import gear_setup
from study.scene import default_scene

THIN = {"gear2.body.holes": 12, "gear2.body.hole_radius": 7.0, "gear2.body.rim_height": 5.0,
        "gear2.body.web_thickness": 6.0}
TEETH = [0, 1, 2, 3, 17, 33, 50]        # around a hole (tooth 0 on a hole axis) and around the gear


def stiffness_and_stress(setup, grading):
    g, body = setup.geometry, setup.body
    mesh = mesh_body(g, body, setup.mesh_size, grading=grading)
    model = fe.assemble(mesh, g.spec.face_width, body.web_thickness, setup.material)
    k, U = fe.tooth_stiffness(model, g, setup.pivot_radius, TEETH, setup.force, setup.patch)
    return k, fe.fillet_stress(model, g, U, TEETH), mesh.n_elements


@pytest.mark.parametrize("body", ["solid", "thin web, 12 holes"])
def test_graded_mesh_keeps_every_tooth_stiffness_within_half_a_percent_of_the_fine_mesh(body):
    setup = gear_setup(default_scene().replace(**THIN), 2)
    if body == "solid":
        setup = setup.solid()
    k_fine, s_fine, n_fine = stiffness_and_stress(setup, "fine")
    k_graded, s_graded, n_graded = stiffness_and_stress(setup, "graded")
    assert np.abs(k_graded / k_fine - 1).max() < 5e-3, k_graded / k_fine - 1
    assert np.abs(s_graded / s_fine - 1).max() < 2e-2, s_graded / s_fine - 1
    assert n_graded < 0.6 * n_fine             # what the grading is for


def test_gradings_are_named_in_errors():
    setup = gear_setup(default_scene(), 2)
    with pytest.raises(ValueError, match="fe.mesh_grading"):
        mesh_body(setup.geometry, setup.body, setup.mesh_size, grading="coarse")
