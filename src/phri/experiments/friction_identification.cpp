#include <phri/experiments/friction_identification.hpp>

#include <phri/control/controller_settings.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/friction_perturbation.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include <Eigen/Dense>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

constexpr double kHoldBandwidth = 30.0;      // rad/s, joint PD of the held joints and of moves
constexpr double kVelocityBandwidth = 80.0;  // rad/s, velocity run-up (double closed-loop pole at -40 rad/s)
constexpr double kMoveSpeed = 1.0;           // rad/s, repositioning of the limited joints
constexpr double kCurrentMargin = 0.95;      // of the drive's current limit
constexpr int kSampleDecimation = 5;
constexpr double kSteadyRelative = 0.02;
constexpr double kSteadyAbsolute = 0.005;  // rad/s
constexpr double kTrialRise_s = 0.05;
constexpr double kMovingFraction = 0.25;   // of the run-up speed: below, the joint stuck

double sign(double x) { return x > 0.0 ? 1.0 : (x < 0.0 ? -1.0 : 0.0); }

// What the joint under test receives, beyond gravity compensation.
enum class Drive { kHold, kVelocity, kTorque };

// The arm in current mode: gravity compensation on every joint, a PD holding the joints not under
// test, and one joint driven by `Drive`.
class FrictionRig {
public:
  FrictionRig(const SimRobotConfig& config, const Model& model)
      : robot_(config),
        model_(model),
        data_(model_),
        n_(robot_.dof()),
        command_(n_),
        hold_(Eigen::VectorXd::Zero(n_)),
        inertia_(Eigen::VectorXd::Zero(n_)) {
    const Eigen::VectorXd q0 = Eigen::Map<const Eigen::VectorXd>(config.initial_q_rad.data(), n_);
    compute_all_terms(model_, data_, q0, Eigen::VectorXd::Zero(n_));
    for (int i = 0; i < n_; ++i) {
      // What the controller would know: its model's inertia plus the nominal rotor inertia.
      inertia_[i] = data_.mass_matrix(i, i) + config.actuators[i].reflected_inertia_kgm2;
      hold_[i] = q0[i];
    }
    command_.mode = LowLevelMode::kCurrent;
    command_.current_A.setZero();
  }

  int dof() const { return n_; }
  const SimRobot& robot() const { return robot_; }
  const RobotState& state() const { return robot_.state(); }
  double time() const { return robot_.state().time_s; }
  bool limited(int j) const { return robot_.position_lower_rad()[j] > -99.0; }
  double inertia(int j) const { return inertia_[j]; }
  /// The torque (beyond gravity compensation) commanded on the joint under test last cycle.
  double test_torque() const { return test_torque_; }

  /// One cycle: reads the state, then writes the command for the next period. `target` is a
  /// position (kHold), a velocity (kVelocity, with its `acceleration` fed forward) or a torque
  /// (kTorque) of joint `j` (-1: none). The velocity servo is a PI with feed-forward of the
  /// nominal friction and of the reference's acceleration.
  const RobotState& step(int j, Drive drive, double target, double acceleration = 0.0) {
    const RobotState& s = robot_.read();
    if (s.fault) throw ExperimentError("friction identification", "the simulated plant faulted");
    compute_gravity(model_, data_, s.q_rad);
    const ActuatorTable& nominal = robot_.config().actuators;
    for (int i = 0; i < n_; ++i) {
      double tau = data_.gravity_torque[i];
      const double w = kHoldBandwidth;
      if (i != j) {
        tau += inertia_[i] * (w * w * (hold_[i] - s.q_rad[i]) - 2.0 * w * s.qd_rad_s[i]);
      } else {
        double extra = 0.0;
        switch (drive) {
          case Drive::kHold:
            extra = inertia_[i] * (w * w * (target - s.q_rad[i]) - 2.0 * w * s.qd_rad_s[i]);
            integral_ = 0.0;
            break;
          case Drive::kVelocity: {
            const double wv = kVelocityBandwidth;
            const double error = target - s.qd_rad_s[i];
            integral_ += inertia_[i] * wv * wv / 4.0 * error * robot_.period_s();
            const FrictionParameters& f = nominal[i].friction;
            extra = f.coulomb_Nm * sign(target) + f.viscous_Nms_per_rad * target + inertia_[i] * (acceleration + wv * error) +
                    integral_;
            break;
          }
          case Drive::kTorque:
            extra = target;
            integral_ = 0.0;
            break;
        }
        test_torque_ = extra;
        tau += extra;
      }
      const double limit = kCurrentMargin * nominal[i].current_limit_A;
      command_.current_A[i] = std::clamp(tau / nominal[i].torque_per_amp(), -limit, limit);
    }
    const WriteStatus status = robot_.write(command_);
    if (status != WriteStatus::kOk) {
      throw ExperimentError("friction identification", "the plant refused a current command");
    }
    return s;
  }

