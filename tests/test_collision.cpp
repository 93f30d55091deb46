// ctest-labels: unit
// Capsule self-collision geometry: segment closest points against a brute-force minimisation,
// distance Jacobians and J̇q̇ against finite differences, collision YAML validation; the collision
// guard against its formula and, from rest, against the distance it opens.
#include <phri/control/torque_guards.hpp>
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/capsule_distance.hpp>
#include <phri/model/collision_model.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <algorithm>
#include <random>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

// min over (s, t) in [0,1]^2 of |a(s) - b(t)|: for fixed s the best t is a clamped projection, and
// the resulting function of s is convex, so a ternary search finds its minimum.
double brute_force_distance(const Eigen::Vector3d& a0, const Eigen::Vector3d& a1, const Eigen::Vector3d& b0,
                            const Eigen::Vector3d& b1) {
  auto at = [&](double s) {
    const Eigen::Vector3d p = a0 + s * (a1 - a0);
    const Eigen::Vector3d v = b1 - b0;
    const double t = v.squaredNorm() > 0 ? std::clamp((p - b0).dot(v) / v.squaredNorm(), 0.0, 1.0) : 0.0;
    return (p - (b0 + t * v)).norm();
  };
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 200; ++i) {
    const double m1 = lo + (hi - lo) / 3.0, m2 = hi - (hi - lo) / 3.0;
    if (at(m1) <= at(m2)) hi = m2; else lo = m1;
  }
  return std::min({at(0.5 * (lo + hi)), at(0.0), at(1.0)});
}

TEST(SegmentClosestPoints, MatchesBruteForceOnRandomAndDegenerateSegments) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  auto rv = [&]() { return Eigen::Vector3d(u(rng), u(rng), u(rng)); };
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    Eigen::Vector3d a0 = rv(), a1 = rv(), b0 = rv(), b1 = rv();
    switch (i % 6) {
      case 1: a1 = a0; break;                                     // a point
      case 2: b1 = b0; break;                                     // the other a point
      case 3: b1 = b0 + 0.7 * (a1 - a0); break;                   // parallel
      case 4: b0 = a0 + 0.3 * (a1 - a0); b1 = a0 + 1.4 * (a1 - a0); break;  // collinear, overlapping
      case 5: b0 = a0 + 1e-9 * rv(); break;                       // touching ends
      default: break;
    }
    const auto closest = phri::closest_points_between_segments(a0, a1, b0, b1);
    EXPECT_GE(closest.s, 0.0);
    EXPECT_LE(closest.s, 1.0);
    EXPECT_GE(closest.t, 0.0);
    EXPECT_LE(closest.t, 1.0);
    EXPECT_TRUE(closest.on_first.isApprox(a0 + closest.s * (a1 - a0), 1e-12) || (a1 - a0).norm() < 1e-12);
    const double reference = brute_force_distance(a0, a1, b0, b1);
    worst = std::max(worst, std::abs(closest.distance() - reference));
    ASSERT_NEAR(closest.distance(), reference, 1e-9) << "case " << i % 6;
  }
  std::printf("worst |distance - brute force| over 20000 segment pairs: %.3e m\n", worst);
}

TEST(SegmentClosestPoints, ClosedFormCases) {
  // Crossing perpendicular segments one unit apart.
  auto c = phri::closest_points_between_segments({-1, 0, 0}, {1, 0, 0}, {0, -1, 1}, {0, 1, 1});
  EXPECT_NEAR(c.distance(), 1.0, 1e-15);
  EXPECT_NEAR(c.s, 0.5, 1e-15);
  EXPECT_NEAR(c.t, 0.5, 1e-15);
  // End point to the interior of the other.
  c = phri::closest_points_between_segments({0, 0, 0}, {0, 0, 1}, {-1, 2, 3}, {1, 2, 3});
  EXPECT_NEAR(c.distance(), std::sqrt(4.0 + 4.0), 1e-15);
  EXPECT_NEAR(c.s, 1.0, 1e-15);
}

class Gen3Collision : public ::testing::Test {
protected:
  phri::Model model_ = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::CollisionModel collision_ = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_);
  phri::Data data_{model_};
  phri::CollisionData out_{model_, collision_};
};

TEST_F(Gen3Collision, AllPairsAreClearInTheReferencePostures) {
  EXPECT_EQ(collision_.capsules().size(), 9u);
  EXPECT_GE(collision_.num_pairs(), 12);
  Eigen::VectorXd q(7);
  for (const Eigen::VectorXd& posture : {Eigen::VectorXd(Eigen::VectorXd::Zero(7)),
                                         Eigen::VectorXd((q << 0, 0.2618, 3.1416, -2.2689, 0, 0.9599, 1.5708).finished()),
                                         Eigen::VectorXd((q << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57).finished())}) {
    phri::forward_kinematics(model_, data_, posture);
    phri::compute_collision_distances(model_, data_, collision_, out_, false);
    EXPECT_GT(out_.distance.minCoeff(), 0.03) << posture.transpose();
  }
  // Folded onto itself (joint 4 at its limit, wrist bent back): some pair must come close.
  q << 0, 1.2, 0, 2.5, 0, 2.0, 0;
  phri::forward_kinematics(model_, data_, q);
  phri::compute_collision_distances(model_, data_, collision_, out_, false);
  EXPECT_LT(out_.distance.minCoeff(), 0.03);
}

