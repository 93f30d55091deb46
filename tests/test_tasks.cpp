// ctest-labels: unit
// Tasks as objects (control/task.hpp, task_registry.hpp): each type's rows against finite
// differences of the model's forward kinematics, its reference against closed forms, the
// registry's errors, per-axis gamma in the tool's axes, and the QP assembled from a list; the
// declared plane constraint's row against finite differences and its bound against the damper's
// closed form.
#include <phri/control/constraint_registry.hpp>
#include <phri/control/task_registry.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/model/algorithms.hpp>

#include "allocation_counter.hpp"
#include "task_spec.hpp"

#include <gtest/gtest.h>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

struct Arm {
  phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data{model};
  Eigen::VectorXd q = Eigen::VectorXd(7), qd = Eigen::VectorXd::Zero(7), tau_ext = Eigen::VectorXd::Zero(7),
                  qdd_ext = Eigen::VectorXd::Zero(7);
  int ee = model.frame_id("end_effector_link");
  Arm() {
    q << 0.1, 0.58, 3.0, -1.84, 0.2, 0.85, 1.57;
    phri::compute_all_terms(model, data, q, qd);
  }
  phri::TaskBuildContext build() const { return {model, ee, 0.1}; }
  phri::TaskContext context(const phri::Vector6d* wrench = nullptr) const {
    return {model, data, q, qd, tau_ext, qdd_ext, wrench, 0.001};
  }
  // The position of a frame at q + h e_i (central differences give its Jacobian column).
  Eigen::Vector3d position(int frame, const Eigen::VectorXd& at) const {
    phri::Data d(model);
    phri::forward_kinematics(model, d, at);
    phri::update_frame_placements(model, d);
    return d.frame_placements[static_cast<std::size_t>(frame)].translation();
  }
  Eigen::MatrixXd linear_jacobian_fd(int frame) const {
    Eigen::MatrixXd j(3, 7);
    for (int i = 0; i < 7; ++i) {
      Eigen::VectorXd up = q, down = q;
      up[i] += 1e-6;
      down[i] -= 1e-6;
      j.col(i) = (position(frame, up) - position(frame, down)) / 2e-6;
    }
    return j;
  }
};

// The end effector's inertia along -z with its other axes held, n' (J M^-1 J')^-1 n.
double inertia_along_minus_z(const Arm& arm) {
  Eigen::MatrixXd j(6, 7);
  phri::frame_jacobian(arm.model, arm.data, arm.ee, phri::ReferenceFrame::kLocalWorldAligned, j);
  const Eigen::MatrixXd m_inverse = arm.data.mass_matrix.inverse();
  const Eigen::MatrixXd lambda = (j * m_inverse * j.transpose()).inverse();
  return lambda(2, 2);  // n = -z: the sign cancels
}

// H and g of one task alone.
std::pair<Eigen::MatrixXd, Eigen::VectorXd> objective(const phri::Task& task) {
  Eigen::MatrixXd h = Eigen::MatrixXd::Zero(7, 7);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd d = Eigen::VectorXd::Zero(7);
  phri::ObjectiveTerms objective{h, d, g};
  task.add_objective(objective);
  h.diagonal() += d;
  return {h, g};
}

TEST(ForceTask, RowIsTheAxisAlongTheFiniteDifferenceJacobianAndReferenceTheAdmittance) {
  Arm arm;
  phri::TaskSpec s = phri::test::task_spec("force", "press");
  s.numbers["force_N"] = {10.0};
  s.numbers["axis"] = {0.0, 0.0, -1.0};
  s.numbers["weight"] = {2.0};
  s.numbers["max_speed_m_s"] = {0.5};
  auto task = phri::make_task(s, arm.build());
  // The environment pushes the robot up with 6 N: the robot applies 6 N down, 4 N short of 10.
  phri::Vector6d wrench = phri::Vector6d::Zero();
  wrench[2] = 6.0;
  task->update(arm.context(&wrench));
  const auto [h, g] = objective(*task);
  const Eigen::RowVectorXd row = Eigen::Vector3d(0, 0, -1).transpose() * arm.linear_jacobian_fd(arm.ee);
  EXPECT_LT((h - 2.0 * row.transpose() * row).norm(), 1e-6);
  // At rest: b = D v* = g (f* - f) / Lambda_n, Lambda_n = n' (J M^-1 J')^-1 n (the default gain 1), g = -w b a.
  const double lambda = inertia_along_minus_z(arm);
  EXPECT_LT((g + 2.0 * (4.0 / lambda) * row.transpose()).norm(), 1e-6);
  // A speed bound below v*: b = D v_max (default D 100).
  s.numbers["max_speed_m_s"] = {0.001};
  auto slow = phri::make_task(s, arm.build());
  slow->update(arm.context(&wrench));
  const auto [h2, g2] = objective(*slow);
  EXPECT_LT((g2 + 2.0 * (100.0 * 0.001) * row.transpose()).norm(), 1e-6);
}

