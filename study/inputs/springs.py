"""Per-tooth torsion springs of a lightened gear from the FE body model, cached.

``gear{g}.spring.stiffness`` selects how the FE map enters the model:

* ``fe-ratio`` (default): the calibrated solid-gear spring ``k_phi`` (eq. 1.2) times each tooth's
  FE stiffness ratio to the solid body (same tooth, web as thick as the face, no holes) computed
  with the same mesh settings and load;
* ``fe``: the FE stiffness itself; with n_k != 1 the nonlinear spring is matched to the FE
  (linear) one at the reference load: k_phi = M_ref / phi_ref**n_k (secant through the FE point);
* ``uniform``: k_phi on every tooth (the lightening ignored).

A solid gear needs no FE at all. Results are cached in memory and on disk (NetCDF under
``$LIGHTGEAR_CACHE`` or ``./.lightgear-cache/fe``) keyed by a hash of everything the FE depends on
(tooth and body geometry, material, pivot, mesh size, load, code version), so a sweep computes
each body once.

CLI: ``lightgear stiffness [SCENE] [--set k=v] [-o OUT.nc]`` computes only the map.
"""
from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import time
from pathlib import Path

import numpy as np
import xarray as xr

from solver import units
from solver.geometry import BodySpec, gear_geometry
from study.scene import Scene

FE_VERSION = "1"   # bump when the FE model or the stiffness definition changes
_memory: dict[str, np.ndarray] = {}


def cache_dir() -> Path:
    return Path(os.environ.get("LIGHTGEAR_CACHE", ".lightgear-cache")) / "fe"


def solid_body(body: BodySpec, face_width: float) -> BodySpec:
    """The same body with the web as thick as the face and no holes (the ratio's reference)."""
    return dataclasses.replace(body, web_thickness=face_width, holes=0, hole_radius=0.0, hole_circle_radius=0.0, hole_phase=0.0)


def reference_torque(scene: Scene) -> float:
    """Torque [N·m] that sets the FE load (the FE is linear: it only scales stresses and fields)."""
    return scene.quasi_static.torque if scene.quasi_static.torque > 0 else 50.0


def _settings(scene: Scene, g: int, body: BodySpec) -> dict:
    if body.holes == 0:  # hole sizes do not matter without holes: one cache entry for all of them
        body = dataclasses.replace(body, hole_radius=0.0, hole_circle_radius=0.0, hole_phase=0.0)
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    size = scene.fe.mesh_size * units.MM if scene.fe.mesh_size > 0 else None
    return dict(tooth=dataclasses.asdict(scene.tooth_spec(g)), body=dataclasses.asdict(body),
                material=dataclasses.asdict(scene.material_spec()), pivot=scene.pivot_radius(g),
                size=size, force=reference_torque(scene) / geo.base_radius, version=FE_VERSION)


def _key(settings: dict) -> str:
    return hashlib.sha256(json.dumps(settings, sort_keys=True, default=float).encode()).hexdigest()[:20]


def contact_patch(scene: Scene, g: int, force: float, size: float) -> float:
    """Half-width [m] of the load patch: the Hertz half-width of the pitch-point contact at the
    reference load (plane strain, equal materials), and at least half an element."""
    g1 = gear_geometry(scene.tooth_spec(1)); g2 = gear_geometry(scene.tooth_spec(2))
    a = math.tan(g1.spec.pressure_angle)
    r1, r2 = g1.base_radius * a, g2.base_radius * a
    r_eq = r1 * r2 / (r1 + r2)
    mat = scene.material_spec()
    e_eq = mat.youngs_modulus / (2 * (1 - mat.poisson_ratio**2))
    b = scene.tooth_spec(g).face_width
    b_h = math.sqrt(4 * force * r_eq / (math.pi * b * e_eq))
    return max(b_h, size / 2)


def fe_stiffness(scene: Scene, g: int, body: BodySpec | None = None, teeth=None, keep_fields: bool = False):
    """FE torsion stiffness [N·m/rad] of gear g's teeth (all, or ``teeth``), cached.

    Returns k (n,) and, when ``keep_fields``, the (model, U) pair for renders (not cached).
    """
    from solver.fe import body as fe
    from solver.fe.mesh import default_mesh_size, mesh_body

    body = body or scene.body_spec(g)
    st = _settings(scene, g, body)
    tooth_list = list(range(scene.gear(g).teeth)) if teeth is None else [int(t) for t in teeth]
    st_key = _key({**st, "teeth": tooth_list})
    if not keep_fields:
        if st_key in _memory:
            return _memory[st_key].copy()
        path = cache_dir() / f"{st_key}.nc"
        if path.exists():
            try:
                with xr.open_dataset(path) as ds:
                    k = ds["k_fe"].values.copy()
                _memory[st_key] = k
                return k.copy()
            except (OSError, KeyError, ValueError):
                pass  # unreadable cache entry: recompute and overwrite
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    size = st["size"] or default_mesh_size(geo.spec.module)
    mesh = mesh_body(geo, body, size, prefix=f"gear{g}.body")
    model = fe.assemble(mesh, geo.spec.face_width, body.web_thickness, scene.material_spec())
    patch = contact_patch(scene, g, st["force"], size)
    k, U = fe.tooth_stiffness(model, geo, st["pivot"], tooth_list, st["force"], patch)
    _memory[st_key] = k.copy()
    _store(st_key, k, st)
    return (k, (model, U)) if keep_fields else k


