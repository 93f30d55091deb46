// ctest-labels: unit
// phri::Model / algorithms: finite differences, identities of the equations of motion, the Gen3
// forward-kinematics check from Kinova's numbers, URDF validation errors, zero heap allocation.
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/fixed_size_ldlt.hpp>
#include <phri/core/batch_math.hpp>
#include <phri/model/model.hpp>
#include <phri/model/small_cholesky.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"
#include "random_chain.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/QR>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <functional>
#include <iterator>
#include <random>
#include <sstream>

namespace {

using phri::ReferenceFrame;

const std::string kGen3Urdf = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf";

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Loading `urdf` (named "bad.urdf" in errors) with `options`, as a callable for expect_config_error.
std::function<void()> loading_urdf(const std::string& urdf, const phri::ModelOptions& options = {}) {
  return [urdf, options] { (void)phri::Model::from_urdf_string(urdf, options, "bad.urdf"); };
}

using phri::test::expect_config_error;

Eigen::VectorXd random_vector(int n, double scale, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd v(n);
  for (int i = 0; i < n; ++i) v[i] = scale * unit(rng);
  return v;
}

// Angular velocity w from dR/dt = [w]x R, by central differences of R.
Eigen::Vector3d angular_velocity_fd(const Eigen::Matrix3d& r_minus, const Eigen::Matrix3d& r_plus,
                                    const Eigen::Matrix3d& r, double dt) {
  const Eigen::Matrix3d w_hat = (r_plus - r_minus) / (2.0 * dt) * r.transpose();
  return Eigen::Vector3d(w_hat(2, 1) - w_hat(1, 2), w_hat(0, 2) - w_hat(2, 0), w_hat(1, 0) - w_hat(0, 1)) / 2.0;
}

struct Robot {
  phri::Model model;
  std::string name;
};

std::vector<Robot> test_robots() {
  std::vector<Robot> robots;
  robots.push_back({phri::Model::from_urdf_file(kGen3Urdf), "gen3"});
  std::mt19937 rng(7);
  for (int dof : {6, 7, 7, 6, 3}) {
    std::vector<double> armature;
    const auto chain = phri::test::make_random_chain(dof, rng, 0.3, &armature);
    phri::ModelOptions options;
    options.armature = armature;
    robots.push_back({phri::Model::from_urdf_string(chain.urdf, options), std::to_string(dof) + "-dof random"});
  }
  return robots;
}

class ModelFiniteDifferences : public ::testing::Test {
protected:
  std::vector<Robot> robots_ = test_robots();
  std::mt19937 rng_{11};
};

TEST_F(ModelFiniteDifferences, JacobianTimesVelocityIsTheDerivativeOfFramePlacement) {
  const double dt = 1e-6;
  for (const auto& [model, name] : robots_) {
    phri::Data data(model), data_minus(model), data_plus(model);
    Eigen::MatrixXd jacobian(6, model.nv());
    for (int sample = 0; sample < 20; ++sample) {
      const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng_);
      const Eigen::VectorXd qd = random_vector(model.nv(), 1.0, rng_);
      phri::forward_kinematics(model, data, q, qd);
      phri::update_frame_placements(model, data);
      phri::forward_kinematics(model, data_minus, q - dt * qd);
      phri::update_frame_placements(model, data_minus);
      phri::forward_kinematics(model, data_plus, q + dt * qd);
      phri::update_frame_placements(model, data_plus);
      for (int f = 0; f < model.num_frames(); ++f) {
        const auto& pose = data.frame_placements[static_cast<std::size_t>(f)];
        const auto& minus = data_minus.frame_placements[static_cast<std::size_t>(f)];
        const auto& plus = data_plus.frame_placements[static_cast<std::size_t>(f)];
        phri::Vector6d expected;
        expected << (plus.translation() - minus.translation()) / (2.0 * dt),
            angular_velocity_fd(minus.linear(), plus.linear(), pose.linear(), dt);
        phri::frame_jacobian(model, data, f, ReferenceFrame::kLocalWorldAligned, jacobian);
        EXPECT_LT((jacobian * qd - expected).norm(), 1e-7 * (1.0 + expected.norm())) << name << " frame " << f;
        EXPECT_LT((phri::frame_velocity(model, data, f, ReferenceFrame::kLocalWorldAligned) - expected).norm(),
                  1e-7 * (1.0 + expected.norm()));
        // The other conventions are the same velocity seen differently.
        for (ReferenceFrame rf : {ReferenceFrame::kWorld, ReferenceFrame::kLocal}) {
          phri::frame_jacobian(model, data, f, rf, jacobian);
          EXPECT_LT((jacobian * qd - phri::frame_velocity(model, data, f, rf)).norm(), 1e-12 * (1.0 + expected.norm()));
        }
        phri::Vector6d local;
        local << pose.linear().transpose() * expected.head<3>(), pose.linear().transpose() * expected.tail<3>();
        EXPECT_LT((phri::frame_velocity(model, data, f, ReferenceFrame::kLocal) - local).norm(), 1e-7 * (1.0 + local.norm()));
      }
    }
  }
}

TEST_F(ModelFiniteDifferences, JdotQdotIsTheDerivativeOfJacobianTimesVelocity) {
  const double dt = 1e-6;
  for (const auto& [model, name] : robots_) {
    phri::Data data(model), data_minus(model), data_plus(model);
    Eigen::MatrixXd j_minus(6, model.nv()), j_plus(6, model.nv());
    for (int sample = 0; sample < 20; ++sample) {
      const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng_);
      const Eigen::VectorXd qd = random_vector(model.nv(), 1.5, rng_);
      ASSERT_TRUE(phri::compute_all_terms(model, data, q, qd));
      phri::forward_kinematics(model, data_minus, q - dt * qd);
      phri::update_frame_placements(model, data_minus);
      phri::forward_kinematics(model, data_plus, q + dt * qd);
      phri::update_frame_placements(model, data_plus);
      for (int f = 0; f < model.num_frames(); ++f) {
        for (ReferenceFrame rf : {ReferenceFrame::kWorld, ReferenceFrame::kLocalWorldAligned, ReferenceFrame::kLocal}) {
          phri::frame_jacobian(model, data_minus, f, rf, j_minus);
          phri::frame_jacobian(model, data_plus, f, rf, j_plus);
          const phri::Vector6d expected = (j_plus - j_minus) * qd / (2.0 * dt);
          const phri::Vector6d jdot_qdot = phri::frame_jdot_qdot(model, data, f, rf);
          EXPECT_LT((jdot_qdot - expected).norm(), 1e-6 * (1.0 + expected.norm()))
              << name << " frame " << model.frame(f).name << " rf " << static_cast<int>(rf);
        }
      }
    }
  }
}

