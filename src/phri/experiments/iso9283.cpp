#include <phri/experiments/iso9283.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_contact.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/parallel_runs.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/trajectory/pose_move.hpp>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

constexpr double kRadToDeg = 180.0 / M_PI;
// The standard's cycle: P1 -> P5 -> P4 -> P3 -> P2 -> P1 (indices of P1..P5).
constexpr int kCycleOrder[5] = {4, 3, 2, 1, 0};

SimRobotConfig iso_plant(const Iso9283Options& o) {
  SimRobotConfig c = SimRobotConfig::from_yaml_file(o.plant_config_path);
  if (static_cast<int>(o.start_q_rad.size()) != c.dof()) {
    throw ConfigError("<iso9283 options>", "start_q_rad", "needs one value per joint");
  }
  c.initial_q_rad = o.start_q_rad;
  c.seed = o.seed;
  c.mismatch.enabled = true;  // the controller's model is not the plant's
  return c;
}

ControllerSettings iso_settings(const Iso9283Options& o, const SimRobotConfig& plant) {
  ControllerSettings s;
  s.urdf_path = o.urdf_path;
  s.actuators_path = o.actuators_path;
  s.collision_path = o.collision_path;
  s.end_effector_frame = o.end_effector_frame;
  s.set_end_of_arm(plant.end_of_arm());
  s.initial_compliance = ComplianceMode::kStiff;  // positioning: no push is let through
  s.initial_loop = LowLevelMode::kPosition;
  return s;
}

double mean(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}
double sample_std(const std::vector<double>& v) {
  if (v.size() < 2) return 0.0;
  const double m = mean(v);
  double sum = 0.0;
  for (double x : v) sum += (x - m) * (x - m);
  return std::sqrt(sum / static_cast<double>(v.size() - 1));
}
double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  const std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

// The true end effector: forward kinematics of the simulator's link-side joint angles.
Eigen::Isometry3d true_pose(const SimRobot& robot, const Controller& cycle, Data& truth) {
  forward_kinematics(cycle.model(), truth, robot.truth().q_rad);
  update_frame_placements(cycle.model(), truth);
  return truth.frame_placements[static_cast<std::size_t>(cycle.end_effector_frame())];
}

// What a measuring instrument reads: the trailing mean over kInstrumentWindow samples (20 ms at
// 1 kHz, ~50 Hz bandwidth); the attained pose is the mean over the dwell's last kAttainedWindow.
constexpr std::size_t kInstrumentWindow = 20;
constexpr std::size_t kAttainedWindow = 100;

Eigen::Vector3d mean_of(const std::vector<Eigen::Vector3d>& v, std::size_t from, std::size_t to) {
  Eigen::Vector3d sum = Eigen::Vector3d::Zero();
  for (std::size_t k = from; k < to; ++k) sum += v[k];
  return sum / static_cast<double>(std::max<std::size_t>(to - from, 1));
}

// The stabilisation time and overshoot of one arrival from the positions after the move's end.
void settle_figures(const std::vector<Eigen::Vector3d>& after, const Eigen::Vector3d& approach, double period_s,
                    const std::array<double, 2>& bands_mm, Iso9283Arrival& a) {
  const std::size_t n = after.size();
  const Eigen::Vector3d attained = mean_of(after, n - std::min(n, kAttainedWindow), n);
  std::array<std::size_t, 2> last_out = {0, 0};
  std::array<bool, 2> ever_out = {false, false};
  double overshoot = 0.0;
  for (std::size_t k = 0; k < n; ++k) {
    const Eigen::Vector3d d = mean_of(after, k + 1 - std::min(k + 1, kInstrumentWindow), k + 1) - attained;
    for (std::size_t b = 0; b < 2; ++b) {
      if (d.norm() > 1e-3 * bands_mm[b]) {
        last_out[b] = k;
        ever_out[b] = true;
      }
    }
    overshoot = std::max(overshoot, d.dot(approach));
  }
  a.attained_m = attained;
  a.overshoot_mm = 1e3 * overshoot;
  for (std::size_t b = 0; b < 2; ++b) {
    a.stabilisation_s[b] = ever_out[b] ? static_cast<double>(last_out[b] + 1) * period_s : 0.0;
    // Still outside the band in the dwell's last tenth: it did not stabilise within the dwell.
    a.settled[b] = !ever_out[b] || last_out[b] + 1 < n - n / 10;
  }
}