  void set_hold(int j, double q) { hold_[j] = q; }

private:
  SimRobot robot_;
  const Model& model_;
  Data data_;
  int n_;
  RobotCommand command_;
  Eigen::VectorXd hold_, inertia_;
  double integral_ = 0.0;
  double test_torque_ = 0.0;
};

int cycles(double seconds, double period) { return std::max(1, static_cast<int>(std::lround(seconds / period))); }

// Moves joint j to `goal` along a ramp at kMoveSpeed, then holds it there for `hold_s`.
void move_to(FrictionRig& rig, int j, double goal, double hold_s) {
  const double dt = rig.robot().period_s();
  double target = rig.state().q_rad[j];
  const double step = kMoveSpeed * dt;
  while (std::abs(goal - target) > step) {
    target += step * sign(goal - target);
    rig.step(j, Drive::kHold, target);
  }
  for (int k = 0; k < cycles(hold_s, dt); ++k) rig.step(j, Drive::kHold, goal);
}

// No torque beyond gravity compensation: a joint at rest stays stuck and its presliding
// deflection relaxes.
void release(FrictionRig& rig, int j, double seconds) {
  for (int k = 0; k < cycles(seconds, rig.robot().period_s()); ++k) rig.step(j, Drive::kTorque, 0.0);
}

struct Mean {
  double sum = 0.0, sum2 = 0.0;
  int n = 0;
  void add(double x) {
    sum += x;
    sum2 += x * x;
    ++n;
  }
  double mean() const { return n > 0 ? sum / n : 0.0; }
  double std() const { return n > 1 ? std::sqrt(std::max(0.0, (sum2 - sum * sum / n) / (n - 1))) : 0.0; }
};

FrictionLevel run_level(FrictionRig& rig, int j, int direction, double speed, const FrictionIdentificationOptions& o,
                        std::vector<FrictionSample>& samples) {
  const double dt = rig.robot().period_s();
  const double kt_gr = rig.robot().config().actuators[j].torque_per_amp();
  // Run-up: the velocity reference ramps from the joint's velocity to the level's during the first
  // half, then stays; the current held afterwards is the servo's mean over the last 0.1 s.
  const int run = cycles(o.run_up_s, dt);
  const int ramp = run / 2;
  const int tail = std::min(run - ramp, cycles(0.1, dt));
  const double v0 = rig.state().qd_rad_s[j];
  const double v1 = direction * speed;
  const double accel = (v1 - v0) / (ramp * dt);
  Mean held;
  for (int k = 0; k < run; ++k) {
    const bool ramping = k < ramp;
    rig.step(j, Drive::kVelocity, ramping ? v0 + accel * (k + 1) * dt : v1, ramping ? accel : 0.0);
    if (k >= run - tail) held.add(rig.test_torque());
  }
  const double tau = held.mean();
  for (int k = 0; k < cycles(o.settle_s, dt); ++k) rig.step(j, Drive::kTorque, tau);
  const int n = cycles(o.average_s, dt);
  Mean current, error, first, second;
  bool in_current_mode = true;
  for (int k = 0; k < n; ++k) {
    const RobotState& s = rig.step(j, Drive::kTorque, tau);
    const double e = kt_gr * s.current_A[j] - s.tau_sensor_Nm[j];
    in_current_mode = in_current_mode && s.mode == LowLevelMode::kCurrent && !s.stop_requested;
    current.add(s.current_A[j]);
    error.add(e);
    (k < n / 2 ? first : second).add(s.qd_rad_s[j]);
    if (k % kSampleDecimation == 0) samples.push_back({j + 1, s.qd_rad_s[j], e});
  }
  FrictionLevel level;
  level.joint = j + 1;
  level.direction = direction;
  level.target_speed_rad_s = speed;
  level.current_A = current.mean();
  level.velocity_rad_s = (first.sum + second.sum) / (first.n + second.n);
  level.torque_error_Nm = error.mean();
  level.torque_error_std_Nm = error.std();
  level.velocity_drift_rad_s = second.mean() - first.mean();
  const bool moving = level.velocity_rad_s * direction > kMovingFraction * speed;
  level.current_mode = in_current_mode;
  level.steady = in_current_mode && moving && std::abs(level.velocity_drift_rad_s) < kSteadyRelative * std::abs(level.velocity_rad_s) + kSteadyAbsolute;
  return level;
}

