"""Loaded-tooth-contact analysis: closed forms, the influence coefficients, mesh convergence."""
import math

import numpy as np
import pytest
from helpers import LIGHT, small_scene, solid_scene

from solver.fe.flank_compliance import lagrange_weights
from solver.fe.ltca import LTCAError, mesh_points, solve_contact
from study.inputs.compliance import gear_compliance
from study.inputs.gearsetup import gear_setups
from study.scene import SceneError
from study.verify import fe_reference as ref_mod

pytestmark = pytest.mark.usefixtures("private_fe_cache")


def test_rigid_bodies_share_the_load_equally_in_closed_form():
    """Rigid bodies, perfect involutes: every pair in the path of contact carries P/n, and the
    TE is the backlash offset plus the contact law's approach (P/(n k))^(1/m1) wherever the
    tip-corner candidates stay open."""
    s = solid_scene()
    angles = np.radians(np.arange(0.0, 6.0, 0.05))
    res, model, _ = ref_mod.reference(s, angles, rigid=True)
    k, m1 = model.law_par[0], model.law_par[1]
    P = s.quasi_static.torque / model.base_radii[1]
    seen = set()
    for a, th in enumerate(angles):
        mp = mesh_points(model, th)
        if res.extended[a] > 0:
            continue                       # a tip corner touches: not the closed-form case
        n = int(np.count_nonzero(mp.kind == 1))
        seen.add(n)
        assert res.te[a] == pytest.approx(model.backlash_offset + (P / (n * k)) ** (1 / m1), rel=1e-9)
        f = res.tooth_force[a][res.tooth_force[a] > 0]
        assert f.size == n and np.allclose(f, P / n, rtol=1e-9)
    assert seen == {1, 2}


def test_contact_solution_linear_law_matches_the_linear_system():
    """m1 = 1: the contact problem is linear; with both contacts active it is a 3x3 system, and
    a large initial separation leaves the second contact open with a non-negative gap."""
    G = np.array([[2.0, 0.8], [0.8, 1.5]]) * 1e-9
    k, P = 1e9, 1000.0
    gap = np.array([0.0, 0.2e-6])
    F, w = solve_contact(G, gap, P, k, 1.0)
    A = np.zeros((3, 3)); A[:2, :2] = G + np.eye(2) / k; A[:2, 2] = -1; A[2, :2] = 1
    x = np.linalg.solve(A, np.array([-gap[0], -gap[1], P]))
    assert np.all(x[:2] > 0)
    assert np.allclose(F, x[:2], rtol=1e-9) and w == pytest.approx(x[2], rel=1e-9)
    F, w = solve_contact(G, np.array([0.0, 5e-6]), P, k, 1.0)
    assert F[1] == 0 and F[0] == pytest.approx(P)
    assert w == pytest.approx(P * (G[0, 0] + 1 / k))
    assert w - 5e-6 - G[1, 0] * P < 0                     # the second pair stays open


def test_contact_solution_satisfies_complementarity_with_a_nonlinear_law():
    rng = np.random.default_rng(3)
    B = rng.normal(size=(4, 4))
    G = (B @ B.T + 4 * np.eye(4)) * 1e-10
    gap = np.array([0.0, 0.3e-6, 1e-6, 0.05e-6])
    k, m1, P = 5.64e6 * 1000.0**1.24, 1.24, 2000.0      # the paper law in SI (N/m^1.24)
    F, w = solve_contact(G, gap, P, k, m1)
    assert F.sum() == pytest.approx(P, rel=1e-9) and np.all(F >= 0)
    approach = w - gap - G @ F                            # left for the local contact
    on = F > 0
    assert np.allclose(approach[on], (F[on] / k) ** (1 / m1), rtol=1e-6, atol=1e-15)
    assert np.all(approach[~on] <= 1e-15)
    with pytest.raises(LTCAError):
        solve_contact(np.zeros((0, 0)), np.zeros(0), P, k, m1)


def test_lagrange_weights_reproduce_cubics():
    grid = np.linspace(0.2, 0.5, 8)
    f = lambda x: 3 * x**3 - x**2 + 0.5
    for x in (0.2, 0.237, 0.41, 0.5):
        i, w = lagrange_weights(grid, x)
        assert w @ f(grid[i]) == pytest.approx(f(x), rel=1e-12)


