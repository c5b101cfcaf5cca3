"""The MUBOCO-PR model of a gear pair as flat arrays for the kernels.

Inputs are plain dataclasses in SI units; `build_model` derives geometry, inertia and the
parameter arrays laid out as in `solver.mbs.kernels.layout`.

Frame: gear 1 (driver) centred at the origin, gear 2 (driven) at (a, 0). Both hub angles
are counter-clockwise positive and zero at the nominal zero-backlash conjugate position:
tooth 0 of gear 1 points along +x into the space of gear 2 centred on the line of centres.
Gear 1 turns counter-clockwise and drives with the "+" flanks; gear 2 turns clockwise.
"""
from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

import numpy as np

from solver.geometry import (
    BodySpec,
    GearGeometry,
    Material,
    PairGeometry,
    ToothSpec,
    gear_geometry,
    pair_geometry,
    validate_body,
)
from solver.inertia import body_inertia, hole_inertia, tooth_inertia
from solver.mbs.kernels import layout as L
from solver.modification import ProfileModification
from solver.pitch_errors import GearErrors


@dataclass(frozen=True)
class GearInput:
    """One gear: teeth, body, pivot and the per-tooth springs (SI)."""

    tooth: ToothSpec
    body: BodySpec
    pivot_radius: float                 # m
    k_phi: np.ndarray                   # per tooth, N·m/rad^n_k
    n_k: float = 1.1
    c_phi: float = 0.0                  # N·m·s/rad (n_c = 1) or N·m/(rad/s)^n_c
    n_c: float = 1.0
    body_stiffness: float = math.inf    # hub -> rim torsion spring, N·m/rad (inf: rigid body)
    body_damping_ratio: float = 0.02    # of critical on the body mode (as the teeth's 2 %)
    tooth_compliance: np.ndarray | None = None  # (Z, Z) rad/(N·m): teeth coupled through the body
    modification: ProfileModification | None = None  # flank deviation (relief, table); None: perfect involutes
    errors: GearErrors | None = None    # pitch deviations and eccentricity; None: a perfect gear
    # local compliance in series with the contact law: (rolls [-], c_loc [m/N]); None: c_loc = 0
    contact_compliance: tuple | None = None


@dataclass(frozen=True)
class ContactLaw:
    """Eq. (1.3) in SI: k [N/m^m1], c [N/((m/s)^m2 m^m3)]; sliding friction on the flanks:
    Coulomb coefficient mu [-] (0: none), regularised as mu*tanh(v_s/friction_velocity) with
    the sliding speed v_s [m/s] (`kernels.gearmesh`)."""

    k: float
    m1: float
    c: float = 0.0
    m2: float = 1.0
    m3: float = 1.5
    mu: float = 0.0
    friction_velocity: float = 0.01     # m/s

    def __post_init__(self):
        if not 0.0 <= self.mu < 0.5:
            raise ValueError(f"contact.friction: the Coulomb coefficient must lie in [0, 0.5), got {self.mu}")
        if not self.friction_velocity > 0.0 or not math.isfinite(self.friction_velocity):
            raise ValueError(f"contact.friction_velocity: must be positive and finite, got {self.friction_velocity}")


