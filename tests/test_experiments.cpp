// ctest-labels: physics
// The paper's experiments (src/phri/experiments) in shortened form: friction identification on two
// joints with few current levels must find the plant's friction within 5 % when the plant's friction
// differs from actuators.yaml by a random 20 %; a short torque-tracking run must show the custom
// loop tracking the moving task's torque better than Kinova's high-velocity loop. The numbers of
// the full runs come from the commands (run_*_command). Also: the friction compensation thresholds
// reach the controller through its loaded actuator table, and the error family (bad options:
// ConfigError, an unwritable output folder: IoError).
#include <phri/core/error.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/torque_tracking.hpp>
#include <phri/experiments/torque_tracking_sweep.hpp>
#include <phri/robot/actuator_table.hpp>

#include "temp_dir.hpp"

#include <gtest/gtest.h>
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <sstream>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

TEST(FrictionIdentification, FindsAPerturbedPlantsFrictionWithinFivePercent) {
  phri::FrictionIdentificationOptions o;
  o.plant_config_path = kRoot + "/configs/plant_gen3.yaml";
  o.urdf_path = kRoot + "/robots/kinova_gen3/gen3.urdf";
  o.output_dir.clear();  // no files
  o.joints = {3, 6};     // a continuous large joint and a limited small one
  o.speed_levels = 5;
  o.static_bisection_steps = 9;
  o.friction_perturbation = 0.2;
  o.seed = 3;
  std::ostringstream progress;
  const phri::FrictionIdentificationResult r = phri::identify_friction(o, &progress);
  ASSERT_EQ(r.joints.size(), 2u);
  for (const auto& e : r.joints) {
    std::printf("joint %d: Coulomb %.4f (plant %.4f, %+.2f %%), viscous %.4f (%.4f, %+.2f %%), static %.4f (%.4f, %+.2f %%), "
                "%d/%d steady levels\n",
                e.joint, e.identified.coulomb_Nm, e.plant.coulomb_Nm, 100 * e.coulomb_error(), e.identified.viscous_Nms_per_rad,
                e.plant.viscous_Nms_per_rad, 100 * e.viscous_error(), e.identified.static_Nm, e.plant.static_Nm,
                100 * e.static_error(), e.levels_used, e.levels_total);
    // The plant really differs from the nominal table, or the check would prove nothing.
    EXPECT_GT(std::abs(e.plant.coulomb_Nm - e.nominal.coulomb_Nm) + std::abs(e.plant.viscous_Nms_per_rad - e.nominal.viscous_Nms_per_rad),
              0.01);
    EXPECT_LT(std::abs(e.coulomb_error()), 0.05);
    EXPECT_LT(std::abs(e.viscous_error()), 0.05);
    EXPECT_LT(std::abs(e.static_error()), 0.05);
    EXPECT_GE(e.levels_used, 8);
    // The fit's intercept is minus the torque sensor's zero offset.
    EXPECT_NEAR(e.offset_Nm, -e.plant_sensor_offset_Nm, 0.02);
  }
  std::printf("simulated %.1f s in %.2f s\n", r.simulated_s, r.wall_s);

  // The YAML carries actuators.yaml's friction keys for each joint.
  const YAML::Node yaml = YAML::Load(phri::friction_identification_yaml(r, o));
  ASSERT_EQ(yaml["joints"].size(), 2u);
  const YAML::Node f = yaml["joints"][0]["friction"];
  EXPECT_EQ(yaml["joints"][0]["name"].as<std::string>(), "joint_3");
  EXPECT_NEAR(f["coulomb_Nm"].as<double>(), r.joints[0].identified.coulomb_Nm, 1e-4);
  EXPECT_NEAR(f["viscous_Nms_per_rad"].as<double>(), r.joints[0].identified.viscous_Nms_per_rad, 1e-4);
  EXPECT_GE(f["static_Nm"].as<double>(), f["coulomb_Nm"].as<double>());
  EXPECT_TRUE(f["velocity_threshold_rad_s"].IsScalar());
  EXPECT_TRUE(f["acceleration_threshold_rad_s2"].IsScalar());
}

