"""The Python API (`import study`): a short script from scene to rendered sweep, and an import
that loads nothing heavy."""
import math
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import xarray as xr

ROOT = Path(__file__).resolve().parents[2]

# The script of the README's "Python API" section, run as it stands there (from the repository root).
SCRIPT = '''
import study

scene = study.load_study("study/scenes/example_study.toml").base_scene()   # 20-tooth pair, uniform springs
scene = scene.replace(**{"gear2.body.holes": 4, "dynamic.duration": 0.008})
ds = study.run_scene(scene)                                                 # STE, DTE and spectra
study.write(ds, "results/api/run.nc")
print(f"DTE RMS {study.summarize(ds)['dte_rms']:.3f} um")
st = study.make_study(scene, grid={"gear2.body.holes": [0, 4], "dynamic.speed": [50.0, 100.0]},
                      outputs={"scalars": ["ste_p2p", "dte_rms"], "curves": ["dte"]}, title="holes and speed")
res = study.run_sweep(st, "results/api/holes_speed.nc", workers=0, progress=False)
print(res.dataset["dte_rms"].to_pandas())
study.render("results/api/holes_speed.nc", "results/api")
'''


def test_the_api_script_runs_a_scene_and_a_sweep_into_archives(tmp_path, monkeypatch, capsys):
    (tmp_path / "study" / "scenes").mkdir(parents=True)
    shutil.copy(ROOT / "study" / "scenes" / "example_study.toml", tmp_path / "study" / "scenes")
    monkeypatch.chdir(tmp_path)
    exec(compile(SCRIPT, "api_script", "exec"), {})
    assert "DTE RMS" in capsys.readouterr().out
    out = tmp_path / "results" / "api"
    with xr.open_dataset(out / "run.nc", engine="netcdf4") as run, xr.open_dataset(out / "holes_speed.nc") as sw:
        run, sw = run.load(), sw.load()
    assert sw.attrs["title"] == "holes and speed" and (sw["status"] == 1).all()
    assert sw["dte_rms"].dims == ("n_holes", "speed") and sw["dte"].dims == ("n_holes", "speed", "time")
    # the sweep's point with the run's scene (4 holes, 100 rad/s) is that run
    pt = sw.sel(n_holes=4, speed=100.0)
    np.testing.assert_allclose(pt["dte"].values, run["dte"].values, rtol=1e-12)
    after = run["dte"].where(run["time"] >= run.attrs["spectrum_start_s"], drop=True).values
    assert math.isclose(float(pt["dte_rms"]), float(np.sqrt(np.mean((after - after.mean()) ** 2))), rel_tol=1e-12)
    # STE does not depend on the speed; the holes change the driven gear's inertia only (uniform springs)
    assert sw["ste_p2p"].dims == ("n_holes",) and sw["dte_rms"].dims == ("n_holes", "speed")   # STE: no speed
    # an output that takes one value over the study (the STE here) gets no figure
    assert float(np.ptp(sw["ste_p2p"].values)) == 0.0
    pngs = {p.name for p in out.glob("*.png")}
    assert "sweep_dte_rms.png" in pngs and "sweep_ste_p2p.png" not in pngs


def test_import_study_loads_nothing_heavy():
    code = ("import sys, study, study.cli; study.cli.build_parser(); "
            "heavy = {m.split('.')[0] for m in sys.modules} & {'gmsh', 'vtk', 'vtkmodules', 'pyvista', 'dask', "
            "'distributed', 'numba', 'matplotlib', 'skfem', 'xarray', 'scipy'}; print(sorted(heavy))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