@dataclass
class Model:
    """Everything the kernels need, plus the derived geometry for reporting."""

    gear_par: np.ndarray            # (2, N_GEAR_PAR)
    pair_par: np.ndarray            # (N_PAIR_PAR,), plus the errors block E_* when a gear has errors
    law_par: np.ndarray             # (N_LAW_PAR,)
    k_phi: np.ndarray               # (Z1 + Z2,) N·m/rad^n_k
    geometry: tuple                 # (GearGeometry, GearGeometry)
    pair: PairGeometry
    teeth_inertia: tuple            # (ToothInertia, ToothInertia)
    body_inertia: tuple             # kg·m² of the bodies without teeth
    inputs: tuple = field(repr=False, default=())
    tooth_compliance: np.ndarray = field(repr=False, default_factory=lambda: np.zeros((0, 0)))
    # (Z1+Z2, Z1+Z2) rad/(N·m), block-diagonal by gear, when the teeth are coupled through
    # the bodies (`kernels.toothcoupling`); 0 x 0 for independent tooth springs

    @property
    def teeth(self) -> tuple:
        return self.geometry[0].teeth, self.geometry[1].teeth

    @property
    def n_teeth(self) -> int:
        return sum(self.teeth)

    @property
    def base_radii(self) -> tuple:
        return self.geometry[0].base_radius, self.geometry[1].base_radius

    def te(self, theta1, theta2):
        """Transmission error rb1*theta1 + rb2*theta2 [m]."""
        return self.base_radii[0] * np.asarray(theta1) + self.base_radii[1] * np.asarray(theta2)

    def theta2_for_te(self, theta1, te):
        """Driven hub angle [rad] giving transmission error te [m] at driver angle theta1."""
        return (te - self.base_radii[0] * theta1) / self.base_radii[1]

    @property
    def backlash_offset(self) -> float:
        """TE of rigid teeth in drive contact: half the normal backlash [m]."""
        return float(self.pair_par[L.JN_HALF])

    @property
    def body_stiffness(self) -> tuple:
        """Hub -> rim torsion stiffness of each body [N·m/rad] (inf: rigid, the plain model)."""
        k = self.gear_par[:, L.K_BODY]
        return tuple(float(x) if x > 0 else math.inf for x in k)

    @property
    def coupled(self) -> bool:
        return bool(np.any(self.gear_par[:, L.K_BODY] > 0))

    @property
    def teeth_coupled(self) -> bool:
        """Tooth springs coupled through a compliance matrix (k_phi then each tooth's own)."""
        return self.tooth_compliance.shape[0] > 0

    @property
    def inertia_total(self) -> tuple:
        return float(self.gear_par[0, L.I_TOT]), float(self.gear_par[1, L.I_TOT])


def body_critical_damping(gp: np.ndarray, i: int) -> float:
    """Critical damping [N·m·s/rad] of gear ``i``'s (0 driver, 1 driven) body mode: its rim
    (with the teeth) against its hub on the body spring, 2 sqrt(k_body I_eff); the driver's hub
    is prescribed (I_eff the rim's), the driven hub free (I_eff rim and hub in series).
    0 for a rigid body."""
    if not gp[i, L.K_BODY] > 0:
        return 0.0
    i_rim = gp[i, L.I_TOT] - gp[i, L.I_HUB]
    i_eff = i_rim if i == 0 else i_rim * gp[i, L.I_HUB] / gp[i, L.I_TOT]
    return 2.0 * math.sqrt(gp[i, L.K_BODY] * i_eff)


def hub_side_inertia(g: GearGeometry, body: BodySpec, density: float) -> float:
    """Inertia [kg·m²] on the hub side of the body spring: the hub ring and half the web (the
    web's wind-up is the spring; its inertia is split between its ends)."""
    r_rim = g.root_radius - body.rim_height
    r_hub = r_rim - body.web_height
    r_bore = r_hub - body.hub_height
    hub = 0.5 * density * math.pi * (r_hub**4 - r_bore**4) * g.spec.face_width
    web = 0.5 * density * math.pi * (r_rim**4 - r_hub**4) * body.web_thickness
    web -= hole_inertia(body, density)[1]
    return hub + 0.5 * web


def _max_pivot_distance(g: GearGeometry, pivot_radius: float) -> float:
    x, y = g.outline(n_involute=40)
    return float(np.max(np.hypot(x - pivot_radius, y))) * 1.001


