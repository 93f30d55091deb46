#include <phri/experiments/drop_test.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_contact.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/parallel_runs.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <mutex>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

// What every drop shares, loaded once and only read by the threads.
struct DropShared {
  const DropTestOptions& o;
  SimRobotConfig plant;
  Model model;
  ActuatorTable actuators;
  std::optional<CollisionModel> collision;
  std::optional<BodyRegionMap> regions;  // power and force limiting's figures
};

ControllerSettings drop_settings(const DropTestOptions& o, DropMode mode, const SimRobotConfig& plant) {
  ControllerSettings s;
  s.end_effector_frame = o.end_effector_frame;
  s.set_end_of_arm(plant.end_of_arm());  // the controller knows the F/T sensor and tool the plant file states
  s.initial_loop = LowLevelMode::kPosition;
  s.observer_gain = o.observer_gain;
  s.external_torque_source = o.external_torque_source;
  s.position_mode_open_loop = o.position_open_loop;
  // Position mode: the vendor servo holds the QP's pose; the task is stiff (no compliance to show).
  s.initial_compliance = mode == DropMode::kTorque ? o.torque_compliance : ComplianceMode::kStiff;
  return s;
}

SimRobotConfig drop_plant(const DropShared& sh, int index) {
  SimRobotConfig c = sh.plant;
  const DropTestOptions& o = sh.o;
  c.initial_q_rad = o.start_q_rad;
  c.seed = o.first_seed + static_cast<std::uint64_t>(index);
  c.mismatch.enabled = o.model_mismatch;
  c.mismatch.seed = o.first_seed + 1000 + static_cast<std::uint64_t>(index);
  c.drop_test.enabled = true;
  c.drop_test.release_time_s = o.release_s;
  c.drop_test.held_by_hand = o.held_by_hand;
  c.elasticity.enabled = o.elastic;
  if (o.servo_encoder) c.elasticity.position_loop_encoder = *o.servo_encoder;
  if (o.joint_stiffness_Nm_per_rad) c.elasticity.stiffness_Nm_per_rad = *o.joint_stiffness_Nm_per_rad;
  if (o.cable_damping_Ns_per_m) c.drop_test.cable_damping_Ns_per_m = *o.cable_damping_Ns_per_m;
  if (o.cable_stiffness_N_per_m) c.drop_test.cable_stiffness_N_per_m = *o.cable_stiffness_N_per_m;
  if (o.release_spread_scale) {
    c.drop_test.release_vertical_spread_m *= *o.release_spread_scale;
    c.drop_test.release_horizontal_spread_m *= *o.release_spread_scale;
  }
  if (o.vendor_gain_scale) {
    for (std::vector<double>* v : {&c.vendor.position_kp_Nm_per_rad, &c.vendor.position_kd_Nms_per_rad,
                                   &c.vendor.position_ki_Nm_per_rad_s}) {
      for (double& x : *v) x *= *o.vendor_gain_scale;
    }
    c.physics_rate_Hz *= std::max(1.0, std::ceil(*o.vendor_gain_scale - 1e-9));
  }
  return c;
}

const char* servo_encoder_words(SimRobotConfig::Elasticity::Encoder e) {
  switch (e) {
    case SimRobotConfig::Elasticity::Encoder::kMotor: return "motor encoder";
    case SimRobotConfig::Elasticity::Encoder::kMotorCompensated: return "motor encoder less the measured deflection";
    case SimRobotConfig::Elasticity::Encoder::kLink: return "link encoder";
  }
  return "?";
}

// The loop the row names: torque mode runs torque_loop from switch_s on, position mode the position loop.
LowLevelMode expected_loop(const DropTestOptions& o, DropMode mode) {
  return mode == DropMode::kTorque ? o.torque_loop : LowLevelMode::kPosition;
}

