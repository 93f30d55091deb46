// ctest-labels: unit
// F/T processing against closed forms: a tool weight in any orientation cancels, a bias is
// learned, a force at a known point gives the expected world wrench at the end effector.
#include <phri/control/wrench_estimator.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <random>

namespace {

Eigen::Isometry3d random_pose(std::mt19937& rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() = Eigen::Quaterniond(Eigen::Vector4d(u(rng), u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  pose.translation() << u(rng), u(rng), u(rng);
  return pose;
}

TEST(WrenchEstimator, RemovesBiasAndToolWeightAndExpressesThePushAtTheEndEffector) {
  phri::WrenchEstimatorSettings settings;
  settings.tool_mass_kg = 0.3;
  settings.tool_com_m = Eigen::Vector3d(0.01, -0.02, 0.05);
  phri::WrenchEstimator estimator(settings);
  std::mt19937 rng(3);
  phri::Vector6d bias;
  bias << 1.5, -0.7, 2.0, 0.05, -0.02, 0.01;
  // The sensor reads the tool's load (f; c x f) in sensor axes, plus its bias.
  auto reading = [&](const Eigen::Isometry3d& sensor, const Eigen::Vector3d& push_world, const Eigen::Vector3d& point_sensor) {
    const Eigen::Vector3d weight = sensor.linear().transpose() * (0.3 * settings.gravity);
    const Eigen::Vector3d push = sensor.linear().transpose() * push_world;
    phri::Vector6d w;
    w << weight + push, settings.tool_com_m.cross(weight) + point_sensor.cross(push);
    return phri::Vector6d(w + bias);
  };
  const Eigen::Isometry3d start = random_pose(rng);
  for (int i = 0; i < settings.bias_samples; ++i) {
    estimator.update(reading(start, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), start, start.translation());
    EXPECT_EQ(estimator.norm(), 0.0);
  }
  ASSERT_TRUE(estimator.calibrated());
  EXPECT_LT((estimator.bias() - bias).norm(), 1e-12);
  phri::test::AllocationCounter count;
  for (int trial = 0; trial < 100; ++trial) {
    const Eigen::Isometry3d sensor = random_pose(rng);
    // No push, any orientation: nothing left.
    estimator.update(reading(sensor, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()), sensor, sensor.translation());
    EXPECT_LT(estimator.norm(), 1e-12);
    // A 15 N push at a point of the tool: the force, and its moment about the end effector.
    const Eigen::Vector3d push(15.0 * std::cos(trial), 15.0 * std::sin(trial), 2.0);
    const Eigen::Vector3d point_sensor(0.02, 0.01, 0.08);
    const Eigen::Vector3d end_effector = sensor * Eigen::Vector3d(0, 0, -0.065);
    estimator.update(reading(sensor, push, point_sensor), sensor, end_effector);
    const Eigen::Vector3d point_world = sensor * point_sensor;
    phri::Vector6d expected;
    expected << push, (point_world - end_effector).cross(push);
    EXPECT_LT((estimator.wrench_world() - expected).norm(), 1e-10);
  }
  EXPECT_EQ(count.allocations(), 0u);
  // A NaN sample is refused, the estimate kept.
  const phri::Vector6d last = estimator.wrench_world();
  phri::Vector6d bad = phri::Vector6d::Zero();
  bad[2] = std::numeric_limits<double>::quiet_NaN();
  estimator.update(bad, start, start.translation());
  EXPECT_EQ(estimator.wrench_world(), last);
  EXPECT_EQ(estimator.rejected_samples(), 1);
}

}  // namespace
