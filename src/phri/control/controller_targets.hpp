#pragma once
// phri::ControllerTargets: everything that changes the controller at run time, as plain data.
// The FSM fills it each period from the gamepad, the dashboard, the timeline or a script, and
// Controller::step(state, targets, command) applies it at the start of that cycle. Nothing else
// reaches into the controller (DESIGN.md section 2: data flow one way).
//
// Requests (the optionals) act once, in the cycle they are given; references persist: a pose or
// posture target given once stays the task's target until the next one (dual compliance may also
// move the end-effector target on release).
#include <phri/control/compliance_mode.hpp>
#include <phri/model/spatial.hpp>
#include <phri/robot/low_level_mode.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <optional>

namespace phri {

/// An end-effector reference: pose, twist and acceleration (world axes, about the frame's origin).
struct PoseReference {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  Vector6d velocity = Vector6d::Zero();
  Vector6d acceleration = Vector6d::Zero();
};

/// A joint-space reference for the posture task.
struct PostureReference {
  Eigen::VectorXd q, qd, qdd;
};

struct ControllerTargets {
  ControllerTargets() = default;
  /// Buffers sized for `nv` joints (so filling them in the cycle allocates nothing).
  explicit ControllerTargets(int nv) {
    posture.q = Eigen::VectorXd::Zero(nv);
    posture.qd = Eigen::VectorXd::Zero(nv);
    posture.qdd = Eigen::VectorXd::Zero(nv);
  }

  std::optional<ComplianceMode> compliance_mode;  ///< switch to this compliance mode
  std::optional<LowLevelMode> low_level_mode;     ///< switch to this loop (bumpless)
  std::optional<double> stiffness_scale;          ///< end-effector stiffness factor, clamped to [0.1, 4]
  // Live gains (the dashboard's sliders), clamped where they enter (ComplianceController). A
  // gamma in [0, 1] replaces the compliance mode's gamma of that task; a negative one gives the
  // task back to its mode.
  std::optional<double> ee_gamma;
  std::optional<double> posture_gamma;
  std::optional<double> posture_stiffness;        ///< posture task stiffness [1/s^2], clamped to [0, 400]
  bool has_pose = false;     ///< `pose` is the end-effector task's new reference
  PoseReference pose;
  bool has_posture = false;  ///< `posture` is the posture task's new reference
  PostureReference posture;

  /// Nothing requested, no new reference (buffers kept).
  void clear() {
    compliance_mode.reset();
    low_level_mode.reset();
    stiffness_scale.reset();
    ee_gamma.reset();
    posture_gamma.reset();
    posture_stiffness.reset();
    has_pose = false;
    has_posture = false;
  }
};

}  // namespace phri
