"""The tolerance workflow on a tiny sampled study: the answer quotes the tables it writes, a
reduced variant by --size and --set, and clear errors on bad options."""
import re
import sys
from pathlib import Path

import xarray as xr

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "study" / "sweep"))
from sweep_cases import BASE  # noqa: E402

from workflows.tolerance import DEFAULT_STUDY, main, reduced_study  # noqa: E402

TINY = 'title = "tiny tolerance"\n' + BASE + '''
[grid]
"gear1.errors.grade" = [5, 7]
[sample]
size = 4
method = "sobol"
seed = 3
design = "saltelli"
"gear1.errors.seed" = {integers = [0, 999]}
"gear1.errors.eccentricity" = {uniform = [0.0, 3.0]}
[outputs]
scalars = ["ste_p2p"]
'''


def test_the_answer_quotes_the_tables_of_a_tiny_tolerance_study(tmp_path, capsys):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    out = tmp_path / "out"
    assert main([str(path), "-o", str(out), "--workers", "0", "--no-progress", "--size", "4",
                 "--limit", "ste_p2p=20"]) == 0
    text = (out / "tolerance.txt").read_text()
    assert text.strip() in capsys.readouterr().out
    with xr.open_dataset(out / "study_tables.nc", engine="netcdf4") as f:
        tab = f.load()
    # --size 4: 4 rows x (2 + 2) matrices at each of the two classes
    assert tab["sample_count"].values.tolist() == [[16], [16]]
    p95 = tab["sample_percentile"].sel(output="ste_p2p", quantile=0.95, bound="estimate").values
    m = re.search(r"driver class 5 to driver class 7 raises the P95 of ste_p2p from ([\d.]+) to ([\d.]+) ", text)
    assert m and float(m[1]) == float(f"{p95[0]:.3g}") and float(m[2]) == float(f"{p95[1]:.3g}"), text
    # 4 rows: 8 independent builds (A and B) a class cannot bound a P95 at 95 %, and the answer says so
    assert "No 95 % interval bounds these P95s: 8 independent builds a grid point are fewer than the 72" in text
    assert "the driver's runout" in text and "the driver's pitch deviations" in text and "ste_p2p exceeds 20 um is" in text and "nan" not in text
    for stem in ("distribution_ste_p2p", "convergence_ste_p2p", "sobol_ste_p2p"):
        assert (out / f"{stem}.png").is_file()


def test_too_few_rows_for_sobol_indices_are_said_not_printed_as_nan(tmp_path, capsys):
    path = tmp_path / "tiny.toml"
    path.write_text(TINY)
    assert main([str(path), "-o", str(tmp_path / "out"), "--workers", "0", "--no-progress", "--size", "2"]) == 0
    text = (tmp_path / "out" / "tolerance.txt").read_text()
    assert "fewer than 4 rows" in text and "nan" not in text


def test_a_reduced_variant_of_the_tolerance_study():
    st = reduced_study(DEFAULT_STUDY, 4, ["dynamic.duration=0.1"])
    assert st.sample.builds == 4 * 7 and st.shape == (2, 28)
    assert st.base_scene().dynamic.duration == 0.1
    assert st.base_scene().gear1.modification.tip_relief == 2.0     # still paper_relief.toml underneath


def test_bad_options_exit_2(tmp_path, capsys):
    assert main([str(DEFAULT_STUDY), "--size", "1", "-o", str(tmp_path)]) == 2
    assert main([str(DEFAULT_STUDY), "--set", "dynamic.durration=0.1", "-o", str(tmp_path)]) == 2
    assert "dynamic.durration" in capsys.readouterr().err