// The metrics of a finished drop: peak, residual, its shift from before the drop, stabilisation per band.
void finish_drop(const DropTestOptions& o, double dt, DropRun& run) {
  drop_metrics(run.error_mm, dt, o.residual_window_s, run.peak_mm, run.residual_mm);
  const std::size_t tail = std::min(run.error_mm.size(), static_cast<std::size_t>(std::lround(o.residual_window_s / dt)));
  double mean = 0.0;
  for (std::size_t k = run.error_mm.size() - tail; k < run.error_mm.size(); ++k) mean += run.error_mm[k];
  mean /= static_cast<double>(std::max<std::size_t>(1, tail));
  run.residual_shift_mm = std::abs(mean - run.before_mm);
  for (double band : o.stabilisation_bands_mm) {
    const Stabilisation s = drop_stabilisation(run.error_mm, dt, o.residual_window_s, band);
    run.band_stabilisation_s.push_back(s.time_s);
    run.band_censored.push_back(s.censored ? 1 : 0);
  }
  run.stabilisation_s = run.band_stabilisation_s.front();
  run.censored = run.band_censored.front() != 0;
}

// One drop on a fresh plant and controller: hold, (torque mode: switch to the custom loop), release,
// record e_z before the release (its mean) and from the catch for window_s.
DropRun run_drop(const DropShared& sh, DropMode mode, int index) {
  const DropTestOptions& o = sh.o;
  SimRobot robot(drop_plant(sh, index));
  Controller cycle(sh.model, sh.actuators, sh.collision, drop_settings(o, mode, sh.plant));
  const int n = robot.dof();
  const double dt = robot.period_s();
  const int window = static_cast<int>(std::lround(o.window_s / dt));
  const int switch_k = mode == DropMode::kTorque ? static_cast<int>(std::lround(o.switch_s / dt)) : 0;
  const int before_k = static_cast<int>(std::lround((o.release_s - o.pre_release_s) / dt));
  const int release_k = static_cast<int>(std::lround(o.release_s / dt));
  RobotCommand command(n);
  ControllerTargets targets(n);
  Data truth(cycle.model());
  std::optional<ContactRecorder> contact = experiment_contact(cycle, sh.regions);
  const auto ee = static_cast<std::size_t>(cycle.end_effector_frame());
  DropRun run;
  run.mode = mode;
  run.index = index;
  run.seed = robot.config().seed;
  run.error_mm.reserve(static_cast<std::size_t>(window));
  int before_samples = 0;
  // The catch must come within 1 s of the release (a 25 cm fall takes 0.23 s).
  const int last = static_cast<int>(std::lround((o.release_s + 1.0 + o.window_s) / dt));
  for (int k = 0; k < last && static_cast<int>(run.error_mm.size()) < window; ++k) {
    const RobotState& state = robot.read();
    if (state.fault) throw ExperimentError("drop test", "the simulated plant faulted (drop " + std::to_string(index) + ")");
    targets.clear();
    if (mode == DropMode::kTorque && k == switch_k) targets.low_level_mode = o.torque_loop;
    const CycleStatus status = cycle.step(state, targets, command);
    run.check_cycle(status, cycle, command, k >= switch_k + 1, expected_loop(o, mode));
    robot.write(command);
    record_true_contact(contact, cycle, robot);
    const SimRobot::Truth& t = robot.truth();
    const bool recording = !run.error_mm.empty() || (t.drop_released && t.cable_force_N > 0.0);
    if (!recording && (k < before_k || k >= release_k)) continue;
    forward_kinematics(cycle.model(), truth, t.q_rad);
    update_frame_placements(cycle.model(), truth);
    const double e = 1e3 * (cycle.qp().end_effector().target_pose().translation().z() -
                            truth.frame_placements[ee].translation().z());
    if (!recording) {
      run.before_mm += e;
      ++before_samples;
      continue;
    }
    if (run.error_mm.empty()) run.catch_s = t.time_s;
    run.error_mm.push_back(static_cast<float>(e));
  }
  if (static_cast<int>(run.error_mm.size()) < window) {
    throw ExperimentError("drop test", "no catch within 1 s of the release (drop " + std::to_string(index) + ")");
  }
  run.before_mm /= std::max(1, before_samples);
  if (contact) run.contact = contact->links();
  finish_drop(o, dt, run);
  return run;
}