// True when `torque` (beyond gravity compensation) starts joint j from rest within the trial time.
bool static_trial(FrictionRig& rig, int j, int direction, double torque, const FrictionIdentificationOptions& o) {
  const double dt = rig.robot().period_s();
  const double q0 = rig.state().q_rad[j];
  bool moved = false;
  // The trial torque rises over kTrialRise_s: a step would excite the coupled presliding modes of
  // the arm's stuck joints and break the joint away slightly below its static level.
  const int rise = cycles(kTrialRise_s, dt);
  for (int k = 0; k < cycles(o.static_trial_s, dt) && !moved; ++k) {
    const double ramp = std::min(1.0, static_cast<double>(k + 1) / rise);
    const RobotState& s = rig.step(j, Drive::kTorque, direction * torque * ramp);
    moved = std::abs(s.q_rad[j] - q0) > o.breakaway_rad;
  }
  if (moved) {
    // Stop where it is, then let it stick with no torque.
    const double here = rig.state().q_rad[j];
    for (int k = 0; k < cycles(0.25, dt); ++k) rig.step(j, Drive::kHold, here);
    if (rig.limited(j) && std::abs(rig.state().q_rad[j]) > 0.2) move_to(rig, j, 0.0, 0.25);
  }
  release(rig, j, 0.15);
  return moved;
}

// Bisection on the smallest torque that starts joint j from rest in `direction`.
double find_static(FrictionRig& rig, int j, int direction, const FrictionIdentificationOptions& o,
                   std::vector<StaticFrictionTrial>& trials) {
  const ActuatorParameters& a = rig.robot().config().actuators[j];
  const double max_torque = 0.5 * a.max_motor_torque_Nm();
  double lo = 0.0;
  double hi = 2.0 * std::max(a.friction.static_Nm, 0.1);
  for (;;) {
    const bool moved = static_trial(rig, j, direction, hi, o);
    trials.push_back({j + 1, direction, hi, moved});
    if (moved) break;
    lo = hi;
    hi *= 1.5;
    if (hi > max_torque) {
      throw ExperimentError("friction identification",
                            "joint " + std::to_string(j + 1) + " does not start below half its maximum torque");
    }
  }
  for (int k = 0; k < o.static_bisection_steps; ++k) {
    const double mid = 0.5 * (lo + hi);
    const bool moved = static_trial(rig, j, direction, mid, o);
    trials.push_back({j + 1, direction, mid, moved});
    (moved ? hi : lo) = mid;
  }
  return hi;  // the smallest tried torque that started the joint
}

void validate(const StribeckRippleSettings& s);

void validate(const FrictionIdentificationOptions& o) {
  const std::string src = "<friction identification options>";
  if (o.joints.empty()) throw ConfigError(src, "joints", "no joint to identify");
  if (o.speed_levels < 2) throw ConfigError(src, "speed_levels", "must be >= 2");
  if (!(o.min_speed_rad_s > 0.0)) throw ConfigError(src, "min_speed_rad_s", "must be > 0");
  if (!(o.max_speed_fraction > 0.0 && o.max_speed_fraction <= 1.0)) {
    throw ConfigError(src, "max_speed_fraction", "must be in (0, 1]");
  }
  if (!(o.run_up_s >= 0.1) || !(o.settle_s >= 0.0) || !(o.average_s >= 0.02)) {
    throw ConfigError(src, "run_up_s/settle_s/average_s", "run-up >= 0.1 s, settle >= 0, average >= 0.02 s");
  }
  if (!(o.limited_half_range_rad > 0.05 && o.limited_half_range_rad < 2.0)) {
    throw ConfigError(src, "limited_half_range_rad", "must be in (0.05, 2) rad");
  }
  if (o.static_bisection_steps < 1) throw ConfigError(src, "static_bisection_steps", "must be >= 1");
  if (!(o.static_trial_s > 0.0) || !(o.breakaway_rad > 0.0)) {
    throw ConfigError(src, "static_trial_s/breakaway_rad", "must be > 0");
  }
  if (o.plant_friction == PlantFrictionForm::kStribeckRipple) validate(o.stribeck_ripple);
}

