"""The closed loop from Python: the same loop as C++, views without copies, targets and events."""
import subprocess

import numpy as np
import pytest

import phri
from conftest import DEMO_YAML, PAPER_POSTURE, controller_settings, plant_config, program

BENCH_SECONDS = 0.3


def bench_scenario(seconds):
    """The scenario of python/bench (and of phri_loop_reference): pushes on the elbow and the tool, dual compliance."""
    config = plant_config()
    config.mismatch.enabled = True
    pushes = []
    start = 1.0
    while start < seconds:
        pushes.append(phri.ExternalForce("forearm_link", [0, 30, 0], start, 1.0))
        pushes.append(phri.ExternalForce("tool", [0, -15, 0], start + 3.0, 1.0))
        start += 6.0
    config.disturbances = pushes
    robot = phri.SimRobot(config)
    controller = phri.Controller(controller_settings(phri.ComplianceMode.dual))
    return robot, controller


def cpp_final_q(seconds):
    out = subprocess.run([program("PHRI_LOOP_REFERENCE"), "--seconds", str(seconds)], capture_output=True, text=True,
                         check=True).stdout
    line = next(l for l in out.splitlines() if l.startswith("final_q"))
    return np.array([float.fromhex(w) for w in line.split()[1:]])


def test_python_stepped_and_cpp_run_loops_end_where_the_cpp_program_ends_bit_for_bit():
    expected = cpp_final_q(1.2)  # through the first push
    robot, controller = bench_scenario(1.2)
    loop = phri.ClosedLoop(robot, controller)
    for _ in range(1200):
        loop.step()
    assert np.array_equal(robot.state().q_rad, expected)
    robot, controller = bench_scenario(1.2)
    loop = phri.ClosedLoop(robot, controller)
    assert loop.run(1200) == 1200 and loop.cycles == 1200
    assert np.array_equal(robot.state().q_rad, expected)


def test_separate_read_step_write_calls_make_the_same_loop():
    robot_a, controller_a = bench_scenario(0.2)
    loop = phri.ClosedLoop(robot_a, controller_a)
    loop.run(200)
    robot, controller = bench_scenario(0.2)
    command, targets = phri.RobotCommand(7), phri.ControllerTargets(7)
    for _ in range(200):
        state = robot.read()
        controller.step(state, targets, command)
        assert robot.write(command) == phri.WriteStatus.ok
    assert np.array_equal(robot.state().q_rad, robot_a.state().q_rad)
    assert np.array_equal(controller.desired_torque, controller_a.desired_torque)


def test_state_and_command_are_views_of_the_cpp_buffers(rig):
    robot, controller, loop = rig
    state = robot.read()
    q = state.q_rad
    assert not q.flags.writeable and q.base is not None
    t0 = state.time_s
    robot.read()
    assert state.time_s > t0 and np.shares_memory(q, robot.state().q_rad)  # the same state, read again
    kept = q.copy()
    loop.run(50)
    assert not np.array_equal(q, kept) or np.array_equal(q, robot.state().q_rad)
    command = phri.RobotCommand(7)
    view = command.q_rad
    view[:] = PAPER_POSTURE  # writes the C++ command
    assert np.array_equal(command.q_rad, PAPER_POSTURE) and np.shares_memory(view, command.q_rad)
    tau = controller.desired_torque
    assert np.shares_memory(tau, controller.desired_torque) and not tau.flags.writeable


def test_targets_reach_the_controller(rig):
    robot, controller, loop = rig
    loop.run(100)
    targets = phri.ControllerTargets(7)
    goal = np.array(PAPER_POSTURE) + 0.1
    targets.set_posture(goal)
    targets.compliance_mode = phri.ComplianceMode.stiff
    targets.low_level_mode = phri.LowLevelMode.kinova_torque
    assert loop.step(targets) == phri.CycleStatus.ok
    assert np.array_equal(controller.posture_target, goal)
    assert controller.compliance_mode == phri.ComplianceMode.stiff
    loop.run(50)
    assert controller.low_level_loop == phri.LowLevelMode.kinova_torque
    pose = controller.ee_pose
    pose[2, 3] += 0.02
    targets.clear()
    targets.set_pose(pose)
    loop.step(targets)
    loop.run(400)  # the reference governor brings the target there at 0.25 m/s
    assert np.allclose(controller.ee_target_pose[:3, 3], pose[:3, 3], atol=1e-6)


def test_an_fsm_drives_the_loop_with_events():
    config = phri.Config.from_yaml_file(DEMO_YAML)
    robot = phri.SimRobot(config.plant)
    controller = phri.Controller(config.controller)
    fsm = phri.Fsm(config.fsm, controller)
    loop = phri.ClosedLoop(robot, controller, fsm)
    with pytest.raises(phri.ArgumentError, match="FSM"):
        loop.step(phri.ControllerTargets(7))
    loop.run(100)
    assert fsm.state == phri.FsmState.startup
    fsm.post(phri.Event.full_body_compliance)
    loop.step()
    assert controller.compliance_mode == phri.ComplianceMode.full_body
    assert fsm.last_event_code == int(phri.Event.full_body_compliance)


def test_record_returns_the_log_rows_of_the_run(rig):
    robot, controller, loop = rig
    rows = loop.record(120)
    assert rows.dtype == phri.log_dtype(7) and len(rows) == 120
    assert np.array_equal(rows["q_3"][-1:], robot.state().q_rad[2:3])
    assert rows["cycle"].dtype == np.int64 and list(rows["cycle"][:3]) == [1, 2, 3]
    assert np.all(np.diff(rows["time_s"]) > 0)
    assert rows["compliance_mode"][0] == int(phri.ComplianceMode.null_space)


def test_the_ft_sensor_mount_is_a_placement_that_reaches_the_controllers_model():
    """ControllerSettings.ft_sensor_mount (4 x 4): the Gen3's straight 0.065 m, and a turned, offset one as the model's
    "ft_sensor" frame on the end effector (the wrench estimator reads through it)."""
    settings = phri.ControllerSettings()
    straight = np.eye(4)
    straight[2, 3] = 0.065
    assert np.array_equal(settings.ft_sensor_mount, straight)
    turned = np.eye(4)
    turned[:3, :3] = [[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]  # its x along the flange's y
    turned[:3, 3] = [0.02, -0.01, 0.065]
    settings.ft_sensor_mount = turned
    assert np.array_equal(settings.ft_sensor_mount, turned)
    model = phri.Controller(settings).model
    sensor = model.frames[model.frame_id("ft_sensor")]
    end_effector = model.frames[model.frame_id(settings.end_effector_frame)]
    assert sensor.body == end_effector.body
    assert np.abs(sensor.placement - end_effector.placement @ turned).max() < 1e-15
