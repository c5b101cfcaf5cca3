"""Scene fields of the pitch errors and eccentricity: round trip, the ISO class's random set,
bad input, the quasi-static range over the errors' period, and a study sweeping them."""
import math

import numpy as np
import pytest

from solver.mbs.kernels import layout as L
from solver.pitch_errors import iso1328_pitch_tolerances
from study.estimate import error_period_note
from study.scene import SceneError, default_scene, error_period, loads_scene, static_rotation
from study.scene_model import geometry_model, static_angles

E = "gear1.errors."
E2 = "gear2.errors."


def test_scene_round_trip_keeps_the_errors():
    pitch = [1.5, -2.0, 0.5] + [0.0] * 64
    s = default_scene().replace(**{E + "pitch": pitch, E + "eccentricity": 5.0, E + "eccentricity_phase": 30.0,
                                   E2 + "grade": 6, E2 + "seed": 1})
    back = loads_scene(s.to_toml())
    assert back == s
    assert back.gear1.errors.pitch == tuple(pitch) and back.gear2.errors.grade == 6
    assert back.errors_spec(2) == s.errors_spec(2)


def test_perfect_gears_keep_the_plain_model_arrays():
    """No errors: pair_par has its plain length (the kernels skip the errors), and the range is
    quasi_static.rotation; with errors the block holds every tooth's turn and each eccentricity."""
    s0 = default_scene()
    assert geometry_model(s0).pair_par.size == L.N_PAIR_PAR and not s0.has_errors
    assert static_rotation(s0) == s0.quasi_static.rotation
    s = s0.replace(**{E + "pitch": [0.0, 2.0, -2.0] + [0.0] * 64, E2 + "eccentricity": 3.0,
                      E2 + "eccentricity_phase": 90.0})
    m = geometry_model(s)
    r1 = s.geometry(1).pitch_radius
    assert m.pair_par.size == L.E_EPS + 134
    np.testing.assert_allclose(m.pair_par[L.E_EPS:L.E_EPS + 3], [0.0, 2e-6 / r1, 0.0], rtol=1e-12, atol=0)
    assert not m.pair_par[L.E_EPS + 67:].any()
    assert m.pair_par[L.E_ECC:L.E_ECC + 4].tolist() == [0.0, 0.0, 3e-6, pytest.approx(math.pi / 2)]


def test_grade_and_seed_give_a_reproducible_set_within_the_class():
    """ISO 1328-1 class 6 on the paper's gear (d = 100.5 mm, m = 1.5 mm): f_pT = 8.1 um,
    F_pT = 26.5 um by the standard's formulas; the set is closed, within both, uses a real
    share of F_pT, repeats with its seed and changes with another."""
    f_pt, f_p = iso1328_pitch_tolerances(100.5e-3, 1.5e-3, 6)
    assert f_pt == pytest.approx((0.1005 + 0.6 + 5) * math.sqrt(2) * 1e-6)
    assert f_p == pytest.approx((0.201 + 0.55 * math.sqrt(100.5) + 1.05 + 12) * math.sqrt(2) * 1e-6)
    for grade in (4, 6, 9):
        err = default_scene().replace(**{E + "grade": grade, E + "seed": 1}).errors_spec(1)
        f = np.asarray(err.pitch)
        tol_pt, tol_p = iso1328_pitch_tolerances(100.5e-3, 1.5e-3, grade)
        assert f.size == 67 and abs(f.sum()) < 1e-12
        assert np.abs(f).max() <= tol_pt and np.ptp(err.cumulative(67)) <= tol_p
        assert np.ptp(err.cumulative(67)) > 0.5 * tol_p
    a = default_scene().replace(**{E + "grade": 6, E + "seed": 1}).errors_spec(1)
    assert default_scene().replace(**{E + "grade": 6, E + "seed": 1}).errors_spec(1) == a
    assert default_scene().replace(**{E + "grade": 6, E + "seed": 2}).errors_spec(1) != a


@pytest.mark.parametrize("over, field, words", [
    ({E + "pitch": [1.0, -1.0]}, E + "pitch", "2 values for 67 teeth"),
    ({E + "pitch": [1.0] + [0.0] * 66}, E + "pitch", "sum to zero"),
    ({E + "pitch": [1.0, -1.0] + [0.0] * 65, E + "grade": 6}, E + "grade", "not both"),
    ({E + "grade": 12}, E + "grade", "<= 11"),
    ({E + "eccentricity": -1.0}, E + "eccentricity", ">= 0"),
    ({E + "eccentricity": 200.0}, "gear1.errors", "0.1 x module"),
    ({E + "pitch": 3.0}, E + "pitch", "a list"),
])
def test_bad_errors_name_the_field(over, field, words):
    with pytest.raises(SceneError) as e:
        default_scene().replace(**over)
    assert e.value.field == field and words in e.value.reason, (e.value.field, e.value.reason)


def test_quasi_static_range_covers_the_errors_period():
    """Gear 1's errors: one driver revolution; gear 2's: one driven revolution (Z2/Z1 driver
    revolutions); both: the hunting period lcm(Z1, Z2)/Z1; the angle step is kept, a longer
    quasi_static.rotation gives whole periods, and the user is told when the range grows much."""
    s = default_scene().replace(**{"gear2.teeth": 71, "quasi_static.angle_step": 0.5})
    one = s.replace(**{E + "eccentricity": 2.0})
    assert error_period(one) == 360.0 and static_rotation(one) == 360.0
    assert np.degrees(np.diff(static_angles(one)[:2]))[0] == pytest.approx(0.5)
    two = s.replace(**{E2 + "eccentricity": 2.0})
    assert error_period(two) == pytest.approx(360.0 * 71 / 67)
    both = s.replace(**{E + "eccentricity": 2.0, E2 + "grade": 5})
    assert error_period(both) == pytest.approx(360.0 * 71)      # 67 and 71 share no factor
    assert static_rotation(one.replace(**{"quasi_static.rotation": 400.0})) == 720.0
    note = error_period_note(one)
    assert note and "360 deg" in note and "721 angles" in note
    assert error_period_note(s) is None


def test_a_study_sweeps_the_errors_like_any_field():
    from study.sweep.grid import make_study
    st = make_study(default_scene(), {"gear1.errors.eccentricity": [0.0, 5.0], "gear1.errors.grade": [0, 6]},
                    outputs={"scalars": ["ste_p2p"]})
    assert st.shape == (2, 2)
    scenes = [p.scene for p in st.points()]
    assert sorted((s.gear1.errors.eccentricity, s.gear1.errors.grade) for s in scenes) == \
        [(0.0, 0), (0.0, 6), (5.0, 0), (5.0, 6)]
    assert sum(s.has_errors for s in scenes) == 3
    # the errors move no mass and no FE body: those analyses are shared across them
    from study.sweep.outputs import reads
    for f in ("gear1.errors.eccentricity", "gear2.errors.grade"):
        assert not reads("geometry", f) and not reads("fe", f)
        assert reads("static", f) and reads("modes", f) and reads("dynamic", f)
    assert reads("fe", "gear1.teeth") and reads("geometry", "gear1.modification.tip_relief")