def build_model(gear1: GearInput, gear2: GearInput, law: ContactLaw, material: Material,
                presearch_margin: float = 0.5) -> Model:
    """Flat-array model of the pair. ``presearch_margin`` widens the pre-search window by
    that fraction of the angular pitch beyond the flank ends (tip-corner contact)."""
    geos, inert, bodies, own = [], [], [], []
    for name, gi in (("gear1", gear1), ("gear2", gear2)):
        g = gear_geometry(gi.tooth, prefix=name)
        validate_body(g, gi.body, prefix=f"{name}.body")
        k = np.asarray(gi.k_phi, dtype=float)
        if gi.tooth_compliance is not None:
            _check_compliance(gi, g.teeth, name)
            k = 1.0 / np.diag(gi.tooth_compliance)
        if k.shape != (g.teeth,):
            raise ValueError(f"{name}.spring.k_phi: expected {g.teeth} per-tooth values, got shape {k.shape}")
        if not np.all(np.isfinite(k)) or np.any(k <= 0):
            raise ValueError(f"{name}.spring.k_phi: per-tooth stiffness must be finite and positive")
        own.append(k)                   # each tooth's own spring (1/C[a, a] with a compliance matrix)
        geos.append(g)
        inert.append(tooth_inertia(g, material.density, gi.pivot_radius))
        bodies.append(body_inertia(g, gi.body, material.density)[1])
    pair = pair_geometry(*geos)

    gp = np.zeros((2, L.N_GEAR_PAR))
    centres = ((0.0, 0.0), (pair.center_distance, 0.0))
    gammas = (0.0, math.pi + math.pi / geos[1].teeth)
    tooth0 = (0, geos[0].teeth)
    for i, (g, gi, ti, ib) in enumerate(zip(geos, (gear1, gear2), inert, bodies)):
        gp[i, L.RB] = g.base_radius
        gp[i, L.PSI_B] = g.psi_base
        gp[i, L.U_LO] = g.u_form
        gp[i, L.U_HI] = g.u_tip
        gp[i, L.R_PV] = gi.pivot_radius
        gp[i, L.PITCH] = g.pitch_angle
        gp[i, L.GAMMA0] = gammas[i]
        gp[i, L.CX], gp[i, L.CY] = centres[i]
        gp[i, L.I_P] = ti.inertia_pivot
        gp[i, L.I_CPL] = ti.inertia_pivot + ti.mass * gi.pivot_radius * (ti.centroid_radius - gi.pivot_radius)
        gp[i, L.I_TOT] = ib + g.teeth * ti.inertia_center
        gp[i, L.R_BND] = _max_pivot_distance(g, gi.pivot_radius)
        gp[i, L.N_K] = gi.n_k
        gp[i, L.C_PHI] = gi.c_phi
        gp[i, L.N_C] = gi.n_c
        gp[i, L.TOOTH0] = tooth0[i]
        gp[i, L.NZ] = g.teeth
        if gi.contact_compliance is not None:
            sample_local_compliance(gi.contact_compliance, g.u_form, g.u_tip, gp[i], ("gear1", "gear2")[i])
        if gi.body_stiffness != math.inf:
            if not gi.body_stiffness > 0:
                raise ValueError(f"{('gear1', 'gear2')[i]}: body torsion stiffness must be positive, got {gi.body_stiffness}")
            gp[i, L.K_BODY] = gi.body_stiffness
        gp[i, L.I_HUB] = hub_side_inertia(g, gi.body, material.density)
        if gp[i, L.K_BODY] > 0:
            gp[i, L.C_BODY] = gi.body_damping_ratio * body_critical_damping(gp, i)
    pp = np.zeros(L.N_PAIR_PAR)
    pp[L.JN_HALF] = 0.5 * pair.normal_backlash
    pp[L.ALPHA] = pair.pressure_angle
    pp[L.MARGIN] = presearch_margin * max(geos[0].pitch_angle, geos[1].pitch_angle)
    lp = np.zeros(L.N_LAW_PAR)
    lp[[L.K_CON, L.M1, L.C_CON, L.M2, L.M3, L.MU, L.V_REG]] = law.k, law.m1, law.c, law.m2, law.m3, law.mu, law.friction_velocity
    kphi = np.concatenate(own)
    ctooth = np.zeros((0, 0))
    if gear1.tooth_compliance is not None or gear2.tooth_compliance is not None:
        for name, gi in (("gear1", gear1), ("gear2", gear2)):
            if gi.n_k != 1.0:
                raise ValueError(f"{name}.spring.n_k: coupled tooth springs are linear (n_k = 1), got {gi.n_k}")
        # the other gear's independent springs are a diagonal block
        blocks = [gi.tooth_compliance if gi.tooth_compliance is not None else np.diag(1.0 / k)
                  for gi, k in zip((gear1, gear2), own)]
        n1 = geos[0].teeth
        ctooth = np.zeros((kphi.size, kphi.size))
        ctooth[:n1, :n1] = blocks[0]
        ctooth[n1:, n1:] = blocks[1]
    model = Model(gp, pp, lp, kphi, tuple(geos), pair, tuple(inert), tuple(bodies), (gear1, gear2, law, material), ctooth)
    return with_flank_deviations(model, (gear1.modification, gear2.modification), (gear1.errors, gear2.errors))


