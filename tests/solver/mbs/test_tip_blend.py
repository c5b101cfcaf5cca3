"""A modified tip corner blends C1 into its flank (`gearmesh.TIP_BLEND`): the penetration has
no kink where a relieved flank's contact runs off its tip, the statics tangent carries the
blend's curvature, and the statics converge at the equilibria that sit on that switch."""
import math
from pathlib import Path

import numpy as np
from test_relief import ELASTIC, small

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.gearmesh import TIP_BLEND, contact_geo, mesh_contacts, new_contact_buffer
from solver.mbs.kernels.statics import newton_system, static_work
from solver.mbs.statics import solve_static
from study.scene import load_scene
from study.scene_model import build_scene_model, geometry_model

SCENES = Path(__file__).resolve().parents[3] / "study" / "scenes"
RELIEF = {"gear1.modification.tip_relief": 9.0, "gear1.modification.tip_length": 1.5, **ELASTIC}
APPROACH = 12e-6       # m: the flanks pushed into each other beyond the 9 um relief


def _th2(model, th1):
    """Driven angle [rad] that puts the rigid flanks APPROACH into each other at driver angle th1."""
    rb1, rb2 = model.base_radii
    return (APPROACH + model.backlash_offset - rb1 * th1) / rb2


def _corner_pair(model):
    """(theta1 [rad], theta2 [rad], the pair (gear-1 tooth, gear-2 tooth)) of a gear-1 tip corner
    that has just run off the flank contact, with the tooth rotations zero, found by
    scanning the driver angle along the conjugate motion (`_th2`)."""
    phi = np.zeros(model.n_teeth)
    rec, pairs = new_contact_buffer()
    for th1 in np.radians(np.arange(0.0, 20.0, 0.01)):
        th2 = _th2(model, th1)
        nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, phi, contact_geo(model.gear_par, model.pair_par, model.law_par), (rec, pairs))
        for c in range(nc):
            if rec[c, L.C_KIND] == 2.0:
                return th1, th2, (rec[c, L.C_TOOTH1], rec[c, L.C_TOOTH2])
    raise AssertionError("no gear-1 tip corner contact found")


def _delta(model, th1, th2, phi, key):
    rec, pairs = new_contact_buffer()
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, phi * 0, contact_geo(model.gear_par, model.pair_par, model.law_par), (rec, pairs))
    for c in range(nc):
        if (rec[c, L.C_TOOTH1], rec[c, L.C_TOOTH2]) == key:
            return rec[c, L.C_DELTA], rec[c, L.C_KIND]
    return math.nan, 0.0


def test_penetration_has_no_kink_where_the_contact_leaves_the_relieved_tip():
    """Along the conjugate motion (the rigid approach fixed), the slope of the penetration of
    the pair whose gear-1 tip corner takes over from its flank contact: its jump across the
    switch is below 1 % of the relief's slope (without the blend it jumps by the whole slope:
    the flank's deviation changes with the roll, the corner's does not)."""
    model = geometry_model(small(**RELIEF))
    th1, _th, key = _corner_pair(model)
    phi = np.zeros(model.n_teeth)

    def pen(a):
        return _delta(model, a, _th2(model, a), phi, key)

    lo, hi = th1 - math.radians(0.01), th1            # bracket the switch by bisection
    assert pen(lo)[1] == 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if pen(mid)[1] == 2.0 else (mid, hi)
    h = 0.005 * TIP_BLEND           # rad of driver: about 0.005 TIP_BLEND of roll
    left = (pen(lo)[0] - pen(lo - h)[0]) / h
    right = (pen(hi + h)[0] - pen(hi)[0]) / h
    row = model.gear_par[0]
    relief_slope = (row[L.DEV0 + L.N_DEV - 1] - row[L.DEV0 + L.N_DEV - 2]) / row[L.DEV_DU]      # m per unit roll
    assert relief_slope > 1e-5                       # the kink the blend removes is sizeable
    assert abs(left) > 0.5 * relief_slope            # the flank side carries the relief's slope
    assert abs(right - left) < 0.01 * relief_slope + relief_slope * h / TIP_BLEND      # + the blend over h


def test_statics_tangent_matches_the_finite_difference_jacobian_in_the_blend():
    """At a loaded state whose gear-1 tip corner is inside the blend, the Newton tangent
    (theta2 and the teeth near the mesh) equals the central-difference Jacobian of the residual
    to 1 % of its largest entry per row (without the blend's curvature the tooth rows are off
    several fold)."""
    model = geometry_model(small(**RELIEF))
    th1, _th, key = _corner_pair(model)
    geo = contact_geo(model.gear_par, model.pair_par, model.law_par)
    mdl = (*geo[:3], model.k_phi, geo[3])
    phi = np.zeros(model.n_teeth)
    # move into the blend: half a blend length past the switch, found along the conjugate motion
    lo, hi = th1 - math.radians(0.01), th1
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if _delta(model, mid, _th2(model, mid), phi, key)[1] == 2.0 else (mid, hi)
    th1 = hi + 0.5 * TIP_BLEND
    th2 = _th2(model, th1)
    rec, pairs = new_contact_buffer()
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, phi, contact_geo(model.gear_par, model.pair_par, model.law_par), (rec, pairs))
    assert any(rec[c, L.C_KGEO] != 0.0 for c in range(nc))
    K, _r, teeth = newton_system(mdl, th1, th2, phi, 0.0, static_work(model.n_teeth))

    def residual(x):
        ph = phi.copy()
        ph[teeth] = x[1:]
        r = newton_system(mdl, th1, x[0], ph, 0.0, static_work(model.n_teeth))[1]
        assert r.size == x.size                      # the same unknowns
        return r

    x0 = np.concatenate([[th2], phi[teeth]])
    J = np.zeros_like(K)
    for k in range(x0.size):
        h = 1e-3 * TIP_BLEND
        e = np.zeros(x0.size)
        e[k] = h
        J[:, k] = -(residual(x0 + e) - residual(x0 - e)) / (2 * h)
    scale = np.abs(J).max(axis=1, keepdims=True) + 1e-30
    assert np.all(np.abs(K - J) <= 0.01 * scale)


def test_statics_converge_where_a_relieved_tip_leaves_the_flank_at_equilibrium():
    """The paper pair with a 2 um long tip relief on the driver only, thin-webbed solid driven
    gear, 50 N*m: the equilibrium at 73.4 deg sits on the switch of a tip corner; Newton stalled
    there (a kink in the penetration) and now converges in a few iterations."""
    scene = load_scene(SCENES / "paper_relief.toml").replace(**{"gear2.modification.tip_relief": 0.0,
                                                                  "gear2.body.holes": 0})
    model = build_scene_model(scene)
    angles = np.radians(np.arange(72.0, 74.5, 0.2))
    st = solve_static(model, angles, 50.0, raise_on_failure=False)
    assert st.converged.all(), st.message
    assert st.iterations.max() <= 20