TEST(ForceTask, WithoutAnFtSensorTheWrenchIsTheLeastSquaresOneThatExplainsTauExt) {
  Arm arm;
  phri::TaskSpec s = phri::test::task_spec("force", "press");
  s.numbers["force_N"] = {0.0};
  s.numbers["max_speed_m_s"] = {0.5};
  auto task = phri::make_task(s, arm.build());
  // A 7 N push down on the end effector: tau_ext = J^T F; along n = -z the robot applies
  // f = -n.F = -7 N, so b = (f* - f) / Lambda_n = 7 / Lambda_n.
  Eigen::MatrixXd j(6, 7);
  phri::frame_jacobian(arm.model, arm.data, arm.ee, phri::ReferenceFrame::kLocalWorldAligned, j);
  phri::Vector6d push = phri::Vector6d::Zero();
  push[2] = -7.0;
  arm.tau_ext = j.transpose() * push;
  task->update(arm.context());
  const auto [h, g] = objective(*task);
  const Eigen::RowVectorXd row = -j.row(2);
  EXPECT_LT((h - 1e4 * row.transpose() * row).norm(), 1e-6);
  EXPECT_LT((g + 1e4 * (7.0 / inertia_along_minus_z(arm)) * row.transpose()).norm() / 1e4, 1e-6);
}

TEST(FrameTask, RowsAreTheLinkPositionJacobianSelectedAndTheReferenceASpringToTheTarget) {
  Arm arm;
  const int elbow = arm.model.frame_id("forearm_link");
  phri::TaskSpec s = phri::test::task_spec("frame", "elbow_height");
  s.words["frame"] = "forearm_link";
  s.numbers["selection"] = {0.0, 0.0, 1.0};
  s.numbers["stiffness"] = {40.0};
  s.numbers["damping"] = {0.0};
  s.numbers["weight"] = {3.0};
  const Eigen::Vector3d p = arm.data.frame_placements[static_cast<std::size_t>(elbow)].translation();
  s.numbers["target_m"] = {p.x(), p.y(), p.z() + 0.05};
  auto task = phri::make_task(s, arm.build());
  task->start(arm.model, arm.data);  // a given target is kept
  task->update(arm.context());
  const auto [h, g] = objective(*task);
  const Eigen::RowVectorXd row = arm.linear_jacobian_fd(elbow).row(2);
  EXPECT_LT((h - 3.0 * row.transpose() * row).norm(), 1e-6);
  EXPECT_LT((g + 3.0 * (40.0 * 0.05) * row.transpose()).norm(), 1e-6);  // at rest: no drift
}