TEST_F(ModelFiniteDifferences, FrameAccelerationWithJointAccelerationIsJqddPlusJdotQdot) {
  for (const auto& [model, name] : robots_) {
    phri::Data data(model);
    Eigen::MatrixXd jacobian(6, model.nv());
    const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng_);
    const Eigen::VectorXd qd = random_vector(model.nv(), 1.5, rng_);
    const Eigen::VectorXd qdd = random_vector(model.nv(), 5.0, rng_);
    phri::compute_all_terms(model, data, q, qd);
    const int f = model.num_frames() - 1;
    for (ReferenceFrame rf : {ReferenceFrame::kWorld, ReferenceFrame::kLocalWorldAligned, ReferenceFrame::kLocal}) {
      const phri::Vector6d bias = phri::frame_jdot_qdot(model, data, f, rf);
      phri::frame_jacobian(model, data, f, rf, jacobian);
      phri::Data with_qdd(model);
      phri::forward_kinematics(model, with_qdd, q, qd, qdd);
      phri::update_frame_placements(model, with_qdd);
      const phri::Vector6d expected = jacobian * qdd + bias;
      EXPECT_LT((phri::frame_acceleration(model, with_qdd, f, rf) - expected).norm(), 1e-12 * (1.0 + expected.norm())) << name;
    }
  }
}

TEST_F(ModelFiniteDifferences, InverseDynamicsIsMassMatrixTimesAccelerationPlusNonlinearEffects) {
  for (const auto& [model, name] : robots_) {
    phri::Data data(model);
    for (int sample = 0; sample < 50; ++sample) {
      const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng_);
      const Eigen::VectorXd qd = random_vector(model.nv(), 2.0, rng_);
      const Eigen::VectorXd qdd = random_vector(model.nv(), 10.0, rng_);
      const Eigen::MatrixXd mass = phri::crba(model, data, q);
      EXPECT_LT((mass - mass.transpose()).norm(), 1e-15 * mass.norm());
      const Eigen::VectorXd h = phri::nonlinear_effects(model, data, q, qd);
      const Eigen::VectorXd tau = phri::rnea(model, data, q, qd, qdd);
      EXPECT_LT((tau - (mass * qdd + h)).norm(), 1e-12 * (1.0 + tau.norm())) << name;
      const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv());
      const Eigen::VectorXd g = phri::compute_gravity(model, data, q);
      EXPECT_LT((g - phri::rnea(model, data, q, zero, zero)).norm(), 1e-12 * (1.0 + g.norm()));
      // M^-1 through the Cholesky factor.
      ASSERT_TRUE(phri::compute_all_terms(model, data, q, qd));
      Eigen::VectorXd x = tau;
      phri::mass_matrix_solve_in_place(data, x);
      EXPECT_LT((mass * x - tau).norm(), 1e-10 * (1.0 + tau.norm()));
      EXPECT_LT((data.nonlinear_effects - h).norm(), 1e-12 * (1.0 + h.norm()));
      EXPECT_LT((data.gravity_torque - g).norm(), 1e-12 * (1.0 + g.norm()));
    }
  }
}

// Lagrangian mechanics: with C from the Christoffel symbols of M (derivatives by finite
// differences), C qd = h - g and dM/dt - 2C is skew-symmetric; so qd'(dM/dt)qd = 2 qd'(h - g),
// the energy balance.
TEST_F(ModelFiniteDifferences, ChristoffelCoriolisMatchesNonlinearEffectsAndMdotMinus2CIsSkew) {
  const double eps = 1e-6;
  for (const auto& [model, name] : robots_) {
    const int n = model.nv();
    phri::Data data(model);
    for (int sample = 0; sample < 5; ++sample) {
      const Eigen::VectorXd q = random_vector(n, 3.0, rng_);
      const Eigen::VectorXd qd = random_vector(n, 2.0, rng_);
      std::vector<Eigen::MatrixXd> dmass(static_cast<std::size_t>(n));  // dM/dq_k
      for (int k = 0; k < n; ++k) {
        Eigen::VectorXd qp = q, qm = q;
        qp[k] += eps;
        qm[k] -= eps;
        const Eigen::MatrixXd mp = phri::crba(model, data, qp);
        const Eigen::MatrixXd mm = phri::crba(model, data, qm);
        dmass[static_cast<std::size_t>(k)] = (mp - mm) / (2.0 * eps);
      }
      Eigen::MatrixXd coriolis = Eigen::MatrixXd::Zero(n, n), mdot = Eigen::MatrixXd::Zero(n, n);
      for (int k = 0; k < n; ++k) mdot += dmass[static_cast<std::size_t>(k)] * qd[k];
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          for (int k = 0; k < n; ++k) {
            coriolis(i, j) += 0.5 * (dmass[static_cast<std::size_t>(k)](i, j) + dmass[static_cast<std::size_t>(j)](i, k) -
                                     dmass[static_cast<std::size_t>(i)](j, k)) * qd[k];
          }
        }
      }
      const Eigen::VectorXd h = phri::nonlinear_effects(model, data, q, qd);
      const Eigen::VectorXd g = phri::compute_gravity(model, data, q);
      EXPECT_LT((coriolis * qd - (h - g)).norm(), 1e-6 * (1.0 + (h - g).norm())) << name;
      const Eigen::MatrixXd n_matrix = mdot - 2.0 * coriolis;
      EXPECT_LT((n_matrix + n_matrix.transpose()).norm(), 1e-6 * (1.0 + mdot.norm())) << name;
      EXPECT_NEAR(qd.dot(mdot * qd), 2.0 * qd.dot(h - g), 1e-6 * (1.0 + std::abs(qd.dot(h - g)))) << name;
    }
  }
}

TEST_F(ModelFiniteDifferences, CoriolisTransposeTimesVelocityIsTheKineticEnergyGradient) {
  const double eps = 1e-6;
  for (const auto& [model, name] : robots_) {
    phri::Data data(model);
    for (int sample = 0; sample < 10; ++sample) {
      const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng_);
      const Eigen::VectorXd qd = random_vector(model.nv(), 2.0, rng_);
      Eigen::VectorXd gradient(model.nv());
      for (int k = 0; k < model.nv(); ++k) {
        Eigen::VectorXd qp = q, qm = q;
        qp[k] += eps;
        qm[k] -= eps;
        const double tp = 0.5 * qd.dot(phri::crba(model, data, qp) * qd);
        const double tm = 0.5 * qd.dot(phri::crba(model, data, qm) * qd);
        gradient[k] = (tp - tm) / (2.0 * eps);
      }
      // Armature does not depend on q, so the gradient is the same with or without it.
      phri::compute_all_terms(model, data, q, qd);
      const Eigen::VectorXd from_all_terms = data.coriolis_transpose_qd;  // its fused backward pass
      const Eigen::VectorXd ctqd = phri::coriolis_transpose_times_velocity(model, data);
      EXPECT_LT((ctqd - gradient).norm(), 1e-6 * (1.0 + gradient.norm())) << name;
      EXPECT_EQ(from_all_terms, ctqd) << name;  // the same operations in the same order
    }
  }
}

