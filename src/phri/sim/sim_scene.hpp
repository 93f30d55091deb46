#pragma once
// phri::SimScene: the MuJoCo scene of the simulated arm, composed in memory around the arm's own
// MJCF (robots/kinova_gen3/gen3_plant.xml stays the arm alone; it is also the reference model of
// the dynamics tests). Added to the arm:
//
//   <flange body> (the body of config.ft_sensor.flange_site, bracelet_link on the Gen3)
//     ft_adapter       welded at the flange site: F/T adapter + sensor body (flange side, not measured)
//       tool           welded at the sensor's mount (translated, turned): the tool (DS4 gamepad + mount);
//                      its origin is the sensor's measuring frame, site "ft_sensor" with a MuJoCo
//                      force and torque sensor; site "cable_anchor" when the drop test is enabled
//   (a tool without an F/T sensor, SimRobotConfig::has_ft_sensor false: `tool` welded at the flange
//   site itself, its origin the flange frame, no adapter, no sensor site, no MuJoCo sensors;
//   neither when the plant has no end of arm, SimRobotConfig::has_end_of_arm: a bare flange)
//   world
//     drop_mass        (drop test only) free body, a sphere; held at the anchor until release
//     floor            (optional) a plane; only the drop mass collides with it
//
// The arm's keyframes are removed (their qpos would not match once the drop mass adds a free
// joint); the initial state comes from the plant configuration.
#include <phri/config/sim_robot_config.hpp>

#include <string>
#include <vector>

namespace phri {

struct SimScene {
  static constexpr const char* kAdapterBody = "ft_adapter";
  static constexpr const char* kToolBody = "tool";
  static constexpr const char* kToolGeom = "tool_geom";  ///< the tool's box (what a body region meets)
  /// A robot bundle's payload is the body kPayloadBodyPrefix + its name, a child of its link's body.
  static constexpr const char* kPayloadBodyPrefix = "payload_";
  static constexpr const char* kSensorSite = "ft_sensor";
  static constexpr const char* kForceSensor = "ft_force";
  static constexpr const char* kTorqueSensor = "ft_torque";
  static constexpr const char* kAnchorSite = "cable_anchor";
  static constexpr const char* kDropBody = "drop_mass";
  static constexpr const char* kFloorGeom = "floor";

  /// The scene MJCF text for `config`. Reads config.mjcf_path; throws phri::ConfigError when the
  /// arm file cannot be read or loaded, has no flange site, or already uses one of the names above.
  static std::string build_mjcf(const SimRobotConfig& config);

  /// A joint of the arm's MJCF as the plant simulates it (for the controller's URDF to be checked
  /// against: same type, same limits).
  struct ArmJoint {
    std::string name;
    bool hinge = true;    ///< false: slide (or another type)
    bool limited = false;
    double lower = 0.0, upper = 0.0;  ///< [rad] when limited
  };
  /// The joints of config.actuators, in order, from config.mjcf_path (the arm alone). Throws
  /// phri::ConfigError when the file cannot be loaded or lacks one of them.
  static std::vector<ArmJoint> arm_joints(const SimRobotConfig& config);
};

}  // namespace phri