// One loop's run: the plant, the controller and what says whether the run counts.
struct LoopRun {
  LoopRun(const Iso9283Options& options, LowLevelMode measured_loop)
      : o(options), loop(measured_loop), plant(iso_plant(options)), robot(plant), cycle(iso_settings(options, plant)),
        command(robot.dof()), targets(robot.dof()), truth(cycle.model()), dt(robot.period_s()),
        contact(experiment_contact(cycle, experiment_body_regions(options.regions_file, options.plant_config_path))) {}

  void step(bool measuring) {
    const RobotState& state = robot.read();
    if (state.fault) throw ExperimentError("iso9283", "the simulated plant faulted");
    cycle.step(state, targets, command);
    targets.clear();
    if (robot.write(command) != WriteStatus::kOk) ++refused;
    if (measuring) {
      record_true_contact(contact, cycle, robot);
      if (cycle.status() != CycleStatus::kOk && bad_cycles++ == 0) first_bad = cycle.status();
      if (cycle.low_level().loop() != loop) ++other_loop_cycles;
      if (cycle.compliance().mode() != ComplianceMode::kStiff) ++other_mode_cycles;
    }
    t += dt;
  }

  // Start-up in the position loop (the F/T bias), the switch, a settle.
  void start_up() {
    while (t < o.switch_s) step(false);
    if (loop != LowLevelMode::kPosition) targets.low_level_mode = loop;
    bool switched = false;
    while (t < o.switch_s + o.settle_s) {
      step(switched);
      switched = true;
    }
  }

  // The move from `from` to `to`, the dwell, the arrival's figures.
  Iso9283Arrival arrive(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, int pose, std::vector<Eigen::Vector3d>& after) {
    PoseMove move;
    move.start(from, to, o.max_speed_m_s, 0.5, 0.5);
    const double t0 = t;
    while (t - t0 < move.duration()) {
      targets.has_pose = true;
      move.evaluate(t - t0, targets.pose);
      step(true);
    }
    targets.has_pose = true;
    targets.pose = PoseReference{to, Vector6d::Zero(), Vector6d::Zero()};
    after.clear();
    const double t1 = t;
    while (t - t1 < o.dwell_s) {
      step(true);
      after.push_back(true_pose(robot, cycle, truth).translation());
    }
    Iso9283Arrival a;
    a.pose = pose;
    settle_figures(after, (to.translation() - from.translation()).normalized(), dt, o.bands_mm, a);
    a.position_error_m = a.attained_m - to.translation();
    const Eigen::AngleAxisd rotation(true_pose(robot, cycle, truth).linear() * to.linear().transpose());
    a.orientation_error_rad = rotation.angle() * rotation.axis();
    return a;
  }

  // Empty when the run counts: every measured cycle ok, in stiff mode and in the loop it names, no
  // refused write.
  std::string invalid_reason() const {
    std::ostringstream why;
    if (other_loop_cycles > 0) why << other_loop_cycles << " cycles not in the " << to_string(loop) << " loop; ";
    if (other_mode_cycles > 0) why << other_mode_cycles << " cycles not in stiff mode; ";
    if (bad_cycles > 0) why << bad_cycles << " cycles not ok (first: " << to_string(first_bad) << "); ";
    if (refused > 0) why << refused << " refused writes; ";
    std::string text = why.str();
    if (!text.empty()) text.resize(text.size() - 2);
    return text;
  }

  const Iso9283Options& o;
  LowLevelMode loop;
  SimRobotConfig plant;
  SimRobot robot;
  Controller cycle;
  RobotCommand command;
  ControllerTargets targets;
  Data truth;
  double dt;
  std::optional<ContactRecorder> contact;
  double t = 0.0;
  long bad_cycles = 0, other_loop_cycles = 0, other_mode_cycles = 0, refused = 0;
  CycleStatus first_bad = CycleStatus::kOk;
};