// The ranges of the plant's friction keys (sim_robot_config.cpp), and static >= Coulomb.
void validate(const StribeckRippleSettings& s) {
  const std::string src = "<friction identification options>";
  auto stribeck_velocity_ok = [](double v) { return v > 0.0 && v <= 1.0; };
  if (!stribeck_velocity_ok(s.stribeck_velocity_rad_s)) throw ConfigError(src, "stribeck_velocity_rad_s", "must be in (0, 1] rad/s");
  for (double v : s.stribeck_velocity_sweep) {
    if (!stribeck_velocity_ok(v)) throw ConfigError(src, "stribeck_velocity_sweep", "each v_s must be in (0, 1] rad/s");
  }
  if (!(s.stribeck_exponent >= 0.5 && s.stribeck_exponent <= 4.0)) throw ConfigError(src, "stribeck_exponent", "must be in [0.5, 4]");
  if (!(s.static_to_coulomb >= 1.0 && s.static_to_coulomb <= 3.0)) throw ConfigError(src, "static_to_coulomb", "must be in [1, 3]");
  if (!(s.ripple_fraction >= 0.0 && s.ripple_fraction <= 0.5)) throw ConfigError(src, "ripple_fraction", "must be in [0, 0.5]");
  if (!(s.ripple_cycles_per_rev >= 0.0 && s.ripple_cycles_per_rev <= 10000.0)) {
    throw ConfigError(src, "ripple_cycles_per_rev", "must be in [0, 10000]");
  }
  if (s.sweep_speed_levels < 2) throw ConfigError(src, "sweep_speed_levels", "must be >= 2");
  for (double a : s.ripple_fraction_sweep) {
    if (!(a >= 0.0 && a <= 0.5)) throw ConfigError(src, "ripple_fraction_sweep", "each a_r must be in [0, 0.5]");
  }
  const bool sweeps = !s.stribeck_velocity_sweep.empty() || !s.ripple_fraction_sweep.empty();
  if (sweeps && s.sweep_joints.empty()) throw ConfigError(src, "sweep_joints", "no joint to sweep");
}

std::string levels_csv(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "joint,direction,target_speed_rad_s,current_A,velocity_rad_s,torque_error_Nm,torque_error_std_Nm,"
       "velocity_drift_rad_s,steady\n";
  for (const FrictionLevel& l : r.levels) {
    s << l.joint << ',' << l.direction << ',' << format_fixed(l.target_speed_rad_s, 5) << ','
      << format_fixed(l.current_A, 6) << ',' << format_fixed(l.velocity_rad_s, 6) << ','
      << format_fixed(l.torque_error_Nm, 6) << ',' << format_fixed(l.torque_error_std_Nm, 6) << ','
      << format_fixed(l.velocity_drift_rad_s, 6) << ',' << (l.steady ? 1 : 0) << '\n';
  }
  return s.str();
}

std::string samples_csv(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "joint,velocity_rad_s,torque_error_Nm\n";
  for (const FrictionSample& x : r.samples) {
    s << x.joint << ',' << format_fixed(x.velocity_rad_s, 5) << ',' << format_fixed(x.torque_error_Nm, 5) << '\n';
  }
  return s.str();
}

std::string static_csv(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "joint,direction,torque_Nm,moved\n";
  for (const StaticFrictionTrial& t : r.static_trials) {
    s << t.joint << ',' << t.direction << ',' << format_fixed(t.torque_Nm, 6) << ',' << (t.moved ? 1 : 0) << '\n';
  }
  return s.str();
}

