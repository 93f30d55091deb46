#include <phri/control/controller.hpp>

#include <phri/control/constraint_registry.hpp>
#include <phri/control/task_registry.hpp>

#include <phri/control/torque_guards.hpp>
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <limits>

namespace phri {

namespace {
// What the controller may ask of a drive beyond the QP's torque limit (the guards, the safe stop's
// brake): this fraction of its peak torque. The rest is K_T's spread (5 % on the plant): the robot
// refuses a torque beyond its own peak and keeps the last accepted one; 0.9 left the brake no reach
// on the Gen3's large joints (QP limit 95 N.m, peak 105) (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 31337).
constexpr double kDriveReach = 0.94;

void require_end_effector_frame(const ControllerSettings& settings) {
  if (settings.end_effector_frame.empty()) {
    throw ConfigError("ControllerSettings", "end_effector_frame", "empty: name the end-effector frame (a robot bundle's frames.end_effector)");
  }
}

// The F/T estimator removes the tool's weight under the model's gravity (one gravity per run).
WrenchEstimatorSettings wrench_settings(const ControllerSettings& settings, const Model& model) {
  WrenchEstimatorSettings w = settings.wrench;
  w.gravity = model.gravity();
  return w;
}
}  // namespace

ModelOptions Controller::model_options(const ControllerSettings& settings) {
  require_end_effector_frame(settings);
  ModelOptions options;
  options.base_link = settings.base_link;
  options.tip_link = settings.tip_link;
  options.locked_joints = settings.locked_joints;
  options.gravity = settings.gravity_m_s2;
  options.base_placement = settings.base_placement;
  ExtraFrame sensor;
  sensor.name = "ft_sensor";
  sensor.parent_frame = settings.end_effector_frame;
  sensor.placement = settings.ft_sensor_mount;
  options.extra_frames.push_back(sensor);
  for (Payload payload : settings.payloads) {
    if (payload.frame.empty()) payload.frame = settings.end_effector_frame;  // default: the end effector
    options.payloads.push_back(payload);
  }
  return options;
}

std::optional<CollisionModel> Controller::collision_model(const ControllerSettings& settings, const Model& model) {
  if (!settings.collision_yaml.empty()) return CollisionModel::from_yaml_string(settings.collision_yaml, model, "fitted capsules");
  if (settings.collision_path.empty()) return std::nullopt;
  return CollisionModel::from_yaml_file(settings.collision_path, model);
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
      qp.compliance_deadband[i] =
          actuators[i].default_compliance_deadband_Nm(settings.deadband_large_Nm, settings.deadband_small_Nm);
    }
  }
  if (qp.power_force_limit && qp.rotor_inertia.size() == 0) {
    qp.rotor_inertia.resize(actuators.size());
    for (int i = 0; i < actuators.size(); ++i) qp.rotor_inertia[i] = actuators[i].reflected_inertia_kgm2;
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
  if (!settings.offered_loops.contains(settings.initial_loop)) {
    throw ConfigError("ControllerSettings", "initial_loop",
                      "'" + std::string(to_string(settings.initial_loop)) + "' is not a loop the robot's drives offer (" +
                          settings.offered_loops.names() + ")");
  }
  // The discrete observer r_k = K_O (p_k - p_0 - sum T (... + r_{k-1})) has the pole 1 - K_O T:
  // unstable for K_O T >= 2, ringing above 1.
  if (!(settings.observer_gain > 0 && settings.observer_gain * settings.period_s < 1.0)) {
    throw ConfigError("ControllerSettings", "observer_gain",
                      "must be > 0 and < 1 / period_s (" + std::to_string(1.0 / settings.period_s) +
                          "): the discrete observer's pole 1 - K_O T must stay in (0, 1)");
  }
  if (!(settings.observer_release_gain >= 0 && settings.observer_release_gain * settings.period_s < 1.0 &&
        settings.observer_release_threshold_Nm >= 0 && settings.observer_release_speed_fraction >= 0)) {
    throw ConfigError("ControllerSettings", "observer_release_gain",
                      "must be >= 0 and < 1 / period_s, with a threshold and a speed fraction >= 0 (the same pole as observer_gain)");
  }
  // The sensor's frame on the end effector (the wrench estimator reads through it): rigid, finite.
  const Eigen::Isometry3d& mount = settings.ft_sensor_mount;
  if (!mount.matrix().allFinite() || !(mount.linear().transpose() * mount.linear()).isIdentity(1e-9)) {
    throw ConfigError("ControllerSettings", "ft_sensor_mount", "must be finite, its linear part a rotation");
  }
  const SafetySettings& safety = settings.safety;
  if (!(safety.max_qp_fallback_s >= 0 && safety.brake_rate > 0 && safety.handover_speed_rad_s > 0 &&
        safety.requested_stop_blend_s >= 0 && safety.requested_stop_blend_s <= 1.0 &&
        safety.max_brake_s > 0 && safety.max_hold_refusals >= 1 && safety.velocity_guard_fraction > 0 && safety.velocity_guard_fraction <= 1.5 &&
        safety.velocity_guard_rate >= 0 && safety.limit_guard_stiffness_Nm_per_rad >= 0 &&
        safety.collision_guard_stiffness_N_per_m >= 0 && safety.collision_guard_damping_Ns_per_m >= 0 &&
        safety.external_torque_bound_factor > 0)) {
    throw ConfigError("ControllerSettings", "safety", "rates, speeds and times must be > 0 (guard fraction <= 1.5)");
  }
  if (!(settings.wrench_trigger_filter_s >= 0)) throw ConfigError("ControllerSettings", "wrench_trigger_filter_s", "must be >= 0");
  require_end_effector_frame(settings);
  return settings;
}

