"""The CalculiX contact peer: its deck (no ccx needed), the error without ccx, and (slow, with
ccx) the default model's STE of the small pair against the peer."""
import math
import re
import shutil

import numpy as np
import pytest
from helpers import small_scene

from solver import units
from solver.fe.mesh import REGION_WEB, tooth_pieces
from solver.peers.calculix import CalculixFailed, CalculixMissing, ccx_path
from solver.peers.calculix.deck import GearPlacement, placed_points, write_deck
from solver.peers.calculix.mesh import EDGES, MeshSizes, mesh_gear, teeth_near
from solver.peers.calculix.run import reached, read_dat, run_deck

# the default model's elastic STE against the peer at a coarse peer mesh (0.3 mm, module/10), per
# position and on the step from double to single contact, as documented in docs/models.md
STE_TOLERANCE = 0.05
STEP_TOLERANCE = 0.15

LIGHT = {"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4, "gear2.body.hole_radius": 3.0,
         "gear2.body.hole_circle_radius": 19.5}


@pytest.fixture(scope="module")
def small_light_meshes():
    """The small pair with a lightened driven gear, coarsely meshed (1 mm flanks), and its model."""
    from study.verify.calculix_reference import peer_gears
    scene = small_scene(**LIGHT)
    gears, model = peer_gears(scene)
    sizes = MeshSizes(flank=1.0e-3, fillet=1.0e-3, body=1.5e-3)
    meshes = [mesh_gear(g.geometry, g.body, sizes, [0, 1, 23], [0, 1]) for g in gears]
    return scene, gears, model, meshes


def _deck(scene, gears, model, meshes, torque=100.0):
    g2 = gears[1].geometry
    placed = tuple(GearPlacement(m, g.geometry.spec.face_width, g.body.web_thickness, c, a)
                   for m, g, c, a in zip(meshes, gears, ((0.0, 0.0), (model.pair.center_distance, 0.0)),
                                         (0.0, math.pi + math.pi / g2.teeth)))
    return write_deck(placed, scene.material_spec(), torque, 2e16)


def _block(text, keyword):
    """Data lines after the first line that starts with ``keyword``."""
    i = text.index(keyword)
    body = text[text.index("\n", i) + 1:]
    return body[:body.index("*")].strip().splitlines()