// The fitted models per joint, for the figure (one row per joint).
std::string models_csv(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  s << "joint,name,coulomb_Nm,viscous_Nms_per_rad,static_Nm,offset_Nm,plant_coulomb_Nm,plant_viscous_Nms_per_rad,"
       "plant_static_Nm\n";
  for (const JointFrictionEstimate& e : r.joints) {
    s << e.joint << ',' << e.name << ',' << format_fixed(e.identified.coulomb_Nm, 6) << ','
      << format_fixed(e.identified.viscous_Nms_per_rad, 6) << ',' << format_fixed(e.identified.static_Nm, 6) << ','
      << format_fixed(e.offset_Nm, 6) << ',' << format_fixed(e.plant.coulomb_Nm, 6) << ','
      << format_fixed(e.plant.viscous_Nms_per_rad, 6) << ',' << format_fixed(e.plant.static_Nm, 6) << '\n';
  }
  return s.str();
}

// The plant of the identification: the options' plant file, upright (no gravity torque), seeded,
// its friction perturbed from actuators.yaml's when asked.
SimRobotConfig identification_plant(const FrictionIdentificationOptions& o) {
  SimRobotConfig config = SimRobotConfig::from_yaml_file(o.plant_config_path);
  const int n = config.dof();
  for (int j : o.joints) {
    if (j < 1 || j > n) {
      throw ConfigError("<friction identification options>", "joints", "joint " + std::to_string(j) + " out of 1.." + std::to_string(n));
    }
  }
  config.initial_q_rad.assign(static_cast<std::size_t>(n), 0.0);  // upright: no gravity torque
  config.seed = o.seed;
  if (o.friction_perturbation > 0.0) {
    config.actuator_overrides = perturbed_friction_overrides(config.actuators, o.friction_perturbation, o.seed);
  }
  if (o.plant_friction == PlantFrictionForm::kStribeckRipple) apply_stribeck_ripple(o.stribeck_ripple, config);
  return config;
}

// The controller's model (with the end of arm the plant file states), for the gravity compensation.
Model identification_model(const FrictionIdentificationOptions& o, const SimRobotConfig& plant) {
  const int plant_dof = plant.dof();
  ControllerSettings settings;
  settings.end_effector_frame = o.end_effector_frame;
  settings.set_end_of_arm(plant.end_of_arm());
  ModelOptions model_options;
  for (Payload p : settings.payloads) {
    p.frame = o.end_effector_frame;
    model_options.payloads.push_back(p);
  }
  Model model = Model::from_urdf_file(o.urdf_path, model_options);
  if (model.nq() != plant_dof) throw ConfigError(o.urdf_path, "joints", "the model and the plant differ in joint count");
  return model;
}

// The constant-current levels of joint j, both directions at each speed, appended to `levels`;
// then the joint stops and comes back to upright (continuous joints: stay where they stopped).
void run_speed_levels(FrictionRig& rig, int j, const FrictionIdentificationOptions& o, FrictionIdentificationResult& result,
                      std::ostream* progress) {
  const ActuatorParameters& nominal = rig.robot().config().actuators[j];
  const bool limited = rig.limited(j);
  const double level_s = o.run_up_s + o.settle_s + o.average_s;
  double max_speed = o.max_speed_fraction * nominal.velocity_limit_rad_s;
  if (limited) max_speed = std::min(max_speed, 0.9 * 2.0 * o.limited_half_range_rad / level_s);
  const double min_speed = std::min(o.min_speed_rad_s, 0.5 * max_speed);
  if (progress) {
    *progress << "joint " << j + 1 << " (" << nominal.joint_name << (limited ? ", limited" : ", continuous")
              << "): " << 2 * o.speed_levels << " constant-current levels, " << format_fixed(min_speed, 3) << " to "
              << format_fixed(max_speed, 3) << " rad/s each way, at t = " << format_fixed(rig.time(), 1) << " s"
              << std::endl;
  }
  for (int k = 0; k < o.speed_levels; ++k) {
    const double speed = min_speed * std::pow(max_speed / min_speed, static_cast<double>(k) / (o.speed_levels - 1));
    for (int direction : {+1, -1}) {
      if (limited) {
        const double half = std::min(0.5 * speed * level_s, o.limited_half_range_rad);
        move_to(rig, j, -direction * half, 0.2);
      }
      result.levels.push_back(run_level(rig, j, direction, speed, o, result.samples));
    }
  }
  const double stop_at = limited ? 0.0 : rig.state().q_rad[j];
  for (int k = 0; k < cycles(0.3, rig.robot().period_s()); ++k) rig.step(j, Drive::kHold, rig.state().q_rad[j]);
  move_to(rig, j, stop_at, 0.3);
  rig.set_hold(j, stop_at);
}

