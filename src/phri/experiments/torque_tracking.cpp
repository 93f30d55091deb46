#include <phri/experiments/torque_tracking.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/core/statistics.hpp>
#include <phri/experiments/experiment_contact.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/friction_perturbation.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <optional>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

// The dynamic scenario's reference, relative to the start pose p0 (world axes):
//   z(t) = z0 + A s(t) sin(w t)                 A = 0.10 m, w = 3 rad/s
//   y(t) = y0 + triangle at 0.1 m/s, first toward -y, between y0 - 0.40 and y0 + 0.05 m
//   x, orientation: held
// Source: the paper authors' demo, bastien-muraccioli/monodzukuri2024_kinova_demo @ c706b4f (main),
// src/states/MonodzukuriKinovaDemo_SinCompliance.cpp ("Sin" state): R = 0.10 m, omega = 3 rad/s,
// y speed 0.1 m/s between minY = -0.4 and maxY = 0.05 starting toward negative y (as transcribed
// in the project's reference notes, paper_parameters section 5). The demo centres the task at
// (0.75, 0, 0.4) on its tool frame; here it is centred at the start pose of the end-effector frame.
// s(t) is a smoothstep over fade_in_s (our addition: the demo starts the sine at full speed).
struct Trajectory {
  double amplitude, omega, speed, low, high, fade;

  // Triangle wave position and velocity at time t >= 0 (starts at 0 toward `low`).
  void triangle(double t, double& y, double& v) const {
    const double leg1 = -low / speed;            // 0 -> low
    const double span = (high - low) / speed;    // low -> high or back
    double tt = t;
    if (tt < leg1) {
      y = -speed * tt;
      v = -speed;
      return;
    }
    tt -= leg1;
    const double period = 2.0 * span;
    tt = std::fmod(tt, period);
    if (tt < span) {
      y = low + speed * tt;
      v = speed;
    } else {
      y = high - speed * (tt - span);
      v = -speed;
    }
  }

  void at(double t, Vector6d& offset, Vector6d& velocity, Vector6d& acceleration) const {
    offset.setZero();
    velocity.setZero();
    acceleration.setZero();
    if (t <= 0.0) return;
    double s = 1.0, ds = 0.0, dds = 0.0;
    if (t < fade) {
      const double u = t / fade;
      s = u * u * (3.0 - 2.0 * u);
      ds = 6.0 * u * (1.0 - u) / fade;
      dds = (6.0 - 12.0 * u) / (fade * fade);
    }
    const double sn = std::sin(omega * t), cs = std::cos(omega * t);
    offset[2] = amplitude * s * sn;
    velocity[2] = amplitude * (ds * sn + s * omega * cs);
    acceleration[2] = amplitude * (dds * sn + 2.0 * ds * omega * cs - s * omega * omega * sn);
    triangle(t, offset[1], velocity[1]);
  }
};

ControllerSettings cycle_settings(const TorqueTrackingOptions& o, TrackingScenario scenario, ComplianceMode mode,
                                  const std::optional<EndOfArm>& end_of_arm) {
  ControllerSettings s;
  s.end_effector_frame = o.end_effector_frame;
  s.set_end_of_arm(end_of_arm);
  s.initial_compliance = mode;
  s.initial_loop = LowLevelMode::kPosition;
  s.custom_torque = o.custom_torque;
  if (scenario == TrackingScenario::kStatic) s.external_torque_source = o.static_external_torque;
  s.position_mode_open_loop = o.position_open_loop;
  return s;
}

// What the controller is built from, loaded once: every run's Controller starts from a copy.
struct ControllerRobot {
  std::optional<EndOfArm> end_of_arm;  ///< as the plant file states it (a payload run adds to the plant's only)
  Model model;
  ActuatorTable actuators;
  std::optional<CollisionModel> collision;
};

