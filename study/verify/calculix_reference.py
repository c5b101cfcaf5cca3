"""The independent FE contact peer's STE of a scene as a reference archive (`lightgear reference
--solver calculix`): the same variables as the project's own reference (`ste` over `angle` [um],
the attribute `backlash_offset_um`), so that a run, the LTCA reference and the peer compare
variable by variable. The peer itself is `solver.peers.calculix`.
"""
from __future__ import annotations

import dataclasses
import math
import sys
import time

import numpy as np
import xarray as xr

from solver import units
from solver.peers.calculix import (
    ATTEMPTS,
    CalculixSettings,
    PeerGear,
    deck_cpu_limit,
    default_settings,
    ste_sweep,
)
from solver.peers.calculix.mesh import round_size
from study.modification import tip_edge_attrs, tip_edge_radii
from study.scene import Scene, SceneError
from study.scene_model import geometry_model

# CPU time [s] of one deck at the default flank size (module/30): the paper pair, ~140,000 nodes,
# 5-10 Newton iterations of ~25 s; a deck's nodes, and its time, grow about as 1/flank_size
# (the small pair at 0.15 mm: 106 s). Only the estimate printed before a run and checked
# against --max-time uses it.
DECK_S = 200.0
# Peak memory of the ccx process of one deck (one at a time): 37 kB a node, measured on the
# small pair (24 teeth, module 3 mm) at flank sizes of 0.4 and 0.2 mm: 18 000 and 38 000 nodes,
# 0.68 and 1.38 GB; its nodes at module/30 taken between its 74 000 and the paper pair's 140 000
# (within 1.4 x of both), growing as 1/flank_size like the time.
DECK_BYTES_PER_NODE = 3.7e4
DECK_NODES = 1.0e5
# The tip edge radius [mm] at which the LTCA's tip-corner contacts (`lightgear reference
# --tip-edge-radius`) read like the peer's sharp corners meshed at 0.1 mm on the flanks: on the
# solid and the paper pair at 50 and 100 N·m every single-contact position within 0.4 %
# (docs/models.md). The peer's corner is sharp, so this is a property of its mesh, not of a gear.
PEER_TIP_EDGE_RADIUS_MM = 0.035


def peer_estimate(n_decks: int, settings: CalculixSettings, module: float):
    """`study.estimate.Estimate` of a peer run: ``n_decks`` decks at ``settings``, module [m]:
    seconds of all decks, bytes of the ccx process of one."""
    from study.estimate import Estimate
    scale = module / 30.0 / settings.sizes.flank
    return Estimate(seconds={"CalculiX decks": n_decks * DECK_S * scale},
                    memory={"CalculiX deck": DECK_BYTES_PER_NODE * DECK_NODES * scale},
                    levers={"CalculiX decks": "fewer angles (a larger --step) or a larger --flank-size"})


def peer_gears(scene: Scene) -> tuple:
    """(PeerGear, PeerGear) of the scene: geometry, body, profile modification and tip edge
    radius of each gear."""
    model = geometry_model(scene)
    out = []
    for g, gi in zip(model.geometry, model.inputs[:2]):
        dev, edge = None, 0.0
        if gi.modification is not None:
            mod, uf, ut = gi.modification, g.u_form, g.u_tip
            dev = (lambda u, mod=mod, uf=uf, ut=ut: mod.deviation(u, uf, ut))
            edge = mod.tip_edge_radius
        out.append(PeerGear(g, gi.body, dev, edge))
    return tuple(out), model


def settings_for(scene: Scene, flank_size_mm: float | None = None, contact_stiffness: float | None = None,
                 thin_decks: bool = False) -> CalculixSettings:
    """Peer settings of a scene: `solver.peers.calculix.default_settings` from gear 1's module, with
    ``flank_size_mm`` [mm] the element size at the flanks, ``contact_stiffness`` [MPa/mm] and
    ``thin_decks`` (`solver.peers.calculix.deck_thickness_scale`: plane stress)."""
    import dataclasses
    m = scene.gear1.module * units.MM
    if flank_size_mm is not None and not (0 < flank_size_mm <= scene.gear1.module / 2):
        raise SceneError("--flank-size", f"must lie in (0, module/2 = {scene.gear1.module / 2:.4g} mm], got {flank_size_mm} mm")
    s = default_settings(m, None if flank_size_mm is None else flank_size_mm * units.MM)
    if contact_stiffness is not None:
        if not contact_stiffness > 0:
            raise SceneError("--contact-stiffness", f"must be positive, got {contact_stiffness} MPa/mm")
        s = dataclasses.replace(s, contact_stiffness=contact_stiffness * units.MPA * units.MM_PER_M)
    return dataclasses.replace(s, thin_decks=bool(thin_decks))