def test_compliance_is_symmetric_and_positive_definite():
    """Maxwell-Betti: reading at the centreline instead of under the load leaves the raw
    influence matrix nearly symmetric; its symmetric part is positive definite; the foundation
    couples neighbouring teeth (positive off-diagonal blocks, decaying with distance)."""
    s = small_scene(**LIGHT)
    c, _ = gear_compliance(gear_setups(s)[1], [0, 1, 2, 3], 1, n_u=6)
    n = c.g.shape[0] * c.g.shape[1]
    M = c.g.reshape(n, n)
    asym = np.abs(M - M.T).max() / np.abs(M).max()
    assert asym < 0.03
    ev = np.linalg.eigvalsh(0.5 * (M + M.T))
    assert ev.min() > 0
    assert np.all(M > 0)
    u = c.u.size // 2
    assert c.g[0, u, 0, u] > c.g[1, u, 0, u] > c.g[3, u, 0, u]
    m = c.matrix([0, 1, 1], [0.3, 0.25, 0.35])
    assert np.allclose(m, m.T) and np.linalg.eigvalsh(m).min() > 0


def test_fe_reference_converges_under_mesh_refinement():
    """STE mean and peak-to-peak of the solid small pair at three mesh sizes (ratio 1.5): the
    change shrinks with refinement."""
    s = small_scene()
    angles = np.radians(np.arange(0.0, 15.0, 0.5))
    stats = []
    for h in (1.8, 1.2, 0.8):
        res, _, _ = ref_mod.reference(s.replace(**{"fe.mesh_size": h}), angles)
        stats.append((res.te.mean(), np.ptp(res.te)))
    stats = np.array(stats)
    d = np.abs(np.diff(stats, axis=0))
    assert d[1, 0] < 0.7 * d[0, 0] and d[1, 1] < 0.7 * d[0, 1] + 1e-9
    assert d[1, 0] < 0.01 * (stats[-1, 0] - ref_mod.reference(s, angles[:1], rigid=True)[0].backlash_offset)


def test_reference_archive_and_errors(tmp_path):
    from study.cli import main
    s = small_scene(**{"fe.mesh_size": 1.8})
    path = tmp_path / "s.toml"
    path.write_text(s.to_toml())
    out = tmp_path / "ref.nc"
    assert main(["reference", str(path), "-o", str(out), "--step", "1.0"]) == 0
    import xarray as xr
    with xr.open_dataset(out) as ds:
        assert ds["ste"].attrs["units"] == "um" and ds.sizes["angle"] == 16
        assert np.all(ds["ste"].values > ds.attrs["backlash_offset_um"])
        total = ds["ste_tooth_force"].sum("driver_tooth").values
        rb2 = 0.5 * 3.0 * 24 * math.cos(math.radians(20.0)) * 1e-3
        assert np.allclose(total, 100.0 / rb2, rtol=1e-9)  # torque balance at every angle
    with pytest.raises(SceneError, match="quasi_static.torque"):
        ref_mod.reference(s.replace(**{"quasi_static.torque": 0.0}))


def test_factorised_bodies_are_reused_for_other_load_sets(monkeypatch):
    """Both gears' factorised bodies stay in memory: new load/read sets on either gear (as the
    body-torsion identification asks after a reference) mesh nothing again, and the shared
    coefficients are the same numbers."""
    import solver.fe.mesh
    calls = []
    real = solver.fe.mesh.mesh_body
    monkeypatch.setattr(solver.fe.mesh, "mesh_body", lambda *a, **k: calls.append(k.get("prefix")) or real(*a, **k))
    s = small_scene(**LIGHT, **{"fe.mesh_size": 1.8})
    g1, g2 = gear_setups(s)
    c1, i1 = gear_compliance(g1, [0], 1, n_u=4)
    c2, _ = gear_compliance(g2, [0, 1], 1, n_u=4)
    meshed = list(calls)        # (a rim's first body meshes whole, then its web alone)
    assert set(meshed) == {"gear1.body", "gear2.body"}
    c1b, i1b = gear_compliance(g1, [0], 2, n_u=4)
    c2b, _ = gear_compliance(g2, [0, 1, 2], 1, n_u=4)
    assert calls == meshed
    assert "mesh_wall_s" in i1["stages"] and "mesh_wall_s" not in i1b["stages"] and not i1b["cached"]
    assert np.allclose(c1b.block(1, 0), c1.block(1, 0), rtol=1e-12, atol=0)
    assert np.allclose(c2b.block(1, 0), c2.block(1, 0), rtol=1e-12, atol=0)
    rel = np.abs(c2.block(0, 0) / c1.block(0, 0) - 1).max()
    assert rel > 0.05, rel          # the holed body is another body
