#pragma once
// phri::UrdfPlant: the plant's MJCF (the arm alone) generated from the robot's URDF, so that no
// second description has to be kept in step with the URDF by hand (issue 16).
//
//   phri::UrdfPlantOptions options;
//   options.urdf_path = "robots/my_arm/my_arm.urdf";
//   const phri::GeneratedPlant plant = phri::UrdfPlant::generate(options);   // throws ConfigError
//   // plant.mjcf: one <body> per URDF link (named after it), a <site> at every link frame (same
//   // name), hinge joints for revolute/continuous, slide joints for prismatic; plant.warnings
//
// The translation reads the URDF with urdfdom (the parser the controller's model uses too) but
// writes numbers with 17 digits and diagonalises each inertia in double precision: MuJoCo's own
// URDF import (mj_loadXML on a .urdf) is the independent reference the tests compare it with, but
// its MJCF export (mj_saveLastXML) keeps only 6 digits, and its fullinertia diagonalisation is
// accurate to ~1e-10 only (tools/mjcf_principal_inertia.py).
//
// What the plant does not take from the URDF: visual and collision geometry (the plant's contacts
// are the drop mass and the floor only), joint <dynamics> (the drive model of actuators.yaml
// applies friction and rotor inertia outside the MJCF), transmissions. Locked joints (e.g. gripper
// fingers) become welds at position 0, as in the controller's model. A link inertia that breaks
// the triangle inequality is refused unless balance_inertia is set, which turns on MuJoCo's
// compiler balanceinertia (the link's moments are then changed: a warning names each such link).
#include <Eigen/Core>

#include <string>
#include <vector>

namespace phri {

struct UrdfPlantOptions {
  std::string urdf_path;
  std::vector<std::string> locked_joints;  ///< welded at 0 (a gripper's fingers)
  bool balance_inertia = false;            ///< MuJoCo's compiler balanceinertia, with a warning per link
  double timestep_s = 0.00025;
  Eigen::Vector3d gravity = Eigen::Vector3d(0.0, 0.0, -9.81);
  std::string source;  ///< the configuration key naming the URDF (error messages); urdf_path when empty
};

struct GeneratedPlant {
  std::string mjcf;
  std::vector<std::string> warnings;  ///< one line each, naming the link
};

class UrdfPlant {
public:
  /// The MJCF of the arm alone. Throws phri::ConfigError naming the file and the link or joint on a
  /// URDF it cannot turn into a plant (floating or planar joints on the arm, loops, bad inertials).
  static GeneratedPlant generate(const UrdfPlantOptions& options);
  /// From URDF text; `source_name` stands for the file in errors.
  static GeneratedPlant generate_from_string(const std::string& urdf, const UrdfPlantOptions& options,
                                             const std::string& source_name);
};

}  // namespace phri
