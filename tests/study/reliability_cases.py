"""The scenes, studies and command-line calls the reliability tests (test_reliability*.py) share."""
from pathlib import Path

from study.cli import main


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


def write_study(tmp_path, grid: str, outputs: str = 'scalars = ["dte_rms"]', section: str = "grid") -> str:
    """The example study's scene with ``grid`` as its [grid] (or the table ``section``)."""
    text = (Path("study/scenes/example_study.toml").read_text().split("[grid]")[0]
            + f"[{section}]\n{grid}\n[outputs]\n{outputs}\n")
    path = tmp_path / "st.toml"
    path.write_text(text)
    return str(path)


def small_scene(**overrides):
    """The example study's 20-tooth pair (uniform springs, no FE), solid."""
    from study.sweep.grid import load_study
    scene = load_study("study/scenes/example_study.toml").points()[0].scene
    return scene.replace(**overrides)


def paper_pair(**kw):
    """The small pair on the paper's model (uniform springs: no FE), a short dynamic run."""
    from tests.helpers import small_scene
    return small_scene(**{"gear1.spring.stiffness": "uniform", "gear2.spring.stiffness": "uniform",
                          "dynamic.duration": 0.02, "dynamic.ramp_time": 0.004, "dynamic.speed": 100.0, **kw})


def dynamic_fields(scene):
    import warnings

    from study.plan import RunOptions
    from study.run import run_fields
    with warnings.catch_warnings():
        warnings.simplefilter("error")      # no raw library warning either
        return run_fields(scene, {"dynamic", "mesh", "gear"}, RunOptions(warn=False))


def sample_study(tmp_path, sample: str) -> str:
    return write_study(tmp_path, sample, 'scalars = ["ste_p2p"]', section="sample")
