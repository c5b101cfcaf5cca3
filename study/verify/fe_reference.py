"""FE reference STE of a scene: loaded-tooth-contact analysis with FE influence coefficients.

`reference_dataset(scene)` takes both gear bodies' bulk compliance between the drive flank points
of the teeth that meet the mesh over the scene's quasi-static rotation
(`study.inputs.compliance.gear_compliance`: the FE body of `solver.fe.body`, same mesh size and
load patch as the tooth springs, influence coefficients of `solver.fe.ltca`) and solves the
loaded contact at every angle of ``quasi_static`` with the scene's contact law in series. The
compliance is cached in memory and on disk (`study.inputs.cache`), so a second run only solves
the contact problems.

CLI: ``lightgear reference [SCENE] [-o OUT.nc] [--set k=v] [--step DEG]``.
"""
from __future__ import annotations

import time

import numpy as np
import xarray as xr

from solver import units
from solver.fe.ltca import ltca_sweep, teeth_in_mesh
from study.archive.run_variables import opening_attrs
from study.inputs.compliance import PROFILE_POINTS, gear_compliance
from study.inputs.gearsetup import gear_setups
from study.modification import tip_edge_attrs, tip_edge_radii
from study.scene import Scene, SceneError, opening_text
from study.scene_model import geometry_model, static_angles

# the reference holds about four times the arrays of a static analysis an angle (contacts and
# load sharing per angle): its angles are checked against memory with this factor
REFERENCE_MEMORY_FACTOR = 4.0

# Seconds of one of the reference's FE bodies (mesh, assembly, factorisation and influence
# coefficients) by its elements n (`study.estimate.body_elements`, the fine grading's
# `study.estimate.FINE_GRADING_COST` times as dear, as their memory `study.estimate.body_bytes`):
# fitted to the CPU time of `lightgear reference` from an empty FE cache on 2 shared cores (load
# 10-15): the small lightened pair with a 1.5 mm rim at fe.mesh_size 0.5-0.18 mm
# and the paper pair with a 2.5 mm rim at 0.375-0.25 mm, graded and fine (3.5-62 s CPU, each
# within 0.8-1.4 x; benchmarks/bench_reference_cost.py).
REF_S_PER_BODY = 0.5             # s: mesher and set-up of a body
REF_S_PER_ELEMENT = 2.2e-4       # s an element
LTCA_S_PER_ANGLE = 1.0e-3        # s: contact solve of one angle (0.7-1.4 s for 1201 measured)


def body_cost(setup) -> tuple[float, float]:
    """(CPU seconds on a quiet machine, peak bytes) of one FE body of the reference."""
    from study.estimate import FINE_GRADING_COST, body_bytes, body_elements
    n = body_elements(setup) * (FINE_GRADING_COST if setup.mesh_grading == "fine" else 1.0)
    return REF_S_PER_BODY + REF_S_PER_ELEMENT * n, body_bytes(setup)


def reference_cost(scene: Scene, angles, teeth=None):
    """`study.estimate.Estimate` of the reference at driver ``angles`` [rad]: seconds (scaled by
    the machine's load) and bytes of each gear's FE body (none when its influence coefficients
    are cached) and of the contact sweep. ``teeth``: (teeth of gear 1, of gear 2, spread) in
    mesh over ``angles`` (`solver.fe.ltca.teeth_in_mesh`; None: found here, from the geometry)."""
    from study.estimate import TEETH_SEARCH_ANGLES, Estimate, load_factor
    from study.inputs.compliance import compliance_cached
    from study.scene_model import STATIC_BYTES_PER_ANGLE, STATIC_BYTES_PER_ANGLE_TOOTH
    if teeth is None and len(angles) <= TEETH_SEARCH_ANGLES:
        teeth = teeth_in_mesh(geometry_model(scene), angles)
    est, load = Estimate(), load_factor()
    for i, (g, s) in enumerate(zip((1, 2), gear_setups(scene))):
        cached = teeth is not None and compliance_cached(s, teeth[i], teeth[2])
        sec, size = (0.0, 0.0) if cached else body_cost(s)
        est.seconds[f"gear {g} FE body"], est.memory[f"gear {g} FE body"] = sec * load, size
    est.seconds["contact sweep"] = LTCA_S_PER_ANGLE * len(angles) * load
    est.memory["contact sweep"] = REFERENCE_MEMORY_FACTOR * len(angles) * (
        STATIC_BYTES_PER_ANGLE + STATIC_BYTES_PER_ANGLE_TOOTH * scene.gear1.teeth)
    return est


