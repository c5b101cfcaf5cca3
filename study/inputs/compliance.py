"""Bulk FE compliance of a gear body between flank points, cached: the influence coefficients
that the coupling fits (`study.inputs.coupling`) and the FE reference (`study.verify.fe_reference`)
read.

`gear_compliance(setup, teeth, spread)` meshes, assembles and factorises the gear's body (same
mesh size and load patch as the tooth springs of `study.inputs.springs`) and computes its
`solver.fe.ltca.BodyCompliance` on a roll-parameter grid along the drive flanks. Results are
kept by `study.inputs.cache.FE_CACHE` in memory and on disk (``ltca-{key}.npz``, the key made of
the gear setup's settings, the load and read teeth, the grid and `LTCA_VERSION`); the factorised
bodies stay in memory for other load sets of the same body.
"""
from __future__ import annotations

import json
import time

import numpy as np

from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import GearSetup

LTCA_VERSION = "2"          # bump when the influence coefficients' definition changes
PROFILE_POINTS = 8          # roll-parameter grid points along each flank (STE within 0.01 um of 16)


def compliance_key(setup: GearSetup, teeth: list, spread: int, u: np.ndarray) -> tuple[str, list, list]:
    """(cache key, loaded teeth, read teeth) of the gear's compliance on the roll grid ``u``."""
    if not setup.lightened:     # a solid body: the columns of tooth 0, read at offsets -spread..spread
        load, read = [0], list(range(-spread, spread + 1))
    else:
        load = read = [int(t) for t in teeth]
    key = FE_CACHE.key({**setup.settings, "load": load, "read": read, "u": [float(x) for x in u], "ltca": LTCA_VERSION})
    return key, load, read


def compliance_cached(setup: GearSetup, teeth: list, spread: int, n_u: int = PROFILE_POINTS) -> bool:
    """True when the compliance `gear_compliance` would compute is in the cache (memory or disk)."""
    from solver.fe.ltca import profile_grid
    key, _, _ = compliance_key(setup, teeth, spread, profile_grid(setup.geometry, n_u))
    return key in FE_CACHE.compliance or (FE_CACHE.folder / f"ltca-{key}.npz").exists()


def gear_compliance(setup: GearSetup, teeth: list, spread: int, n_u: int = PROFILE_POINTS,
                    u: np.ndarray | None = None) -> tuple:
    """(BodyCompliance [m/N], info) of the gear's body, cached. A solid body: columns of tooth 0,
    read at offsets -spread..spread; a lightened body: every tooth in ``teeth`` loaded and read.
    ``u``: the roll grid (default: ``n_u`` points from the form circle to the tip). ``info``:
    mesh size [m], whether it came from the cache, wall and CPU times [s] of each stage."""
    from solver.fe.ltca import body_compliance, profile_grid

    geo = setup.geometry
    symmetric = not setup.lightened
    u = profile_grid(geo, n_u) if u is None else np.asarray(u, float)
    key, load, read = compliance_key(setup, teeth, spread, u)
    info = {"mesh_size_m": setup.mesh_size, "cached": True, "wall_time_s": 0.0, "load_cases": len(load) * u.size}
    c = FE_CACHE.read_compliance(key)
    if c is not None:
        return c, info
    t0, c0 = time.perf_counter(), time.process_time()
    stages = {}              # wall and CPU seconds of each stage (CPU: all threads of the process)
    model = factorised_body(setup, stages)
    c = body_compliance(model, geo, u, load, read, setup.patch, symmetric_body=symmetric, timings=stages)
    info.update(cached=False, wall_time_s=time.perf_counter() - t0, cpu_time_s=time.process_time() - c0,
                dofs=int(model.n_dofs), stages=stages)
    FE_CACHE.write_compliance(key, c)
    return c, info


def factorised_body(setup: GearSetup, stages: dict | None = None):
    """The gear's meshed, assembled and factorised FE body (`solver.fe.body.BodyModel`), kept
    in memory by `FE_CACHE` for every FE result of the same body: the spring map, its fillet
    stress and the influence coefficients share one factorisation (the body depends on the
    geometry, material and mesh only, not on the load or the pivot). ``stages``: if given and
    the body is built, the wall and CPU seconds of meshing, assembly and factorisation."""
    from solver.fe import body as fe
    from solver.fe.mesh import mesh_body

    def build():
        t0, c0 = time.perf_counter(), time.process_time()
        mesh = mesh_body(setup.geometry, setup.body, setup.mesh_size, prefix=f"{setup.prefix}.body",
                         grading=setup.mesh_grading)
        model = fe.assemble(mesh, setup.geometry.spec.face_width, setup.body.web_thickness, setup.material)
        if stages is not None:
            stages.update(mesh_wall_s=time.perf_counter() - t0 - model.assembly_time - model.factor_time,
                          mesh_cpu_s=time.process_time() - c0 - model.assembly_cpu - model.factor_cpu,
                          assembly_wall_s=model.assembly_time, assembly_cpu_s=model.assembly_cpu,
                          factor_wall_s=model.factor_time, factor_cpu_s=model.factor_cpu)
        return model
    key = json.dumps({k: v for k, v in setup.settings.items() if k not in ("force", "pivot")}, sort_keys=True, default=float)
    return FE_CACHE.body(key, build)