def with_flank_deviations(model: Model, modifications, errors) -> Model:
    """A copy of ``model`` with the gears' profile modifications ((ProfileModification |
    None) x 2) and pitch errors ((GearErrors | None) x 2) in place of its own: the deviation
    columns DEV_* of gear_par and the errors block E_* of pair_par written anew (`build_model`
    writes them the same way), its other arrays copied (the caller may change the copy in place;
    the geometry objects are shared). What a sampled build of a tolerance study changes: its
    model is the study's one with these rewritten, not built again."""
    geos = model.geometry
    gp = model.gear_par.copy()
    for i, (name, mod, g) in enumerate(zip(("gear1", "gear2"), modifications, geos)):
        if mod is not None:
            mod.check(g.u_form, g.u_tip, name)
        sample_deviation(mod, g.u_form, g.u_tip, gp[i])
    write_tip_edges(model, modifications, gp)
    for name, e, g in zip(("gear1", "gear2"), errors, geos):
        if e is not None:
            # limited to 0.1 module: a few % of a pitch, well inside the pre-search margin
            e.check(g.teeth, g.spec.module, name)
    pp = np.concatenate([model.pair_par[:L.N_PAIR_PAR], error_block(errors, geos)])
    inputs = model.inputs
    if inputs:
        inputs = tuple(dataclasses.replace(gi, modification=mod, errors=e)
                       for gi, mod, e in zip(inputs[:2], modifications, errors)) + tuple(inputs[2:])
    return dataclasses.replace(model, gear_par=gp, pair_par=pp, law_par=model.law_par.copy(), k_phi=model.k_phi.copy(),
                               tooth_compliance=model.tooth_compliance.copy(), inputs=inputs)


def write_tip_edges(model: Model, modifications, gp: np.ndarray) -> None:
    """Write the EDGE_* columns of ``gp`` (the model's gear_par or its copy) for the gears'
    modifications ((ProfileModification | None) x 2): the round of each tip edge radius
    (`solver.tip_edge.tip_round` on the modified flank: its tangent roll and the deviation there)
    and its compliance's law (`solver.tip_edge.edge_columns`: the model's Young's modulus, the
    narrower face, the contact law's radius of curvature); all 0 for a sharp corner."""
    from solver.tip_edge import edge_columns, law_radius, tip_round
    gp[:, L.EDGE_INV_R:L.N_GEAR_PAR] = 0.0
    radii = [0.0 if mod is None else float(mod.tip_edge_radius) for mod in modifications]
    if not any(radii):
        return
    if len(model.inputs) < 4:
        raise ValueError("gearN.modification.tip_edge_radius: the model has no material to take the edge's law from")
    material = model.inputs[3]
    b = min(g.spec.face_width for g in model.geometry)
    law_r = law_radius(*model.geometry)
    for i, (r, mod, g) in enumerate(zip(radii, modifications, model.geometry)):
        if r == 0.0:
            continue
        dev = (lambda u, mod=mod, g=g: mod.deviation(u, g.u_form, g.u_tip))
        rnd = tip_round(g, r, dev)
        gp[i, L.EDGE_INV_R:L.EDGE_INV_R + 3] = edge_columns(r, material.youngs_modulus, b, law_r)
        gp[i, L.EDGE_R] = r
        gp[i, L.EDGE_U] = rnd.u_flank
        gp[i, L.EDGE_DEV] = float(dev(np.array([rnd.u_flank]))[0])


