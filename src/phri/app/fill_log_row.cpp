#include <phri/app/fill_log_row.hpp>

#include <phri/control/controller.hpp>
#include <phri/app/fsm.hpp>
#include <phri/robot/robot_state.hpp>

#include <algorithm>

namespace phri {
namespace {

void copy_joints(LogRow::Joints& out, const Eigen::VectorXd& v) {
  const int n = std::min<int>(kLogMaxJoints, static_cast<int>(v.size()));
  for (int i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = v[i];
  for (int i = n; i < kLogMaxJoints; ++i) out[static_cast<std::size_t>(i)] = 0.0;
}

void copy_pose(std::array<double, 3>& position, std::array<double, 4>& quaternion, const Eigen::Isometry3d& pose) {
  for (int i = 0; i < 3; ++i) position[static_cast<std::size_t>(i)] = pose.translation()[i];
  const Eigen::Quaterniond q(pose.linear());
  quaternion = {q.w(), q.x(), q.y(), q.z()};
}

}  // namespace

void fill_log_row(LogRow& row, const RobotState& state, const Controller& cycle) {
  row.time_s = state.time_s;
  row.cycle = static_cast<std::int64_t>(state.cycle);
  copy_joints(row.q, state.q_rad);
  copy_joints(row.qd, state.qd_rad_s);
  copy_joints(row.tau_s, state.tau_sensor_Nm);
  copy_joints(row.current, state.current_A);
  const WholeBodyQp& qp = cycle.qp();
  copy_joints(row.qdd_d, qp.desired_acceleration());
  copy_joints(row.tau_d, qp.desired_torque());
  copy_joints(row.tau_ext, cycle.observer().external_torque());
  const EndEffectorTask& ee = qp.end_effector();
  copy_pose(row.ee_position, row.ee_quaternion, ee.pose());
  copy_pose(row.target_position, row.target_quaternion, ee.target_pose());
  const Vector6d& error = ee.error();
  for (int i = 0; i < 6; ++i) row.error[static_cast<std::size_t>(i)] = error[i];
  row.error_position_m = error.head<3>().norm();
  row.error_orientation_rad = error.tail<3>().norm();
  for (int i = 0; i < 3; ++i) {
    row.ee_velocity[static_cast<std::size_t>(i)] = ee.velocity()[i];
    row.target_velocity[static_cast<std::size_t>(i)] = ee.target_velocity()[i];
  }
  const Vector6d& wrench = cycle.wrench().wrench_world();
  for (int i = 0; i < 6; ++i) row.wrench[static_cast<std::size_t>(i)] = wrench[i];
  row.wrench_norm = cycle.wrench().norm();
  for (int i = 0; i < 6; ++i) row.ft_wrench[static_cast<std::size_t>(i)] = state.wrench_sensor[i];
  row.compliance_mode = static_cast<std::int32_t>(cycle.compliance().mode());
  row.touched = cycle.compliance().touched() ? 1 : 0;
  row.low_level_loop = static_cast<std::int32_t>(cycle.low_level().loop());
  row.cycle_status = static_cast<std::int32_t>(cycle.status());
  row.safety_state = static_cast<std::int32_t>(cycle.supervisor().state());
  row.safety_fault = static_cast<std::int32_t>(cycle.supervisor().sample_fault());
  row.ft_status = static_cast<std::int32_t>(cycle.wrench_supervisor().status());
  row.controller_status = static_cast<std::int32_t>(qp.status());
  row.qp_status = static_cast<std::int32_t>(qp.qp_status());
  row.qp_iterations = qp.qp_iterations();
  row.stiffness_scale = cycle.compliance().stiffness_scale();
}

void fill_log_row(LogRow& row, const RobotState& state, const Controller& cycle, const Fsm& fsm) {
  fill_log_row(row, state, cycle);
  row.fsm_state = static_cast<std::int32_t>(fsm.state());
  row.event = fsm.last_event_code();
}

}  // namespace phri
