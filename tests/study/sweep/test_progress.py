"""A study's progress bar: FE bodies and points in one bar, an ETA from the start (not '?'
until the first point ends), paced by the analyses after each worker's first."""
import re

import pytest
from sweep_cases import BASE

from study.sweep.engine import run_sweep
from study.sweep.grid import loads_study
from study.sweep.progress import StudyProgress, eta_text


def test_the_eta_starts_from_the_estimate_and_a_slow_first_analysis_does_not_set_the_pace(monkeypatch):
    monkeypatch.setattr("study.estimate.load_factor", lambda: 1.0)
    fe = {"body-a": 4.0, "body-b": 4.0}
    tasks = {f"t{i}": 1.0 for i in range(10)}
    bar = StudyProgress("s", 10, fe, tasks, parallel=2, startup_s=3.0, show=False)
    assert bar.eta_s() == pytest.approx((8.0 + 10.0) / 2 + 3.0)          # before anything ends
    bar.fe_done("body-a")
    bar.fe_done("body-b")
    bar.task_done("t0", 30.0, 1)              # each worker's first: loads the kernels (30 x its estimate)
    bar.task_done("t1", 25.0, 1)
    assert bar.eta_s() == pytest.approx(8.0 / 2)     # still the estimate's pace: 8 analyses of 1 s on 2 workers
    for i in range(2, 6):
        bar.task_done(f"t{i}", 2.0, 1)         # the machine runs at half the estimated speed
    assert bar.eta_s() == pytest.approx(4 * 2.0 / 2)
    assert eta_text(75) == "1 min 15 s" and eta_text(3700) == "1 h 01 min" and eta_text(4.4) == "4 s"


def test_in_process_the_fe_of_an_analysis_is_its_cost_and_done_with_it(monkeypatch):
    monkeypatch.setattr("study.estimate.load_factor", lambda: 1.0)
    bar = StudyProgress("s", 2, {"body-a": 5.0}, {"t0": 1.0, "t1": 1.0}, parallel=1, show=False,
                        fe_in_tasks={"t0": ["body-a"]})
    assert bar.eta_s() == pytest.approx(7.0)
    bar.task_done("t0", 6.0, 1)
    assert bar.fe_left == {} and bar.eta_s() == pytest.approx(1.0)


def test_a_sweep_shows_its_eta_before_the_first_point_ends(tmp_path, capsys):
    st = loads_study('title = "bar"\n' + BASE.replace("dynamic = {duration = 0.01, ramp_time = 0.002}",
                                                       "dynamic = {enabled = false}")
                     + '[grid]\n"quasi_static.torque" = [20.0, 40.0, 60.0]\n[outputs]\nscalars = ["ste_p2p"]\n')
    run_sweep(st, tmp_path / "bar.nc", workers=0, progress=True)
    lines = [line for line in re.split(r"[\r\n]", capsys.readouterr().err) if "points" in line]
    first = next(line for line in lines if "ETA" in line)
    assert "0/3 points" in first and "analyses 0/3" in first, lines
    assert re.search(r"ETA \d+ s", first)
    assert "3/3 points" in lines[-1] and "analyses 3/3" in lines[-1] and "ETA 0 s" in lines[-1]
