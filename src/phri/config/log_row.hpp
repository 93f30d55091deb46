#pragma once
// phri::LogRow: one control cycle as the logger records it (app/logger.hpp; filled by app/fill_log_row.hpp): a fixed-size,
// trivially copyable record, so that the control thread copies it into a preallocated ring slot
// with no allocation. Joint vectors hold up to kLogMaxJoints joints (the Gen3 has 7); the logger
// writes the first `dof` of them.
//
// CSV columns, in order (visit_log_columns is the one definition the header and the rows share):
//   time_s, cycle                         robot time [s], control cycle count
//   q_i, qd_i                             measured joint position [rad], velocity [rad/s]
//   qdd_d_i, tau_d_i                      QP's desired acceleration [rad/s^2], torque [N.m]
//   tau_s_i, tau_ext_i                    joint torque sensors, observer's external torque [N.m]
//   current_i                             measured motor current [A]
//   ee_x ee_y ee_z, ee_qw ee_qx ee_qy ee_qz           end effector (controller's model) [m], unit quaternion
//   target_x ..., target_qw ...                       end-effector target the task tracks
//   err_x err_y err_z, err_rx err_ry err_rz           target - pose [m], log(R* R^T) [rad]
//   err_pos_m, err_ori_rad                            their norms
//   ee_vx ee_vy ee_vz, target_vx target_vy target_vz  end-effector velocity (J qd, measured joints) and the
//                                                     tracked target's velocity, world axes [m/s] (the paper's
//                                                     velocity errors, Fig. dynamic-comparison, without derivatives)
//   wrench_fx wrench_fy wrench_fz wrench_mx wrench_my wrench_mz, wrench_norm
//                                         operator wrench at the EE, world axes [N, N.m] (F/T)
//   ft_fx ft_fy ft_fz ft_mx ft_my ft_mz   the F/T sensor's latest sample as it reads it: its own frame
//                                         (the model's "ft_sensor"), bias and tool load included [N, N.m]
//   live_push_n                           the live front end's push on the arm this cycle (0: none) [N]
//   compliance_mode, touched, low_level_loop, fsm_state, event,
//   cycle_status, safety_state, safety_fault, ft_status, controller_status, qp_status, qp_iterations
//                                         integer codes; the legend is the sidecar
//                                         <log>.legend.yaml (Logger::legend_yaml())
//   stiffness_scale                       live end-effector stiffness scale [-]
//   pfl_ratio, pfl_link                   power and force limiting (ISO/TS 15066), the link whose capsule point
//                                         is closest to its permissible speed: v / v_max and the link's index
//                                         (the sidecar legend names them; -1: no body regions configured)
//   pfl_speed_m_s, pfl_reflected_mass_kg, pfl_permissible_speed_m_s, pfl_energy_j
//                                         that point's speed, reflected mass along its motion, v_max and
//                                         1/2 mu v^2 (the plant's true state on a simulated arm)
//   cycle_time_s                          wall-clock time of the cycle's computation [s]
#include <array>
#include <cstdint>
#include <type_traits>

namespace phri {

inline constexpr int kLogMaxJoints = 7;

struct LogRow {
  using Joints = std::array<double, kLogMaxJoints>;