// The options' files as the controller uses them, with actuators.yaml's friction compensation
// thresholds replaced in memory when the options set them.
ControllerRobot load_controller_robot(const TorqueTrackingOptions& o) {
  // The model options do not depend on the scenario (frame names, F/T offset and payloads only).
  const std::optional<EndOfArm> end_of_arm = SimRobotConfig::from_yaml_file(o.plant_config_path).end_of_arm();
  const ControllerSettings settings = cycle_settings(o, TrackingScenario::kStatic, o.static_compliance, end_of_arm);
  Model model = Model::from_urdf_file(o.urdf_path, Controller::model_options(settings));
  ActuatorTable actuators = ActuatorTable::from_yaml_file(o.actuators_path);
  for (int i = 0; i < actuators.size(); ++i) {
    FrictionParameters& f = actuators[i].friction;
    if (o.friction_velocity_threshold_rad_s > 0.0) f.velocity_threshold_rad_s = o.friction_velocity_threshold_rad_s;
    if (o.friction_acceleration_threshold_rad_s2 > 0.0) {
      f.acceleration_threshold_rad_s2 = o.friction_acceleration_threshold_rad_s2;
    }
  }
  std::optional<CollisionModel> collision;
  if (!o.collision_path.empty()) collision = CollisionModel::from_yaml_file(o.collision_path, model);
  return {end_of_arm, std::move(model), std::move(actuators), std::move(collision)};
}

SimRobotConfig plant_config(const TorqueTrackingOptions& o, TrackingScenario scenario) {
  SimRobotConfig c = SimRobotConfig::from_yaml_file(o.plant_config_path);
  if (static_cast<int>(o.start_q_rad.size()) != c.dof()) {
    throw ConfigError("<torque tracking options>", "start_q_rad", "needs one value per joint");
  }
  c.initial_q_rad = o.start_q_rad;
  c.seed = o.seed;
  c.mismatch.enabled = o.model_mismatch;
  if (o.elastic) c.elasticity.enabled = true;
  if (o.torque_constant_error >= 0.0) c.mismatch.torque_constant_fraction = o.torque_constant_error;
  if (o.mismatch_seed) c.mismatch.seed = *o.mismatch_seed;
  if (o.friction_perturbation > 0.0) {
    c.actuator_overrides = perturbed_friction_overrides(c.actuators, o.friction_perturbation, o.seed);
  }
  if (scenario == TrackingScenario::kStatic && o.payload_kg > 0.0 && o.payload_mode == PayloadMode::kHungAfterSwitch) {
    ExternalForce weight;
    weight.body = "tool";
    weight.point_m = c.tool.com_m;
    weight.frame = ExternalForce::Frame::kWorld;
    weight.force_N = Eigen::Vector3d(0.0, 0.0, -9.81 * o.payload_kg);
    weight.profile = ExternalForce::Profile::kRamp;
    weight.start_s = o.position_phase_s + o.payload_hang_delay_s;
    weight.rise_s = o.payload_rise_s;
    weight.duration_s = 1e6;
    c.disturbances.push_back(weight);
  } else if (scenario == TrackingScenario::kStatic && o.payload_kg > 0.0) {
    // The weight clamped to the tool: same centre of mass, inertia scaled with the mass.
    const double scale = (c.tool.mass_kg + o.payload_kg) / c.tool.mass_kg;
    c.tool.mass_kg += o.payload_kg;
    c.tool.inertia_kgm2 *= scale;
  }
  return c;
}

std::string loop_name(LowLevelMode loop) { return std::string(to_string(loop)); }

// The cycle counts of one run: position control, then the loop under test, whose first `skip`
// cycles are left out of the statistics; the dynamic trajectory starts `delay` cycles after the switch.
struct RunSchedule {
  int position_cycles = 0, test_cycles = 0, skip = 0, delay = 0;
};

RunSchedule run_schedule(const TorqueTrackingOptions& o, TrackingScenario scenario, double dt) {
  const double duration = scenario == TrackingScenario::kStatic ? o.static_duration_s : o.dynamic_duration_s;
  return {static_cast<int>(std::lround(o.position_phase_s / dt)), static_cast<int>(std::lround(duration / dt)),
          static_cast<int>(std::lround(o.transient_s / dt)), static_cast<int>(std::lround(o.trajectory_delay_s / dt))};
}

