// ctest-labels: physics
// phri's rigid-body dynamics against MuJoCo 2.2.2, an independent implementation: the Kinova Gen3
// (robots/kinova_gen3: gen3.urdf vs gen3_plant.xml) and random 6/7-DoF chains written both as URDF
// and MJCF. Compared: M, h, RNEA, g, every link pose, frame Jacobians. Worst relative errors are
// printed at the end of the run.
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>

#include "mujoco_reference.hpp"
#include "random_chain.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <random>

namespace {

using phri::test::MujocoReference;

constexpr double kTolerance = 1e-9;
const std::string kGen3Dir = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

// Relative error, the reference's infinity norm (floored at 1, so tiny entries count absolutely).
double relative_error(const Eigen::MatrixXd& value, const Eigen::MatrixXd& reference) {
  return (value - reference).cwiseAbs().maxCoeff() / std::max(1.0, reference.cwiseAbs().maxCoeff());
}

std::map<std::string, double>& worst_errors() {
  static std::map<std::string, double> worst;
  return worst;
}
void record(const std::string& what, double err) {
  double& w = worst_errors()[what];
  w = std::max(w, err);
}

class PrintWorstErrors : public ::testing::Environment {
public:
  void TearDown() override {
    std::printf("\nworst relative errors against MuJoCo:\n");
    for (const auto& [what, err] : worst_errors()) std::printf("  %-34s %.3e\n", what.c_str(), err);
  }
};
const auto* const kPrinter = ::testing::AddGlobalTestEnvironment(new PrintWorstErrors);

// Compares every quantity at one state; `label` prefixes the recorded error names.
void compare_state(const phri::Model& model, phri::Data& data, MujocoReference& mj, const Eigen::VectorXd& q,
                   const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd, const std::string& label,
                   const std::vector<std::pair<std::string, std::string>>& frame_to_site) {
  mj.set_state(q, qd, qdd);
  ASSERT_TRUE(phri::compute_all_terms(model, data, q, qd));

  double e = relative_error(data.mass_matrix, mj.mass_matrix());
  record(label + " M vs mj_fullM", e);
  EXPECT_LT(e, kTolerance) << "M";
  e = relative_error(data.nonlinear_effects, mj.bias());
  record(label + " h vs qfrc_bias", e);
  EXPECT_LT(e, kTolerance) << "h";

  // Frames: every link that MuJoCo also has as a body, and the named sites.
  Eigen::MatrixXd jacobian(6, model.nv());
  auto check_frame = [&](int frame, const Eigen::Isometry3d& reference, int mj_body) {
    const Eigen::Isometry3d& pose = data.frame_placements[static_cast<std::size_t>(frame)];
    double ep = (pose.translation() - reference.translation()).norm();
    double er = (pose.linear() - reference.linear()).cwiseAbs().maxCoeff();
    record(label + " frame position", ep);
    record(label + " frame rotation", er);
    EXPECT_LT(ep, kTolerance) << model.frame(frame).name;
    EXPECT_LT(er, kTolerance) << model.frame(frame).name;
    phri::frame_jacobian(model, data, frame, phri::ReferenceFrame::kLocalWorldAligned, jacobian);
    const Eigen::MatrixXd reference_jacobian = mj.point_jacobian(mj_body, pose.translation());
    e = relative_error(jacobian, reference_jacobian);
    record(label + " J (local-world-aligned) vs mj_jac", e);
    EXPECT_LT(e, kTolerance) << model.frame(frame).name;
    // World convention: the spatial Jacobian is mj_jac at the world origin.
    phri::frame_jacobian(model, data, frame, phri::ReferenceFrame::kWorld, jacobian);
    e = relative_error(jacobian, mj.point_jacobian(mj_body, Eigen::Vector3d::Zero()));
    record(label + " J (world) vs mj_jac", e);
    EXPECT_LT(e, kTolerance) << model.frame(frame).name;
  };
  for (int f = 0; f < model.num_frames(); ++f) {
    const std::string& name = model.frame(f).name;
    if (mj.has_body(name)) check_frame(f, mj.body_pose(name), mj.body_id(name));
  }
  for (const auto& [frame_name, site] : frame_to_site) {
    check_frame(model.frame_id(frame_name), mj.site_pose(site), mj.body_of_site(site));
  }

  const Eigen::VectorXd tau = phri::rnea(model, data, q, qd, qdd);
  e = relative_error(tau, mj.inverse());
  record(label + " RNEA vs mj_inverse", e);
  EXPECT_LT(e, kTolerance) << "rnea vs mj_inverse";
  // mj_rne leaves armature out: compare with RNEA minus the armature term.
  Eigen::VectorXd armature(model.nv());
  for (int i = 0; i < model.nv(); ++i) armature[i] = model.joint(i).armature;
  e = relative_error(tau - armature.cwiseProduct(qdd), mj.rne_with_acceleration());
  record(label + " RNEA vs mj_rne", e);
  EXPECT_LT(e, kTolerance) << "rnea vs mj_rne";

  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(model.nv());
  mj.set_state(q, zero, zero);
  e = relative_error(phri::compute_gravity(model, data, q), mj.bias());
  record(label + " g vs qfrc_bias(qd = 0)", e);
  EXPECT_LT(e, kTolerance) << "gravity";
}

TEST(ModelVsMujoco, KinovaGen3OneThousandRandomStates) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3Dir + "gen3.urdf");
  ASSERT_EQ(model.nq(), 7);
  phri::Data data(model);
  MujocoReference mj = MujocoReference::from_file(kGen3Dir + "gen3_plant.xml");
  mj.bind(model);
  std::vector<std::pair<std::string, std::string>> sites;
  if (mj.has_site("end_effector")) sites.emplace_back("end_effector_link", "end_effector");

  std::mt19937 rng(42);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  Eigen::VectorXd q(7), qd(7), qdd(7);
  for (int sample = 0; sample < 1000; ++sample) {
    for (int i = 0; i < 7; ++i) {
      const phri::Joint& j = model.joint(i);
      // Inside the limits, so that MuJoCo's limit constraints stay inactive in mj_inverse.
      q[i] = j.has_position_limits() ? 0.98 * j.upper * unit(rng) : 2.0 * M_PI * unit(rng);
      qd[i] = 2.0 * unit(rng);
      qdd[i] = 10.0 * unit(rng);
    }
    compare_state(model, data, mj, q, qd, qdd, "gen3", sites);
    if (HasFailure()) FAIL() << "sample " << sample << " q = " << q.transpose();
  }
}

