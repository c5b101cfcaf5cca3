"""Bulk FE compliance of a gear body between flank points, cached: the influence coefficients
that the coupling fits (`study.inputs.coupling`) and the FE reference (`study.verify.fe_reference`)
read.

`gear_compliance(setup, teeth, spread)` meshes, assembles and factorises the gear's body (same
mesh size and load patch as the tooth springs of `study.inputs.springs`) and computes its
`solver.fe.flank_compliance.BodyCompliance` on a roll-parameter grid along the drive flanks. Results are
kept by `study.inputs.cache.FE_CACHE` in memory and on disk (``ltca-{key}.npz``, the key made of
the gear setup's settings, the load and read teeth, the grid and `LTCA_VERSION`); the factorised
bodies stay in memory for other load sets of the same body.
"""
from __future__ import annotations

import json
import time

import numpy as np

from solver.body import BodySpec
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


def compliance_cached(setup: GearSetup, teeth: list, spread: int, n_u: int = PROFILE_POINTS,
                      u: np.ndarray | None = None) -> bool:
    """True when the compliance `gear_compliance` would compute is in the cache (memory or disk)."""
    from solver.fe.flank_compliance import profile_grid
    key, _, _ = compliance_key(setup, teeth, spread, profile_grid(setup.geometry, n_u) if u is None else u)
    return key in FE_CACHE.compliance or (FE_CACHE.folder / f"ltca-{key}.npz").exists()


def gear_compliance(setup: GearSetup, teeth: list, spread: int, n_u: int = PROFILE_POINTS,
                    u: np.ndarray | None = None) -> tuple:
    """(BodyCompliance [m/N], info) of the gear's body, cached. A solid body: columns of tooth 0,
    read at offsets -spread..spread; a lightened body: every tooth in ``teeth`` loaded and read.
    ``u``: the roll grid (default: ``n_u`` points from the form circle to the tip). ``info``:
    mesh size [m], whether it came from the cache, wall and CPU times [s] of each stage."""
    from solver.fe.flank_compliance import FlankLoads, body_compliance, profile_grid

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
    rim, pkey = _rim_products(model, u, load, read, setup.patch)
    c = body_compliance(model, geo, FlankLoads(u, load, read, setup.patch, symmetric), timings=stages)
    if rim is not None and pkey in rim.products and not (FE_CACHE.folder / f"{_products_file(rim, pkey)}.npz").exists():
        G0, A, B = rim.products[pkey]
        FE_CACHE.write_arrays(_products_file(rim, pkey), G0=G0, A=A, B=B)
    info.update(cached=False, wall_time_s=time.perf_counter() - t0, cpu_time_s=time.process_time() - c0,
                dofs=int(model.n_dofs), stages=stages)
    FE_CACHE.write_compliance(key, c)
    return c, info


def _products_file(rim, pkey: str) -> str:
    return f"rim-{rim.key}-{FE_CACHE.key({'products': pkey})}"


def _rim_products(model, u, load, read, patch) -> tuple:
    """(rim, load-set key) of a condensed body, the rim's products of the load set read from
    disk into it when stored there; (None, None) for a body factorised whole."""
    from solver.fe.flank_compliance import products_key
    cb = model.condensed
    if cb is None or not cb.rim.key:
        return None, None
    pkey = products_key(u, load, read, patch)
    if pkey not in cb.rim.products:
        stored = FE_CACHE.read_arrays(_products_file(cb.rim, pkey))
        n_i, m, k = cb.rim.n_interface, len(read) * len(u), len(load) * len(u)
        if stored is not None and stored["G0"].shape == (m, k) and stored["A"].shape == (m, n_i) and stored["B"].shape == (n_i, k):
            cb.rim.products[pkey] = (stored["G0"], stored["A"], stored["B"])
    return cb.rim, pkey