void validate(const DropTestOptions& o) {
  const std::string src = "<drop test options>";
  if (o.drops < 1 || o.jobs < 1) throw ConfigError(src, "drops/jobs", "need at least one drop and one job");
  if (!(o.switch_s >= 0.3 && o.release_s > o.switch_s + 0.5)) {
    throw ConfigError(src, "switch_s/release_s", "need switch_s >= 0.3 s (F/T bias) and release_s > switch_s + 0.5 s");
  }
  if (!(o.window_s > o.residual_window_s && o.residual_window_s > 0.0)) {
    throw ConfigError(src, "window_s/residual_window_s", "need window_s > residual_window_s > 0");
  }
  if (o.stabilisation_bands_mm.empty() ||
      std::any_of(o.stabilisation_bands_mm.begin(), o.stabilisation_bands_mm.end(), [](double b) { return !(b > 0.0); })) {
    throw ConfigError(src, "stabilisation_bands_mm", "need at least one band, each > 0 mm");
  }
  if (!(o.pre_release_s > 0.0 && o.pre_release_s < o.release_s - o.switch_s)) {
    throw ConfigError(src, "pre_release_s", "must be > 0 and end after the switch to torque control");
  }
  if (!(o.observer_gain > 0.0 && o.observer_gain * 1e-3 < 1.0)) throw ConfigError(src, "observer_gain", "must be in (0, 1000)");
}

std::string band_name(double band_mm) {
  std::string b = format_fixed(band_mm, 2);
  std::replace(b.begin(), b.end(), '.', 'p');
  return b + "mm";
}

// One row per drop: metrics, censoring, per-band stabilisation, then validity (valid 0/1 and why not).
std::string runs_csv(const DropTestResult& r, const DropTestOptions& o) {
  std::ostringstream s;
  s << "mode,index,seed,catch_s,peak_mm,stabilisation_s,censored,residual_mm,before_mm,residual_shift_mm";
  for (double b : o.stabilisation_bands_mm) s << ",stabilisation_" << band_name(b) << "_s,censored_" << band_name(b);
  s << ",qp_fallbacks,safe_stop,loop_mismatch_cycles,loop_ran,valid,invalid_reason\n";
  for (const DropRun& d : r.runs) {
    s << to_string(d.mode) << ',' << d.index << ',' << d.seed << ',' << format_fixed(d.catch_s, 3) << ','
      << format_fixed(d.peak_mm, 5) << ',' << format_fixed(d.stabilisation_s, 3) << ',' << (d.censored ? 1 : 0) << ','
      << format_fixed(d.residual_mm, 5) << ',' << format_fixed(d.before_mm, 5) << ',' << format_fixed(d.residual_shift_mm, 5);
    for (std::size_t b = 0; b < d.band_stabilisation_s.size(); ++b) {
      s << ',' << format_fixed(d.band_stabilisation_s[b], 3) << ',' << static_cast<int>(d.band_censored[b]);
    }
    s << ',' << d.qp_fallbacks << ',' << (d.safe_stop ? 1 : 0) << ',' << d.loop_mismatch_cycles << ',' << d.loop_ran << ','
      << (d.valid() ? 1 : 0) << ',' << d.invalid_reason_csv() << '\n';
  }
  return s.str();
}

std::string traces_csv(const DropTestResult& r, double dt) {
  std::ostringstream s;
  s << "t_s";
  for (const DropRun& d : r.runs) s << ',' << to_string(d.mode) << '_' << d.index;
  s << '\n';
  const std::size_t samples = r.runs.empty() ? 0 : r.runs.front().error_mm.size();
  for (std::size_t k = 0; k < samples; k += 2) {  // every 2 ms: the figure, not the metrics
    s << format_fixed(static_cast<double>(k) * dt, 3);
    for (const DropRun& d : r.runs) s << ',' << format_fixed(d.error_mm[k], 4);
    s << '\n';
  }
  return s.str();
}

void mean_sd(const std::vector<double>& v, double& mean, double& sd) {
  mean = 0.0;
  for (double x : v) mean += x;
  mean /= static_cast<double>(std::max<std::size_t>(1, v.size()));
  double ss = 0.0;
  for (double x : v) ss += (x - mean) * (x - mean);
  sd = v.size() > 1 ? std::sqrt(ss / static_cast<double>(v.size() - 1)) : 0.0;
}

}  // namespace

