"""The lightest-gear workflow: feasibility, choice of the lightest body and the refinement grid
on synthetic study archives, the answer's figures, and clear errors on bad options."""
import math

import numpy as np
import pytest
import xarray as xr

from workflows.lightest_gear import (
    COARSE,
    FIELDS,
    Limits,
    answer,
    body_of,
    candidate_rows,
    candidates,
    feasible,
    limiting_location,
    main,
    ranked,
    refine_points,
)

SOLID = {"ste_p2p": 1.0, "dte_rms": 2.0, "mass_gear2": 2.0, "inertia_gear2": 900.0}


def synthetic_grid():
    """A 2 x 2 x 1 x 2 grid archive: mass saving grows with holes, hole radius and a thinner web;
    the TE grows with it. One point failed, one has no stress ratio (no FE)."""
    holes, radius, rim, web = [3, 6], [5.0, 7.0], [6.0], [6.0, 10.0]
    h, r, w = np.meshgrid(holes, radius, web, indexing="ij")
    saving = (2.0 * h + 3.0 * r + (10.0 - w))[:, :, None, :]            # % (rim axis of one)
    dims = ("n_holes", "hole_radius", "rim_thickness", "web_thickness")
    ste = 1.0 + saving / 100.0                                          # +1 % STE per % saved
    dte = 2.0 * (1.0 + saving / 200.0)
    ratio = 1.0 + saving / 200.0
    status = np.ones(saving.shape, np.int8)
    status[1, 1, 0, 0] = 4                                              # the lightest point failed
    ratio[1, 1, 0, 1] = np.nan                                          # no FE: stress unknown
    coords = {"n_holes": holes, "hole_radius": radius, "rim_thickness": rim, "web_thickness": web}
    ds = xr.Dataset({"status": (dims, status), "ste_p2p": (dims, ste), "dte_rms": (dims, dte),
                     "mass_saving_gear2": (dims, saving), "mass_gear2": (dims, 2.0 * (1 - saving / 100)),
                     "inertia_gear2": (dims, 900.0 * (1 - saving / 100)),
                     "root_stress_ratio_gear2": (dims, ratio), "root_stress_max_gear2": (dims, 300.0 * ratio),
                     # S_F: the root's falls with the root stress, the web's with the hole radius
                     "bending_safety_root_gear2": (dims, 3.0 / ratio), "bending_safety_rim_gear2": (dims, np.full(ratio.shape, 9.0)),
                     "bending_safety_web_gear2": (dims, np.broadcast_to((9.0 - r)[:, :, None, :], ratio.shape).copy()),
                     "failure_mode_gear2": (dims, np.zeros(ratio.shape))},
                    coords=coords)
    sf = np.fmin(ds["bending_safety_root_gear2"], np.fmin(ds["bending_safety_rim_gear2"], ds["bending_safety_web_gear2"]))
    ds["bending_safety_gear2"] = sf
    # the static outputs of a sweep lie over fewer dimensions: the table broadcasts them
    return ds.assign(mass_gear2=ds["mass_gear2"].isel(rim_thickness=0, drop=True))


def test_the_lightest_feasible_body_within_every_limit():
    ds = synthetic_grid()
    table = candidates(ds)
    assert table.sizes["candidate"] == 8 and table["mass_gear2"].dims == ("candidate",)
    lim = Limits(ste_factor=1.36, dte_factor=1.2, stress_ratio=1.2)
    ok = feasible(table, SOLID, lim)
    saving = table["mass_saving_gear2"].values
    expect = ((table["status"] == 1) & (1 + saving / 100 <= 1.36) & (1 + saving / 200 <= 1.2)
              & (table["root_stress_ratio_gear2"] <= 1.2)).values
    np.testing.assert_array_equal(ok.values, expect)
    order = ranked(table, ok)
    assert np.all(np.diff(saving[order]) <= 0)                          # most mass saved first
    best = body_of(table, order[0])
    # the two lightest (6 holes of 7 mm: 37 % failed, 33 % without a stress ratio) are out; next come
    # 6 x 5 mm and 3 x 7 mm holes with the 6 mm web (31 %)
    assert saving[order[0]] == pytest.approx(31.0) and best["gear2.body.web_thickness"] == 6.0
    # the failed point and the unknown stress are never chosen, however light
    failed = int(np.flatnonzero(table["status"].values == 4)[0])
    unknown = int(np.flatnonzero(np.isnan(table["root_stress_ratio_gear2"].values))[0])
    assert failed not in order and unknown not in order
    # a stress limit in MPa removes what the ratio allowed
    assert not feasible(table, SOLID, Limits(1.36, 1.2, 1.2, stress_max=300.0)).values.any()
    assert not feasible(table, SOLID, Limits(1.0, 1.0, 1.2)).values.any()   # nothing as quiet as solid


