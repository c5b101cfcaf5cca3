"""What a careless user or script meets: every bad input is exit 2 with the field or option
named, before any work; every refusal names the lever that helps."""
import pytest

from study.cli import main


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out = capsys.readouterr()
    return code, out.out, out.err


# ---------------------------------------------------------------- files and output names

def test_a_scene_or_study_file_that_is_not_utf8_is_named(tmp_path, capsys):
    bad = tmp_path / "latin1.toml"
    bad.write_bytes('title = "engrenage allégé"\n'.encode("latin-1"))
    code, _, err = run_cli(capsys, "run", bad, "-o", tmp_path / "r.nc")
    assert code == 2 and "scene: " in err and "not UTF-8" in err
    code, _, err = run_cli(capsys, "sweep", bad, "-o", tmp_path / "s.nc")
    assert code == 2 and "study: " in err and "not UTF-8" in err


def test_a_study_whose_scene_is_a_number_is_named(tmp_path, capsys):
    st = tmp_path / "s.toml"
    st.write_text('scene = 5\n[grid]\n"dynamic.speed" = [50.0]\n')
    code, _, err = run_cli(capsys, "sweep", st, "-o", tmp_path / "s.nc")
    assert code == 2 and "scene: must be a file name or a table" in err


@pytest.mark.parametrize("command", ["run", "stiffness", "reference", "precision"])
def test_an_output_name_too_long_for_the_file_system_is_refused_up_front(tmp_path, capsys, command):
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("a" * 300 + ".nc"))
    assert code == 2 and "-o: a name of 303 bytes is too long" in err
    # and one that leaves no room for the temporary file of the atomic write
    code, _, err = run_cli(capsys, command, "-o", tmp_path / ("b" * 240 + ".nc"))
    assert code == 2 and "at most 215 bytes" in err


def test_a_file_where_the_parts_folder_goes_is_refused(tmp_path, capsys):
    (tmp_path / ".s.nc.parts").write_text("not a folder")
    code, _, err = run_cli(capsys, "sweep", "study/scenes/example_study.toml", "-o", tmp_path / "s.nc", "--workers", 0)
    assert code == 2 and ".s.nc.parts is a file" in err


# ---------------------------------------------------------------- options

@pytest.mark.parametrize("option, value, says", [("--duration", "0", "must be a positive number"),
                                                 ("--rotation", "0", "must be a positive number"),
                                                 ("--duration", "nan", "must be a positive number"),
                                                 ("--ramp-fraction", "2", "must lie in (0, 1]"),
                                                 ("--repeats", "0", "at least 1")])
def test_precision_options_are_checked_before_any_work(tmp_path, capsys, option, value, says):
    code, out, err = run_cli(capsys, "precision", option, value, "-o", tmp_path / "p.nc")
    assert code == 2 and f"{option}: " in err and says in err and "study ..." not in out


def test_workflow_scripts_options_give_exit_2_not_a_traceback(tmp_path, capsys):
    from study.cli import script_main
    from workflows import sensitivity_sweep, validation
    assert script_main("validation", lambda: validation.main(["--step", "0", "-o", str(tmp_path / "v.nc")])) == 2
    assert "--step: the driver angle step must be a positive number" in capsys.readouterr().err
    assert script_main("sweep", lambda: sensitivity_sweep.main(["--grid", "bad", "-o", str(tmp_path / "s.nc")])) == 2
    assert "a grid axis must look like field=v1,v2" in capsys.readouterr().err


def test_a_material_too_soft_for_weber_is_named_by_fit_contact(capsys):
    code, _, err = run_cli(capsys, "fit-contact", "--set", "material.youngs_modulus=1e-9")
    assert code == 2 and "material.youngs_modulus" in err and "LinAlgError" not in err
    code, _, err = run_cli(capsys, "fit-contact", "--set", "quasi_static.torque=0")
    assert code == 2 and "quasi_static.torque" in err


# ---------------------------------------------------------------- estimates and their levers

def test_static_angles_that_do_not_fit_in_memory_are_refused_before_they_are_built(tmp_path, capsys):
    code, _, err = run_cli(capsys, "reference", "--step", "1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "--step: the static analysis needs about" in err and "TiB" in err
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.rotation=1e9", "--max-time", "1e30",
                           "-o", tmp_path / "r.nc")
    assert code == 2 and "quasi_static.angle_step: the static analysis needs" in err


def test_a_refusal_names_the_lever_of_its_largest_part(tmp_path, capsys):
    code, _, err = run_cli(capsys, "run", "--no-dynamic", "--set", "quasi_static.angle_step=1e-5", "-o", tmp_path / "r.nc")
    assert code == 2 and "make the statics cheaper: a larger quasi_static.angle_step" in err
    assert "fe.mesh_size" not in err
    code, _, err = run_cli(capsys, "run", "--no-static", "--set", "gear2.body.holes=0", "--set", "contact.friction=0.05",
                           "--set", "contact.friction_velocity=1e-9", "-o", tmp_path / "r.nc")
    assert code == 2 and "make the dynamics cheaper" in err and "contact.friction_velocity" in err
    assert "fe.mesh_size" not in err