void drop_metrics(const std::vector<float>& e, double dt, double residual_window_s, double& peak_mm, double& residual_mm) {
  peak_mm = 0.0;
  for (float x : e) peak_mm = std::max(peak_mm, static_cast<double>(std::abs(x)));
  const std::size_t tail = std::min(e.size(), static_cast<std::size_t>(std::lround(residual_window_s / dt)));
  double mean = 0.0;
  for (std::size_t k = e.size() - tail; k < e.size(); ++k) mean += e[k];
  mean /= static_cast<double>(std::max<std::size_t>(1, tail));
  residual_mm = std::abs(mean);
}

Stabilisation drop_stabilisation(const std::vector<float>& e, double dt, double residual_window_s, double band_mm) {
  const std::size_t tail = std::min(e.size(), static_cast<std::size_t>(std::lround(residual_window_s / dt)));
  double mean = 0.0;
  for (std::size_t k = e.size() - tail; k < e.size(); ++k) mean += e[k];
  mean /= static_cast<double>(std::max<std::size_t>(1, tail));
  // The first sample after which the error never leaves the band around its final mean.
  std::size_t settled = 0;
  for (std::size_t k = 0; k < e.size(); ++k) {
    if (std::abs(e[k] - mean) > band_mm) settled = k + 1;
  }
  const std::size_t limit = e.size() - tail;
  Stabilisation s;
  s.censored = settled > limit;
  s.time_s = static_cast<double>(s.censored ? limit : settled) * dt;
  return s;
}

DropTestResult run_drop_test(const DropTestOptions& o, std::ostream* progress) {
  validate(o);
  const auto wall_start = std::chrono::steady_clock::now();
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  SimRobotConfig plant = SimRobotConfig::from_yaml_file(o.plant_config_path);
  const ControllerSettings settings = drop_settings(o, DropMode::kTorque, plant);
  Model model = Model::from_urdf_file(o.urdf_path, Controller::model_options(settings));
  std::optional<CollisionModel> collision;
  if (!o.collision_path.empty()) collision = CollisionModel::from_yaml_file(o.collision_path, model);
  const DropShared shared{o, std::move(plant), std::move(model),
                          ActuatorTable::from_yaml_file(o.actuators_path), std::move(collision),
                          experiment_body_regions(o.regions_file, o.plant_config_path)};
  DropTestResult result;
  result.servo_encoder = o.servo_encoder.value_or(shared.plant.elasticity.position_loop_encoder);
  result.runs.resize(static_cast<std::size_t>(2 * o.drops));
  std::mutex mutex;
  int done = 0;
  run_in_parallel(2 * o.drops, o.jobs, [&](int task) {
    const DropMode mode = task < o.drops ? DropMode::kTorque : DropMode::kPosition;
    DropRun run = run_drop(shared, mode, task % o.drops);
    const std::lock_guard<std::mutex> lock(mutex);
    ++done;
    if (progress) {
      *progress << "  [" << done << "/" << 2 * o.drops << "] " << to_string(mode) << " drop " << run.index << ": peak "
                << format_fixed(run.peak_mm, 3) << " mm, stabilisation " << (run.censored ? "> " : "")
                << format_fixed(run.stabilisation_s, 3) << " s" << (run.censored ? " (censored)" : "") << ", residual "
                << format_fixed(run.residual_mm, 4) << " mm"
                << (run.invalid_reason().empty() ? "" : ", INVALID: " + run.invalid_reason()) << std::endl;
    }
    result.simulated_s += run.catch_s + o.window_s;
    result.runs[static_cast<std::size_t>(task)] = std::move(run);
  });
  result.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  if (!o.output_dir.empty()) {
    result.files = write_output_files(o.output_dir, {{"drop_test_runs.csv", runs_csv(result, o)},
                                                     {"drop_test_traces.csv", traces_csv(result, shared.plant.control_period_s)},
                                                     {"drop_test.md", drop_test_table(result, o)}});
  }
  return result;
}

