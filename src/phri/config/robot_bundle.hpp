#pragma once
// phri::RobotBundle: one folder per robot, robots/<robot>/robot.yaml (issue 16), naming the URDF
// and what the URDF does not say: the frames, the locked joints, the drives (actuators.yaml), the
// self-collision capsules (collision.yaml, optional), the end of arm (F/T sensor and tool), the
// compliance dead band per joint, the drive model and how the plant is made. Every key is
// commented in robots/kinova_gen3/robot.yaml.
//
//   const phri::RobotBundle robot = phri::RobotBundle::from_folder("robots/kinova_gen3");
//   robot.apply_to(controller_settings);   // model files, chain, frames, payloads, dead band
//   robot.apply_to(plant_config);          // arm description, drives, F/T sensor and tool
//
// `collision:` names a collision.yaml, or says `fitted`: capsules fitted from the URDF at load
// (link-frame radius 0.04 m; pairs closer than 0.03 m at the home posture, the self-collision
// damper's influence distance, left out). Absent: no self-collision constraint.
//
// A run YAML names a bundle with `robot: ../robots/kinova_gen3` (relative to the YAML), and
// `phri run --robot DIR` replaces whatever robot the YAML names. Errors are phri::ConfigError
// naming robot.yaml and the key path (e.g. "end_of_arm.tool.mass_kg").
#include <phri/control/controller_settings.hpp>
#include <phri/robot/drive_kind.hpp>
#include <phri/config/sim_robot_config.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <optional>
#include <string>
#include <vector>

namespace phri {

struct RobotBundle {
  /// Loads <folder>/robot.yaml; file names in it are relative to the folder and must exist.
  static RobotBundle from_folder(const std::string& folder);

  void apply_to(ControllerSettings& settings) const;
  /// The arm, its drives and its end of arm; the initial posture when the plant has none.
  void apply_to(SimRobotConfig& plant) const;

  std::string source;  ///< robot.yaml
  std::string name;
  std::string urdf_path, actuators_path, collision_path;  ///< absolute; collision_path '' for none
  /// `collision: fitted`: capsules fitted from the URDF at the home posture (model/capsule_fit.hpp),
  /// as a collision.yaml's text; '' otherwise.
  std::string collision_yaml;
  std::string base_link, tip_link, end_effector_frame;
  std::vector<std::string> locked_joints;
  std::vector<double> home_q_rad;
  /// `gravity_m_s2` [m/s^2, world frame] and `base_placement` {xyz_m, rpy_rad} (the base link in
  /// the world, URDF origin convention: R = Rz(yaw) Ry(pitch) Rx(roll)): the controller's model
  /// and the plant get the same. Defaults: (0, 0, -9.81), the identity.
  Eigen::Vector3d gravity_m_s2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  Eigen::Isometry3d base_placement = Eigen::Isometry3d::Identity();
  Eigen::VectorXd compliance_deadband_Nm;  ///< per joint
  /// `drive: kinova | generic`: whose drives, hence the loops offered (robot/drive_kind.hpp); the
  /// controller gets the offered loops, the plant the matching drive loops.
  DriveKind drive = DriveKind::kKinova;
  /// `drive: {kind: generic, position_hold: {kp_Nm_per_rad, kd_Nms_per_rad}}`: the generic drive's
  /// position hold (sim/generic_drive.hpp; empty: its default rule on the arm's inertia).
  GenericHoldGains generic_hold;
  /// The custom torque loop's H(z) (b, a in powers of z^-1); both empty: Kinova's (the library's) on a
  /// kinova drive, none (H = 0) on another (apply_to).
  std::vector<double> custom_loop_numerator, custom_loop_denominator;

  /// `end_of_arm`: the F/T sensor and the tool (becoming the controller's payloads and the
  /// plant's bodies); nullopt when the key is absent or says `none` (a bare flange).
  std::optional<EndOfArm> end_of_arm;
  /// `payloads`: bodies fixed to links of the arm beyond its URDF and its end of arm (none by
  /// default); the controller's model and the plant both carry them.
  std::vector<LinkPayload> payloads;

  struct Plant {
    std::string mjcf_path;  ///< hand-written arm MJCF; '' : generated from the URDF
    std::string flange_site;
    bool balance_inertia = false;
  } plant;
};

}  // namespace phri
