"""CalculiX input deck of a gear pair in contact at one driver angle.

Both gears are the meshes of `solver.peers.calculix.mesh` placed in the pair frame of
`solver.mbs.model` (gear 1 at the origin, gear 2 at (a, 0), hub angles counter-clockwise
positive, tooth 0 of gear 1 along +x, tooth 0 of gear 2 at pi + pi/z2 + theta2). Quadratic
plane-stress triangles (CPS6), one *SOLID SECTION per gear and region: thickness = face width on
the teeth, rim and hub, the web thickness in the web. Gear 1's bore is fixed; gear 2's bore nodes
form a *RIGID BODY about its centre (REF NODE fixed, ROT NODE free about z only) loaded by the
resisting torque (counter-clockwise: it holds the driven gear back). Frictionless penalty
contact (*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR) between the drive flanks and tip arcs
of the teeth around the mesh: gear 2's faces are the slave surface, gear 1's the master.

Units in the deck: N, mm, MPa (N/mm²), N·mm; converted here from SI with `solver.units`.
"""
from __future__ import annotations

import io
import math
from dataclasses import dataclass

import numpy as np

from solver import units
from solver.fe.mesh import REGION_HUB, REGION_NAMES, REGION_RIM, REGION_WEB
from solver.geometry import Material
from solver.peers.calculix.mesh import GearMesh

REGION_LABEL = {REGION_RIM: "RIM", REGION_WEB: "WEB", REGION_HUB: "HUB"}
# smallest load increment of a step (a fraction of the step)
MIN_INCREMENT = 1.0 / 64.0


@dataclass(frozen=True)
class GearPlacement:
    """One gear of the deck: its mesh, thicknesses [m], and its pose in the pair frame."""

    mesh: GearMesh
    face_width: float       # m
    web_thickness: float    # m
    centre: tuple           # (x, y) [m]
    angle: float            # rotation of the gear frame [rad], counter-clockwise


@dataclass(frozen=True)
class DeckNumbers:
    """Node and element numbering of a written deck (CalculiX numbers from 1)."""

    node_offset: tuple      # first node number - 1 of gear 1, gear 2
    element_offset: tuple   # first element number - 1 of gear 1, gear 2
    ref_node: int           # rigid body reference node (gear 2's centre)
    rot_node: int           # rigid body rotation node: its U3 is gear 2's rotation [rad]
    n_nodes: int
    n_elements: int
    end_time: float = 1.0   # total time at the end of the last step (one per step)


def placed_points(p: GearPlacement) -> np.ndarray:
    """Node coordinates of a placed gear in the pair frame [m]."""
    c, s = math.cos(p.angle), math.sin(p.angle)
    x, y = p.mesh.points[:, 0], p.mesh.points[:, 1]
    return np.column_stack([p.centre[0] + c * x - s * y, p.centre[1] + s * x + c * y])


