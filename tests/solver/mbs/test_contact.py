"""Exact contact geometry against brute force, gradients against finite differences."""
import math

import numpy as np
import pytest
from helpers import compiled_call
from matplotlib.path import Path

from solver.mbs.kernels import layout as L
from solver.mbs.kernels.contact import flank_flank, point_flank
from solver.mbs.kernels.gearmesh import contact_geo, mesh_contacts, new_contact_buffer


def _tooth_world(g, center, axis, phi=0.0, pivot_radius=None):
    x, y = g.outline(n_involute=400, n_fillet=40, n_tip=40, n_root=8)
    if phi:
        # rotate about the pivot on the tooth axis
        px = pivot_radius
        c, s = math.cos(phi), math.sin(phi)
        x, y = px + c * (x - px) - s * y, s * (x - px) + c * y
    c, s = math.cos(axis), math.sin(axis)
    return center[0] + c * x - s * y, center[1] + s * x + c * y


def _brute_penetration(xa, ya, ca, xb, yb, cb):
    """Deepest point of one outline inside the other, as distance to that outline [m]."""
    best = 0.0
    pa = Path(np.c_[np.r_[xa, ca[0]], np.r_[ya, ca[1]]])
    pb = Path(np.c_[np.r_[xb, cb[0]], np.r_[yb, cb[1]]])
    for xs, ys, poly, ox, oy in ((xa, ya, pb, xb, yb), (xb, yb, pa, xa, ya)):
        pts = np.c_[xs, ys]
        seg0 = np.c_[ox[:-1], oy[:-1]]
        ab = np.c_[ox[1:], oy[1:]] - seg0
        for p in pts[poly.contains_points(pts)]:
            t = np.clip(((p - seg0) * ab).sum(1) / (ab * ab).sum(1), 0, 1)
            best = max(best, np.min(np.hypot(*(seg0 + t[:, None] * ab - p).T)))
    return best


@pytest.mark.parametrize("deg, phi_a, phi_b", [(0.0, 0, 0), (2.0, 0, 0), (3.75, 0, 0), (3.9, 0, 0), (4.3, 0, 0),
                                               (1.0, 2e-3, -1e-3), (3.9, 1.5e-3, 1.5e-3)])
def test_penetration_matches_brute_force_distance(paper_solid_model, deg, phi_a, phi_b):
    """Flank-flank and tip-corner contacts, rigid and with rotated teeth, against sampled outlines."""
    m = paper_solid_model
    g1, g2 = m.geometry
    th1 = math.radians(deg)
    th2 = m.theta2_for_te(th1, m.backlash_offset + 5.5e-6)
    phi = np.zeros(m.n_teeth)
    rec, pairs = new_contact_buffer()
    # first find the contacts with rigid teeth, then rotate the teeth involved
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, phi, contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    assert nc >= 2
    k, j = int(rec[0, L.C_TOOTH1]), int(rec[0, L.C_TOOTH2])
    phi[k] = phi_a
    phi[m.teeth[0] + j] = phi_b
    nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, np.zeros_like(phi), contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
    rows = [c for c in range(nc) if int(rec[c, L.C_TOOTH1]) == k and int(rec[c, L.C_TOOTH2]) == j]
    exact = max([rec[c, L.C_DELTA] for c in rows], default=0.0)
    ax1 = th1 + m.gear_par[0, L.GAMMA0] + k * g1.pitch_angle
    ax2 = th2 + m.gear_par[1, L.GAMMA0] + j * g2.pitch_angle
    xa, ya = _tooth_world(g1, (0, 0), ax1, phi_a, m.gear_par[0, L.R_PV])
    xb, yb = _tooth_world(g2, (m.pair.center_distance, 0), ax2, phi_b, m.gear_par[1, L.R_PV])
    brute = _brute_penetration(xa, ya, (0, 0), xb, yb, (m.pair.center_distance, 0))
    assert exact == pytest.approx(brute, abs=5e-9)   # 5 nm: sampling of the outlines


def test_primitives_against_numeric_minimisation():
    """point_flank equals the distance from a point to a densely sampled involute."""
    rb, beta = 0.04, 0.3
    u = np.linspace(0, 0.6, 200001)
    t = beta - u
    px = rb * np.cos(t) - rb * u * np.sin(t)
    py = rb * np.sin(t) + rb * u * np.cos(t)
    for q in [(0.0425, 0.012), (0.043, 0.0148), (0.041, 0.020)]:
        d, uf, nx, ny = point_flank(q[0], q[1], 0.0, 0.0, rb, beta, 1.0)
        dist = np.min(np.hypot(px - q[0], py - q[1]))
        assert abs(d) == pytest.approx(dist, abs=1e-9)
    # flank_flank: two identical circles, conjugate position -> zero penetration at the pitch point
    a = 0.1
    r = 0.05
    rbv = r * math.cos(0.35)
    inv = math.tan(0.35) - 0.35
    delta, ua, ub, nx, ny, _, _ = compiled_call(flank_flank)(0.0, 0.0, rbv, inv, a, 0.0, rbv, math.pi + inv, 1.0)
    assert delta == pytest.approx(0.0, abs=1e-15)
    assert ua == pytest.approx(math.tan(0.35)) and ub == pytest.approx(math.tan(0.35))


