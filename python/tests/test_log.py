"""phri logs as numpy structured arrays: a session's CSV (Logger) loaded with load_log equals what the
same run recorded in memory (ClosedLoop.record), and equals numpy's own CSV parser's reading."""
import numpy as np
import pytest

import phri
from conftest import DEMO_YAML, controller_settings, plant_config


def test_logged_csv_loads_into_the_rows_the_run_recorded(tmp_path):
    settings = phri.LoggerSettings()
    settings.path = str(tmp_path / "run.csv")
    settings.dof = 7
    robot = phri.SimRobot(plant_config())
    controller = phri.Controller(controller_settings(phri.ComplianceMode.dual))
    logger = phri.Logger(settings)
    loop = phri.ClosedLoop(robot, controller, None, logger)
    recorded = loop.record(300)
    stats = logger.close()
    assert stats.written == 300 and stats.dropped == 0
    loaded = phri.load_log(settings.path)
    assert loaded.dtype == phri.log_dtype(7) == recorded.dtype
    # Every cell, bit for bit: the logger writes the shortest text that reads back to the same double.
    assert loaded.tobytes() == recorded.tobytes()
    # numpy's own parser agrees (its dtype: float64 everywhere).
    reference = np.genfromtxt(settings.path, delimiter=",", names=True)
    for name in loaded.dtype.names:
        assert np.array_equal(loaded[name].astype(np.float64), reference[name]), name


def test_log_columns_follow_the_cpp_header():
    header = phri.Logger.header(7).split(",")
    assert [name for name, _ in phri.log_columns(7)] == header
    kinds = dict(phri.log_columns(7))
    assert kinds["time_s"] == "float64" and kinds["compliance_mode"] == "int64" and kinds["q_7"] == "float64"


def test_a_session_log_opens_with_its_codes_as_enums(tmp_path):
    result = phri.run(DEMO_YAML, duration_s=0.3, out_dir=tmp_path)
    assert result.summary.cycles == 300
    log = result.log()
    assert len(log) == 300 and log["time_s"][-1] == pytest.approx(0.3)
    assert phri.FsmState(int(log["fsm_state"][0])) == phri.FsmState.startup
    assert phri.LowLevelMode(int(log["low_level_loop"][0])) == phri.LowLevelMode.position


def test_a_session_measures_power_and_force_limiting_on_the_plants_true_state(tmp_path):
    result = phri.run(DEMO_YAML, duration_s=0.5, out_dir=tmp_path)
    config = phri.Config.from_yaml_file(DEMO_YAML)
    links = [c.link for c in result.summary.contact]
    assert links and result.summary.contact_true_state
    for c in result.summary.contact:
        assert c.region == config.body_regions.for_link(c.link).name
        if c.max_ratio > 0:
            assert c.max_ratio == pytest.approx(c.speed_at_max_m_s / c.permissible_speed_at_max_m_s, rel=1e-12)
    log = result.log()
    worst = log["pfl_link"]
    assert worst.min() >= 0 and worst.max() < len(links)
    # The logged worst link's ratio is its speed over its v_max, and none of the summary's links went faster.
    moving = log["pfl_permissible_speed_m_s"] > 0
    assert np.allclose(log["pfl_ratio"][moving], log["pfl_speed_m_s"][moving] / log["pfl_permissible_speed_m_s"][moving])
    assert log["pfl_ratio"].max() == pytest.approx(max(c.max_ratio for c in result.summary.contact), rel=1e-12)


def test_a_bad_cell_names_its_line_and_column(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time_s,cycle\n0.001,1\n0.002,two\n")
    with pytest.raises(phri.IoError, match=r"line 3, column 'cycle': not an integer: 'two'"):
        phri.load_log(str(path))


def test_an_mcap_log_loads_into_the_same_rows_as_its_csv(tmp_path):
    csv = phri.run(DEMO_YAML, duration_s=0.5, out_dir=tmp_path / "csv", log="csv")
    mcap = phri.run(DEMO_YAML, duration_s=0.5, out_dir=tmp_path / "mcap", log="mcap")
    assert mcap.log_path.endswith(".mcap") and csv.log_path.endswith(".csv")
    a, b = phri.load_log(csv.log_path), phri.load_log(mcap.log_path)
    assert a.dtype == b.dtype and len(a) == len(b) == 500
    for name in a.dtype.names:
        if name != "cycle_time_s":  # the wall clock of each cycle's computation
            assert a[name].tobytes() == b[name].tobytes(), name
    exported = tmp_path / "exported.csv"
    assert phri.export_log_csv(mcap.log_path, exported) == 500
    assert phri.load_log(exported).tobytes() == b.tobytes()


def test_a_long_run_logs_to_mcap_unless_told_otherwise():
    config = phri.Config.from_yaml_file(DEMO_YAML)
    config.run.duration_s = 120.0
    assert phri.resolve_log_format(config) == phri.LogFormat.mcap and config.logging.path.endswith(".mcap")
    config = phri.Config.from_yaml_file(DEMO_YAML)
    assert phri.resolve_log_format(config) == phri.LogFormat.csv and config.logging.path.endswith(".csv")
    with pytest.raises(ValueError):
        phri.run(DEMO_YAML, duration_s=0.01, log="parquet")


def test_the_shipped_configs_run_from_any_working_directory(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)  # no configs/ here
    result = phri.run("configs/demo.yaml", duration_s=0.05, out_dir="out")
    assert result.summary.cycles == 50 and (tmp_path / "out").is_dir()