// ------------------------------------------------------------------- CRBA against the textbook sum
// M = sum_k J_k^T I_k J_k + armature: body k's world spatial Jacobian (the S_j of the joints j <= k)
// through its 6 x 6 spatial inertia about the world origin, built here from the model's local inertia
// and the body placement. No composite inertia, no recursion: an independent check of the CRBA.
Eigen::Matrix<double, 6, 6> spatial_inertia_in_world(const phri::Inertia& local, const Eigen::Isometry3d& placement) {
  const Eigen::Vector3d c = placement * local.com;
  const Eigen::Matrix3d rotation = placement.linear();
  Eigen::Matrix3d c_hat;  // c_hat x = c.cross(x)
  c_hat << 0.0, -c.z(), c.y(), c.z(), 0.0, -c.x(), -c.y(), c.x(), 0.0;
  Eigen::Matrix<double, 6, 6> inertia;
  inertia << local.mass * Eigen::Matrix3d::Identity(), -local.mass * c_hat,  //
      local.mass * c_hat, rotation * local.inertia_com * rotation.transpose() - local.mass * c_hat * c_hat;
  return inertia;
}

// The sum with the placements and motion subspaces that forward kinematics left in data.
Eigen::MatrixXd mass_matrix_as_sum_over_bodies(const phri::Model& model, const phri::Data& data) {
  const int n = model.nv();
  Eigen::MatrixXd mass = Eigen::MatrixXd::Zero(n, n);
  for (int k = 0; k < n; ++k) {
    Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(6, n);
    jacobian.leftCols(k + 1) = data.motion_subspace.leftCols(k + 1);
    mass += jacobian.transpose() *
            spatial_inertia_in_world(model.body_inertia(k), data.body_placements[static_cast<std::size_t>(k)]) * jacobian;
  }
  for (int i = 0; i < n; ++i) mass(i, i) += model.joint(i).armature;
  return mass;
}

double relative_difference(const Eigen::MatrixXd& value, const Eigen::MatrixXd& reference) {
  return (value - reference).cwiseAbs().maxCoeff() / reference.cwiseAbs().maxCoeff();
}

// The Gen3 (revolute joints about their local z), the random chains of test_robots (any axis,
// prismatic joints, armature) and a 30-DoF random chain; crba and compute_all_terms (which runs the
// same composite pass on the inertias of its own forward pass).
TEST(ModelCrba, MassMatrixIsTheSumOverBodiesOfJacobianInertiaJacobianToRounding) {
  std::vector<Robot> robots = test_robots();
  std::mt19937 rng(19);
  robots.push_back({phri::Model::from_urdf_string(phri::test::make_random_chain(30, rng).urdf), "30-dof random"});
  int prismatic = 0, revolute_off_z = 0;
  for (const auto& [model, name] : robots) {
    for (const phri::Joint& joint : model.joints()) {
      if (joint.type == phri::JointType::kPrismatic) ++prismatic;
      else if (!joint.axis.isApprox(Eigen::Vector3d::UnitZ())) ++revolute_off_z;
    }
    phri::Data data(model);
    for (int sample = 0; sample < 20; ++sample) {
      const Eigen::VectorXd q = random_vector(model.nq(), 3.0, rng);
      const Eigen::MatrixXd mass = phri::crba(model, data, q);
      const Eigen::MatrixXd reference = mass_matrix_as_sum_over_bodies(model, data);
      EXPECT_LT(relative_difference(mass, reference), 1e-12) << name << " sample " << sample;
      EXPECT_EQ(mass, mass.transpose()) << name;
      ASSERT_TRUE(phri::compute_all_terms(model, data, q, random_vector(model.nv(), 1.0, rng)));
      EXPECT_LT(relative_difference(data.mass_matrix, reference), 1e-12) << name << " sample " << sample;
    }
  }
  EXPECT_GT(prismatic, 0);  // the general joints are covered, not only the Gen3's
  EXPECT_GT(revolute_off_z, 0);
}

// SmallCholesky (the mass matrix's factor) against Eigen's LLT, the reference: the same factor and
// solutions to rounding for every size from 1 to 30 (conditioning up to 1e6), only the lower
// triangle read, a matrix's columns solved as the vectors are, and Eigen's refusals (indefinite,
// singular) plus a NaN, which Eigen's pivot test (x <= 0) lets through.
// The kinematics' sines and cosines against libm's: within 1 ulp (plus 1e-16 absolute where the
// value passes through zero) for joint angles, 2 ulp up to the reduction's bound, libm's own beyond
// it and for non-finite angles; any batch length up to its width, and the same for an angle
// whatever its place in the batch.
TEST(BatchMath, SinCosWithinAnUlpOfLibmAndLibmsOwnBeyondTheReduction) {
  namespace bs = phri::batch_math;
  auto ulp = [](double v) { return std::nextafter(std::abs(v), INFINITY) - std::abs(v); };
  std::mt19937_64 rng(11);
  struct Range {
    double half_width, ulps;
  };
  for (const Range range : {Range{1.0, 1.0}, Range{2.0 * M_PI, 1.0}, Range{100.0, 1.0}, Range{bs::kReducibleRad, 2.0}}) {
    SCOPED_TRACE(range.half_width);
    std::uniform_real_distribution<double> angle(-range.half_width, range.half_width);
    double worst = 0.0;
    for (int trial = 0; trial < 20000; ++trial) {
      double x[bs::kWidth], s[bs::kWidth], c[bs::kWidth];
      const int n = 1 + trial % bs::kWidth;
      for (int i = 0; i < n; ++i) x[i] = angle(rng);
      bs::sincos(x, n, s, c);
      for (int i = 0; i < n; ++i) {
        const double es = std::abs(s[i] - std::sin(x[i])), ec = std::abs(c[i] - std::cos(x[i]));
        ASSERT_LE(es, range.ulps * ulp(std::sin(x[i])) + 1e-16) << x[i];
        ASSERT_LE(ec, range.ulps * ulp(std::cos(x[i])) + 1e-16) << x[i];
        worst = std::max({worst, es / ulp(std::sin(x[i])), ec / ulp(std::cos(x[i]))});
      }
    }
    EXPECT_LE(worst, range.ulps);
  }
  const double specials[] = {0.0, M_PI / 4, -M_PI / 4, M_PI / 2, -M_PI / 2, M_PI, 3 * M_PI / 2, 1e-300,
                             bs::kReducibleRad, std::nextafter(bs::kReducibleRad, INFINITY), 1e10, -1e300,
                             INFINITY, -INFINITY, NAN, 5.0};
  for (int start = 0; start + bs::kWidth <= static_cast<int>(std::size(specials)); start += 4) {
    double s[bs::kWidth], c[bs::kWidth];
    bs::sincos(specials + start, bs::kWidth, s, c);
    for (int i = 0; i < bs::kWidth; ++i) {
      const double x = specials[start + i];
      SCOPED_TRACE(x);
      if (!std::isfinite(x)) {
        EXPECT_TRUE(std::isnan(s[i]) && std::isnan(c[i]));
      } else if (std::abs(x) > bs::kReducibleRad) {
        EXPECT_EQ(s[i], std::sin(x));
        EXPECT_EQ(c[i], std::cos(x));
      } else {
        EXPECT_LE(std::abs(s[i] - std::sin(x)), ulp(std::sin(x)) + 1e-16);
        EXPECT_LE(std::abs(c[i] - std::cos(x)), ulp(std::cos(x)) + 1e-16);
      }
      double alone_s, alone_c;
      bs::sincos(&x, 1, &alone_s, &alone_c);
      EXPECT_TRUE(alone_s == s[i] || (std::isnan(alone_s) && std::isnan(s[i])));
      EXPECT_TRUE(alone_c == c[i] || (std::isnan(alone_c) && std::isnan(c[i])));
    }
  }
}

