#include <phri/control/controller.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <cmath>

namespace phri {

ModelOptions Controller::model_options(const ControllerSettings& settings) {
  ModelOptions options;
  ExtraFrame sensor;
  sensor.name = "ft_sensor";
  sensor.parent_frame = settings.end_effector_frame;
  sensor.placement.translation() = Eigen::Vector3d(0.0, 0.0, settings.ft_sensor_offset_m);
  options.extra_frames.push_back(sensor);
  for (Payload payload : settings.payloads) {
    if (payload.frame.empty()) payload.frame = settings.end_effector_frame;  // default: the end effector
    options.payloads.push_back(payload);
  }
  return options;
}

WholeBodyQpSettings Controller::qp_settings(const ControllerSettings& settings, const ActuatorTable& actuators) {
  WholeBodyQpSettings qp = settings.qp;
  qp.end_effector_frame = settings.end_effector_frame;
  if (qp.torque_limit.size() == 0) {
    qp.torque_limit.resize(actuators.size());
    for (int i = 0; i < actuators.size(); ++i) qp.torque_limit[i] = actuators[i].torque_limit_Nm;
  }
  if (qp.compliance_deadband.size() == 0) {
    qp.compliance_deadband.resize(actuators.size());
    for (int i = 0; i < actuators.size(); ++i) {
      qp.compliance_deadband[i] = actuators[i].size == ActuatorSize::kLarge ? settings.deadband_large_Nm
                                                                            : settings.deadband_small_Nm;
    }
  }
  if (qp.velocity_limit.size() == 0) {
    qp.velocity_limit.resize(actuators.size());
    for (int i = 0; i < actuators.size(); ++i) qp.velocity_limit[i] = actuators[i].velocity_limit_rad_s;
  }
  return qp;
}

namespace {
// The actuator table must list the model's joints, in order.
const ActuatorTable& checked(const ActuatorTable& table, const Model& model, const std::string& source) {
  if (table.size() != model.nq()) {
    throw ConfigError(source, "joints",
                      std::to_string(table.size()) + " actuators for a model with " + std::to_string(model.nq()) + " joints");
  }
  for (int i = 0; i < model.nq(); ++i) {
    if (table[i].joint_name != model.joint(i).name) {
      throw ConfigError(source, "joints[" + std::to_string(i) + "].name",
                        "'" + table[i].joint_name + "' but the model's joint " + std::to_string(i + 1) + " is '" +
                            model.joint(i).name + "'");
    }
  }
  return table;
}

const ControllerSettings& checked(const ControllerSettings& settings) {
  if (!(settings.period_s > 0)) throw ConfigError("ControllerSettings", "period_s", "must be > 0");
  if (!(settings.observer_gain > 0)) throw ConfigError("ControllerSettings", "observer_gain", "must be > 0");
  // The discrete observer's residual r[k] = (1 - K T) r[k-1] + ... rings for K T > 1, diverges above 2.
  if (!(settings.observer_gain * settings.period_s < 1.0)) {
    throw ConfigError("ControllerSettings", "observer_gain", "observer_gain x period_s must be < 1");
  }
  if (!(settings.wrench_trigger_filter_s >= 0)) throw ConfigError("ControllerSettings", "wrench_trigger_filter_s", "must be >= 0");
  return settings;
}

CustomTorqueSettings custom_torque_settings(const ControllerSettings& settings) {
  CustomTorqueSettings c = settings.custom_torque;
  c.period_s = settings.period_s;
  return c;
}

}  // namespace

Controller::LoadedRobot Controller::load(const ControllerSettings& settings) {
  Model model = Model::from_urdf_file(settings.urdf_path, model_options(settings));
  ActuatorTable actuators = ActuatorTable::from_yaml_file(settings.actuators_path);
  std::optional<CollisionModel> collision;
  if (!settings.collision_path.empty()) collision = CollisionModel::from_yaml_file(settings.collision_path, model);
  return {std::move(model), std::move(actuators), std::move(collision), settings.actuators_path};
}

Controller::Controller(const ControllerSettings& settings) : Controller(load(settings), settings) {}

Controller::Controller(Model model, ActuatorTable actuators, std::optional<CollisionModel> collision,
                       const ControllerSettings& settings)
    : Controller(LoadedRobot{std::move(model), std::move(actuators), std::move(collision), "ActuatorTable"}, settings) {}

Controller::Controller(LoadedRobot robot, const ControllerSettings& settings)
    : settings_(checked(settings)),
      model_(std::move(robot.model)),
      data_(model_),
      actuators_(checked(robot.actuators, model_, robot.actuators_source)),
      collision_(std::move(robot.collision)),
      qp_(model_, collision_ ? &*collision_ : nullptr, qp_settings(settings, actuators_)),
      compliance_(settings.compliance),
      observer_(model_, settings.observer_gain),
      wrench_(settings.wrench),
      low_level_(actuators_, custom_torque_settings(settings), settings.initial_loop),
      end_effector_frame_(model_.frame_id(settings.end_effector_frame)),
      sensor_frame_(model_.frame_id("ft_sensor")),
      q_(Eigen::VectorXd::Zero(model_.nq())),
      qd_(Eigen::VectorXd::Zero(model_.nv())),
      ee_jacobian_(Eigen::MatrixXd::Zero(6, model_.nv())),
      ft_torque_(Eigen::VectorXd::Zero(model_.nv())),
      tau_ext_(Eigen::VectorXd::Zero(model_.nv())),
      trigger_filter_(settings.wrench_trigger_filter_s, settings.period_s),
      ft_fusion_(model_.nv(), settings.observer_gain, settings.period_s),
      no_targets_(model_.nv()) {}

namespace {
bool usable(const PostureReference& r, int nv) {
  return r.q.size() == nv && r.qd.size() == nv && r.qdd.size() == nv && r.q.allFinite() && r.qd.allFinite() &&
         r.qdd.allFinite();
}
bool usable(const PoseReference& r) {
  return r.pose.matrix().allFinite() && r.velocity.allFinite() && r.acceleration.allFinite();
}
}  // namespace

// Each target is checked where it enters; a bad one is ignored (the previous one stays) and
// counted, never passed on to the QP. Returns false when one was ignored.
bool Controller::apply(const ControllerTargets& targets) {
  const long rejected_before = rejected_targets_;
  auto accept = [&](bool ok) {
    if (!ok) ++rejected_targets_;
    return ok;
  };
  if (targets.stiffness_scale && accept(*targets.stiffness_scale > 0.0 && std::isfinite(*targets.stiffness_scale))) {
    compliance_.set_stiffness_scale(*targets.stiffness_scale, qp_);
  }
  if (targets.has_posture && accept(usable(targets.posture, model_.nv()))) {
    qp_.posture().set_target(targets.posture.q, targets.posture.qd, targets.posture.qdd);
  }
  if (targets.has_pose && accept(usable(targets.pose))) {
    qp_.end_effector().set_target(targets.pose.pose, targets.pose.velocity, targets.pose.acceleration);
  }
  if (targets.compliance_mode && accept(static_cast<int>(*targets.compliance_mode) >= 0 &&
                                        static_cast<int>(*targets.compliance_mode) < kComplianceModeCount)) {
    pending_mode_ = targets.compliance_mode;
  }
  if (targets.low_level_mode && accept(is_valid(*targets.low_level_mode))) low_level_.request(*targets.low_level_mode);
  return rejected_targets_ == rejected_before;
}

bool Controller::state_usable(const RobotState& state) {
  if (state.q_rad.size() != model_.nq() || state.qd_rad_s.size() != model_.nv() ||
      state.tau_sensor_Nm.size() != model_.nv() || !state.joints.valid || !state.torque.valid ||
      !state.q_rad.allFinite() || !state.qd_rad_s.allFinite() || !state.tau_sensor_Nm.allFinite() ||
      !state.current_A.allFinite()) {
    status_ = CycleStatus::kInvalidState;
    return false;
  }
  if (started_ && state.joints.sequence == last_joint_sequence_) {
    status_ = CycleStatus::kStaleState;
    return false;
  }
  return true;
}

// Model terms, momentum observer, F/T wrench at the end effector.
void Controller::estimate(const RobotState& state) {
  compute_all_terms(model_, data_, q_, qd_);
  coriolis_transpose_times_velocity(model_, data_);
  observer_.update(data_, qd_, state.tau_sensor_Nm, settings_.period_s);
  if (state.wrench.valid && state.wrench.sequence != last_wrench_sequence_) {
    last_wrench_sequence_ = state.wrench.sequence;
    const Eigen::Isometry3d& sensor = data_.frame_placements[static_cast<std::size_t>(sensor_frame_)];
    const Eigen::Isometry3d& ee = data_.frame_placements[static_cast<std::size_t>(end_effector_frame_)];
    wrench_.update(state.wrench_sensor, sensor, ee.translation());
  }
}

// tau_ext for the QP and the inverse dynamics, from the source the settings choose.
void Controller::select_external_torque() {
  if (settings_.external_torque_source == ExternalTorqueSource::kObserver) {
    tau_ext_ = observer_.external_torque();
    return;
  }
  // J^T of the operator's wrench at the end effector (world axes, about its origin).
  frame_jacobian(model_, data_, end_effector_frame_, ReferenceFrame::kLocalWorldAligned, ee_jacobian_);
  ft_torque_.noalias() = ee_jacobian_.transpose() * wrench_.wrench_world();
  if (settings_.external_torque_source == ExternalTorqueSource::kForceTorqueSensor) {
    tau_ext_ = ft_torque_;
  } else {
    // The paper's code: the F/T's fast part on top of the observer's (crossover at K_O).
    tau_ext_ = ft_fusion_.update(observer_.external_torque(), ft_torque_);
  }
}

CycleStatus Controller::step(const RobotState& state, const ControllerTargets& targets, RobotCommand& command) {
  const bool targets_accepted = apply(targets);
  if (!state_usable(state)) {
    ++held_cycles_;
    // The previous command stays in `command`; before any, hold the measured pose if possible.
    if (!have_command_ && state.q_rad.size() == model_.nq() && state.q_rad.allFinite()) {
      command.mode = LowLevelMode::kPosition;
      command.q_rad = state.q_rad;
    }
    return status_;
  }
  last_joint_sequence_ = state.joints.sequence;
  q_ = state.q_rad;
  qd_ = state.qd_rad_s;
  estimate(state);

  // ---- modes and targets
  if (!started_) {
    started_ = true;
    qp_.posture().set_target(q_);
    compliance_.initialise(settings_.initial_compliance, qp_, data_);
  }
  if (pending_mode_) {
    compliance_.set_mode(*pending_mode_, qp_, data_);
    pending_mode_.reset();
  }
  // The trigger sees the wrench norm through a short low-pass (settings.wrench_trigger_filter_s):
  // single-sample spikes of the F/T signal (tool inertia during stick-slip jolts, noise) must not
  // free the end effector for a few milliseconds.
  compliance_.update(trigger_filter_.update(wrench_.calibrated() ? wrench_.norm() : 0.0), qp_, data_);

  // ---- QP and inverse dynamics. Under the robot's position loop the external torque is not fed
  // back: the stiff servo rejects it and the observer would only see servo effort.
  select_external_torque();
  if (low_level_.requested() == LowLevelMode::kPosition) tau_ext_.setZero();
  const WholeBodyQpStatus qp_status = qp_.update(model_, data_, q_, qd_, tau_ext_, settings_.period_s);

  // ---- low level
  low_level_.update(state, qp_.desired_torque(), qp_.desired_acceleration(), command);
  have_command_ = true;
  status_ = qp_status != WholeBodyQpStatus::kOk ? CycleStatus::kQpFallback
            : targets_accepted                 ? CycleStatus::kOk
                                               : CycleStatus::kTargetsRejected;
  return status_;
}

}  // namespace phri