TEST_F(Gen3Collision, DistanceJacobianAndBiasMatchFiniteDifferences) {
  std::mt19937 rng(9);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  phri::CollisionData minus(model_, collision_), plus(model_, collision_);
  phri::Data dm(model_), dp(model_);
  const double dt = 1e-6;
  int checked = 0;
  for (int sample = 0; sample < 200; ++sample) {
    Eigen::VectorXd q(7), qd(7);
    for (int i = 0; i < 7; ++i) {
      q[i] = 2.0 * u(rng);
      qd[i] = u(rng);
    }
    phri::compute_all_terms(model_, data_, q, qd);
    phri::compute_collision_distances(model_, data_, collision_, out_, true);
    phri::compute_all_terms(model_, dm, q - dt * qd, qd);
    phri::compute_collision_distances(model_, dm, collision_, minus, true);
    phri::compute_all_terms(model_, dp, q + dt * qd, qd);
    phri::compute_collision_distances(model_, dp, collision_, plus, true);
    for (int k = 0; k < collision_.num_pairs(); ++k) {
      // Skip pairs whose closest points jump between segment ends/interior within the step
      // (the distance is then only piecewise smooth) and near-parallel axes.
      if ((plus.point_first.col(k) - minus.point_first.col(k)).norm() > 1e-4) continue;
      const double velocity_fd = (plus.distance[k] - minus.distance[k]) / (2.0 * dt);
      EXPECT_NEAR(out_.jacobian.row(k).dot(qd), velocity_fd, 1e-6) << "pair " << k;
      EXPECT_NEAR(out_.velocity[k], velocity_fd, 1e-6);
      const double acceleration_fd = (plus.jacobian.row(k).dot(qd) - minus.jacobian.row(k).dot(qd)) / (2.0 * dt);
      EXPECT_NEAR(out_.jdot_qdot[k], acceleration_fd, 1e-4 * (1.0 + std::abs(acceleration_fd))) << "pair " << k;
      ++checked;
    }
  }
  EXPECT_GT(checked, 1000);
}

// The collision guard (torque_guards.hpp, Controller::guard_torque).
TEST_F(Gen3Collision, TorqueIsTheFormulaOnThePairsInsideTheSafetyDistance) {
  Eigen::VectorXd q(7), qd(7);
  q << 0, 1.2, 0, 2.5, 0, 2.0, 0;  // folded: some pairs close
  qd << 0.3, -0.2, 0.1, 0.4, -0.3, 0.2, 0.1;
  phri::compute_all_terms(model_, data_, q, qd);
  phri::compute_collision_distances(model_, data_, collision_, out_, true);
  const double safety_distance = out_.distance.minCoeff() + 0.02;  // some pairs inside, not all
  const double k = 6000.0, c = 150.0;
  Eigen::VectorXd tau = Eigen::VectorXd::Constant(7, 1.0), expected = tau;
  int inside = 0;
  for (int p = 0; p < collision_.num_pairs(); ++p) {
    if (out_.distance[p] >= safety_distance) continue;
    ++inside;
    const double force = k * (safety_distance - out_.distance[p]) + c * std::max(-out_.velocity[p], 0.0);
    expected += force * out_.jacobian.row(p).transpose();
  }
  ASSERT_GT(inside, 0);
  ASSERT_LT(inside, collision_.num_pairs());
  EXPECT_TRUE(phri::add_collision_guard(out_, safety_distance, k, c, tau));
  EXPECT_TRUE(tau.isApprox(expected, 1e-14));
  // Every pair outside: nothing added.
  Eigen::VectorXd untouched = Eigen::VectorXd::Constant(7, 1.0);
  EXPECT_FALSE(phri::add_collision_guard(out_, out_.distance.minCoeff() - 1e-3, k, c, untouched));
  EXPECT_EQ(untouched, Eigen::VectorXd::Constant(7, 1.0));
}

