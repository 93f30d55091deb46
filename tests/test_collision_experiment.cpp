// ctest-labels: physics
// The simulated collision test (experiments/collision.hpp): the body-region surrogate against the
// standard's two-body closed form (peak force v sqrt(mu k), energy), its contact rules, its force
// as MuJoCo's own F/T sensor sees it on the tool, then a short experiment on the plant that checks
// what each run names ran and the constraint's effect.
#include <phri/experiments/collision.hpp>
#include <phri/sim/body_region_surrogate.hpp>
#include <phri/sim/sim_robot.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

// A free robot mass m_R at speed v meets the free surrogate (semi-implicit Euler, as the plant).
// The two-body model: the peak force is v sqrt(mu k), mu = (1/m_H + 1/m_R)^-1, and the energy
// 1/2 mu v^2 is stored in the spring at the peak: F^2 / (2 k).
TEST(BodyRegionSurrogate, AFreeMassHittingItPeaksAtTheTwoBodyModelsForce) {
  for (double m_r : {0.8, 2.0, 6.0}) {
    phri::BodyRegionSurrogateSettings s;
    s.mass_kg = 0.6;
    s.stiffness_N_per_m = 75000.0;
    phri::BodyRegionSurrogate region(s);
    const double dt = 1e-5, v0 = 0.5;
    double x = -1e-3, v = v0, peak = 0.0;
    for (int k = 0; k < 200000; ++k) {
      const double f = region.step(x, true, dt);
      peak = std::max(peak, f);
      v -= f / m_r * dt;
      x += v * dt;
    }
    const double mu = 1.0 / (1.0 / s.mass_kg + 1.0 / m_r);
    EXPECT_NEAR(peak, v0 * std::sqrt(mu * s.stiffness_N_per_m), 2e-3 * peak) << "m_R " << m_r;
    // Momentum is conserved and the contact is elastic: the robot leaves at (m_R - m_H) / (m_R + m_H) v0.
    EXPECT_NEAR(v, (m_r - s.mass_kg) / (m_r + s.mass_kg) * v0, 1e-3 * v0);
    EXPECT_NEAR(region.velocity_m_s(), 2.0 * m_r / (m_r + s.mass_kg) * v0, 1e-3 * v0);
    EXPECT_EQ(region.force_N(), 0.0);  // they parted
  }
}

TEST(BodyRegionSurrogate, BackedByAWallItIsASpringThatOnlyPushesAndIsEnteredOnlyThroughItsFace) {
  phri::BodyRegionSurrogateSettings s;
  s.stiffness_N_per_m = 40000.0;
  s.backed_by_wall = true;
  phri::BodyRegionSurrogate region(s);
  EXPECT_EQ(region.step(-0.01, true, 1e-3), 0.0);           // in front of the face
  EXPECT_NEAR(region.step(0.002, true, 1e-3), 80.0, 1e-9);  // 2 mm in: k x
  EXPECT_NEAR(region.step(0.003, true, 1e-3), 120.0, 1e-9);
  EXPECT_EQ(region.displacement_m(), 0.0);                  // the wall holds the mass
  EXPECT_EQ(region.step(0.003, false, 1e-3), 0.0);          // slid off the face's edge
  // Back over the face while 3 mm deep: it came from beside the body, not through its face.
  EXPECT_EQ(region.step(0.003, true, 1e-3), 0.0);
  EXPECT_EQ(region.step(-0.001, true, 1e-3), 0.0);
  EXPECT_NEAR(region.step(0.001, true, 1e-3), 40.0, 1e-9);  // through the face again
  s.damping_Ns_per_m = 100.0;
  phri::BodyRegionSurrogate damped(s);
  EXPECT_NEAR(damped.step(0.001, true, 1e-3), 40.0, 1e-9);   // no rate on the first step
  EXPECT_NEAR(damped.step(0.002, true, 1e-3), 80.0 + 100.0 * 1.0, 1e-9);  // + c dx/dt (1 m/s)
  EXPECT_EQ(damped.step(0.0015, true, 1e-6), 0.0);  // pulling back fast: it never pulls
}

