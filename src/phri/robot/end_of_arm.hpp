#pragma once
// phri::EndOfArm: what an arm carries beyond its URDF at its flange: an F/T sensor (the adapter
// and the sensor's own body on the flange side) and the tool below the sensor, or a tool alone on
// the flange (no F/T sensor: no wrench signal, no adapter). The library has
// no default end of arm (a bare flange): a robot bundle's `end_of_arm` (robots/<robot>/robot.yaml)
// or a plant YAML's `ft_sensor` and `tool` state it; the controller carries it as payloads
// (ControllerSettings::set_end_of_arm), the plant as bodies (SimRobotConfig::set_end_of_arm).
#include <Eigen/Geometry>

#include <string>
#include <string_view>

namespace phri {

/// A rigid body given by its mass, centre of mass and principal moments of inertia about it.
struct RigidBodyData {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d principal_inertia_kgm2 = Eigen::Vector3d::Zero();
};

struct EndOfArm {
  /// false: the tool sits on the flange with no F/T sensor between (sensor_mount the identity, no
  /// flange_side body; the tool's COM in the flange frame).
  bool has_ft_sensor = true;
  /// The F/T measuring frame in the flange frame: a straight adapter is a translation along the
  /// flange z; a sensor turned about the flange z (its x at 45 or 90 degrees to the flange's) or
  /// set off sideways is not. The tool below rotates with it (its COM and axes are the sensor's).
  Eigen::Isometry3d sensor_mount = Eigen::Isometry3d::Identity();
  RigidBodyData flange_side;  ///< adapter + sensor body, COM in the flange frame (not measured by the sensor)
  RigidBodyData tool;         ///< below the sensor, COM and principal axes in the sensor frame
};

class YamlReader;
/// The sensor_mount from a YAML map: `xyz_key` [m] or `offset_key` [m] (d alone: xyz [0, 0, d];
/// one of the two, never both), and `rpy_key` [rad] (optional: no rotation), a URDF origin's
/// R = Rz(y) Ry(p) Rx(r). |xyz| at most 0.5 m, each angle within a turn. Throws ConfigError
/// naming the key (robots/<robot>/robot.yaml's end_of_arm.ft_sensor, a plant YAML's ft_sensor).
Eigen::Isometry3d read_sensor_mount(const YamlReader& sensor, std::string_view offset_key, std::string_view xyz_key,
                                    std::string_view rpy_key);

/// A rigid body fixed to a link of the arm that its URDF does not carry (a robot bundle's
/// `payloads`: a camera, a cable reel, a valve block): the controller's model merges it into that
/// link's body (ModelOptions::payloads), the plant welds it into the link's body.
struct LinkPayload {
  std::string name;
  std::string link;    ///< the URDF link it is fixed to (a frame of the model, a body of the plant)
  RigidBodyData body;  ///< mass, COM and principal moments about the COM, in the link's frame
};

}  // namespace phri