struct EeErrors {
  Eigen::Vector3d position, velocity;
};

// The errors of one run after the switch: every sample into the time series (CSV), those past the
// transient into the statistics.
class TrackingRecorder {
public:
  TrackingRecorder(int dof, int test_cycles, int skip) : error_sum_(Eigen::VectorXd::Zero(dof)), skip_(skip) {
    csv_ << "t_s,error_norm_Nm,error_norm_true_Nm";
    for (int i = 0; i < dof; ++i) csv_ << ",error_" << (i + 1) << "_Nm";
    csv_ << ",ee_error_mm,ee_err_y_mm,ee_err_z_mm,ee_verr_y_mm_s,ee_verr_z_mm_s\n";
    for (std::vector<double>* v : {&norms_, &norms_true_, &ee_errors_}) v->reserve(static_cast<std::size_t>(test_cycles));
    for (std::vector<double>& v : axis_errors_) v.reserve(static_cast<std::size_t>(test_cycles));
  }

  /// Sample `sample` (0: the first period after the switch) at time sample * dt.
  /// ee: end-effector position error (target - plant) [m] and velocity error (reference - plant) [m/s].
  void record(int sample, double dt, const Eigen::VectorXd& error, const Eigen::VectorXd& error_true, const EeErrors& ee) {
    const double ee_error = ee.position.norm();
    csv_ << format_fixed(sample * dt, 3) << ',' << format_fixed(error.norm(), 5) << ',' << format_fixed(error_true.norm(), 5);
    for (int i = 0; i < error.size(); ++i) csv_ << ',' << format_fixed(error[i], 5);
    csv_ << ',' << format_fixed(1e3 * ee_error, 4) << ',' << format_fixed(1e3 * ee.position.y(), 4) << ','
         << format_fixed(1e3 * ee.position.z(), 4) << ',' << format_fixed(1e3 * ee.velocity.y(), 3) << ','
         << format_fixed(1e3 * ee.velocity.z(), 3) << '\n';
    if (sample < skip_) return;
    const double axes[4] = {ee.position.y(), ee.position.z(), ee.velocity.y(), ee.velocity.z()};
    for (int a = 0; a < 4; ++a) axis_errors_[static_cast<std::size_t>(a)].push_back(axes[a]);
    norms_.push_back(error.norm());
    error_sum_ += error;
    norms_true_.push_back(error_true.norm());
    ee_errors_.push_back(ee_error);
  }

  void fill_statistics(TorqueTrackingRun& run) const {
    run.rms_Nm = rms(norms_);
    run.p95_Nm = percentile(norms_, 0.95);
    run.max_Nm = norms_.empty() ? 0.0 : *std::max_element(norms_.begin(), norms_.end());
    run.bias_Nm = norms_.empty() ? 0.0 : error_sum_.norm() / static_cast<double>(norms_.size());
    run.rms_true_Nm = rms(norms_true_);
    run.p95_true_Nm = percentile(norms_true_, 0.95);
    run.ee_position_rms_mm = 1e3 * rms(ee_errors_);
    run.ee_position_max_mm = ee_errors_.empty() ? 0.0 : 1e3 * *std::max_element(ee_errors_.begin(), ee_errors_.end());
    run.samples = static_cast<int>(norms_.size());
    run.ee_y_rms_mm = 1e3 * rms(axis_errors_[0]);
    run.ee_z_rms_mm = 1e3 * rms(axis_errors_[1]);
    run.ee_vy_rms_mm_s = 1e3 * rms(axis_errors_[2]);
    run.ee_vz_rms_mm_s = 1e3 * rms(axis_errors_[3]);
  }

  std::string csv() const { return csv_.str(); }

private:
  std::ostringstream csv_;
  std::vector<double> norms_, norms_true_, ee_errors_;
  std::array<std::vector<double>, 4> axis_errors_;  // y, z position [m]; y, z velocity [m/s]
  Eigen::VectorXd error_sum_;
  int skip_;
};