def test_a_minimum_safety_factor_removes_bodies_and_says_which_location_limits_each():
    """Synthetic S_F: the web's 9 - hole radius (4 with 5 mm holes, 2 with 7 mm), the root's
    3 / stress ratio (2.6-2.9), the rim's 9. The web limits the 7 mm holes (and the body whose
    root is unknown), the root the 5 mm ones; S_F >= 2.5 removes the 7 mm holes."""
    table = candidates(synthetic_grid())
    where = limiting_location(table)
    r, sf_root = table["hole_radius"].values, table["bending_safety_root_gear2"].values
    assert list(where) == ["web" if (x == 7.0 or np.isnan(y)) else "root" for x, y in zip(r, sf_root)]
    loose = feasible(table, SOLID, Limits(1.36, 1.2, 1.2, safety_min=0.0))
    assert (feasible(table, SOLID, Limits(1.36, 1.2, 1.2, safety_min=1.4)) == loose).all()
    strict = feasible(table, SOLID, Limits(1.36, 1.2, 1.2, safety_min=2.5))
    kept = np.flatnonzero(strict.values)
    assert kept.size and set(kept) < set(np.flatnonzero(loose.values))
    assert np.all(r[kept] == 5.0) and np.all(table["bending_safety_gear2"].values[kept] >= 2.5)
    best = ranked(table, strict)[0]
    assert r[best] == 5.0 and saving_of(table, best) <= saving_of(table, ranked(table, loose)[0])
    # a body whose S_F is unknown (no strength computed) never passes a minimum
    table["bending_safety_gear2"].values[kept[0]] = np.nan
    assert not feasible(table, SOLID, Limits(1.36, 1.2, 1.2, safety_min=2.5)).values[kept[0]]
    csv = candidate_rows(table, strict).splitlines()
    col = csv[0].split(",").index("limiting_location")
    assert len(csv) == table.sizes["candidate"] + 1
    assert [line.split(",")[col] for line in csv[1:]] == list(where)


def saving_of(table, i):
    return float(table["mass_saving_gear2"].values[i])


def test_refinement_moves_half_a_step_towards_the_lighter_side_within_the_grid():
    grid = {**COARSE, "gear2.body.hole_radius": [5.0, 7.0], "gear2.body.rim_height": [5.0, 7.0],
            "gear2.body.web_thickness": [6.0, 10.0, 14.0]}
    seed = {"gear2.body.holes": 6, "gear2.body.hole_radius": 5.0, "gear2.body.rim_height": 7.0,
            "gear2.body.web_thickness": 10.0}
    pts = refine_points([seed], grid)
    assert len(pts) == 7 and seed not in pts                            # 2 x 2 x 2 less the seed
    assert {p["gear2.body.hole_radius"] for p in pts} == {5.0, 6.0}       # larger holes are lighter
    assert {p["gear2.body.rim_height"] for p in pts} == {6.0, 7.0}        # thinner rim is lighter
    assert {p["gear2.body.web_thickness"] for p in pts} == {8.0, 10.0}    # thinner web, the nearer value
    assert all(p["gear2.body.holes"] == 6 for p in pts)
    # at the lighter end of the grid a field stays (never past the grid's range)
    edge = {**seed, "gear2.body.hole_radius": 7.0, "gear2.body.rim_height": 5.0, "gear2.body.web_thickness": 6.0}
    assert refine_points([edge], grid) == []
    # two seeds sharing refined bodies give each once
    other = {**seed, "gear2.body.web_thickness": 14.0}
    both = refine_points([seed, other], grid)
    keys = [tuple(sorted(p.items())) for p in both]
    assert len(keys) == len(set(keys)) and seed not in both


