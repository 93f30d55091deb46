// ctest-labels: physics
// The compliant QP controller closing the loop on MuJoCo (the Gen3 plant model with its rotor
// inertia, joint torques applied exactly, ideal torque sensors, pushes with mj_applyFT): the paper's compliance behaviours and stiff safety
// constraints, measured. This is the ideal-actuator check; the realistic plant (friction, rotor
// inertia, sensor noise, model mismatch) is exercised through phri::SimRobot elsewhere.
#include <phri/control/compliance_controller.hpp>
#include <phri/control/momentum_observer.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/model/algorithms.hpp>

#include "mujoco_reference.hpp"

#include <gtest/gtest.h>

#include <functional>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

struct Push {
  std::string body;
  Eigen::Vector3d point_in_body = Eigen::Vector3d::Zero();
  Eigen::Vector3d force = Eigen::Vector3d::Zero();  // world
};

class ClosedLoop {
public:
  explicit ClosedLoop(phri::ComplianceMode mode, phri::WholeBodyQpSettings settings = {})
      : model_(phri::Model::from_urdf_file(kGen3 + "gen3.urdf")),
        data_(model_),
        collision_(phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_)),
        mj_(phri::test::MujocoReference::from_file(kGen3 + "gen3_plant.xml")),
        qp_(model_, &collision_, with_paper_limits(settings)),
        compliance_(phri::ComplianceSettings{}),
        observer_(model_, 50.0) {
    mj_.bind(model_);
    // The real arm's reflected rotor inertia (actuators.yaml, 0.03 kg.m^2 per joint) sits on the
    // motor side of the torque sensors: MuJoCo carries it as armature, the applied torque adds
    // I_r qdd_d (as the low-level loop does) and the ideal sensor reads tau - I_r qdd.
    for (int i = 0; i < 7; ++i) mj_.model_mutable()->dof_armature[i] = kRotorInertia;
    q_.resize(7);
    q_ << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;  // the paper demo's postureTarget
    qd_ = Eigen::VectorXd::Zero(7);
    mj_.set_state(q_, qd_, qd_);
    phri::compute_all_terms(model_, data_, q_, qd_);
    tau_ = data_.gravity_torque;
    tau_sensor_ = tau_;
    qp_.posture().set_target(q_);
    compliance_.initialise(mode, qp_, data_);
    ee_ = model_.frame_id("end_effector_link");
  }

  static phri::WholeBodyQpSettings with_paper_limits(phri::WholeBodyQpSettings s) {
    if (s.end_effector_frame.empty()) s.end_effector_frame = "end_effector_link";  // no library default
    if (s.torque_limit.size() == 0) {
      s.torque_limit.resize(7);
      s.torque_limit << 95, 95, 95, 95, 26, 45, 26;  // actuators.yaml (paper QP limits)
    }
    if (s.velocity_limit.size() == 0) {
      s.velocity_limit.resize(7);
      s.velocity_limit << 2.0944, 2.0944, 2.0944, 2.0944, 3.049, 3.049, 3.049;
    }
    return s;
  }

  // One 1 ms control cycle and 4 physics steps; `push` (if any) acts during them.
  void step(const std::optional<Push>& push) {
    const mjModel* m = mj_.model();
    mjData* d = mj_.data();
    for (int i = 0; i < 7; ++i) {
      q_[i] = d->qpos[i];
      qd_[i] = d->qvel[i];
    }
    phri::compute_all_terms(model_, data_, q_, qd_);
    phri::coriolis_transpose_times_velocity(model_, data_);
    observer_.update(data_, qd_, tau_sensor_, kDt);
    const bool on_ee = push && push->body == "bracelet_link";
    compliance_.update(on_ee ? push->force.norm() : 0.0, qp_, data_);
    status_ = qp_.update(model_, data_, q_, qd_, observer_.external_torque(), kDt);
    max_torque_step_ = std::max(max_torque_step_, (qp_.desired_torque() - tau_).cwiseAbs().maxCoeff());
    tau_ = qp_.desired_torque();
    torque_within_limits_ &= (tau_.cwiseAbs().array() <= qp_.torque_limit().array() + 1e-6).all();
    for (int s = 0; s < 4; ++s) {
      for (int i = 0; i < 7; ++i) d->qfrc_applied[i] = tau_[i] + kRotorInertia * qp_.desired_acceleration()[i];
      if (push) {
        const int body = mj_.body_id(push->body);
        Eigen::Vector3d point = body_pose(push->body) * push->point_in_body;
        mjtNum f[3] = {push->force.x(), push->force.y(), push->force.z()}, torque[3] = {0, 0, 0};
        mjtNum p[3] = {point.x(), point.y(), point.z()};
        mj_applyFT(m, d, f, torque, p, body, d->qfrc_applied);
      }
      mj_step(m, d);
    }
    for (int i = 0; i < 7; ++i) tau_sensor_[i] = tau_[i] + kRotorInertia * (qp_.desired_acceleration()[i] - d->qacc[i]);
    time_ += kDt;
  }
  void run(double seconds, const std::optional<Push>& push, const std::function<void()>& each = {}) {
    const int n = static_cast<int>(std::lround(seconds / kDt));
    for (int k = 0; k < n; ++k) {
      step(push);
      if (each) each();
    }
  }

  Eigen::Isometry3d body_pose(const std::string& name) const { return mj_.body_pose(name); }
  Eigen::Isometry3d ee_pose() const { return mj_.site_pose("end_effector"); }
  double ee_position_error() const { return (qp_.end_effector().target_pose().translation() - ee_pose().translation()).norm(); }
  double ee_orientation_error() const {
    return phri::rotation_log(qp_.end_effector().target_pose().linear() * ee_pose().linear().transpose()).norm();
  }

  static constexpr double kDt = 1e-3;
  static constexpr double kRotorInertia = 0.03;
  phri::Model model_;
  phri::Data data_;
  phri::CollisionModel collision_;
  phri::test::MujocoReference mj_;
  phri::WholeBodyQp qp_;
  phri::ComplianceController compliance_;
  phri::MomentumObserver observer_;
  Eigen::VectorXd q_, qd_, tau_, tau_sensor_;
  int ee_ = 0;
  double time_ = 0.0;
  double max_torque_step_ = 0.0;
  bool torque_within_limits_ = true;
  phri::WholeBodyQpStatus status_ = phri::WholeBodyQpStatus::kOk;
};

