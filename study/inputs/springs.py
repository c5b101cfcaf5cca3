"""Per-tooth torsion springs of a lightened gear from the FE body model, cached.

``gear{g}.spring.stiffness`` selects how the FE map enters the model:

* ``fe-ratio`` (default): the calibrated solid-gear spring ``k_phi`` (eq. 1.2) times each tooth's
  FE stiffness ratio to the solid body (same tooth, web as thick as the face, no holes) computed
  with the same mesh settings and load;
* ``fe``: the FE stiffness itself; with n_k != 1 the nonlinear spring is matched to the FE
  (linear) one at the reference load: k_phi = M_ref / phi_ref**n_k (secant through the FE point);
* ``uniform``: k_phi on every tooth (the lightening ignored).

The FE helpers take a prepared `study.inputs.gearsetup.GearSetup`. A solid gear needs no FE at
all. Results are cached in memory and on disk (`study.inputs.cache.FE_CACHE`: NetCDF under
``$LIGHTGEAR_CACHE`` or ``./.lightgear-cache/fe``) keyed by a hash of everything the FE depends on
(`GearSetup.settings`: tooth and body geometry, material, pivot, mesh size, load, code version),
so a sweep computes each body once.

CLI: ``lightgear stiffness [SCENE] [--set k=v] [-o OUT.nc]`` computes only the map.
"""
from __future__ import annotations

import math
import time

import numpy as np

from solver import units
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import GearSetup, gear_setups
from study.scene import Scene


def fe_stiffness(setup: GearSetup, teeth=None, keep_fields: bool = False):
    """FE torsion stiffness [N·m/rad] of the gear's teeth (all, or ``teeth``), cached.

    The same solve gives each tooth's largest fillet stress (`root_stress`), cached with the map.
    Returns k (n,) and, when ``keep_fields``, the (model, U) pair of the full solve (not cached).
    """
    from solver.fe import body as fe
    from study.inputs.compliance import factorised_body

    settings = setup.settings
    tooth_list = _teeth(setup, teeth)
    key = FE_CACHE.key({**settings, "teeth": tooth_list})
    if not keep_fields:
        k = FE_CACHE.read_stiffness(key)
        if k is not None:
            return k
    geo = setup.geometry
    model = factorised_body(setup)      # shared with the influence coefficients of the same body
    if not keep_fields:                 # only the reads of k and the stress: no full fields
        k, stress = fe.tooth_map(model, geo, setup.pivot_radius, tooth_list, setup.force, setup.patch)
        FE_CACHE.write_stiffness(key, k, settings, stress)
        return k
    k, U = fe.tooth_stiffness(model, geo, setup.pivot_radius, tooth_list, setup.force, setup.patch)
    stress = fe.fillet_stress(model, geo, U, tooth_list)
    FE_CACHE.write_stiffness(key, k, settings, stress)
    return k, (model, U)


def _teeth(setup: GearSetup, teeth) -> list[int]:
    return list(range(setup.teeth)) if teeth is None else [int(t) for t in teeth]


def root_stress(setup: GearSetup, teeth=None) -> np.ndarray:
    """Largest von Mises fillet stress [Pa] of the gear's teeth (all, or ``teeth``), each under
    its own FE reference load (``setup.force`` at the pitch point): from the FE solve of the
    stiffness map (`fe_stiffness`), cached with it; a map cached without it is solved again."""
    key = FE_CACHE.key({**setup.settings, "teeth": _teeth(setup, teeth)})
    s = FE_CACHE.read_root_stress(key)
    if s is None:
        fe_stiffness(setup, teeth, keep_fields=True)
        s = FE_CACHE.read_root_stress(key)
    return s


def root_stresses(setups, stress: bool = True) -> dict:
    """{gear: (root stress of each tooth [Pa], of the solid body's tooth 0 [Pa]) or the reason
    it is not computed} for `study.archive.lightening.lightening_variables`: read for the gears
    whose springs use the FE (from the cache, or the FE solve of the map); ``stress`` False:
    for none (the caller needs no stress)."""
    out = {}
    for s in setups:
        if not stress:
            out[s.gear] = "not requested"
        elif not uses_fe_springs(s):
            why = "solid body" if not s.lightened else "springs 'uniform'"
            out[s.gear] = f"{why}, its springs need no FE (none is run for this output alone)"
        else:
            out[s.gear] = (root_stress(s), float(root_stress(s.solid(), teeth=[0])[0]))
    return out