def write_deck(gears: tuple, material: Material, torque: float, contact_stiffness: float,
               increments: tuple = (1.0, 1.0), ground_stiffness: float = 0.0,
               both_ways: bool = False, soft_start: float = 0.0) -> tuple[str, DeckNumbers]:
    """The .inp text and its numbering. ``gears``: (GearPlacement of gear 1, of gear 2);
    ``torque`` [N·m] resisting on gear 2 (> 0); ``contact_stiffness`` [Pa/m] slope of the linear
    pressure-overclosure law; ``increments``: (initial, maximum[, minimum]) fraction of the
    step's load (minimum: `MIN_INCREMENT` unless given);
    ``ground_stiffness`` [N·m/rad]: a torsion spring from the driven gear to the ground (SPRING1 on
    the rotation node; 0: none) that keeps the system regular when a Newton iteration opens every
    contact: it carries ground_stiffness * U3 of the torque, U3 the rotation from the start;
    ``both_ways``: a second contact pair with gear 1's faces as the slave surface;
    ``soft_start`` (0 < f < 1): the torque is first carried with the contact stiffness times f
    (a first step), then the contact is stiffened to ``contact_stiffness`` under the same torque
    (*CHANGE SURFACE BEHAVIOR, a second step): a soft penalty lets the few nodes of a narrow
    contact patch settle where a stiff one makes them chatter in and out; 0: one step. The
    deck's last step ends at total time `DeckNumbers.end_time`."""
    if not 0.0 <= soft_start < 1.0:
        raise ValueError(f"soft_start must lie in [0, 1), got {soft_start}")
    if not torque > 0:
        raise ValueError(f"quasi_static.torque: the contact peer needs a positive (drive-side) torque, got {torque}")
    if not contact_stiffness > 0:
        raise ValueError(f"contact stiffness must be positive, got {contact_stiffness}")
    mm = units.MM_PER_M
    out = io.StringIO()
    w = out.write
    w("** lightgear: gear pair in frictionless contact, plane stress, units N, mm, MPa\n")
    node_off, elem_off, ref, rot, n, e = _bodies(out, gears, material)
    for i, gp in enumerate(gears):
        w(f"*NSET, NSET=BORE{i + 1}\n")
        _ids(out, gp.mesh.bore + node_off[i] + 1)
        w(f"*SURFACE, NAME=FLANKS{i + 1}, TYPE=ELEMENT\n")
        f = gp.mesh.contact_faces
        np.savetxt(out, np.column_stack([f[:, 0] + elem_off[i] + 1, f[:, 1] + 1]), fmt="%d,S%d")
    w(f"*NSET, NSET=REF\n{ref}\n*NSET, NSET=ROT\n{rot}\n")
    w(f"*RIGID BODY, NSET=BORE2, REF NODE={ref}, ROT NODE={rot}\n")
    w(f"*BOUNDARY\nBORE1,1,2\n{ref},1,3\n{rot},1,2\n")
    if ground_stiffness > 0:
        w(f"*ELEMENT, TYPE=SPRING1, ELSET=GROUND\n{e + 1},{rot}\n*SPRING, ELSET=GROUND\n3\n{ground_stiffness / units.NMM:.9g}\n")
    # slope [MPa/mm]; a small tension (0.1 MPa) for clearances below 0.1 um keeps the slave
    # nodes next to the contact from chattering in and out between iterations
    law = "*SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=LINEAR\n{:.9g},0.1,1.e-4\n"
    k = contact_stiffness / units.MPA / mm
    w("*SURFACE INTERACTION, NAME=FLANK\n" + law.format(k * soft_start if soft_start > 0 else k))
    # both ways round: each gear's tip corner is then a slave node on the other's flank (a
    # master corner pokes between the slave nodes and carries too little of the tip contact)
    w("*CONTACT PAIR, INTERACTION=FLANK, TYPE=NODE TO SURFACE\nFLANKS2,FLANKS1\n")
    if both_ways:
        w("*CONTACT PAIR, INTERACTION=FLANK, TYPE=NODE TO SURFACE\nFLANKS1,FLANKS2\n")
    # the smallest increment 1/64 of the step: a deck whose contact chatters fails after a few
    # cut-backs (each one Newton iterations of the whole pair) instead of after seventeen
    smallest = increments[2] if len(increments) > 2 else MIN_INCREMENT
    static = f"*STATIC\n{increments[0]:.6g},1.,{smallest:.6g},{increments[1]:.6g}\n"
    prints = "*NODE PRINT, NSET=ROT\nU\n*NODE PRINT, NSET=REF, TOTALS=ONLY\nRF\n"
    w(f"*STEP, INC=100\n{static}*CLOAD\n{rot},3,{torque / units.NMM:.9g}\n{prints}*END STEP\n")
    if soft_start > 0:
        w(f"*STEP, INC=100\n{static}*CHANGE SURFACE BEHAVIOR, INTERACTION=FLANK\n{law.format(k)}{prints}*END STEP\n")
    return out.getvalue(), DeckNumbers(tuple(node_off), tuple(elem_off), ref, rot, n + 2, e, 2.0 if soft_start > 0 else 1.0)


def _bodies(out, gears: tuple, material: Material) -> tuple:
    """Write both gears' nodes, the driven gear's reference and rotation nodes, the elements by
    region, the material and the sections; (node offsets, element offsets, reference node,
    rotation node, nodes of the gears, elements)."""
    mm = units.MM_PER_M
    w = out.write
    w("*NODE, NSET=NALL\n")
    node_off, elem_off = [], []
    n = e = 0
    for gp in gears:
        node_off.append(n)
        xy = placed_points(gp) * mm
        ids = np.arange(n + 1, n + 1 + xy.shape[0])
        np.savetxt(out, np.column_stack([ids, xy, np.zeros(len(ids))]), fmt="%d,%.9f,%.9f,%.1f")
        n += xy.shape[0]
    ref, rot = n + 1, n + 2
    a2 = gears[1].centre
    w(f"{ref},{a2[0] * mm:.9f},{a2[1] * mm:.9f},0.0\n{rot},{a2[0] * mm:.9f},{a2[1] * mm:.9f},0.0\n")
    for i, gp in enumerate(gears):
        elem_off.append(e)
        tri = gp.mesh.triangles + node_off[i] + 1
        ids = np.arange(e + 1, e + 1 + tri.shape[0])
        for reg in np.unique(gp.mesh.region):
            sel = gp.mesh.region == reg
            w(f"*ELEMENT, TYPE=CPS6, ELSET=G{i + 1}{REGION_LABEL[int(reg)]}\n")
            np.savetxt(out, np.column_stack([ids[sel], tri[sel]]), fmt="%d", delimiter=",")
        e += tri.shape[0]
    w("*MATERIAL, NAME=STEEL\n*ELASTIC\n")
    w(f"{material.youngs_modulus / units.MPA:.9g},{material.poisson_ratio:.9g}\n")
    for i, gp in enumerate(gears):
        for reg in np.unique(gp.mesh.region):
            t = gp.web_thickness if int(reg) == REGION_WEB else gp.face_width
            w(f"** {REGION_NAMES[int(reg)]} of gear {i + 1}\n")
            w(f"*SOLID SECTION, ELSET=G{i + 1}{REGION_LABEL[int(reg)]}, MATERIAL=STEEL\n{t * mm:.9g}\n")
    return node_off, elem_off, ref, rot, n, e


def _ids(out, ids) -> None:
    """Node numbers, 16 to a line (CalculiX reads at most 16 entries a set line)."""
    ids = np.asarray(ids, int)
    for i in range(0, ids.size, 16):
        out.write(",".join(str(v) for v in ids[i:i + 16]) + "\n")