// compute_with_shifted factors A and A + diag(d) in one pass: each factor and each solve equal
// compute()'s bit for bit at every size (the 6- and 7-joint kernels and the general one), as do the
// paired solves (solve_pair_in_place) each single solve's; and a
// refused A (indefinite, rescued by the shift) leaves the shifted factor good, and the other way round.
TEST(SmallCholesky, FactoringWithAShiftedCopyGivesEachFactorBitForBit) {
  std::mt19937 rng(45);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int n = 1; n <= 12; ++n) {
    const Eigen::MatrixXd random = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return unit(rng); });
    const Eigen::MatrixXd a = random * random.transpose() + 0.1 * Eigen::MatrixXd::Identity(n, n);
    const Eigen::VectorXd shift = Eigen::VectorXd::NullaryExpr(n, [&] { return 0.5 + 0.5 * unit(rng); });
    Eigen::MatrixXd a_shifted = a;
    a_shifted.diagonal() += shift;
    phri::SmallCholesky plain(n), shifted(n), plain_alone(n), shifted_alone(n);
    ASSERT_TRUE(phri::SmallCholesky::compute_with_shifted(a, shift, plain, shifted)) << n;
    ASSERT_TRUE(plain_alone.compute(a) && shifted_alone.compute(a_shifted));
    EXPECT_EQ(Eigen::MatrixXd(plain.factor().triangularView<Eigen::Lower>()),
              Eigen::MatrixXd(plain_alone.factor().triangularView<Eigen::Lower>())) << n;
    EXPECT_EQ(Eigen::MatrixXd(shifted.factor().triangularView<Eigen::Lower>()),
              Eigen::MatrixXd(shifted_alone.factor().triangularView<Eigen::Lower>())) << n;
    const Eigen::VectorXd b = Eigen::VectorXd::NullaryExpr(n, [&] { return unit(rng); });
    Eigen::VectorXd x1 = b, x2 = b, y1 = b, y2 = b;
    plain.solve_in_place(x1);
    plain_alone.solve_in_place(x2);
    shifted.solve_in_place(y1);
    shifted_alone.solve_in_place(y2);
    EXPECT_EQ(x1, x2) << n;
    EXPECT_EQ(y1, y2) << n;
    EXPECT_LT((a_shifted * y1 - b).norm(), 1e-12 * (1.0 + y1.norm())) << n;
    // Two right-hand sides solved side by side: each bit for bit its own solve.
    const Eigen::VectorXd c = Eigen::VectorXd::NullaryExpr(n, [&] { return unit(rng); });
    Eigen::VectorXd pair_b = b, pair_c = c, single_c = c;
    plain.solve_pair_in_place(pair_b, pair_c);
    plain.solve_in_place(single_c);
    EXPECT_EQ(pair_b, x1) << n;
    EXPECT_EQ(pair_c, single_c) << n;
  }
  // Indefinite A, positive definite A + diag(d): only the shifted factor holds; and the other way round.
  const Eigen::Matrix3d indefinite = Eigen::Vector3d(1.0, -0.5, 2.0).asDiagonal();
  phri::SmallCholesky plain(3), shifted(3), alone(3);
  EXPECT_FALSE(phri::SmallCholesky::compute_with_shifted(indefinite, Eigen::Vector3d::Ones(), plain, shifted));
  EXPECT_FALSE(plain.ok());
  EXPECT_TRUE(shifted.ok());
  ASSERT_TRUE(alone.compute(Eigen::Matrix3d(Eigen::Vector3d(2.0, 0.5, 3.0).asDiagonal())));
  EXPECT_EQ(Eigen::MatrixXd(shifted.factor().triangularView<Eigen::Lower>()),
            Eigen::MatrixXd(alone.factor().triangularView<Eigen::Lower>()));
  EXPECT_FALSE(phri::SmallCholesky::compute_with_shifted(Eigen::Matrix3d::Identity(), -2.0 * Eigen::Vector3d::Ones(), plain, shifted));
  EXPECT_TRUE(plain.ok());
  EXPECT_FALSE(shifted.ok());
  // Sizes that do not match are the caller's error.
  phri::SmallCholesky two(2);
  EXPECT_THROW(phri::SmallCholesky::compute_with_shifted(Eigen::Matrix3d::Identity(), Eigen::Vector3d::Ones(), plain, two),
               phri::ArgumentError);
  EXPECT_THROW(phri::SmallCholesky::compute_with_shifted(Eigen::Matrix3d::Identity(), Eigen::Vector2d::Ones(), plain, shifted),
               phri::ArgumentError);
  Eigen::VectorXd three = Eigen::VectorXd::Ones(3), two_long = Eigen::VectorXd::Ones(2);
  EXPECT_THROW(plain.solve_pair_in_place(three, two_long), phri::ArgumentError);
}