def check_reference_memory(scene: Scene, est, field: str = "fe.mesh_size", what: str | None = None,
                           lever: str = "a coarser fe.mesh_size (or fewer teeth)") -> str | None:
    """Refuse (BudgetError naming ``field``) a reference whose estimated memory ``est.memory``
    exceeds `study.estimate.MEMORY_REFUSE` of the memory available, before any FE work; a line
    to warn with beyond `study.estimate.MEMORY_WARN`, else None. ``what``: what needs it (default:
    the FE bodies of the scene's mesh); ``lever``: what needs less."""
    from study import estimate
    from study.memory import bytes_text
    need = sum(est.memory.values())
    if what is None:
        elements = " and ".join(f"{estimate.body_elements(s):.3g}" for s in gear_setups(scene))
        what = (f"the FE bodies need about {{need}} for the reference ({elements} elements at fe.mesh_size "
                f"{gear_setups(scene)[1].mesh_size * 1e3:.3g} mm, {scene.fe.mesh_grading})")
    return estimate.check_memory(need, field, what.format(need=bytes_text(need)), lever)


def reference(scene: Scene, angles=None, rigid: bool = False, n_u: int = PROFILE_POINTS, progress: bool = False,
              tip_edge_radius: float | None = None):
    """(LTCAResult, model, info) of the scene at driver ``angles`` [rad] (default: quasi-static).

    ``rigid``: rigid bodies, only the contact law deforms (the closed-form check);
    ``n_u``: profile points per flank of the influence coefficients; ``progress``: a bar on
    stderr (unit: the estimated second) when the run is expected to be long;
    ``tip_edge_radius`` [m]: both gears' tip-corner contacts carry the compliance of an edge of
    that radius (`tip_edge`), on the corners' geometry as the scene has it; None: each gear's
    ``modification.tip_edge_radius`` (`scene_edges`; 0: under the flanks' contact law). The
    scene's radius also rounds the corners' geometry (the model's gear_par EDGE_*,
    `solver.fe.ltca.mesh_points`)."""
    from study import estimate
    qs = scene.quasi_static
    if not qs.torque > 0:
        raise SceneError("quasi_static.torque", f"the FE reference needs a positive (drive-side) torque, got {qs.torque}")
    angles = static_angles(scene, memory_factor=REFERENCE_MEMORY_FACTOR) if angles is None else np.asarray(angles, float)
    model = geometry_model(scene)        # the LTCA takes its compliance from the FE, not springs
    teeth = None if rigid else teeth_in_mesh(model, angles)
    parts = reference_cost(scene, angles, teeth).seconds if not rigid else {"contact sweep": 0.0}
    bar = estimate.progress_bar(sum(parts.values()), sum(parts.values()), "FE reference", "s (estimated)", progress)
    edge = scene_edges(scene, model, tip_edge_radius)
    try:
        return _reference(scene, angles, rigid, n_u, model, _Stages(bar, parts), teeth, edge)
    finally:
        if bar is not None:
            bar.close()


def tip_edge(scene: Scene, model, radius: float):
    """`solver.fe.ltca.TipEdge` of the scene for a tip edge radius [m]: the contact law's radius
    is the pair's equivalent radius of curvature at the pitch point, where its Weber fit is taken
    (`solver.identify.weber`). SceneError naming --tip-edge-radius for a radius that is not
    positive or not below the module."""
    import math

    from solver.fe.ltca import TipEdge
    from solver.tip_edge import law_radius
    if not (isinstance(radius, (int, float)) and math.isfinite(radius) and 0 < radius < scene.gear1.module * units.MM):
        raise SceneError("--tip-edge-radius", f"must be a positive radius below the module ({scene.gear1.module:g} mm), "
                                              f"got {radius * units.MM_PER_M if isinstance(radius, (int, float)) else radius!r} mm")
    b = min(scene.gear1.face_width, scene.gear2.face_width) * units.MM
    return TipEdge(float(radius), scene.material_spec().youngs_modulus, b, law_radius(*model.geometry))


def edge_radii(scene: Scene, tip_edge_radius: float | None = None) -> tuple[float, float]:
    """(gear 1, gear 2) tip edge radius [m] the LTCA takes: ``tip_edge_radius`` [m] for both
    where given (`lightgear reference --tip-edge-radius`), else the scene's
    ``gearN.modification.tip_edge_radius`` (0: a sharp corner)."""
    if tip_edge_radius is not None:
        return float(tip_edge_radius), float(tip_edge_radius)
    return tip_edge_radii((scene.gear1, scene.gear2))


def scene_edges(scene: Scene, model, tip_edge_radius: float | None = None):
    """(gear 1's, gear 2's) `solver.fe.ltca.TipEdge` or None (a sharp corner) of `edge_radii`;
    None where neither gear has one."""
    radii = edge_radii(scene, tip_edge_radius)
    if not any(radii):
        return None
    return tuple(tip_edge(scene, model, r) if r > 0 else None for r in radii)


