"""The README's first run and first study, each command as written, from an empty directory, and
what docs/design.md says of the paper gear's FE stiffness map (the parsing of the pages in
test_doc_blocks.py). One file, so that the paper pair's FE bodies the first run computes serve the
stiffness map too, from the FE cache."""
import shlex

import pytest
from test_doc_blocks import ROOT, blocks, commands


@pytest.mark.slow
@pytest.mark.parametrize("section", ["## A first run", "## A first study"])
def test_the_readme_commands_run_in_order(section, tmp_path, monkeypatch, capsys):
    """Each command of a README section, as written, from an empty directory: exit 0. The FE
    cache is the suite's (the default's folder is relative to where a command runs): the bodies
    the commands compute serve the other tests, which check the FE, and theirs these."""
    import os
    from pathlib import Path

    from study.cli import main
    text = (ROOT / "README.md").read_text()
    start = text.index(section)
    block = next(b for b in blocks("sh") if b.page == "README.md" and b.line > text.count("\n", 0, start))
    monkeypatch.setenv("LIGHTGEAR_CACHE", str(Path(os.environ.get("LIGHTGEAR_CACHE", ".lightgear-cache")).resolve()))
    monkeypatch.chdir(tmp_path)
    ran = []
    for cmd in commands(block):
        assert main(shlex.split(cmd)[1:]) == 0, cmd
        ran.append(cmd)
    assert ran and all(p.stat().st_size > 0 for p in (tmp_path / "results").glob("*.nc"))


@pytest.mark.slow
def test_the_teeth_over_a_hole_are_the_stiffest_as_design_md_says():
    """docs/design.md: on the paper's gear the stiffest teeth lie within about one pitch of a
    hole's centre line, the softest about 3 pitches from it, ratios 0.754-0.799."""
    import numpy as np

    import study
    from solver.geometry import hole_offset
    scene = study.load_scene("paper")
    ds = study.stiffness(scene)
    g = scene.gear2
    ratio = ds["stiffness_ratio"].sel(gear=2).values[: g.teeth]
    off = hole_offset(g.teeth, g.body.holes, g.body.hole_phase)
    assert abs(off[np.argmax(ratio)]) <= 1.2 and 2.5 <= abs(off[np.argmin(ratio)]) <= 4.0
    assert ratio.min() == pytest.approx(0.754, abs=0.003) and ratio.max() == pytest.approx(0.799, abs=0.003)
    assert "0.754 to 0.799" in (ROOT / "docs" / "design.md").read_text()