phri::TorqueTrackingOptions short_tracking() {
  phri::TorqueTrackingOptions o;
  o.plant_config_path = kRoot + "/configs/plant_gen3.yaml";
  o.urdf_path = kRoot + "/robots/kinova_gen3/gen3.urdf";
  o.actuators_path = kRoot + "/robots/kinova_gen3/actuators.yaml";
  o.collision_path = kRoot + "/robots/kinova_gen3/collision.yaml";
  o.output_dir.clear();
  o.position_phase_s = 0.5;
  o.static_duration_s = 1.5;
  o.dynamic_duration_s = 2.5;  // 0.5 s hold, then the sine fades in over 1 s with the triangle under way
  return o;
}

TEST(TorqueTracking, CustomLoopTracksTheMovingTaskBetterThanTheHighVelocityLoop) {
  phri::TorqueTrackingOptions o = short_tracking();
  o.scenarios = {phri::TrackingScenario::kDynamic};
  const phri::TorqueTrackingResult r = phri::run_torque_tracking(o);
  const auto* custom = r.find(phri::TrackingScenario::kDynamic, phri::LowLevelMode::kCurrent);
  const auto* hv = r.find(phri::TrackingScenario::kDynamic, phri::LowLevelMode::kKinovaTorqueHighVelocity);
  ASSERT_NE(custom, nullptr);
  ASSERT_NE(hv, nullptr);
  std::printf("dynamic (2.5 s): RMS custom %.3f, high-velocity %.3f N.m (ratio %.2f); p95 %.3f / %.3f; EE RMS %.2f / %.2f mm\n",
              custom->rms_Nm, hv->rms_Nm, r.rms_ratio(phri::TrackingScenario::kDynamic), custom->p95_Nm, hv->p95_Nm,
              custom->ee_position_rms_mm, hv->ee_position_rms_mm);
  EXPECT_LT(custom->rms_Nm, 0.5 * hv->rms_Nm);
  EXPECT_LT(custom->p95_Nm, hv->p95_Nm);
  EXPECT_EQ(custom->qp_fallbacks, 0);
  EXPECT_EQ(hv->qp_fallbacks, 0);
}

TEST(TorqueTracking, FrictionThresholdsReachTheControllerWithoutARewrittenActuatorsFile) {
  // The controller is built from the loaded actuator table with the thresholds set on it; no copy
  // of actuators.yaml is written anywhere.
  phri::TorqueTrackingOptions o = short_tracking();
  o.scenarios = {phri::TrackingScenario::kDynamic};
  o.loops = {phri::LowLevelMode::kCurrent};
  const phri::test::TempDir dir("phri_test_tracking_thresholds");
  o.output_dir = dir.path.string();
  const phri::TorqueTrackingResult nominal = phri::run_torque_tracking(o);
  o.friction_velocity_threshold_rad_s = 0.05;
  o.friction_acceleration_threshold_rad_s2 = 0.7;
  const phri::TorqueTrackingResult changed = phri::run_torque_tracking(o);
  std::printf("dynamic (2.5 s), custom loop: RMS %.4f N.m with actuators.yaml's thresholds, %.4f N.m with 0.05 / 0.7\n",
              nominal.runs[0].rms_Nm, changed.runs[0].rms_Nm);
  EXPECT_NE(nominal.runs[0].rms_Nm, changed.runs[0].rms_Nm);
  EXPECT_FALSE(std::filesystem::exists(dir.path / "controller_actuators.yaml"));
  EXPECT_EQ(changed.files.size(), 3u);  // the run's series, the summary and the table
}

TEST(TorqueTracking, BadOptionsAreConfigErrorsAndAnUnwritableFolderAnIoError) {
  phri::TorqueTrackingOptions o = short_tracking();
  o.scenarios.clear();
  EXPECT_THROW(phri::run_torque_tracking(o), phri::ConfigError);
  o = short_tracking();
  o.output_dir = "/proc/phri_cannot_write_here";
  EXPECT_THROW(phri::run_torque_tracking(o), phri::IoError);
}

