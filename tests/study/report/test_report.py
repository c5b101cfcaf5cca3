"""Numbers and pages to hand on: `lightgear export` writes a run's summary scalars, `lightgear
report` one self-contained HTML page and its Markdown twin (scene, summary with units, the
model's validation, the figures) for a run, a study and a tolerance study."""
import base64
import re

import numpy as np
import pandas as pd
import pytest

import study
from study.cli import main
from study.report.report_page import VALIDATION
from study.sweep.grid import loads_study
from study.sweep.outputs import SCALARS

ROOT = __import__("pathlib").Path(__file__).resolve().parents[3]


@pytest.fixture(scope="module")
def run_archive(tmp_path_factory):
    """A short run of the example study's small pair (uniform springs: the paper's model, no FE)."""
    out = tmp_path_factory.mktemp("run") / "small.nc"
    scene = study.load_study("example_study").base_scene().replace(**{"dynamic.duration": 0.03,
                                                                      "quasi_static.rotation": 18.0})
    ds = study.run_scene(scene)
    study.write(ds, out)
    return ds, out


def test_export_writes_the_summary_scalars_with_their_units(run_archive, tmp_path):
    ds, path = run_archive
    assert main(["export", str(path), "-o", str(tmp_path)]) == 0
    table = pd.read_csv(tmp_path / "scalars.csv").set_index("name")
    s = study.summarize(ds)
    for name in ("ste_p2p", "ste_mean", "dte_rms", "dte_mean", "dte_p2p", "mesh_mode_frequency"):
        assert table.loc[name, "value"] == pytest.approx(s[name], rel=1e-14), name
        assert table.loc[name, "unit"] == SCALARS[name].units and table.loc[name, "long_name"] == SCALARS[name].long_name
    assert table.loc["dte_rms", "unit"] == "um" and table.index.is_unique


def test_a_run_report_is_one_self_contained_page_and_its_markdown_twin(run_archive, tmp_path, capsys):
    ds, path = run_archive
    assert main(["report", str(path), "-o", str(tmp_path), "--no-renders"]) == 0
    html = (tmp_path / "small_report.html").read_text()
    md = (tmp_path / "small_report.md").read_text()
    pngs = sorted(tmp_path.glob("small_*.png"))
    assert {p.name for p in pngs} >= {"small_ste.png", "small_dte.png", "small_spectrum.png"}
    # every figure inside the page, byte for byte; nothing the page loads from elsewhere
    embedded = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert sorted(base64.b64decode(e) for e in embedded) == sorted(p.read_bytes() for p in pngs)
    assert re.findall(r'(?:src|href)="(?!data:)', html) == []
    assert all(f"]({p.name})" in md for p in pngs)
    # the summary with units, the numbers of summarize
    s = study.summarize(ds)
    row = next(line for line in md.splitlines() if line.startswith("| `ste_p2p` |")).split("|")
    assert float(row[2]) == pytest.approx(s["ste_p2p"], rel=1e-3) and row[3].strip() == "um"
    assert any(line.startswith("| `dte_rms` |") and "| um |" in line for line in md.splitlines())
    # the model and its validation status, the scene as run
    assert ds.attrs["coupling_model"] == "paper"
    assert VALIDATION["paper"].verdict in md and "54.9" in md
    assert ds.attrs["scene"].strip().splitlines()[0] in md and "<pre>" in html
    assert "report:" in capsys.readouterr().out


def test_the_validation_status_quotes_the_models_page():
    """The report's validation figures are those of docs/models.md's largest-error row and relief
    table (and the README's)."""
    text = (ROOT / "docs" / "models.md").read_text()
    row = next(line for line in text.splitlines() if line.startswith("| **largest"))
    cells = [c.strip(" *") for c in re.split(r"(?<!\\)\|", row)[-4:-1]]
    for name, cell in zip(("paper", "body-torsion", "compliance"), cells):
        v = VALIDATION[name]
        assert [float(x) for x in cell.split(" / ")] == [v.mean_pct, v.p2p_pct, v.hole_pct], name
    readme = (ROOT / "README.md").read_text()
    for name, v in VALIDATION.items():
        relief = " / ".join(f"{r:+.2f}" for r in v.relief_um)
        assert f"| `\"{name}\"`" in readme and relief in readme, (name, relief)


# a 20-tooth pair with uniform springs (no FE) whose STE covers one driver revolution at 0.5 deg
BASE = """
[scene]
gear1.teeth = 20
gear2.teeth = 20
gear1.body = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0}
gear2.body = {rim_height = 3.0, web_height = 4.0, hub_height = 3.0, holes = 0}
gear2.spring.stiffness = "uniform"
quasi_static = {rotation = 6.0, angle_step = 0.5}
dynamic = {enabled = false}
"""
SAMPLED = ('title = "runout"\n' + BASE + '[grid]\n"gear1.errors.grade" = [0, 6]\n[sample]\nsize = 8\nmethod = "lhs"\n'
           'seed = 3\n"gear1.errors.eccentricity" = {uniform = [0.0, 4.0]}\n[outputs]\nscalars = ["ste_p2p"]\n')


def test_a_tolerance_study_report_has_its_statistics_table(tmp_path):
    path = tmp_path / "runout.nc"
    res = study.run_sweep(loads_study(SAMPLED), path, workers=0, progress=False)
    html, md = study.write_report(path, tmp_path / "out", renders=False)
    text = md.read_text()
    assert "## Statistics over the builds" in text
    y = res.dataset["ste_p2p"].isel(gear1_errors_grade=1).values
    line = next(t for t in text.splitlines() if t.strip().startswith("gear1.errors.grade = 6:"))
    assert f"P95 {np.quantile(y, 0.95):.4g} (no interval)" in line and f"mean {y.mean():.4g}" in line
    row = next(t for t in text.splitlines() if t.startswith("| `ste_p2p` |"))
    assert f"{np.nanmax(res.dataset['ste_p2p'].values):.4g}" in row and "| um |" in row
    assert (tmp_path / "out" / "runout_distribution_ste_p2p.png").is_file()
    assert html.read_text().count("data:image/png;base64,") == len(list((tmp_path / "out").glob("*.png")))


def test_a_report_after_render_takes_its_figures_and_draws_them_again_for_a_newer_archive(run_archive, tmp_path):
    """`lightgear report` beside `lightgear render`'s figures of the same archive embeds those
    files as they are; once the archive is written again, its figures are drawn again."""
    import os
    import shutil
    _, source = run_archive
    path = tmp_path / source.name
    shutil.copy2(source, path)
    assert main(["render", str(path), "--no-renders"]) == 0
    pngs = sorted(tmp_path.glob("small_*.png"))
    assert {p.name for p in pngs} >= {"small_ste.png", "small_dte.png", "small_spectrum.png"}
    written = {p.name: p.stat().st_mtime_ns for p in pngs}
    assert main(["report", str(path), "--no-renders"]) == 0
    assert {p.name: p.stat().st_mtime_ns for p in pngs} == written
    html = (tmp_path / "small_report.html").read_text()
    embedded = re.findall(r'src="data:image/png;base64,([^"]+)"', html)
    assert sorted(base64.b64decode(e) for e in embedded) == sorted(p.read_bytes() for p in pngs)
    later = max(written.values()) / 1e9 + 10.0          # the archive written again after the figures
    os.utime(path, (later, later))
    assert main(["report", str(path), "--no-renders"]) == 0
    assert all(p.stat().st_mtime_ns != written[p.name] for p in pngs)