def test_deck_counts_sets_units_and_torque_sign(small_light_meshes):
    scene, gears, model, meshes = small_light_meshes
    text, nums = _deck(scene, gears, model, meshes)
    n1, n2 = meshes[0].n_nodes, meshes[1].n_nodes
    assert nums.n_nodes == n1 + n2 + 2 and nums.ref_node == n1 + n2 + 1 and nums.rot_node == n1 + n2 + 2
    assert len(_block(text, "*NODE, NSET=NALL")) == nums.n_nodes
    elements = [ln for ln in text.splitlines() if re.match(r"^\d+(,\d+){6}$", ln)]
    assert len(elements) == nums.n_elements == meshes[0].n_elements + meshes[1].n_elements
    # units: the reference node at the centre distance in mm, E in MPa, thicknesses in mm
    ref = _block(text, "*NODE, NSET=NALL")[nums.ref_node - 1].split(",")
    assert float(ref[1]) == pytest.approx(model.pair.center_distance * 1e3, rel=1e-9)
    assert _block(text, "*ELASTIC")[0] == f"{scene.material.youngs_modulus:.9g},{scene.material.poisson_ratio:.9g}"
    assert _block(text, "*SOLID SECTION, ELSET=G2WEB")[0] == "8"           # mm: the lightened web
    assert _block(text, "*SOLID SECTION, ELSET=G2RIM")[0] == "20"          # mm: the face
    assert _block(text, "*SOLID SECTION, ELSET=G1WEB")[0] == "20"          # gear 1 solid
    assert np.any(meshes[1].region == REGION_WEB)
    # the resisting torque holds the driven gear back: counter-clockwise (+z), in N·mm
    node, dof, value = _block(text, "*CLOAD")[0].split(",")
    assert (int(node), int(dof), float(value)) == (nums.rot_node, 3, pytest.approx(100.0 / units.NMM))
    assert f"*RIGID BODY, NSET=BORE2, REF NODE={nums.ref_node}, ROT NODE={nums.rot_node}" in text
    bore1 = [int(v) for ln in _block(text, "*NSET, NSET=BORE1") for v in ln.split(",")]
    assert sorted(bore1) == list(meshes[0].bore + 1)
    # the four holes of gear 2 leave the deck's nodes outside them
    xy = placed_points(GearPlacement(meshes[1], 0.02, 0.008, (0.0, 0.0), 0.0))
    for t in range(4):
        c = 19.5e-3 * np.array([math.cos(t * math.pi / 2), math.sin(t * math.pi / 2)])
        assert np.hypot(*(xy - c).T).min() > 3e-3 * (1 - 1e-6)
    with pytest.raises(ValueError, match="positive"):
        _deck(scene, gears, model, meshes, torque=-1.0)
    # the driven gear's ground spring: on the rotation node's z rotation, N·mm/rad
    assert "GROUND" not in text
    placed = (GearPlacement(meshes[0], 0.02, 0.02, (0.0, 0.0), 0.0), GearPlacement(meshes[1], 0.02, 0.008, (0.07, 0.0), 0.0))
    grounded, nums = write_deck(placed, scene.material_spec(), 100.0, 2e16, ground_stiffness=1e3)
    assert f"*ELEMENT, TYPE=SPRING1, ELSET=GROUND\n{nums.n_elements + 1},{nums.rot_node}\n*SPRING, ELSET=GROUND\n3\n1000000\n" in grounded


def test_contact_faces_are_the_drive_flanks_and_tips_of_the_teeth_at_the_mesh(small_light_meshes):
    _, gears, _, meshes = small_light_meshes
    for pg, m in zip(gears, meshes):
        g = pg.geometry
        mid = m.points[m.triangles[m.contact_faces[:, 0], EDGES[m.contact_faces[:, 1], 2]]]
        r = np.hypot(*mid.T)
        assert np.all(r >= g.form_radius * (1 - 1e-6)) and np.all(r <= g.tip_radius * (1 + 1e-6))
        a = np.arctan2(mid[:, 1], mid[:, 0])
        tooth = np.rint(a / g.pitch_angle).astype(int) % g.teeth
        assert set(tooth) == {0, 1}
        rel = a - np.rint(a / g.pitch_angle) * g.pitch_angle
        tip = r > g.tip_radius - 0.02 * g.spec.module
        assert np.all(rel[~tip] > 0)                      # the + (drive) flank only
        assert tip.any() and (~tip).sum() > 5


def test_contact_flank_nodes_lie_on_the_involute(small_light_meshes):
    """Every node of the contact flanks (mid-sides included) within 0.01 um of the involute: a
    spline through the FE body's 12 points per flank strays up to 4 um, as much as the STE."""
    _, gears, _, meshes = small_light_meshes
    for pg, m in zip(gears, meshes):
        g = pg.geometry
        f = m.contact_faces
        nodes = np.unique(m.triangles[f[:, 0][:, None], EDGES[f[:, 1]]])
        p = m.points[nodes]
        r, a = np.hypot(*p.T), np.arctan2(p[:, 1], p[:, 0])
        on = (r > g.form_radius) & (r < g.tip_radius - 1e-6)   # the flank, not the tip arc
        u = g.roll_at(r[on])
        rel = (a[on] - np.rint(a[on] / g.pitch_angle) * g.pitch_angle)
        deviation = (rel - (g.psi_base - (u - np.arctan(u)))) * g.base_radius   # along the line of action
        assert on.sum() > 20 and np.abs(deviation).max() < 1e-8