Iso9283Loop run_loop(const Iso9283Options& o, LowLevelMode loop, std::vector<Eigen::Vector3d>* commanded_out) {
  LoopRun run(o, loop);
  run.start_up();
  // The commanded poses are the controller's (its own kinematics, as a programmed robot's are);
  // the attained ones are the truth: AP includes every error between the two.
  const Eigen::Isometry3d start = run.cycle.qp().end_effector().target_pose();
  const std::vector<Eigen::Vector3d> commanded = iso9283_cube_poses(start.translation(), o.cube_side_m);
  if (commanded_out) *commanded_out = commanded;
  Iso9283Loop result;
  result.loop = loop;
  Eigen::Isometry3d from = start;
  std::vector<Eigen::Vector3d> after;
  after.reserve(static_cast<std::size_t>(std::lround(o.dwell_s / run.dt)) + 2);
  for (int c = 0; c < o.cycles; ++c) {
    for (int pose : kCycleOrder) {
      Eigen::Isometry3d to = start;
      to.translation() = commanded[static_cast<std::size_t>(pose)];
      result.arrivals.push_back(run.arrive(from, to, pose, after));
      from = to;
    }
  }
  result.invalid_reason = run.invalid_reason();
  result.valid = result.invalid_reason.empty();
  if (run.contact) result.contact = run.contact->links();
  for (int p = 0; p < 5; ++p) {
    std::vector<Iso9283Arrival> at;
    for (const Iso9283Arrival& a : result.arrivals) {
      if (a.pose == p) at.push_back(a);
    }
    result.poses.push_back(iso9283_pose_figures(at));
  }
  return result;
}

std::string arrivals_csv(const Iso9283Result& r) {
  std::ostringstream out;
  out << "loop,valid,pose,dx_mm,dy_mm,dz_mm,da_deg,db_deg,dc_deg,stabilisation_tight_s,stabilisation_coarse_s,"
         "overshoot_mm,settled_tight,settled_coarse\n";
  for (const Iso9283Loop& l : r.loops) {
    for (const Iso9283Arrival& a : l.arrivals) {
      out << to_string(l.loop) << ',' << (l.valid ? 1 : 0) << ",P" << a.pose + 1;
      for (int i = 0; i < 3; ++i) out << ',' << format_fixed(1e3 * a.position_error_m[i], 5);
      for (int i = 0; i < 3; ++i) out << ',' << format_fixed(kRadToDeg * a.orientation_error_rad[i], 5);
      out << ',' << format_fixed(a.stabilisation_s[0], 3) << ',' << format_fixed(a.stabilisation_s[1], 3) << ','
          << format_fixed(a.overshoot_mm, 4) << ',' << (a.settled[0] ? 1 : 0) << ',' << (a.settled[1] ? 1 : 0) << '\n';
    }
  }
  return out.str();
}

std::string poses_csv(const Iso9283Result& r) {
  std::ostringstream out;
  out << "loop,valid,pose,ap_mm,rp_mm,ap_a_deg,ap_b_deg,ap_c_deg,rp_a_deg,rp_b_deg,rp_c_deg,"
         "stabilisation_tight_median_s,stabilisation_tight_max_s,stabilisation_coarse_median_s,stabilisation_coarse_max_s,"
         "overshoot_max_mm,arrivals,unsettled_tight,unsettled_coarse\n";
  for (const Iso9283Loop& l : r.loops) {
    for (std::size_t p = 0; p < l.poses.size(); ++p) {
      const Iso9283Pose& f = l.poses[p];
      out << to_string(l.loop) << ',' << (l.valid ? 1 : 0) << ",P" << p + 1 << ',' << format_fixed(f.ap_mm, 4) << ','
          << format_fixed(f.rp_mm, 4);
      for (int i = 0; i < 3; ++i) out << ',' << format_fixed(f.ap_deg[i], 4);
      for (int i = 0; i < 3; ++i) out << ',' << format_fixed(f.rp_deg[i], 4);
      for (std::size_t b = 0; b < 2; ++b) {
        out << ',' << format_fixed(f.stabilisation_median_s[b], 3) << ',' << format_fixed(f.stabilisation_max_s[b], 3);
      }
      out << ',' << format_fixed(f.overshoot_max_mm, 4) << ',' << f.arrivals << ',' << f.unsettled[0] << ','
          << f.unsettled[1] << '\n';
    }
  }
  return out.str();
}

}  // namespace

std::vector<Eigen::Vector3d> iso9283_cube_poses(const Eigen::Vector3d& centre, double side) {
  const double h = 0.5 * side;
  // The diagonal plane through C1 (-,-,-), C2 (+,+,-), C7 (+,+,+), C8 (-,-,+): its corners, and
  // each pose 10 % of the plane's diagonal from its corner.
  const Eigen::Vector3d corners[4] = {{-h, -h, -h}, {h, h, -h}, {h, h, h}, {-h, -h, h}};
  std::vector<Eigen::Vector3d> poses = {centre};
  for (const Eigen::Vector3d& c : corners) poses.push_back(centre + 0.8 * c);
  return poses;
}

