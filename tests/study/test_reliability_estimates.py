"""What a careless user or script meets: the estimates of a run or a sweep and their levers,
ranges, integers and seeds, each refused before any work with the field named."""
from pathlib import Path

import numpy as np
import pytest
from reliability_cases import run_cli, sample_study, write_study

from study.inputs.cache import FE_CACHE

# ---------------------------------------------------------------- estimates and their levers

def test_static_angles_that_do_not_fit_in_memory_are_refused_before_they_are_built(tmp_path, capsys):
    code, _, err = run_cli(capsys, "reference", "--step", "1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "--step: the static analysis needs about" in err and "TiB" in err
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.rotation=1e9", "--max-time", "1e30",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "quasi_static.angle_step: the static analysis needs" in err


def test_a_refusal_names_the_lever_of_its_largest_part(tmp_path, capsys, monkeypatch):
    # 6e6 angles: some 11 GiB (fits in the 64 GiB said here), minutes of statics and hours of
    # mesh linearisations: the time, not the memory, is what refuses it
    import study.scene_model
    monkeypatch.setattr(study.scene_model, "available_memory", lambda: 64 * 2.0 ** 30)
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.angle_step=2e-5", "--max-time", "100",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "make the mesh stiffness cheaper: a larger quasi_static.angle_step" in err
    assert "fe.mesh_size" not in err
    # (the paper's model: the friction's regularisation bounds its step as it does the default
    # model's; its dampers' loaded equilibria take a static sweep the friction tests compile)
    code, _, err = run_cli(capsys, "run", "--no-static", "--set", "gear2.body.holes=0", "--set", "coupling.model=paper",
                           "--set", "contact.friction=0.05", "--set", "contact.friction_velocity=1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "make the dynamics cheaper" in err and "contact.friction_velocity" in err
    assert "fe.mesh_size" not in err


# ---------------------------------------------------------------- a sweep's estimate

def test_a_grid_too_large_to_list_is_refused_before_it_is_built(tmp_path, capsys, monkeypatch):
    from study.sweep.grid import Study
    built = []
    monkeypatch.setattr(Study, "points", lambda self: built.append(1) or [])
    st = write_study(tmp_path, '"dynamic.speed" = {start = 10.0, stop = 400.0, num = 1000}\n'
                               '"dynamic.torque" = {start = 10.0, stop = 60.0, num = 1000}\n'
                               '"gear2.body.holes" = [0, 2, 3, 4, 5, 6, 7, 8, 9, 10]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "grid: the study has 1e+07 points (1000 x 1000 x 10)" in err and not built
    st = write_study(tmp_path, '"dynamic.speed" = {start = 10.0, stop = 400.0, num = 10000000}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "dynamic.speed: range num = 10000000 values on one axis" in err


def test_a_sweep_gets_the_estimate_and_max_time_of_its_tasks(tmp_path, capsys):
    """Four dynamic runs of 1 s each at the explicit step: tens of seconds of CPU, refused under
    --max-time 5 with the parts and the lever, before any task runs."""
    st = write_study(tmp_path, '"dynamic.speed" = [50.0, 100.0]\n"dynamic.duration" = [1.0, 2.0]')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", 5)
    assert code == 2 and "--max-time: the run is estimated at" in err and "dynamics (4 runs" in err
    assert "a shorter dynamic.duration" in err and "fewer grid points" in err
    assert not (tmp_path / ".s.nc.parts").exists()


# ---------------------------------------------------------------- ranges, integers and seeds

@pytest.mark.parametrize("field, value", [("gear1.errors.eccentricity_phase", 1e19),
                                          ("gear2.errors.eccentricity_phase", -400.0),
                                          ("gear1.modification.tip_start_roll", 1e5),
                                          ("gear2.modification.profile_roll", [10.0, 1e6])])
def test_every_angle_valued_field_has_a_range(field, value):
    from study.scene import SceneError
    from tests.helpers import small_scene
    with pytest.raises(SceneError) as e:
        small_scene(**{field: value})
    assert e.value.field == field and "must be " in e.value.reason and "360.0 deg" in e.value.reason


def test_integers_beyond_64_bits_are_refused_and_those_within_kept_exactly():
    from study.scene import SceneError
    from tests.helpers import small_scene
    assert small_scene(**{"gear1.errors.seed": 2 ** 53 + 1}).gear1.errors.seed == 2 ** 53 + 1
    with pytest.raises(SceneError, match="must fit in 64 bits"):
        small_scene(**{"gear1.errors.seed": 2 ** 64})


def test_integer_draws_and_seeds_are_checked_before_any_build(tmp_path, capsys):
    st = sample_study(tmp_path, 'size = 4\n"gear1.errors.grade" = {integers = [5, 6]}\n'
                                '"gear1.errors.seed" = {integers = [0, 1e20]}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "gear1.errors.seed: [sample] integers upper end" in err and "64 bits" in err
    st = sample_study(tmp_path, f'size = 4\nseed = {2 ** 64}\n"gear2.body.hole_radius" = {{uniform = [1.0, 1.5]}}')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "sample.seed: must fit in 64 bits" in err and not (tmp_path / ".s.nc.parts").exists()


def test_a_sample_is_counted_and_bounded_like_a_grid(tmp_path, capsys, monkeypatch):
    from study.sweep.grid import Study
    built = []
    monkeypatch.setattr(Study, "points", lambda self: built.append(1) or [])
    for size in ("1000000", "1000000000000"):
        st = sample_study(tmp_path, f'size = {size}\n"gear2.body.hole_radius" = {{uniform = [1.0, 1.5]}}')
        code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--max-time", 3600)
        assert code == 2 and f"sample.size: the study has {float(size):.4g} points" in err and not built
    monkeypatch.undo()
    st = sample_study(tmp_path, 'size = 3\n"gear2.body.hole_radius" = {uniform = [1.0, 1.5]}')
    code, out, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc", "--workers", 0, "--no-progress")
    assert code == 0 and "3 points (3" in out, out + err


def test_a_hole_order_the_record_does_not_resolve_is_not_fitted():
    """4 holes (order 4 of the driven gear, 90 deg) on a 20/20 pair: a known amplitude over a
    whole hole period is found; over 18 deg (19 or 181 angles) it is NaN with the reason, not
    a least-squares fit of 21 columns reporting 1e7 times the STE."""
    from study.verify.model_validation import order_amplitude, order_unresolved
    z, holes = 20, 4

    def ste(x):
        return 1.0 + 0.3 * np.cos(holes * x + 0.4) + 0.8 * np.cos(z * x) + 0.1 * np.sin(2 * z * x)
    whole = np.radians(np.arange(0.0, 90.0, 0.5))
    assert order_amplitude(whole, ste(whole), holes, z) == pytest.approx(0.3, rel=1e-9)
    assert order_unresolved(whole, holes) is None
    for step in (1.0, 0.1):
        short = np.radians(np.arange(0.0, 18.0 + 1e-9, step))
        assert np.isnan(order_amplitude(short, ste(short), holes, z))
    assert "fewer than the 21 columns" in order_unresolved(np.radians(np.arange(0.0, 18.5, 1.0)), holes)
    assert "less than one period of order 4 (90 deg)" in order_unresolved(np.radians(np.arange(0.0, 18.05, 0.1)), holes)


def test_a_sweep_point_with_a_tiny_time_step_is_estimated_and_refused_like_a_run(tmp_path, capsys):
    """One point of many at dynamic.time_step = 1e-13 (ten million steps per microsecond of
    the run): the sampled steps of the others would miss it."""
    points = "".join(f'[[points]]\n"dynamic.speed" = {50.0 + i}\n' + ('"dynamic.time_step" = 1e-13\n' if i == 2 else "")
                     for i in range(9))
    path = tmp_path / "p.toml"
    path.write_text(Path("study/scenes/example_study.toml").read_text().split("[grid]")[0] + points
                    + '[outputs]\nscalars = ["dte_rms"]\n')
    code, _, err = run_cli(capsys, "sweep", path, "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and "--max-time: the run is estimated at" in err and "dt down to 1e-13 s" in err
    assert "dynamic.time_step (1e-13 s given)" in err and not (tmp_path / ".s.nc.parts").exists()


def test_a_load_too_small_to_resolve_is_refused_before_the_fe_naming_the_torque(tmp_path, capsys, private_fe_cache):
    code, _, err = run_cli(capsys, "run", "small_pair", "--set", "dynamic.torque=1e-6", "-o", tmp_path / "r.nc")
    assert code == 2 and "dynamic.torque: a load too small to resolve: 1e-06 N*m" in err
    assert "damping_ratio" not in err and not FE_CACHE.folder.exists()      # no FE body made
    from study.plausibility import MIN_APPROACH_MM, approach_estimate_mm, smallest_torque
    from tests.helpers import small_scene
    t = smallest_torque(small_scene())
    assert approach_estimate_mm(small_scene(), t) == pytest.approx(MIN_APPROACH_MM, rel=1e-6)
    small_scene(**{"dynamic.torque": 1.01 * t, "dynamic.torque_change_time": 0.1, "dynamic.torque_after": 0.0})
