"""Per-gear sweep scalars (mass, saving, inertia, root stress) in the shared tiny study."""
import numpy as np
from sweep_cases import swept  # noqa: F401  (the sweep, run once per session)


def test_swept_mass_saving_follows_the_body_not_the_speed(swept):
    ds = swept[0].dataset
    saving = ds["mass_saving_gear2"]
    assert float(saving.sel(n_holes=0, web_thickness=17.0).max()) == 0.0
    assert (saving.sel(n_holes=4) > 0).all() and (saving.sel(web_thickness=12.0) > 0).all()
    assert ds["mass_gear2"].dims == ("n_holes", "web_thickness")          # geometry: not over the speed
    assert ds["mass_gear2"].attrs["units"] == "kg" and ds["inertia_gear2"].attrs["units"] == "kg mm2"
    assert np.isnan(ds["root_stress_max_gear2"]).all()          # uniform springs: no FE
    # the solid driven gear is its own stress reference; a lightened one on uniform springs is unknown
    ratio = ds["root_stress_ratio_gear2"]
    assert (ratio.sel(n_holes=0, web_thickness=17.0) == 1.0).all()
    assert np.isnan(ratio.sel(n_holes=4)).all() and np.isnan(ratio.sel(web_thickness=12.0)).all()
    assert (ds["root_stress_ratio_gear1"] == 1.0).all()