TEST(TorqueTracking, StaticHoldIsAtTheSensorNoiseFloorWithEitherLoop) {
  // With the arm at rest the observer's external torque makes tau_d follow the sensed torque for
  // both loops (the weight is compensated through it), so what is left is the sensors' and the
  // controller's noise: sqrt(7) x 0.05 N.m of torque-sensor noise alone is 0.13 N.m.
  phri::TorqueTrackingOptions o = short_tracking();
  o.scenarios = {phri::TrackingScenario::kStatic};
  const phri::TorqueTrackingResult r = phri::run_torque_tracking(o);
  for (const auto& run : r.runs) {
    std::printf("static (1.5 s, 1.25 kg): %s RMS %.3f N.m, p95 %.3f N.m, EE RMS %.3f mm\n",
                std::string(phri::to_string(run.loop)).c_str(), run.rms_Nm, run.p95_Nm, run.ee_position_rms_mm);
    EXPECT_GT(run.rms_Nm, 0.13);
    EXPECT_LT(run.rms_Nm, 0.35);
    EXPECT_LT(run.ee_position_rms_mm, 0.5);
  }
}

TEST(TorqueTracking, StaticSweepSeparatesTheLoopsOnlyBeyondTheFrictionBand) {
  // At rest the error is fixed by where friction stops the joints (torque_tracking_sweep.hpp): a
  // drive-gain error whose static imbalance |k - 1| tau_s stays below the static friction moves
  // nothing, so both loops show the same error; a larger one makes the joints slide until the error
  // reaches the loop's stick band, ~tau_st / 2 for Kinova's loop and ~tau_st / 26 for the custom one.
  phri::StaticSweepOptions o;
  o.tracking = short_tracking();
  o.tracking.static_duration_s = 3.0;
  o.torque_constant_errors = {0.0, 0.25};
  o.mismatch_seeds = {4};  // a draw whose joint-2 gain error (about -20 %) exceeds the band
  const phri::test::TempDir dir("phri_test_static_sweep");
  o.output_dir = dir.path.string();
  o.figure_script.clear();
  const phri::StaticSweepResult r = phri::run_static_sweep(o);
  ASSERT_EQ(r.rows.size(), 2u);
  ASSERT_EQ(r.summary.size(), 2u);
  for (const auto& row : r.rows) {
    std::printf("static sweep: gain error %.2f: RMS custom %.3f, high-velocity %.3f N.m, ratio %.2f; bias %.3f / %.3f N.m\n",
                row.torque_constant_error, row.custom_rms_Nm, row.high_velocity_rms_Nm, row.ratio, row.custom_bias_Nm,
                row.high_velocity_bias_Nm);
  }
  EXPECT_LT(r.rows[0].ratio, 1.3);
  EXPECT_GT(r.rows[1].ratio, 3.0);
  // The high-velocity loop's steady error stays within its band, sqrt(sum (tau_st / 2)^2).
  double band = 0.0;
  const phri::ActuatorTable drives = phri::ActuatorTable::from_yaml_file(o.tracking.actuators_path);
  for (int i = 0; i < drives.size(); ++i) band += std::pow(0.5 * drives[i].friction.static_Nm, 2);
  std::printf("static sweep: high-velocity stick band sqrt(sum (tau_st / 2)^2) = %.2f N.m\n", std::sqrt(band));
  EXPECT_LT(r.rows[1].high_velocity_bias_Nm, std::sqrt(band) + 0.3);  // + the sensors' zero offsets
  // The custom loop's stays near its own band (and the offsets).
  EXPECT_LT(r.rows[1].custom_bias_Nm, 0.35);
  EXPECT_TRUE(std::filesystem::exists(o.output_dir + "/static_sweep.csv"));
  EXPECT_TRUE(std::filesystem::exists(o.output_dir + "/static_sweep.md"));
}

}  // namespace