TEST(PoseTask, FrameAxesWithIsotropicGainsGiveTheWorldAxesObjective) {
  // ||R^T r||^2 = ||r||^2: with the same gain on every axis the tool's axes change nothing.
  Arm arm;
  arm.qd << 0.2, -0.1, 0.3, 0.1, -0.2, 0.4, 0.1;
  phri::compute_all_terms(arm.model, arm.data, arm.q, arm.qd);
  arm.qdd_ext << 0.5, -1.0, 0.2, 0.3, 0.0, -0.4, 1.0;
  std::pair<Eigen::MatrixXd, Eigen::VectorXd> results[2];
  for (int frame_axes = 0; frame_axes < 2; ++frame_axes) {
    phri::EndEffectorTask task(arm.model, arm.ee);
    task.set_axes(frame_axes ? phri::TaskAxes::kFrame : phri::TaskAxes::kWorld);
    task.reset_gains(phri::Vector6d::Constant(80.0), phri::Vector6d::Constant(9.0), 10.0, phri::Vector6d::Constant(0.5));
    Eigen::Isometry3d target = arm.data.frame_placements[static_cast<std::size_t>(arm.ee)];
    target.translation() += Eigen::Vector3d(0.02, -0.01, 0.03);
    task.set_target(target);
    task.update(arm.context());
    results[frame_axes] = objective(task);
  }
  EXPECT_LT((results[0].first - results[1].first).norm(), 1e-9 * results[0].first.norm());
  EXPECT_LT((results[0].second - results[1].second).norm(), 1e-9 * results[0].second.norm());
}

TEST(PoseTask, PerAxisGammaInTheToolAxesLetsThroughOnlyThePushAlongTheToolZ) {
  Arm arm;
  arm.qdd_ext << 0.5, -1.0, 0.2, 0.3, 0.0, -0.4, 1.0;
  phri::EndEffectorTask task(arm.model, arm.ee);
  task.set_axes(phri::TaskAxes::kFrame);
  phri::Vector6d gamma = phri::Vector6d::Zero();
  gamma[2] = 1.0;
  task.reset_gains(phri::Vector6d::Zero(), phri::Vector6d::Zero(), 1.0, phri::Vector6d::Zero());
  task.set_fixed_gamma(gamma);
  task.set_role_gamma(0.0);  // a mode's gamma does not touch a declared one
  task.hold_current_pose(arm.data);
  task.update(arm.context());
  // Rows R^T J; reference: the drift in tool axes plus gamma R^T J qdd_ext, only on the tool's z.
  const Eigen::Matrix3d r = arm.data.frame_placements[static_cast<std::size_t>(arm.ee)].linear();
  Eigen::MatrixXd j(6, 7);
  phri::frame_jacobian(arm.model, arm.data, arm.ee, phri::ReferenceFrame::kLocalWorldAligned, j);
  EXPECT_LT((task.rows().topRows<3>() - r.transpose() * j.topRows<3>()).norm(), 1e-12);
  const Eigen::Vector3d push_tool = r.transpose() * (j.topRows<3>() * arm.qdd_ext);
  phri::Vector6d drift = phri::frame_jdot_qdot(arm.model, arm.data, arm.ee, phri::ReferenceFrame::kLocalWorldAligned);
  EXPECT_NEAR(task.reference()[2], push_tool.z() - (r.transpose() * drift.head<3>()).z(), 1e-12);
  EXPECT_NEAR(task.reference()[0], -(r.transpose() * drift.head<3>()).x(), 1e-12);
}

TEST(PoseTask, ASelectionOfZeroLeavesTheAxisOutOfTheObjective) {
  Arm arm;
  phri::EndEffectorTask task(arm.model, arm.ee);
  phri::Vector6d selection = phri::Vector6d::Ones();
  selection[2] = 0.0;
  task.set_selection(selection);
  task.reset_gains(phri::Vector6d::Constant(50.0), phri::Vector6d::Constant(5.0), 2.0, phri::Vector6d::Zero());
  task.hold_current_pose(arm.data);
  task.update(arm.context());
  Eigen::MatrixXd j(6, 7);
  phri::frame_jacobian(arm.model, arm.data, arm.ee, phri::ReferenceFrame::kLocalWorldAligned, j);
  const auto [h, g] = objective(task);
  const Eigen::MatrixXd expected = 2.0 * j.transpose() * selection.asDiagonal() * j;
  EXPECT_LT((h - expected).norm(), 1e-9 * expected.norm());
}