// The arm holds its pose; a wall-backed region pressed 2 mm onto the tool. MuJoCo's F/T sensor
// between the adapter and the tool sees the region's force (in world axes) on top of what it read
// before, once the arm has settled.
TEST(BodyRegionSurrogate, ItsForceOnTheToolIsWhatTheSimulatorsFtSensorMeasures) {
  phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.noise.torque_sensor_std_Nm = 0.0;
  c.surrogate.enabled = true;
  c.surrogate.region.stiffness_N_per_m = 10000.0;
  c.surrogate.region.backed_by_wall = true;
  c.surrogate.face_m = Eigen::Vector3d(0.0, 0.0, -100.0);
  phri::SimRobot robot(c);
  auto sensor_force_world = [&] {
    return Eigen::Vector3d(robot.truth().sensor_rotation * robot.truth().wrench_sensor.head<3>());
  };
  for (int k = 0; k < 500; ++k) robot.read();
  const Eigen::Vector3d before = sensor_force_world();
  const Eigen::Vector3d d = Eigen::Vector3d(0.3, -1.0, 0.2).normalized();  // the tool moves along d into the face
  robot.set_surrogate_face(robot.tool_point_along(d) - 0.002 * d, -d);
  for (int k = 0; k < 1500; ++k) robot.read();
  const double force = robot.truth().surrogate_force_N;
  EXPECT_GT(force, 5.0);
  EXPECT_NEAR(force, 10000.0 * robot.truth().surrogate_compression_m, 1e-9);
  const Eigen::Vector3d change = sensor_force_world() - before;
  std::printf("region force %.3f N; F/T change (world) %.3f %.3f %.3f N\n", force, change.x(), change.y(), change.z());
  // The sensor measures what the tool exerts on the adapter: the region's push -F d, as the tool
  // passes it on (the settled arm barely accelerates).
  EXPECT_LT((change - force * (-d)).norm(), 0.02 * force + 0.05);
}

phri::CollisionOptions short_test() {
  phri::CollisionOptions o;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path, &o.regions_file}) {
    *path = kRoot + "/" + *path;
  }
  o.output_dir.clear();
  o.regions = {"face"};
  o.speeds_m_s = {0.5};
  o.dynamic = false;
  o.modes = {phri::ComplianceMode::kFullBody};
  o.loops = {phri::LowLevelMode::kCurrent};
  o.contact_window_s = 0.4;
  return o;
}

TEST(CollisionExperiment, TheRunsTouchInTheModeAndLoopTheyNameAndTheConstraintKeepsTheTouchWithinVmax) {
  const phri::CollisionResult r = phri::run_collision(short_test());
  ASSERT_EQ(r.runs.size(), 4u);  // free / clamped x without / with the constraint
  for (const phri::CollisionRun& c : r.runs) {
    ASSERT_TRUE(c.valid) << c.invalid_reason;
    EXPECT_GT(c.peak_force_N, 0.0);
    EXPECT_GT(c.reflected_mass_kg, 0.5);
    if (!c.constraint) {
      EXPECT_GT(c.approach_speed_m_s, 0.4);  // the line's peak speed at its middle, where the face is
      EXPECT_GT(c.approach_speed_m_s, c.permissible_speed_m_s);  // the face's v_max is ~0.2 m/s
    } else {
      EXPECT_LE(c.approach_speed_m_s, 1.01 * c.permissible_speed_m_s);
      EXPECT_LE(c.max_tool_ratio, 1.01);
    }
    if (!c.clamped) {
      // The first peak of a free contact is the two-body model's, at the measured speed and mass.
      const double mu = 1.0 / (1.0 / c.region.mass_kg + 1.0 / c.reflected_mass_kg);
      const double model = c.approach_speed_m_s * std::sqrt(mu * c.region.stiffness_N_per_m);
      std::printf("%s: peak %.1f N, model %.1f N\n", c.constraint ? "limited" : "unlimited", c.peak_force_N, model);
      EXPECT_NEAR(c.peak_force_N, model, 0.25 * model);
    }
  }
  // Free: the constraint's slower touch is the lower peak, below the face's limit.
  EXPECT_LT(r.runs[1].peak_force_N, 0.6 * r.runs[0].peak_force_N);
  EXPECT_LT(r.runs[1].peak_force_N, r.runs[1].limit_N());
  EXPECT_NE(phri::collision_table(r).find("| face | point_to_point 0.50 m/s | free |"), std::string::npos);
}

TEST(CollisionExperiment, AnUnknownRegionIsAConfigErrorNamingTheKnownOnes) {
  phri::CollisionOptions o = short_test();
  o.regions = {"elbow_of_a_giraffe"};
  try {
    phri::run_collision(o);
    FAIL() << "no error";
  } catch (const phri::Error& e) {
    EXPECT_NE(std::string(e.what()).find("hand_fingers"), std::string::npos) << e.what();
  }
}

}  // namespace