def _check_compliance(gi: GearInput, z: int, name: str) -> None:
    c = np.asarray(gi.tooth_compliance, float)
    if c.shape != (z, z):
        raise ValueError(f"{name}.tooth_compliance: expected a {z} x {z} matrix, got shape {c.shape}")
    if not np.all(np.isfinite(c)) or np.max(np.abs(c - c.T)) > 1e-9 * np.max(np.abs(c)):
        raise ValueError(f"{name}.tooth_compliance: must be finite and symmetric")
    try:
        np.linalg.cholesky(c)
    except np.linalg.LinAlgError:
        raise ValueError(f"{name}.tooth_compliance: must be positive definite") from None


def sample_local_compliance(table, u_form: float, u_tip: float, row: np.ndarray, name: str) -> None:
    """Write the CLOC_* columns of a gear_par row: the local compliance ``table`` = (rolls [-],
    c_loc [m/N]) resampled on N_CLOC rolls from u_form to u_tip (a monotone cubic through the
    table's points, constant beyond them)."""
    from scipy.interpolate import PchipInterpolator
    u, c = (np.asarray(x, float) for x in table)
    if u.ndim != 1 or u.shape != c.shape or u.size < 2 or np.any(np.diff(u) <= 0) or not np.all(np.isfinite(c)):
        raise ValueError(f"{name}.contact_compliance: need finite values on at least two increasing rolls")
    grid = np.linspace(u_form, u_tip, L.N_CLOC)
    row[L.CLOC_U0] = u_form
    row[L.CLOC_DU] = grid[1] - grid[0]
    row[L.CLOC0:L.CLOC0 + L.N_CLOC] = PchipInterpolator(u, c, extrapolate=False)(np.clip(grid, u[0], u[-1]))
    row[L.CLOC_ON] = 1.0 if np.any(row[L.CLOC0:L.CLOC0 + L.N_CLOC] != 0.0) else 0.0


def sample_deviation(mod: ProfileModification | None, u_form: float, u_tip: float, row: np.ndarray) -> None:
    """Write the model columns DEV_* of one gear into ``row`` (a gear_par row): the deviation
    [m] on N_DEV rolls from u_form to u_tip, the flag DEV_ON, the grid and DEV_NEG (a bound on
    the material addition [m], which widens the rigid gap bound of the pre-search)."""
    u = np.linspace(u_form, u_tip, L.N_DEV)
    dev = np.zeros(L.N_DEV) if mod is None else mod.deviation(u, u_form, u_tip)
    row[L.DEV_U0] = u_form
    row[L.DEV_DU] = u[1] - u[0]
    row[L.DEV0:L.DEV0 + L.N_DEV] = dev
    row[L.DEV_ON] = 1.0 if np.any(dev != 0.0) else 0.0
    # the cubic through the samples may undershoot them by a fraction of a step near a kink
    row[L.DEV_NEG] = max(0.0, -float(dev.min())) + 0.25 * float(np.abs(np.diff(dev)).max())


def error_block(errors, geometries) -> np.ndarray:
    """The pair_par tail (`layout` E_*) of both gears' errors ((GearErrors | None) x 2), or an
    empty array when neither has any (the kernels then skip the errors entirely)."""
    if all(e is None or e.is_zero for e in errors):
        return np.zeros(0)
    z = [g.teeth for g in geometries]
    block = np.zeros(L.E_EPS - L.N_PAIR_PAR + z[0] + z[1])
    bound = 0.0
    for g, (e, geo) in enumerate(zip(errors, geometries)):
        if e is None:
            continue
        eps = e.cumulative(geo.teeth) / geo.pitch_radius
        i0 = L.E_EPS - L.N_PAIR_PAR + (0 if g == 0 else z[0])
        block[i0:i0 + geo.teeth] = eps
        block[L.E_ECC + 2 * g - L.N_PAIR_PAR] = e.eccentricity
        block[L.E_ECC + 2 * g + 1 - L.N_PAIR_PAR] = e.eccentricity_phase
        # a tooth turned by eps about the centre moves its flank points at most eps*r_tip;
        # the centre offset moves them by e
        bound += np.max(np.abs(eps), initial=0.0) * geo.tip_radius + e.eccentricity
    block[L.E_BOUND - L.N_PAIR_PAR] = bound
    return block
