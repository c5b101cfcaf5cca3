"""Prepared gear setups: what the FE of one gear needs, derived once from a scene.

`gear_setups(scene)` converts both gears to SI specs (tooth, body, material), derives their
geometry and fixes the FE settings every FE helper shares: element size, reference load at the
pitch point and the load patch. The FE helpers of `study.inputs` (tooth springs, body
compliance, coupling fits) take a `GearSetup`, never the scene; `GearSetup.settings` is what
their cache keys are made of (`study.inputs.cache`).
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from solver import units
from solver.fe.mesh import default_mesh_size
from solver.geometry import BodySpec, GearGeometry, Material, ToothSpec, body_settings, pair_geometry, solid_body
from study.inputs.cache import FE_CACHE
from study.scene import Scene, SpringSection

# bump when the FE model or the stiffness definition changes (it is in every key); 2: the webs
# meshed without the outline's 1D mesh; 3: rims condensed from a body of their own; 4: the webs
# condensed by compiled sparse solves (the same results to rounding, 1e-13)
FE_VERSION = "4"


@dataclass(frozen=True)
class GearSetup:
    """One gear of a scene, prepared for the FE. SI units."""

    gear: int                   # 1 (driver) or 2
    tooth: ToothSpec
    geometry: GearGeometry
    body: BodySpec
    material: Material
    pivot_radius: float         # tooth pivot [m] (the root circle when the scene gives 0)
    spring: SpringSection       # the scene's spring law of the gear (scene units, N·mm/rad^n_k)
    lightened: bool             # holes or a web thinner than the face (else the body is a solid disc)
    sap_roll: float             # roll parameter at the start of the active profile [-]
    mesh_size_setting: float | None   # fe.mesh_size [m]; None: the default from the module
    force: float                # FE reference load at the pitch point [N]
    hertz_half_width: float     # Hertz half-width of the pitch-point contact under ``force`` [m]
    mesh_grading: str = "graded"   # fe.mesh_grading (`solver.fe.mesh.GRADINGS`)

    @property
    def teeth(self) -> int:
        return self.tooth.teeth

    @property
    def prefix(self) -> str:
        """The scene path of the gear, for error messages ('gear1')."""
        return f"gear{self.gear}"

    @property
    def mesh_size(self) -> float:
        """Element size at the outline [m]."""
        return self.mesh_size_setting or default_mesh_size(self.tooth.module)

    @property
    def patch(self) -> float:
        """Half-width [m] of the load patch: the Hertz half-width, at least half an element."""
        return max(self.hertz_half_width, self.mesh_size / 2)

    @property
    def settings(self) -> dict:
        """Everything the FE of this gear depends on (geometry, body, material, pivot, mesh
        size and grading, load, code version): the content of the cache keys."""
        # hole sizes do not matter without holes (one cache entry for all of them); a round-holed
        # body keeps the key it had before the other opening shapes existed
        out = dict(tooth=dataclasses.asdict(self.tooth), body=body_settings(self.body),
                   material=dataclasses.asdict(self.material), pivot=self.pivot_radius,
                   size=self.mesh_size_setting, force=self.force, version=FE_VERSION)
        if self.mesh_grading != "fine":   # the fine mesh keeps the keys it had before the grading existed
            out["grading"] = self.mesh_grading
        return out

    @property
    def key(self) -> str:
        return FE_CACHE.key(self.settings)

    def solid(self) -> GearSetup:
        """The same gear with a solid body (`solver.geometry.solid_body`), same FE settings."""
        return dataclasses.replace(self, body=solid_body(self.body, self.tooth.face_width), lightened=False)


def reference_torque(scene: Scene) -> float:
    """Torque [N·m] that sets the FE load (the FE is linear: it only scales stresses and fields)."""
    return scene.quasi_static.torque if scene.quasi_static.torque > 0 else 50.0


def hertz_half_width(g1: GearGeometry, g2: GearGeometry, material: Material, face_width: float, force: float) -> float:
    """Hertz half-width [m] of the pitch-point contact of the pair under ``force`` [N] on
    ``face_width`` [m] (plane strain, equal materials)."""
    a = math.tan(g1.spec.pressure_angle)
    r1, r2 = g1.base_radius * a, g2.base_radius * a
    r_eq = r1 * r2 / (r1 + r2)
    e_eq = material.youngs_modulus / (2 * (1 - material.poisson_ratio**2))
    return math.sqrt(4 * force * r_eq / (math.pi * face_width * e_eq))


def gear_setups(scene: Scene) -> tuple[GearSetup, GearSetup]:
    """Both gears of a (checked) scene, prepared for the FE."""
    geos = tuple(scene.geometry(g) for g in (1, 2))
    pair = pair_geometry(*geos)
    material = scene.material_spec()
    torque = reference_torque(scene)
    size = scene.fe.mesh_size * units.MM if scene.fe.mesh_size > 0 else None
    out = []
    for g, geo in zip((1, 2), geos):
        force = torque / geo.base_radius
        out.append(GearSetup(g, geo.spec, geo, scene.body_spec(g), material, scene.pivot_radius(g), scene.gear(g).spring,
                             scene.is_lightened(g), pair.u_sap[g - 1], size, force,
                             hertz_half_width(*geos, material, geo.spec.face_width, force), scene.fe.mesh_grading))
    return out[0], out[1]


def gear_setup(scene: Scene, g: int) -> GearSetup:
    """Gear g (1 or 2) of the scene, prepared for the FE."""
    if g not in (1, 2):
        raise ValueError("gear index is 1 or 2")
    return gear_setups(scene)[g - 1]
