"""The CalculiX peer's plane stress: a deck as thick as the face width is stiffer than plane
stress; one written as thin as its flank elements (`solver.peers.calculix.deck_thickness_scale`,
``--thin-decks``) reads the plane-stress answer of the project's own FE on the same mesh (slow,
needs ccx)."""
import math
import os
import re
import shutil
import subprocess

import numpy as np
import pytest

from solver.peers.calculix import deck_thickness_scale

E, NU = 206e9, 0.3                 # Pa, -
R_DISC, R_BORE = 17.19e-3, 5e-3    # m: a disc of the paper pair's flank radius at the pitch point
FACE = 17e-3                       # m
H_LOAD = 0.1e-3                    # m: element size at the load (the peer's flank size)


def test_deck_thickness_scale():
    """The thickest section goes down to the flank element size, never up; the settings take it
    with thin decks only, and the option is the peer's alone."""
    import dataclasses

    from solver.peers.calculix import default_settings
    assert deck_thickness_scale(17e-3, 0.1e-3) == pytest.approx(0.1 / 17)
    assert deck_thickness_scale(0.05e-3, 0.1e-3) == 1.0
    s = default_settings(1.5e-3, 0.1e-3)
    assert s.deck_scale(FACE) == 1.0
    assert dataclasses.replace(s, thin_decks=True).deck_scale(FACE) == pytest.approx(0.1 / 17)


def test_thin_decks_need_the_peer(capsys, tmp_path):
    from study.cli import main
    code = main(["reference", "small_pair", "--thin-decks", "-o", str(tmp_path / "r.nc")])
    assert code == 2 and "--thin-decks" in capsys.readouterr().err


def _disc_mesh():
    """(points (n, 2) [m], 6-node triangles, bore node indices, index of the node at (R, 0))."""
    from solver.fe.mesh import generate, start_gmsh
    gmsh = start_gmsh()
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("disc")
        occ = gmsh.model.occ
        surf, _ = occ.cut([(2, occ.addDisk(0, 0, 0, R_DISC, R_DISC))], [(2, occ.addDisk(0, 0, 0, R_BORE, R_BORE))])
        occ.synchronize()
        p = occ.addPoint(R_DISC, 0, 0)
        occ.synchronize()
        f = gmsh.model.mesh.field
        d = f.add("Distance")
        f.setNumbers(d, "PointsList", [p])
        th = f.add("Threshold")
        for k, v in (("InField", d), ("SizeMin", H_LOAD), ("SizeMax", 1.5e-3), ("DistMin", 0.6e-3), ("DistMax", 6e-3)):
            f.setNumber(th, k, v)
        f.setAsBackgroundMesh(th)
        generate(gmsh, order=2)
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, _, conn = gmsh.model.mesh.getElements(2, surf[0][1])     # 6-node triangles (gmsh type 9)
    finally:
        gmsh.finalize()
    index = {int(t): i for i, t in enumerate(tags)}
    points = xyz.reshape(-1, 3)[:, :2]
    tri = np.array([index[int(t)] for t in conn[0]]).reshape(-1, 6)
    used = np.unique(tri)
    keep = np.full(points.shape[0], -1)
    keep[used] = np.arange(used.size)
    points, tri = points[used], keep[tri]
    a = points[tri[:, :3]]
    flip = (a[:, 1, 0] - a[:, 0, 0]) * (a[:, 2, 1] - a[:, 0, 1]) - (a[:, 2, 0] - a[:, 0, 0]) * (a[:, 1, 1] - a[:, 0, 1]) < 0
    tri[flip] = tri[flip][:, [0, 2, 1, 5, 4, 3]]                    # counter-clockwise
    bore = np.flatnonzero(np.abs(np.hypot(*points.T) - R_BORE) < 1e-9)
    load = int(np.argmin(np.hypot(points[:, 0] - R_DISC, points[:, 1])))
    return points, tri, bore, load