def _store(key: str, k: np.ndarray, settings: dict) -> None:
    from study.report.results import write_netcdf
    ds = xr.Dataset({"k_fe": xr.Variable("tooth", k, {"units": "N m rad-1", "long_name": "FE tooth torsion stiffness"})},
                    attrs={"settings": json.dumps(settings, default=float)})
    try:
        write_netcdf(ds, cache_dir() / f"{key}.nc")
    except OSError:
        pass  # a read-only cache only costs recomputation


def fe_ratio(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray, float]:
    """(k_fe of each tooth [N·m/rad], ratio to the solid body [1], k_fe of the solid body [N·m/rad])."""
    body = scene.body_spec(g)
    k = fe_stiffness(scene, g, body)
    k_solid = float(fe_stiffness(scene, g, solid_body(body, scene.tooth_spec(g).face_width), teeth=[0])[0])
    return k, k / k_solid, k_solid


def tooth_springs(scene: Scene, g: int) -> tuple[np.ndarray, np.ndarray]:
    """Per-tooth spring k_phi [N·mm/rad^n_k] and FE stiffness ratio [1] of gear g."""
    gs = scene.gear(g)
    z = gs.teeth
    if not scene.is_lightened(g) or gs.spring.stiffness == "uniform":
        return np.full(z, gs.spring.k_phi), np.ones(z)
    k_fe, ratio, _ = fe_ratio(scene, g)
    if gs.spring.stiffness == "fe-ratio":
        return gs.spring.k_phi * ratio, ratio
    # "fe": secant match of M = k_phi*phi^n to the linear FE spring at the reference moment
    from solver.fe.body import load_case
    geo = gear_geometry(scene.tooth_spec(g))
    lever = load_case(geo, 0, scene.pivot_radius(g)).lever
    m_ref = reference_torque(scene) / geo.base_radius * lever       # N·m
    phi_ref = m_ref / k_fe                                           # rad
    k_si = m_ref / phi_ref**gs.spring.n_k                            # N·m/rad^n
    return k_si / units.spring_stiffness_to_si(1.0), ratio


def body_fe(scene: Scene, g: int, tooth: int = 0):
    """Mesh, displacement and von Mises stress of gear g's body under the load on ``tooth``."""
    from solver.fe import body as fe
    geo = gear_geometry(scene.tooth_spec(g))
    st = _settings(scene, g, scene.body_spec(g))
    _, (model, U) = fe_stiffness(scene, g, teeth=[tooth], keep_fields=True)
    return fe.body_field(model, geo, U[:, 0], tooth, st["force"], st["pivot"])


# ------------------------------------------------------------------ dataset and CLI

def stiffness_dataset(scene: Scene) -> xr.Dataset:
    """tooth_stiffness (N mm rad-1) and stiffness_ratio of both gears, with hole positions."""
    from study.report import results
    t0 = time.perf_counter()
    springs = [tooth_springs(scene, g) for g in (1, 2)]
    coords, data = results.stiffness_variables((springs[0][0], springs[1][0]), (springs[0][1], springs[1][1]))
    ds = xr.Dataset(data, coords=coords, attrs={"scene": scene.to_toml(), "wall_time_springs_s": time.perf_counter() - t0,
                                                **results.provenance()})
    return ds


def hole_offset(scene: Scene, g: int) -> np.ndarray:
    """Angular distance [tooth pitches] of each tooth's axis to the nearest hole centre."""
    b = scene.gear(g).body
    z = scene.gear(g).teeth
    if b.holes == 0:
        return np.full(z, np.nan)
    tooth = np.arange(z) * 360.0 / z
    holes = b.hole_phase + np.arange(b.holes) * 360.0 / b.holes
    d = (tooth[:, None] - holes[None, :] + 180.0) % 360.0 - 180.0
    return d[np.arange(z), np.argmin(np.abs(d), axis=1)] / (360.0 / z)


def identify_spring(scene: Scene, g: int, radii: int = 7, levels=(0.25, 0.5, 1.0)):
    """Fit (pivot radius, k_phi, n) of gear g's tooth 0 to FE compliance at ``radii`` load points
    from the start of active profile to near the tip and at ``levels`` times the reference load."""
    from solver.fe import body as fe
    from solver.fe.mesh import default_mesh_size, mesh_body
    from solver.geometry import pair_geometry
    from solver.identify.pivot import SpringFit, fit_pivot, fit_power_law

    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    pair = pair_geometry(gear_geometry(scene.tooth_spec(1)), gear_geometry(scene.tooth_spec(2)))
    u = np.linspace(pair.u_sap[g - 1], geo.u_tip, radii + 2)[1:-1]
    st = _settings(scene, g, scene.body_spec(g))
    size = st["size"] or default_mesh_size(geo.spec.module)
    mesh = mesh_body(geo, scene.body_spec(g), size, prefix=f"gear{g}.body")
    model = fe.assemble(mesh, geo.spec.face_width, scene.body_spec(g).web_thickness, scene.material_spec())
    patch = contact_patch(scene, g, st["force"], size)
    comp, t = [], []
    for ui in u:
        case = fe.load_case(geo, 0, 0.0, ui)
        f = fe.load_vector(model, case, 1.0, patch)
        d = fe.point_displacement(model, fe.solve_load(model, f), case.centre_point) @ case.direction
        comp.append(d)
        t.append(geo.psi_base - ui)
    r_q, k, err = fit_pivot(geo.base_radius, t, comp)
    # load levels at the pitch point: moment and rotation about the identified pivot
    case = fe.load_case(geo, 0, r_q)
    c_pitch = np.interp(math.tan(geo.spec.pressure_angle), u, comp)
    F = st["force"] * np.asarray(levels)
    k_phi, n = fit_power_law(F * case.lever, F * c_pitch / case.lever)
    return SpringFit(r_q, k_phi, n, err), u, np.array(comp)
