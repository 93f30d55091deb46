#include <phri/experiments/dual_compliance.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/experiments/experiment_contact.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include <algorithm>
#include <cmath>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

SimRobotConfig dual_plant(const DualComplianceOptions& o) {
  SimRobotConfig c = SimRobotConfig::from_yaml_file(o.plant_config_path);
  if (static_cast<int>(o.start_q_rad.size()) != c.dof()) {
    throw ConfigError("<dual compliance options>", "start_q_rad", "needs one value per joint");
  }
  c.initial_q_rad = o.start_q_rad;
  c.seed = o.seed;
  c.mismatch.enabled = true;
  for (const DualComplianceOptions::Guide& g : o.guides) {
    ExternalForce hand;
    hand.body = "tool";
    hand.point_m = c.tool.com_m;
    hand.frame = ExternalForce::Frame::kWorld;
    hand.force_N = g.force_N;
    hand.profile = ExternalForce::Profile::kHalfSine;
    hand.start_s = g.start_s;
    hand.duration_s = g.duration_s;
    c.disturbances.push_back(hand);
  }
  return c;
}

// One sample of the plant's truth and the controller's trigger.
struct DualSample {
  double t, wrench, ee_force, tau_norm, ee_speed, qd_norm;
  bool touched;
  Eigen::Vector3d ee;
};

DualSample sample(const SimRobot& robot, const Controller& cycle, Data& truth) {
  const SimRobot::Truth& t = robot.truth();
  forward_kinematics(cycle.model(), truth, t.q_rad, t.qd_rad_s);
  update_frame_placements(cycle.model(), truth);
  const int frame = cycle.end_effector_frame();
  const Vector6d v = frame_velocity(cycle.model(), truth, frame, ReferenceFrame::kLocalWorldAligned);
  return {t.time_s,
          cycle.trigger_wrench_norm(),
          cycle.wrench().wrench_world().head<3>().norm(),
          robot.state().tau_sensor_Nm.norm(),
          v.head<3>().norm(),
          t.qd_rad_s.norm(),
          cycle.compliance().touched(),
          truth.frame_placements[static_cast<std::size_t>(frame)].translation()};
}

// The guides' metrics from the samples: each touched interval in order is one guide.
std::vector<DualComplianceGuide> guide_metrics(const std::vector<DualSample>& s, double drift_window_s) {
  std::vector<DualComplianceGuide> guides;
  for (std::size_t k = 1; k < s.size(); ++k) {
    if (s[k].touched && !s[k - 1].touched) {
      guides.push_back({});
      guides.back().touch_s = s[k].t;
      guides.back().displacement_mm = 0.0;
    }
    if (guides.empty()) continue;
    DualComplianceGuide& g = guides.back();
    if (g.release_s < 0.0) g.peak_wrench = std::max(g.peak_wrench, s[k].wrench);
    if (!s[k].touched && s[k - 1].touched) {
      g.release_s = s[k].t;
      const auto touch = static_cast<std::size_t>(std::lround((g.touch_s - s.front().t) / (s[1].t - s[0].t)));
      g.displacement_mm = 1e3 * (s[k].ee - s[std::min(touch, k)].ee).norm();
      std::size_t end = k;
      while (end + 1 < s.size() && s[end + 1].t <= s[k].t + drift_window_s) ++end;
      g.drift_mm = 1e3 * (s[end].ee - s[k].ee).norm();
    }
  }
  return guides;
}

std::string samples_csv(const std::vector<DualSample>& s) {
  std::ostringstream out;
  out << "t_s,wrench_norm,touched,ee_force_N,tau_norm_Nm,ee_speed_m_s,qd_norm_rad_s,ee_x,ee_y,ee_z\n";
  for (std::size_t k = 0; k < s.size(); k += 2) {
    const DualSample& d = s[k];
    out << format_fixed(d.t, 3) << ',' << format_fixed(d.wrench, 4) << ',' << (d.touched ? 1 : 0) << ','
        << format_fixed(d.ee_force, 4) << ',' << format_fixed(d.tau_norm, 4) << ',' << format_fixed(d.ee_speed, 5) << ','
        << format_fixed(d.qd_norm, 5) << ',' << format_fixed(d.ee.x(), 5) << ',' << format_fixed(d.ee.y(), 5) << ','
        << format_fixed(d.ee.z(), 5) << '\n';
  }
  return out.str();
}

}  // namespace