  double time_s = 0.0;
  std::int64_t cycle = 0;
  Joints q{}, qd{}, qdd_d{}, tau_d{}, tau_s{}, tau_ext{}, current{};
  std::array<double, 3> ee_position{};
  std::array<double, 4> ee_quaternion{1.0, 0.0, 0.0, 0.0};  ///< w, x, y, z
  std::array<double, 3> target_position{};
  std::array<double, 4> target_quaternion{1.0, 0.0, 0.0, 0.0};
  std::array<double, 6> error{};  ///< position (3), orientation log (3)
  double error_position_m = 0.0;
  double error_orientation_rad = 0.0;
  std::array<double, 3> ee_velocity{};      ///< linear, world axes [m/s]
  std::array<double, 3> target_velocity{};  ///< linear, world axes [m/s]
  std::array<double, 6> wrench{};  ///< force (3), moment (3)
  double wrench_norm = 0.0;
  std::array<double, 6> ft_wrench{};  ///< the sensor's sample in its frame: force (3), moment (3)
  double live_push_N = 0.0;            ///< the dashboard's push in force this cycle (0: none)
  std::int32_t compliance_mode = 0;    ///< ComplianceMode
  std::int32_t touched = 0;            ///< dual compliance: 1 while the end effector is touched
  std::int32_t low_level_loop = 0;     ///< LowLevelMode running
  std::int32_t fsm_state = -1;         ///< FsmState; -1: no FSM
  std::int32_t event = -1;             ///< Event handled in this cycle (the last one); -1: none
  std::int32_t cycle_status = 0;       ///< CycleStatus
  std::int32_t safety_state = 0;       ///< SupervisorState
  std::int32_t safety_fault = 0;       ///< SafetyFault of this cycle's sample (0: plausible)
  std::int32_t ft_status = 0;          ///< WrenchStatus of the F/T source (from 2 on: dropped, why)
  std::int32_t controller_status = 0;  ///< WholeBodyQpStatus of the whole-body QP
  std::int32_t qp_status = 0;          ///< QpStatus of the solver
  std::int32_t qp_iterations = 0;
  double stiffness_scale = 1.0;
  double pfl_ratio = 0.0;
  std::int32_t pfl_link = -1;
  double pfl_speed_m_s = 0.0, pfl_reflected_mass_kg = 0.0, pfl_permissible_speed_m_s = 0.0, pfl_energy_j = 0.0;
  double cycle_time_s = 0.0;
};

/// Calls, in column order, v.number(name, value) for each real column, v.integer(name, value) for
/// each integer column and v.joints(name, values, dof) for each per-joint group (columns name_1 ..
/// name_dof). `Row` is LogRow or const LogRow: a visitor may fill a row (the MCAP log's reader).
template <class Visitor, std::size_t N, class Values>
void visit_numbers(Visitor& v, const std::array<const char*, N>& names, Values& values) {
  for (std::size_t i = 0; i < N; ++i) v.number(names[i], values[i]);
}

template <class Row, class Visitor>
void visit_log_columns(Row&& r, int dof, Visitor&& v) {
  static_assert(std::is_same_v<std::remove_cvref_t<Row>, LogRow>);
  v.number("time_s", r.time_s);
  v.integer("cycle", r.cycle);
  v.joints("q", r.q, dof);
  v.joints("qd", r.qd, dof);
  v.joints("qdd_d", r.qdd_d, dof);
  v.joints("tau_d", r.tau_d, dof);
  v.joints("tau_s", r.tau_s, dof);
  v.joints("tau_ext", r.tau_ext, dof);
  v.joints("current", r.current, dof);
  visit_numbers<Visitor, 3>(v, {"ee_x", "ee_y", "ee_z"}, r.ee_position);
  visit_numbers<Visitor, 4>(v, {"ee_qw", "ee_qx", "ee_qy", "ee_qz"}, r.ee_quaternion);
  visit_numbers<Visitor, 3>(v, {"target_x", "target_y", "target_z"}, r.target_position);
  visit_numbers<Visitor, 4>(v, {"target_qw", "target_qx", "target_qy", "target_qz"}, r.target_quaternion);
  visit_numbers<Visitor, 6>(v, {"err_x", "err_y", "err_z", "err_rx", "err_ry", "err_rz"}, r.error);
  v.number("err_pos_m", r.error_position_m);
  v.number("err_ori_rad", r.error_orientation_rad);
  visit_numbers<Visitor, 3>(v, {"ee_vx", "ee_vy", "ee_vz"}, r.ee_velocity);
  visit_numbers<Visitor, 3>(v, {"target_vx", "target_vy", "target_vz"}, r.target_velocity);
  visit_numbers<Visitor, 6>(v, {"wrench_fx", "wrench_fy", "wrench_fz", "wrench_mx", "wrench_my", "wrench_mz"}, r.wrench);
  v.number("wrench_norm", r.wrench_norm);
  visit_numbers<Visitor, 6>(v, {"ft_fx", "ft_fy", "ft_fz", "ft_mx", "ft_my", "ft_mz"}, r.ft_wrench);
  v.number("live_push_n", r.live_push_N);
  v.integer("compliance_mode", r.compliance_mode);
  v.integer("touched", r.touched);
  v.integer("low_level_loop", r.low_level_loop);
  v.integer("fsm_state", r.fsm_state);
  v.integer("event", r.event);
  v.integer("cycle_status", r.cycle_status);
  v.integer("safety_state", r.safety_state);
  v.integer("safety_fault", r.safety_fault);
  v.integer("ft_status", r.ft_status);
  v.integer("controller_status", r.controller_status);
  v.integer("qp_status", r.qp_status);
  v.integer("qp_iterations", r.qp_iterations);
  v.number("stiffness_scale", r.stiffness_scale);
  v.number("pfl_ratio", r.pfl_ratio);
  v.integer("pfl_link", r.pfl_link);
  v.number("pfl_speed_m_s", r.pfl_speed_m_s);
  v.number("pfl_reflected_mass_kg", r.pfl_reflected_mass_kg);
  v.number("pfl_permissible_speed_m_s", r.pfl_permissible_speed_m_s);
  v.number("pfl_energy_j", r.pfl_energy_j);
  v.number("cycle_time_s", r.cycle_time_s);
}

}  // namespace phri