def tip_corner_law(radii) -> str:
    """In words, the local law of the tip-corner contacts of tip edge radii (gear 1, gear 2) [m]."""
    if not any(radii):
        return "the flanks' contact law"
    r1, r2 = (r * units.MM_PER_M for r in radii)
    return (f"the flanks' contact law + in series the compliance of the rounded tip edge (radius {r1:g} mm on gear 1, "
            f"{r2:g} mm on gear 2; 0: a sharp corner): its Hertz patch against the mating flank instead of the two flanks'; "
            "a corner the scene rounds (gearN.modification.tip_edge_radius) meets the flank with the round's circle")


class _Stages:
    """The progress bar's stages of one reference (None: no bar): each stage's estimated
    seconds (``parts``) added when it is done."""

    def __init__(self, bar, parts: dict):
        self.bar, self.parts = bar, parts

    def stage(self, name: str):
        if self.bar is not None:
            self.bar.set_postfix_str(name)

    def done(self, name: str):
        if self.bar is not None:
            self.bar.update(self.parts[name])


def _reference(scene, angles, rigid, n_u, model, stages: _Stages, teeth=None, edge=None):
    stage, done = stages.stage, stages.done
    info = {}
    t0, c0 = time.perf_counter(), time.process_time()
    if rigid:
        comp = (None, None)
    else:
        t1, t2, spread = teeth or teeth_in_mesh(model, angles)
        info.update(wall_time_teeth_s=time.perf_counter() - t0, cpu_time_teeth_s=time.process_time() - c0)
        setup1, setup2 = gear_setups(scene)
        stage("gear 1 FE body")
        c1, i1 = gear_compliance(setup1, t1, spread, n_u)
        done("gear 1 FE body")
        stage("gear 2 FE body")
        c2, i2 = gear_compliance(setup2, t2, spread, n_u)
        done("gear 2 FE body")
        comp = (c1, c2)
        info.update(gear1=i1, gear2=i2)
    info.update(wall_time_compliance_s=time.perf_counter() - t0, cpu_time_compliance_s=time.process_time() - c0)
    t0, c0 = time.perf_counter(), time.process_time()
    stage("contact sweep")
    res = ltca_sweep(model, comp, angles, scene.quasi_static.torque, edge=edge)
    info.update(wall_time_contact_s=time.perf_counter() - t0, cpu_time_contact_s=time.process_time() - c0)
    return res, model, info


def reference_dataset(scene: Scene, angles=None, progress: bool = False, tip_edge_radius: float | None = None) -> xr.Dataset:
    """FE reference archive: ste, load sharing and contacts over the driver angle (``progress``,
    ``tip_edge_radius`` [m]: see `reference`)."""
    from study.archive.netcdf import cf_variable, provenance

    t0 = time.perf_counter()
    res, model, info = reference(scene, angles, progress=progress, tip_edge_radius=tip_edge_radius)
    wall = time.perf_counter() - t0
    coords = {"angle": cf_variable("angle", np.degrees(res.angle), "degree", "driver rotation from the nominal position"),
              "driver_tooth": cf_variable("driver_tooth", np.arange(model.teeth[0]), "1", "driver tooth index")}
    off = res.backlash_offset
    data = {
        "ste": cf_variable("angle", res.te * units.UM_PER_M, "um", "FE reference static transmission error rb1*theta1 + rb2*theta2",
                            comment=f"LTCA with FE influence coefficients; rigid teeth in drive contact read +{off * 1e6:.4f} um"),
        "ste_contacts": cf_variable("angle", res.n_contacts.astype("int16"), "1", "loaded tooth contacts"),
        "ste_tooth_force": cf_variable(("angle", "driver_tooth"), res.tooth_force, "N", "normal contact force on each driver tooth"),
        "extended_contact_force": cf_variable("angle", res.extended, "N", "force carried by tip-corner contacts outside the path of contact"),
    }
    shaped = [opening_text(scene.gear(g).body) for g in (1, 2) if scene.gear(g).body.holes and scene.gear(g).body.opening != "round"]
    attrs = {"title": f"FE reference (LTCA): {scene.title}" + "".join(f"; {t}" for t in shaped), "scene": scene.to_toml(),
             **opening_attrs(scene),
             "backlash_offset_um": off * units.UM_PER_M, "contact_ratio": model.pair.contact_ratio,
             "mesh_order": float(scene.gear2.teeth), "hole_order": float(scene.gear2.body.holes),
             "static_torque_N_m": res.torque, "wall_time_reference_s": wall,
             "wall_time_compliance_s": info["wall_time_compliance_s"], "wall_time_contact_s": info["wall_time_contact_s"],
             "profile_points": PROFILE_POINTS,
             **tip_edge_attrs(edge_radii(scene, tip_edge_radius)),
             "fe_mesh_size_mm": info["gear2"]["mesh_size_m"] * 1e3,
             "method": "loaded-tooth-contact analysis: bulk FE compliance read at the tooth centreline (both bodies, "
                       "clamped at the bore, all loaded teeth coupled) + contact law k_con*delta^m1 in series",
             "tip_corner_law": tip_corner_law(edge_radii(scene, tip_edge_radius)),
             "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
             **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)