// How far the plant's true end effector (forward kinematics of its true joint angles and
// velocities) is from the end-effector task's target [m] and its reference velocity [m/s].
EeErrors true_ee_error(const Controller& cycle, const SimRobot& robot, Data& truth_data) {
  forward_kinematics(cycle.model(), truth_data, robot.truth().q_rad, robot.truth().qd_rad_s);
  update_frame_placements(cycle.model(), truth_data);
  const int frame = cycle.end_effector_frame();
  const std::size_t ee = static_cast<std::size_t>(frame);
  const EndEffectorTask& task = cycle.qp().end_effector();
  const Vector6d v = frame_velocity(cycle.model(), truth_data, frame, ReferenceFrame::kLocalWorldAligned);
  return {task.target_pose().translation() - truth_data.frame_placements[ee].translation(),
          task.target_velocity().head<3>() - v.head<3>()};
}

// Runs the schedule: position control, the switch to `loop`, the dynamic scenario's trajectory;
// records the errors and the run's validity.
void drive_run(const TorqueTrackingOptions& o, TrackingScenario scenario, LowLevelMode loop, const RunSchedule& schedule,
               SimRobot& robot, Controller& cycle, TrackingRecorder& recorder, std::optional<ContactRecorder>& contact,
               RunValidity& validity, std::ostream* progress) {
  const int n = robot.dof();
  const double dt = robot.period_s();
  const Trajectory trajectory{o.sine_amplitude_m, o.sine_omega_rad_s, o.triangle_speed_m_s,
                              o.triangle_min_m,   o.triangle_max_m,   o.fade_in_s};
  RobotCommand command(n);
  ControllerTargets targets(n);
  Data truth_data(cycle.model());  // FK of the plant's true joint angles (same kinematics)
  Eigen::VectorXd tau_desired_prev = Eigen::VectorXd::Zero(n);
  Eigen::Isometry3d start = Eigen::Isometry3d::Identity();
  for (int k = 0; k < schedule.position_cycles + schedule.test_cycles + 1; ++k) {
    const RobotState& state = robot.read();
    targets.clear();
    const int after = k - schedule.position_cycles;  // cycles since the switch (the switch happens at after == 0)
    if (after >= 1) {
      // The previous cycle's set-point against what the sensors read at the end of its period.
      recorder.record(after - 1, dt, tau_desired_prev - state.tau_sensor_Nm,
                      tau_desired_prev - robot.truth().tau_transmitted_Nm, true_ee_error(cycle, robot, truth_data));
    }
    if (after == 0) {
      targets.low_level_mode = loop;
      start = cycle.qp().end_effector().target_pose();
      if (progress) {
        *progress << "  " << to_string(scenario) << " / " << loop_name(loop) << ": switched from position control at t = "
                  << format_fixed(state.time_s, 2) << " s" << std::endl;
      }
    }
    if (scenario == TrackingScenario::kDynamic && after > schedule.delay) {
      Vector6d offset, velocity, acceleration;
      trajectory.at((after - schedule.delay) * dt, offset, velocity, acceleration);
      Eigen::Isometry3d target = start;
      target.translation() += offset.head<3>();
      targets.has_pose = true;
      targets.pose = {target, velocity, acceleration};
    }
    validity.check_cycle(cycle.step(state, targets, command), cycle, command, after >= 1, loop);
    if (after >= 0) record_true_contact(contact, cycle, robot);
    tau_desired_prev = cycle.qp().desired_torque();
    robot.write(command);
    if (state.fault) throw ExperimentError("torque tracking", "the simulated plant faulted");
  }
}