TEST(TaskRegistry, ErrorsNameTheKeyAndListWhatIsKnown) {
  Arm arm;
  auto message = [&](const phri::TaskSpec& s) {
    try {
      phri::make_task(s, arm.build());
    } catch (const phri::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message(phri::test::task_spec("polish", "p")).find("unknown task type 'polish' (known: pose, posture, force, frame)"),
            std::string::npos);
  phri::TaskSpec s = phri::test::task_spec("force", "press");
  s.numbers["forse_N"] = {10.0};
  EXPECT_NE(message(s).find("controller.tasks[0]: forse_N: unknown key for a force task"), std::string::npos);
  s = phri::test::task_spec("force", "press");
  s.numbers["force_N"] = {1e6};
  EXPECT_NE(message(s).find("force_N: 1e+06 is outside [-200, 200]"), std::string::npos);
  s = phri::test::task_spec("force", "press");
  s.numbers["axis"] = {0.0, 0.0, 0.0};
  EXPECT_NE(message(s).find("axis: must not be zero"), std::string::npos);
  s = phri::test::task_spec("frame", "elbow");
  EXPECT_NE(message(s).find("frame: name the frame"), std::string::npos);
  s.words["frame"] = "no_such_link";
  EXPECT_NE(message(s).find("no frame 'no_such_link'"), std::string::npos);
  s = phri::test::task_spec("pose", "tool");
  s.words["frame"] = "end_effector";
  s.words["axes"] = "tool";
  EXPECT_NE(message(s).find("axes: 'tool' is not one of: world, frame"), std::string::npos);
}

TEST(WholeBodyQp, TasksAreAListNamesUniqueAndTheCycleAllocatesNothingWithTheNewTypes) {
  Arm arm;
  phri::WholeBodyQpSettings settings;
  settings.end_effector_frame = "end_effector_link";
  phri::WholeBodyQp qp(arm.model, nullptr, settings);
  ASSERT_EQ(qp.tasks().size(), 2u);
  EXPECT_EQ(qp.tasks()[0]->name(), "end_effector");
  EXPECT_EQ(qp.tasks()[1]->type(), "posture");
  phri::TaskSpec force = phri::test::task_spec("force", "press");
  phri::TaskSpec elbow = phri::test::task_spec("frame", "elbow");
  elbow.words["frame"] = "forearm_link";
  qp.add_task(phri::make_task(force, arm.build()));
  qp.add_task(phri::make_task(elbow, arm.build()));
  EXPECT_THROW(qp.add_task(phri::make_task(force, arm.build())), phri::ConfigError);
  EXPECT_EQ(qp.find_task("press")->type(), "force");
  qp.start_tasks(arm.model, arm.data);
  qp.posture().set_target(arm.q);
  qp.update(arm.model, arm.data, arm.q, arm.qd, arm.tau_ext, 0.001);  // warm-up
  phri::Vector6d wrench = phri::Vector6d::Zero();
  phri::test::AllocationCounter counter;
  for (int i = 0; i < 10; ++i) qp.update(arm.model, arm.data, arm.q, arm.qd, arm.tau_ext, 0.001, i % 2 ? &wrench : nullptr);
  EXPECT_EQ(counter.allocations(), 0u);
  EXPECT_EQ(qp.status(), phri::WholeBodyQpStatus::kOk);
}

// The plane constraint (plane_constraint.cpp) on the end effector: its row predicts the distance's
// second derivative (central differences of n . p along q(t) = q + qd t + qdd t^2 / 2), and its
// lower bound is the paper's damper, -k (d - d_s) - lambda ḋ, written out here.
TEST(PlaneConstraint, RowIsTheDistancesSecondDerivativeAndItsBoundThePapersDamper) {
  Arm arm;
  arm.qd << 0.3, -0.2, 0.4, 0.1, -0.5, 0.3, 0.2;
  phri::compute_all_terms(arm.model, arm.data, arm.q, arm.qd);
  const Eigen::Vector3d n = Eigen::Vector3d(0.2, -0.3, 1.0).normalized();
  const double p0 = n.dot(arm.data.frame_placements[static_cast<std::size_t>(arm.ee)].translation());
  phri::ConstraintSpec s = phri::test::task_spec("plane", "table");
  s.words["frame"] = "end_effector";
  s.numbers["normal"] = {0.2, -0.3, 1.0};
  s.numbers["offset_m"] = {p0 - 0.03};  // 30 mm from the plane: within the influence distance
  s.numbers["influence_distance_m"] = {0.05};
  s.numbers["safety_distance_m"] = {0.01};
  s.numbers["approach_speed_m_s"] = {0.1};
  s.numbers["amortization"] = {1.8};
  std::unique_ptr<phri::Constraint> plane = phri::make_constraint(s, {arm.model, arm.ee});
  ASSERT_EQ(plane->num_rows(), 1);
  const Eigen::VectorXd torque_limit = Eigen::VectorXd::Constant(7, 50.0), diag = arm.data.mass_matrix.diagonal();
  const phri::ConstraintContext context{arm.model, arm.data, arm.q, arm.qd, arm.tau_ext, arm.tau_ext, torque_limit, diag};
  Eigen::MatrixXd a(1, 7);
  Eigen::VectorXd l(1), u(1);
  plane->fill_rows(context, a, l, u);

  Eigen::VectorXd qdd(7);
  qdd << 1.0, -0.5, 0.7, 0.2, -1.1, 0.4, 0.9;
  const double h = 1e-4;
  auto d = [&](double t) { return n.dot(arm.position(arm.ee, arm.q + arm.qd * t + 0.5 * qdd * t * t)) - (p0 - 0.03); };
  const double d_dot = (d(h) - d(-h)) / (2 * h);
  const double d_ddot = (d(h) - 2 * d(0) + d(-h)) / (h * h);
  const double drift = d_ddot - a.row(0).dot(qdd);  // n . J̇ qd, if the row is right for every qdd
  Eigen::VectorXd qdd2 = -2.0 * qdd;
  auto d2 = [&](double t) { return n.dot(arm.position(arm.ee, arm.q + arm.qd * t + 0.5 * qdd2 * t * t)); };
  EXPECT_NEAR((d2(h) - 2 * d2(0) + d2(-h)) / (h * h) - a.row(0).dot(qdd2), drift, 1e-4);
  EXPECT_NEAR(a.row(0).dot(arm.qd), d_dot, 1e-7);

  const double lambda = 4.0 * 1.8 * 1.8 * 0.1 / (0.05 - 0.01);
  const double k = lambda * lambda / (4.0 * 1.8 * 1.8);
  EXPECT_NEAR(l[0], -k * (0.03 - 0.01) - lambda * d_dot - drift, 1e-4);
  EXPECT_TRUE(std::isinf(u[0]) && u[0] > 0);

  // Beyond the influence distance the row is free.
  s.numbers["offset_m"] = {p0 - 0.2};
  phri::make_constraint(s, {arm.model, arm.ee})->fill_rows(context, a, l, u);
  EXPECT_TRUE(std::isinf(l[0]) && l[0] < 0);
}

TEST(ConstraintRegistry, ErrorsNameTheKeyAndSayThePapersConstraintsAreAlwaysOn) {
  Arm arm;
  auto message = [&](const phri::ConstraintSpec& s) {
    try {
      phri::make_constraint(s, {arm.model, arm.ee});
    } catch (const phri::ConfigError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string unknown = message(phri::test::task_spec("joint_limits", "j"));
  EXPECT_NE(unknown.find("unknown constraint type 'joint_limits' (known: plane; the paper's safety constraints are "
                         "always on"),
            std::string::npos)
      << unknown;
  phri::ConstraintSpec s = phri::test::task_spec("plane", "table");
  s.words["frame"] = "end_effector";
  EXPECT_NE(message(s).find("offset_m"), std::string::npos);
  s.numbers["offset_m"] = {0.1};
  s.numbers["ofset"] = {0.1};
  EXPECT_NE(message(s).find("controller.tasks[0]: ofset: unknown key for a plane constraint (known: type, name, frame"),
            std::string::npos)
      << message(s);
  s.numbers.erase("ofset");
  s.numbers["safety_distance_m"] = {0.08};
  EXPECT_NE(message(s).find("safety_distance_m: must be below influence_distance_m"), std::string::npos) << message(s);
  s.numbers.erase("safety_distance_m");
  s.words["frame"] = "elbow_that_is_not";
  EXPECT_NE(message(s).find("no frame 'elbow_that_is_not'"), std::string::npos) << message(s);
}

}  // namespace