Iso9283Pose iso9283_pose_figures(const std::vector<Iso9283Arrival>& arrivals) {
  Iso9283Pose f;
  f.arrivals = static_cast<int>(arrivals.size());
  if (arrivals.empty()) return f;
  Eigen::Vector3d mean_p = Eigen::Vector3d::Zero(), mean_a = Eigen::Vector3d::Zero();
  for (const Iso9283Arrival& a : arrivals) {
    mean_p += a.position_error_m;
    mean_a += a.orientation_error_rad;
  }
  mean_p /= static_cast<double>(arrivals.size());
  mean_a /= static_cast<double>(arrivals.size());
  f.ap_mm = 1e3 * mean_p.norm();  // the errors are P_j - P_c, so their mean is mean(P) - P_c
  f.ap_deg = kRadToDeg * mean_a.cwiseAbs();
  std::vector<double> l, stabilisation[2], angle[3];
  for (const Iso9283Arrival& a : arrivals) {
    l.push_back((a.position_error_m - mean_p).norm());
    for (int i = 0; i < 3; ++i) angle[i].push_back(a.orientation_error_rad[i]);
    for (std::size_t b = 0; b < 2; ++b) {
      stabilisation[b].push_back(a.stabilisation_s[b]);
      f.stabilisation_max_s[b] = std::max(f.stabilisation_max_s[b], a.stabilisation_s[b]);
      if (!a.settled[b]) ++f.unsettled[b];
    }
    f.overshoot_max_mm = std::max(f.overshoot_max_mm, a.overshoot_mm);
  }
  f.rp_mm = 1e3 * (mean(l) + 3.0 * sample_std(l));
  for (int i = 0; i < 3; ++i) f.rp_deg[i] = kRadToDeg * 3.0 * sample_std(angle[i]);
  for (std::size_t b = 0; b < 2; ++b) f.stabilisation_median_s[b] = median(stabilisation[b]);
  return f;
}

Iso9283Result run_iso9283(const Iso9283Options& o, std::ostream* progress) {
  if (o.cycles < 2) throw ConfigError("<iso9283 options>", "cycles", "needs at least 2 (RP is a spread)");
  if (o.loops.empty()) throw ConfigError("<iso9283 options>", "loops", "name at least one loop");
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  Iso9283Result r;
  r.options = o;
  r.loops.resize(o.loops.size());
  std::mutex print;
  run_in_parallel(static_cast<int>(o.loops.size()), o.jobs, [&](int i) {
    std::vector<Eigen::Vector3d> commanded;
    r.loops[static_cast<std::size_t>(i)] = run_loop(o, o.loops[static_cast<std::size_t>(i)], &commanded);
    const std::lock_guard<std::mutex> lock(print);
    if (i == 0) r.commanded = commanded;
    if (progress) {
      *progress << "  " << to_string(o.loops[static_cast<std::size_t>(i)]) << ": " << o.cycles << " cycles of 5 poses done"
                << std::endl;
    }
  });
  if (!o.output_dir.empty()) {
    r.files = write_output_files(o.output_dir, {{"iso9283_arrivals.csv", arrivals_csv(r)},
                                                {"iso9283_poses.csv", poses_csv(r)},
                                                {"iso9283.md", iso9283_table(r)}});
  }
  return r;
}

