"""The Python API (`import study`): a short script from scene to rendered sweep, and an import
that loads nothing heavy."""
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import xarray as xr

import study

ROOT = Path(__file__).resolve().parents[2]

# The script of the README's "A first study" section, run as it stands there (from any directory).
SCRIPT = '''
import study

scene = study.load_study("example_study").base_scene()         # an embedded study's small 20-tooth pair, by name
scene = scene.replace(**{"gear2.spring.stiffness": "fe-ratio",    # tooth springs from the FE body of the gear
                         "gear2.body.holes": 4, "gear2.body.hole_radius": 1.8,
                         "quasi_static.rotation": 90.0,          # STE over one period of the four holes [deg]
                         "dynamic.duration": 0.03})
ds = study.run_scene(scene)                                      # STE, DTE and spectra
study.write(ds, "results/api/run.nc")
print(f"DTE RMS {study.summarize(ds)['dte_rms']:.3f} um")
st = study.make_study(scene, grid={"gear2.body.holes": [0, 4], "dynamic.speed": [50.0, 100.0]},
                      outputs=["ste_p2p", "dte_rms", "dte"], title="holes and speed")
res = study.run_sweep(st, "results/api/holes_speed.nc", workers=0, progress=False)
print(res.dataset["ste_p2p"].to_pandas())
study.render("results/api/holes_speed.nc", "results/api")
'''


def readme_script() -> str:
    """The Python block of the README's first study."""
    text = (ROOT / "README.md").read_text()
    start = text.index("```python\n", text.index("## A first study")) + len("```python\n")
    return text[start:text.index("```", start)]


def test_the_readme_script_is_the_one_tested():
    assert readme_script().strip() == SCRIPT.strip()


def test_the_api_script_runs_a_scene_and_a_sweep_into_archives_from_any_directory(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)             # no scene files here: the study is found by name
    exec(compile(SCRIPT, "api_script", "exec"), {})
    assert "DTE RMS" in capsys.readouterr().out
    out = tmp_path / "results" / "api"
    with xr.open_dataset(out / "run.nc", engine="netcdf4") as run, xr.open_dataset(out / "holes_speed.nc") as sw:
        run, sw = run.load(), sw.load()
    assert sw.attrs["title"] == "holes and speed" and (sw["status"] == 1).all()
    assert sw["dte_rms"].dims == ("n_holes", "speed") and sw["dte"].dims == ("n_holes", "speed", "time")
    # the outputs given as a list: only those (no scalar the list did not name)
    assert {"ste_p2p", "dte_rms", "dte"} <= set(sw.data_vars) and "tooth_force_max" not in sw
    # the sweep's point with the run's scene (4 holes, 100 rad/s) is that run
    pt = sw.sel(n_holes=4, speed=100.0)
    np.testing.assert_allclose(pt["dte"].values, run["dte"].values, rtol=1e-12)
    after = run["dte"].where(run["time"] >= run.attrs["spectrum_start_s"], drop=True).values
    assert math.isclose(float(pt["dte_rms"]), float(np.sqrt(np.mean((after - after.mean()) ** 2))), rel_tol=1e-12)
    # the holes soften the teeth near them: the STE ripple over a mesh period grows by a tenth
    assert sw["ste_p2p"].dims == ("n_holes",)
    assert float(sw["ste_p2p"].sel(n_holes=4)) > 1.08 * float(sw["ste_p2p"].sel(n_holes=0))
    assert (sw["dte_rms"].sel(n_holes=4) > 1.005 * sw["dte_rms"].sel(n_holes=0)).all()    # at both speeds (+1.0, +2.3 %)
    assert {"sweep_dte_rms.png", "sweep_ste_p2p.png"} <= {p.name for p in out.glob("*.png")}
    # summarize on the sweep: its scalars over the swept dimensions
    s = study.summarize(sw)
    assert s["dte_rms"].dims == ("n_holes", "speed") and float(s["ste_p2p"].sel(n_holes=4, speed=100.0)) == float(pt["ste_p2p"])


def test_import_study_loads_nothing_heavy():
    code = ("import sys, study, study.cli; study.cli.build_parser(); "
            "heavy = {m.split('.')[0] for m in sys.modules} & {'gmsh', 'vtk', 'vtkmodules', 'pyvista', 'dask', "
            "'distributed', 'numba', 'matplotlib', 'skfem', 'xarray', 'scipy'}; print(sorted(heavy))")
    out = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
