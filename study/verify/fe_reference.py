"""FE reference STE of a scene: loaded-tooth-contact analysis with FE influence coefficients.

`reference_dataset(scene)` builds both gear bodies' FE models (`solver.fe.body`, same mesh size and
load patch as the tooth springs of `study.inputs.springs`), their bulk compliance between the drive
flank points of the teeth that meet the mesh over the scene's quasi-static rotation
(`solver.fe.ltca`), and solves the loaded contact at every angle of ``quasi_static`` with the
scene's contact law in series. The compliance is cached in memory and on disk (same directory
and key scheme as the FE springs), so a second run only solves the contact problems.

CLI: ``lightgear reference [SCENE] [-o OUT.nc] [--set k=v] [--step DEG]``.
"""
from __future__ import annotations

import hashlib
import json
import math
import time

import numpy as np
import xarray as xr

from solver import units
from solver.fe.ltca import BodyCompliance, body_compliance, ltca_sweep, mesh_points, profile_grid
from solver.geometry import gear_geometry
from study.inputs.springs import _settings, cache_dir, contact_patch
from study.scene import Scene, SceneError

LTCA_VERSION = "2"          # bump when the influence coefficients' definition changes
PROFILE_POINTS = 8          # roll-parameter grid points along each flank (STE within 0.01 um of 16)
_memory: dict[str, BodyCompliance] = {}
_bodies: dict = {}          # the last BODY_SLOTS factorised bodies (least recently used first)
BODY_SLOTS = 2              # one per gear: a reference and then the coupling of both gears reuse them


def static_angles(scene: Scene, step_deg: float | None = None) -> np.ndarray:
    """Driver angles [rad]: the scene's quasi-static rotation at its step (or ``step_deg``)."""
    qs = scene.quasi_static
    step = qs.angle_step if step_deg is None else step_deg
    n = int(math.floor(qs.rotation / step + 1e-9)) + 1
    return np.radians(np.arange(n) * step)