// One scenario with one loop on a fresh plant and controller; its time series goes to the output folder.
TorqueTrackingRun run_one(const TorqueTrackingOptions& o, TrackingScenario scenario, LowLevelMode loop,
                          const ControllerRobot& controller_robot, std::ostream* progress, double& simulated) {
  const ComplianceMode mode = scenario == TrackingScenario::kStatic ? o.static_compliance : o.dynamic_compliance;
  SimRobot robot(plant_config(o, scenario));
  Controller cycle(controller_robot.model, controller_robot.actuators, controller_robot.collision,
                   cycle_settings(o, scenario, mode, controller_robot.end_of_arm));
  const RunSchedule schedule = run_schedule(o, scenario, robot.period_s());
  TrackingRecorder recorder(robot.dof(), schedule.test_cycles, schedule.skip);
  TorqueTrackingRun run;
  run.scenario = scenario;
  run.loop = loop;
  std::optional<ContactRecorder> contact = experiment_contact(cycle, experiment_body_regions(o.regions_file, o.plant_config_path));
  drive_run(o, scenario, loop, schedule, robot, cycle, recorder, contact, run, progress);
  run.elastic_modes = elastic_joint_modes(robot);
  if (contact) run.contact = contact->links();
  simulated += robot.state().time_s;
  recorder.fill_statistics(run);
  if (!o.output_dir.empty()) {
    const std::string name = std::string("torque_tracking_") + to_string(scenario) + "_" + loop_name(loop) + ".csv";
    run.csv_path = write_output_files(o.output_dir, {{name, recorder.csv()}}).front();
    if (!run.elastic_modes.empty()) {
      const std::string modes = std::string("elastic_modes_") + to_string(scenario) + "_" + loop_name(loop) + ".csv";
      write_output_files(o.output_dir, {{modes, elastic_modes_csv(run.elastic_modes)}});
    }
  }
  if (progress) {
    *progress << "  " << to_string(scenario) << " / " << loop_name(loop) << ": ||tau_d - tau_s|| RMS "
              << format_fixed(run.rms_Nm, 4) << " N.m, p95 " << format_fixed(run.p95_Nm, 4) << " N.m (true: RMS "
              << format_fixed(run.rms_true_Nm, 4) << "), EE error RMS " << format_fixed(run.ee_position_rms_mm, 2)
              << " mm" << (run.valid() ? "" : ", INVALID: " + run.invalid_reason()) << std::endl;
  }
  return run;
}

// The statistics of every run, one row each.
std::string summary_csv(const TorqueTrackingResult& result, const TorqueTrackingOptions& o) {
  std::ostringstream summary;
  summary << "scenario,loop,rms_Nm,p95_Nm,max_Nm,bias_Nm,rms_true_Nm,p95_true_Nm,window_start_s,samples,"
             "ee_rms_mm,ee_y_rms_mm,ee_z_rms_mm,ee_vy_rms_mm_s,ee_vz_rms_mm_s,elastic,qp_fallbacks,safe_stop,"
             "loop_mismatch_cycles,loop_ran,valid,invalid_reason\n";
  for (const TorqueTrackingRun& run : result.runs) {
    summary << to_string(run.scenario) << ',' << loop_name(run.loop) << ',' << format_fixed(run.rms_Nm, 6) << ','
            << format_fixed(run.p95_Nm, 6) << ',' << format_fixed(run.max_Nm, 6) << ',' << format_fixed(run.bias_Nm, 6) << ','
            << format_fixed(run.rms_true_Nm, 6) << ',' << format_fixed(run.p95_true_Nm, 6) << ','
            << format_fixed(o.transient_s, 3) << ',' << run.samples << ',' << format_fixed(run.ee_position_rms_mm, 4) << ','
            << format_fixed(run.ee_y_rms_mm, 4) << ',' << format_fixed(run.ee_z_rms_mm, 4) << ','
            << format_fixed(run.ee_vy_rms_mm_s, 3) << ',' << format_fixed(run.ee_vz_rms_mm_s, 3) << ',' << (o.elastic ? 1 : 0)
            << ',' << run.qp_fallbacks << ',' << (run.safe_stop ? 1 : 0) << ',' << run.loop_mismatch_cycles << ','
            << run.loop_ran << ',' << (run.valid() ? 1 : 0) << ',' << run.invalid_reason_csv() << '\n';
  }
  return summary.str();
}