// Least squares on the steady levels: e = c0 + tau_c sign(qd) + tau_v qd. Sets the estimate's
// offset, Coulomb and viscous coefficients, residual and level counts.
void fit_sliding_friction(const std::vector<FrictionLevel>& levels, bool model_form, JointFrictionEstimate& e) {
  int used = 0;
  for (const FrictionLevel& l : levels) used += l.steady ? 1 : 0;
  e.levels_total = static_cast<int>(levels.size());
  e.levels_used = used;
  if (used < 4 && !model_form) {
    // On a plant of another form a joint may not slide steadily at constant current (where the
    // Stribeck curve falls, or the ripple stalls it): not a result, and said so.
    e.valid = false;
    e.invalid_reason = "only " + std::to_string(used) + " steady levels of " + std::to_string(e.levels_total);
    return;
  }
  if (used < 4) {
    throw ExperimentError("friction identification",
                          "joint " + std::to_string(e.joint) + ": only " + std::to_string(used) + " steady levels");
  }
  Eigen::MatrixXd a(used, 3);
  Eigen::VectorXd b(used);
  int row = 0;
  for (const FrictionLevel& l : levels) {
    if (!l.steady) continue;
    a(row, 0) = 1.0;
    a(row, 1) = sign(l.velocity_rad_s);
    a(row, 2) = l.velocity_rad_s;
    b[row] = l.torque_error_Nm;
    ++row;
  }
  const Eigen::Vector3d x = a.colPivHouseholderQr().solve(b);
  e.offset_Nm = x[0];
  e.identified.coulomb_Nm = x[1];
  e.identified.viscous_Nms_per_rad = x[2];
  e.residual_rms_Nm = std::sqrt((a * x - b).squaredNorm() / used);
}

// The breakaway level of joint j in each direction, from rest at upright; the joint is held where
// it ends (limited joints: back at upright).
// Returns where each direction's search started (the breakaway level may depend on position).
std::pair<double, double> identify_static_friction(FrictionRig& rig, int j, const FrictionIdentificationOptions& o,
                                                   JointFrictionEstimate& e, std::vector<StaticFrictionTrial>& trials) {
  const bool limited = rig.limited(j);
  if (limited) move_to(rig, j, 0.0, 0.2);
  release(rig, j, 0.2);
  const double q_positive = rig.state().q_rad[j];
  e.static_positive_Nm = find_static(rig, j, +1, o, trials);
  if (limited) move_to(rig, j, 0.0, 0.2);
  release(rig, j, 0.2);
  const double q_negative = rig.state().q_rad[j];
  e.static_negative_Nm = find_static(rig, j, -1, o, trials);
  e.identified.static_Nm = 0.5 * (e.static_positive_Nm + e.static_negative_Nm);
  rig.set_hold(j, rig.state().q_rad[j]);
  if (limited) {
    move_to(rig, j, 0.0, 0.2);
    rig.set_hold(j, 0.0);
  }
  release(rig, -1, 0.2);
  return {q_positive, q_negative};
}