def test_the_answer_gives_saving_te_and_stress_against_the_solid_gear():
    row = {"n_holes": 6, "hole_radius": 7.0, "rim_thickness": 5.0, "web_thickness": 6.0, "mass_saving_gear2": 25.0,
           "mass_gear2": 1.5, "inertia_gear2": 700.0, "ste_p2p": 1.1, "dte_rms": 2.5,
           "root_stress_max_gear2": 330.0, "root_stress_ratio_gear2": 1.1, "bending_safety_gear2": 2.5,
           "bending_safety_root_gear2": 3.0, "bending_safety_rim_gear2": 9.0, "bending_safety_web_gear2": 2.5,
           "failure_mode_gear2": 2.0}
    text = answer(row, SOLID, 100.0)
    assert text.startswith("6 holes of 7 mm radius, a 5 mm rim and a 6 mm web save 25.0 % mass")
    assert "+10.0 % STE p2p" in text and "+25.0 % DTE RMS at 100 rad/s" in text
    assert "root stress 330.0 MPa (x 1.10 of solid)" in text
    assert "bending safety S_F 2.50, limited by the web, failure mode web" in text


@pytest.mark.parametrize("argv, field", [
    (["--ste-factor", "0"], "--ste-factor"), (["--speed", "-5"], "--speed"), (["--refine", "-1"], "--refine"),
    (["--workers", "-2"], "--workers"), (["--safety-min", "-1"], "--safety-min"), (["--grid", "gear2.body.teeth=20,30"], "gear2.body.teeth"),
    (["--grid", "gear2.body.holes=2.5"], "gear2.body.holes"),
    (["--duration", "0.02", "--set", "dynamic.ramp_time=0.5"], "dynamic.duration"),
])
def test_bad_options_are_one_line_errors_before_any_work(argv, field, capsys, tmp_path, monkeypatch):
    import study
    monkeypatch.setattr(study, "run_sweep", lambda *a, **k: pytest.fail("work started"))
    workers = [] if "--workers" in argv else ["--workers", "0"]
    assert main([*argv, *workers, "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and field in err and "\n" not in err and "Traceback" not in err


def test_fields_are_the_driven_gear_body():
    assert set(FIELDS) == set(COARSE) and all(p.startswith("gear2.body.") for p in FIELDS)
    assert math.isinf(Limits().stress_max)


def test_small_pair_end_to_end_gives_the_lightest_body_its_figure_and_archives(tmp_path, capsys, private_fe_cache):
    """24-tooth pair, coarse FE mesh, two hole radii and one refined between them: the lightest
    body is the larger holes, its answer is measured against the solid gear's run."""

    from study.scene import load_scene
    scene = load_scene("small_pair").replace(**{"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4,
                                                "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5,
                                                "quasi_static.rotation": 30.0, "dynamic.ramp_time": 0.002})
    (tmp_path / "scene.toml").write_text(scene.to_toml())
    out = tmp_path / "out"
    rc = main([str(tmp_path / "scene.toml"), "--grid", "gear2.body.holes=4", "--grid", "gear2.body.hole_radius=2.0,3.0",
               "--grid", "gear2.body.rim_height=4.0", "--grid", "gear2.body.web_thickness=8.0", "--refine", "2",
               "--ste-factor", "3", "--dte-factor", "3", "--stress-ratio", "3", "--angle-step", "0.5",
               "--set", "fe.mesh_size=2.0", "--duration", "0.01", "--workers", "0", "--no-progress", "-o", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "coarse grid: 2 of 2 bodies feasible" in text and "refinement: 1 bodies around 2" in text
    said = (out / "lightest.txt").read_text()
    assert said.startswith("4 holes of 3 mm radius, a 4 mm rim and a 8 mm web save") and said.strip() in text
    with xr.open_dataset(out / "refine.nc") as fine, xr.open_dataset(out / "solid.nc") as solid:
        assert fine["hole_radius"].values.tolist() == [2.5]             # half-way to the lighter neighbour
        assert float(solid["root_stress_ratio_gear2"].squeeze()) == 1.0 and float(solid["mass_saving_gear2"]) == 0.0
    with xr.open_dataset(out / "coarse.nc") as coarse, xr.open_dataset(out / "solid.nc") as solid:
        # the solid reference runs by the model the lightened bodies run
        assert solid.attrs["coupling_model"] == coarse.attrs["coupling_model"] == "compliance"
        best = coarse.sel(hole_radius=3.0).squeeze()
        assert f"save {float(best['mass_saving_gear2']):.1f} % mass" in said
        assert f"root stress {float(best['root_stress_max_gear2']):.1f} MPa" in said
    assert (out / "tradeoff.png").stat().st_size > 10_000
    rows = (out / "candidates.csv").read_text().splitlines()
    where = rows[0].split(",").index("limiting_location")
    assert len(rows) == 1 + 3 and all(r.split(",")[where] in ("root", "rim", "web") for r in rows[1:])
    assert "S_F limited by: " in text and "limited by the " in said


def test_other_shapes_are_sized_by_their_own_field_and_refined_towards_less_mass():
    """A slot is sized by its width (wider is lighter), a window by its spokes (narrower is
    lighter); a candidate's body names its opening, and the answer says the shape."""
    from workflows.lightest_gear import SHAPE_COARSE, fields_of
    assert fields_of("round") == FIELDS
    assert "gear2.body.spoke_width" in fields_of("window") and "gear2.body.hole_radius" not in fields_of("window")
    grid = {**COARSE, **SHAPE_COARSE, "gear2.body.spoke_width": [8.0, 12.0, 16.0]}
    seed = {"gear2.body.holes": 6, "gear2.body.spoke_width": 12.0, "gear2.body.rim_height": 7.0,
            "gear2.body.web_thickness": 10.0, "gear2.body.opening": "window"}
    pts = refine_points([seed], grid)
    assert {p["gear2.body.spoke_width"] for p in pts} == {10.0, 12.0}        # narrower spokes are lighter
    assert all(p["gear2.body.opening"] == "window" and "gear2.body.hole_radius" not in p for p in pts)
    ds = synthetic_grid().rename(hole_radius="slot_width")
    table = candidates(ds, {"gear2.body.opening": "slot"})
    assert set(table["opening"].values) == {"slot"} and np.isnan(table["hole_radius"].values).all()
    body = body_of(table, 0)
    assert body["gear2.body.opening"] == "slot" and body["gear2.body.slot_width"] == 5.0
    row = {"n_holes": 6, "opening": "window", "spoke_width": 12.0, "rim_thickness": 5.0, "web_thickness": 6.0,
           "mass_saving_gear2": 25.0, "mass_gear2": 1.5, "inertia_gear2": 700.0, "ste_p2p": 1.1, "dte_rms": 2.5,
           "root_stress_max_gear2": 330.0, "root_stress_ratio_gear2": 1.1, "bending_safety_gear2": 2.0,
           "bending_safety_root_gear2": 2.0, "bending_safety_rim_gear2": 9.0, "bending_safety_web_gear2": 3.0,
           "failure_mode_gear2": 0.0}
    said = answer(row, SOLID, 100.0)
    assert said.startswith("6 windows between spokes of 12 mm, a 5 mm rim") and "limited by the root" in said


def test_an_unknown_shape_is_a_one_line_error(capsys, tmp_path):
    assert main(["--shapes", "round,star", "--workers", "0", "-o", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --shapes") and "\n" not in err


def test_small_pair_searches_round_holes_and_windows(tmp_path, capsys, private_fe_cache):
    """Both shapes run their coarse grid (its own archive each) and compete for the answer."""
    from study.scene import load_scene
    scene = load_scene("small_pair").replace(**{"gear2.body.web_thickness": 8.0, "gear2.body.holes": 4,
                                                "gear2.body.hole_radius": 3.0, "gear2.body.hole_circle_radius": 19.5,
                                                "gear2.body.window_height": 8.0,
                                                "quasi_static.rotation": 30.0, "dynamic.ramp_time": 0.002})
    (tmp_path / "scene.toml").write_text(scene.to_toml())
    out = tmp_path / "out"
    rc = main([str(tmp_path / "scene.toml"), "--shapes", "round,window", "--grid", "gear2.body.holes=4",
               "--grid", "gear2.body.hole_radius=3.0", "--grid", "gear2.body.spoke_width=6.0",
               "--grid", "gear2.body.rim_height=4.0", "--grid", "gear2.body.web_thickness=8.0", "--refine", "0",
               "--ste-factor", "5", "--dte-factor", "5", "--stress-ratio", "5", "--angle-step", "0.5",
               "--set", "fe.mesh_size=2.0", "--duration", "0.01", "--workers", "0", "--no-progress", "-o", str(out)])
    text = capsys.readouterr().out
    assert rc == 0, text
    assert "coarse grid: 2 of 2 bodies feasible" in text
    with xr.open_dataset(out / "coarse.nc") as r, xr.open_dataset(out / "coarse_window.nc") as w:
        m_round, m_window = float(r["mass_saving_gear2"].squeeze()), float(w["mass_saving_gear2"].squeeze())
        assert w.attrs["base_scene"].count('opening = "window"') == 1
    # four windows between 6 mm spokes take far more than four 3 mm holes: the lightest is the windows
    assert m_window > m_round
    assert (out / "lightest.txt").read_text().startswith("4 windows between spokes of 6 mm")