TEST(SmallCholesky, AgreesWithEigensLltToRoundingAndRefusesWhatItRefuses) {
  std::mt19937 rng(44);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int n = 1; n <= 30; ++n) {
    for (const double condition : {1.0, 1e3, 1e6}) {
      // A = Q diag(1 .. 1/condition) Q^T with a random orthogonal Q.
      const Eigen::MatrixXd random = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return unit(rng); });
      const Eigen::MatrixXd q = Eigen::HouseholderQR<Eigen::MatrixXd>(random).householderQ();
      Eigen::VectorXd spectrum(n);
      for (int i = 0; i < n; ++i) spectrum[i] = std::pow(condition, -double(i) / std::max(n - 1, 1));
      Eigen::MatrixXd a = q * spectrum.asDiagonal() * q.transpose();
      a = 0.5 * (a + a.transpose()).eval();
      const Eigen::LLT<Eigen::MatrixXd> reference(a);
      ASSERT_EQ(reference.info(), Eigen::Success);

      Eigen::MatrixXd upper_garbage = a;
      upper_garbage.triangularView<Eigen::StrictlyUpper>().setConstant(std::nan(""));
      phri::SmallCholesky factor(n);
      ASSERT_TRUE(factor.compute(upper_garbage)) << n;
      const Eigen::MatrixXd l = factor.factor().triangularView<Eigen::Lower>();
      const Eigen::MatrixXd l_reference = reference.matrixL();
      EXPECT_LT((l - l_reference).cwiseAbs().maxCoeff(), 1e-14 * n * condition) << n << " cond " << condition;

      const Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(n, 3, [&] { return unit(rng); });
      Eigen::MatrixXd x = b;
      factor.solve_in_place(x);
      const Eigen::MatrixXd x_reference = reference.solve(b);
      EXPECT_LT((x - x_reference).norm() / x_reference.norm(), 1e-15 * n * condition) << n << " cond " << condition;
      EXPECT_LT((a * x - b).norm() / x.norm(), 1e-14 * n) << n << " cond " << condition;  // backward error, ||A|| = 1
      for (int c = 0; c < 3; ++c) {
        Eigen::VectorXd column = b.col(c);
        factor.solve_in_place(column);
        EXPECT_EQ(column, x.col(c));  // a matrix is solved column by column, bit for bit
      }
    }
  }
  // The refusals, and a refusal is remembered until the next factor.
  phri::SmallCholesky factor(3);
  Eigen::Matrix3d indefinite = Eigen::Vector3d(1.0, -1e-9, 2.0).asDiagonal();
  Eigen::Matrix3d singular = Eigen::Matrix3d::Ones();
  Eigen::Matrix3d not_a_number = Eigen::Matrix3d::Identity();
  not_a_number(2, 1) = std::nan("");
  for (const Eigen::Matrix3d& bad : {indefinite, singular}) {
    EXPECT_FALSE(factor.compute(bad));
    EXPECT_FALSE(factor.ok());
    EXPECT_NE(Eigen::LLT<Eigen::MatrixXd>(bad).info(), Eigen::Success);
  }
  EXPECT_FALSE(factor.compute(not_a_number));
  EXPECT_TRUE(factor.compute(Eigen::Matrix3d::Identity()));
  EXPECT_TRUE(factor.ok());
  // Another size is the caller's error, named, never a read past the factor.
  EXPECT_THROW(factor.compute(Eigen::Matrix2d::Identity()), phri::ArgumentError);
  EXPECT_THROW(factor.compute(Eigen::MatrixXd::Identity(3, 4)), phri::ArgumentError);
  Eigen::VectorXd too_long = Eigen::VectorXd::Ones(4);
  EXPECT_THROW(factor.solve_in_place(too_long), phri::ArgumentError);
}

// FixedSizeLdlt (the singular-direction weight's 6 x 6 tests and solves) against Eigen's LLT and its
// defining identity: L D L^T rebuilt from the pivots equals A, the solve's backward error is at
// rounding, and definiteness is decided as the spectrum says, down to eigenvalues of 1e-10 ||A||.
template <int N>
void check_fixed_size_ldlt(std::mt19937& rng) {
  using Matrix = Eigen::Matrix<double, N, N>;
  using Vector = Eigen::Matrix<double, N, 1>;
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 200; ++trial) {
    const Matrix q = Eigen::HouseholderQR<Matrix>(Matrix::NullaryExpr([&] { return unit(rng); })).householderQ();
    for (const double smallest : {1.0, 1e-3, 1e-6, 1e-10, -1e-10, -1e-3}) {
      Vector spectrum = Vector::NullaryExpr([&] { return 1.0 + unit(rng); }).cwiseMax(smallest);
      spectrum[trial % N] = smallest;
      Matrix a = q * spectrum.asDiagonal() * q.transpose();
      a = (0.5 * (a + a.transpose())).eval();
      Matrix upper_garbage = a;
      upper_garbage.template triangularView<Eigen::StrictlyUpper>().setConstant(std::nan(""));
      phri::FixedSizeLdlt<N> ldlt;
      const bool definite = ldlt.compute(upper_garbage);
      EXPECT_EQ(definite, smallest > 0.0) << N << " smallest eigenvalue " << smallest;
      EXPECT_EQ(ldlt.ok(), definite);
      if (!definite) continue;
      const double condition = 2.0 / smallest;
      const Eigen::LLT<Matrix> reference(a);
      const Vector d = reference.matrixL().toDenseMatrix().diagonal().cwiseAbs2();
      EXPECT_LT(((ldlt.pivots() - d).cwiseQuotient(d)).cwiseAbs().maxCoeff(), 1e-15 * N * condition) << N;
      const Vector b = Vector::NullaryExpr([&] { return unit(rng); });
      const Vector x = ldlt.solve(b);
      EXPECT_LT((a * x - b).norm() / (2.0 * x.norm()), 1e-14 * N) << N << " smallest " << smallest;  // ||A|| <= 2
      EXPECT_LT((x - reference.solve(b)).norm() / x.norm(), 1e-15 * N * condition) << N << " smallest " << smallest;
    }
  }
  // A NaN on or below the diagonal is refused; the refusal holds until the next factor.
  Matrix not_a_number = Matrix::Identity();
  not_a_number(N - 1, 0) = std::nan("");
  phri::FixedSizeLdlt<N> ldlt;
  EXPECT_FALSE(ldlt.compute(not_a_number));
  EXPECT_FALSE(ldlt.ok());
  EXPECT_TRUE(ldlt.compute(Matrix::Identity()));
}