// One joint (1-based): sliding levels and their fit, then the static search; on a plant of another
// form, the identified model against the plant's true friction.
JointFrictionEstimate identify_joint(FrictionRig& rig, int joint, const FrictionIdentificationOptions& o,
                                     FrictionIdentificationResult& result, std::ostream* progress) {
  const int j = joint - 1;
  const ActuatorParameters& nominal = rig.robot().config().actuators[j];
  const std::size_t first_level = result.levels.size();
  run_speed_levels(rig, j, o, result, progress);
  const std::vector<FrictionLevel> levels(result.levels.begin() + static_cast<std::ptrdiff_t>(first_level), result.levels.end());
  const bool model_form = o.plant_friction == PlantFrictionForm::kModelForm;

  JointFrictionEstimate e;
  e.joint = joint;
  e.name = nominal.joint_name;
  e.nominal = nominal.friction;
  e.plant = rig.robot().plant_actuators()[j].friction;
  const std::vector<double>& offsets = rig.robot().config().noise.torque_sensor_offset_Nm;
  e.plant_sensor_offset_Nm = offsets.empty() ? 0.0 : offsets[static_cast<std::size_t>(j)];
  e.identified = nominal.friction;
  fit_sliding_friction(levels, model_form, e);
  if (!e.valid) {
    if (progress) *progress << "  INVALID: " << e.invalid_reason << "; not identified" << std::endl;
    return e;
  }
  if (progress) {
    *progress << "  fit on " << e.levels_used << "/" << e.levels_total << " steady levels: Coulomb "
              << format_fixed(e.identified.coulomb_Nm, 4) << " N.m, viscous " << format_fixed(e.identified.viscous_Nms_per_rad, 4)
              << " N.m.s/rad, offset " << format_fixed(e.offset_Nm, 4) << " N.m" << (o.static_search ? "; static search..." : "")
              << std::endl;
  }
  std::pair<double, double> static_start{0.0, 0.0};
  if (o.static_search) static_start = identify_static_friction(rig, j, o, e, result.static_trials);
  if (progress && o.static_search) {
    *progress << "  static " << format_fixed(e.static_positive_Nm, 4) << " / " << format_fixed(e.static_negative_Nm, 4)
              << " N.m (+/-); plant: Coulomb " << format_fixed(e.plant.coulomb_Nm, 4) << ", viscous "
              << format_fixed(e.plant.viscous_Nms_per_rad, 4) << ", static " << format_fixed(e.plant.static_Nm, 4)
              << std::endl;
  }
  if (!model_form) {
    e.form = model_form_error(e, levels, rig.robot().dry_friction_parameters(j), static_start.first, static_start.second);
  }
  return e;
}

}  // namespace

double FrictionIdentificationResult::worst_relative_error() const {
  double worst = 0.0;
  for (const JointFrictionEstimate& e : joints) {
    if (!e.valid) continue;
    worst = std::max({worst, std::abs(e.coulomb_error()), std::abs(e.viscous_error()), std::abs(e.static_error())});
  }
  return worst;
}

FrictionIdentificationResult identify_friction(const FrictionIdentificationOptions& o, std::ostream* progress) {
  validate(o);
  const auto wall_start = std::chrono::steady_clock::now();
  const SimRobotConfig config = identification_plant(o);
  const Model model = identification_model(o, config);
  FrictionRig rig(config, model);
  FrictionIdentificationResult result;
  result.samples.reserve(40000);
  release(rig, -1, 0.3);  // everything held at upright
  for (int joint : o.joints) result.joints.push_back(identify_joint(rig, joint, o, result, progress));
  result.simulated_s = rig.time();
  result.plant_friction = o.plant_friction;
  if (o.plant_friction == PlantFrictionForm::kStribeckRipple) result.sweep = friction_form_sweeps(o, progress);
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::vector<OutputFile> files = {{"friction_levels.csv", levels_csv(result)},
                                                            {"friction_samples.csv", samples_csv(result)},
                                                            {"friction_static.csv", static_csv(result)},
                                                            {"friction_models.csv", models_csv(result)},
                                                            {"friction_identified.yaml", friction_identification_yaml(result, o)},
                                                            {"friction_identification.md", friction_identification_table(result)}};
  if (o.plant_friction != PlantFrictionForm::kModelForm) {
    files.push_back({"friction_form.csv", model_form_csv(result)});
    files.push_back({"friction_form_sweep.csv", sweep_csv(result.sweep)});
  }
  result.files = write_output_files(o.output_dir, files);
  return result;
}