def _ccx_ux(points, tri, bore, node, force, thickness, tmp_path) -> np.ndarray:
    """x displacements [m] of all nodes of the disc (bore fixed) under ``force`` [N] in -x at
    ``node``, CPS6 of ``thickness`` [m] in CalculiX."""
    lines = ["*NODE, NSET=NALL"] + [f"{i + 1},{x * 1e3:.9f},{y * 1e3:.9f},0.0" for i, (x, y) in enumerate(points)]
    lines += ["*ELEMENT, TYPE=CPS6, ELSET=EALL"] + [",".join(str(v) for v in [k + 1, *(t + 1)]) for k, t in enumerate(tri)]
    lines += ["*MATERIAL, NAME=STEEL", "*ELASTIC", f"{E / 1e6:.9g},{NU}", "*SOLID SECTION, ELSET=EALL, MATERIAL=STEEL",
              f"{thickness * 1e3:.9g}", "*NSET, NSET=BORE"]
    ids = bore + 1
    lines += [",".join(str(v) for v in ids[i:i + 16]) for i in range(0, ids.size, 16)]
    lines += ["*BOUNDARY", "BORE,1,2", "*STEP", "*STATIC", "*CLOAD", f"{node + 1},1,{-force:.9g}",
              "*NODE PRINT, NSET=NALL", "U", "*END STEP"]
    (tmp_path / "a.inp").write_text("\n".join(lines) + "\n")
    subprocess.run(["ccx", "-i", "a"], cwd=tmp_path, capture_output=True, check=True, timeout=300,
                   env=dict(os.environ, OMP_NUM_THREADS="1"))
    ux = np.full(points.shape[0], np.nan)
    for m in re.finditer(r"^\s*(\d+)\s+(\S+)\s+\S+\s+\S+\s*$", (tmp_path / "a.dat").read_text(), re.M):
        ux[int(m.group(1)) - 1] = float(m.group(2)) * 1e-3
    return ux


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed: make sysdeps installs it")
def test_thin_deck_reads_plane_stress(tmp_path):
    """A disc of the flanks' radius, bore fixed, 530 N on its rim (the paper pair's load per
    contact at 25 N·m), the same mesh in CalculiX (CPS6) and in the project's plane-stress FE:
    written 17 mm thick, CalculiX reads 2-3 % stiffer 1-3 mm from the load and 6.6 % at it
    (its one layer of expanded 3D elements cannot contract through a thickness 170 times the
    elements there); written as thin as `deck_thickness_scale` says, with the load scaled alike,
    within 0.5 % in the body and 1.5 % at the load, where plane stress holds whatever the
    thickness."""
    import skfem

    from solver.fe.body import plane_stress_lame, plane_stress_p2_stiffness
    from solver.fe.factor import factorise
    points, tri, bore, load = _disc_mesh()
    used = np.unique(tri[:, :3])
    remap = np.full(points.shape[0], -1)
    remap[used] = np.arange(used.size)
    m = skfem.MeshTri(points[used].T.copy(), remap[tri[:, :3]].T.copy())
    basis = skfem.Basis(m, skfem.ElementVector(skfem.ElementTriP2()))
    lam, mu = plane_stress_lame(E, NU)
    K = plane_stress_p2_stiffness(basis, lam, mu, np.full(m.t.shape[1], FACE)).tocsr()
    fixed = basis.get_dofs(lambda x: np.hypot(x[0], x[1]) < R_BORE + 1e-9).all()
    free = np.setdiff1d(np.arange(basis.N), fixed)
    f = np.zeros(basis.N)
    force = 530.0
    f[basis.nodal_dofs[0, remap[load]]] = -force
    u = np.zeros(basis.N)
    u[free] = factorise(K[free][:, free].tocsc()).solve(f[free])
    # vertices on the load line at the load and 1 and 3 mm inside
    nodes = [int(np.argmin(np.hypot(points[:, 0] - (R_DISC - d), points[:, 1]) + 1.0 * (remap < 0))) for d in (0.0, 1e-3, 3e-3)]
    plane_stress = np.array([u[basis.nodal_dofs[0, remap[n]]] for n in nodes])
    thick = _ccx_ux(points, tri, bore, load, force, FACE, tmp_path)[nodes]
    s = deck_thickness_scale(FACE, H_LOAD)
    thin = _ccx_ux(points, tri, bore, load, s * force, s * FACE, tmp_path)[nodes]
    assert np.all(plane_stress < 0) and math.isclose(s, H_LOAD / FACE)
    assert thick[0] / plane_stress[0] < 0.95 and np.all(thick[1:] / plane_stress[1:] < 0.985)
    assert thin[0] == pytest.approx(plane_stress[0], rel=0.015)
    np.testing.assert_allclose(thin[1:], plane_stress[1:], rtol=0.005)