class RandomChainVsMujoco : public ::testing::TestWithParam<int> {};

TEST_P(RandomChainVsMujoco, FiftyRobotsTwentyStatesEach) {
  const int dof = GetParam();
  std::mt19937 rng(1000 + static_cast<unsigned>(dof));
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int robot = 0; robot < 50; ++robot) {
    std::vector<double> armature;
    const phri::test::RandomChain chain = phri::test::make_random_chain(dof, rng, 0.5, &armature);
    phri::ModelOptions options;
    options.armature = armature;
    const phri::Model model = phri::Model::from_urdf_string(chain.urdf, options);
    ASSERT_EQ(model.nq(), dof);
    phri::Data data(model);
    MujocoReference mj = MujocoReference::from_string(chain.mjcf);
    mj.bind(model);
    ASSERT_EQ(mj.nv(), dof);
    Eigen::VectorXd q(dof), qd(dof), qdd(dof);
    for (int sample = 0; sample < 20; ++sample) {
      for (int i = 0; i < dof; ++i) {
        q[i] = 3.0 * unit(rng);
        qd[i] = 2.0 * unit(rng);
        qdd[i] = 10.0 * unit(rng);
      }
      compare_state(model, data, mj, q, qd, qdd, std::to_string(dof) + "-dof random", {});
      if (HasFailure()) FAIL() << "robot " << robot << " sample " << sample << "\n" << chain.urdf << "\n" << chain.mjcf;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(SixAndSevenDof, RandomChainVsMujoco, ::testing::Values(6, 7));

}  // namespace