std::string iso9283_table(const Iso9283Result& r) {
  const Iso9283Options& o = r.options;
  std::ostringstream s;
  s << "ISO 9283 pose accuracy and repeatability, simulated Gen3 (plant " << o.plant_config_path << ", seed " << o.seed
    << "): " << o.cycles << " cycles P1 -> P5 -> P4 -> P3 -> P2 -> P1, cube " << format_fixed(1e3 * o.cube_side_m, 0)
    << " mm, moves at " << format_fixed(1e3 * o.max_speed_m_s, 0) << " mm/s peak, dwell " << format_fixed(o.dwell_s, 2)
    << " s, stiff mode; the attained pose is the simulator's true end effector. Worst of the five poses:\n\n";
  s << "| loop | valid | AP [mm] | RP [mm] | AP orientation [deg] | RP orientation [deg] | overshoot max [mm] |";
  for (double band : o.bands_mm) s << " stabilisation median / max [s], band " << format_general(band, 3) << " mm (unsettled) |";
  s << "\n|---|---|---|---|---|---|---|---|---|\n";
  const Iso9283Loop* position = nullptr;
  for (const Iso9283Loop& l : r.loops) {
    if (l.loop == LowLevelMode::kPosition && l.valid) position = &l;
    Iso9283Pose worst;
    std::array<double, 2> worst_median = {0.0, 0.0};
    for (const Iso9283Pose& p : l.poses) {
      worst.ap_mm = std::max(worst.ap_mm, p.ap_mm);
      worst.rp_mm = std::max(worst.rp_mm, p.rp_mm);
      worst.ap_deg[0] = std::max(worst.ap_deg[0], p.ap_deg.maxCoeff());
      worst.rp_deg[0] = std::max(worst.rp_deg[0], p.rp_deg.maxCoeff());
      worst.overshoot_max_mm = std::max(worst.overshoot_max_mm, p.overshoot_max_mm);
      worst.arrivals += p.arrivals;
      for (std::size_t b = 0; b < 2; ++b) {
        worst.stabilisation_max_s[b] = std::max(worst.stabilisation_max_s[b], p.stabilisation_max_s[b]);
        worst_median[b] = std::max(worst_median[b], p.stabilisation_median_s[b]);
        worst.unsettled[b] += p.unsettled[b];
      }
    }
    s << "| " << to_string(l.loop) << " | " << (l.valid ? "yes" : "NO: " + l.invalid_reason) << " | "
      << format_fixed(worst.ap_mm, 3) << " | " << format_fixed(worst.rp_mm, 3) << " | " << format_fixed(worst.ap_deg[0], 3)
      << " | " << format_fixed(worst.rp_deg[0], 3) << " | " << format_fixed(worst.overshoot_max_mm, 3) << " |";
    for (std::size_t b = 0; b < 2; ++b) {
      s << " " << format_fixed(worst_median[b], 3) << " / " << format_fixed(worst.stabilisation_max_s[b], 3) << " ("
        << worst.unsettled[b] << " of " << worst.arrivals << ") |";
    }
    s << "\n";
  }
  // The conclusion, from this run's numbers: each torque loop against the position loop.
  std::vector<std::pair<std::string, std::vector<ContactLinkSummary>>> contact;
  for (const Iso9283Loop& l : r.loops) contact.emplace_back(std::string(to_string(l.loop)), l.contact);
  s << contact_overview(contact) << "\n";
  if (!position) {
    s << "No valid position-loop run to compare with.\n";
    return s.str();
  }
  auto worst_of = [](const Iso9283Loop& l, double Iso9283Pose::*field) {
    double w = 0.0;
    for (const Iso9283Pose& p : l.poses) w = std::max(w, p.*field);
    return w;
  };
  const double ap0 = worst_of(*position, &Iso9283Pose::ap_mm), rp0 = worst_of(*position, &Iso9283Pose::rp_mm);
  for (const Iso9283Loop& l : r.loops) {
    if (&l == position) continue;
    if (!l.valid) {
      s << "- " << to_string(l.loop) << ": invalid (" << l.invalid_reason << "), no comparison.\n";
      continue;
    }
    const double ap = worst_of(l, &Iso9283Pose::ap_mm), rp = worst_of(l, &Iso9283Pose::rp_mm);
    s << "- " << to_string(l.loop) << ": AP " << format_fixed(ap, 3) << " mm vs the position loop's " << format_fixed(ap0, 3)
      << " mm (" << (ap <= ap0 ? "as accurate or better" : format_fixed(ap / std::max(ap0, 1e-9), 1) + "x the error")
      << "); RP " << format_fixed(rp, 3) << " mm vs " << format_fixed(rp0, 3) << " mm ("
      << (rp <= rp0 ? "as repeatable or better" : format_fixed(rp / std::max(rp0, 1e-9), 1) + "x the spread") << ").\n";
  }
  return s.str();
}

int run_iso9283_command(const Iso9283Options& options, std::ostream& out) {
  out << "ISO 9283 pose test: " << options.loops.size() << " loops x " << options.cycles << " cycles x 5 poses" << std::endl;
  const Iso9283Result r = run_iso9283(options, &out);
  report_experiment({iso9283_table(r), r.files, options.output_dir, options.figure_script, "iso9283.png"}, out);
  bool all_valid = true;
  for (const Iso9283Loop& l : r.loops) all_valid = all_valid && l.valid;
  return all_valid ? 0 : 1;
}

}  // namespace phri