def lightening_dataset(scene: Scene, stress: bool = True):
    """The variables of `study.archive.lightening.lightening_variables` for a scene, alone (no
    solve: the FE runs only for a gear whose springs need it and whose map is not cached)."""
    import xarray as xr

    from solver.inertia import gear_mass
    from study.archive.lightening import lightening_variables
    setups = gear_setups(scene)
    masses = [gear_mass(s.geometry, s.body, s.material.density) for s in setups]
    coords, data = lightening_variables(setups, masses, root_stresses(setups, stress))
    return xr.Dataset(data, coords=coords)


def fe_ratio(setup: GearSetup) -> tuple[np.ndarray, np.ndarray, float]:
    """(k_fe of each tooth [N·m/rad], ratio to the solid body [1], k_fe of the solid body [N·m/rad])."""
    k = fe_stiffness(setup)
    k_solid = float(fe_stiffness(setup.solid(), teeth=[0])[0])
    return k, k / k_solid, k_solid


def uses_fe_springs(setup: GearSetup) -> bool:
    """True when the gear's springs come from the FE body (a lightened gear, stiffness not
    'uniform'): its FE map, and that of its solid reference, are computed for the springs."""
    return setup.lightened and setup.spring.stiffness != "uniform"


def tooth_springs(setup: GearSetup) -> tuple[np.ndarray, np.ndarray]:
    """Per-tooth spring k_phi [N·mm/rad^n_k] and FE stiffness ratio [1] of the gear (a solid
    gear, or spring.stiffness 'uniform': the scene's k_phi on every tooth, no FE)."""
    spring = setup.spring
    z = setup.teeth
    if not uses_fe_springs(setup):
        return np.full(z, spring.k_phi), np.ones(z)
    k_fe, ratio, _ = fe_ratio(setup)
    if spring.stiffness == "fe-ratio":
        return spring.k_phi * ratio, ratio
    # "fe": secant match of M = k_phi*phi^n to the linear FE spring at the reference moment
    from solver.fe.body import load_case
    lever = load_case(setup.geometry, 0, setup.pivot_radius).lever
    m_ref = setup.force * lever                                      # N·m
    phi_ref = m_ref / k_fe                                           # rad
    k_si = m_ref / phi_ref**spring.n_k                               # N·m/rad^n
    return k_si / units.spring_stiffness_to_si(1.0), ratio


def body_fields(setup: GearSetup, teeth, solve: bool = True) -> list | None:
    """`solver.fe.body.BodyField` (mesh, displacement, von Mises stress) of the gear's body
    under the reference load on each of ``teeth``, for renders: from the FE cache, else solved
    through the gear's factorised body (`study.inputs.compliance.factorised_body`: the one a run
    or a map of this process made, else made now) and stored in the cache, or None when not
    cached and ``solve`` is False."""
    from study.inputs.compliance import factorised_body
    teeth = [int(t) for t in teeth]
    key = _fields_key(setup, teeth)
    fields = FE_CACHE.read_fields(key)
    if fields is not None or not solve:
        return fields
    return _solve_fields(setup, teeth, key, factorised_body(setup))


def _fields_key(setup: GearSetup, teeth: list) -> str:
    return FE_CACHE.key({**setup.settings, "fields": teeth})


def _solve_fields(setup: GearSetup, teeth: list, key: str, model) -> list:
    """The body fields of ``teeth`` through the factorised body ``model`` (one block of solves,
    the displacements of `solver.fe.body.tooth_stiffness` that the spring map reads), stored
    in the FE cache under ``key``."""
    from solver.fe import body as fe
    _, U = fe.tooth_stiffness(model, setup.geometry, setup.pivot_radius, teeth, setup.force, setup.patch)
    basis = fe.stress_basis(model)
    fields = [fe.body_field(model, setup.geometry, U[:, j], t, setup.force, setup.pivot_radius, basis)
              for j, t in enumerate(teeth)]
    FE_CACHE.write_fields(key, fields)
    return fields