def teeth_in_mesh(model, angles) -> tuple[list, list, int]:
    """Teeth of each gear that meet the mesh at ``angles`` [rad], and the largest index spread
    between simultaneous candidates (for the solid body's symmetric columns)."""
    s1, s2, spread = set(), set(), 1
    z = model.teeth
    for th in angles:
        mp = mesh_points(model, float(th))
        s1.update(int(t) % z[0] for t in mp.tooth1)
        s2.update(int(t) % z[1] for t in mp.tooth2)
        for t, zz in ((mp.tooth1, z[0]), (mp.tooth2, z[1])):
            if t.size > 1:
                d = (t[:, None] - t[None, :] + zz // 2) % zz - zz // 2
                spread = max(spread, int(np.abs(d).max()))
    return sorted(s1), sorted(s2), spread


def body_compliance_cached(scene: Scene, g: int, teeth: list, spread: int, n_u: int = PROFILE_POINTS,
                           u: np.ndarray | None = None) -> tuple[BodyCompliance, dict]:
    """Gear g's bulk compliance (cached). A solid body: columns of tooth 0, read at offsets
    -spread..spread; a lightened body: every tooth in ``teeth`` loaded and read. ``u``: the roll
    grid (default: ``n_u`` points from the form circle to the tip)."""
    from solver.fe import body as fe
    from solver.fe.mesh import default_mesh_size, mesh_body

    body = scene.body_spec(g)
    geo = gear_geometry(scene.tooth_spec(g), f"gear{g}")
    st = _settings(scene, g, body)
    size = st["size"] or default_mesh_size(geo.spec.module)
    symmetric = not scene.is_lightened(g)
    u = profile_grid(geo, n_u) if u is None else np.asarray(u, float)
    if symmetric:
        load, read = [0], list(range(-spread, spread + 1))
    else:
        load = read = [int(t) for t in teeth]
    key = hashlib.sha256(json.dumps({**st, "load": load, "read": read, "u": [float(x) for x in u], "ltca": LTCA_VERSION},
                                    sort_keys=True, default=float).encode()).hexdigest()[:20]
    info = {"mesh_size_m": size, "cached": True, "wall_time_s": 0.0, "load_cases": len(load) * u.size}
    if key in _memory:
        return _memory[key], info
    path = cache_dir() / f"ltca-{key}.npz"
    if path.exists():
        try:
            with np.load(path) as d:
                c = BodyCompliance(d["u"], d["read"], d["load"], d["g"], bool(d["symmetric"]), int(d["teeth"]))
            _memory[key] = c
            return c, info
        except (OSError, KeyError, ValueError):
            pass  # unreadable cache entry: recompute
    t0, c0 = time.perf_counter(), time.process_time()
    stages = {}              # wall and CPU seconds of each stage (CPU: all threads of the process)
    # the body model depends on geometry, material and mesh size only (not on the load or pivot)
    bkey = json.dumps({k: v for k, v in st.items() if k not in ("force", "pivot")}, sort_keys=True, default=float)
    model = _bodies.pop(bkey, None)
    if model is None:
        while len(_bodies) >= BODY_SLOTS:       # factorisations are large (~0.5 GB): keep a few
            _bodies.pop(next(iter(_bodies)))
        mesh = mesh_body(geo, body, size, prefix=f"gear{g}.body")
        stages.update(mesh_wall_s=time.perf_counter() - t0, mesh_cpu_s=time.process_time() - c0)
        model = fe.assemble(mesh, geo.spec.face_width, body.web_thickness, scene.material_spec())
        stages.update(assembly_wall_s=model.assembly_time, assembly_cpu_s=model.assembly_cpu,
                      factor_wall_s=model.factor_time, factor_cpu_s=model.factor_cpu)
    _bodies[bkey] = model                       # most recently used last
    patch = contact_patch(scene, g, st["force"], size)
    c = body_compliance(model, geo, u, load, read, patch, symmetric_body=symmetric, timings=stages)
    info.update(cached=False, wall_time_s=time.perf_counter() - t0, cpu_time_s=time.process_time() - c0,
                dofs=int(model.n_dofs), stages=stages)
    _memory[key] = c
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_name(f".{path.stem}.tmp.npz")
        np.savez(tmp, u=c.u, read=c.read_teeth, load=c.load_teeth, g=c.g, symmetric=c.symmetric_body, teeth=c.teeth)
        tmp.replace(path)
    except OSError:
        pass  # a read-only cache only costs recomputation
    return c, info


def reference(scene: Scene, angles=None, rigid: bool = False, n_u: int = PROFILE_POINTS):
    """(LTCAResult, model, info) of the scene at driver ``angles`` [rad] (default: quasi-static).

    ``rigid``: rigid bodies, only the contact law deforms (the closed-form check);
    ``n_u``: profile points per flank of the influence coefficients."""
    from study.setup import geometry_model

    qs = scene.quasi_static
    if not qs.torque > 0:
        raise SceneError("quasi_static.torque", f"the FE reference needs a positive (drive-side) torque, got {qs.torque}")
    angles = static_angles(scene) if angles is None else np.asarray(angles, float)
    model = geometry_model(scene)        # the LTCA takes its compliance from the FE, not springs
    info = {}
    t0, c0 = time.perf_counter(), time.process_time()
    if rigid:
        comp = (None, None)
    else:
        t1, t2, spread = teeth_in_mesh(model, angles)
        info.update(wall_time_teeth_s=time.perf_counter() - t0, cpu_time_teeth_s=time.process_time() - c0)
        c1, i1 = body_compliance_cached(scene, 1, t1, spread, n_u)
        c2, i2 = body_compliance_cached(scene, 2, t2, spread, n_u)
        comp = (c1, c2)
        info.update(gear1=i1, gear2=i2)
    info.update(wall_time_compliance_s=time.perf_counter() - t0, cpu_time_compliance_s=time.process_time() - c0)
    t0, c0 = time.perf_counter(), time.process_time()
    res = ltca_sweep(model, comp, angles, qs.torque)
    info.update(wall_time_contact_s=time.perf_counter() - t0, cpu_time_contact_s=time.process_time() - c0)
    return res, model, info


def reference_dataset(scene: Scene, angles=None) -> xr.Dataset:
    """FE reference archive: ste, load sharing and contacts over the driver angle."""
    from study.report import results

    t0 = time.perf_counter()
    res, model, info = reference(scene, angles)
    wall = time.perf_counter() - t0
    coords = {"angle": results._var("angle", np.degrees(res.angle), "degree", "driver rotation from the nominal position"),
              "driver_tooth": results._var("driver_tooth", np.arange(model.teeth[0]), "1", "driver tooth index")}
    off = res.backlash_offset
    data = {
        "ste": results._var("angle", res.te * units.UM_PER_M, "um", "FE reference static transmission error rb1*theta1 + rb2*theta2",
                            comment=f"LTCA with FE influence coefficients; rigid teeth in drive contact read +{off * 1e6:.4f} um"),
        "ste_contacts": results._var("angle", res.n_contacts.astype("int16"), "1", "loaded tooth contacts"),
        "ste_tooth_force": results._var(("angle", "driver_tooth"), res.tooth_force, "N", "normal contact force on each driver tooth"),
        "extended_contact_force": results._var("angle", res.extended, "N", "force carried by tip-corner contacts outside the path of contact"),
    }
    attrs = {"title": f"FE reference (LTCA): {scene.title}", "scene": scene.to_toml(),
             "backlash_offset_um": off * units.UM_PER_M, "contact_ratio": model.pair.contact_ratio,
             "mesh_order": float(scene.gear2.teeth), "hole_order": float(scene.gear2.body.holes),
             "static_torque_N_m": res.torque, "wall_time_reference_s": wall,
             "wall_time_compliance_s": info["wall_time_compliance_s"], "wall_time_contact_s": info["wall_time_contact_s"],
             "profile_points": PROFILE_POINTS,
             "fe_mesh_size_mm": info["gear2"]["mesh_size_m"] * 1e3,
             "method": "loaded-tooth-contact analysis: bulk FE compliance read at the tooth centreline (both bodies, "
                       "clamped at the bore, all loaded teeth coupled) + contact law k_con*delta^m1 in series",
             "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
             **results.provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)