def calculix_dataset(scene: Scene, angles=None, settings: CalculixSettings | None = None, progress: bool = False,
                     keep: str | None = None, starts=None) -> xr.Dataset:
    """Peer reference archive of the scene at driver ``angles`` [rad] (default: the quasi-static
    angles) under quasi_static.torque; ``progress``: a line per deck on stderr; ``starts``: each
    deck's start approach [m] (`solver.peers.calculix.ste_sweep`)."""
    from study.archive.netcdf import cf_variable, provenance
    from study.scene_model import static_angles

    torque = scene.quasi_static.torque
    if not torque > 0:
        raise SceneError("quasi_static.torque", f"the contact peer needs a positive (drive-side) torque, got {torque}")
    angles = static_angles(scene) if angles is None else np.asarray(angles, float)
    gears, model = peer_gears(scene)
    settings = settings or settings_for(scene)
    t_start = time.perf_counter()

    def report(i, n, te, wall):
        if progress:
            done = time.perf_counter() - t_start
            print(f"  deck {i + 1}/{n} at {math.degrees(angles[i]):.3f} deg: elastic STE "
                  f"{(te - model.backlash_offset) * units.UM_PER_M:.4f} um ({wall:.0f} s; about "
                  f"{done / (i + 1) * (n - i - 1):.0f} s left)", file=sys.stderr, flush=True)

    if keep:
        settings = dataclasses.replace(settings, keep=keep)
    res = ste_sweep(gears, model.pair, scene.material_spec(), angles, torque, settings, progress=report, starts=starts)
    nodes = sum(m.n_nodes for m in res.meshes)
    coords = {"angle": cf_variable("angle", np.degrees(res.angle), "degree", "driver rotation from the nominal position")}
    off = res.backlash_offset
    data = {
        "ste": cf_variable("angle", res.te * units.UM_PER_M, "um", "FE contact peer static transmission error rb1*theta1 + rb2*theta2",
                           comment=f"CalculiX, both gears meshed in full in penalty contact; rigid teeth in drive contact read +{off * 1e6:.4f} um"),
        "deck_wall_time": cf_variable("angle", res.wall_time_s, "s", "wall time of each CalculiX deck"),
        "deck_cpu_time": cf_variable("angle", res.cpu_time_s, "s", "CPU time of the ccx process of each deck"),
    }
    s = res.settings
    attrs = {"title": f"FE contact peer (CalculiX): {scene.title}", "scene": scene.to_toml(),
             "solver": "calculix", "ccx_version": res.version,
             "backlash_offset_um": off * units.UM_PER_M, "contact_ratio": model.pair.contact_ratio,
             "mesh_order": float(scene.gear2.teeth), "hole_order": float(scene.gear2.body.holes),
             "static_torque_N_m": float(torque),
             "element_type": "CPS6 (6-node plane-stress triangle; thickness = face width, web thickness in the web)",
             **tip_edge_attrs(tip_edge_radii((scene.gear1, scene.gear2))),
             **({"tip_edge_mesh_size_mm": np.array([round_size(g.edge_radius, s.sizes.flank) * units.MM_PER_M
                                                    if g.edge_radius > 0 else 0.0 for g in gears])}
                if any(g.edge_radius > 0 for g in gears) else {}),
             "flank_mesh_size_mm": s.sizes.flank * units.MM_PER_M, "fillet_mesh_size_mm": s.sizes.fillet * units.MM_PER_M,
             "body_mesh_size_mm": s.sizes.body * units.MM_PER_M,
             "contact_stiffness_MPa_per_mm": s.contact_stiffness / units.MPA * units.MM,
             "deck_thickness_scale": s.deck_scale(max(scene.gear1.face_width, scene.gear2.face_width) * units.MM),
             "fine_teeth_each_side": s.fine_teeth, "contact_teeth_each_side": s.contact_teeth,
             "deck_cpu_limit_s": deck_cpu_limit(res.meshes, s),
             "deck_attempts": "; ".join(f"{'soft start (contact stiffness x' + format(soft, 'g') + ', then stiffened)' if soft else 'stiff contact'}"
                                        f" from {frac:g} x the start approach" for frac, soft in ATTEMPTS),
             "nodes": nodes, "elements": sum(m.n_elements for m in res.meshes),
             "wall_time_reference_s": time.perf_counter() - t_start, "cpu_time_ccx_s": float(res.cpu_time_s.sum()),
             "method": "FE contact analysis: both gears meshed in full (quadratic plane-stress triangles), driver bore fixed, "
                       "driven bore a rigid body under the resisting torque, frictionless node-to-surface penalty contact "
                       "between the real drive flanks and tip arcs; STE from the rigid body's rotation",
             "te_convention": "TE = rb1*theta1 + rb2*theta2, positive when the driven gear lags, zero at the zero-backlash conjugate position",
             **provenance()}
    return xr.Dataset(data, coords=coords, attrs=attrs)
