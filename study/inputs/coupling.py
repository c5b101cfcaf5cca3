"""Foundation coupling of a scene's gears, identified from the FE body (cached).

`body_torsion(setup)` loads every tooth of the gear's FE body at the pitch point (one tooth
for a solid body, by symmetry) and reads each tooth's and its neighbours' deflection along
the line of action at the tooth centreline (`solver.fe.ltca` influence coefficients, same mesh
and load patch as the FE tooth springs), then splits the body wind-up off the tooth springs
(`solver.identify.coupling.body_torsion_fit`). Used by `study.scene_model.coupling_fit` when
``coupling.model = "body-torsion"``.

`tooth_compliance(setup, samples)`, the full version (``coupling.model = "compliance"``): the
influence coefficients of every tooth with itself and its neighbours along the profiles (a
lightened body: every tooth loaded; a solid body: one, the rest by symmetry), read at the
contact points the mesh loads together (`mesh_samples` of the pair's rigid geometry, weighted by
the load the mesh puts there), fitted as body wind-up plus coupled tooth springs
(`solver.identify.coupling.tooth_compliance_fit`), and the local compliance along the profile
that the rigid teeth miss (`solver.identify.coupling.local_compliance`, in series with the
contact law).

All take a prepared `study.inputs.gearsetup.GearSetup`; the FE comes from
`study.inputs.compliance.gear_compliance` (cached).
"""
from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from solver.fe.body import load_case
from solver.identify.coupling import (
    BodyTorsionFit,
    InfluenceSamples,
    ToothComplianceFit,
    body_torsion_fit,
    local_compliance,
    tooth_compliance_fit,
)
from solver.mbs.model import Model
from study.inputs.compliance import PROFILE_POINTS, compliance_cached, gear_compliance
from study.inputs.gearsetup import GearSetup


def _pitch_roll(setup: GearSetup) -> np.ndarray:
    """The roll grid of the pitch point alone [-]."""
    return np.array([math.tan(setup.geometry.spec.pressure_angle)])


def pitch_compliances_cached(setup: GearSetup) -> bool:
    """True when `pitch_compliances` of the gear needs no FE solve (memory or disk cache)."""
    return compliance_cached(setup, list(range(setup.teeth)), 1, u=_pitch_roll(setup))


def pitch_compliances(setup: GearSetup) -> tuple[np.ndarray, np.ndarray]:
    """(c_total, c_adjacent) (Z,) [m/N] of the gear's bore-clamped FE body at the pitch point,
    read along the line of action at the tooth centreline: each tooth's own compliance, and its
    mean compliance under a load on either neighbour (the body's wind-up the neighbours share).
    A lightened body: every tooth loaded; a solid body: one, the rest by symmetry."""
    geo = setup.geometry
    z = geo.teeth
    u = _pitch_roll(setup)
    if setup.lightened:
        c, _ = gear_compliance(setup, list(range(z)), 1, u=u)
        G = c.g[:, 0, :, 0]                        # read tooth, load tooth
        a = np.arange(z)
        return G[a, a], 0.5 * (G[a, (a - 1) % z] + G[a, (a + 1) % z])
    c, _ = gear_compliance(setup, [0], 1, u=u)
    G = c.g[:, 0, 0, 0]                            # read offsets -1, 0, 1
    return np.full(z, G[1]), np.full(z, 0.5 * (G[0] + G[2]))


def body_torsion(setup: GearSetup) -> BodyTorsionFit:
    """Body spring [N·m/rad] and tooth springs without the body wind-up of the gear, about the
    pivot of `tooth_pivot` (so `BodyTorsionFit.k_total` is the plain FE spring about it)."""
    geo = setup.geometry
    c_tot, c_adj = pitch_compliances(setup)
    r_q, k_q = tooth_pivot(setup, float(np.mean(c_adj)))
    return body_torsion_fit(c_tot, c_adj, load_case(geo, 0, r_q).lever, geo.base_radius, r_q, k_q)


def plain_windup(setup: GearSetup) -> float:
    """Compliance [m/N] along the line of action of the body wind-up from the bore that the
    plain model's tooth springs of the gear hold: c_body of `body_torsion` (the mean over the
    teeth of the FE compliance under the neighbours' pitch-point loads), of the body the springs
    stand for: the gear's own when its springs come from its FE ('fe-ratio', 'fe'), else the
    solid body's (a solid gear; 'uniform' springs, the calibrated solid-gear k_phi)."""
    return float(np.mean(pitch_compliances(windup_body(setup))[1]))


def windup_body(setup: GearSetup) -> GearSetup:
    """The body whose wind-up the plain model's springs of the gear hold (`plain_windup`)."""
    from study.inputs.springs import uses_fe_springs
    return setup if uses_fe_springs(setup) else setup.solid()


# fit weight of a tip-corner contact's nominal load share [1]: a corner outside the path of
# contact carries load only when the deflection closes its gap (high load, little relief)
CORNER_SHARE = 0.1