// What the drives and sensors can report: the URDF range, the drives' limits.
SensorRanges sensor_ranges(const Model& model, const ActuatorTable& actuators) {
  const int n = model.nv();
  SensorRanges r;
  r.q_lower = model.lower_limits();
  r.q_upper = model.upper_limits();
  for (Eigen::VectorXd* v : {&r.velocity_limit, &r.torque_range, &r.current_range, &r.torque_per_amp, &r.reflected_inertia,
                             &r.friction_static, &r.friction_coulomb, &r.friction_viscous, &r.transmission_compliance}) {
    v->resize(n);
  }
  for (int i = 0; i < n; ++i) {
    if (!model.joint(i).has_position_limits()) {
      r.q_lower[i] = -std::numeric_limits<double>::infinity();
      r.q_upper[i] = std::numeric_limits<double>::infinity();
    }
    const ActuatorParameters& a = actuators[i];
    r.velocity_limit[i] = a.velocity_limit_rad_s;
    r.torque_range[i] = std::max(a.max_motor_torque_Nm(), a.torque_limit_Nm);
    r.current_range[i] = a.current_limit_A;
    r.torque_per_amp[i] = a.torque_per_amp();
    r.reflected_inertia[i] = a.reflected_inertia_kgm2;
    r.friction_static[i] = a.friction.static_Nm;
    r.friction_coulomb[i] = a.friction.coulomb_Nm;
    r.friction_viscous[i] = a.friction.viscous_Nms_per_rad;
    r.transmission_compliance[i] = a.transmission_stiffness_Nm_per_rad > 0 ? 1.0 / a.transmission_stiffness_Nm_per_rad : 0.0;
  }
  return r;
}