TEST(FixedSizeLdlt, FactorsSolvesAndDecidesDefinitenessAsTheSpectrumSays) {
  std::mt19937 rng(2026);
  check_fixed_size_ldlt<1>(rng);
  check_fixed_size_ldlt<3>(rng);
  check_fixed_size_ldlt<6>(rng);
  check_fixed_size_ldlt<7>(rng);
}

// ------------------------------------------------------------------- Kinova's own FK figures
TEST(Gen3Model, ForwardKinematicsMatchesKinovaTable) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3Urdf);
  EXPECT_EQ(model.nq(), 7);
  EXPECT_NEAR(model.total_mass(), 8.0519 - 1.697, 1e-12);  // the base link does not move
  phri::Data data(model);
  const int ee = model.frame_id("end_effector_link");
  const int tool = model.frame_id("tool_frame");
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  // kinova_gen3.md section e, computed from Kinova's xacro: q = 0 and the home posture.
  EXPECT_LT((data.frame_placements[static_cast<std::size_t>(ee)].translation() - Eigen::Vector3d(0.0, -0.0248596, 1.1873848)).norm(), 1e-7);
  q << 0, 0.2618, 3.1416, -2.2689, 0, 0.9599, 1.5708;
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  const auto& pose = data.frame_placements[static_cast<std::size_t>(ee)];
  EXPECT_LT((pose.translation() - Eigen::Vector3d(0.4566726, 0.0013436, 0.4337285)).norm(), 1e-7);
  const Eigen::Quaterniond quat(pose.linear());
  EXPECT_LT(std::abs(std::abs(quat.coeffs().dot(Eigen::Vector4d(0.5000027, 0.4999991, 0.4999965, 0.5000017))) - 1.0), 1e-6);
  EXPECT_TRUE(data.frame_placements[static_cast<std::size_t>(tool)].isApprox(pose, 1e-15));
  // Limits as in the URDF.
  EXPECT_FALSE(model.joint(0).has_position_limits());
  EXPECT_DOUBLE_EQ(model.joint(1).upper, 2.24);
  EXPECT_DOUBLE_EQ(model.joint(3).lower, -2.57);
  EXPECT_DOUBLE_EQ(model.joint(4).velocity_limit, 1.2218);
  EXPECT_DOUBLE_EQ(model.joint(0).effort_limit, 39.0);
}

TEST(Gen3Model, BasePlacementMovesEveryFrameAndGravityStaysInTheWorld) {
  phri::ModelOptions options;
  options.base_placement = Eigen::Isometry3d::Identity();
  options.base_placement.linear() = Eigen::AngleAxisd(M_PI / 2, Eigen::Vector3d::UnitX()).toRotationMatrix();
  options.base_placement.translation() << 0.1, 0.2, 0.3;
  const phri::Model moved = phri::Model::from_urdf_file(kGen3Urdf, options);
  const phri::Model upright = phri::Model::from_urdf_file(kGen3Urdf);
  phri::Data dm(moved), du(upright);
  Eigen::VectorXd q(7);
  q << 0.1, 0.5, -0.3, 1.2, 0.4, -0.7, 0.9;
  phri::forward_kinematics(moved, dm, q);
  phri::update_frame_placements(moved, dm);
  phri::forward_kinematics(upright, du, q);
  phri::update_frame_placements(upright, du);
  for (int f = 0; f < moved.num_frames(); ++f) {
    EXPECT_TRUE(dm.frame_placements[static_cast<std::size_t>(f)].isApprox(
        options.base_placement * du.frame_placements[static_cast<std::size_t>(f)], 1e-14));
  }
  // Arm mounted on a wall (base x axis up): same M, different gravity torques; with gravity
  // rotated along, the same as upright.
  EXPECT_TRUE(phri::crba(moved, dm, q).isApprox(phri::crba(upright, du, q), 1e-13));
  options.gravity = options.base_placement.linear() * Eigen::Vector3d(0, 0, -9.81);
  const phri::Model moved_gravity = phri::Model::from_urdf_file(kGen3Urdf, options);
  phri::Data dg(moved_gravity);
  EXPECT_TRUE(phri::compute_gravity(moved_gravity, dg, q).isApprox(phri::compute_gravity(upright, du, q), 1e-12));
  EXPECT_FALSE(phri::compute_gravity(moved, dm, q).isApprox(phri::compute_gravity(upright, du, q), 1e-3));
}

TEST(ModelOptionsTest, ExtraFramesAreFixedToTheirParent) {
  phri::ModelOptions options;
  phri::ExtraFrame tcp;
  tcp.name = "tcp";
  tcp.parent_frame = "end_effector_link";
  tcp.placement.translation() << 0.0, 0.0, 0.12;
  options.extra_frames.push_back(tcp);
  const phri::Model model = phri::Model::from_urdf_file(kGen3Urdf, options);
  phri::Data data(model);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.3);
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  const auto& ee = data.frame_placements[static_cast<std::size_t>(model.frame_id("end_effector_link"))];
  const auto& frame = data.frame_placements[static_cast<std::size_t>(model.frame_id("tcp"))];
  EXPECT_TRUE(frame.isApprox(ee * tcp.placement, 1e-14));
}

TEST(ModelOptionsTest, PayloadEqualsTheSameMassWrittenInTheUrdf) {
  // A 0.5 kg box on end_effector_link, as a payload and as a fixed link in the URDF.
  phri::ModelOptions options;
  phri::Payload payload;
  payload.name = "tool";
  payload.frame = "end_effector_link";
  payload.inertia.mass = 0.5;
  payload.inertia.com = Eigen::Vector3d(0.01, 0.0, 0.08);
  payload.inertia.inertia_com = Eigen::Vector3d(1e-3, 2e-3, 2.5e-3).asDiagonal();
  options.payloads.push_back(payload);
  const phri::Model with_payload = phri::Model::from_urdf_file(kGen3Urdf, options);
  std::string urdf = read_file(kGen3Urdf);
  urdf.insert(urdf.rfind("</robot>"),
              "<link name=\"box\"><inertial><origin xyz=\"0.01 0 0.08\"/><mass value=\"0.5\"/><inertia ixx=\"1e-3\" "
              "ixy=\"0\" ixz=\"0\" iyy=\"2e-3\" iyz=\"0\" izz=\"2.5e-3\"/></inertial></link><joint name=\"box_joint\" "
              "type=\"fixed\"><parent link=\"end_effector_link\"/><child link=\"box\"/></joint>");
  const phri::Model in_urdf = phri::Model::from_urdf_string(urdf);
  phri::Data a(with_payload), b(in_urdf);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, 0.7);
  EXPECT_TRUE(phri::crba(with_payload, a, q).isApprox(phri::crba(in_urdf, b, q), 1e-14));
  EXPECT_TRUE(phri::compute_gravity(with_payload, a, q).isApprox(phri::compute_gravity(in_urdf, b, q), 1e-14));
  payload.inertia.mass = -1.0;
  options.payloads = {payload};
  expect_config_error(loading_urdf(read_file(kGen3Urdf), options), {.mentions = {"mass"}, .file = "bad.urdf"});
}

