#pragma once
// phri::Controller: one control period of the paper's framework, data flowing one way
// (DESIGN.md section 2):
//
//   RobotState -> model terms (M, h, g, J, J̇q̇) -> momentum observer tau_ext, F/T wrench
//              -> compliance mode (dual-compliance trigger) -> WholeBodyQp (qdd_d, tau_d)
//              -> LowLevelController -> RobotCommand
//
// Built once from ControllerSettings (files loaded and checked at construction, ConfigError on
// bad input); step() allocates nothing and never throws. Invalid or stale sensor data: the cycle
// holds (the previous command is kept) and says so in status().
#include <phri/control/controller_settings.hpp>
#include <phri/control/compliance_controller.hpp>
#include <phri/control/momentum_observer.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/control/wrench_estimator.hpp>
#include <phri/lowlevel/low_level_controller.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/model.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>

#include <optional>
#include <string_view>

namespace phri {

enum class CycleStatus {
  kOk,
  kQpFallback,     ///< the QP failed; the brake of WholeBodyQp::fallback ran
  kInvalidState,   ///< non-finite or invalid joint/torque data: previous command held
  kStaleState,     ///< the joint data did not advance since the last cycle: previous command held
};
constexpr std::string_view to_string(CycleStatus s) {
  switch (s) {
    case CycleStatus::kOk: return "ok";
    case CycleStatus::kQpFallback: return "qp_fallback";
    case CycleStatus::kInvalidState: return "invalid_state";
    case CycleStatus::kStaleState: return "stale_state";
  }
  return "unknown";
}

class Controller {
public:
  explicit Controller(const ControllerSettings& settings);

  /// First call: takes the robot's state as the targets (hold where the arm is). Then one cycle.
  CycleStatus step(const RobotState& state, RobotCommand& command);

  // ---- live switches (gamepad, FSM, scripts); effective from the next step
  void set_compliance_mode(ComplianceMode mode);
  void set_low_level_loop(LowLevelMode loop) { low_level_.request(loop); }
  void set_stiffness_scale(double scale) { compliance_.set_stiffness_scale(scale, qp_); }

  // ---- access
  const Model& model() const { return model_; }
  const Data& data() const { return data_; }
  WholeBodyQp& qp() { return qp_; }
  const WholeBodyQp& qp() const { return qp_; }
  const ComplianceController& compliance() const { return compliance_; }
  const MomentumObserver& observer() const { return observer_; }
  /// The external joint torque the QP used in the last step (see ExternalTorqueSource).
  const Eigen::VectorXd& external_torque() const { return tau_ext_; }
  const WrenchEstimator& wrench() const { return wrench_; }
  const LowLevelController& low_level() const { return low_level_; }
  const ActuatorTable& actuators() const { return actuators_; }
  int end_effector_frame() const { return end_effector_frame_; }
  int sensor_frame() const { return sensor_frame_; }
  CycleStatus status() const { return status_; }
  long held_cycles() const { return held_cycles_; }
  const ControllerSettings& settings() const { return settings_; }
  bool started() const { return started_; }
  /// The wrench norm the dual-compliance trigger sees (low-passed).
  double trigger_wrench_norm() const { return trigger_wrench_norm_; }

private:
  static Model load_model(const ControllerSettings& settings);
  static WholeBodyQpSettings qp_settings(const ControllerSettings& settings, const ActuatorTable& actuators);
  bool state_usable(const RobotState& state);

  ControllerSettings settings_;
  Model model_;
  Data data_;
  ActuatorTable actuators_;
  std::optional<CollisionModel> collision_;
  WholeBodyQp qp_;
  ComplianceController compliance_;
  MomentumObserver observer_;
  WrenchEstimator wrench_;
  LowLevelController low_level_;
  int end_effector_frame_ = 0;
  int sensor_frame_ = 0;
  Eigen::VectorXd q_, qd_, zero_torque_;
  std::uint32_t last_joint_sequence_ = 0;
  std::uint32_t last_wrench_sequence_ = 0;
  bool started_ = false;
  bool have_command_ = false;
  std::optional<ComplianceMode> pending_mode_;
  CycleStatus status_ = CycleStatus::kOk;
  long held_cycles_ = 0;
  double trigger_wrench_norm_ = 0.0;
  Eigen::MatrixXd ee_jacobian_;              // 6 x nv, for J^T F
  Eigen::VectorXd ft_torque_, ft_torque_low_, tau_ext_;
};

}  // namespace phri
