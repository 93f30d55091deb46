#pragma once
// phri::EndOfArm: what an arm carries beyond its URDF at its flange: an F/T sensor (the adapter
// and the sensor's own body on the flange side) and the tool below the sensor, or a tool alone on
// the flange (no F/T sensor: no wrench signal, no adapter). The library has
// no default end of arm (a bare flange): a robot bundle's `end_of_arm` (robots/<robot>/robot.yaml)
// or a plant YAML's `ft_sensor` and `tool` state it; the controller carries it as payloads
// (ControllerSettings::set_end_of_arm), the plant as bodies (SimRobotConfig::set_end_of_arm).
#include <Eigen/Core>

#include <string>

namespace phri {

/// A rigid body given by its mass, centre of mass and principal moments of inertia about it.
struct RigidBodyData {
  double mass_kg = 0.0;
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();
  Eigen::Vector3d principal_inertia_kgm2 = Eigen::Vector3d::Zero();
};

struct EndOfArm {
  /// false: the tool sits on the flange with no F/T sensor between (sensor_offset_m 0, no
  /// flange_side body; the tool's COM in the flange frame).
  bool has_ft_sensor = true;
  double sensor_offset_m = 0.0;  ///< flange -> F/T measuring frame, along the flange's z axis [m]
  RigidBodyData flange_side;     ///< adapter + sensor body, COM in the flange frame (not measured by the sensor)
  RigidBodyData tool;            ///< below the sensor, COM in the sensor frame
};

/// A rigid body fixed to a link of the arm that its URDF does not carry (a robot bundle's
/// `payloads`: a camera, a cable reel, a valve block): the controller's model merges it into that
/// link's body (ModelOptions::payloads), the plant welds it into the link's body.
struct LinkPayload {
  std::string name;
  std::string link;    ///< the URDF link it is fixed to (a frame of the model, a body of the plant)
  RigidBodyData body;  ///< mass, COM and principal moments about the COM, in the link's frame
};

}  // namespace phri