DualComplianceResult run_dual_compliance(const DualComplianceOptions& o, std::ostream* progress) {
  if (!o.output_dir.empty()) ensure_output_directory(o.output_dir);
  const SimRobotConfig plant = dual_plant(o);
  ControllerSettings settings;
  settings.urdf_path = o.urdf_path;
  settings.actuators_path = o.actuators_path;
  settings.collision_path = o.collision_path;
  settings.end_effector_frame = o.end_effector_frame;
  settings.set_end_of_arm(plant.end_of_arm());  // the F/T sensor and tool the plant file states
  settings.initial_compliance = ComplianceMode::kDual;
  settings.initial_loop = LowLevelMode::kPosition;
  SimRobot robot(plant);
  Controller cycle(settings);
  RobotCommand command(robot.dof());
  ControllerTargets targets(robot.dof());
  Data truth(cycle.model());
  std::optional<ContactRecorder> contact = experiment_contact(cycle, experiment_body_regions(o.regions_file, o.plant_config_path));
  std::vector<DualSample> samples;
  const int cycles = static_cast<int>(std::lround(o.duration_s / robot.period_s()));
  samples.reserve(static_cast<std::size_t>(cycles));
  for (int k = 0; k < cycles; ++k) {
    const RobotState& state = robot.read();
    if (state.fault) throw ExperimentError("dual compliance", "the simulated plant faulted");
    targets.clear();
    if (k == static_cast<int>(std::lround(o.switch_s / robot.period_s()))) targets.low_level_mode = LowLevelMode::kCurrent;
    cycle.step(state, targets, command);
    robot.write(command);
    record_true_contact(contact, cycle, robot);
    samples.push_back(sample(robot, cycle, truth));
  }
  DualComplianceResult r;
  if (contact) r.contact = contact->links();
  r.guides = guide_metrics(samples, o.drift_window_s);
  r.touch_threshold = settings.compliance.touch_threshold;
  r.release_threshold = settings.compliance.release_threshold;
  if (progress) *progress << "  dual compliance: " << r.guides.size() << " guides, " << o.duration_s << " s" << std::endl;
  if (!o.output_dir.empty()) {
    r.files = write_output_files(o.output_dir, {{"dual_compliance.csv", samples_csv(samples)},
                                                {"dual_compliance.md", dual_compliance_table(r)}});
  }
  return r;
}

std::string dual_compliance_table(const DualComplianceResult& r) {
  std::ostringstream s;
  s << "| guide | touched at [s] | released at [s] | peak wrench norm | moved [mm] | drift 2 s after release [mm] |\n"
       "|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < r.guides.size(); ++i) {
    const DualComplianceGuide& g = r.guides[i];
    s << "| " << i + 1 << " | " << format_fixed(g.touch_s, 3) << " | " << format_fixed(g.release_s, 3) << " | "
      << format_fixed(g.peak_wrench, 2) << " | " << format_fixed(g.displacement_mm, 1) << " | " << format_fixed(g.drift_mm, 3)
      << " |\n";
  }
  s << "\nSchmitt trigger on the F/T wrench norm: touch above " << format_fixed(r.touch_threshold, 1) << ", release below "
    << format_fixed(r.release_threshold, 1) << ".\n";
  s << contact_overview({{"dual compliance, guided by hand", r.contact}});
  return s.str();
}

int run_dual_compliance_command(const DualComplianceOptions& options, std::ostream& out) {
  out << "dual compliance: " << options.guides.size() << " guides by hand" << std::endl;
  const DualComplianceResult r = run_dual_compliance(options, &out);
  report_experiment({dual_compliance_table(r), r.files, "", "", ""}, out);
  return 0;
}

}  // namespace phri
