"""The experiments from Python do what the phri command does: the same files, byte for byte."""
import subprocess

import pytest

import phri
from conftest import program


def test_torque_tracking_from_python_writes_what_the_cli_writes(tmp_path):
    cli_out, py_out = tmp_path / "cli", tmp_path / "py"
    subprocess.run([program("PHRI_CLI"), "experiment", "torque-tracking", "--static-s", "1", "--dynamic-s", "1",
                    "--out", str(cli_out)], check=True, capture_output=True)
    options = phri.TorqueTrackingOptions()
    options.static_duration_s = 1.0
    options.dynamic_duration_s = 1.0
    options.output_dir = str(py_out)
    options.figure_script = ""
    result = phri.run_torque_tracking(options, progress=False)
    assert len(result.runs) == 4
    for name in ("torque_tracking_summary.csv", "torque_tracking_static_custom.csv",
                 "torque_tracking_dynamic_kinova_torque_high_velocity.csv"):
        assert (py_out / name).read_bytes() == (cli_out / name).read_bytes(), name
    summary = (cli_out / "torque_tracking_summary.csv").read_text().splitlines()
    first = dict(zip(summary[0].split(","), summary[1].split(",")))
    run = result.runs[0]
    assert first["scenario"] == run.scenario.name and float(first["rms_Nm"]) == pytest.approx(run.rms_Nm, abs=5e-7)
    assert result.rms_ratio(phri.TrackingScenario.static) > 0.0


def test_experiment_options_find_the_shipped_files():
    options = phri.SafetyFuzzOptions()
    assert options.plant_config_path.endswith("configs/plant_gen3.yaml")
    assert phri.locate(options.plant_config_path) == options.plant_config_path
    with pytest.raises(phri.ConfigError):
        options.plant_config_path = "/nonexistent/plant.yaml"
        options.pushes = 1
        phri.run_safety_fuzz(options, progress=False)


def test_drop_test_from_python_catches_after_a_free_fall():
    options = phri.DropTestOptions()
    options.output_dir = ""
    options.figure_script = ""
    options.drops = 1
    options.release_s = 2.0
    options.window_s = 1.5
    result = phri.run_drop_test(options, progress=False)
    assert [r.mode for r in result.runs] == [phri.DropMode.torque, phri.DropMode.position]
    for run in result.runs:
        fall = run.catch_s - options.release_s
        # Free fall over the slack length, the hand's release +-2 cm: sqrt(2 (0.25 +- 0.02) / g).
        assert (2 * 0.23 / 9.81) ** 0.5 - 2e-3 < fall < (2 * 0.27 / 9.81) ** 0.5 + 2e-3
        assert run.peak_mm == pytest.approx(max(abs(e) for e in run.error_mm), rel=1e-6)