TEST(ModelOptionsTest, LockedJointBehavesAsFixedAtZero) {
  // A gripper-like branch: a movable joint off the chain is an error unless locked.
  std::string urdf = read_file(kGen3Urdf);
  const std::string finger =
      "  <link name=\"finger\"><inertial><origin xyz=\"0 0 0.02\"/><mass value=\"0.1\"/>"
      "<inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial></link>\n"
      "  <joint name=\"finger_joint\" type=\"prismatic\"><parent link=\"bracelet_link\"/><child link=\"finger\"/>"
      "<origin xyz=\"0 0.03 -0.07\"/><axis xyz=\"0 1 0\"/><limit lower=\"0\" upper=\"0.04\" effort=\"10\" velocity=\"0.1\"/></joint>\n";
  urdf.insert(urdf.rfind("</robot>"), finger);
  phri::ModelOptions options;
  options.tip_link = "end_effector_link";
  // An unlocked branch is refused.
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"finger_joint"}, .file = "bad.urdf"});
  options.locked_joints = {"finger_joint"};
  const phri::Model locked = phri::Model::from_urdf_string(urdf, options);
  EXPECT_EQ(locked.nq(), 7);
  EXPECT_NEAR(locked.total_mass(), 8.0519 - 1.697 + 0.1, 1e-12);
  // Same as the finger welded: the fixed-joint version of the same file.
  std::string welded = urdf;
  welded.replace(welded.find("type=\"prismatic\""), 16, "type=\"fixed\"");
  const phri::Model fixed = phri::Model::from_urdf_string(welded, {});
  phri::Data dl(locked), df(fixed);
  const Eigen::VectorXd q = Eigen::VectorXd::Constant(7, -0.4);
  EXPECT_TRUE(phri::crba(locked, dl, q).isApprox(phri::crba(fixed, df, q), 1e-14));
}

// ------------------------------------------------------------------- validation of bad input
std::string gen3_with(const std::string& from, const std::string& to) {
  std::string urdf = read_file(kGen3Urdf);
  const std::size_t at = urdf.find(from);
  if (at == std::string::npos) throw std::runtime_error("test setup: '" + from + "' not in gen3.urdf");
  urdf.replace(at, from.size(), to);
  return urdf;
}

