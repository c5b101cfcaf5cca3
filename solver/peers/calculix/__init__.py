"""Independent FE contact peer: the static transmission error of a gear pair solved by CalculiX.

Both gears are meshed in full (`mesh`: the FE body's outline, holes, web, relief and rounded tip
edges; quadratic
plane-stress triangles, fine on the flanks and fillets of the teeth around the mesh), placed at
each driver angle at their nominal positions with the driven gear turned into its rigid drive
contact (TE = jn/2) plus a start approach, and pressed together by the resisting torque on the
driven gear's bore (a rigid body) against the driver's fixed bore with frictionless penalty
contact between the real flanks and tip arcs (`deck`, `run`). The local flattening at the
contact comes from the mesh itself, not from a contact law, and nothing is read at a tooth
centreline: the only result is the driven gear's rigid rotation.

    TE = rb1*theta1 + rb2*theta2 = jn/2 + start + rb2*U3,    elastic STE = TE - jn/2,

U3 the rotation of the rigid body's ROT NODE (counter-clockwise, the driven gear held back).
Units: SI (m, N, rad, N·m, Pa); the deck is written in N, mm, MPa (`deck`).
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from solver.geometry import BodySpec, GearGeometry, Material, PairGeometry
from solver.peers.calculix.deck import GearPlacement, write_deck
from solver.peers.calculix.mesh import GearMesh, MeshSizes, mesh_gear, teeth_near
from solver.peers.calculix.run import CalculixFailed, CalculixMissing, ccx_path, ccx_version, run_deck

__all__ = ["ATTEMPTS", "CalculixFailed", "CalculixMissing", "CalculixSettings", "PeerGear", "PeerResult", "ccx_path",
           "ccx_version", "deck_cpu_limit", "deck_thickness_scale", "default_settings", "pair_meshes", "ste_sweep"]


# stiffness of the driven gear's ground spring over the mesh's (`deck.write_deck`)
GROUND_FRACTION = 1e-4
# the attempts at a deck, in order: (start approach over the given one, soft_start of
# `deck.write_deck`). The stiff penalty in one step converges in 5-10 Newton iterations where the
# contact patch spans several elements; where it spans one or two (a single pair near the tip,
# a low load) its few nodes chatter in and out and the step never converges (the 12-hole body
# at 4.0 deg; the relieved pair's single-contact decks crawl): a penalty 1/8 as stiff first,
# then stiffened, settles them in about 1.3 times a converging stiff deck's iterations. So the
# soft start first, the stiff deck where it chatters too, then the soft start from nearer.
ATTEMPTS = ((1.0, 0.125), (1.0, 0.0), (0.7, 0.125))
# CPU seconds a deck may use per node of the pair, all attempts together, and at least
DECK_CPU_PER_NODE = 6e-3
DECK_CPU_MIN = 120.0
# wall seconds allowed per CPU second of the limit (a shared machine gives ccx a fraction of a core)
WALL_PER_CPU = 10.0


def deck_thickness_scale(face_width: float, flank_size: float) -> float:
    """Factor [1] on every thickness and load of a deck so that its thickest section is as thick as
    the flank elements are wide. CalculiX expands a plane-stress triangle (CPS6) into one layer of
    3D elements of the section's thickness, and a layer much thicker than the triangles are wide
    cannot contract freely through its thickness: on the same mesh and load (a 17.19 mm disc, a
    point load on its rim, 0.1 mm elements there) a 17 mm deck reads 2-3 % stiffer than plane
    stress in the body and 6.6 % at the load, a 100 mm one 6-8 %, a 0.1 mm one within 0.3 % and
    0.9 %. Plane stress scales with thickness and load together (displacements unchanged,
    pressures unchanged), so the deck is written that thin and the result is the plane-stress one."""
    return min(1.0, flank_size / face_width)


@dataclass(frozen=True)
class CalculixSettings:
    """Mesh and contact settings of the peer (SI)."""

    sizes: MeshSizes
    contact_stiffness: float     # Pa/m, slope of the linear pressure-overclosure law
    fine_teeth: int = 3          # teeth each side of the line of centres meshed fine (at every angle)
    contact_teeth: int = 2       # teeth each side whose drive flanks and tips are contact faces
    both_ways: bool = True       # a second contact pair, gear 1 the slave (`deck.write_deck`)
    deck_cpu_s: float | None = None  # CPU seconds a deck may use (None: `deck_cpu_limit`'s default)
    thin_decks: bool = False     # decks as thin as the flank elements (`deck_thickness_scale`): plane stress
    keep: str | None = None      # a folder that keeps each deck's files (None: a temporary one, removed)

    def deck_scale(self, face_width: float) -> float:
        """Factor [1] on every thickness and load of the decks of a pair whose widest face is
        ``face_width`` [m]: `deck_thickness_scale` with ``thin_decks``, else 1 (the full face
        width, 2-6 % stiffer than plane stress)."""
        return deck_thickness_scale(face_width, self.sizes.flank) if self.thin_decks else 1.0


def default_settings(module: float, flank_size: float | None = None) -> CalculixSettings:
    """Defaults from the module [m]: flanks at module/30 (0.05 mm at m 1.5 mm), fillets at twice
    that, the rest of the outline at module/2; contact stiffness 2e7 MPa/mm (the penalty's own
    approach then ~0.05 um at 1000 MPa of contact pressure, about 1 % of the STE)."""
    h = flank_size or module / 30.0
    return CalculixSettings(MeshSizes(flank=h, fillet=2.0 * h, body=max(module / 2.0, 4.0 * h)),
                            contact_stiffness=2e7 * 1e6 * 1e3)


@dataclass(frozen=True)
class PeerGear:
    """One gear of the pair as the peer needs it (SI)."""

    geometry: GearGeometry
    body: BodySpec
    deviation: object = None     # None or u -> flank deviation [m] (profile modification)
    edge_radius: float = 0.0     # tip edge radius [m] (`solver.tip_edge`); 0: sharp tip corners


@dataclass
class PeerResult:
    """Elastic STE over driver angles and what produced it."""

    angle: np.ndarray            # driver rotation [rad]
    te: np.ndarray               # rb1*theta1 + rb2*theta2 [m]
    backlash_offset: float       # jn/2 [m]
    meshes: tuple                # (GearMesh, GearMesh)
    wall_time_s: np.ndarray      # per deck
    cpu_time_s: np.ndarray       # per deck (ccx)
    settings: CalculixSettings
    version: str

    @property
    def elastic_ste(self) -> np.ndarray:
        """TE - jn/2 [m]."""
        return self.te - self.backlash_offset


def pair_meshes(gears: tuple, pair: PairGeometry, angles, settings: CalculixSettings) -> tuple[GearMesh, GearMesh]:
    """Both gears meshed once for all ``angles`` [rad]: the teeth within `fine_teeth` pitches of
    the line of centres at any angle fine, those within `contact_teeth` with contact faces."""
    g1, g2 = gears[0].geometry, gears[1].geometry
    th2 = -g1.base_radius * np.asarray(angles) / g2.base_radius
    out = []
    for i, (pg, th, axis0, target) in enumerate(((gears[0], angles, 0.0, 0.0),
                                                 (gears[1], th2, math.pi + math.pi / g2.teeth, math.pi))):
        g = pg.geometry
        fine = teeth_near(g.pitch_angle, axis0, target, th, settings.fine_teeth)
        contact = teeth_near(g.pitch_angle, axis0, target, th, settings.contact_teeth)
        out.append(mesh_gear(g, pg.body, settings.sizes, fine, contact, pg.deviation, prefix=f"gear{i + 1}.body",
                             edge_radius=pg.edge_radius))
    return tuple(out)


def start_approach(gears: tuple, material: Material, torque: float) -> float:
    """A first guess of the loaded approach [m] along the line of action: the normal load over
    about 10 N/(mm·um) of face width (the mesh stiffness of a pair with the bodies' wind-up)."""
    g1, g2 = gears[0].geometry, gears[1].geometry
    b = min(g1.spec.face_width, g2.spec.face_width)
    load = torque / g2.base_radius
    return load / (10.0e6 * 1e3 * b) * (material.youngs_modulus / 206e9) ** -1


def deck_cpu_limit(meshes, settings: CalculixSettings) -> float:
    """CPU seconds one deck may use, all its attempts together: ``settings.deck_cpu_s``, or
    `DECK_CPU_PER_NODE` per node of the pair (a converging deck of the paper pair at 0.1 mm,
    ~66,000 nodes, takes 60-120 s; the limit is 400 s), at least `DECK_CPU_MIN`."""
    if settings.deck_cpu_s is not None:
        return float(settings.deck_cpu_s)
    return max(DECK_CPU_MIN, DECK_CPU_PER_NODE * sum(m.n_nodes for m in meshes))


def ste_sweep(gears: tuple, pair: PairGeometry, material: Material, angles, torque: float,
              settings: CalculixSettings, progress=None, starts=None) -> PeerResult:
    """STE at every driver angle [rad] under the resisting ``torque`` [N·m] on gear 2, one deck
    an angle. ``progress(i, n, te_m, wall_s)``: called after each deck. Each deck starts from
    ``starts[i]`` [m] (an approach near the loaded one, e.g. a model's elastic STE: fewer Newton
    iterations; the result does not depend on it) or else from the previous deck's approach (the
    first from `start_approach`), and is tried as `ATTEMPTS` says until one converges, within
    `deck_cpu_limit` CPU seconds in all; `CalculixFailed` (one line: the angle, each attempt's
    reason) when none does. ``settings.keep``: a folder that keeps each deck's files."""
    ccx_path()
    angles = np.asarray(angles, float)
    meshes = pair_meshes(gears, pair, angles, settings)
    limit = deck_cpu_limit(meshes, settings)
    jn2 = 0.5 * pair.normal_backlash
    te = np.empty(angles.size)
    wall, cpu = np.empty(angles.size), np.empty(angles.size)
    start = start_approach(gears, material, torque)
    deck = _Deck(gears, meshes, pair, material, torque, settings, limit)
    for a, th1 in enumerate(angles):
        t0 = time.perf_counter()
        if starts is not None:
            start = float(starts[a])
        res, s, used = deck.solve(a, th1, start)
        # the ground spring took ground * U3 of the torque: back to the full torque along the
        # pair's secant stiffness (a correction of order 1e-4 of the start error)
        te[a] = jn2 + s + gears[1].geometry.base_radius * res.rotation * (1.0 + GROUND_FRACTION)
        wall[a], cpu[a] = time.perf_counter() - t0, used
        start = te[a] - jn2
        if progress is not None:
            progress(a, angles.size, te[a], wall[a])
    return PeerResult(angles, te, jn2, meshes, wall, cpu, settings, ccx_version())


@dataclass(frozen=True)
class _Deck:
    """What every deck of a sweep shares: the gears and their meshes, the pair, the material,
    the torque [N·m], the settings and the CPU seconds a deck may use."""

    gears: tuple
    meshes: tuple
    pair: PairGeometry
    material: Material
    torque: float
    settings: CalculixSettings
    limit: float

    def solve(self, a: int, th1: float, start: float) -> tuple:
        """(the converged deck's result, its start approach [m], CPU seconds used) of the deck
        ``a`` at driver angle ``th1`` [rad] from the approach ``start`` [m], tried as `ATTEMPTS`
        says; `CalculixFailed` when no attempt converges."""
        gears, pair, settings, limit = self.gears, self.pair, self.settings, self.limit
        g1, g2 = gears[0].geometry, gears[1].geometry
        rb1, rb2 = g1.base_radius, g2.base_radius
        th2 = (0.5 * pair.normal_backlash - rb1 * th1) / rb2
        thin = settings.deck_scale(max(g1.spec.face_width, g2.spec.face_width))
        why, used = [], 0.0
        for n, (frac, soft) in enumerate(ATTEMPTS):
            if limit - used < 1.0:
                why.append("no CPU time left for the next attempt")
                break
            s = frac * start
            placed = (GearPlacement(self.meshes[0], thin * g1.spec.face_width, thin * gears[0].body.web_thickness, (0.0, 0.0), th1),
                      GearPlacement(self.meshes[1], thin * g2.spec.face_width, thin * gears[1].body.web_thickness,
                                    (pair.center_distance, 0.0), th2 + s / rb2 + math.pi + math.pi / g2.teeth))
            # a ground spring of 1e-4 of the mesh's torsional stiffness (about torque / start angle):
            # it takes 1e-4 of the torque per start error of the size of the approach
            ground = GROUND_FRACTION * thin * self.torque * rb2 / max(s, 1e-9)
            # the stiff deck without cut-backs: its start overclosure is not scaled by the
            # increment, so a smaller one does not help it (a soft start's may)
            inc = (1.0, 1.0, 1.0) if soft == 0 else (1.0, 1.0)
            text, nums = write_deck(placed, self.material, thin * self.torque, settings.contact_stiffness, inc, ground,
                                    settings.both_ways, soft_start=soft)
            # half of what is left, all of it for the last attempt: a chattering attempt leaves
            # time for the next
            cap = (limit - used) * (1.0 if n == len(ATTEMPTS) - 1 else 0.5)
            try:
                res = run_deck(text, nums.rot_node, nums.ref_node, timeout_s=WALL_PER_CPU * cap,
                               keep=settings.keep and f"{settings.keep}/deck{a:03d}_{n}", cpu_limit_s=cap,
                               end_time=nums.end_time)
                return res, s, used + res.cpu_time_s
            except CalculixFailed as e:
                used += e.cpu_time_s
                why.append(f"{'soft start' if soft else 'stiff contact'} from {s * 1e6:.3g} um: {e}")
        raise CalculixFailed(f"the deck at driver angle {math.degrees(th1):.4f} deg did not converge "
                             f"({used:.0f} of {limit:.0f} s CPU): " + "; ".join(why))