std::string friction_identification_table(const FrictionIdentificationResult& r) {
  std::ostringstream s;
  auto pct = [](double x) { return format_fixed(100.0 * x, 2); };
  s << "| joint | Coulomb plant | identified | err % | viscous plant | identified | err % | static plant | identified "
       "(+/-) | err % | offset fit / plant | levels | residual rms |\n";
  s << "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const JointFrictionEstimate& e : r.joints) {
    if (!e.valid) {
      s << "| " << e.joint << " | INVALID: " << e.invalid_reason << " |||||||||||\n";
      continue;
    }
    s << "| " << e.joint << " | " << format_fixed(e.plant.coulomb_Nm, 4) << " | " << format_fixed(e.identified.coulomb_Nm, 4)
      << " | " << pct(e.coulomb_error()) << " | " << format_fixed(e.plant.viscous_Nms_per_rad, 4) << " | "
      << format_fixed(e.identified.viscous_Nms_per_rad, 4) << " | " << pct(e.viscous_error()) << " | "
      << format_fixed(e.plant.static_Nm, 4) << " | " << format_fixed(e.identified.static_Nm, 4) << " ("
      << format_fixed(e.static_positive_Nm, 4) << " / " << format_fixed(e.static_negative_Nm, 4) << ") | "
      << pct(e.static_error()) << " | " << format_fixed(e.offset_Nm, 3) << " / " << format_fixed(-e.plant_sensor_offset_Nm, 3)
      << " | " << e.levels_used << "/" << e.levels_total << " | " << format_fixed(e.residual_rms_Nm, 4) << " |\n";
  }
  s << "\nUnits: N.m (Coulomb, static, offset), N.m.s/rad (viscous). err % = (identified - plant) / plant. "
       "The offset is the fit's intercept, expected at minus the torque sensor's zero offset.\n";
  s << "Worst |error|: " << format_fixed(100.0 * r.worst_relative_error(), 2) << " %. Simulated "
    << format_fixed(r.simulated_s, 1) << " s in " << format_fixed(r.wall_s, 2) << " s of wall time.\n";
  if (r.plant_friction != PlantFrictionForm::kModelForm) s << "\n" << model_form_markdown(r) << "\n" << sweep_markdown(r.sweep);
  return s.str();
}

std::string friction_identification_yaml(const FrictionIdentificationResult& r, const FrictionIdentificationOptions& o) {
  std::ostringstream s;
  s << "# Joint friction identified by phri (paper section \"Friction parameters identification\"):\n"
    << "# constant current per joint at the upright stance, least squares on the steady levels\n"
    << "# (Coulomb + viscous), bisection on the breakaway current (static). Plant: " << o.plant_config_path << ",\n"
    << "# friction perturbation " << o.friction_perturbation << ", seed " << o.seed << ".\n"
    << "# Each `friction:` block has the keys of robots/kinova_gen3/actuators.yaml; the thresholds are the\n"
    << "# nominal ones (the identification does not measure them).\n"
    << "joints:\n";
  for (const JointFrictionEstimate& e : r.joints) {
    if (!e.valid) {
      s << "  # " << e.name << ": INVALID (" << e.invalid_reason << "), not identified\n";
      continue;
    }
    const FrictionParameters& f = e.identified;
    const bool raised = f.static_Nm < f.coulomb_Nm;
    s << "  - name: " << e.name << "\n"
      << "    friction:\n"
      << "      coulomb_Nm: " << format_fixed(f.coulomb_Nm, 4) << "\n"
      << "      viscous_Nms_per_rad: " << format_fixed(f.viscous_Nms_per_rad, 4) << "\n"
      << "      static_Nm: " << format_fixed(std::max(f.static_Nm, f.coulomb_Nm), 4)
      << (raised ? "   # identified " + format_fixed(f.static_Nm, 4) + ", raised to Coulomb (static >= coulomb)" : "")
      << "\n"
      << "      velocity_threshold_rad_s: " << f.velocity_threshold_rad_s << "\n"
      << "      acceleration_threshold_rad_s2: " << f.acceleration_threshold_rad_s2 << "\n";
  }
  return s.str();
}

int run_friction_identification_command(const FrictionIdentificationOptions& options, std::ostream& out) {
  out << "friction identification: plant " << options.plant_config_path
      << (options.plant_friction == PlantFrictionForm::kStribeckRipple ? " (friction: Stribeck + ripple)" : "")
      << ", friction perturbation " << options.friction_perturbation << ", seed " << options.seed << ", joints";
  for (int j : options.joints) out << ' ' << j;
  out << std::endl;
  const FrictionIdentificationResult r = identify_friction(options, &out);
  report_experiment({friction_identification_table(r), r.files, options.output_dir, options.figure_script,
                     "friction_identification.png"},
                    out);
  return 0;
}

}  // namespace phri