def keep_render_fields(setups, k_phi) -> list[int]:
    """Store in the FE cache the body fields a render of the run will draw (`archive_body_fields`:
    each lightened gear's stiffest and softest tooth of ``k_phi``, its tooth springs as the
    archive's ``tooth_stiffness``, (2, teeth) with NaN past a gear's teeth), for each gear
    whose factorised body this process holds already (the run's springs, coupling fit or
    strength made it): two solves and a file of about a MB, instead of the render factorising
    the body again. A body not held, or fields already stored, cost nothing. -> the gears stored."""
    from study.inputs.compliance import held_body
    done = []
    for setup in setups:
        if not setup.lightened:
            continue
        teeth = render_teeth(k_phi[setup.gear - 1])
        key = _fields_key(setup, teeth)
        model = None if FE_CACHE.has_fields(key) else held_body(setup)
        if model is not None:
            _solve_fields(setup, teeth, key, model)
            done.append(setup.gear)
    return done


def render_teeth(k_phi) -> list[int]:
    """The teeth an FE stress render loads: the stiffest and the softest of ``k_phi`` (one gear's
    tooth springs, NaN past its teeth)."""
    k = np.asarray(k_phi, float)
    k = k[np.isfinite(k)]
    return [int(np.argmax(k)), int(np.argmin(k))]


def archive_body_fields(ds, solve: bool = True) -> dict:
    """{gear: [BodyField under the stiffest tooth's load, under the softest's]} of each
    lightened gear of a run archive (its ``scene`` attribute and ``tooth_stiffness``), what its
    renders draw: from the FE cache, else solved (``solve``) and cached; a gear whose fields are
    neither cached nor solved is left out."""
    from study.inputs.gearsetup import gear_setup
    from study.scene import loads_scene
    scene = loads_scene(ds.attrs["scene"], "archive attribute 'scene'")
    out = {}
    for g in (1, 2):
        if scene.is_lightened(g):
            fields = body_fields(gear_setup(scene, g), render_teeth(ds["tooth_stiffness"].sel(gear=g).values), solve)
            if fields is not None:
                out[g] = fields
    return out


# ------------------------------------------------------------------ dataset

def stiffness_dataset(scene: Scene):
    """xarray Dataset: tooth_stiffness (N·mm/rad^n_k; CF unit N mm) and stiffness_ratio of both gears, with hole positions."""
    import xarray as xr

    from study.archive.netcdf import provenance
    from study.archive.run_variables import stiffness_variables
    t0 = time.perf_counter()
    springs = [tooth_springs(setup) for setup in gear_setups(scene)]
    coords, data = stiffness_variables((springs[0][0], springs[1][0]), (springs[0][1], springs[1][1]))
    ds = xr.Dataset(data, coords=coords, attrs={"scene": scene.to_toml(), "wall_time_springs_s": time.perf_counter() - t0,
                                                **provenance()})
    return ds


def identify_spring(setup: GearSetup, radii: int = 7, levels=(0.25, 0.5, 1.0)):
    """Fit (pivot radius, k_phi, n) of the gear's tooth 0 to FE compliance at ``radii`` load points
    from the start of active profile to near the tip and at ``levels`` times the reference load."""
    from solver.fe import body as fe
    from solver.fe.mesh import mesh_body
    from solver.identify.pivot import SpringFit, fit_pivot, fit_power_law

    geo = setup.geometry
    u = np.linspace(setup.sap_roll, geo.u_tip, radii + 2)[1:-1]
    mesh = mesh_body(geo, setup.body, setup.mesh_size, prefix=f"{setup.prefix}.body",
                     grading=setup.mesh_grading)
    model = fe.assemble(mesh, geo.spec.face_width, setup.body.web_thickness, setup.material)
    comp, t = [], []
    for ui in u:
        case = fe.load_case(geo, 0, 0.0, ui)
        f = fe.load_vector(model, case, 1.0, setup.patch)
        d = fe.point_displacement(model, fe.solve_load(model, f), case.centre_point) @ case.direction
        comp.append(d)
        t.append(geo.psi_base - ui)
    r_q, k, err = fit_pivot(geo.base_radius, t, comp)
    # load levels at the pitch point: moment and rotation about the identified pivot
    case = fe.load_case(geo, 0, r_q)
    c_pitch = np.interp(math.tan(geo.spec.pressure_angle), u, comp)
    F = setup.force * np.asarray(levels)
    k_phi, n = fit_power_law(F * case.lever, F * c_pitch / case.lever)
    return SpringFit(r_q, k_phi, n, err), u, np.array(comp)
