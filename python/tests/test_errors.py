"""C++ errors arrive as Python exceptions of the phri.Error family with the same one-line messages.

The reference for "the same message" is the phri command itself: it prints every phri::Error as
`phri: error: <what()>` on one line, so the test asks the CLI and the module to load the same bad file
and compares the two lines.
"""
import subprocess

import numpy as np
import pytest

import phri
from conftest import GEN3_URDF, SOURCE_DIR, program

CLI_PREFIX = "phri: error: "


def cli_error_line(*arguments):
    done = subprocess.run([program("PHRI_CLI"), *arguments], capture_output=True, text=True)
    assert done.returncode != 0
    lines = done.stderr.splitlines()
    assert len(lines) == 1 and lines[0].startswith(CLI_PREFIX), done.stderr
    return lines[0][len(CLI_PREFIX):]


def test_missing_urdf_gives_the_cli_message(tmp_path):
    missing = str(tmp_path / "missing.urdf")
    with pytest.raises(phri.ConfigError) as caught:
        phri.Model.from_urdf_file(missing)
    assert str(caught.value) == cli_error_line("info", "--urdf", missing)
    assert "\n" not in str(caught.value)
    assert caught.value.file == missing and caught.value.reason
    assert isinstance(caught.value, phri.Error) and isinstance(caught.value, RuntimeError)


def test_bad_run_configuration_gives_the_cli_message(tmp_path):
    config = tmp_path / "bad.yaml"
    demo = (SOURCE_DIR / "configs/demo.yaml").read_text()
    # A release threshold above the touch threshold: refused with the key path.
    demo = demo.replace("../robots/", f"{SOURCE_DIR}/robots/").replace("file: plant_gen3.yaml", f"file: {SOURCE_DIR}/configs/plant_gen3.yaml")
    config.write_text(demo.replace("release_threshold: 4.0", "release_threshold: 40.0"))
    assert "release_threshold: 40.0" in config.read_text()
    with pytest.raises(phri.ConfigError) as caught:
        phri.Config.from_yaml_file(str(config))
    assert str(caught.value) == cli_error_line("run", "--config", str(config), "--out", str(tmp_path / "out"))
    assert "release_threshold" in caught.value.element


def test_wrong_vector_size_is_an_argument_error_with_the_library_message():
    model = phri.Model.from_urdf_file(GEN3_URDF)
    data = phri.Data(model)
    with pytest.raises(phri.ArgumentError) as caught:
        phri.crba(model, data, np.zeros(3))
    # The library's check_size wording (core/error.hpp), naming the function called.
    assert str(caught.value) == "crba: q has 3 entries, expected 7"
    assert isinstance(caught.value, ValueError)


def test_a_non_finite_joint_vector_is_an_argument_error_not_a_nan_result():
    model = phri.Model.from_urdf_file(GEN3_URDF)
    data = phri.Data(model)
    q = np.zeros(7)
    q[2] = np.nan
    with pytest.raises(phri.ArgumentError, match=r"rnea: q\[2\] is not finite"):
        phri.rnea(model, data, q, np.zeros(7), np.zeros(7))
    with pytest.raises(phri.ArgumentError, match=r"compute_all_terms: qd\[0\] is not finite"):
        phri.compute_all_terms(model, data, np.zeros(7), np.full(7, np.inf))


def test_command_vectors_keep_their_size():
    command = phri.RobotCommand(7)
    with pytest.raises(phri.ArgumentError, match="tau_Nm: the new value has 2 entries, expected 7"):
        command.tau_Nm = [1.0, 2.0]


def test_io_error_names_the_path(tmp_path):
    with pytest.raises(phri.IoError) as caught:
        phri.load_log(str(tmp_path / "none.csv"))
    assert caught.value.path == str(tmp_path / "none.csv")
    assert str(caught.value) == f"{tmp_path / 'none.csv'}: cannot open the file"


def test_a_missing_file_is_also_a_file_not_found_error_and_paths_may_be_path_objects(tmp_path):
    missing = tmp_path / "missing.urdf"
    for load in (phri.Model.from_urdf_file, phri.Config.from_yaml_file, phri.ActuatorTable.from_yaml_file,
                 phri.SimRobotConfig.from_yaml_file):
        with pytest.raises(FileNotFoundError) as caught:
            load(missing)  # a pathlib.Path, as os.PathLike
        assert isinstance(caught.value, phri.ConfigError) and isinstance(caught.value, OSError)
        assert caught.value.file == str(missing) and "\n" not in str(caught.value)
    # A file that is there but wrong stays a ConfigError only.
    bad = tmp_path / "bad.urdf"
    bad.write_text("<robot name='x'><link name='a'/><joint name='j' type='revolute'></joint></robot>")
    with pytest.raises(phri.ConfigError) as caught:
        phri.Model.from_urdf_file(bad)
    assert not isinstance(caught.value, FileNotFoundError)
    assert phri.Model.from_urdf_file(SOURCE_DIR / "robots/kinova_gen3/gen3.urdf").nq == 7
