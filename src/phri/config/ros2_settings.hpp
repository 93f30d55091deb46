#pragma once
// The ROS 2 bridge's settings (a run YAML's `ros2:`; `phri run --ros2 [--ros-domain N]
// [--ros-namespace NS]` override them). The bridge itself is src/phri/ros2/ (docs/ros2.md).
#include <string>

namespace phri {

struct Ros2Settings {
  bool enabled = false;
  /// DDS domain id (ROS_DOMAIN_ID); -1: the environment's ROS_DOMAIN_ID, else 0.
  int domain = -1;
  /// Prefix of phri's own topics (/phri/wrench ...); /joint_states and /tf stay global as ROS 2
  /// tools expect them. A ROS 2 name: '/', then [A-Za-z0-9_] segments separated by '/'.
  std::string topic_namespace = "/phri";
  /// Publishing every this many control cycles: /joint_states (1: 1 kHz) and every other topic.
  int joint_states_decimation = 10;
  int decimation = 20;
  /// Take /phri/target_pose and /phri/event (false: publish only).
  bool subscribe = true;
  /// The run's F/T sensor is <namespace>/ft_in (geometry_msgs/WrenchStamped from another machine,
  /// `phri ft-bridge`), checked by the controller's WrenchSupervisor like the arm's own.
  bool ft_in = false;
  /// Inputs faster than this are refused (counted), per topic [1/s].
  double max_input_rate_hz = 50.0;
  /// A target farther than this from the base is refused [m]; 0: the arm's reach from its model.
  double max_reach_m = 0.0;
  /// Discovery: "loopback" (unicast to 127.0.0.1, no multicast: one machine) or "network"
  /// (Cyclone's defaults, multicast); or a Cyclone XML file given by the CYCLONEDDS_URI variable.
  std::string discovery = "loopback";
};

/// A namespace for phri's topics: "/", then segments of [A-Za-z0-9_] not starting with a digit,
/// joined by '/', no trailing '/' ("/phri", "/lab/arm_1").
bool valid_ros_namespace(const std::string& ns);

}  // namespace phri