def test_teeth_near_the_mesh():
    p = 2 * math.pi / 24
    assert teeth_near(p, 0.0, 0.0, [0.0], 1) == [0, 1, 23]
    # gear 2's teeth face gear 1 at polar angle pi, straddling it; half a pitch of rotation
    # brings the next one within a pitch
    assert teeth_near(p, math.pi + p / 2, math.pi, [0.0], 1) == [0, 23]
    assert teeth_near(p, math.pi + p / 2, math.pi, [0.0, -p / 2], 1) == [0, 1, 23]


def test_relief_moves_the_flank_by_its_deviation_along_the_normal():
    from study.verify.calculix_reference import peer_gears
    scene = small_scene(**{"gear1.modification.tip_relief": 20.0, "gear1.modification.tip_length": 2.0})
    (pg, _), _ = peer_gears(scene)
    g = pg.geometry
    perfect, relieved = tooth_pieces(g)[len(tooth_pieces(g)) // 2 + 1][0], tooth_pieces(g, deviation=pg.deviation)
    moved = relieved[len(relieved) // 2 + 1][0]
    u = np.linspace(g.u_tip, g.u_form, perfect.shape[0])
    assert np.hypot(*(moved - perfect).T) == pytest.approx(pg.deviation(u), abs=1e-12)
    assert pg.deviation(g.u_tip) == pytest.approx(20e-6)
    # the tip arc ends at the relieved corners
    assert np.allclose(relieved[len(relieved) // 2][0][-1], moved[0])


def test_rounded_tip_edge_is_tangent_to_the_flank_and_the_tip_circle():
    """With a tip edge radius the tooth outline runs flank, round, tip arc, round, flank: each
    round's points lie on a circle of that radius, and it meets the flank and the tip arc without
    a kink (the chords next to each junction turn by the same small angle as the chords along
    the curve), the flank below it on the involute; the tip arc is shorter by the rounds."""
    from solver.tip_edge import tip_round
    from study.verify.calculix_reference import peer_gears
    (pg, pg2), _ = peer_gears(small_scene(**{"gear1.modification.tip_edge_radius": 0.2}))
    assert pg.edge_radius == pytest.approx(0.2e-3) and pg2.edge_radius == 0.0
    g, r = pg.geometry, pg.edge_radius
    sharp, pieces = tooth_pieces(g, n=150), tooth_pieces(g, n=150, edge_radius=r)
    assert len(pieces) == len(sharp) + 2
    mid = len(pieces) // 2
    tip, rnd, flank = pieces[mid][0], pieces[mid + 1][0], pieces[mid + 2][0]
    t = tip_round(g, r)
    assert np.hypot(*(rnd - t.centre).T) == pytest.approx(r, rel=1e-12)
    assert np.allclose(rnd[0], tip[-1], rtol=0, atol=1e-15) and np.allclose(rnd[-1], flank[0], rtol=0, atol=1e-15)
    assert np.hypot(*tip.T) == pytest.approx(g.tip_radius, rel=1e-12)
    assert math.atan2(tip[-1, 1], tip[-1, 0]) < g.tip_half_angle
    # the flank below the round on the involute (rel. polar angle of the + flank at its radius)
    rr, a = np.hypot(*flank.T), np.arctan2(flank[:, 1], flank[:, 0])
    u = g.roll_at(rr)
    assert np.abs(a - (g.psi_base - (u - np.arctan(u)))).max() * g.base_radius < 1e-12

    def heading(p):
        d = np.diff(p, axis=0)
        return np.arctan2(d[:, 1], d[:, 0])
    # no kink: the turn across each junction is no larger than the turn between chords inside
    for before, after in ((tip, rnd), (rnd, flank)):
        step = abs((heading(after)[0] - heading(before)[-1] + math.pi) % (2 * math.pi) - math.pi)
        inside = max(np.abs(np.diff(heading(before))).max(), np.abs(np.diff(heading(after))).max())
        assert step <= inside * 1.01
    # the whole round turns from the tip circle's direction to the flank's, about 90 deg - alpha_a
    # (its 16 chords' headings span 15/16 of the turn)
    turn = (heading(rnd)[-1] - heading(rnd)[0] + math.pi) % (2 * math.pi) - math.pi
    assert abs(turn) * 16 / 15 == pytest.approx(0.5 * math.pi - math.acos(g.base_radius / g.tip_radius), rel=0.02)


def test_peer_meshes_the_round_fine_and_on_its_circle():
    """The peer's mesh of a gear with 0.2 mm tip edges (flanks at 0.3 mm): on each fine tooth's
    drive round the boundary nodes (mid-sides included) lie on the round's circle and no further
    apart than a quarter radius (its element size, `round_size`); the drive round is contact
    face, as the flank below it."""
    from solver.peers.calculix.mesh import boundary_edges, round_size
    from solver.tip_edge import tip_round
    from study.verify.calculix_reference import peer_gears
    (pg, _), _ = peer_gears(small_scene(**{"gear1.modification.tip_edge_radius": 0.2}))
    g, r = pg.geometry, pg.edge_radius
    sizes = MeshSizes(flank=0.3e-3, fillet=0.6e-3, body=1.5e-3)
    m = mesh_gear(g, pg.body, sizes, [0, 1, 23], [0, 1], edge_radius=r)
    assert round_size(r, sizes.flank) == pytest.approx(r / 4)
    t = tip_round(g, r)
    b = boundary_edges(m.triangles)
    on_outline = np.unique(m.triangles[b[:, 0][:, None], EDGES[b[:, 1]]])
    face_nodes = np.unique(m.triangles[m.contact_faces[:, 0][:, None], EDGES[m.contact_faces[:, 1]]])
    a_tip = math.atan2(t.tip_point[1] - t.centre[1], t.tip_point[0] - t.centre[0])
    a_flank = math.atan2(t.flank_point[1] - t.centre[1], t.flank_point[0] - t.centre[0])
    for k in (0, 1, 23):
        c = np.array(t.centre) @ np.array([[math.cos(k * g.pitch_angle), math.sin(k * g.pitch_angle)],
                                          [-math.sin(k * g.pitch_angle), math.cos(k * g.pitch_angle)]])
        p = m.points[on_outline] - c
        ang = (np.arctan2(p[:, 1], p[:, 0]) - k * g.pitch_angle - a_tip + math.pi) % (2 * math.pi) - math.pi
        span = (a_flank - a_tip + math.pi) % (2 * math.pi) - math.pi
        sel = (np.hypot(*p.T) < 1.5 * r) & (ang >= -1e-9) & (ang <= span + 1e-9)
        assert np.abs(np.hypot(*p[sel].T) - r).max() < 1e-3 * r        # on the circle (the spline's 17 points)
        gaps = np.diff(np.sort(ang[sel])) * r
        assert sel.sum() >= 9 and gaps.max() <= 0.5 * round_size(r, sizes.flank) * 1.3   # mid-sides: half an element
        if k in (0, 1):
            assert np.isin(on_outline[sel], face_nodes).all()


def test_peer_archive_names_the_tip_edges_only_where_there_are_some(monkeypatch):
    """The peer's archive carries each gear's tip edge radius and the element size on its round
    (a quarter radius) where a gear has one, and neither attribute for sharp corners (the sweep
    itself replaced: no ccx)."""
    import study.verify.calculix_reference as cr
    from solver.peers.calculix import PeerResult

    class Mesh:
        n_nodes, n_elements = 10, 5

    def sweep(gears, pair, material, angles, torque, settings, progress=None, starts=None):
        n = len(angles)
        return PeerResult(np.asarray(angles), np.zeros(n), 0.0, (Mesh(), Mesh()), np.ones(n), np.ones(n), settings, "x")
    monkeypatch.setattr(cr, "ste_sweep", sweep)
    edged = small_scene(**{"gear1.modification.tip_edge_radius": 0.2})
    ds = cr.calculix_dataset(edged, np.radians([0.0]), cr.settings_for(edged, 0.3))
    np.testing.assert_allclose(ds.attrs["tip_edge_radius_mm"], [0.2, 0.0])
    np.testing.assert_allclose(ds.attrs["tip_edge_mesh_size_mm"], [0.05, 0.0])
    sharp = cr.calculix_dataset(small_scene(), np.radians([0.0]), cr.settings_for(small_scene(), 0.3))
    assert "tip_edge_radius_mm" not in sharp.attrs and "tip_edge_mesh_size_mm" not in sharp.attrs


def test_soft_start_deck_stiffens_the_contact_in_a_second_step(small_light_meshes):
    """A soft start carries the torque at 1/8 of the contact stiffness in a first step, then
    stiffens the contact under the same torque; the result is read at the end of the second."""
    scene, gears, model, meshes = small_light_meshes
    placed = tuple(GearPlacement(m, 0.02, g.body.web_thickness, c, 0.0)
                   for m, g, c in zip(meshes, gears, ((0.0, 0.0), (model.pair.center_distance, 0.0))))
    one, n1 = write_deck(placed, scene.material_spec(), 100.0, 2e16)
    two, n2 = write_deck(placed, scene.material_spec(), 100.0, 2e16, soft_start=0.125)
    assert (n1.end_time, n2.end_time) == (1.0, 2.0)
    assert one.count("*STEP") == 1 and two.count("*STEP") == 2 and "*CHANGE SURFACE BEHAVIOR" not in one
    laws = [ln for blk in two.split("*SURFACE BEHAVIOR")[1:] for ln in [blk.splitlines()[1]]]
    # MPa/mm: 2e16 Pa/m = 2e7 MPa/mm, first an eighth of it
    assert [float(v.split(",")[0]) for v in laws] == [2.5e6, 2e7]
    assert two.index("*CHANGE SURFACE BEHAVIOR, INTERACTION=FLANK") > two.rindex("*STEP")
    # the torque is applied once (in the first step) and held
    assert two.count("*CLOAD") == 1
    with pytest.raises(ValueError, match="soft_start"):
        write_deck(placed, scene.material_spec(), 100.0, 2e16, soft_start=1.0)


def test_a_deck_past_its_cpu_limit_is_stopped_with_one_line(tmp_path, monkeypatch):
    """A ccx that never converges (here one that spins) is stopped by the kernel at its CPU
    limit and reported in one line, not waited for."""
    spin = tmp_path / "ccx"
    spin.write_text("#!/bin/sh\nwhile :; do :; done\n")
    spin.chmod(0o755)
    monkeypatch.setenv("LIGHTGEAR_CCX", str(spin))
    import time
    t0 = time.perf_counter()
    with pytest.raises(CalculixFailed, match="CPU-time limit of 1 s") as e:
        run_deck("*HEADING\n", 2, 1, cpu_limit_s=1.0, timeout_s=60.0)
    assert time.perf_counter() - t0 < 30.0
    assert e.value.cpu_time_s >= 0.9 and "\n" not in str(e.value)


def test_reached_reads_the_last_converged_increment(tmp_path):
    (tmp_path / "pair.sta").write_text(
        "SUMMARY OF JOB INFORMATION\n  STEP      INC     ATT  ITRS     TOT TIME     STEP TIME      INC TIME\n"
        "     1          1     1   6  0.100000E+01  0.100000E+01  0.100000E+01\n"
        "     2          1     1U  12  0.100000E+01  0.000000E+00  0.100000E+01\n"
        "     2          1     2   7  0.125000E+01  0.250000E+00  0.250000E+00\n")
    assert reached(str(tmp_path), 2.0) == ", having converged up to 0.62 of the deck"
    assert reached(str(tmp_path / "none"), 1.0) == ""


def test_a_deck_that_never_converges_ends_with_its_angle_and_attempts(small_light_meshes, monkeypatch, capsys, tmp_path):
    """Every attempt of `ATTEMPTS` tried within the deck's CPU limit, then one `CalculixFailed`
    naming the angle and each attempt; the command line prints it in one line, exit 3, no archive."""
    import solver.peers.calculix as peer
    from study.cli import main
    from study.verify.calculix_reference import peer_gears
    calls = []

    def never(text, rot, ref, timeout_s=0.0, keep=None, cpu_limit_s=None, end_time=1.0):
        static = text[text.index("*STATIC\n") + 8:].splitlines()[0].split(",")
        calls.append((cpu_limit_s, "*CHANGE SURFACE BEHAVIOR" in text, end_time, float(static[2])))
        raise CalculixFailed("ccx did not converge within its CPU-time limit", cpu_limit_s)
    monkeypatch.setattr(peer, "run_deck", never)
    scene, gears, model, meshes = small_light_meshes
    monkeypatch.setattr(peer, "pair_meshes", lambda *a: tuple(meshes))
    settings = peer.CalculixSettings(MeshSizes(1e-3, 1e-3, 1.5e-3), 2e16, deck_cpu_s=100.0)
    with pytest.raises(CalculixFailed, match=r"driver angle 2\.0000 deg did not converge \(100 of 100 s CPU\)") as e:
        peer.ste_sweep(peer_gears(scene)[0], model.pair, scene.material_spec(), [math.radians(2.0)], 100.0, settings)
    # the soft start, the stiff deck, the soft start from nearer; half the time left each, the last all of it
    assert [c[1] for c in calls] == [soft > 0 for _, soft in peer.ATTEMPTS] == [True, False, True]
    assert [c[0] for c in calls] == pytest.approx([50.0, 25.0, 25.0])
    assert [c[2] for c in calls] == [2.0, 1.0, 2.0]
    # the stiff deck without cut-backs (they do not scale its start overclosure), the soft ones with
    assert [c[3] for c in calls] == [1 / 64, 1.0, 1 / 64]
    assert str(e.value).count("soft start") == 2 and "\n" not in str(e.value)
    # the command line: one line, exit 3, nothing written
    monkeypatch.setenv("LIGHTGEAR_CCX", "true")
    code = main(["reference", "small_pair", "--solver", "calculix", "--flank-size", "1.0", "--step", "15",
                 "--set", "quasi_static.rotation=15", "-o", str(tmp_path / "r.nc")])
    err = [ln for ln in capsys.readouterr().err.strip().splitlines() if not ln.startswith(("CalculiX contact peer", "  deck"))]
    assert code == 3 and len(err) == 1 and "did not converge" in err[0] and "driver angle 0.0000 deg" in err[0]
    assert not (tmp_path / "r.nc").exists()


def test_read_dat_takes_the_last_converged_block():
    dat = """
 displacements (vx,vy,vz) for set ROT and time  0.5000000E+00

        12  0.000000E+00  0.000000E+00 -1.000000E-05

 displacements (vx,vy,vz) for set ROT and time  0.1000000E+01

        12  0.000000E+00  0.000000E+00  2.500000E-05

 total force (fx,fy,fz) for set REF and time  0.1000000E+01

       -1.000000E+02  5.0E+01  0.000000E+00
"""
    rot, rf = read_dat(dat, 12)
    assert rot == 2.5e-5 and rf == (-100.0, 50.0, 0.0)


def test_missing_ccx_is_one_clear_line(monkeypatch, capsys, tmp_path):
    from study.cli import main
    monkeypatch.setenv("LIGHTGEAR_CCX", "no-such-ccx-here")
    with pytest.raises(CalculixMissing, match="apt-get install calculix-ccx"):
        ccx_path()
    code = main(["reference", "small_pair", "--solver", "calculix", "-o", str(tmp_path / "r.nc")])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2 and len(err) == 1 and "apt-get install calculix-ccx" in err[0]
    assert not (tmp_path / "r.nc").exists()


def test_solver_options_need_the_peer(capsys, tmp_path):
    from study.cli import main
    code = main(["reference", "small_pair", "--flank-size", "0.1", "-o", str(tmp_path / "r.nc")])
    assert code == 2 and "--solver calculix" in capsys.readouterr().err


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed: make sysdeps installs it")
def test_a_chattering_deck_stops_at_its_cpu_limit_in_one_line(small_light_meshes):
    """A flank mesh of 1 mm against a contact patch of ~0.2 mm (the lightened small pair at
    100 N·m): the few contact nodes chatter in and out under the stiff and the soft penalty
    alike, and the deck never converges. It must end at its CPU limit (5 s here), the attempts
    tried in turn, with one line that names the angle, not hang (such a deck ran for hours)."""
    import solver.peers.calculix as peer
    from study.verify.calculix_reference import peer_gears
    scene, _, model, _ = small_light_meshes
    gears = peer_gears(scene)[0]
    settings = peer.CalculixSettings(MeshSizes(1e-3, 1e-3, 1.5e-3), 2e16, deck_cpu_s=5.0)
    with pytest.raises(CalculixFailed, match=r"driver angle 0\.0000 deg did not converge") as e:
        peer.ste_sweep(gears, model.pair, scene.material_spec(), [0.0], 100.0, settings)
    msg = str(e.value)
    # the soft start first, then the stiff deck, until the time is spent
    assert "\n" not in msg and msg.index("soft start") < msg.index("stiff contact")
    used, limit = (float(v) for v in re.search(r"\((\d+) of (\d+) s CPU\)", msg).groups())
    assert limit == 5.0 and used <= limit + 3 * 1.0     # s: each attempt's limit rounds up to a second


@pytest.mark.slow
@pytest.mark.skipif(shutil.which("ccx") is None, reason="CalculiX (ccx) is not installed: make sysdeps installs it")
def test_default_model_ste_within_tolerance_of_the_peer(monkeypatch):
    """Small pair at 100 N·m, the peer at 0.3 mm on the flanks (two decks, ~30 s each on a quiet
    machine), at a double-contact (0 deg) and a single-contact position (11 deg): the default
    (compliance) model's elastic STE within the documented tolerance at both (measured: +0.4 %
    and -2.5 %), and the step from double to single contact (-11.9 %). A flank 4 um off the
    involute (+13 % at 0 deg) or the paper model's springs (x4) fail it."""
    import solver.peers.calculix as peer
    import study
    from study.verify.model_validation import model_ste
    # these decks converge under the stiff penalty at once (26 s each against the soft start's
    # 34 s, the same STE: docs/models.md); the soft start is held to its failure above
    monkeypatch.setattr(peer, "ATTEMPTS", tuple(a for a in peer.ATTEMPTS if a[1] == 0.0))
    scene = small_scene(**{"quasi_static.rotation": 11.0})
    peer = study.reference(scene, step=11.0, solver="calculix", flank_size=0.3)
    assert peer.attrs["solver"] == "calculix" and peer["ste"].attrs["units"] == "um"
    # s: 6 ms a node of the pair, at least 120 s
    assert peer.attrs["deck_cpu_limit_s"] == pytest.approx(max(120.0, 6e-3 * peer.attrs["nodes"]))
    np.testing.assert_allclose(peer["angle"].values, [0.0, 11.0])
    ste_peer = peer["ste"].values - peer.attrs["backlash_offset_um"]
    te, off = model_ste(scene, "compliance", np.radians(peer["angle"].values))
    ste_model = (te - off) * units.UM_PER_M
    assert ste_model == pytest.approx(ste_peer, rel=STE_TOLERANCE)
    assert np.diff(ste_model)[0] == pytest.approx(np.diff(ste_peer)[0], rel=STEP_TOLERANCE)
    assert np.diff(ste_peer)[0] > 2.0          # um: one pair carries the load at 11 deg
