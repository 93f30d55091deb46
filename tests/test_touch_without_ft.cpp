// ctest-labels: physics integration
// Dual compliance on an arm without an F/T sensor (issue 40): the touch trigger reads the
// end-effector wrench estimated from the momentum observer's tau_ext, F = (J J^T)^-1 J tau_ext.
// The arm is robots/example_6dof with a tool on its flange and no sensor. Independent references:
// the push the plant applies (its force in world axes, scaled by its own profile) and the flange's
// position in MuJoCo.
#include <phri/config/config.hpp>
#include <phri/control/controller.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>

#include "hand_push.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

const std::string kExample = std::string(PHRI_SOURCE_DIR) + "/robots/example_6dof";

// robots/example_6dof copied, its end of arm a tool on the flange (no F/T sensor).
std::string tool_only_bundle() {
  const std::string folder = phri::test::temp_path("phri_test_touch_without_ft", "tool_only");
  std::filesystem::create_directories(folder);
  for (const char* file : {"example_6dof.urdf", "actuators.yaml"}) {
    std::filesystem::copy_file(kExample + "/" + file, folder + "/" + file, std::filesystem::copy_options::overwrite_existing);
  }
  std::ifstream in(kExample + "/robot.yaml");
  std::stringstream s;
  s << in.rdbuf();
  std::string robot = s.str();
  const std::size_t begin = robot.find("\nend_of_arm:");
  const std::size_t end = robot.find("\nplant:");
  robot.replace(begin, end - begin,
                "\nend_of_arm: {tool: {mass_kg: 0.8, com_m: [0.01, -0.02, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}}\n");
  std::ofstream(folder + "/robot.yaml") << robot;
  return folder;
}

Eigen::Vector3d flange(const phri::SimRobot& robot) {
  const int id = mj_name2id(robot.mujoco_model(), mjOBJ_SITE, "flange");
  const mjtNum* p = robot.mujoco_data()->site_xpos + 3 * id;
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

struct TouchRun {
  int touches = 0;
  bool touched_at_end = true;
  bool wrench_ever_valid = false;
  bool estimated_source = true;
  double moved_m = 0.0;          // flange displacement from start to the end of the push
  double drift_after_m = 0.0;    // largest flange motion after it settled past the release
  double force_error = 0.0;      // mean |F_est - F_applied| / |F_applied| while the push is held
  double condition = 0.0;
  double peak_norm = 0.0;
  double rest_norm = 0.0;        // largest estimated wrench norm before the push
};

// A 15 N push on the tool along world y from 0.5 s, held 0.35 s, then released; 2.5 s in all.
TouchRun push_tool(phri::ComplianceMode mode) {
  const std::string folder = tool_only_bundle();
  const std::string run = "robot: " + folder + "\nrun: {duration_s: 3}\nfsm: {startup: {enabled: false}}\n"
                          "logging: {enabled: false}\ngamepad: {enabled: false}\n";
  phri::Config config = phri::Config::from_yaml_string(run, "touch_without_ft.yaml", folder);
  EXPECT_FALSE(config.plant.ft_sensor_present());
  config.controller.initial_compliance = mode;
  const Eigen::Vector3d force(0.0, 15.0, 0.0);
  const double start = 0.5, hold = 0.35;
  config.plant.disturbances.push_back(phri::test::hand_push("tool", Eigen::Vector3d(0, 0, 0.06), force, start, hold));
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::RobotCommand command(robot.dof());
  const Eigen::Vector3d p0 = flange(robot);
  Eigen::Vector3d settled = p0;
  TouchRun out;
  double error_sum = 0.0;
  long error_samples = 0;
  const double settle_at = start + hold + 0.4;
  for (long k = 0; k < 2500; ++k) {
    const phri::RobotState& state = robot.read();
    out.wrench_ever_valid |= state.wrench.valid;
    cycle.step(state, command);
    EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
    const double t = state.time_s;
    out.estimated_source &= cycle.touch_source() == phri::Controller::TouchSource::kEstimated;
    const double norm = cycle.estimated_wrench().norm();
    if (t < start) out.rest_norm = std::max(out.rest_norm, norm);
    out.peak_norm = std::max(out.peak_norm, norm);
    // The force part against the plant's push, while it is held (the observer's lag, 20 ms, past).
    if (t > start + 0.15 && t < start + hold) {
      const double scale = config.plant.disturbances[0].scale_at(t);
      error_sum += (cycle.estimated_wrench().head<3>() - scale * force).norm() / force.norm();
      ++error_samples;
      out.condition = cycle.estimated_wrench_condition();
    }
    if (t <= start + hold + 0.06) out.moved_m = (flange(robot) - p0).norm();
    if (t > settle_at && t < settle_at + 1e-3 + 1e-9) settled = flange(robot);
    if (t > settle_at) out.drift_after_m = std::max(out.drift_after_m, (flange(robot) - settled).norm());
  }
  EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
  out.touches = cycle.compliance().touch_count();
  out.force_error = error_samples > 0 ? error_sum / static_cast<double>(error_samples) : 1.0;
  out.touched_at_end = cycle.compliance().touched();
  return out;
}

TEST(TouchWithoutFt, DualComplianceFiresOnAToolPushFromTheEstimatedWrench) {
  const TouchRun dual = push_tool(phri::ComplianceMode::kDual);
  const TouchRun null_space = push_tool(phri::ComplianceMode::kNullSpace);
  std::printf("no F/T, dual: touches %d, estimated wrench at rest <= %.2f, peak %.1f, force error %.1f %% (cond(J) %.1f), "
              "flange moved %.1f mm under the push, drift after release %.2f mm\n",
              dual.touches, dual.rest_norm, dual.peak_norm, 100 * dual.force_error, dual.condition, 1e3 * dual.moved_m,
              1e3 * dual.drift_after_m);
  std::printf("no F/T, null space (no trigger): flange moved %.1f mm under the same push\n", 1e3 * null_space.moved_m);
  EXPECT_FALSE(dual.wrench_ever_valid);
  EXPECT_TRUE(dual.estimated_source);
  EXPECT_LT(dual.rest_norm, 4.0);       // below the release threshold: no standing touch at rest
  EXPECT_LT(dual.force_error, 0.25);    // the push's force (less the dead band), within 25 %
  EXPECT_GT(dual.touches, 0);           // "touched" fired (and released)
  EXPECT_FALSE(dual.touched_at_end);    // released again once the hand left
  EXPECT_GT(dual.moved_m, 0.015);       // the end effector went with the hand
  EXPECT_GT(dual.moved_m, 5.0 * null_space.moved_m);  // far beyond what the stiff task yields
  EXPECT_LT(dual.drift_after_m, 2e-3);  // and holds where it was released
}

}  // namespace