def mesh_samples(model: Model, g: int, n_angles: int = 25) -> dict[int, np.ndarray]:
    """Where and how hard the mesh loads gear g's teeth together: for each index offset d
    (load tooth - read tooth), rows (u_read [-], u_load [-], weight [1]) of the contacts that
    coexist over one mesh pitch of the pair's rigid geometry ``model``
    (`study.scene_model.geometry_model`; d = 0: each contact with itself).

    The weight is the product of the two contacts' nominal load shares (1/n for each of the n
    flank contacts in the path of contact, `CORNER_SHARE` for a tip corner): the rigid tooth
    of the model follows the FE compliance along the profile only approximately (about 10 %
    RMS for Table 1), so the fit puts its error where the mesh carries little load. Weighted
    so, the hole-order STE amplitude against the FE reference goes from -10 % to -3 % and the
    relief that minimises the STE moves towards the FE reference's (docs/models.md)."""
    from solver.fe.ltca import mesh_points
    z = model.teeth[g - 1]
    out: dict[int, list] = {}
    for th in np.linspace(0.0, 2 * math.pi / model.teeth[0], n_angles, endpoint=False):
        mp = mesh_points(model, float(th))
        t, u = (mp.tooth1, mp.u1) if g == 1 else (mp.tooth2, mp.u2)
        flank = mp.kind == 1
        share = np.where(flank, 1.0 / max(int(flank.sum()), 1), CORNER_SHARE)
        for i in range(t.size):
            for k in range(t.size):
                d = int((t[k] - t[i] + z // 2) % z - z // 2)
                out.setdefault(d, []).append((u[i], u[k], share[i] * share[k]))
    return {d: np.array(v) for d, v in sorted(out.items())}


def bilinear_weights(grid: np.ndarray, points: np.ndarray) -> np.ndarray:
    """(n, m*m) weights that interpolate a field on the m x m ``grid`` x ``grid`` (row-major)
    bilinearly at ``points`` (n, 2); points outside the grid extrapolate from the edge cell."""
    m = grid.size
    w = np.zeros((len(points), m * m))
    idx = [np.clip(np.searchsorted(grid, points[:, k]) - 1, 0, m - 2) for k in (0, 1)]
    t = [(points[:, k] - grid[idx[k]]) / (grid[idx[k] + 1] - grid[idx[k]]) for k in (0, 1)]
    rows = np.arange(len(points))
    for di, wi in ((0, 1 - t[0]), (1, t[0])):
        for dj, wj in ((0, 1 - t[1]), (1, t[1])):
            np.add.at(w, (rows, (idx[0] + di) * m + idx[1] + dj), wi * wj)
    return w


def tooth_compliance(setup: GearSetup, samples: dict[int, np.ndarray]) -> ToothComplianceFit:
    """Body spring [N·m/rad], pivot and coupled tooth compliance [rad/(N·m)] of the gear fitted
    to its FE influence coefficients at the points the mesh loads together (``samples``, from
    `mesh_samples`; `solver.identify.coupling.tooth_compliance_fit`; blocks interpolated
    bilinearly between the profile points). A lightened body: every tooth loaded at every
    profile point (cached on disk); a solid body: one tooth, the others by symmetry."""
    geo = setup.geometry
    z = geo.teeth
    reach = max(abs(d) for d in samples)
    if setup.lightened:
        c, _ = gear_compliance(setup, list(range(z)), reach, PROFILE_POINTS)
        pos = {int(t): i for i, t in enumerate(c.read_teeth)}

        def block(a, d):
            return c.g[pos[a], :, pos[(a + d) % z], :]
    else:
        c, _ = gear_compliance(setup, [0], reach, PROFILE_POINTS)

        def block(a, d):       # read a, load a + d = read offset -d from the loaded tooth
            return c.g[reach - d, :, 0, :]
    weights = {d: bilinear_weights(c.u, uv[:, :2]) for d, uv in samples.items()}
    pairs, sp, ur, ul, val, wt = [], [], [], [], [], []
    for a in range(z):
        for d, uv in samples.items():
            sp.append(np.full(len(uv), len(pairs)))
            pairs.append((a, (a + d) % z))
            ur.append(uv[:, 0])
            ul.append(uv[:, 1])
            wt.append(uv[:, 2])
            val.append(weights[d] @ block(a, d).ravel())
    # the pivot lies in the rim under the tooth
    bounds = (geo.root_radius - setup.body.rim_height, geo.root_radius)
    cat = np.concatenate
    fit = tooth_compliance_fit(InfluenceSamples(np.array(pairs), cat(sp), cat(ur), cat(ul), cat(val), cat(wt)), z,
                               geo.base_radius, geo.psi_base, bounds, own_completed=True)
    n = c.u.size
    own = np.array([[block(a, 0)[i, i] for i in range(n)] for a in range(z if setup.lightened else 1)])
    return replace(fit, local_u=np.array(c.u), local_compliance=local_compliance(fit, c.u, own, geo.base_radius, geo.psi_base))


def tooth_pivot(setup: GearSetup, c_body: float) -> tuple[float, float]:
    """(pivot radius [m], spring [N·m/rad]) of the gear's tooth 0 refitted to its FE compliance
    along the profile less the body compliance c_body [m/N] (see `solver.identify.coupling`)."""
    from solver.identify.pivot import fit_pivot
    geo = setup.geometry
    if setup.lightened:
        c, _ = gear_compliance(setup, [0], 0, PROFILE_POINTS)
        off = 0
    else:
        c, _ = gear_compliance(setup, [0], 1, PROFILE_POINTS)
        off = 1
    diag = np.array([c.g[off, i, 0, i] for i in range(c.u.size)])
    r_q, k, _err = fit_pivot(geo.base_radius, geo.psi_base - c.u, diag - c_body)
    return r_q, k


def plain_fe_springs(setup: GearSetup) -> np.ndarray:
    """Per-tooth FE springs [N·m/rad] of the plain model about the scene's pivot, from the same
    influence coefficients (lever**2 / c_total: body wind-up included in every tooth)."""
    lever = load_case(setup.geometry, 0, setup.pivot_radius).lever
    return lever**2 / body_torsion(setup).c_total