def test_gradient_matches_finite_differences(paper_solid_model):
    """G = d delta / d(theta1, phi_A, theta2, phi_B) of every contact, flank and corner."""
    m = paper_solid_model
    rec, pairs = new_contact_buffer()
    kinds = set()
    for deg in (1.0, 3.8, 4.3):
        th1 = math.radians(deg)
        th2 = m.theta2_for_te(th1, m.backlash_offset + 5.5e-6)
        phi = np.zeros(m.n_teeth)
        z = np.zeros(m.n_teeth)
        nc, _ = mesh_contacts((th1, th2, 0.0, 0.0), phi, z, contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
        base = rec[:nc].copy()
        h = 1e-8
        for c in range(nc):
            k, j = int(base[c, L.C_TOOTH1]), int(base[c, L.C_TOOTH2])
            kinds.add(int(abs(base[c, L.C_KIND])))

            def delta_at(d1=0.0, da=0.0, d2=0.0, db=0.0):
                p = phi.copy()
                p[k] += da
                p[m.teeth[0] + j] += db
                n2, _ = mesh_contacts((th1 + d1, th2 + d2, 0.0, 0.0), p, z, contact_geo(m.gear_par, m.pair_par, m.law_par), (rec, pairs))
                for r in range(n2):
                    if int(rec[r, L.C_TOOTH1]) == k and int(rec[r, L.C_TOOTH2]) == j and rec[r, L.C_KIND] == base[c, L.C_KIND]:
                        return rec[r, L.C_DELTA]
                raise AssertionError("contact lost")

            fd = [(delta_at(**{key: h}) - delta_at(**{key: -h})) / (2 * h) for key in ("d1", "da", "d2", "db")]
            g = base[c, [L.C_G1, L.C_GA, L.C_G2, L.C_GB]]
            np.testing.assert_allclose(g, fd, rtol=1e-5, atol=1e-9)
    assert kinds >= {1, 2}


# flank deviations, pitch errors and friction on the paper pair (the series compliance needs the
# FE springs of the compliance model: `test_compile_ahead.test_the_default_models_first_run_...`)
PARTS = {"deviations": {"gear1.modification.tip_relief": 10.0, "gear1.modification.tip_length": 3.0,
                        "gear2.modification.tip_relief": 10.0, "gear2.modification.tip_length": 3.0},
         "errors": {"gear1.errors.grade": 6, "gear1.errors.seed": 1, "gear2.errors.eccentricity": 5.0},
         "friction": {"contact.friction": 0.1}}


@pytest.mark.parametrize("present", [(), ("deviations",), ("errors", "friction")])
def test_contact_search_variant_holds_the_parts_the_model_has(present):
    """`contact_parts` names exactly the parts a model has (each part's array, None for the
    others), and the contact search compiled for that set, the branches of the absent parts
    pruned by numba, gives every contact record to the bit as its source run as plain Python
    (which tests the parts at run time), at a loaded state with teeth rotated and moving and
    contacts of both kinds (flank-flank and tip corner)."""
    from helpers import solid_scene

    from solver.mbs.kernels import python_calls
    from solver.mbs.kernels.gearmesh import contact_parts, pair_contacts
    from study.scene_model import build_scene_model
    over = {k: v for name in present for k, v in PARTS[name].items()}
    # the model's arrays without its dampers converted from ratios: the search reads no damper,
    # and the conversion would solve the loaded equilibria (a static sweep compiled per variant)
    m = build_scene_model(solid_scene(**over), convert_damping=False)
    gp, pp, lp = m.gear_par, m.pair_par, m.law_par
    parts = contact_parts(gp, pp, lp)
    # (the series compliances and the tip edges that join them: `test_tip_edge`)
    arrays = {"deviations": gp, "series": gp, "errors": pp, "friction": lp, "edges": gp}
    for name in L.ContactParts._fields:
        assert (getattr(parts, name) is arrays[name]) == (name in present), name
    geo = (gp, pp, lp, parts)
    rng = np.random.default_rng(5)
    kinds = set()
    for deg in (0.3, 1.9, 3.9, 4.3):
        th1 = math.radians(deg)
        th2 = m.theta2_for_te(th1, m.backlash_offset + 16e-6)    # through the 10 um relief
        phi = rng.normal(scale=2e-4, size=m.n_teeth)
        dphi = rng.normal(scale=5.0, size=m.n_teeth)
        state = (th1, th2, 100.0, -100.0 * m.base_radii[0] / m.base_radii[1])
        rec, pairs = new_contact_buffer()
        nc, npair = mesh_contacts(state, phi, dphi, geo, (rec, pairs))
        ref = np.zeros_like(rec)
        with python_calls():     # the search's source and its wrapper-less callees as plain Python
            n, npair_ref = pair_contacts.py_func(state, phi, dphi, geo, (ref, np.zeros_like(pairs)), *parts)
        assert n == nc >= 1 and npair_ref == npair
        np.testing.assert_array_equal(rec[:nc], ref[:nc])
        kinds |= {abs(int(rec[c, L.C_KIND])) for c in range(nc)}
        if "friction" in present:
            assert np.any(rec[:nc, L.C_FT] != 0.0)
        else:
            assert np.all(rec[:nc, L.C_FT] == 0.0)
    assert 1 in kinds and kinds & {2, 3}


def test_wrap_is_the_remainder_to_the_bit():
    """The angle wrap (the search's flank roll angles) gives the remainder's bits, in the turn
    around zero where it skips the library call and beyond it, compiled and as Python."""
    from solver.mbs.kernels.contact import wrap
    compiled = compiled_call(wrap)
    rng = np.random.default_rng(7)
    angles = np.concatenate([rng.uniform(-math.pi, math.pi, 200), rng.uniform(-40.0, 40.0, 200),
                             [-math.pi, math.pi, 0.0, -0.0, 3 * math.pi, -3 * math.pi, math.nextafter(math.pi, 0.0)]])
    for a in angles:
        want = (a + math.pi) % (2.0 * math.pi) - math.pi
        assert compiled(a) == want and wrap.py_func(a) == want
        assert -math.pi <= want < math.pi