TEST(ModelValidation, MalformedXmlNamesTheProblem) {
  expect_config_error(loading_urdf("<robot name=\"x\"><link name=\"a\"></robot>"),
                      {.mentions = {"not a valid URDF"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf("this is not xml at all"), {.mentions = {"not a valid URDF"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf(""), {.mentions = {"not a valid URDF"}, .file = "bad.urdf"});
  // A joint that names a missing link.
  expect_config_error(loading_urdf(gen3_with("<child link=\"forearm_link\"/>", "<child link=\"no_such_link\"/>")),
                      {.mentions = {"not a valid URDF"}, .file = "bad.urdf"});
}

TEST(ModelValidation, InertialProblemsNameTheLink) {
  const std::string urdf = read_file(kGen3Urdf);
  // Remove the inertial of a moving link.
  const std::size_t link = urdf.find("<link name=\"half_arm_1_link\">");
  ASSERT_NE(link, std::string::npos);
  const std::size_t begin = urdf.find("<inertial>", link);
  const std::size_t end = urdf.find("</inertial>", begin) + std::string("</inertial>").size();
  std::string missing = urdf;
  missing.erase(begin, end - begin);
  expect_config_error(loading_urdf(missing), {.mentions = {"joint_2", "no <inertial>"}, .file = "bad.urdf"});

  expect_config_error(loading_urdf(gen3_with("<mass value=\"1.1636\"", "<mass value=\"-1.1636\"")),
                      {.mentions = {"half_arm_1_link", "mass must be positive"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf(gen3_with("<mass value=\"0.9302\"", "<mass value=\"0\"")),
                      {.mentions = {"forearm_link", "mass must be positive"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf(gen3_with("ixx=\"0.011088\"", "ixx=\"-0.011088\"")),
                      {.mentions = {"half_arm_1_link", "not positive definite"}, .file = "bad.urdf"});
  // Positive definite but not physical (I1 + I2 < I3): accepted with a warning, see
  // test_urdf_robustness.cpp.
  expect_config_error(loading_urdf(gen3_with("<mass value=\"1.1636\"", "<mass value=\"nan\"")),
                      {.mentions = {"half_arm_1_link"}, .file = "bad.urdf"});
}

// Physical ranges: finite but absurd inertials are refused too, naming the link.
TEST(ModelValidation, AbsurdInertialsNameTheLink) {
  expect_config_error(loading_urdf(gen3_with("<mass value=\"1.1636\"", "<mass value=\"1e300\"")),
                      {.element = "link 'half_arm_1_link' <inertial>", .mentions = {"1000 kg"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf(gen3_with("<mass value=\"1.1636\"", "<mass value=\"1500\"")),
                      {.element = "link 'half_arm_1_link' <inertial>", .mentions = {"1000 kg"}, .file = "bad.urdf"});
  EXPECT_NO_THROW((void)phri::Model::from_urdf_string(gen3_with("<mass value=\"1.1636\"", "<mass value=\"999\"")));
  // Moments of a body several metres across for its mass (radius of gyration above 2 m).
  expect_config_error(loading_urdf(gen3_with("ixx=\"0.011088\" ixy=\"5E-06\" ixz=\"0\" iyy=\"0.001072\" iyz=\"-0.000691\" izz=\"0.011255\"",
                                             "ixx=\"50\" ixy=\"0\" ixz=\"0\" iyy=\"50\" iyz=\"0\" izz=\"50\"")),
                      {.element = "link 'half_arm_1_link' <inertial>", .mentions = {"radius of gyration"}, .file = "bad.urdf"});
}

// A revolute joint's limits beyond one turn each way (+-200 rad): a typo, or a joint that should be
// 'continuous'.
TEST(ModelValidation, RevoluteLimitsBeyondOneTurn) {
  expect_config_error(loading_urdf(gen3_with("lower=\"-2.24\" upper=\"2.24\"", "lower=\"-200\" upper=\"200\"")),
                      {.element = "joint 'joint_2' <limit>", .mentions = {"2 pi", "continuous"}, .file = "bad.urdf"});
  EXPECT_NO_THROW((void)phri::Model::from_urdf_string(gen3_with("lower=\"-2.24\" upper=\"2.24\"", "lower=\"-6.28\" upper=\"6.28\"")));
}

TEST(ModelValidation, JointProblemsNameTheJoint) {
  expect_config_error(loading_urdf(gen3_with("lower=\"-2.24\" upper=\"2.24\"", "lower=\"2.24\" upper=\"-2.24\"")),
                      {.mentions = {"joint_2", "lower"}, .file = "bad.urdf"});
  expect_config_error(loading_urdf(gen3_with("<joint name=\"joint_3\" type=\"continuous\"",
                                             "<joint name=\"joint_3\" type=\"floating\"")),
                      {.mentions = {"joint_3", "floating"}, .file = "bad.urdf"});
  std::string urdf = read_file(kGen3Urdf);
  const std::size_t j4 = urdf.find("<joint name=\"joint_4\"");
  const std::size_t axis = urdf.find("<axis xyz=\"0 0 1\"", j4);
  urdf.replace(axis, std::string("<axis xyz=\"0 0 1\"").size(), "<axis xyz=\"0 0 0\"");
  expect_config_error(loading_urdf(urdf), {.mentions = {"joint_4", "axis"}, .file = "bad.urdf"});
}

TEST(ModelValidation, ChainProblems) {
  const std::string urdf = read_file(kGen3Urdf);
  phri::ModelOptions options;
  options.tip_link = "no_such_link";
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"tip_link", "no_such_link"}, .file = "bad.urdf"});
  options = {};
  options.base_link = "nope";
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"base_link", "nope"}, .file = "bad.urdf"});
  options = {};
  options.base_link = "forearm_link";
  options.tip_link = "shoulder_link";
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"not below base"}, .file = "bad.urdf"});
  options = {};
  options.base_link = "end_effector_link";
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"no movable joint"}, .file = "bad.urdf"});
  options = {};
  options.armature = {0.1, 0.2};
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"armature", "7 joints"}, .file = "bad.urdf"});
  options = {};
  options.extra_frames.push_back({"tcp", "nowhere", Eigen::Isometry3d::Identity()});
  expect_config_error(loading_urdf(urdf, options), {.mentions = {"tcp", "nowhere"}, .file = "bad.urdf"});
  // Two movable branches and no tip named.
  std::string branched = urdf;
  branched.insert(branched.rfind("</robot>"),
                  "<link name=\"side\"><inertial><mass value=\"0.1\"/><inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" "
                  "iyz=\"0\" izz=\"1e-4\"/></inertial></link><joint name=\"side_joint\" type=\"continuous\">"
                  "<parent link=\"half_arm_2_link\"/><child link=\"side\"/><axis xyz=\"1 0 0\"/></joint>");
  expect_config_error(loading_urdf(branched), {.mentions = {"half_arm_2_link", "branches"}, .file = "bad.urdf"});
  options = {};
  options.tip_link = "side";
  expect_config_error(loading_urdf(branched, options), {.mentions = {"joint_4", "locked_joints"}, .file = "bad.urdf"});
  options.locked_joints = {"joint_4", "joint_5", "joint_6", "joint_7"};
  EXPECT_EQ(phri::Model::from_urdf_string(branched, options).nq(), 4);
  // Missing file.
  expect_config_error([] { (void)phri::Model::from_urdf_file("/nonexistent/robot.urdf"); },
                      {.file = "/nonexistent/robot.urdf"});
  const phri::Model model = phri::Model::from_urdf_string(urdf);
  expect_config_error([&] { (void)model.frame_id("unknown"); }, {.mentions = {"unknown"}});
  expect_config_error([&] { (void)model.joint_id("unknown"); }, {.mentions = {"unknown"}});
}

// ------------------------------------------------------------------- no heap allocation
TEST(ModelAllocation, AlgorithmsDoNotAllocate) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3Urdf);
  phri::Data data(model);
  std::mt19937 rng(3);
  const Eigen::VectorXd q = random_vector(7, 2.0, rng), qd = random_vector(7, 1.0, rng), qdd = random_vector(7, 5.0, rng);
  Eigen::MatrixXd jacobian(6, 7);
  Eigen::VectorXd x = Eigen::VectorXd::Ones(7);
  const int ee = model.frame_id("end_effector_link");
  phri::Vector6d sink = phri::Vector6d::Zero();
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int repeat = 0; repeat < 3; ++repeat) {
      phri::compute_all_terms(model, data, q, qd);
      phri::coriolis_transpose_times_velocity(model, data);
      phri::frame_jacobian(model, data, ee, ReferenceFrame::kLocalWorldAligned, jacobian);
      phri::frame_jacobian(model, data, ee, ReferenceFrame::kLocal, jacobian);
      sink += phri::frame_jdot_qdot(model, data, ee, ReferenceFrame::kLocalWorldAligned);
      sink += phri::frame_velocity(model, data, ee, ReferenceFrame::kLocal);
      phri::mass_matrix_solve_in_place(data, x);
      phri::crba(model, data, q);
      phri::compute_mass_matrix_cholesky(data);
      phri::rnea(model, data, q, qd, qdd);
      phri::nonlinear_effects(model, data, q, qd);
      phri::compute_gravity(model, data, q);
      phri::forward_kinematics(model, data, q, qd, qdd);
      phri::update_frame_placements(model, data);
      sink += phri::frame_acceleration(model, data, ee, ReferenceFrame::kWorld);
    }
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_TRUE(sink.allFinite());
}

}  // namespace

TEST(ModelArguments, AWrongSizeIsAnArgumentErrorNamingTheFunctionAndTheSizes) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3Urdf);
  phri::Data data(model);
  const Eigen::VectorXd short_q = Eigen::VectorXd::Zero(model.nq() - 1);
  try {
    phri::forward_kinematics(model, data, short_q);
    FAIL() << "no exception";
  } catch (const phri::ArgumentError& e) {
    EXPECT_STREQ(e.what(), "forward_kinematics: q has 6 entries, expected 7");
  }
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(model.nq());
  EXPECT_THROW(phri::rnea(model, data, q, q, short_q), phri::ArgumentError);
  Eigen::MatrixXd jacobian(6, model.nv() + 1);
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  EXPECT_THROW(phri::frame_jacobian(model, data, 0, phri::ReferenceFrame::kWorld, jacobian), phri::Error);
}
