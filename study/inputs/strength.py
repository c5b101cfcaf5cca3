"""Bending strength of each gear body under the loads a run computes, from its FE body.

Per gear (`gear_strength`):

1. The body's stress per unit load at its strength sites (`solver.fe.stress.strength_sites`:
   root fillets, inner half of the rim, web opening edges and ligaments), for a load on each
   tooth the STE loads, at five roll parameters along the profile: the start of the active
   profile, the inner point of single contact, the pitch point, the outer point of single
   contact (HPSTC) and the tip. One load case per (tooth, roll) through the body's one
   factorisation (the same body as the springs'), all in one block and, on a body with a
   condensed rim, solved only at the DOFs the sites read (`solver.fe.stress.load_case_stress`),
   cached on disk with the sites (``strength-{key}.npz`` in the FE cache).
2. The static contact forces of the STE (each loaded contact's tooth, roll parameter and force:
   `static_loads`) superposed on those load cases, each force shared between the two nearest
   rolls (linear in the roll): the stress at every site node at every STE angle, and its
   largest value over the angles (`solver.fe.stress.peak_stress`). No FE solve per angle.
3. With a dynamic run, the static peaks scaled by the dynamic run's torque over the static
   torque times the dynamic factor K_v (largest dynamic over largest static tooth force at the
   dynamic torque), as ISO 6336-3 scales sigma_F0 by K_v.

Units: SI (m, N, Pa).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from solver.strength import LOCATIONS  # noqa: F401  (BodyStress.location indexes it; imported from here too)
from study.inputs.cache import FE_CACHE
from study.inputs.gearsetup import GearSetup

# bump when the sites or the load cases change (in every key); 4: the load cases solved only
# where the sites read them (the same stresses to rounding, 1e-13)
STRENGTH_VERSION = "4"


@dataclass
class BodyStress:
    """Stress per unit load of one gear body at its strength sites (see the module)."""

    points: np.ndarray          # (n, 2) site node coordinates [m], gear frame
    location: np.ndarray        # (n,) 0 root, 1 rim, 2 web (index into LOCATIONS)
    root_tooth: np.ndarray      # (n,) the tooth of a root node (-1 elsewhere)
    lig_kind: np.ndarray        # (k,) ligament kind (index into solver.fe.stress.LIGAMENT_KINDS)
    lig_width: np.ndarray       # (k,) ligament width [m]
    lig_ends: np.ndarray        # (k, 2, 2) the ligament's ends [m]
    lig_node: np.ndarray        # (k, n) True where a site node lies on the ligament
    openings: int               # number of web openings
    opening_outer_radius: float  # largest radius of an opening's edge [m] (NaN without)
    teeth: np.ndarray           # teeth of the load cases
    rolls: np.ndarray           # roll parameters of the load cases [rad]
    S: np.ndarray               # (3, n, n_teeth, n_rolls) stress per unit load [Pa/N]

    def arrays(self) -> dict:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


def load_rolls(setup: GearSetup, pair) -> np.ndarray:
    """The roll parameters [rad] of the strength load cases of the gear (see the module)."""
    from solver.peers.iso6336_strength import inner_single_contact_roll, single_contact_roll
    g = setup.geometry
    u_sap = float(pair.u_sap[setup.gear - 1])
    u = [u_sap, inner_single_contact_roll(g.tip_radius, g.base_radius, pair.base_pitch), math.tan(g.spec.pressure_angle),
         single_contact_roll(g.tip_radius, g.base_radius, pair.base_pitch, pair.contact_ratio), g.u_tip]
    return np.unique(np.clip(np.round(u, 12), u_sap, g.u_tip))


def body_stress(setup: GearSetup, teeth, rolls) -> BodyStress:
    """`BodyStress` of the gear for loads on ``teeth`` at ``rolls``, cached (memory of the FE
    cache's bodies, disk ``strength-{key}.npz``)."""
    teeth = np.asarray(sorted({int(t) for t in teeth}), np.int64)
    rolls = np.asarray(rolls, float)
    settings = {k: v for k, v in setup.settings.items() if k not in ("force", "pivot")}
    key = FE_CACHE.key({**settings, "patch": setup.patch, "teeth": teeth.tolist(), "rolls": rolls.tolist(),
                        "strength": STRENGTH_VERSION})
    stored = FE_CACHE.read_arrays(f"strength-{key}")
    if stored is not None and set(stored) == set(BodyStress.__dataclass_fields__):
        return BodyStress(**{k: (int(v) if k == "openings" else float(v) if k == "opening_outer_radius" else v)
                             for k, v in stored.items()})
    bs = _compute(setup, teeth, rolls)
    FE_CACHE.write_arrays(f"strength-{key}", **bs.arrays())
    return bs


def site_operator(setup: GearSetup, model) -> tuple:
    """(`solver.fe.stress.StrengthSites`, the `solver.fe.stress.StressOperator` of every site
    node: root, rim, web in that order, each read in its own region's elements, the location of
    each node (index into LOCATIONS)) of the gear's factorised body ``model``."""
    import scipy.sparse as sp

    from solver.fe.body import plane_stress_lame
    from solver.fe.mesh import REGION_RIM, REGION_WEB
    from solver.fe.stress import SiteRadii, StressOperator, strength_sites, stress_operator
    from solver.geometry import bore_radius

    g, body, mesh = setup.geometry, setup.body, model.mesh
    r_rim = g.root_radius - body.rim_height
    radii = SiteRadii(g.root_radius, g.form_radius, r_rim, r_rim - body.web_height, bore_radius(g, body))
    sites = strength_sites(mesh.points, mesh.triangles, mesh.region, radii, g.teeth)
    lam, mu = plane_stress_lame(model.material.youngs_modulus, model.material.poisson_ratio)
    ops = [stress_operator(model.basis, lam, mu, sites.root, mesh.region == REGION_RIM),
           stress_operator(model.basis, lam, mu, sites.rim, mesh.region == REGION_RIM),
           stress_operator(model.basis, lam, mu, sites.web, mesh.region == REGION_WEB)]
    nodes = np.concatenate([o.nodes for o in ops])
    op = StressOperator(nodes, *(sp.vstack([getattr(o, c) for o in ops]).tocsr() for c in ("xx", "yy", "xy")))
    location = np.concatenate([np.full(o.nodes.size, i) for i, o in enumerate(ops)])
    return sites, op, location


def _compute(setup: GearSetup, teeth: np.ndarray, rolls: np.ndarray) -> BodyStress:
    from solver.fe.body import load_case
    from solver.fe.flank_compliance import flank_load_vector
    from solver.fe.stress import LIGAMENT_KINDS, load_case_stress
    from study.inputs.compliance import factorised_body

    g = setup.geometry
    model = factorised_body(setup)
    mesh = model.mesh
    sites, op, location = site_operator(setup, model)
    nodes = op.nodes
    root_tooth = np.concatenate([sites.root_tooth, np.full(sites.rim.size + sites.web.size, -1)])
    def flank_load(tooth, u):       # 1 N along the flank normal at roll u, its patch ends exact on the involute
        return flank_load_vector(model, g, load_case(g, tooth, setup.pivot_radius, u), u, 1.0, setup.patch)
    S = load_case_stress(model, op, teeth, rolls, flank_load)
    ligs = sites.ligaments
    lig_node = np.zeros((len(ligs), nodes.size), bool)
    for i, lg in enumerate(ligs):
        lig_node[i] = (location == 2) & np.isin(nodes, lg.nodes)
    r = np.hypot(*mesh.points.T)
    outer = max((float(r[o].max()) for o in sites.openings), default=float("nan"))
    return BodyStress(mesh.points[nodes], location, root_tooth,
                      np.array([LIGAMENT_KINDS.index(lg.kind) for lg in ligs], np.int64),
                      np.array([lg.width for lg in ligs]), np.array([[lg.start, lg.end] for lg in ligs]).reshape(-1, 2, 2),
                      lig_node, len(sites.openings), outer, teeth, rolls, S)


def static_loads(model, st) -> tuple[tuple, tuple]:
    """The STE's contact loads on each gear: ((step, tooth, roll [rad], force [N]) of gear 1,
    the same of gear 2), from the static result ``st`` (forces per driver tooth) and the
    rigid mesh kinematics at each angle (`solver.fe.ltca.mesh_points`: the tooth pairs and
    their roll parameters). A driver tooth with two candidate contacts loads the closer one."""
    from solver.fe.ltca import mesh_points

    out = [[], []]
    for i, a in enumerate(st.angle):
        if not st.converged[i]:
            continue
        mp = mesh_points(model, float(a))
        seen = set()
        for r in np.argsort(mp.gap, kind="stable"):
            k = int(mp.tooth1[r])
            f = float(st.tooth_force[i, k])
            if k in seen or not f > 0:
                continue
            seen.add(k)
            out[0].append((i, k, mp.u1[r], f))
            out[1].append((i, int(mp.tooth2[r]), mp.u2[r], f))
    return tuple(tuple(np.array(c) for c in zip(*rows)) if rows else
                 (np.empty(0, int), np.empty(0, int), np.empty(0), np.empty(0)) for rows in out)


@dataclass
class GearStrength:
    """The strength of one gear under a run's loads (SI units; see `gear_strength`)."""

    body: BodyStress
    peak: dict                 # `solver.fe.stress.peak_stress` of the static loads: per node
    steps: int                 # STE angles superposed
    hpstc: float               # largest FE root stress [Pa], max principal, one tooth loaded at the HPSTC by `force`
    hpstc_tooth: int
    force: float               # the HPSTC load [N] (T / rb of the static torque)


def gear_strength(setup: GearSetup, pair, loads: tuple, n_steps: int, force: float) -> GearStrength:
    """`GearStrength` of the gear under the static ``loads`` (step, tooth, roll, force) of
    ``n_steps`` STE angles; ``force`` [N] the tooth load of the HPSTC check (the static torque
    over the base radius: the whole load on one tooth)."""
    from solver.fe.stress import load_weights, max_principal, peak_stress

    step, tooth, u, f = loads
    rolls = load_rolls(setup, pair)
    teeth = np.unique(tooth) if tooth.size else np.array([0])
    bs = body_stress(setup, teeth, rolls)
    n_cases = bs.teeth.size * bs.rolls.size
    S = bs.S.reshape(3, bs.points.shape[0], n_cases)
    W = load_weights(bs.rolls, bs.teeth, step.astype(np.int64), tooth.astype(np.int64), u, f, max(n_steps, 1))
    peak = peak_stress(S, W)
    # the FE beside ISO 6336-3: each load case's tooth loaded alone at the HPSTC, its own root
    j = int(np.argmin(np.abs(bs.rolls - _hpstc(setup, pair))))
    mp = max_principal(bs.S[:, :, :, j]) * force                 # (n, n_teeth)
    own = bs.root_tooth[:, None] == bs.teeth[None, :]
    per_tooth = np.where(own, mp, -np.inf).max(axis=0)
    t = int(np.argmax(per_tooth))
    return GearStrength(bs, peak, n_steps, float(per_tooth[t]), int(bs.teeth[t]), force)


def _hpstc(setup: GearSetup, pair) -> float:
    from solver.peers.iso6336_strength import single_contact_roll
    g = setup.geometry
    return single_contact_roll(g.tip_radius, g.base_radius, pair.base_pitch, pair.contact_ratio)