// From rest the guard's torque alone accelerates the arm by M^-1 tau; after a short time h the
// pair inside d_s must have opened by h^2 / 2 J M^-1 J^T F > 0, measured on the distances
// themselves (no Jacobian): the torque separates the pair it answers.
TEST_F(Gen3Collision, FromRestTheTorqueOpensThePair) {
  Eigen::VectorXd q(7);
  q << 0, 1.2, 0, 2.5, 0, 2.0, 0;
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(7);
  phri::compute_all_terms(model_, data_, q, rest);
  phri::compute_collision_distances(model_, data_, collision_, out_, true);
  int closest = 0;
  const double d0 = out_.distance.minCoeff(&closest);
  const double safety_distance = d0 + 0.005;
  // Only the closest pair inside d_s.
  Eigen::VectorXd sorted = out_.distance;
  std::sort(sorted.data(), sorted.data() + sorted.size());
  ASSERT_GT(sorted[1], safety_distance);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(7);
  ASSERT_TRUE(phri::add_collision_guard(out_, safety_distance, 6000.0, 150.0, tau));
  const Eigen::LLT<Eigen::MatrixXd> inertia(data_.mass_matrix);
  const Eigen::VectorXd qdd = inertia.solve(tau);
  const double h = 1e-3, force = 6000.0 * 0.005;
  const Eigen::VectorXd jacobian = out_.jacobian.row(closest).transpose();
  const double predicted = 0.5 * h * h * force * jacobian.dot(inertia.solve(jacobian));
  phri::forward_kinematics(model_, data_, q + 0.5 * h * h * qdd);
  phri::CollisionData after(model_, collision_);
  phri::compute_collision_distances(model_, data_, collision_, after, false);
  const double opened = after.distance[closest] - d0;
  EXPECT_GT(opened, 0.0);
  EXPECT_NEAR(opened, predicted, 1e-3 * predicted);
  std::printf("closest pair %d at %.2f mm: opened %.3e m in 1 ms from rest (predicted %.3e)\n", closest, 1e3 * d0,
              opened, predicted);
}

TEST_F(Gen3Collision, DistancesDoNotAllocate) {
  Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.4), qd = Eigen::VectorXd::Constant(7, 0.2);
  phri::compute_all_terms(model_, data_, q, qd);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    phri::compute_collision_distances(model_, data_, collision_, out_, true);
  }
  EXPECT_EQ(count.allocations(), 0u);
}

TEST_F(Gen3Collision, BadYamlNamesTheKey) {
  const auto loading = [this](const std::string& yaml) {
    return [this, yaml] { (void)phri::CollisionModel::from_yaml_string(yaml, model_, "bad.yaml"); };
  };
  using phri::test::expect_config_error;
  const std::string capsule_a = "capsules:\n  - {link: base_link, p0: [0,0,0], p1: [0,0,0.1], radius: 0.05}\n";
  const std::string capsule_b = "  - {link: forearm_link, p0: [0,0,0], p1: [0,-0.2,0], radius: 0.04}\n";
  expect_config_error(loading(capsule_a + capsule_b + "pairs:\n  - [base_link, forearm_link]\nextra: 1\n"),
                      {.element = "extra", .file = "bad.yaml"});
  expect_config_error(loading("capsules:\n  - {link: nowhere, p0: [0,0,0], p1: [0,0,1], radius: 0.1}\npairs: []\n"),
                      {.element = "capsules[0].link", .mentions = {"nowhere"}});
  expect_config_error(loading("capsules:\n  - {link: base_link, p0: [0,0,0], p1: [0,0,1], radius: -0.1}\npairs: []\n"),
                      {.element = "capsules[0].radius"});
  expect_config_error(loading("capsules:\n  - {link: base_link, p0: [0,0], p1: [0,0,1], radius: 0.1}\npairs: []\n"),
                      {.element = "capsules[0].p0"});
  expect_config_error(loading("capsules:\n  - {link: base_link, p0: [0,0,x], p1: [0,0,1], radius: 0.1}\npairs: []\n"),
                      {.element = "capsules[0].p0[2]"});
  expect_config_error(loading(capsule_a + "pairs:\n  - [base_link, forearm_link]\n"), {.element = "pairs[0][1]"});
  expect_config_error(loading(capsule_a + capsule_b + "pairs:\n  - [base_link]\n"), {.element = "pairs[0]"});
  expect_config_error(loading("capsules: [ {link: base_link\n"), {.mentions = {"invalid YAML"}, .file = "bad.yaml"});
  expect_config_error(loading(capsule_a + capsule_b + "pairs:\n  - [base_link, forearm_link]\npairs: []\n"),
                      {.element = "pairs", .mentions = {"duplicate key"}});
  expect_config_error(loading("capsules:\n  - {link: base_link, p0: [0,0,0], p1: [0,0,1], radius: }\npairs: []\n"),
                      {.element = "capsules[0].radius", .mentions = {"null"}});
  expect_config_error(loading("capsules:\n  - {link: base_link, p0: [0,0,0], p1: [0,0,1], radius: 5}\npairs: []\n"),
                      {.element = "capsules[0].radius", .mentions = {"must be in"}});
  // Links connected by one joint: their capsules meet at the joint, always "in collision".
  const std::string capsule_c = "  - {link: spherical_wrist_1_link, p0: [0,0,0], p1: [0,0,-0.1], radius: 0.035}\n";
  expect_config_error(loading(capsule_a + capsule_b + capsule_c + "pairs:\n  - [base_link, forearm_link]\n"
                                                                   "  - [forearm_link, spherical_wrist_1_link]\n"),
                      {.element = "pairs[1]", .mentions = {"joint_5", "connected by one joint"}});
  expect_config_error(loading(capsule_a + capsule_b + "pairs:\n  - [forearm_link, forearm_link]\n"),
                      {.element = "pairs[0]", .mentions = {"same body"}});
}

}  // namespace