std::string drop_test_table(const DropTestResult& r, const DropTestOptions& o) {
  // Valid drops only; stabilisation as the median of the settled ones plus the censored count (a
  // censored drop has no settling time to average).
  auto column = [&](DropMode mode, double DropRun::*field, bool settled_only) {
    std::vector<double> v;
    for (const DropRun& d : r.runs) {
      if (d.mode == mode && d.invalid_reason().empty() && !(settled_only && d.censored)) v.push_back(d.*field);
    }
    return v;
  };
  auto count = [&](DropMode mode, bool censored_only) {
    return std::count_if(r.runs.begin(), r.runs.end(), [&](const DropRun& d) {
      return d.mode == mode && d.invalid_reason().empty() && (!censored_only || d.censored);
    });
  };
  std::ostringstream s;
  s << "| metric | torque mean | torque sd | position mean | position sd |\n|---|---|---|---|---|\n";
  const std::pair<const char*, double DropRun::*> metrics[] = {{"peak [mm]", &DropRun::peak_mm},
                                                               {"residual [mm]", &DropRun::residual_mm},
                                                               {"residual shift from before the drop [mm]", &DropRun::residual_shift_mm},
                                                               {"stabilisation, settled drops only [s]", &DropRun::stabilisation_s}};
  for (const auto& [name, field] : metrics) {
    const bool settled_only = field == &DropRun::stabilisation_s;
    double mt = 0, st = 0, mp = 0, sp = 0;
    mean_sd(column(DropMode::kTorque, field, settled_only), mt, st);
    mean_sd(column(DropMode::kPosition, field, settled_only), mp, sp);
    s << "| " << name << " | " << format_fixed(mt, 3) << " | " << format_fixed(st, 3) << " | " << format_fixed(mp, 3)
      << " | " << format_fixed(sp, 3) << " |\n";
  }
  s << "\nValid drops: torque " << count(DropMode::kTorque, false) << ", position " << count(DropMode::kPosition, false)
    << " of " << o.drops << " each (invalid: safe stop, QP fallback or another loop; left out). Not settled within "
    << format_fixed(o.stabilisation_bands_mm.front(), 2) << " mm by " << format_fixed(o.window_s - o.residual_window_s, 1)
    << " s (censored): torque " << count(DropMode::kTorque, true) << ", position " << count(DropMode::kPosition, true) << ".\n";
  s << "\n" << o.drops << " drops per mode; torque mode: " << to_string(o.torque_loop) << " loop, "
    << to_string(o.torque_compliance) << " compliance, external torque " << to_string(o.external_torque_source)
    << ", K_O " << format_fixed(o.observer_gain, 0) << " 1/s; position mode "
    << (o.position_open_loop ? "open loop (the paper's)" : "on the measured state") << "; "
    << (o.elastic ? std::string("elastic joints, servo on the ") + servo_encoder_words(r.servo_encoder)
                  : std::string("rigid joints"))
    << "; release at " << format_fixed(o.release_s, 1)
    << " s, metrics over " << format_fixed(o.window_s, 1) << " s after the catch. Simulated "
    << format_fixed(r.simulated_s, 0) << " s in " << format_fixed(r.wall_s, 1) << " s of wall time (" << o.jobs
    << " jobs).\n";
  std::vector<std::pair<std::string, std::vector<ContactLinkSummary>>> contact(2);
  for (const DropRun& run : r.runs) {
    auto& mode = contact[run.mode == DropMode::kTorque ? 0 : 1];
    mode.first = std::string(to_string(run.mode)) + " mode, all drops";
    merge_contact(mode.second, run.contact);
  }
  s << contact_overview(contact);
  return s.str();
}

int run_drop_test_command(const DropTestOptions& options, std::ostream& out) {
  out << "drop test: " << options.drops << " + " << options.drops << " drops, " << options.jobs << " jobs" << std::endl;
  const DropTestResult r = run_drop_test(options, &out);
  report_experiment({drop_test_table(r, options), r.files, options.output_dir, options.figure_script, "drop_test.png"}, out);
  return 0;
}

}  // namespace phri