TEST(ClosedLoop, NullSpaceComplianceElbowMovesEndEffectorHolds) {
  ClosedLoop loop(phri::ComplianceMode::kNullSpace);
  loop.run(0.3, std::nullopt);
  const Eigen::Vector3d elbow_start = loop.body_pose("forearm_link").translation();
  double max_pos = 0.0, max_ori = 0.0, elbow_move = 0.0;
  auto track = [&]() {
    max_pos = std::max(max_pos, loop.ee_position_error());
    max_ori = std::max(max_ori, loop.ee_orientation_error());
    elbow_move = std::max(elbow_move, (loop.body_pose("forearm_link").translation() - elbow_start).norm());
  };
  loop.run(1.0, Push{"forearm_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 30, 0)}, track);
  loop.run(3.0, std::nullopt, track);
  const double elbow_back = (loop.body_pose("forearm_link").translation() - elbow_start).norm();
  std::printf("null-space: elbow moved %.1f mm, EE error max %.3f mm / %.3f deg, elbow back to %.2f mm\n",
              1e3 * elbow_move, 1e3 * max_pos, max_ori * 180 / M_PI, 1e3 * elbow_back);
  EXPECT_GT(elbow_move, 0.05);
  EXPECT_LT(max_pos, 0.002);
  EXPECT_LT(max_ori * 180 / M_PI, 1.0);
  EXPECT_LT(elbow_back, 0.01);
  EXPECT_TRUE(loop.torque_within_limits_);
}

TEST(ClosedLoop, FullBodyComplianceYieldsAndReturns) {
  ClosedLoop loop(phri::ComplianceMode::kFullBody);
  loop.run(0.3, std::nullopt);
  const Eigen::Vector3d start = loop.ee_pose().translation();
  double moved = 0.0;
  loop.run(1.5, Push{"bracelet_link", Eigen::Vector3d(0, 0, -0.0615), Eigen::Vector3d(0, 0, -20)},
           [&]() { moved = std::max(moved, (loop.ee_pose().translation() - start).norm()); });
  loop.run(4.0, std::nullopt);
  const double back = (loop.ee_pose().translation() - start).norm();
  std::printf("full-body: EE moved %.1f mm under 20 N, %.2f mm from the target 4 s after release\n", 1e3 * moved,
              1e3 * back);
  EXPECT_GT(moved, 0.03);
  EXPECT_LT(back, 0.002);
}

TEST(ClosedLoop, DualComplianceKeepsTheNewPoseAndIgnoresLightTouches) {
  ClosedLoop loop(phri::ComplianceMode::kDual);
  loop.run(0.3, std::nullopt);
  const Eigen::Vector3d start = loop.ee_pose().translation();
  loop.run(1.0, Push{"bracelet_link", Eigen::Vector3d(0, 0, -0.0615), Eigen::Vector3d(0, 3, 0)});
  EXPECT_EQ(loop.compliance_.touch_count(), 0);
  const double light = (loop.ee_pose().translation() - start).norm();
  loop.run(1.0, Push{"bracelet_link", Eigen::Vector3d(0, 0, -0.0615), Eigen::Vector3d(0, 15, 0)});
  EXPECT_EQ(loop.compliance_.touch_count(), 1);
  loop.run(0.5, std::nullopt);
  EXPECT_FALSE(loop.compliance_.touched());
  const Eigen::Vector3d released = loop.ee_pose().translation();
  double drift = 0.0;
  loop.run(2.0, std::nullopt, [&]() { drift = std::max(drift, (loop.ee_pose().translation() - released).norm()); });
  std::printf("dual: 3 N moved the EE %.2f mm (no switch); 15 N moved it %.1f mm; drift after release %.3f mm\n",
              1e3 * light, 1e3 * (released - start).norm(), 1e3 * drift);
  EXPECT_GT((released - start).norm(), 0.03);
  EXPECT_LT(drift, 0.001);
}

TEST(ClosedLoop, JointLimitDamperNegatesAPushTowardTheLimit) {
  ClosedLoop loop(phri::ComplianceMode::kFullBody);
  loop.run(0.2, std::nullopt);
  // Fold the elbow: a force at the wrist along -d(wrist)/d(q4).
  phri::Data& data = loop.data_;
  Eigen::MatrixXd jacobian(3, 7);
  const int wrist_body = 4;  // spherical_wrist_1_link moves with joint 5's body; its origin is on joint 4's chain
  const Eigen::Vector3d wrist = data.body_placements[static_cast<std::size_t>(wrist_body)].translation();
  phri::body_point_linear_jacobian(loop.model_, data, 3, wrist, jacobian);
  const Eigen::Vector3d direction = -jacobian.col(3).normalized();
  const double lower = -2.57, d_s = 0.01 * 5.14;
  double min_q4 = 0.0, max_speed_ratio = 0.0;
  loop.run(2.0, Push{"spherical_wrist_1_link", Eigen::Vector3d::Zero(), 60.0 * direction}, [&]() {
    min_q4 = std::min(min_q4, loop.q_[3]);
    max_speed_ratio = std::max(max_speed_ratio, (loop.qd_.cwiseAbs().array() / loop.qp_.velocity_limit().array()).maxCoeff());
  });
  std::printf("joint limit: q4 min %.4f rad (limit + d_s = %.4f), max |qd|/limit %.3f\n", min_q4, lower + d_s, max_speed_ratio);
  EXPECT_GT(min_q4, lower + d_s - 0.5 * M_PI / 180);
  EXPECT_LT(max_speed_ratio, 1.0 / 0.9);  // never beyond the robot's limit (the QP keeps 0.9 of it)
  EXPECT_TRUE(loop.torque_within_limits_);
}

TEST(ClosedLoop, SelfCollisionDamperKeepsTheWristOffTheBase) {
  ClosedLoop loop(phri::ComplianceMode::kFullBody);
  loop.run(0.2, std::nullopt);
  double min_distance = 1.0;
  for (int phase = 0; phase < 3; ++phase) {
    loop.run(1.0, std::nullopt, [&]() {});
    // Push the wrist toward the base column, re-aimed every second.
    const Eigen::Vector3d wrist = loop.body_pose("spherical_wrist_2_link").translation();
    const Eigen::Vector3d direction = (Eigen::Vector3d(0, 0, 0.1) - wrist).normalized();
    loop.run(1.5, Push{"spherical_wrist_2_link", Eigen::Vector3d::Zero(), 60.0 * direction}, [&]() {
      min_distance = std::min(min_distance, loop.qp_.collision_data()->distance.minCoeff());
    });
  }
  std::printf("self-collision: smallest capsule distance %.1f mm (d_s = 15 mm)\n", 1e3 * min_distance);
  EXPECT_GT(min_distance, 0.015 - 0.002);
}

TEST(ClosedLoop, UnreachableTargetGivesBoundedSmoothTorques) {
  ClosedLoop loop(phri::ComplianceMode::kStiff);
  loop.run(0.2, std::nullopt);
  Eigen::Isometry3d far = loop.qp_.end_effector().target_pose();
  far.translation() = Eigen::Vector3d(1.5, 0.0, 0.4);  // beyond reach: the arm stretches to a singularity
  loop.qp_.end_effector().set_target(far);
  loop.max_torque_step_ = 0.0;
  loop.run(3.0, std::nullopt);
  std::printf("unreachable target: max torque step %.2f N.m per ms, status %s\n", loop.max_torque_step_,
              std::string(phri::to_string(loop.status_)).c_str());
  EXPECT_TRUE(loop.torque_within_limits_);
  EXPECT_TRUE(loop.tau_.allFinite());
  EXPECT_LT(loop.max_torque_step_, 20.0);
}

}  // namespace