def factorised_body(setup: GearSetup, stages: dict | None = None):
    """The gear's meshed, assembled and factorised FE body (`solver.fe.body.BodyModel`), kept
    in memory by `FE_CACHE` for every FE result of the same body: the spring map, its fillet
    stress and the influence coefficients share one factorisation (the body depends on the
    geometry, material and mesh only, not on the load or the pivot). ``stages``: if given and
    the body is built, the wall and CPU seconds of meshing, assembly and factorisation.

    A body with a web or hub is solved through its teeth and rim condensed once per rim height
    (`condensed_rim`, `solver.fe.condense`): it factors only its web, with the same results as
    the whole-body factorisation to rounding. Should its rim's mesh ever differ from the
    condensed one, the whole body is factorised instead."""
    from solver.fe import body as fe
    from solver.fe.condense import RimMismatch, assemble_condensed, join_rim
    from solver.fe.mesh import mesh_body

    def build():
        t0, c0 = time.perf_counter(), time.process_time()
        geo, body = setup.geometry, setup.body

        def mesh(rim=True):
            return mesh_body(geo, body, setup.mesh_size, prefix=f"{setup.prefix}.body", grading=setup.mesh_grading, rim=rim)
        whole, model = None, None
        has_web = body.web_height > 0 or body.hub_height > 0
        if CONDENSE and has_web:
            try:        # the rim of this rim height (kept, read from disk or condensed), the web meshed alone
                rim = condensed_rim(setup)
                whole = join_rim(rim, mesh(rim=False))
                t1, c1 = time.perf_counter(), time.process_time()    # a rim's own cost is not the body's
                model = assemble_condensed(whole, geo.spec.face_width, body.web_thickness, setup.material, rim)
            except RimMismatch:
                whole, model = None, None
        if model is None:
            whole = whole or mesh()
            t1, c1 = time.perf_counter(), time.process_time()
            model = fe.assemble(whole, geo.spec.face_width, body.web_thickness, setup.material)
        if stages is not None:
            stages.update(mesh_wall_s=t1 - t0, mesh_cpu_s=c1 - c0,    # with the rim's, when condensed here
                          assembly_wall_s=model.assembly_time, assembly_cpu_s=model.assembly_cpu,
                          factor_wall_s=model.factor_time, factor_cpu_s=model.factor_cpu)
        return model
    return FE_CACHE.body(body_key(setup), build)


def body_key(setup: GearSetup) -> str:
    """The key `factorised_body` keeps the gear's body by: its settings less the load and the
    pivot (the body does not depend on them)."""
    return json.dumps({k: v for k, v in setup.settings.items() if k not in ("force", "pivot")}, sort_keys=True, default=float)


def held_body(setup: GearSetup):
    """The gear's factorised body if this process holds it already (`factorised_body` made it
    and it is among the last kept), else None: nothing is built."""
    return FE_CACHE.held_body(body_key(setup))


CONDENSE = True         # solve bodies with a web or hub through their condensed teeth and rim
RIM_VERSION = "2"       # bump when the condensation changes (it is in every rim key); 2: condensed from `rim_source`


def rim_key(setup: GearSetup) -> str:
    """Cache key of the gear's teeth and rim: everything they depend on (tooth, rim height,
    material, mesh size and grading, code versions), not the web, hub or holes."""
    st = setup.settings
    return FE_CACHE.key({"tooth": st["tooth"], "rim_height": setup.body.rim_height, "material": st["material"],
                         "size": st["size"], "grading": setup.mesh_grading, "version": st["version"], "rim": RIM_VERSION})


def rim_source(setup: GearSetup) -> BodySpec:
    """The body a rim is condensed from: the gear's teeth and rim over a plain hub down to half
    the rim's inner radius, made of the rim key's content alone. Two bodies' meshes hold the same
    rim elements, but gmsh places their nodes a few 1e-15 m apart (1e-13 in a body's stiffness
    and root stress): condensed from whichever body asked first, a body's bits would depend on
    the order the bodies of its rim were computed in."""
    r_in = setup.geometry.root_radius - setup.body.rim_height
    return BodySpec(rim_height=setup.body.rim_height, web_height=0.0, hub_height=0.5 * r_in,
                    web_thickness=setup.geometry.spec.face_width)


def condensed_rim(setup: GearSetup):
    """The gear's teeth and rim condensed onto the web (`solver.fe.condense.RimBlock`), from the
    mesh of `rim_source`, kept by `FE_CACHE` in memory and, its condensed stiffness and its mesh,
    on disk (``rim-{key}.npz``): the same bits for every body of the rim, whichever came first,
    in this process or another."""
    from solver.fe.condense import RimMismatch, rim_block
    from solver.fe.mesh import BodyMesh, mesh_body

    key = rim_key(setup)

    def build():
        geo = setup.geometry
        r_if = geo.root_radius - setup.body.rim_height
        stored = FE_CACHE.read_arrays(f"rim-{key}")
        if stored is not None:
            try:
                own = BodyMesh(stored["points"], stored["triangles"], stored["region"], 0.5 * r_if, setup.mesh_size)
                rim = rim_block(own, geo.spec.face_width, setup.material, r_if, S=stored["S"])
                if rim.keys.shape == stored["keys"].shape and np.allclose(rim.keys, stored["keys"], rtol=0, atol=1e-9):
                    rim.key = key
                    return rim
            except (RimMismatch, KeyError):
                pass
        mesh = mesh_body(geo, rim_source(setup), setup.mesh_size, prefix=f"{setup.prefix}.body", grading=setup.mesh_grading)
        rim = rim_block(mesh, geo.spec.face_width, setup.material, r_if)
        rim.key = key
        rm = rim.model.mesh
        FE_CACHE.write_arrays(f"rim-{key}", S=rim.S, keys=rim.keys, points=rm.points, triangles=rm.triangles, region=rm.region)
        return rim
    return FE_CACHE.rim(key, build)