void validate(const TorqueTrackingOptions& o) {
  const std::string src = "<torque tracking options>";
  if (o.scenarios.empty() || o.loops.empty()) throw ConfigError(src, "scenarios/loops", "nothing to run");
  if (!(o.position_phase_s >= 0.3)) throw ConfigError(src, "position_phase_s", "must be >= 0.3 s (F/T bias)");
  if (!(o.static_duration_s > o.transient_s) || !(o.dynamic_duration_s > o.transient_s) || !(o.transient_s >= 0.0)) {
    throw ConfigError(src, "static_duration_s/dynamic_duration_s", "must exceed transient_s >= 0");
  }
  if (!(o.payload_kg >= 0.0)) throw ConfigError(src, "payload_kg", "must be >= 0");
  if (!(o.torque_constant_error <= 0.5)) throw ConfigError(src, "torque_constant_error", "must be <= 0.5");
  if (!(o.triangle_min_m < 0.0 && o.triangle_max_m > 0.0 && o.triangle_speed_m_s > 0.0)) {
    throw ConfigError(src, "triangle_min_m/triangle_max_m/triangle_speed_m_s", "need min < 0 < max and speed > 0");
  }
  if (!(o.fade_in_s >= 0.0) || !(o.trajectory_delay_s >= 0.0)) {
    throw ConfigError(src, "fade_in_s/trajectory_delay_s", "must be >= 0");
  }
}

}  // namespace

const TorqueTrackingRun* TorqueTrackingResult::find(TrackingScenario scenario, LowLevelMode loop) const {
  for (const TorqueTrackingRun& r : runs) {
    if (r.scenario == scenario && r.loop == loop) return &r;
  }
  return nullptr;
}

double TorqueTrackingResult::rms_ratio(TrackingScenario scenario) const {
  const TorqueTrackingRun* custom = find(scenario, LowLevelMode::kCurrent);
  const TorqueTrackingRun* hv = find(scenario, LowLevelMode::kKinovaTorqueHighVelocity);
  return custom != nullptr && hv != nullptr && custom->rms_Nm > 0.0 ? hv->rms_Nm / custom->rms_Nm : 0.0;
}

TorqueTrackingResult run_torque_tracking(const TorqueTrackingOptions& o, std::ostream* progress) {
  validate(o);
  const auto wall_start = std::chrono::steady_clock::now();
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  TorqueTrackingResult result;
  const ControllerRobot controller_robot = load_controller_robot(o);
  for (TrackingScenario scenario : o.scenarios) {
    for (LowLevelMode loop : o.loops) {
      if (progress) {
        *progress << to_string(scenario) << " scenario, " << loop_name(loop) << " loop: "
                   << format_fixed(o.position_phase_s, 1) << " s position control, then "
                   << format_fixed(scenario == TrackingScenario::kStatic ? o.static_duration_s : o.dynamic_duration_s, 1)
                   << " s" << std::endl;
      }
      result.runs.push_back(run_one(o, scenario, loop, controller_robot, progress, result.simulated_s));
      if (!result.runs.back().csv_path.empty()) result.files.push_back(result.runs.back().csv_path);
    }
  }
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (!o.output_dir.empty()) {
    const std::vector<std::string> written = write_output_files(
        o.output_dir, {{"torque_tracking_summary.csv", summary_csv(result, o)}, {"torque_tracking.md", torque_tracking_table(result, o)}});
    result.files.insert(result.files.end(), written.begin(), written.end());
  }
  return result;
}

