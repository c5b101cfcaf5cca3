"""The model-only analyses kept per process (`solver.mbs.memo`): the same numbers as solved
afresh, a model changed in place solved again, and a caller's copy that cannot spoil the kept one."""
import dataclasses

import numpy as np
import pytest

from solver.mbs import memo
from solver.mbs.kernels import layout as L
from solver.mbs.modes import modal_analysis
from solver.mbs.stability import stability_limit, stable_time_step
from study.scene import load_scene
from study.scene_model import build_scene_model


@pytest.fixture(scope="module")
def model():
    return build_scene_model(load_scene("small_pair").replace(**{"coupling.model": "paper"}))


def test_a_kept_step_bound_and_modes_are_those_solved_afresh(model):
    memo.forget()
    first, modes = stability_limit(model, 40.0, implicit_dampers=True), modal_analysis(model, 40.0)
    assert stability_limit(model, 40.0, implicit_dampers=True) == first
    memo.forget()
    assert stability_limit(model, 40.0, implicit_dampers=True) == first
    fresh = modal_analysis(model, 40.0)
    np.testing.assert_array_equal(modes.frequency, fresh.frequency)
    np.testing.assert_array_equal(modes.damping, fresh.damping)
    assert modes.kind == fresh.kind
    # another load, another bound (the contact stiffens under load)
    assert stability_limit(model, 400.0, implicit_dampers=True)[1] > first[1]


def test_a_model_changed_in_place_is_solved_again(model):
    m = build_scene_model(load_scene("small_pair").replace(**{"coupling.model": "paper"}))
    dt, w = stable_time_step(m, 40.0)
    m.law_par[L.K_CON] *= 4.0            # a stiffer contact: a higher top frequency, a shorter step
    dt4, w4 = stable_time_step(m, 40.0)
    assert w4 > 1.2 * w and dt4 < dt
    assert stable_time_step(dataclasses.replace(m), 40.0) == (dt4, w4)    # another object, the same arrays


def test_the_caller_gets_a_copy(model):
    md = modal_analysis(model, 40.0)
    f0 = md.frequency.copy()
    md.frequency[:] = -1.0
    np.testing.assert_array_equal(modal_analysis(model, 40.0).frequency, f0)