SupervisorSettings supervisor_settings(const ControllerSettings& settings) {
  SupervisorSettings s = settings.safety.supervisor;
  s.period_s = settings.period_s;
  return s;
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
  collision = collision_model(settings, model);
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
      compliance_(with_main_task_stiffness(settings.compliance, settings.tasks)),
      leash_(model_, model_.frame_id(settings.end_effector_frame), settings.compliance.return_leash),
      observer_(model_, settings.observer_gain),
      wrench_(wrench_settings(settings, model_)),
      low_level_(actuators_, custom_torque_settings(settings), settings.initial_loop),
      supervisor_(sensor_ranges(model_, actuators_), supervisor_settings(settings)),
      wrench_supervisor_(settings.safety.wrench, settings.period_s, settings.observer_gain, model_.nv()),
      end_effector_frame_(model_.frame_id(settings.end_effector_frame)),
      sensor_frame_(model_.frame_id("ft_sensor")),
      q_(Eigen::VectorXd::Zero(model_.nq())),
      qd_(Eigen::VectorXd::Zero(model_.nv())),
      ee_jacobian_(Eigen::MatrixXd::Zero(6, model_.nv())),
      ft_torque_(Eigen::VectorXd::Zero(model_.nv())),
      tau_ext_(Eigen::VectorXd::Zero(model_.nv())),
      tau_ext_fast_(Eigen::VectorXd::Zero(model_.nv())),
      uncancelled_(Eigen::VectorXd::Zero(model_.nv()), Eigen::VectorXd(), settings.period_s),
      qdd_sent_(Eigen::VectorXd::Zero(model_.nv())),
      sent_change_(Eigen::VectorXd::Zero(model_.nv())),
      trigger_filter_(settings.wrench_trigger_filter_s, settings.period_s),
      estimate_torque_(Eigen::VectorXd::Zero(model_.nv())),
      ft_fusion_(model_.nv(), settings.observer_gain, settings.period_s),
      no_targets_(model_.nv()),
      hold_q_(Eigen::VectorXd::Zero(model_.nv())),
      hold_qd_(Eigen::VectorXd::Zero(model_.nv())),
      acceleration_(Eigen::VectorXd::Zero(model_.nv())),
      filtered_qd_(Eigen::VectorXd::Zero(model_.nv())),
      brake_q_(Eigen::VectorXd::Zero(model_.nv())),
      brake_qd_(Eigen::VectorXd::Zero(model_.nv())),
      brake_tau_(Eigen::VectorXd::Zero(model_.nv())),
      stop_entry_tau_(Eigen::VectorXd::Zero(model_.nv())),
      guarded_tau_(Eigen::VectorXd::Zero(model_.nv())),
      limit_lower_(supervisor_.ranges().q_lower),
      limit_upper_(supervisor_.ranges().q_upper),
      torque_limit_(qp_.torque_limit()),
      drive_velocity_limit_(supervisor_.ranges().velocity_limit),
      reflected_inertia_(Eigen::VectorXd::Zero(model_.nv())),
      static_friction_(Eigen::VectorXd::Zero(model_.nv())),
      drive_torque_(supervisor_.ranges().torque_range),
      guard_excess_(Eigen::VectorXd::Zero(model_.nv())),
      guard_damping_(Eigen::VectorXd::Zero(model_.nv())),
      collision_guard_(Eigen::VectorXd::Zero(model_.nv())),
      guard_inertia_(Eigen::MatrixXd::Zero(model_.nv(), model_.nv())),
      guard_mobility_(Eigen::MatrixXd::Zero(model_.nv(), model_.nv())),
      guard_llt_(model_.nv()) {
  observer_.set_release_path(settings.observer_release_gain, settings.observer_release_threshold_Nm,
                             settings.observer_release_speed_fraction * drive_velocity_limit_);
  for (int i = 0; i < model_.nv(); ++i) {
    reflected_inertia_[i] = actuators_[i].reflected_inertia_kgm2;
    static_friction_[i] = std::max(actuators_[i].friction.static_Nm, actuators_[i].friction.coulomb_Nm);
  }
  uncancelled_ = UncancelledPush(reflected_inertia_, supervisor_.ranges().transmission_compliance, settings.period_s);
  // The uncancelled push's M + B, factored with M in compute_all_terms (one pass for both).
  if (settings.observer_release_gain > 0.0) data_.rotor_inertia = reflected_inertia_;
  add_declared_tasks(settings.tasks);
  add_declared_constraints(settings.constraints);
}

// The run's declared constraints, after the paper's safety constraints.
void Controller::add_declared_constraints(const std::vector<TaskSpec>& specs) {
  const ConstraintBuildContext context{model_, end_effector_frame_};
  for (const TaskSpec& spec : specs) qp_.add_constraint(make_constraint(spec, context));
}

// The run's declared tasks: the paper's two configured, the others built and added to the QP.
void Controller::add_declared_tasks(const std::vector<TaskSpec>& specs) {
  const TaskBuildContext context{model_, end_effector_frame_, settings_.qp.smoothing_time_constant};
  for (const TaskSpec& spec : specs) {
    if (spec.name == "end_effector") {
      configure_main_task(spec, qp_.end_effector());
    } else if (spec.name == "posture") {
      configure_posture_task(spec, qp_.posture());
    } else {
      qp_.add_task(make_task(spec, context));
    }
  }
}

ComplianceSettings Controller::with_main_task_stiffness(ComplianceSettings compliance, const std::vector<TaskSpec>& specs) {
  for (const TaskSpec& spec : specs) {
    if (spec.name == "end_effector" && spec.has("stiffness")) {
      compliance.ee_axis_stiffness = spec.six("stiffness", Vector6d::Zero(), 0.0, 1e4);
    }
  }
  return compliance;
}

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
  auto finite_or_empty = [](const std::optional<double>& v) { return !v || std::isfinite(*v); };
  if ((targets.ee_gamma || targets.posture_gamma || targets.posture_stiffness) &&
      accept(finite_or_empty(targets.ee_gamma) && finite_or_empty(targets.posture_gamma) &&
             finite_or_empty(targets.posture_stiffness))) {
    compliance_.set_live_gains(targets.ee_gamma, targets.posture_gamma, targets.posture_stiffness, qp_);
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
  // A loop the drives do not offer is refused like an invalid one: the running loop stays.
  if (targets.low_level_mode && accept(settings_.offered_loops.contains(*targets.low_level_mode))) {
    low_level_.request(*targets.low_level_mode);
  }
  return rejected_targets_ == rejected_before;
}

// Model terms, momentum observer, F/T wrench at the end effector.
void Controller::estimate(const RobotState& state, double dt) {
  ft_torque_current_ = false;
  compute_all_terms(model_, data_, q_, qd_);  // C^T qd for the observer included
  observer_.update(data_, qd_, state.tau_sensor_Nm, dt);
  estimate_wrench(state);
  if (settings_.position_mode_open_loop && low_level_.integrating_position()) {
    // The paper's position mode: from here on the cycle sees its own integrated state, not the
    // arm (the estimates above used the measurements).
    q_ = low_level_.position_reference();
    qd_ = low_level_.velocity_reference();
    compute_all_terms(model_, data_, q_, qd_);
    ft_torque_current_ = false;
  }
}

// The F/T wrench, once the WrenchSupervisor found the sample plausible; then J^T F against the
// observer. A dropped source leaves the estimate at zero (the trigger released, the hand's pose the
// target, as when a hand lets go) and select_external_torque() on the observer.
void Controller::estimate_wrench(const RobotState& state) {
  if (state.wrench.valid) ft_seen_ = true;  // a sensorless plant may still count samples: validity decides
  if (!ft_seen_) {
    estimate_wrench_from_observer();
    return;
  }
  if (wrench_supervisor_.check(state, qd_, observer_.external_torque())) {
    const Eigen::Isometry3d& sensor = data_.frame_placements[static_cast<std::size_t>(sensor_frame_)];
    const Eigen::Isometry3d& ee = data_.frame_placements[static_cast<std::size_t>(end_effector_frame_)];
    // Each axis through a median of its last three samples: a single-sample spike of any size
    // (a corrupted frame, a jolt of the tool) never reaches the estimate or the touch trigger.
    for (int i = 0; i < 6; ++i) {
      const double x = state.wrench_sensor[i], p = wrench_history_(i, 0), pp = wrench_history_(i, 1);
      wrench_median_[i] = std::max(std::min(p, pp), std::min(std::max(p, pp), x));
      wrench_history_(i, 1) = p;
      wrench_history_(i, 0) = x;
    }
    if (wrench_samples_ < 2) wrench_median_ = state.wrench_sensor;  // not three samples yet
    ++wrench_samples_;
    wrench_.update(wrench_median_, sensor, ee.translation());
  }
  if (wrench_supervisor_.usable() && wrench_.calibrated()) {
    frame_jacobian(model_, data_, end_effector_frame_, ReferenceFrame::kLocalWorldAligned, ee_jacobian_);
    ft_torque_.noalias() = ee_jacobian_.transpose() * wrench_.wrench_world();
    ft_torque_current_ = true;
    wrench_supervisor_.check_consistency(ft_torque_, observer_.external_torque());
  }
  if (wrench_supervisor_.dropped() && !wrench_cleared_) {
    wrench_cleared_ = true;
    wrench_.recalibrate();  // zero estimate; a reset source would re-estimate the bias
    wrench_history_.setZero();
    wrench_samples_ = 0;
    ft_torque_.setZero();
    ft_torque_current_ = false;
  }
}

// Without an F/T sensor: the operator's wrench at the end effector from the observer's tau_ext,
// the least-squares solution of J^T F = tau_ext, F = (J J^T)^-1 J tau_ext. tau_ext first loses the
// compliance dead band per joint (soft threshold): the observer's bias from model error (5 % of
// the link inertials on the plant) would otherwise read as a standing wrench of several newtons.
// Joint torques cannot tell a hand on the tool from one elsewhere on the arm: on a 6-DoF arm every
// push maps onto some end-effector wrench (a redundant arm's null-space part is left out).
// Fixed-size 6x6 algebra: allocation-free.
void Controller::estimate_wrench_from_observer() {
  const Eigen::VectorXd& tau = observer_.external_torque();
  const Eigen::VectorXd& band = qp_.compliance_deadband();
  for (Eigen::Index i = 0; i < tau.size(); ++i) {
    const double excess = std::abs(tau[i]) - (i < band.size() ? band[i] : 0.0);
    estimate_torque_[i] = excess > 0.0 ? std::copysign(excess, tau[i]) : 0.0;
  }
  frame_jacobian(model_, data_, end_effector_frame_, ReferenceFrame::kLocalWorldAligned, ee_jacobian_);
  Eigen::Matrix<double, 6, 6> jjt;
  Vector6d jtau;
  for (int r = 0; r < 6; ++r) {
    jtau[r] = ee_jacobian_.row(r).dot(estimate_torque_);
    for (int c = r; c < 6; ++c) jjt(r, c) = jjt(c, r) = ee_jacobian_.row(r).dot(ee_jacobian_.row(c));
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix<double, 6, 6>> eig(jjt);
  const Vector6d& lambda = eig.eigenvalues();  // ascending
  const double largest = lambda[5];
  if (!(largest > 0.0) || !std::isfinite(largest)) {
    estimated_wrench_.setZero();
    estimated_condition_ = std::numeric_limits<double>::infinity();
    return;
  }
  const double floor = 1e-6 * largest;
  Vector6d projected = eig.eigenvectors().transpose() * jtau;
  for (int k = 0; k < 6; ++k) projected[k] = lambda[k] > floor ? projected[k] / lambda[k] : 0.0;
  estimated_wrench_ = eig.eigenvectors() * projected;
  estimated_condition_ = lambda[0] > floor ? std::sqrt(largest / lambda[0]) : std::numeric_limits<double>::infinity();
}

// tau_ext for the QP and the inverse dynamics, from the source the settings choose.
void Controller::select_external_torque() {
  // An F/T not fresh or dropped: the observer alone (a bad wrench must never drive the arm).
  if (settings_.external_torque_source == ExternalTorqueSource::kObserver || !wrench_supervisor_.fresh()) {
    tau_ext_ = observer_.external_torque();
    return;
  }
  // J^T of the operator's wrench at the end effector (world axes, about its origin), unless
  // estimate_wrench() computed it on the same model terms.
  if (!ft_torque_current_) {
    frame_jacobian(model_, data_, end_effector_frame_, ReferenceFrame::kLocalWorldAligned, ee_jacobian_);
    ft_torque_.noalias() = ee_jacobian_.transpose() * wrench_.wrench_world();
  }
  if (settings_.external_torque_source == ExternalTorqueSource::kForceTorqueSensor) {
    tau_ext_ = ft_torque_;
  } else {
    // The paper's code: the F/T's fast part on top of the observer's (crossover at K_O).
    tau_ext_ = ft_fusion_.update(observer_.external_torque(), ft_torque_);
  }
}

// The push the command does not cancel yet, from the observer's fast estimate and the motion (the
// safety bounds hold for it too): in torque loops with the release path on. True when estimated.
bool Controller::estimate_uncancelled_push(bool torque_loop, bool commanded_last, double dt) {
  if (!torque_loop || !(settings_.observer_release_gain > 0.0)) {
    uncancelled_.forget();
    return false;
  }
  tau_ext_fast_ = observer_.fast_external_torque();
  bound_external_torque(tau_ext_fast_);
  // After missed periods the arm ran on a held command, and the fast observer's step (gain x dt)
  // overshoots: no motion evidence across a gap.
  const bool one_period = dt <= 1.5 * settings_.period_s;
  uncancelled_.update(data_, tau_ext_, tau_ext_fast_, qd_, commanded_last && one_period ? &qdd_sent_ : nullptr, dt);
  return true;
}

// The acceleration the command sent asks of the arm: the QP's qdd_d, plus (M + B)^-1 of what the
// guards and the clamps changed in its torque. The motion is measured against it: a brake the
// guard added, or a command cut at its torque limit, is the command's own doing, not a push.
void Controller::note_sent_acceleration() {
  qdd_sent_ = qp_.desired_acceleration();
  if (guarded_tau_ == qp_.desired_torque() || data_.rotor_inertia.size() == 0 || !data_.mass_matrix_with_rotors_llt.ok()) {
    return;
  }
  sent_change_ = guarded_tau_ - qp_.desired_torque();
  data_.mass_matrix_with_rotors_llt.solve_in_place(sent_change_);
  qdd_sent_ += sent_change_;
}

// Keeps the previous command while the supervisor holds the last good state (bounded: it turns
// into a safe stop after max_degraded_s). Before any command: the robot's hold at the measured pose.
void Controller::hold_previous(const RobotState& state, RobotCommand& command) {
  ++held_cycles_;
  const SafetyFault fault = supervisor_.sample_fault();
  status_ = fault == SafetyFault::kStale || fault == SafetyFault::kStampFrozen || fault == SafetyFault::kFrozenValues
                ? CycleStatus::kStaleState
                : CycleStatus::kInvalidState;
  if (!have_command_ && state.q_rad.size() == model_.nq() && state.q_rad.allFinite() &&
      command.q_rad.size() == model_.nq()) {
    command.mode = LowLevelMode::kPosition;
    command.q_rad = state.q_rad;
  }
}

// The latched safe stop, designed for a moving arm. The robot's position hold at once, its
// reference braking from where the arm is and how it moves (brake_state()), kept within the
// following bound of it. After a QP failure under a push, or a stop the robot asked for, in the
// torque and current loops: gravity compensation with joint damping on the brake's state (after a
// QP failure also -tau_ext while the samples stay good; a requested stop blended in from the last
// command), then, at rest or after max_brake_s, the hand-over to the hold there.
void Controller::safe_stop(bool sample_good, RobotCommand& command) {
  status_ = CycleStatus::kSafeStop;
  const SafetySettings& s = settings_.safety;
  brake_state();
  if (safe_stop_cycles_++ == 0) {
    const bool position_loop = have_command_ && low_level_.loop() == LowLevelMode::kPosition;
    // The torque brake where the torque loop still serves: resisting a push the QP could not
    // answer, or a stop the robot asked for (blended in). Any other fault goes straight to the
    // robot's position hold, its reference braking from the arm's state: the robot's servo closes
    // on its own encoders (a sensor fault of ours does not reach it) and resists a hand that
    // keeps pushing, which a damping brake only slows down.
    const SafetyFault reason = supervisor_.safe_stop_transition().reason;
    const bool torque_brake = reason == SafetyFault::kQpFailure || reason == SafetyFault::kRobotStopRequest;
    holding_ = !have_command_ || position_loop || !torque_brake || !supervisor_.has_kinematics();
    brake_against_push_ = !holding_ && reason == SafetyFault::kQpFailure;
    hold_q_ = supervisor_.has_kinematics() ? brake_q_ : q_;
    hold_qd_.setZero();
    if (holding_ && have_command_ && !position_loop && supervisor_.has_kinematics()) hold_from_brake_speed();
    stop_entry_tau_ = guarded_tau_;
    // In the position loop the reference brakes from where it is (kept within the following
    // error of the measured pose, LowLevelController): a jump to the measured pose, or a reference
    // stopped dead, is a step of kd x qd in the servo's torque (33 N.m with the arm at 0.8 rad/s).
    if (position_loop) {
      hold_q_ = low_level_.position_reference();
      hold_qd_ = low_level_.velocity_reference();
    }
  }
  if (holding_) {
    brake_reference();
    keep_hold_acceptable();
    low_level_.hold(hold_q_, command);
    return;
  }
  const bool at_rest = brake_qd_.cwiseAbs().maxCoeff() < s.handover_speed_rad_s;
  if (at_rest || static_cast<double>(safe_stop_cycles_) * settings_.period_s > s.max_brake_s) {
    holding_ = true;
    hold_q_ = brake_q_;
    low_level_.hold(hold_q_, command);
    return;
  }
  // A push the QP could not answer goes on being resisted (see step()); after a sensor fault the
  // estimate is not trusted (a phantom push would be driven).
  if (!sample_good) brake_against_push_ = false;
  brake_tau_.setZero();  // zero velocity: data_.nonlinear_effects = g(q)
  compute_all_terms(model_, data_, brake_q_, brake_tau_);
  for (int i = 0; i < model_.nv(); ++i) {
    const double inertia = data_.mass_matrix(i, i) + reflected_inertia_[i];
    // Gravity (and the push) up to what the drive gives (the arm must not fall, whatever the QP's
    // limit), the damping within the QP's torque limit.
    const double damping = std::clamp(-s.brake_rate * inertia * brake_qd_[i], -torque_limit_[i], torque_limit_[i]);
    const double push = brake_against_push_ ? tau_ext_[i] : 0.0;
    const double reach = std::max(torque_limit_[i], kDriveReach * drive_torque_[i]);
    brake_tau_[i] = std::clamp(data_.nonlinear_effects[i] - push + damping, -reach, reach);
  }
  // A stop the robot asked for: blended in from the last command (the emergencies brake at once).
  if (supervisor_.safe_stop_transition().reason == SafetyFault::kRobotStopRequest && s.requested_stop_blend_s > 0.0) {
    const double share = std::min(1.0, static_cast<double>(safe_stop_cycles_) * settings_.period_s / s.requested_stop_blend_s);
    brake_tau_ = share * brake_tau_ + (1.0 - share) * stop_entry_tau_;
  }
  low_level_.command_torque(brake_tau_, command);
}

// The state the brake works on: the measured joints while their part of the sample is plausible
// (also when only τ_s or the current is wrong); while it is not, a bounded prediction from the last
// plausible one. Up to the stop the robot ran on the previous torque command (a missing sample, a
// stalled thread): the arm coasts on at its recent acceleration, its speed within the larger of the
// drive's limit and its own; from the stop on it decelerates at brake_rate as the brake makes it:
// q + q̇ (1 - e^(-r t)) / r, within the joint limits. Never a stale velocity repeated for longer than
// the data lasted, nor a brake assumed before there was one (the hold's reference would start behind
// the arm and the servo would yank it back).
void Controller::brake_state() {
  if (!supervisor_.has_kinematics()) return;
  const double rate = settings_.safety.brake_rate;
  const double age_s = kinematics_age_s();
  if (supervisor_.kinematics_fresh()) {
    coast_s_ = 0.0;
  } else if (safe_stop_cycles_ == 0) {
    const bool torque_command = have_command_ && low_level_.loop() != LowLevelMode::kPosition;
    coast_s_ = torque_command ? age_s : 0.0;
  }
  const double coast = std::min(coast_s_, age_s);
  const double decay = std::exp(-rate * (age_s - coast));
  const Eigen::VectorXd& q = supervisor_.kinematic_q();
  const Eigen::VectorXd& qd = supervisor_.kinematic_qd();
  for (int i = 0; i < model_.nv(); ++i) {
    const double bound = std::max(std::abs(qd[i]), drive_velocity_limit_[i]);
    const double coasted_qd = std::clamp(qd[i] + coast * acceleration_[i], -bound, bound);
    const double coasted_q = q[i] + 0.5 * (qd[i] + coasted_qd) * coast;
    brake_q_[i] = std::clamp(coasted_q + (1.0 - decay) / rate * coasted_qd, limit_lower_[i], limit_upper_[i]);
    brake_qd_[i] = decay * coasted_qd;
  }
}

// Steps since the last plausible kinematics, or the robot's time since them when longer (a
// stalled control thread runs no steps): by the stamps and by the sequence, whichever says less
// (one of them may have jumped; an age too long would put the hold's reference ahead of the arm).
double Controller::kinematics_age_s() const {
  const double by_sequence =
      static_cast<double>(static_cast<std::uint32_t>(stop_sequence_ - supervisor_.kinematic_sequence())) * settings_.period_s;
  const double by_clock = std::clamp(std::min(stop_stamp_s_ - supervisor_.kinematic_stamp(), by_sequence), 0.0, 1.0);
  return std::max(static_cast<double>(cycles_since_good_) * settings_.period_s, by_clock);
}

// The hold's reference within the position loop's following bound of where the arm is (the
// brake's state): the robot refuses a set-point further away, and keeps its last command then.
void Controller::keep_hold_acceptable() {
  if (!supervisor_.has_kinematics()) return;
  const double bound = low_level_.following_error();
  for (int i = 0; i < model_.nv(); ++i) {
    const double error = hold_q_[i] - brake_q_[i];
    if (std::abs(error) <= bound) continue;
    hold_q_[i] = brake_q_[i] + std::copysign(bound, error);
    hold_qd_[i] = 0.0;
  }
}

bool Controller::answer_refused_write(const RobotState& state, RobotCommand& command) {
  supervisor_.report(SafetyFault::kWriteRefused, state.time_s);
  refusals_in_row_ = refused_step_ >= steps_ - 1 ? refusals_in_row_ + 1 : 1;
  refused_step_ = steps_;
  if (refusals_in_row_ > settings_.safety.max_hold_refusals) {
    supervisor_.report(SafetyFault::kHoldRefused, state.time_s);
  }
  if (safe_stop_cycles_ == 0) {  // the stop starts now, from this cycle's state
    safe_stop(supervisor_.kinematics_fresh(), command);
    return true;
  }
  // Refused during the stop: hold from where the arm is, braking on from how it moves (a reference
  // stopped dead would slam the servo into the arm once writes pass again). The robot's own
  // reading of its joints, when finite and within the joint range, is the nearest pose it
  // accepts, even in a sample the supervisor rejected for another signal.
  holding_ = true;
  hold_from_brake_speed();
  hold_q_ = brake_q_;
  if (state.q_rad.size() == model_.nq() && state.q_rad.allFinite() &&
      (state.q_rad.array() >= limit_lower_.array()).all() && (state.q_rad.array() <= limit_upper_.array()).all()) {
    hold_q_ = state.q_rad;
  }
  low_level_.hold(hold_q_, command);
  return true;
}

// A sample the supervisor did not pass. At the velocity guard (velocity_guard_fraction of the
// drive's limit, where the QP's velocity bound holds the arm against a hand) the torque loops'
// command is a balance against that hand, shaped from the measured speed; repeated blind it is no
// brake (a hand pulling at the tool took the arm from 0.9x to 1.2x its limit within the 20 ms
// budget). A sample whose joints are plausible (its torque or current is not) stops at once where
// their velocity, carried on at the recent acceleration over the budget, reaches the guard: the
// hold then brakes from the measured state (a hand on the tool took a wrist joint from 0.83x to
// 1.08x in the 20 ms of an infinite torque reading). A missing sample does the same with
// stop_missed_at_speed. Elsewhere, and after a gap already beyond the budget (a stall: the next
// samples re-synchronise and the supervisor's stop brakes on them), the previous command stands in
// (hold_previous()).
void Controller::missing_sample(const RobotState& state, RobotCommand& command) {
  const double budget = supervisor_.settings().max_degraded_s;
  const bool judge_speed =
      supervisor_.kinematics_fresh() || (settings_.safety.stop_missed_at_speed && kinematics_age_s() <= budget);
  if (judge_speed && have_command_ && low_level_.loop() != LowLevelMode::kPosition && supervisor_.has_kinematics() &&
      ((supervisor_.kinematic_qd() + budget * acceleration_).cwiseAbs().array() >=
       settings_.safety.velocity_guard_fraction * drive_velocity_limit_.array()).any()) {
    supervisor_.report(SafetyFault::kMissedAtSpeed, state.time_s);
    safe_stop(false, command);
    return;
  }
  hold_previous(state, command);
}

// The joints' recent acceleration for missing_sample(): the rate of the velocity low-passed over
// 10 ms (a raw difference of 1 kHz velocities is mostly noise).
void Controller::track_acceleration(const Eigen::VectorXd& qd, double dt) {
  const double alpha = dt / (0.01 + dt);
  for (int i = 0; i < model_.nv(); ++i) {
    const double previous = filtered_qd_[i];
    filtered_qd_[i] += alpha * (qd[i] - filtered_qd_[i]);
    acceleration_[i] = (filtered_qd_[i] - previous) / dt;
  }
}

// The held reference moves on at the brake's speed, never faster than the drive's limit: a hand
// that took the arm past it while the robot ran on a refused or stale command is braked by the
// servo from there (a reference moving at the arm's 1.43x lagged behind the servo's damping, which
// pulled the arm forward again once writes passed).
void Controller::hold_from_brake_speed() {
  hold_qd_ = brake_qd_.cwiseMax(-drive_velocity_limit_).cwiseMin(drive_velocity_limit_);
}

// The held reference's velocity decays at brake_rate (as the torque loops' brake), the reference
// staying within the URDF limits; from rest (the other safe stops) it stays where it is.
void Controller::brake_reference() {
  const SafetySettings& s = settings_.safety;
  if (hold_qd_.cwiseAbs().maxCoeff() < s.handover_speed_rad_s) {
    hold_qd_.setZero();
    return;
  }
  hold_qd_ *= std::exp(-s.brake_rate * settings_.period_s);
  hold_q_ = (hold_q_ + settings_.period_s * hold_qd_).cwiseMax(limit_lower_).cwiseMin(limit_upper_);
}

// More than the joint's torque limit (times a factor) is not a push the controller can act on;
// and beyond a joint's safety distance d_s from its limit, the component of tau_ext pointing away
// from the limit may be the hard stop's reaction, not a hand: fed back, it would make tau_d press
// into the stop (the observer then reads the stop's answer as a push, and so on). It is dropped
// there. Not in the whole damper band d_i, where it could hide a hand pushing the joint out at speed
// (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 8642).
void Controller::bound_external_torque(Eigen::VectorXd& tau) const {
  for (int i = 0; i < model_.nv(); ++i) {
    const double bound = settings_.safety.external_torque_bound_factor * torque_limit_[i];
    double t = std::clamp(tau[i], -bound, bound);
    if (q_[i] > qp_.safe_upper()[i]) t = std::max(t, 0.0);
    if (q_[i] < qp_.safe_lower()[i]) t = std::min(t, 0.0);
    tau[i] = std::isfinite(t) ? t : 0.0;
  }
}

// The last lines behind the QP, on the torque (torque_guards.hpp):
// - velocity guard: damping rate x (M_ii + I_r) on the excess speed above velocity_guard_fraction
//   of the drive's limit, scaled down where joints that share an axis would make it ring
//   (guard_coupling_scale). It acts on the latest sample: a mean acts a cycle late on a step
//   (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 31337 full_body/custom/22);
// - limit guard: beyond a limit's safety distance d_s an outward torque of the joint's static
//   friction plus a spring on the depth (the damper's acceleration alone is below stiction, so a
//   joint could rest there);
// - collision guard: capsule pairs inside d_s pushed apart through their distance Jacobian. The
//   QP's damper asks the same through the acceleration, but the torque loops' tracking error can
//   let a pair through d_s under a strong push (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 4242 full_body/kinova_torque/21).
// A guard that acts may go beyond the QP's limit up to kDriveReach of the drive's peak torque.
void Controller::guard_torque(Eigen::VectorXd& tau) {
  // g <= 1.5 in guard_coupling_scale (replays measured before the QP's return gain): 1.0 left
  // joint 3 at 1.08x under a push near the elbow's straight posture (joints 3 and 5 aligned, seed
  // 60606, full_body/custom/23; 1.07x at 1.5); on the two-sample mean, 2.0 let joints 1 and 3 ring
  // again (1.04x on full_body/custom/0, against 1.007x at 1.5).
  constexpr double kGuardMaxStep = 1.5;
  const SafetySettings& s = settings_.safety;
  const int n = model_.nv();
  bool speeding = false;
  for (int i = 0; i < n; ++i) {
    guard_excess_[i] = std::max(std::abs(qd_[i]) - s.velocity_guard_fraction * drive_velocity_limit_[i], 0.0);
    guard_damping_[i] = s.velocity_guard_rate * (data_.mass_matrix(i, i) + reflected_inertia_[i]);
    speeding = speeding || guard_excess_[i] > 0.0;
  }
  double scale = 1.0;
  if (speeding) {
    guard_inertia_ = data_.mass_matrix;
    guard_inertia_.diagonal() += reflected_inertia_;
    if (guard_llt_.compute(guard_inertia_)) {
      guard_mobility_.setIdentity();
      guard_llt_.solve_in_place(guard_mobility_);
      scale = guard_coupling_scale(guard_mobility_, guard_damping_, guard_excess_, settings_.period_s, kGuardMaxStep);
    }
  }
  collision_guard_.setZero();
  if (const CollisionData* pairs = qp_.collision_data()) {
    add_collision_guard(*pairs, qp_.settings().collision.safety_distance, s.collision_guard_stiffness_N_per_m,
                        s.collision_guard_damping_Ns_per_m, collision_guard_);
  }
  for (int i = 0; i < n; ++i) {
    const double excess = guard_excess_[i];
    const double above = q_[i] - qp_.safe_upper()[i], below = qp_.safe_lower()[i] - q_[i];
    const double limit = excess > 0.0 || above > 0.0 || below > 0.0 || collision_guard_[i] != 0.0
                             ? std::max(torque_limit_[i], kDriveReach * drive_torque_[i])
                             : torque_limit_[i];
    if (excess > 0.0) tau[i] -= std::copysign(scale * guard_damping_[i] * excess, qd_[i]);
    if (above > 0.0) tau[i] -= static_friction_[i] + s.limit_guard_stiffness_Nm_per_rad * above;
    if (below > 0.0) tau[i] += static_friction_[i] + s.limit_guard_stiffness_Nm_per_rad * below;
    tau[i] += collision_guard_[i];
    tau[i] = std::clamp(tau[i], -limit, limit);
  }
}

// A QP that keeps failing leaves the arm on the fallback brake: after max_qp_fallback_s, a safe
// stop. So does an invalid input (non-finite estimate), at once.
void Controller::check_qp(WholeBodyQpStatus qp_status, double t) {
  if (qp_status == WholeBodyQpStatus::kInvalidInput) {
    supervisor_.report(SafetyFault::kQpFailure, t);
    return;
  }
  qp_fallbacks_in_row_ = solved(qp_status) ? 0 : qp_fallbacks_in_row_ + 1;
  if (static_cast<double>(qp_fallbacks_in_row_) * settings_.period_s > settings_.safety.max_qp_fallback_s) {
    supervisor_.report(SafetyFault::kQpFailure, t);
  }
}

// Start, pending mode change, dual compliance's touch trigger.
void Controller::update_modes_and_targets() {
  if (!started_) {
    started_ = true;
    qp_.start_tasks(model_, data_);
    qp_.posture().set_target(q_);
    compliance_.initialise(settings_.initial_compliance, qp_, data_);
    leash_.reset();
  }
  if (pending_mode_) {
    compliance_.set_mode(*pending_mode_, qp_, data_);
    pending_mode_.reset();
  }
  // The trigger sees the wrench norm through a short low-pass (settings.wrench_trigger_filter_s):
  // single-sample spikes of the F/T signal (tool inertia during stick-slip jolts, noise) must not
  // free the end effector for a few milliseconds.
  // A wrench that is not fresh (WrenchSupervisor::fresh: stuck or stale beyond a few of the
  // sensor's periods, or dropped) is no touch: released at once, as when the hand leaves.
  // Without an F/T sample (no sensor): the wrench estimated from the observer, the same trigger.
  const bool estimated = !ft_seen_;
  const bool fresh = estimated || (wrench_supervisor_.fresh() && wrench_.calibrated());
  if (!fresh) trigger_filter_.reset(0.0);
  const double norm = estimated ? estimated_wrench_.norm() : wrench_.norm();
  if (compliance_.update(fresh ? trigger_filter_.update(norm) : 0.0, qp_, data_)) {
    // A hand let go in dual compliance: its pose is the end effector's new target (paper), and the
    // configuration it left the arm in is the posture's. The old posture target lies off the new
    // pose's self-motion manifold; the paper's posture stiffness of 0 there leaves the arm where the
    // hand put it, and with ours it would creep along the self-motion toward the old target.
    qp_.posture().set_target(q_);
    leash_.reset();
  }
}

// After the external torque is known: the return leash, the posture's weight and the stiction
// terms for this cycle.
void Controller::shape_tasks() {
  // The way back after a hand carried the arm (return_leash.hpp): dragged in full-body compliance
  // while a hand is on the arm (tau_ext beyond the compliance dead band on some joint), never by
  // the arm's own motion, which would otherwise pull the leash along with it.
  const bool carried = compliance_.mode() == ComplianceMode::kFullBody &&
                       (tau_ext_.cwiseAbs().array() > qp_.compliance_deadband().array()).any();
  leash_.update(model_, q_, qd_, qp_.posture().target(), qp_.posture().target_velocity(), carried, settings_.period_s);
  qp_.posture().set_target_offset(leash_.offset());
  qp_.end_effector().set_target_offset(leash_.pose_offset());
  qp_.posture().set_weight(leash_.posture_weight(compliance_.settings().posture_weight));
  // The tasks' stiction terms and the vendor loops' friction assist in the torque loops, where
  // friction pre-compensation (custom loop) or the assist (vendor loops) turns their acceleration
  // into torque at rest. Off while a hand carries the arm in full-body compliance (they would wind
  // up against it; the leash follows the hand instead), and in dual compliance while a hand guides
  // the end effector (its task has no target to hold then).
  const bool stiction_terms = low_level_.requested() != LowLevelMode::kPosition && !carried &&
                              !(compliance_.mode() == ComplianceMode::kDual && compliance_.touched());
  qp_.posture().enable_integral(stiction_terms);
  qp_.end_effector().enable_integral(stiction_terms);
  low_level_.enable_breakaway_ramp(stiction_terms);
}

CycleStatus Controller::step(const RobotState& state, const ControllerTargets& targets, RobotCommand& command) {
  ++steps_;
  // Whether the previous cycle sent the QP's command (the motion since then answers it).
  const bool commanded_last = qp_commanded_;
  qp_commanded_ = false;
  if (std::isfinite(state.joints.stamp_s)) stop_stamp_s_ = state.joints.stamp_s;
  stop_sequence_ = state.joints.sequence;
  const bool targets_accepted = apply(targets);
  const bool had_good = supervisor_.has_good();
  const double previous_good_stamp = supervisor_.last_good_time();
  const std::uint32_t previous_good_sequence = supervisor_.last_good().joints.sequence;
  const bool good = supervisor_.check(state);
  // The brake's prediction ages by the steps without plausible kinematics, the degraded ones too.
  cycles_since_good_ = supervisor_.kinematics_fresh() ? 0 : cycles_since_good_ + 1;
  // The observer integrates over the time since the last sample it saw (missed ones included): by
  // the stamps and by the sequence, whichever says less (after a re-sync one of them jumped).
  const double by_sequence =
      static_cast<double>(static_cast<std::uint32_t>(state.joints.sequence - previous_good_sequence)) * settings_.period_s;
  const double dt = had_good ? std::clamp(std::min(state.joints.stamp_s - previous_good_stamp, by_sequence), settings_.period_s,
                                          settings_.period_s + supervisor_.settings().max_degraded_s)
                             : settings_.period_s;
  if (supervisor_.safe_stop()) {
    // After a QP failure (the samples good, a push beyond what the constraints could answer) the
    // brake keeps resisting the push as the QP's fallback did (dropping it flings the arm). The
    // estimate stays current.
    if (good && brake_against_push_ && !holding_) {
      q_ = state.q_rad;
      qd_ = state.qd_rad_s;
      estimate(state, dt);
      select_external_torque();
      bound_external_torque(tau_ext_);
    }
    safe_stop(good, command);
    return status_;
  }
  if (!good) {
    missing_sample(state, command);
    return status_;
  }
  track_acceleration(state.qd_rad_s, dt);
  q_ = state.q_rad;
  qd_ = state.qd_rad_s;
  estimate(state, dt);

  // ---- modes and targets
  update_modes_and_targets();

  // ---- QP and inverse dynamics. Under the robot's position loop the external torque is not fed
  // back: the stiff servo rejects it and the observer would only see servo effort.
  select_external_torque();
  bound_external_torque(tau_ext_);
  const bool torque_loop = low_level_.requested() != LowLevelMode::kPosition;
  if (!torque_loop) tau_ext_.setZero();
  const bool fast_estimate = estimate_uncancelled_push(torque_loop, commanded_last, dt);
  shape_tasks();
  // The F/T wrench for the tasks that read it (a force task), when it is plausible and in use.
  const bool wrench_usable = wrench_supervisor_.fresh() && wrench_.calibrated();
  const WholeBodyQpStatus qp_status =
      qp_.update(model_, data_, q_, qd_, tau_ext_, settings_.period_s, wrench_usable ? &wrench_.wrench_world() : nullptr,
                 fast_estimate ? &uncancelled_.acceleration() : nullptr, fast_estimate ? &uncancelled_.release_acceleration() : nullptr);
  check_qp(qp_status, state.time_s);
  if (supervisor_.safe_stop()) {
    safe_stop(true, command);
    return status_;
  }

  // ---- guards, low level
  guarded_tau_ = qp_.desired_torque();
  guard_torque(guarded_tau_);
  low_level_.update(state, guarded_tau_, qp_.desired_acceleration(), command);
  note_sent_acceleration();
  supervisor_.note_command(command);
  have_command_ = true;
  qp_commanded_ = true;
  status_ = !solved(qp_status)                 ? CycleStatus::kQpFallback
            : targets_accepted                 ? CycleStatus::kOk
                                               : CycleStatus::kTargetsRejected;
  return status_;
}

}  // namespace phri