std::string torque_tracking_table(const TorqueTrackingResult& r, const TorqueTrackingOptions& o) {
  std::ostringstream s;
  s << "| scenario | loop | RMS [N.m] | p95 [N.m] | max [N.m] | bias [N.m] | RMS true [N.m] | p95 true [N.m] | EE RMS [mm] | "
       "EE max [mm] | valid |\n";
  s << "|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const TorqueTrackingRun& run : r.runs) {
    s << "| " << to_string(run.scenario) << " | " << loop_name(run.loop) << " | " << format_fixed(run.rms_Nm, 4) << " | "
      << format_fixed(run.p95_Nm, 4) << " | " << format_fixed(run.max_Nm, 3) << " | " << format_fixed(run.bias_Nm, 4) << " | "
      << format_fixed(run.rms_true_Nm, 4)
      << " | " << format_fixed(run.p95_true_Nm, 4) << " | " << format_fixed(run.ee_position_rms_mm, 2) << " | "
      << format_fixed(run.ee_position_max_mm, 2) << " | " << (run.valid() ? "yes" : "INVALID: " + run.invalid_reason())
      << " |\n";
  }
  std::vector<std::pair<std::string, std::vector<ContactLinkSummary>>> contact;
  for (const TorqueTrackingRun& run : r.runs) contact.emplace_back(std::string(to_string(run.scenario)) + " / " + loop_name(run.loop), run.contact);
  s << contact_overview(contact) << "\n";
  for (TrackingScenario scenario : o.scenarios) {
    const TorqueTrackingRun* c = r.find(scenario, LowLevelMode::kCurrent);
    const TorqueTrackingRun* h = r.find(scenario, LowLevelMode::kKinovaTorqueHighVelocity);
    if (c == nullptr || h == nullptr || !c->valid() || !h->valid()) continue;  // invalid runs: no ratio
    s << "- " << to_string(scenario) << ": high-velocity / custom = " << format_fixed(h->rms_Nm / c->rms_Nm, 2)
      << " (RMS), " << format_fixed(h->p95_Nm / c->p95_Nm, 2) << " (p95); true torque: "
      << format_fixed(h->rms_true_Nm / c->rms_true_Nm, 2) << " (RMS), " << format_fixed(h->p95_true_Nm / c->p95_true_Nm, 2)
      << " (p95)\n";
  }
  s << "\nError: ||tau_d[k] - tau_s[k+1]|| over the 7 joints, from " << o.transient_s
    << " s after the switch from position control; measured = the plant's torque sensors (noise "
       "0.05 N.m, zero offsets), true = the noise-free transmitted torque; bias = norm of the per-joint mean error. "
       "Custom loop: lambda "
    << o.custom_torque.transfer_gain << ", K_I " << o.custom_torque.integral_gain << " 1/s, theta "
    << o.custom_torque.integral_leak << " 1/s, friction compensation thresholds "
    << (o.friction_velocity_threshold_rad_s > 0.0 ? format_fixed(o.friction_velocity_threshold_rad_s, 3) + " rad/s"
                                                  : std::string("from actuators.yaml"))
    << " / "
    << (o.friction_acceleration_threshold_rad_s2 > 0.0 ? format_fixed(o.friction_acceleration_threshold_rad_s2, 3) + " rad/s^2"
                                                        : std::string("from actuators.yaml"))
    << ". Plant: model mismatch " << (o.model_mismatch ? "on" : "off")
    << (o.model_mismatch && o.torque_constant_error >= 0.0
            ? " (drive gain error up to " + format_fixed(100.0 * o.torque_constant_error, 0) + " %)"
            : std::string())
    << ", friction perturbation " << o.friction_perturbation << ", seed " << o.seed << ", static payload "
    << o.payload_kg << " kg, " << (o.elastic ? "elastic" : "rigid") << " joints, position loop "
    << (o.position_open_loop ? "open loop (the paper's)" : "on the measured state") << ". Simulated " << format_fixed(r.simulated_s, 1) << " s in " << format_fixed(r.wall_s, 1)
    << " s of wall time.\n";
  return s.str();
}

int run_torque_tracking_command(const TorqueTrackingOptions& options, std::ostream& out) {
  out << "torque tracking: plant " << options.plant_config_path << ", seed " << options.seed << std::endl;
  const TorqueTrackingResult r = run_torque_tracking(options, &out);
  report_experiment({torque_tracking_table(r, options), r.files, options.output_dir, options.figure_script,
                     "torque_tracking.png"},
                    out);
  return 0;
}

}  // namespace phri
